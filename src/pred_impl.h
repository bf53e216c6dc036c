/* The predictive algorithm's internals, shared by its files (STYLE: src/<module>_impl.h):
 *   algo_predictive.c  the orchestration: set-up, the rounds of a step (find, claim, react,
 *                      predict again) in all-pairs and grid modes, the update, resume;
 *   pred_find.c        a sphere's earliest event: its pairs and planes (paper Procedure 9);
 *   pred_react.c       a reaction (Procedure 8) and the lasting contacts it makes or ends:
 *                      resting on planes, held spheres, cages, jams;
 *   pred_settle.c      settling: spheres slow for SETTLE_STEPS steps held where they are;
 *   pred_cells.c       cells mode: the algorithm's side of the in-step event loop (evloop.h);
 *   pred_ways.c        how many threads run a step's events, measured step by step.
 * The state they share is pred_ctx (one per run) and thread_ws (one per thread); the small
 * helpers every one of them calls are inline here. */
#ifndef NBEP_PRED_IMPL_H
#define NBEP_PRED_IMPL_H

#include <math.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "nbep/barrier.h"
#include "nbep/contact.h"
#include "nbep/feq.h"
#include "nbep/grid.h"
#include "nbep/periodic.h"
#include "nbep/physics.h"
#include "nbep/predict.h"
#include "evloop.h"
#include "sim_impl.h"

/* Every this many rounds of one step (cells mode: every STALL_EVENTS events, pred_cells.c),
 * time must have advanced by more than STALL_FRACTION of a step, or the run stops as a
 * numerical failure: a step may hold any number of real events (a fast sphere between close
 * walls: thousands), but a cascade that no longer advances time is a contact the model cannot
 * resolve, and so is one whose time creeps on by round-off. A step that advances less needs
 * over 10^11 rounds or 10^12 events, days of a core's time, which no scene that can run asks.
 * Until 2026-12-01 it was 1e-12, which 64 spheres packed tight, each given a speed, passed,
 * creeping on by about 1e-19 an event for ever in every mode (tests/test_extremes.c; a new
 * user's 1000 on a lattice ran ten minutes without a step). */
#define STALL_ROUNDS 100000u
#define STALL_FRACTION 1e-6
/* Every this many rounds of one step, thread 0 looks at the stop signal: a step of the paper's
 * box has a few rounds and never looks; a step of many (a long dt over a crowded scene: a
 * round costs microseconds to a millisecond) is abandoned within a second of a SIGTERM. */
#define STOP_ROUNDS 1024u
/* The stall's message (printf: step, time, STALL_FRACTION, their count, "rounds" or "events").
 * A step whose real events are far shorter than it (a review's 27 spheres at 1e18 times their
 * radius a time unit, dt = 1: 1e18 list expiries a sphere a step) stalls by this measure too,
 * and will not end either: the message names both causes. */
#define STALL_MESSAGE                                                                              \
    "nbep: step %llu: events at t = %.17g do not resolve (time advanced less than %g of a step " \
    "over %u %s: endless zero-time reactions, or a time step far too long for the scene's "      \
    "events); stopping"
/* Sphere-sphere contacts that different accelerations press together (a sphere on one that
 * rests on a floor, a pile) would bounce ever faster (inelastic collapse: infinitely many
 * collisions in finite time) or, with e = 1, forever at a vanishing height. Such a pair leaves
 * every response with at least the separating speed that keeps it apart for t_min: the smaller
 * of MIN_BOUNCE_STEP_FRACTION of a step and the time a bounce of MIN_BOUNCE_REL_HEIGHT of the
 * smaller radius takes (so the jitter stays far below the geometry at any dt). Between two free
 * spheres the kick keeps momentum and adds at most mu (a t_min)^2 / 8 of energy (mu the reduced
 * mass, a the pressing acceleration): about 6e-8 J for two 1 kg spheres under gravity at
 * dt = 1e-3. Where either leans on planes, the kick is shared along the two spheres'
 * mobilities (min_bounce, pred_react.c) and adds at most the same, mu then the pair's mass
 * along n. (Until 2026-12-01 a sphere on planes took none of it, and the energy changed by
 * m (v.n) du + m du^2 / 2: up to 5e-4 J in a step of a pile; README, granular.) */
#define MIN_BOUNCE_STEP_FRACTION 0.1
#define MIN_BOUNCE_REL_HEIGHT 1e-6
/* Settling (pred_settle.c): a sphere whose speed stayed at or below SETTLE_SPEED_FACTOR times
 * its rest speed for SETTLE_STEPS whole steps is held where it is. */
#define SETTLE_STEPS 10u
#define SETTLE_SPEED_FACTOR 2.0

/* One sphere's settling record (see SETTLE_STEPS): written by its owner, in the update and in
 * the settle sub-phases; cand and still are the snapshot other threads read in settle_gather,
 * live[] the one they read in settle_phases' rounds (the round before's parity). */
typedef struct settle_rec {
    double peak2;     /* highest speed squared in the current step so far */
    uint32_t slow;    /* whole steps in a row at or below the settle speed (up to SETTLE_STEPS) */
    bool cand;        /* at the last step's end: not held, slow for SETTLE_STEPS steps */
    bool still;       /* at the last step's end: held */
    bool held_now;    /* held by settle_phases this step (its supports' counts not yet stamped) */
    bool more;        /* a candidate touched more supports than sup holds (the least nearly
                       * below were left out) */
    bool live[2];     /* a candidate still has supports after settle_phases' round k (written
                       * at k's parity, read by all at the next round) */
    uint8_t n_sup;
    int32_t sup[NBEP_CONTACT_MAX]; /* a candidate's supports as gathered (rest_set's who) */
} settle_rec;

#define KEY_FREE UINT64_MAX
static const nbep_vec3 ZERO3 = {0.0, 0.0, 0.0};

typedef struct thread_ws {
    alignas(NBEP_CACHELINE) uint32_t *cand;  /* owned: own spheres with an event before T_end */
    size_t n_cand;
    uint32_t *redo;           /* owned: own spheres to re-predict this round */
    size_t n_redo;
    int par;                  /* rounds modes: the parity of the round being reacted to (its
                               * claims name the spheres other threads may change) */
    uint32_t *fired;          /* owned: spheres that reacted in this thread's last react phase
                               * (and own spheres let go after it) */
    size_t n_fired;
    uint32_t *rel;            /* owned: own held spheres to let go this round */
    size_t n_rel;
    uint64_t *lock;           /* owned, rounds modes with settling: the keys of pairs that
                               * lock (a jammed sphere and one in the jam) that met this
                               * round, whose body lock_phase makes */
    size_t n_lock;
    uint64_t woken;           /* held spheres this thread changed so far (react, let_go) */
    size_t n_settle;          /* own settle candidates at the last step's end (settle_count) */
    size_t n_settled;         /* own spheres settle_phases held in the last step */
    size_t n_live[2], n_lost[2]; /* own candidates with supports after settle_phases' round k,
                                  * and those that lost their last in it (k's parity) */
    uint32_t jam_step;        /* the current step's number, low bits (run.max_reactions) */
    uint32_t jammed;          /* 1 + the lowest sphere this thread saw past run.max_reactions
                               * (the run then stops), 0 if none */
    uint32_t *claimed;        /* owned: claim words written in the last claim phase */
    size_t n_claimed;
    uint32_t *tclaimed;       /* owned, run.order = "step": time claim words written in the
                               * last claim_time_phase */
    size_t n_tclaimed;
    nbep_event *part;         /* owned: best event over this thread's partners, per chunk entry */
    double t_min;             /* earliest candidate time this round, +inf if none */
    double vmax_react;        /* grid mode: fastest sphere after this thread's reactions in
                               * the current step */
    double vmax_end, amax_end; /* grid mode: fastest own sphere and largest own acceleration
                               * at the end of the last step (read by grid_prepare) */
    nbep_vec3 grid_lo, grid_hi; /* grid mode: bounds of own centres at the step's start;
                                 * cells mode without a box: at a rebuild or a step's end */
    size_t grid_sum;          /* grid mode: spheres in own cells (the build's prefix sum) */
    nbep_predict_ws *pws;     /* owned: quartic workspace */
} thread_ws;
/* The lasting contacts of one sphere: planes (who >= 0) and held spheres (who = -1 - j, with
 * the support's response count when it took the load; a later response lets go). */
typedef struct rest_set {
    int32_t who[NBEP_CONTACT_MAX];
    uint64_t ver[NBEP_CONTACT_MAX];
    uint8_t n;
    bool still;       /* held still: v = 0 and aeff = 0 exactly */
} rest_set;

/* A sphere's meeting with an immobile face (a plane p: who = p, or a held sphere j:
 * who = -1 - j): when, the face's normal towards the sphere and the sphere's centre then
 * (t = -inf: none). */
typedef struct face_met {
    double t;
    nbep_vec3 n, p;
    int32_t who;
} face_met;
/* Faces remembered per sphere, newest first (caged): with the face met now, as many as a
 * contact set holds. Two opposite faces make a slot; a sphere on a floor between two held
 * neighbours, one beside it and one above, is in a three-face channel, whose faces taken two
 * at a time each leave it a velocity of round-off size heading into the third (measured: a
 * million zero-time reactions in one step of a 300-sphere pour, seed 3, step 618). */
#define CAGE_FACES (NBEP_CONTACT_MAX - 1)

/* The neighbours per sphere that nbep check counts in cells mode's lists (with their rooms
 * and the pool's growth, nbep_nblist_bytes): more than a dense scene lists (a fluid at phi
 * 0.30 to 0.50: 10 to 11, nblist.h; a settled pile at phi 0.6 about 14 by the same scaling),
 * so a dilute scene's estimate is high (a pour's start lists about one: README, nbep check);
 * spheres of mixed sizes may list more, as the cutoff is the largest diameter's. */
#define ESTIMATE_NEIGHBOURS 24.0
_Static_assert(CAGE_FACES == NBEP_CONTACT_FACES, "the file keeps every face remembered");

/* A sphere's reactions in the step `step` (low bits; zeroed memory: none, steps start at 1). */
typedef struct jam_count {
    uint32_t step, n;
} jam_count;

/* The ways a step's events may run (pred_ways.c): on one thread, a pair, or the whole team
 * (cells mode's team loop) or crew (grid mode's rounds) where that is more; chosen step by
 * step by measuring each. Thread 0 writes it, between steps. */
#define PRED_WAYS_MAX 3
/* A probe's part of a cells-mode step: its events before T0 + PRED_WAYS_PART dt (pred_ways.c) */
#define PRED_WAYS_PART 0.125
typedef struct pred_ways {
    int n;                      /* the ways: 0 (one thread only, nothing to choose) to 3 */
    int crew[PRED_WAYS_MAX];    /* each way's threads: 1, 2, and the whole team or crew */
    /* the way of each step, by the step's parity: step k reads way[k & 1], which thread 0
     * wrote during step k - 1 (nbep__pred_ways_choose), whose end every thread crossed, and
     * which no one writes during step k */
    int way[2];
    /* cells mode: the way of the first part of each step (a probe, PRED_WAYS_PART), by the
     * step's parity as way; -1: none, the step runs way[] throughout */
    int probe[2];
    double cost[PRED_WAYS_MAX]; /* measured seconds per event (cells mode) or per step (grid
                                 * mode) of each way; 0: none yet */
    int force;                  /* NBEP_TEAM (nbep__pred_ways_forced) */
    int last;                   /* grid mode: the way of the step before (-1: none yet) */
} pred_ways;

/* The terms added to a thread's sums (virial, wall impulses) while the cells mode's scheduled
 * loop runs, in order: a rollback takes those of its undone events out again, each finite one
 * by adding its negation, which an exact sum (xsum.h) undoes exactly (pred_cells.c,
 * cells_back), an infinite or NaN one (summed apart, as a double, where inf - inf would leave
 * NaN) by putting back the sum's special part as it was. Emptied at each window's end, when
 * every event so far stands. */
typedef struct nbep_sum_term {
    nbep_xsum *sum;
    double x;
    double special; /* x not finite: the sum's special part before it */
} nbep_sum_term;
typedef struct nbep_sum_journal {
    nbep_sum_term *term;
    size_t n, cap;
    bool oom; /* a term not recorded: no memory (the loop then fails) */
} nbep_sum_journal;

typedef struct pred_ctx {
    nbep_barrier bar;
    nbep_feq *q;                  /* owned */
    uint64_t *ver;                /* owned: responses per sphere; older predictions are stale */
    double *tau;                  /* owned: local time of each sphere inside the step */
    const nbep_state *st;         /* borrowed: the run's state (pred_import) */
    /* model only what the scene needs: rest and aeff are NULL when no sphere accelerates
     * (free_flight: no contact can rest or hold, every sphere flies with a = 0), t_last when
     * the TC model cannot change a restitution (e = 1 or tc = 0) */
    rest_set *rest;               /* owned: the contacts holding each sphere */
    /* e < 1: a supported sphere slower than the rest speed may be held still, its speed taken
     * (the model's dissipation, as restitution's); at e = 1 only a sphere whose contacts leave
     * it no velocity at all rests still (until 2026-12-02 an elastic sphere sliding on a floor
     * at 0.5 mm/s stopped, and a slow elastic collision with a sliding sphere stopped both) */
    bool hold_slow;
    bool locking;                 /* rounds modes: thread 0 is in nbep__pred_lock_phase, the
                                   * others waiting at its barrier (jam_lock's walk reads and
                                   * writes any sphere: nowhere else) */
    uint8_t *lock_mark;           /* owned, rounds modes with settling: 1 for a sphere in a
                                   * body of the lock_phase under way (no other body takes
                                   * it), else 0 */
    uint64_t *unlocked;           /* owned with lock_mark: for sphere lo, the step (low bits)
                                   * << 32 | 1 + hi of a pair (lo, hi) whose body its lock_phase
                                   * could not make (jam_lock: past LOCK_MAX), whose next
                                   * meeting is an ordinary response, as in cells mode (react);
                                   * else 0 */
    nbep_vec3 *aeff;              /* owned: acceleration each sphere flies with (rest_solve) */
    double *t_last;               /* owned: time of each sphere's last sphere collision (TC) */
    face_met *face;               /* owned with t_last when something accelerates: each
                                   * sphere's last meeting with an immobile face (caged) */
    settle_rec *settle;           /* owned when something accelerates and e < 1 (SETTLE_STEPS) */
    /* run.max_reactions (jam_max): each sphere's reactions in one step (NULL for an elastic
     * scene without accelerations: free flight at e = 1 cannot jam) */
    jam_count *jam;
    uint32_t jam_max;
    uint8_t *flags;               /* owned: IN_CAND | IN_REDO */
    _Atomic uint64_t *claim[2];   /* owned: smallest pair key claiming a sphere, by round parity */
    /* run.order = "step" (the paper's step, approximate): every candidate reacts that is the
     * earliest of both its spheres, not only those at the round's earliest time */
    bool order_step;
    _Atomic uint64_t *tclaim;     /* owned, step order only: earliest event time claiming a
                                   * sphere this round (time_word) */
    _Atomic uint64_t *reacted;    /* owned: round stamp of a sphere's last reaction */
    thread_ws *ws;                /* owned, one per thread */
    int nt;
    bool imported;                /* slots came from a resumed run: no initial predictions */
    /* run.neighbors = "grid" (beyond the paper): a re-prediction tests only the spheres that
     * can reach it before a horizon; see grid_prepare */
    bool use_grid;
    nbep_grid grid;               /* owned: centres at the step's start */
    double rmax;                  /* largest radius */
    double vmax, amax;            /* fastest sphere and largest acceleration at the step's start */
    double horizon;               /* H: absolute time up to which this step's predictions look */
    /* run.neighbors = "cells" (beyond the paper): the in-step event loop (evloop.h) */
    nbep_evloop *ev;              /* owned, NULL in the other modes */
    /* a scene without a box: the cells cover the spheres' extent at each rebuild, grown on
     * each side (fit_region), and a step whose spheres have left that region rebuilds
     * (cells_fit, cells_outgrown) */
    bool refit;
    nbep_vec3 fit_lo, fit_hi;     /* the region the cells cover now */
    nbep_periodic pb;             /* the box's periodic axes (scene.c: cells and all-pairs) */
    /* all-pairs mode in a periodic box: partners are compared at their nearest image, which
     * stays the touching one while no sphere strays farther than its reach from where it was
     * last predicted (periodic.h); an image-horizon event re-predicts it there. Sphere i's
     * reach is that of its own largest contact distance, r_i plus the largest radius among
     * the others (pred_find.c, image_horizon): a pair's two reaches then add to at most the
     * pair's own, and a small sphere does not take the reach of two large ones, which a box a
     * hair past two large diameters makes vanish (one large and one small sphere there made
     * 1602 predictions and no collision in a step, hours a time unit, until 2026-12-01) */
    bool image_horizon;
    /* each partner compared at the 27 images around its nearest, for a far longer reach
     * (nbep_periodic_reach_wide), where the nearest image's reach is under 1/27 of that: a
     * box near two largest diameters, whose nearest-image reach goes to 0 (two spheres of
     * radius 1 in a box of side 4 + 1e-6 made 1.6e5 predictions a step, until 2026-12-01) */
    bool image_wide;
    size_t big;        /* the largest sphere when no other is as large, else SIZE_MAX */
    double rmax_other; /* the largest radius of the others, for `big` */
    bool ev_failed;               /* thread 0: the loop stalled this step */
    bool part_failed;             /* thread 0: the loop stalled in this step's first part
                                   * (a probe's; read while thread 0 runs the second) */
    bool free_flight;             /* no sphere accelerates: straight flight, nothing rests */
    double sigma_all;             /* every pair's contact distance when all radii are equal,
                                   * else 0 (the pair loop then looks each radius up) */
    double mass_all;              /* every sphere's mass when all are equal, else 0 (masses
                                   * are positive): a pair's reaction then reads no mass,
                                   * two misses fewer in a large fluid */
    /* cells mode on two threads or more, in a scene whose reactions change only their own two
     * spheres (free flight, any e): threads 1 to team_size - 1 handle events ahead of
     * thread 0's (nbep_evloop_run_lead), counting them apart until they stand (cells_merge) */
    bool team;
    int team_size;  /* the threads that may run the event loop: the run's, at most
                     * NBEP_EVLOOP_TEAM_MAX, or NBEP_TEAM's count */
    pred_ways ways; /* the ways a step's events may run, and each step's (pred_ways.c) */
    /* grid mode on two threads or more: a step's rounds run on the crew ways.crew[ways.way[step
     * & 1]] (threads 0 .. crew - 1, each with its own share of the spheres for that crew),
     * chosen as the cells mode's team is (pred_ways.c), with the barrier of its size; the
     * other threads wait for the rounds at bar. A crowded scene's rounds are short (a settling
     * pile: about one event each, behind four barriers), and a crew of 16 ran a pour 1.4 times
     * as long as one thread on a 16-core node; the paper's box gains from every thread. The
     * results are the same bit for bit whatever the crew: every round's outcome is (tests). */
    bool crews;
    nbep_barrier crew_bar[PRED_WAYS_MAX];
    /* thread 0, where the crew is smaller than the run's threads, for the others after the
     * barrier that ends the rounds: whether the rounds stopped the run */
    bool crew_quit;
    /* set (for good) by a look at the stop signal within a step that finds one: thread 0's,
     * every STOP_ROUNDS rounds (rounds modes), read by the crew past the barrier that follows;
     * any thread's, within a rebuild's predictions (cells mode), read by every thread past the
     * barrier that ends them */
    atomic_int stop_seen;
    uint64_t rounds_before; /* thread 0's: the rounds of the steps before this one */
    uint64_t seen_before;   /* thread 0's: seen_woken where the step before's rounds ended */
    nbep_counters *help_cnt;      /* owned when team, team_size NBEP_EVLOOP_RING: each place's
                                   * event's counts (the team loop's ring of places, evloop.h),
                                   * thread t's at t NBEP_EVLOOP_RING + ring slot (each written
                                   * by the thread that handles the place: it stays on its
                                   * core) */
    nbep_thread_max *help_mx;     /* owned when team, the same: their sums (wall: one buffer) */
    nbep_xsum *help_wall;         /* owned when team: team_size NBEP_EVLOOP_RING rows of
                                   * n_planes */
    bool scheduled;               /* cells mode: the loop runs through the scheduler
                                   * (NBEP_SCHEDULED, evloop_warp.c) */
    nbep_sum_journal jr;          /* when scheduled: thread 0's sums' terms (its mx->jr while
                                   * the loop runs) */
    int slabs;                    /* when scheduled: its slabs (NBEP_SLABS; 1: one) */
    int slab_crew;                /* when scheduled on slabs: the threads that run them, the
                                   * run's and at most one a slab (thread t runs slabs t,
                                   * t + slab_crew, ...; slab k's world takes thread
                                   * k % slab_crew's workspace); else 1 */
    struct cells_world *worlds;   /* owned, scheduled on slabs: each slab's world (pred_cells.c),
                                   * made at the first call, and what the engine borrows of
                                   * them (owned): their contexts and response counts */
    void **world_u;
    const uint64_t **world_ver;
    int n_worlds;
} pred_ctx;

/* s += x, and x recorded in mx's journal where it keeps one (nbep_thread_max.jr) */
static inline void nbep__pred_sum_add(nbep_thread_max *mx, nbep_xsum *s, double x)
{
    nbep_sum_journal *j = mx->jr;
    if (!j) {
        nbep_xsum_add(s, x);
        return;
    }
    const double special = s->special; /* (before x, which may change it) */
    nbep_xsum_add(s, x);
    if (!nbep_room_for_one((void **)&j->term, &j->cap, j->n, sizeof *j->term)) {
        j->oom = true;
        return;
    }
    j->term[j->n++] = (nbep_sum_term){s, x, special};
}

/* The terms of j past its first `to` taken out of their sums again, newest first: each sum as
 * it was before them, bit for bit (its value, and what later terms make of it) */
static inline void nbep__pred_sums_back(nbep_sum_journal *j, size_t to)
{
    while (j->n > to) {
        const nbep_sum_term *t = &j->term[--j->n];
        if (isfinite(t->x))
            nbep_xsum_add(t->sum, -t->x);
        else
            t->sum->special = t->special;
    }
}

static inline bool is_zero(nbep_vec3 v)
{
    return v.x == 0.0 && v.y == 0.0 && v.z == 0.0;
}

/* The acceleration sphere i flies with: its own, less the part its contacts carry. */
static inline nbep_vec3 effective_acc(const pred_ctx *c, const nbep_state *s, size_t i)
{
    (void)s;
    return c->aeff ? c->aeff[i] : ZERO3;
}

/* The separation from sphere a to sphere b, by the minimum image in a periodic box (a pair in
 * contact is closer than half a period, so this is the image that touches). Cells mode keeps
 * stored positions in their cells, never more than a period apart, so the comparing form
 * serves; all-pairs mode (c->image_horizon) wraps them only at a step's end, and within a long
 * step two spheres drift any number of periods apart, past the comparing form's one and a
 * half: the general one then (until 2026-11-30 the comparing one there gave an image a period
 * away, the pair was not turned apart, and the step stalled). */
static inline nbep_vec3 sep(const pred_ctx *c, const nbep_state *s, size_t a, size_t b)
{
    nbep_vec3 d = nbep_vec3_sub(s->pos[b], s->pos[a]);
    if (!c->pb.any)
        return d;
    return c->image_horizon ? nbep_periodic_image(&c->pb, d) : nbep_periodic_near_image(&c->pb, d);
}

/* The minimum bounce's time (MIN_BOUNCE_STEP_FRACTION) for radius r pressed by an acceleration
 * of magnitude a > 0. */
static inline double min_bounce_time(double r, double a, double dt)
{
    return fmin(MIN_BOUNCE_STEP_FRACTION * dt, sqrt(8.0 * MIN_BOUNCE_REL_HEIGHT * r / a));
}

/* The rest speed of sphere i pressed by an acceleration of magnitude amag (see "Lasting
 * sphere-sphere contacts"): amag t_min, twice the speed the minimum bounce leaves with, the
 * speed it comes back at. 0 when nothing presses. */
static inline double rest_speed(const nbep_state *s, size_t i, double amag, double dt)
{
    return amag > 0.0 ? amag * min_bounce_time(s->radius[i], amag, dt) : 0.0;
}

/* Whether r names `who` among its contacts (rest_set's who: plane p, or -1 - j for sphere j). */
static inline bool rest_names(const rest_set *r, int32_t who)
{
    for (int k = 0; k < r->n; k++)
        if (r->who[k] == who)
            return true;
    return false;
}

static inline bool rest_has_plane(const rest_set *r, size_t p)
{
    return rest_names(r, (int32_t)p);
}

/* Whether r (a held sphere's contacts) names sphere k among its supports. */
static inline bool rest_has_sphere(const rest_set *r, size_t k)
{
    return rest_names(r, -1 - (int32_t)k);
}

static inline bool is_fresh(const pred_ctx *c, size_t i, const nbep_event *ev)
{
    if (ev->kind == NBEP_EVENT_NONE || ev->ver_self != c->ver[i])
        return false;
    return ev->kind != NBEP_EVENT_SPHERE || ev->ver_partner == c->ver[ev->partner];
}

static inline void keep_earlier(nbep_event *best, nbep_event e)
{
    if (e.time < NBEP_NEVER && (best->kind == NBEP_EVENT_NONE || nbep_feq_event_before(&e, best)))
        *best = e;
}

/* Where neighbour j is compared with sphere i: at its image nearest to i in a periodic box
 * (the shift to add to its position), at itself otherwise. */
static inline nbep_vec3 neighbour_shift(const pred_ctx *c, const nbep_state *s, size_t i,
                                        size_t j)
{
    return nbep_periodic_near_shift(&c->pb, nbep_vec3_sub(s->pos[j], s->pos[i]));
}

/* The bounds of every thread's centres (each thread's grid_lo and grid_hi), in *lo and *hi:
 * min and max are exact, so the result is the same for any thread count. */
static inline void merged_bounds(const pred_ctx *c, nbep_vec3 *lo, nbep_vec3 *hi)
{
    nbep_vec3 l = c->ws[0].grid_lo, h = c->ws[0].grid_hi;
    for (int t = 1; t < c->nt; t++) {
        const thread_ws *u = &c->ws[t];
        l = nbep_vec3_make(fmin(l.x, u->grid_lo.x), fmin(l.y, u->grid_lo.y),
                           fmin(l.z, u->grid_lo.z));
        h = nbep_vec3_make(fmax(h.x, u->grid_hi.x), fmax(h.y, u->grid_hi.y),
                           fmax(h.z, u->grid_hi.z));
    }
    *lo = l;
    *hi = h;
}

/* The ordering key of an event: lower sphere in the high half, then the partner; planes
 * (stored as UINT32_MAX - plane) after every sphere, and an image horizon after the planes.
 * Equal for both copies of one pair. */
static inline uint64_t event_key(size_t i, const nbep_event *ev, uint32_t *lo, uint32_t *hi)
{
    if (ev->kind != NBEP_EVENT_SPHERE) {
        *lo = (uint32_t)i;
        *hi = UINT32_MAX - ev->partner;
    } else {
        *lo = (uint32_t)(i < ev->partner ? i : ev->partner);
        *hi = (uint32_t)(i < ev->partner ? ev->partner : i);
    }
    return (uint64_t)*lo << 32 | *hi;
}

/* Sphere i's speed now counts towards its step's highest (SETTLE_STEPS). */
static inline void settle_note(pred_ctx *c, const nbep_state *s, size_t i)
{
    if (c->settle)
        c->settle[i].peak2 = fmax(c->settle[i].peak2, nbep_vec3_norm2(s->vel[i]));
}

static inline void advance_to(pred_ctx *c, nbep_state *s, size_t i, double t_local)
{
    double h = t_local - c->tau[i];
    if (h > 0.0)
        nbep_physics_drift(&s->pos[i], &s->vel[i], effective_acc(c, s, i), h);
    c->tau[i] = t_local;
    settle_note(c, s, i);
}

/* Sphere i's settle speed: SETTLE_SPEED_FACTOR times its rest speed. */
static inline double settle_speed(const nbep_state *s, size_t i, double dt)
{
    return SETTLE_SPEED_FACTOR * rest_speed(s, i, nbep_vec3_norm(s->acc[i]), dt);
}


/* ---- pred_find.c: a sphere's earliest event ----------------------------------------------- */

/* keep_earlier of sphere i (flying with ai) and each of its partners js[0..m), j at its nearest
 * image when images; T0 the step's start. */
void nbep__pred_keep_pairs(nbep_event *best, const pred_ctx *c, const nbep_state *s, uint32_t i,
                           nbep_vec3 ai, const uint32_t *js, size_t m, bool images, double T0,
                           thread_ws *w);
/* Paper Procedure 9, one thread's share: sphere i's earliest event with spheres [lo, hi) and,
 * when with_planes, every plane. */
nbep_event nbep__pred_predict_some(const pred_ctx *c, const nbep_state *s, size_t i, size_t lo,
                                   size_t hi, bool with_planes, double T0, thread_ws *w,
                                   nbep_counters *cnt);
/* Grid mode: sphere i's earliest event before the horizon, or the horizon. */
nbep_event nbep__pred_predict_grid(const pred_ctx *c, const nbep_state *s, size_t i, double T0,
                                   double V, thread_ws *w, nbep_counters *cnt);

/* ---- pred_react.c: a reaction and the lasting contacts ------------------------------------ */

/* Solves sphere i's contacts r with velocity *v (writes the acceleration left in *a; hold: a
 * speed below the rest speed stops); returns whether they hold it still. */
bool nbep__pred_rest_solve(const pred_ctx *c, const nbep_state *s, size_t i, rest_set *r,
                           nbep_vec3 *v, nbep_vec3 *a, double dt, bool tangent, bool hold);
/* The reaction to event ev of spheres lo and hi (hi: UINT32_MAX - plane for a plane) at
 * absolute time t_abs, t_local into the step; the spheres it changed in w->fired. */
void nbep__pred_react(pred_ctx *c, nbep_state *s, const nbep_scene *sc, double t_abs,
                      double t_local, uint32_t lo, uint32_t hi, const nbep_event *ev,
                      thread_ws *w, nbep_counters *cnt, nbep_thread_max *mx);
/* Sphere i is held and a sphere it rests on has reacted since it took the load. */
bool nbep__pred_held_on_changed(const pred_ctx *c, size_t i);
/* Rounds modes, thread 0 between barriers after a react phase whose pairs that lock were
 * noted (thread_ws.lock of the crew's threads, 0 .. crew - 1, the threads that ran it): each
 * pair's body, in the order of their keys. */
void nbep__pred_lock_phase(pred_ctx *c, nbep_state *s, int crew, double dt, double t_local,
                           thread_ws *w);

/* Held sphere i lets go of the supports that reacted, at local time t_local. */
void nbep__pred_let_go(pred_ctx *c, nbep_state *s, size_t i, double dt, double t_local,
                       thread_ws *w);
/* run.max_reactions: sphere i reacted too often in step `step`, at about time t; the run
 * stops. */
void nbep__pred_jam_fail(nbep_sim *sim, uint64_t step, size_t i, double t);

/* ---- pred_settle.c: settling -------------------------------------------------------------- */

/* The update, own sphere i at the step's end: whether it is a candidate to settle. */
bool nbep__pred_settle_count(pred_ctx *c, const nbep_state *s, size_t i, double dt);
/* Every thread at a step's end: holds the candidates whose supports end up held; whether any
 * sphere was held. */
bool nbep__pred_settle_phases(nbep_sim *sim, pred_ctx *c, nbep_range own, thread_ws *w);

/* ---- pred_cells.c: cells mode ------------------------------------------------------------- */

/* Frees the scheduled loop's worlds on slabs (pred_cells.c), if any. */
void nbep__pred_cells_worlds_free(pred_ctx *c);
/* The steps of cells mode, every thread, inside pred_run's parallel region. */
void nbep__pred_cells_steps(nbep_sim *sim, pred_ctx *c, int tid, nbep_range own, thread_ws *w);

/* ---- pred_ways.c: the threads of a step's events ------------------------------------------ */

/* NBEP_TEAM's value v (NULL: unset): PRED_WAYS_ALWAYS the whole team, PRED_WAYS_NEVER one
 * thread, k >= 2 a team of k (at most NBEP_EVLOOP_TEAM_MAX), PRED_WAYS_CYCLE the ways in
 * turn; PRED_WAYS_FREE (anything else) the fastest way, measured. */
#define PRED_WAYS_FREE 0
#define PRED_WAYS_ALWAYS 1
#define PRED_WAYS_NEVER (-1)
#define PRED_WAYS_CYCLE (-2)
int nbep__pred_ways_forced(const char *v);
/* The ways of a team or crew of `size` threads (0: none, nothing to choose): one thread, a pair
 * and the whole team, as many as it has threads for; NBEP_TEAM's choice force; nothing
 * measured yet, the first step's way the largest (PRED_WAYS_NEVER: one thread). */
void nbep__pred_ways_init(pred_ways *w, int size, int force);
/* Thread 0, after a part of a cells-mode step ran `events` events in `seconds` way `way`: its
 * figure, as a probe's (replacing the way's) or as the way taken's (its running mean). */
void nbep__pred_ways_note(pred_ways *w, int way, bool probe, uint64_t events, double seconds);
/* Thread 0, after cells mode's step `step` ran its events (`events` of them in `seconds`, the
 * first part's apart: nbep__pred_ways_note) way `way`: the ways of step + 1 (way[], probe[]). */
void nbep__pred_ways_choose(pred_ways *w, uint64_t step, int way, uint64_t events,
                            double seconds);
/* Thread 0, after grid mode's step `step` ran way `way` in `seconds`: the way of step + 1. */
void nbep__pred_ways_choose_crew(pred_ways *w, uint64_t step, int way, double seconds);

#endif
