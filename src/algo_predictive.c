/* The predictive algorithm (paper Algorithm 2, Sections 3 and 4): every sphere's earliest
 * future event sits in its slot of the future event queue (feq.c); a step only examines the
 * slots, reacts to the events that fall inside it, and re-predicts the spheres whose future
 * changed. Threads own spheres by index range (whole blocks); sub-phases are separated by
 * nbep_barrier inside one parallel region over all steps.
 *
 * A step from T0 to T_end runs in rounds; each round has three sub-phases:
 *   find    each thread re-predicts its invalid or stale spheres against every sphere and
 *           plane (paper Procedure 9), then collects its spheres whose event falls before
 *           T_end (Procedure 13) and publishes their earliest time;
 *   claim   every thread takes the same global earliest time t_min; each event at t_min
 *           claims both its spheres by compare-and-swap, keeping the smallest pair key;
 *   react   an event whose key holds both claims reacts (Procedure 8): its spheres are
 *           advanced to t_min, the response applied, their response counts bumped (which
 *           makes every other event naming them stale) and their local time set to t_min.
 * Rounds repeat until no event falls before T_end; then every sphere flies to T_end (the
 * paper's update, Section 4.3.1).
 *
 * Departures from the paper's pseudocode, and why:
 * - Time order inside a step. The paper reacts to every event found in a step at once. But an
 *   event can be shadowed: a's slot names a later event than the one it will really have,
 *   because its true partner only changed course in this step. Reacting only to the earliest
 *   events of each round, and re-predicting in between, gives the sequence a serial event-
 *   driven code would, so positions stay exact (pairs are advanced to contact, not detected
 *   after they overlap). The paper's own step stays available as run.order = "step"
 *   (scene.h: order_step; approximate, off by default): each round reacts at once to every
 *   candidate that is the earliest event of both its spheres, found by two claims: by time
 *   (claim_time_phase), then, among the events that hold both time claims, by pair key
 *   (claim_phase). The earliest candidate of all always reacts, so each round makes
 *   progress; a sphere reacts at most once per round. An event can still be shadowed: a
 *   reaction creates an earlier event for a sphere that has already reacted later in the same
 *   round; the next round finds that pair from the later of the two local times, overlapping,
 *   and reacts to it there (predict.h: an overlapping, closing pair touches now). Held
 *   spheres whose support reacted in a round let go at the round's earliest event time
 *   (let_go_phase), as in time order; one that became held later in that round starts to fall
 *   from there, the same kind of approximation.
 * - Reacting twice. Procedure 8 tests-and-sets a flag of e.o1 only; when the slots of both
 *   spheres name each other and the spheres belong to two threads, both react. Here the two
 *   copies of one pair carry the same key, both see they won the claims, and a
 *   compare-and-swap on the lower sphere's reacted tag lets exactly one of them react.
 * - Simultaneous events sharing a sphere (a Newton's cradle) are ordered by pair key, the
 *   same for any thread count, so frames are bitwise identical for 1..N threads.
 * - The barrier is nbep_barrier, safe to reuse back to back (Procedure 4 is not).
 * - Resting contact: a sphere whose bounce off a plane would last less than
 *   NBEP_REST_FRACTION of a step (or, squeezed by a neighbour, that is no faster than the rest
 *   speed) is set to rest on it: its normal velocity is zeroed and the plane carries its
 *   weight (its acceleration loses the component into the plane) until a response moves it
 *   off; otherwise infinitely many ever-smaller bounces would come in finite
 *   time (e < 1), and a sphere pressed on a plane at zero speed would react forever.
 *   Since issue 9 a sphere keeps up to NBEP_CONTACT_MAX such contacts at once (planes, and
 *   spheres held still), its flight acceleration projected onto the cone they allow
 *   (contact.h); see "Lasting sphere-sphere contacts" for held spheres, tc_restitution for the
 *   TC model that ends inelastic collapse, and caged for a sphere between two fixed faces. */
#include <float.h>
#include <math.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/barrier.h"
#include "nbep/contact.h"
#include "nbep/feq.h"
#include "nbep/grid.h"
#include "nbep/periodic.h"
#include "nbep/physics.h"
#include "nbep/predict.h"
#include "evloop.h"
#include "sim_impl.h"

/* A bounce whose flight would last less than this fraction of a step ends in resting contact:
 * with restitution e the remaining bounces take 2 v/|a| / (1 - e) in all, so below this the
 * sphere is indistinguishable from resting at the step's resolution, and the kinetic energy
 * removed, m (a t/2)^2 / 2 with t = 1e-9 dt, is far below round-off of the total. */
#define NBEP_REST_FRACTION 1e-9
#define NO_PLANE (-1)
/* Every this many rounds of one step, time must have advanced by more than STALL_FRACTION of
 * a step, or the run stops as a numerical failure: a step may hold any number of real events
 * (a fast sphere between close walls: thousands), but a cascade that no longer advances time
 * is a contact the model cannot resolve. */
#define STALL_ROUNDS 100000u
#define STALL_FRACTION 1e-12
/* Sphere-sphere contacts that different accelerations press together (a sphere on one that
 * rests on a floor, a pile) would bounce ever faster (inelastic collapse: infinitely many
 * collisions in finite time) or, with e = 1, forever at a vanishing height. Such a pair leaves
 * every response with at least the separating speed that keeps it apart for t_min: the smaller
 * of MIN_BOUNCE_STEP_FRACTION of a step and the time a bounce of MIN_BOUNCE_REL_HEIGHT of the
 * smaller radius takes (so the jitter stays far below the geometry at any dt). Between two free
 * spheres the kick keeps momentum and adds at most mu (a t_min)^2 / 8 of energy (mu the reduced
 * mass, a the pressing acceleration): about 6e-8 J for two 1 kg spheres under gravity at
 * dt = 1e-3. When one of them rests on planes, the other takes the whole kick du and the planes
 * the momentum, so it changes the energy by m (v.n) du + m du^2 / 2: either sign, and larger
 * when the pair moves along n (measured on a 300-sphere pile at e = 0: 1492 kicks, 1408 of them
 * removing energy, the largest adding 4.9e-5 J; README, granular). */
#define MIN_BOUNCE_STEP_FRACTION 0.1
#define MIN_BOUNCE_REL_HEIGHT 1e-6
/* Lasting sphere-sphere contacts (issue 9). A sphere whose contacts (planes, and spheres that
 * are themselves held still) leave it no acceleration is "held still": velocity and effective
 * acceleration exactly zero, so it costs no events and can carry others in turn; a settled
 * pile is a network of held spheres on planes.
 *
 * The rest speed (rest_speed) sets what is slow enough to hold: |a| t_min, twice the separating
 * speed of the minimum bounce above (9.8e-4 m/s under gravity at dt = 1e-3). A pressed pair
 * leaves every response at least that fast, so any lasting contact the model does not hold
 * jitters at that speed for ever; a hold threshold below it (1e-3 |a| dt, before) is never met
 * in a crowd: a 300-sphere pour had no sphere held at all after 0.8 s, and every jittering
 * impact on a held sphere knocked it loose again. So a supported sphere slower than the rest
 * speed is held when a partner meets it; a sphere that meets a held one no faster than the
 * rest speed (along the line of centres, and in all) joins it if the contacts it then has
 * (its planes, that sphere, and the other held spheres it touches: a pocket, pocket_gather)
 * leave it no motion, else bounces off it as off a wall (the held sphere, carried by the pile,
 * takes no momentum); a faster impact is an ordinary response and wakes what the held sphere
 * carried, unless the pile carries it (carried, below). The kinetic energy removed by
 * holding, at most m (rest speed)^2 / 2 per hold (4.8e-7 J for 1 kg under gravity at
 * dt = 1e-3), is the model's, besides restitution. A held
 * sphere is let go (time-ordered, at the instant its support changed) as soon as any of its
 * supports reacts. */
/* Jams (run.max_reactions). A sphere that reacts more than run.max_reactions times within one
 * step is jammed: pressed between walls and neighbours that the contact model cannot hold
 * still (README, granular: a wedge), it would collide ever faster while time crawls on (1e-9 s
 * per event is typical), so the step never ends and the job's SIGTERM, read between steps, is
 * never seen. The run stops as a numerical failure instead, its frames intact. A real scene
 * stays far below the default of 1e6: a sphere collides about once per mean free time, so that
 * would be a step of a million mean free times (a fast sphere bouncing between walls close
 * together: thousands; the busiest sphere of the hopper and pile decks: 200 to 2000).
 * Counting costs 8 bytes a sphere (jam_count), not spent on elastic free flight, which cannot
 * jam. The limit is kept below UINT32_MAX, so a count never wraps before it trips. */
/* Settling (issue 9). try_hold and land_on_held hold a sphere on what it touches at one
 * meeting, which must already be held: a pile whose spheres carry each other (one on two
 * neighbours that lean on it in turn) never freezes that way, and jitters near the rest speed
 * for ever, at a cost that rises as it cools (a 300-sphere pour: 150 to 260 collisions per
 * sphere per step after 0.9 s, rising). Speed over time shows what one meeting cannot: a sphere
 * whose speed stayed at or below its settle speed v_s = SETTLE_SPEED_FACTOR x its rest speed
 * for SETTLE_STEPS whole steps changed velocity by at most 2 v_s over that window, so the mean
 * net force on it was at most 2 v_s / (SETTLE_STEPS dt) / |a| of its weight: with t_min <=
 * 0.1 dt (min_bounce_time), at most 2 x 2 x 0.1 / 10 = 4 %, at any dt. Its contacts carry
 * it. It is held where it is (settle_phases), on the planes and the spheres below it (against
 * its acceleration) that it touches within v_s^2 / |a| (twice its highest hop at that speed)
 * and that are held already or settle in the same step (candidates whose own supports do not
 * settle do not: settle_recheck); then it wakes as any held sphere does (an
 * impact faster than the rest speed, or a support that reacts). The speed test is exact:
 * between events |v + a t| is convex in t, so a step's highest speed is at an event (advance_to
 * before a reaction, fire after it) or at its ends (the update). Only dissipative scenes
 * (e < 1) with accelerations settle: an elastic pile keeps its energy. Energy: at most
 * m v_s^2 / 2 per hold (1.9e-6 J for 1 kg under gravity at dt = 1e-3), the model's, besides
 * restitution. A resumed run starts its windows afresh (it re-finds held spheres anyway). */
#define SETTLE_STEPS 10u
#define SETTLE_SPEED_FACTOR 2.0
/* A sphere that has reacted this many times in one step is held where it is when it next
 * meets a held sphere slowly (along the line of centres no faster than the rest speed:
 * land_on_held; jam_hold), or any sphere while its planes carry it (react: a row of spheres
 * that fits a box exactly, a Newton's cradle without gaps). Bounced between a held sphere and
 * a face across from it (a slot a diameter wide between a wall and a held sphere a hair lower
 * than it, so that its weight
 * presses it on that sphere's curve as it slides along the slot), a sphere re-meets the held
 * one 1e-10 to 1e-12 s after each minimum bounce (the cage takes the bounce back), a million
 * times before the step ends (a 300-sphere pour, seed 1, steps 892 and 898, sliding at 1.3
 * and 3.9 mm/s). The model holds spheres still on sphere supports but has no sliding contact
 * with one, and no geometry rule covers every such wedge; ten thousand reactions in a step is
 * far above any motion it resolves (the busiest sphere of the hopper and pile decks reacts 200
 * to 2000 times in a step). Energy: the sphere's kinetic energy at the hold, the model's,
 * besides restitution (1/2 m (3.9 mm/s)^2 = 7.6e-6 J per kg in the case measured). */
#define JAM_HOLD ((uint32_t)NBEP_JAM_HOLD) /* nbep/scene.h: --help-deck names it */
/* Impacts the pile carries (carried). A free sphere k meeting held sphere j faster than the rest
 * speed woke j (an ordinary response), and through let_go everything j carried. In a pile
 * whose upper layers still move at millimetres to centimetres a second, every such touch woke
 * part of it: the 2000-sphere deck run on from 2.5 s (median speed 1.6 mm/s, 99th percentile
 * 2 cm/s) held 801 spheres at 2.9 s and 259 at 3.1 s, each cascade letting spheres fall and
 * slide into the next, and did not settle. So held j stays put when k's push on it (along
 * the line of centres, from k to j) points into the cone of the faces that hold it -- its own
 * contacts, and the other held spheres and the planes it touches to within settle_gather's reach,
 * all immobile, as for a sphere that lands on j (land_on_held) -- and k closes no faster than
 * the speed of a fall from physics.carry_drop of j's radius, sqrt(2 |a| carry_drop r): 7.7 cm/s
 * for the pile deck's 3 cm spheres under g at the default, NBEP_CARRY_DROP = 0.01. That is
 * above the agitation of a settling pile (the deck's fastest sphere at 2.5 s: 5 cm/s) and far
 * below what a pour brings (a sphere falling one diameter onto it: 1.1 m/s). k then bounces
 * off j as off a wall (land_on_held: restitution, and the TC model); the momentum, at most
 * m (1 + e) times that speed, goes to the pile, as to a plane, and no energy does (j does not
 * move). A push j's faces cannot take (from the side of a sphere alone on a floor, from below)
 * or a faster one is an ordinary response, which wakes j. carry_drop = 0 turns the rule off. */

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

/* Re-predictions are shared out in chunks of this many spheres: each thread finds the best
 * event of every sphere of the chunk among its own partners, then the owners merge. The
 * chunk bounds the per-thread buffers (not O(n) per thread). */
#define CHUNK 512

/* Per-sphere flags, touched only by the sphere's owner. */
#define IN_CAND 1u
#define IN_REDO 2u

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
/* A cage's second face comes at zero time: the sphere has not moved off the first one. One
 * that has moved off it along its normal by more than this fraction of its radius had room to
 * bounce (a channel a little wider than the sphere): no cage. */
#define CAGE_TOUCH_REL 1e-9

/* A sphere's reactions in the step `step` (low bits; zeroed memory: none, steps start at 1). */
typedef struct jam_count {
    uint32_t step, n;
} jam_count;

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
     * stays the touching one while no sphere strays farther than image_reach from where it
     * was last predicted (periodic.h); an image-horizon event re-predicts it there */
    bool image_horizon;
    double image_reach;
    bool ev_failed;               /* thread 0: the loop stalled this step */
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
    /* the ways a step's events may run (team_crew: the threads of each, 1 for the one-thread
     * loop, 2 for a pair, team_size for the whole team when that is more), and the way of
     * each step, by the step's parity: step k reads team_way[k & 1], which thread 0 wrote
     * during step k - 1 (team_choose), whose end every thread crossed, and which no one writes
     * during step k; and the measured seconds per event of each way (0: none yet) */
    int team_ways;
    int team_crew[3];
    int team_way[2];
    double team_cost[3];
    int team_force; /* NBEP_TEAM, read once (team_forced) */
    /* grid mode on two threads or more: a step's rounds run on the crew team_crew[team_way[step
     * & 1]] (threads 0 .. crew - 1, each with its own share of the spheres for that crew),
     * chosen by team_choose as the cells mode's team is, with the barrier of its size; the
     * other threads wait for the rounds at bar. A crowded scene's rounds are short (a settling
     * pile: about one event each, behind four barriers), and a crew of 16 ran a pour 1.4 times
     * as long as one thread on a 16-core node; the paper's box gains from every thread. The
     * results are the same bit for bit whatever the crew: every round's outcome is (tests). */
    bool crews;
    nbep_barrier crew_bar[3];
    /* thread 0, where the crew is smaller than the run's threads, for the others after the
     * barrier that ends the rounds: whether the rounds stopped the run */
    bool crew_quit;
    int crew_last;  /* thread 0's: the way of the step before (-1: none yet) */
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
} pred_ctx;

static bool is_zero(nbep_vec3 v)
{
    return v.x == 0.0 && v.y == 0.0 && v.z == 0.0;
}

static void pred_destroy(void *p)
{
    pred_ctx *c = p;
    if (!c)
        return;
    nbep_feq_destroy(&c->q);
    nbep_grid_fini(&c->grid);
    nbep_evloop_destroy(&c->ev);
    nbep_free_aligned(c->help_cnt);
    nbep_free_aligned(c->help_mx);
    free(c->help_wall);
    nbep_free_aligned(c->ver);
    nbep_free_aligned(c->tau);
    nbep_free_aligned(c->rest);
    nbep_free_aligned(c->aeff);
    nbep_free_aligned(c->t_last);
    nbep_free_aligned(c->face);
    nbep_free_aligned(c->settle);
    nbep_free_aligned(c->jam);
    nbep_free_aligned(c->flags);
    nbep_free_aligned((void *)c->claim[0]);
    nbep_free_aligned((void *)c->claim[1]);
    nbep_free_aligned((void *)c->tclaim);
    nbep_free_aligned((void *)c->reacted);
    if (c->ws) {
        for (int t = 0; t < c->nt; t++) {
            free(c->ws[t].cand);
            free(c->ws[t].redo);
            free(c->ws[t].fired);
            free(c->ws[t].rel);
            free(c->ws[t].claimed);
            free(c->ws[t].tclaimed);
            nbep_free_aligned(c->ws[t].part);
            nbep_predict_ws_destroy(&c->ws[t].pws);
        }
        nbep_free_aligned(c->ws);
    }
    free(c);
}

/* A scene without a box, cells mode: the region the cells cover around the centres' extent
 * [lo, hi] (fit_lo, fit_hi), grown on each side by an eighth of the extent along that axis
 * and at least two of the largest diameters. Spheres move between rebuilds, and one that
 * leaves the region is clamped into its edge cells (correct, slower), so a step whose spheres
 * have left it rebuilds (cells_outgrown): the eighth makes a region that has to follow a
 * growing extent (a hopper's outflow, a gas that expands) grow geometrically, a few rebuilds
 * in all; the two diameters keep a layer one sphere thick (no extent across it) from
 * rebuilding each time a sphere hops off it. */
static void fit_region(pred_ctx *c, nbep_vec3 lo, nbep_vec3 hi)
{
    const double floor_pad = 4.0 * c->rmax;
    const nbep_vec3 pad = {fmax(floor_pad, 0.125 * (hi.x - lo.x)),
                           fmax(floor_pad, 0.125 * (hi.y - lo.y)),
                           fmax(floor_pad, 0.125 * (hi.z - lo.z))};
    c->fit_lo = nbep_vec3_sub(lo, pad);
    c->fit_hi = nbep_vec3_add(hi, pad);
}

static int team_forced(void);

/* The neighbours per sphere that nbep check counts in cells mode's lists (with their rooms
 * and the pool's growth, nbep_nblist_bytes): more than a dense scene lists (a fluid at phi
 * 0.30 to 0.50: 6 to 11, nblist.h; a settled pile at phi 0.6 about 14 by the same scaling),
 * so a dilute scene's estimate is high (a pour's start lists about one: README, nbep check);
 * spheres of mixed sizes may list more, as the cutoff is the largest diameter's. */
#define ESTIMATE_NEIGHBOURS 24.0

/* What pred_create makes for a run of a scene on nt threads: the models the scene needs
 * (each keeps arrays of its own per sphere), each mode's workspaces and each thread's share.
 * pred_create allocates by it and pred_bytes (nbep check's memory estimate) counts by it, so
 * the estimate holds the arrays a run of that scene makes: no granular ones for an elastic
 * fluid, no rounds' ones in cells mode. */
typedef struct pred_plan {
    size_t n, n_planes;
    int nt;
    bool free_flight;   /* no sphere accelerates: nothing rests (no rest sets, no aeff) */
    bool tc_model;      /* physics.tc > 0 and e < 1: each sphere's last collision (t_last) */
    bool cage_model;    /* the TC model where something accelerates: faces met (face) */
    bool settle_model;  /* something accelerates and e < 1: settling records (settle) */
    bool jam_model;     /* something accelerates or e < 1: reaction counts (jam) */
    bool rounds;        /* not cells mode: flags, claims, reaction stamps, candidate lists */
    bool order_step;    /* run.order = "step", rounds only: time claims */
    bool use_grid;      /* run.neighbors = "grid": a cell grid */
    bool cells;         /* run.neighbors = "cells": the event loop */
    bool crews;         /* grid mode on two threads or more: crews run the rounds (pred_ctx) */
    bool team;          /* cells mode: a team of team_size >= 2 may run the event loop */
    int team_size;      /* cells mode: the threads that may run the event loop */
    int team_ways;      /* the ways a step may run, their threads (pred_ctx) */
    int team_crew[3];
} pred_plan;

/* The plan of a run of scene sc from state st (the scene's, or a run's copy of it) on nt
 * threads, with NBEP_TEAM's choice team_force (team_forced). */
static pred_plan plan_of(const nbep_scene *sc, const nbep_state *st, int nt, int team_force)
{
    pred_plan p = {.n = st->n, .n_planes = st->n_planes, .nt = nt, .free_flight = true};
    for (size_t i = 0; i < p.n; i++)
        p.free_flight &= is_zero(st->acc[i]);
    p.tc_model = sc->tc > 0.0 && sc->restitution < 1.0;
    p.cage_model = p.tc_model && !p.free_flight;
    p.settle_model = !p.free_flight && sc->restitution < 1.0;
    p.jam_model = !p.free_flight || sc->restitution < 1.0;
    /* the rounds' bookkeeping (flags, claims, reaction stamps, candidate and redo lists):
     * not in cells mode, whose event loop needs none of it (25 to 45 bytes a sphere) */
    p.rounds = !sc->neighbors_cells;
    p.order_step = p.rounds && sc->order_step; /* scene.c refuses it in cells mode */
    p.use_grid = sc->neighbors_grid;
    p.cells = sc->neighbors_cells;
    if (p.use_grid && nt >= 2) {
        /* the ways of grid mode's rounds: one thread, two, and every thread (or NBEP_TEAM's
         * count) where that is more */
        int size = nt;
        if (team_force >= 2 && team_force < size)
            size = team_force;
        p.crews = true;
        p.team_ways = size > 2 ? 3 : 2;
        p.team_crew[0] = 1;
        p.team_crew[1] = 2;
        p.team_crew[2] = size;
    }
    if (p.cells) {
        /* the team loop: reactions in free flight change their own spheres only (nothing
         * rests, holds, settles or is caged without an acceleration): their motion, and at
         * e < 1 their TC clocks and reaction counts, which the loop keeps with the motion to
         * undo a speculative reaction (cells_save) */
        const bool can_team = nt >= 2 && p.free_flight;
        int size = nt < NBEP_EVLOOP_TEAM_MAX ? nt : NBEP_EVLOOP_TEAM_MAX;
        if (team_force >= 2 && team_force < size)
            size = team_force;
        p.team_size = can_team ? size : 1;
        p.team = p.team_size >= 2;
        p.team_ways = !p.team ? 1 : p.team_size > 2 ? 3 : 2;
        p.team_crew[0] = 1;
        p.team_crew[1] = 2;
        p.team_crew[2] = p.team_size;
    }
    return p;
}

/* Thread t's share of the spheres, which sizes its workspaces: its own range and one, or in
 * grid mode its largest share in any crew it belongs to. */
static size_t plan_own(const pred_plan *p, int t)
{
    const nbep_range r = nbep__range_split(p->n, t, p->nt);
    size_t own = r.hi - r.lo + 1;
    for (int k = 0; p->crews && k < p->team_ways; k++)
        if (t < p->team_crew[k]) {
            const nbep_range q = nbep__range_split(p->n, t, p->team_crew[k]);
            own = own > q.hi - q.lo + 1 ? own : q.hi - q.lo + 1;
        }
    return own;
}

/* The room of thread t's list of fired spheres: 2 per reaction, 1 per let-go; cells mode: one
 * reaction's 3 and every held sphere letting go after it, on the thread that runs the event
 * loop (and a team's helper, whose reactions change their own two spheres only). */
static size_t plan_fired(const pred_plan *p, int t)
{
    if (p->rounds)
        return 3 * plan_own(p, t);
    return t == 0 ? p->n + 3 : p->team && t < p->team_size ? 3 : 1;
}

/* The bytes pred_create allocates for a run of sc on nt threads, by the same plan: the
 * algorithm's part of nbep check's memory estimate (cells mode: lists of ESTIMATE_NEIGHBOURS;
 * each thread's quartic workspace, a few hundred bytes, left out). */
static size_t pred_bytes(const nbep_scene *sc, int nt)
{
    const pred_plan p = plan_of(sc, &sc->state, nt, team_forced());
    const pred_ctx *c = NULL;  /* for element sizes only: sizeof does not evaluate */
    const thread_ws *w = NULL;
    const size_t n = p.n;
    size_t bytes = sizeof *c + nbep_feq_bytes(n) + n * (sizeof *c->ver + sizeof *c->tau);
    if (!p.free_flight)
        bytes += n * (sizeof *c->rest + sizeof *c->aeff);
    if (p.tc_model)
        bytes += n * sizeof *c->t_last;
    if (p.cage_model)
        bytes += n * CAGE_FACES * sizeof *c->face;
    if (p.settle_model)
        bytes += n * sizeof *c->settle;
    if (p.jam_model)
        bytes += n * sizeof *c->jam;
    if (p.rounds)
        bytes += n * (sizeof *c->flags + sizeof *c->claim[0] + sizeof *c->claim[1] +
                      sizeof *c->reacted);
    if (p.order_step)
        bytes += n * sizeof *c->tclaim;
    bytes += (size_t)nt * sizeof *c->ws;
    for (int t = 0; t < nt; t++) {
        const size_t own = plan_own(&p, t);
        bytes += plan_fired(&p, t) * sizeof *w->fired + CHUNK * sizeof *w->part;
        if (p.rounds)
            bytes += own * (sizeof *w->cand + sizeof *w->redo + sizeof *w->rel +
                            2 * sizeof *w->claimed);
        if (p.order_step)
            bytes += 2 * own * sizeof *w->tclaimed;
    }
    if (p.use_grid)
        bytes += nbep_grid_bytes(n);
    if (p.cells)
        bytes += nbep_evloop_bytes(n, ESTIMATE_NEIGHBOURS);
    if (p.team) {
        const size_t rows = (size_t)p.team_size * NBEP_EVLOOP_RING;
        bytes += rows * (sizeof *c->help_cnt + sizeof *c->help_mx +
                         (p.n_planes ? p.n_planes : 1) * sizeof *c->help_wall);
    }
    return bytes;
}

static nbep_status pred_create(nbep_sim *sim, void **out, nbep_diag *d)
{
    size_t n = sim->st.n;
    pred_ctx *c = calloc(1, sizeof *c);
    if (!c)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the predictive algorithm");
    c->nt = sim->nt;
    c->st = &sim->st;
    nbep_barrier_init(&c->bar, (unsigned)sim->nt);
    nbep_status st = nbep_feq_create(n, &c->q, d);
    if (st != NBEP_OK) {
        pred_destroy(c);
        return st;
    }
    c->team_force = team_forced();
    /* what to allocate: the same plan as pred_bytes counts (keep the two in step) */
    const pred_plan p = plan_of(sim->scene, &sim->st, sim->nt, c->team_force);
    c->free_flight = p.free_flight;
    c->ver = nbep_alloc_aligned(n, sizeof *c->ver);
    c->tau = nbep_alloc_aligned(n, sizeof *c->tau);
    if (!p.free_flight) {
        c->rest = nbep_alloc_aligned(n, sizeof *c->rest);
        c->aeff = nbep_alloc_aligned(n, sizeof *c->aeff);
    }
    if (p.tc_model)
        c->t_last = nbep_alloc_aligned(n, sizeof *c->t_last);
    if (p.cage_model)
        c->face = nbep_alloc_aligned(n * CAGE_FACES, sizeof *c->face);
    if (p.settle_model)
        c->settle = nbep_alloc_aligned(n, sizeof *c->settle);
    const uint64_t jam_max = sim->scene->max_reactions; /* 0 (a scene built in code): none */
    c->jam_max = (uint32_t)(jam_max > 0 && jam_max < UINT32_MAX - 1 ? jam_max : UINT32_MAX - 1);
    if (p.jam_model)
        c->jam = nbep_alloc_aligned(n, sizeof *c->jam);
    const bool rounds = p.rounds;
    if (rounds) {
        c->flags = nbep_alloc_aligned(n, sizeof *c->flags);
        c->claim[0] = nbep_alloc_aligned(n, sizeof *c->claim[0]);
        c->claim[1] = nbep_alloc_aligned(n, sizeof *c->claim[1]);
        c->reacted = nbep_alloc_aligned(n, sizeof *c->reacted);
    }
    c->order_step = p.order_step;
    if (c->order_step)
        c->tclaim = nbep_alloc_aligned(n, sizeof *c->tclaim);
    c->ws = nbep_alloc_aligned((size_t)sim->nt, sizeof *c->ws);
    if (!c->ver || !c->tau || (!p.free_flight && (!c->rest || !c->aeff)) ||
        (p.tc_model && !c->t_last) || (p.cage_model && !c->face) || (p.jam_model && !c->jam) ||
        (p.settle_model && !c->settle) ||
        !c->ws ||
        (rounds && (!c->flags || !c->claim[0] || !c->claim[1] || !c->reacted)) ||
        (c->order_step && !c->tclaim)) {
        pred_destroy(c);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the predictive algorithm (%zu spheres)",
                  n);
    }
    c->use_grid = p.use_grid;
    c->crews = p.crews;
    c->team_ways = p.team_ways;
    for (int w = 0; w < 3; w++)
        c->team_crew[w] = p.team_crew[w];
    if (c->crews) {
        for (int w = 0; w < c->team_ways; w++)
            nbep_barrier_init(&c->crew_bar[w], (unsigned)c->team_crew[w]);
        /* the first step takes the largest crew (team_choose) */
        c->team_way[0] = c->team_way[1] = c->team_force == -1 ? 0 : c->team_ways - 1;
        c->crew_last = -1;
    }
    c->pb = nbep_periodic_make(sim->scene->has_box ? sim->scene->periodic : NULL,
                               sim->scene->box_min, sim->scene->box_max);
    if (c->use_grid) {
        st = nbep_grid_init(&c->grid, n, d);
        if (st != NBEP_OK) {
            pred_destroy(c);
            return st;
        }
    }
    bool mono = true, same_mass = true;
    for (size_t i = 0; i < n; i++) {
        c->rmax = fmax(c->rmax, sim->st.radius[i]);
        mono &= sim->st.radius[i] == sim->st.radius[0];
        same_mass &= sim->st.mass[i] == sim->st.mass[0];
    }
    c->sigma_all = n > 0 && mono ? sim->st.radius[0] + sim->st.radius[0] : 0.0;
    c->mass_all = n > 0 && same_mass ? sim->st.mass[0] : 0.0;
    c->image_horizon = c->pb.any && !c->use_grid && !sim->scene->neighbors_cells;
    c->image_reach = nbep_periodic_reach(&c->pb, 2.0 * c->rmax);
    if (p.cells) {
        /* see cells_steps: only those frames are rebuild points of the uninterrupted run
         * (nbep_output_open_resume picks such a frame; a caller of its own may not) */
        const nbep_resume *r = sim->opt.resume;
        if (r && !nbep_scene_resume_point(sim->scene, r->step)) {
            pred_destroy(c);
            NBEP_FAIL(d, NBEP_EDECK,
                      "nbep: run.neighbors = \"cells\" resumes bit for bit only from a frame at a "
                      "multiple of output.every (%llu), not from step %lld",
                      (unsigned long long)sim->scene->output_every, (long long)r->step);
        }
        c->team_size = p.team_size;
        /* without a box, the cells are laid out at the first rebuild (cells_fit) and again at
         * each one after; until then they are one cell */
        c->refit = !sim->scene->has_box && n > 0;
        st = nbep_evloop_create(n, sim->scene->box_min, sim->scene->box_max, 2.0 * c->rmax,
                                c->pb.axis, c->team_size, c->q, c->ver, &c->ev, d);
        c->team = st == NBEP_OK && p.team;
        /* the first step: the whole team (team_choose) */
        c->team_way[0] = c->team_way[1] = c->team_force == -1 ? 0 : c->team_ways - 1;
        if (c->team) {
            const size_t np = sim->st.n_planes, rows = (size_t)c->team_size * NBEP_EVLOOP_RING;
            c->help_cnt = nbep_alloc_aligned(rows, sizeof *c->help_cnt);
            c->help_mx = nbep_alloc_aligned(rows, sizeof *c->help_mx);
            c->help_wall = calloc(rows * (np ? np : 1), sizeof *c->help_wall);
            if (!c->help_cnt || !c->help_mx || !c->help_wall) {
                nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory for the cells engine");
                st = NBEP_ENOMEM;
            } else {
                for (size_t m = 0; m < rows; m++) {
                    c->help_cnt[m] = (nbep_counters){0};
                    c->help_mx[m] = (nbep_thread_max){.wall = c->help_wall + m * np};
                }
            }
        }
        if (st != NBEP_OK) {
            pred_destroy(c);
            return st;
        }
    }
    for (size_t i = 0; i < n; i++) {
        if (c->rest) {
            c->rest[i] = (rest_set){.n = 0};
            c->aeff[i] = sim->st.acc[i];
        }
        if (c->t_last)
            c->t_last[i] = -INFINITY;
        for (size_t f = 0; c->face && f < CAGE_FACES; f++)
            c->face[i * CAGE_FACES + f] = (face_met){.t = -INFINITY, .who = INT32_MIN};
        if (c->settle)
            c->settle[i] = (settle_rec){.peak2 = nbep_vec3_norm2(sim->st.vel[i])};
        if (rounds) {
            atomic_init(&c->claim[0][i], KEY_FREE);
            atomic_init(&c->claim[1][i], KEY_FREE);
            atomic_init(&c->reacted[i], 0);
        }
        if (c->order_step)
            atomic_init(&c->tclaim[i], KEY_FREE);
    }
    for (int t = 0; t < sim->nt; t++) {
        const size_t own = plan_own(&p, t);
        thread_ws *w = &c->ws[t];
        w->fired = malloc(plan_fired(&p, t) * sizeof *w->fired);
        w->part = nbep_alloc_aligned(CHUNK, sizeof *w->part);
        if (rounds) {
            w->cand = malloc(own * sizeof *w->cand);
            w->redo = malloc(own * sizeof *w->redo);
            w->rel = malloc(own * sizeof *w->rel);
            w->claimed = malloc(2 * own * sizeof *w->claimed);
        }
        if (c->order_step)
            w->tclaimed = malloc(2 * own * sizeof *w->tclaimed);
        if (!w->fired || !w->part ||
            (rounds && (!w->cand || !w->redo || !w->rel || !w->claimed)) ||
            (c->order_step && !w->tclaimed)) {
            pred_destroy(c);
            NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the predictive algorithm");
        }
        st = nbep_predict_ws_create(&w->pws, d);
        if (st != NBEP_OK) {
            pred_destroy(c);
            return st;
        }
    }
    *out = c;
    return NBEP_OK;
}

/* The acceleration sphere i flies with: its own, less the part its contacts carry. */
static nbep_vec3 effective_acc(const pred_ctx *c, const nbep_state *s, size_t i)
{
    (void)s;
    return c->aeff ? c->aeff[i] : ZERO3;
}

/* The separation from sphere a to sphere b, by the minimum image in a periodic box (a pair in
 * contact is closer than half a period, so this is the image that touches; stored positions
 * are never more than a period apart, so the comparing form serves). */
static nbep_vec3 sep(const pred_ctx *c, const nbep_state *s, size_t a, size_t b)
{
    nbep_vec3 d = nbep_vec3_sub(s->pos[b], s->pos[a]);
    return c->pb.any ? nbep_periodic_near_image(&c->pb, d) : d;
}

/* The minimum bounce's time (MIN_BOUNCE_STEP_FRACTION) for radius r pressed by an acceleration
 * of magnitude a > 0. */
static double min_bounce_time(double r, double a, double dt)
{
    return fmin(MIN_BOUNCE_STEP_FRACTION * dt, sqrt(8.0 * MIN_BOUNCE_REL_HEIGHT * r / a));
}

/* The rest speed of sphere i pressed by an acceleration of magnitude amag (see "Lasting
 * sphere-sphere contacts"): amag t_min, twice the speed the minimum bounce leaves with, the
 * speed it comes back at. 0 when nothing presses. */
static double rest_speed(const nbep_state *s, size_t i, double amag, double dt)
{
    return amag > 0.0 ? amag * min_bounce_time(s->radius[i], amag, dt) : 0.0;
}

/* A sphere whose contacts carry its whole weight (it may still slide): a slow partner treats it
 * as part of the support. */
static bool supported(const pred_ctx *c, size_t i)
{
    return c->rest && c->rest[i].n > 0 && is_zero(c->aeff[i]);
}

static bool rest_has_plane(const rest_set *r, size_t p)
{
    for (int k = 0; k < r->n; k++)
        if (r->who[k] == (int32_t)p)
            return true;
    return false;
}

/* Whether r (a held sphere's contacts) names sphere k among its supports. */
static bool rest_has_sphere(const rest_set *r, size_t k)
{
    for (int q = 0; q < r->n; q++)
        if (r->who[q] == -1 - (int32_t)k)
            return true;
    return false;
}

/* Unit normals of the contacts of r, from support to sphere i. */
static void rest_normals(const pred_ctx *c, const nbep_state *s, size_t i, const rest_set *r,
                         nbep_vec3 *n)
{
    for (int k = 0; k < r->n; k++) {
        if (r->who[k] >= 0) {
            n[k] = s->plane_normal[r->who[k]];
        } else {
            nbep_vec3 d = sep(c, s, (size_t)(-1 - r->who[k]), i);
            double len = nbep_vec3_norm(d);
            n[k] = nbep_vec3_make(d.x / len, d.y / len, d.z / len);
        }
    }
}

/* Sphere contacts hold a sphere still when they leave it at most this fraction of its
 * acceleration. A sphere contact is taken on within a gap (the pocket and settling
 * tolerances: at most 8 MIN_BOUNCE_REL_HEIGHT of the radius, twice the highest hop of a
 * minimum bounce), so its normal is known to about 4 MIN_BOUNCE_REL_HEIGHT radians only; what
 * is left below that is a slope the geometry does not resolve (measured: a sphere in the
 * groove between two held floor spheres, another held one above it, a wall at its end; the
 * groove tilted 3e-7 by where the spheres had settled, and the sphere, not held, bounced a
 * million times in one step between the groove and the sphere above, a 300-sphere pour, seed
 * 3, step 1429). Planes are exact: on planes alone the tolerance is NBEP_CONTACT_TOL. */
#define HOLD_SLOPE MIN_BOUNCE_REL_HEIGHT

/* Solves the contacts r of sphere i with velocity *v: keeps the contacts that carry load,
 * writes the acceleration left (*a) and, when tangent, removes v's components along them.
 * A sphere contact is only valid while the sphere is held still (a tangent plane would let
 * it float off a curved support); if the result is not still, sphere contacts are dropped
 * and the planes solved alone. Returns the still flag. */
static bool rest_solve(const pred_ctx *c, const nbep_state *s, size_t i, rest_set *r,
                       nbep_vec3 *v, nbep_vec3 *a, double dt, bool tangent)
{
    nbep_vec3 n[NBEP_CONTACT_MAX];
    for (int pass = 0; pass < 2; pass++) {
        rest_normals(c, s, i, r, n);
        unsigned act;
        *a = nbep_contact_project(s->acc[i], n, r->n, &act);
        if (tangent)
            *v = nbep_contact_tangent(*v, n, r->n, act);
        rest_set k = {.n = 0};
        bool spheres = false;
        for (int j = 0; j < r->n; j++)
            if (act >> j & 1u) {
                k.who[k.n] = r->who[j];
                k.ver[k.n++] = r->ver[j];
                spheres |= r->who[j] < 0;
            }
        *r = k;
        double amag = nbep_vec3_norm(s->acc[i]);
        if (r->n > 0 && nbep_vec3_norm(*a) <= (spheres ? HOLD_SLOPE : NBEP_CONTACT_TOL) * amag) {
            *a = nbep_vec3_make(0.0, 0.0, 0.0);
            if (nbep_vec3_norm(*v) <= rest_speed(s, i, amag, dt))
                *v = nbep_vec3_make(0.0, 0.0, 0.0);
        }
        r->still = r->n > 0 && is_zero(*a) && is_zero(*v);
        if (r->still || !spheres)
            return r->still;
        k.n = 0; /* sphere contacts without being held: planes only */
        for (int j = 0; j < r->n; j++)
            if (r->who[j] >= 0)
                k.who[k.n++] = r->who[j];
        *r = k;
    }
    return r->still;
}

static bool is_fresh(const pred_ctx *c, size_t i, const nbep_event *ev)
{
    if (ev->kind == NBEP_EVENT_NONE || ev->ver_self != c->ver[i])
        return false;
    return ev->kind != NBEP_EVENT_SPHERE || ev->ver_partner == c->ver[ev->partner];
}

static void keep_earlier(nbep_event *best, nbep_event e)
{
    if (e.time < NBEP_NEVER && (best->kind == NBEP_EVENT_NONE || nbep_feq_event_before(&e, best)))
        *best = e;
}

/* The relative motion of spheres i (flying with ai) and j, each at its own local time, both
 * brought to the later of the two (t0): dp, dv, da and their contact distance. j is taken at
 * its position plus shift (its copy across periodic faces; zero otherwise). */
typedef struct pair_rel {
    nbep_vec3 dp, dv, da;
    double t0, sigma;
} pair_rel;

static pair_rel pair_relative(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 ai,
                              size_t j, nbep_vec3 shift)
{
    const double ti = c->tau[i], tj = c->tau[j];
    const double t0 = ti > tj ? ti : tj;
    nbep_vec3 pi = s->pos[i], vi = s->vel[i], pj = s->pos[j], vj = s->vel[j];
    if (c->pb.any)
        pj = nbep_vec3_add(pj, shift);
    const nbep_vec3 aj = effective_acc(c, s, j);
    if (ti < t0)
        nbep_physics_drift(&pi, &vi, ai, t0 - ti);
    if (tj < t0)
        nbep_physics_drift(&pj, &vj, aj, t0 - tj);
    return (pair_rel){nbep_vec3_sub(pj, pi), nbep_vec3_sub(vj, vi), nbep_vec3_sub(aj, ai), t0,
                      s->radius[i] + s->radius[j]};
}

/* The earliest the pair r can touch, from the step's start T0 (nbep_predict_pair_bound, or
 * nbep_predict_pair_quadratic_bound for a pair with equal accelerations, whose motion relative
 * to each other is straight): NBEP_NEVER where it never can. Rounding is monotone, so the time
 * of the root, no earlier than the bound, is no earlier than this either. Until 2026-11-27 a
 * pair with equal accelerations took no bound (its root, a quadratic's, was thought to cost
 * about what a bound would); the quadratic bound, without a square root or a branch, lets
 * keep_pairs skip the roots of receding and passing pairs and of those the best so far rules
 * out: paired runs, the same bits, 0.81 to 0.88 of the time for the paper's box in grid mode,
 * 0.93 for a 300-sphere pour, 0.96 for the 400-sphere hopper, about 0.9 for the 2000-sphere
 * pile at 1.6 s, all in cells mode but the box. */
static double pair_earliest(const pair_rel *r, double T0)
{
    if (r->da.x == 0.0 && r->da.y == 0.0 && r->da.z == 0.0) {
        const double lb = nbep_predict_pair_quadratic_bound(r->dp, r->dv, r->sigma);
        return lb == NBEP_NEVER ? NBEP_NEVER : T0 + (r->t0 + lb);
    }
    const double lb = nbep_predict_pair_bound(r->dp, r->dv, r->da, r->sigma);
    return lb == NBEP_NEVER ? NBEP_NEVER : T0 + (r->t0 + lb);
}

/* Whether a pair that can touch no earlier than `earliest` may still come before *best (ties
 * may: the partner decides them). */
static bool may_beat(const nbep_event *best, double earliest)
{
    return earliest < NBEP_NEVER && (best->kind == NBEP_EVENT_NONE || !(earliest > best->time));
}

/* How far from T0 + t0 a pair's contact may come and still beat *best or tie with it (for
 * nbep_predict_pair_within): T0 + (t0 + dt) can round to best's time or below only while dt
 * is below best - T0 - t0 plus the roundings of those sums, each under an ulp of the largest
 * of |best|, |T0|, |t0| and |dt| (dt is near best - T0 - t0 there); 16 ulps of their sum is
 * far more. No best: no limit. */
static double beat_cap(const nbep_event *best, double T0, double t0)
{
    if (best->kind == NBEP_EVENT_NONE || !(best->time < NBEP_NEVER))
        return INFINITY;
    const double d = best->time - T0 - t0;
    return d + 16.0 * DBL_EPSILON * (fabs(best->time) + fabs(T0) + fabs(t0));
}

/* The contact of spheres i (flying with ai) and j (pair_relative), stamped with both response
 * counts: the paper's all-pairs loop, which solves every pair (its pairs share one
 * acceleration in the paper's box, and a bound per pair slowed its step by a quarter). */
static nbep_event pair_event(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 ai,
                             size_t j, nbep_vec3 shift, double T0, thread_ws *w)
{
    const pair_rel r = pair_relative(c, s, i, ai, j, shift);
    const double dt = nbep_predict_pair(r.dp, r.dv, r.da, r.sigma, w->pws);
    return (nbep_event){T0 + (r.t0 + dt), (uint32_t)j, NBEP_EVENT_SPHERE, c->ver[i], c->ver[j]};
}

/* keep_earlier of the contact of spheres i and j, moving relative to each other as r says
 * (pair_relative), stamped with both response counts; not solved where it can touch no
 * earlier than `earliest` (pair_earliest) and that cannot come before *best: *best ends the
 * same, bit for bit. */
static void keep_rel(nbep_event *best, const pred_ctx *c, size_t i, size_t j, const pair_rel *r,
                     double earliest, double T0, thread_ws *w)
{
    if (!may_beat(best, earliest))
        return;
    const double dt =
        nbep_predict_pair_within(r->dp, r->dv, r->da, r->sigma, beat_cap(best, T0, r->t0), w->pws);
    keep_earlier(best, (nbep_event){T0 + (r->t0 + dt), (uint32_t)j, NBEP_EVENT_SPHERE, c->ver[i],
                                    c->ver[j]});
}

/* Where neighbour j is compared with sphere i: at its image nearest to i in a periodic box
 * (the shift to add to its position), at itself otherwise. */
static inline nbep_vec3 neighbour_shift(const pred_ctx *c, const nbep_state *s, size_t i,
                                        size_t j)
{
    return nbep_periodic_near_shift(&c->pb, nbep_vec3_sub(s->pos[j], s->pos[i]));
}

/* Partners whose relative motions keep_pairs holds at once (a list of a fluid or a pile has
 * about 10 to 40; a grid block as many or more, taken 32 at a time). */
#define PAIRS_BATCH 32

/* keep_rel of sphere i (flying with ai) and each of js[0..m) (pair_relative, pair_earliest), j
 * at its nearest image when images: *best ends the same, bit for bit, as solving every pair in
 * list order would leave it. In each
 * batch of partners the pair that can touch first is solved first, so that its root (a
 * quartic where the two accelerate differently: a settling pile, where this was most of the
 * run) lets most of the others go unsolved; keep_earlier's winner is the same in any order
 * (cells_pairs_free). */
static void keep_pairs(nbep_event *best, const pred_ctx *c, const nbep_state *s, uint32_t i,
                       nbep_vec3 ai, const uint32_t *js, size_t m, bool images, double T0,
                       thread_ws *w)
{
    pair_rel rel[PAIRS_BATCH];
    double earliest[PAIRS_BATCH];
    for (size_t k0 = 0; k0 < m; k0 += PAIRS_BATCH) {
        const size_t n = m - k0 < PAIRS_BATCH ? m - k0 : PAIRS_BATCH;
        size_t first = 0;
        for (size_t q = 0; q < n; q++) {
            const uint32_t j = js[k0 + q];
            rel[q] = pair_relative(c, s, i, ai, j, images ? neighbour_shift(c, s, i, j) : ZERO3);
            earliest[q] = pair_earliest(&rel[q], T0);
            first = earliest[q] < earliest[first] ? q : first;
        }
        for (size_t q = 0; q < n; q++) { /* first, then the others in list order */
            const size_t k = q == 0 ? first : q == first ? 0 : q;
            keep_rel(best, c, i, js[k0 + k], &rel[k], earliest[k], T0, w);
        }
    }
}

/* All-pairs mode in a periodic box: when sphere i (at its local time) will have strayed
 * image_reach from here along a periodic axis (kind HORIZON, partner n_planes so that it ranks
 * after the planes); NBEP_NEVER when it does not move. */
static nbep_event image_horizon(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 ai,
                                double T0)
{
    const double D = c->image_reach;
    const double v[3] = {s->vel[i].x, s->vel[i].y, s->vel[i].z}, a[3] = {ai.x, ai.y, ai.z};
    double t = NBEP_NEVER;
    for (int k = 0; k < 3; k++)
        if (c->pb.axis[k])
            t = fmin(t, fmin(nbep_predict_plane(D, v[k], a[k]),
                             nbep_predict_plane(D, -v[k], -a[k])));
    return (nbep_event){T0 + (c->tau[i] + t), (uint32_t)s->n_planes, NBEP_EVENT_HORIZON,
                        c->ver[i], 0};
}

/* Paper Procedure 9, one thread's share: the earliest event of sphere i with the spheres
 * [lo, hi) (each at its own local time; a pair is compared at the later of the two) and, when
 * with_planes, with every plane. T0 is the step's start time. Returns kind NONE if none. */
static nbep_event predict_some(const pred_ctx *c, const nbep_state *s, size_t i, size_t lo,
                               size_t hi, bool with_planes, double T0, thread_ws *w,
                               nbep_counters *cnt)
{
    nbep_event best = {.time = NBEP_NEVER, .kind = NBEP_EVENT_NONE};
    const double ti = c->tau[i];
    const nbep_vec3 ai = effective_acc(c, s, i);
    if (with_planes) {
        const double speed = nbep_vec3_norm(s->vel[i]);
        for (size_t p = 0; p < s->n_planes; p++) {
            if (c->rest && rest_has_plane(&c->rest[i], p))
                continue;
            nbep_vec3 n = s->plane_normal[p];
            double gap = nbep_physics_plane_gap(n, s->plane_offset[p], s->pos[i], s->radius[i]);
            double dt = nbep_predict_plane_contact(gap, nbep_vec3_dot(n, s->vel[i]),
                                                   nbep_vec3_dot(n, ai), speed);
            keep_earlier(&best, (nbep_event){T0 + (ti + dt), (uint32_t)p, NBEP_EVENT_PLANE,
                                             c->ver[i], 0});
        }
        cnt->c[NBEP_COUNTER_PREDICTIONS] += s->n_planes;
        if (c->image_horizon)
            keep_earlier(&best, image_horizon(c, s, i, ai, T0));
    }
    for (size_t j = lo; j < hi; j++) {
        if (j == i)
            continue;
        nbep_vec3 shift = ZERO3;
        if (c->pb.any) { /* all-pairs in a periodic box: j's nearest image */
            int cells[3];
            nbep_periodic_nearest(&c->pb, nbep_vec3_sub(s->pos[j], s->pos[i]), cells);
            shift = nbep_periodic_shift(&c->pb, cells);
        }
        keep_earlier(&best, pair_event(c, s, i, ai, j, shift, T0, w));
    }
    cnt->c[NBEP_COUNTER_PREDICTIONS] += hi - lo - (i >= lo && i < hi);
    return best;
}

/* Grid mode (beyond the paper): the earliest event of sphere i before the horizon, testing
 * every plane but only the spheres that can reach i by then; "horizon" when there is none.
 * A partner j sat in its cell at the step's start and has moved at most V t + amax t^2 / 2
 * since (V: the fastest sphere at the step's start or after any reaction so far this step), and
 * i moves at most |v_i| H + |a_i| H^2 / 2 before the horizon, so partners farther than the sum
 * of those and the radii cannot touch i before it. A partner whose course changes later is
 * re-predicted itself and finds i then, as in the paper's argument for one-sided inserts. */
static nbep_event predict_grid(const pred_ctx *c, const nbep_state *s, size_t i, double T0,
                               double V, thread_ws *w, nbep_counters *cnt)
{
    nbep_event best = predict_some(c, s, i, 0, 0, true, T0, w, cnt); /* the planes */
    /* beyond the horizon nothing is known (a partner from farther away may come first): the
     * horizon stands for anything later before the pairs are tried, so that a pair that
     * cannot touch by then goes unsolved (most of a settling pile's quartics). A pair
     * touching at the horizon itself still comes first, as it did when the horizon replaced
     * a later best at the end: at one time a sphere event ranks before a horizon. */
    if (best.kind == NBEP_EVENT_NONE || !(best.time <= c->horizon))
        best = (nbep_event){c->horizon, 0, NBEP_EVENT_HORIZON, c->ver[i], 0};
    const double H = c->horizon - T0;
    const nbep_vec3 ai = effective_acc(c, s, i);
    double reach = s->radius[i] + c->rmax + nbep_vec3_norm(s->vel[i]) * H +
                   0.5 * nbep_vec3_norm(ai) * H * H + V * H + 0.5 * c->amax * H * H;
    size_t lo[3], hi[3];
    uint64_t tested = 0;
    uint32_t js[PAIRS_BATCH]; /* the partners, a batch at a time (keep_pairs) */
    size_t m = 0;
    nbep_grid_block(&c->grid, s->pos[i], reach, lo, hi);
    for (size_t z = lo[2]; z <= hi[2]; z++)
        for (size_t y = lo[1]; y <= hi[1]; y++)
            for (size_t x = lo[0]; x <= hi[0]; x++) {
                size_t cell = nbep_grid_index(&c->grid, x, y, z);
                for (size_t k = c->grid.start[cell]; k < c->grid.start[cell + 1]; k++) {
                    const uint32_t j = c->grid.item[k];
                    if (j == i)
                        continue;
                    js[m++] = j;
                    if (m == PAIRS_BATCH) {
                        keep_pairs(&best, c, s, (uint32_t)i, ai, js, m, false, T0, w);
                        tested += m;
                        m = 0;
                    }
                }
            }
    keep_pairs(&best, c, s, (uint32_t)i, ai, js, m, false, T0, w);
    tested += m;
    cnt->c[NBEP_COUNTER_PREDICTIONS] += tested;
    return best;
}

/* The bounds of every thread's centres (each thread's grid_lo and grid_hi), in *lo and *hi:
 * min and max are exact, so the result is the same for any thread count. */
static void merged_bounds(const pred_ctx *c, nbep_vec3 *lo, nbep_vec3 *hi)
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

/* Grid mode, every thread at a step's start (every sphere at T0, no thread reading the grid:
 * the find phase that follows reads none): the grid of the centres, built by all threads
 * (grid.h: the same grid whatever their number; four barriers), and the horizon: predictions
 * look up to H = T0 + k dt, k chosen so that the fastest sphere travels at most half a cell by
 * then (at least one step, at most 64). The speed bounds are the whole scene's: each thread's
 * own, measured in the update (or here, at the first step). */
static void grid_prepare(pred_ctx *c, const nbep_state *s, int tid, nbep_range own, double T0,
                         double dt, bool first)
{
    thread_ws *w = &c->ws[tid];
    const int nt = c->nt;
    if (first) {
        double vmax = 0.0, amax = 0.0;
        for (size_t i = own.lo; i < own.hi; i++) {
            vmax = fmax(vmax, nbep_vec3_norm(s->vel[i]));
            amax = fmax(amax, nbep_vec3_norm(effective_acc(c, s, i)));
        }
        w->vmax_end = vmax;
        w->amax_end = amax;
    }
    nbep_grid_bounds(s->pos, own.lo, own.hi, &w->grid_lo, &w->grid_hi);
    nbep_barrier_wait(&c->bar);
    if (tid == 0) {
        double vmax = 0.0, amax = 0.0;
        for (int t = 0; t < nt; t++) {
            vmax = fmax(vmax, c->ws[t].vmax_end);
            amax = fmax(amax, c->ws[t].amax_end);
        }
        nbep_vec3 lo, hi;
        merged_bounds(c, &lo, &hi);
        nbep_grid_size(&c->grid, lo, hi, s->n, 2.0 * c->rmax);
        double step_travel = vmax * dt + 0.5 * amax * dt * dt;
        double k = step_travel > 0.0 ? floor(0.5 * c->grid.h / step_travel) : 64.0;
        k = fmin(fmax(k, 1.0), 64.0);
        c->vmax = vmax;
        c->amax = amax;
        /* at least the step's end, exactly: a horizon inside the step would recur forever */
        c->horizon = fmax(T0 + k * dt, T0 + dt);
        for (int t = 0; t < nt; t++)
            c->ws[t].vmax_react = 0.0;
    }
    nbep_barrier_wait(&c->bar);
    nbep_grid_assign(&c->grid, s->pos, own.lo, own.hi);
    nbep_barrier_wait(&c->bar);
    const nbep_range cells = nbep__range_split(nbep_grid_cells(&c->grid), tid, nt);
    w->grid_sum = nbep_grid_count(&c->grid, cells.lo, cells.hi);
    nbep_barrier_wait(&c->bar);
    size_t offset = 0;
    for (int t = 0; t < tid; t++)
        offset += c->ws[t].grid_sum;
    nbep_grid_place(&c->grid, cells.lo, cells.hi, offset);
}

static void add_cand(pred_ctx *c, thread_ws *w, size_t i)
{
    if (!(c->flags[i] & IN_CAND)) {
        c->flags[i] |= IN_CAND;
        w->cand[w->n_cand++] = (uint32_t)i;
    }
}

static void add_redo(pred_ctx *c, thread_ws *w, size_t i)
{
    if (!(c->flags[i] & IN_REDO)) {
        c->flags[i] |= IN_REDO;
        w->redo[w->n_redo++] = (uint32_t)i;
    }
}

/* The find sub-phase of one round (paper Procedures 12 and 13), own spheres only: the first
 * round of a step examines every own slot (stale or invalid -> redo, event before T_end ->
 * candidate); later rounds only the own candidates and the own spheres that reacted (in the
 * reactions of the crew's threads, 0 .. crew - 1). */
static void find_phase(pred_ctx *c, nbep_range own, int crew, bool first, double T_end,
                       thread_ws *w, nbep_counters *cnt)
{
    w->n_redo = 0;
    if (first) {
        w->n_cand = 0;
        for (size_t i = own.lo; i < own.hi; i++) {
            const nbep_event *ev = nbep_feq_slot(c->q, i);
            if (!is_fresh(c, i, ev) || (ev->kind == NBEP_EVENT_HORIZON && ev->time < T_end))
                add_redo(c, w, i);
            else if (ev->time < T_end)
                add_cand(c, w, i);
        }
        cnt->c[NBEP_COUNTER_CHECKS] += own.hi - own.lo;
    } else {
        for (int t = 0; t < crew; t++) {
            const thread_ws *o = &c->ws[t];
            for (size_t k = 0; k < o->n_fired; k++) {
                size_t i = o->fired[k];
                if (i >= own.lo && i < own.hi)
                    add_redo(c, w, i);
            }
        }
        size_t m = 0;
        for (size_t k = 0; k < w->n_cand; k++) {
            size_t i = w->cand[k];
            if (!(c->flags[i] & IN_REDO) && is_fresh(c, i, nbep_feq_slot(c->q, i))) {
                w->cand[m++] = (uint32_t)i;
                continue;
            }
            c->flags[i] &= (uint8_t)~IN_CAND;
            add_redo(c, w, i);
        }
        cnt->c[NBEP_COUNTER_CHECKS] += w->n_cand;
        w->n_cand = m;
    }
}

static double cand_t_min(const pred_ctx *c, const thread_ws *w)
{
    double t_min = INFINITY;
    for (size_t k = 0; k < w->n_cand; k++)
        t_min = fmin(t_min, nbep_feq_slot(c->q, w->cand[k])->time);
    return t_min;
}

/* Re-prediction of every thread's redo spheres, shared by the crew's threads (0 .. crew - 1,
 * meeting at bar) chunk by chunk: each thread finds each sphere's best event among its own
 * partners (and thread 0 the planes); then each owner keeps the earliest of the partial bests
 * (the order of nbep_feq_insert is strict, so the result is the same for any split) and adds
 * it to its candidates. Every thread of the crew calls this with the same totals; it ends
 * with a barrier.
 * setup: the run, for the initial predictions (else NULL). All-pairs mode's take n^2/2 pair
 * tests, minutes for 30000 spheres on one core, and a job's time limit may send its SIGTERM
 * meanwhile: thread 0 looks at the stop signal once a chunk, between the chunk's barriers,
 * and sets setup->stop; after the chunk's last barrier every thread sees it and returns (the
 * slots left unpredicted are never used: the run ends at step 0, whose frame is written). */
static void redo_phase(pred_ctx *c, const nbep_state *s, nbep_range own, int tid, int crew,
                       nbep_barrier *bar, double T0, double T_end, thread_ws *w,
                       nbep_counters *cnt, nbep_sim *setup)
{
    size_t total = 0;
    double V = c->vmax;
    for (int t = 0; t < crew; t++) {
        total += c->ws[t].n_redo;
        V = fmax(V, c->ws[t].vmax_react);
    }
    for (size_t off = 0; off < total; off += CHUNK) {
        size_t end = off + CHUNK < total ? off + CHUNK : total;
        /* this thread's partial best for every sphere of the chunk */
        size_t base = 0;
        for (int t = 0; t < crew; t++) {
            const thread_ws *o = &c->ws[t];
            size_t lo = off > base ? off - base : 0;
            size_t hi = end - base < o->n_redo ? end - base : o->n_redo;
            for (size_t k = lo; k < hi && base + k < end; k++) {
                nbep_event *out = &w->part[base + k - off];
                if (!c->use_grid) /* every thread takes its own range of partners */
                    *out = predict_some(c, s, o->redo[k], own.lo, own.hi, tid == 0, T0, w, cnt);
                else if ((base + k) % (size_t)crew == (size_t)tid) /* a few partners: one */
                    *out = predict_grid(c, s, o->redo[k], T0, V, w, cnt); /* thread each */
                else
                    *out = (nbep_event){.time = NBEP_NEVER, .kind = NBEP_EVENT_NONE};
            }
            base += o->n_redo;
            if (base >= end)
                break;
        }
        nbep_barrier_wait(bar);
        /* owners merge their spheres of the chunk */
        base = 0;
        for (int t = 0; t < tid; t++)
            base += c->ws[t].n_redo;
        for (size_t k = 0; k < w->n_redo; k++) {
            size_t g = base + k;
            if (g < off || g >= end)
                continue;
            size_t i = w->redo[k];
            nbep_event best = {.time = NBEP_NEVER, .kind = NBEP_EVENT_NONE};
            for (int t = 0; t < crew; t++)
                if (c->ws[t].part[g - off].kind != NBEP_EVENT_NONE)
                    keep_earlier(&best, c->ws[t].part[g - off]);
            if (best.kind == NBEP_EVENT_NONE) {
                nbep_feq_set_never(c->q, i, c->ver[i]);
            } else {
                nbep_feq_remove(c->q, i);
                nbep_feq_insert(c->q, i, best);
            }
            c->flags[i] &= (uint8_t)~IN_REDO;
            if (best.time < T_end &&
                (best.kind == NBEP_EVENT_SPHERE || best.kind == NBEP_EVENT_PLANE ||
                 (best.kind == NBEP_EVENT_HORIZON && c->image_horizon)))
                add_cand(c, w, i);
        }
        if (setup && tid == 0 && nbep_sim_stop_status(setup->opt.stop_signal) != NBEP_OK)
            atomic_store_explicit(&setup->stop, 1, memory_order_relaxed);
        nbep_barrier_wait(bar);
        /* relaxed: the barrier above ordered thread 0's store */
        if (setup && atomic_load_explicit(&setup->stop, memory_order_relaxed))
            return;
    }
}

/* The ordering key of an event: lower sphere in the high half, then the partner; planes
 * (stored as UINT32_MAX - plane) after every sphere, and an image horizon after the planes.
 * Equal for both copies of one pair. */
static uint64_t event_key(size_t i, const nbep_event *ev, uint32_t *lo, uint32_t *hi)
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

/* Keeps the smaller key in a claim word. relaxed: claims are read only after the barrier that
 * ends the claim phase, which orders every claim before every read. */
static void claim_min(_Atomic uint64_t *word, uint64_t key)
{
    uint64_t cur = atomic_load_explicit(word, memory_order_relaxed);
    while (key < cur &&
           !atomic_compare_exchange_weak_explicit(word, &cur, key, memory_order_relaxed,
                                                  memory_order_relaxed)) {
    }
}

/* run.order = "step": an event time as a claim word. Event times are absolute and a run
 * starts at t = 0, so they are >= +0, and the bits of non-negative doubles order as the
 * numbers do (+inf and KEY_FREE above every finite time). */
static uint64_t time_word(double t)
{
    uint64_t u;
    memcpy(&u, &t, sizeof u);
    return u;
}

/* run.order = "step", the first of two claims: every candidate claims both its spheres with
 * its time, the earliest winning. An event of sphere i's slot may name a partner j whose own
 * slot holds a later event (inserts are one-sided: j was not re-predicted when i found the
 * pair), so a sphere's earliest event is found here, not in its slot. relaxed: read only in
 * claim_phase and react_phase, after the barrier that ends this phase; reset at the next
 * round's start, after the barrier that ends react_phase. */
static void claim_time_phase(pred_ctx *c, thread_ws *w)
{
    w->n_tclaimed = 0;
    for (size_t k = 0; k < w->n_cand; k++) {
        size_t i = w->cand[k];
        const nbep_event *ev = nbep_feq_slot(c->q, i);
        uint32_t lo, hi;
        (void)event_key(i, ev, &lo, &hi);
        const uint64_t t = time_word(ev->time);
        claim_min(&c->tclaim[lo], t);
        w->tclaimed[w->n_tclaimed++] = lo;
        if (ev->kind == NBEP_EVENT_SPHERE) {
            claim_min(&c->tclaim[hi], t);
            w->tclaimed[w->n_tclaimed++] = hi;
        }
    }
}

/* run.order = "step": the event is the earliest of both its spheres (it may share that time
 * with another event of one of them: the pair key decides in claim_phase). */
static bool holds_time(const pred_ctx *c, const nbep_event *ev, uint32_t lo, uint32_t hi)
{
    const uint64_t t = time_word(ev->time);
    return atomic_load_explicit(&c->tclaim[lo], memory_order_relaxed) == t &&
           (ev->kind != NBEP_EVENT_SPHERE ||
            atomic_load_explicit(&c->tclaim[hi], memory_order_relaxed) == t);
}

/* Each event at t_min (run.order = "step": each event holding both its time claims) claims
 * both its spheres with its pair key, the smallest winning. */
static void claim_phase(pred_ctx *c, int par, double t_min, thread_ws *w)
{
    w->n_claimed = 0;
    for (size_t k = 0; k < w->n_cand; k++) {
        size_t i = w->cand[k];
        const nbep_event *ev = nbep_feq_slot(c->q, i);
        if (!c->order_step && ev->time != t_min)
            continue;
        uint32_t lo, hi;
        uint64_t key = event_key(i, ev, &lo, &hi);
        if (c->order_step && !holds_time(c, ev, lo, hi))
            continue;
        claim_min(&c->claim[par][lo], key);
        w->claimed[w->n_claimed++] = lo;
        if (ev->kind == NBEP_EVENT_SPHERE) {
            claim_min(&c->claim[par][hi], key);
            w->claimed[w->n_claimed++] = hi;
        }
    }
}

/* What sphere i's plane contacts leave of a unit impulse direction u (frictionless: they push,
 * never pull; contact.h): u itself when it has none. Sphere contacts do not count: a response
 * lets go of them. *leans is set when i has a plane contact. */
static nbep_vec3 plane_mobility(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 u,
                                bool *leans)
{
    if (!c->rest)
        return u;
    const rest_set *r = &c->rest[i];
    nbep_vec3 n[NBEP_CONTACT_MAX];
    int k = 0;
    for (int j = 0; j < r->n; j++)
        if (r->who[j] >= 0)
            n[k++] = s->plane_normal[r->who[j]];
    unsigned act;
    *leans |= k > 0;
    return k == 0 ? u : nbep_contact_project(u, n, k, &act);
}

/* After a response, a sphere leaves every contact along whose normal it now moves (and its
 * sphere contacts if it moves at all); the rest are solved again. A plane counts as left only
 * beyond round-off: a response along a tilted plane leaves v.n at a few ulps of |v|. */
static void update_rest(pred_ctx *c, nbep_state *s, size_t i, double dt)
{
    if (!c->rest || c->rest[i].n == 0)
        return;
    rest_set *r = &c->rest[i];
    nbep_vec3 n[NBEP_CONTACT_MAX];
    rest_normals(c, s, i, r, n);
    rest_set k = {.n = 0};
    for (int j = 0; j < r->n; j++)
        if (r->who[j] >= 0 ? fabs(nbep_vec3_dot(s->vel[i], n[j])) <=
                                 NBEP_CONTACT_TOL * nbep_vec3_norm(s->vel[i])
                           : nbep_vec3_dot(s->vel[i], n[j]) == 0.0 && is_zero(s->vel[i])) {
            k.who[k.n] = r->who[j];
            k.ver[k.n++] = r->ver[j];
        }
    *r = k;
    rest_solve(c, s, i, r, &s->vel[i], &c->aeff[i], dt, true);
}

/* Sphere i's speed now counts towards its step's highest (SETTLE_STEPS). */
static void settle_note(pred_ctx *c, const nbep_state *s, size_t i)
{
    if (c->settle)
        c->settle[i].peak2 = fmax(c->settle[i].peak2, nbep_vec3_norm2(s->vel[i]));
}

static void advance_to(pred_ctx *c, nbep_state *s, size_t i, double t_local)
{
    double h = t_local - c->tau[i];
    if (h > 0.0)
        nbep_physics_drift(&s->pos[i], &s->vel[i], effective_acc(c, s, i), h);
    c->tau[i] = t_local;
    settle_note(c, s, i);
}

static void note_overlap(nbep_thread_max *mx, double ov, double r)
{
    if (ov > mx->overlap)
        mx->overlap = ov;
    if (ov / r > mx->overlap_rel)
        mx->overlap_rel = ov / r;
}

/* See MIN_BOUNCE_STEP_FRACTION: a pair pressed together by its accelerations leaves with at
 * least the separating speed that keeps it apart for t_min, given as an impulse along the line
 * of centres shared by mass like a response (momentum is kept). */
static void min_bounce(const pred_ctx *c, nbep_state *s, double dt, uint32_t lo, uint32_t hi)
{
    if (!c->aeff)
        return; /* nothing accelerates: nothing presses a pair together */
    nbep_vec3 dp = sep(c, s, lo, hi);
    double dist = nbep_vec3_norm(dp);
    if (!(dist > 0.0))
        return;
    nbep_vec3 n = nbep_vec3_scale(dp, 1.0 / dist);
    double an = nbep_vec3_dot(nbep_vec3_sub(effective_acc(c, s, hi), effective_acc(c, s, lo)), n);
    if (!(an < 0.0))
        return; /* nothing presses them together: they part for good */
    double rmin = fmin(s->radius[lo], s->radius[hi]);
    double t_min = min_bounce_time(rmin, -an, dt);
    double want = -an * t_min / 2.0;
    double u = nbep_vec3_dot(nbep_vec3_sub(s->vel[hi], s->vel[lo]), n);
    if (u >= want)
        return;
    double m = s->mass[lo] + s->mass[hi], du = want - u;
    /* a sphere whose planes carry its weight takes no share: the kick would otherwise pump
     * energy into the bottom of a pile, kick after kick (measured: a settled pile heats up) */
    double share_lo = s->mass[hi] / m, share_hi = s->mass[lo] / m;
    if (supported(c, lo) != supported(c, hi)) {
        share_lo = supported(c, lo) ? 0.0 : 1.0;
        share_hi = 1.0 - share_lo;
    }
    s->vel[lo] = nbep_vec3_axpy(s->vel[lo], -du * share_lo, n);
    s->vel[hi] = nbep_vec3_axpy(s->vel[hi], du * share_hi, n);
}

/* A sphere k without support pressed onto a held sphere j (n from j to k) leaves it with at
 * least the separating speed that keeps it off for t_min (see MIN_BOUNCE_STEP_FRACTION); j, held
 * by the pile, does not move. */
static void min_bounce_held(const pred_ctx *c, nbep_state *s, double dt, size_t k, size_t j,
                            nbep_vec3 n)
{
    double an = nbep_vec3_dot(c->aeff[k], n);
    if (!(an < 0.0))
        return;
    double rmin = fmin(s->radius[k], s->radius[j]);
    double t_min = min_bounce_time(rmin, -an, dt);
    double want = -an * t_min / 2.0, u = nbep_vec3_dot(s->vel[k], n);
    if (u < want)
        s->vel[k] = nbep_vec3_axpy(s->vel[k], want - u, n);
}

/* The TC model (Luding and McNamara 1998; DynamO's choice): a collision within tc of the last
 * one of either sphere is elastic (here planes count too: a sphere squeezed between a wall and
 * a neighbour collapses just the same; for a plane, a == b). Inelastic collapse needs ever faster
 * re-collisions; these stop dissipating, so the sequence ends. tc is physically the duration
 * of a real contact, during which a hard-sphere model has no business dissipating twice. */
static double tc_restitution(pred_ctx *c, double tc, double e, double t_abs, size_t a, size_t b)
{
    if (!c->t_last) /* e = 1 or tc = 0: the model never changes e */
        return e;
    bool recent = t_abs - c->t_last[a] < tc || t_abs - c->t_last[b] < tc;
    c->t_last[a] = t_abs;
    c->t_last[b] = t_abs;
    return recent ? 1.0 : e;
}

static void fire(pred_ctx *c, thread_ws *w, const nbep_state *s, size_t i, bool was_still)
{
    c->ver[i]++;
    settle_note(c, s, i);
    if (was_still && c->settle) /* woken: its window starts again (a sphere let go at rest is
                                 * slow for a while as it starts to fall) */
        c->settle[i].slow = 0;
    if (c->jam) { /* run.max_reactions; i is this thread's to change (it reacts or lets go) */
        jam_count *j = &c->jam[i];
        if (j->step != w->jam_step)
            *j = (jam_count){.step = w->jam_step, .n = 0};
        if (++j->n > c->jam_max && (w->jammed == 0 || i + 1 < w->jammed))
            w->jammed = (uint32_t)i + 1;
    }
    w->fired[w->n_fired++] = (uint32_t)i;
    if (c->use_grid) /* the grid's speed bound (grid_prepare) */
        w->vmax_react = fmax(w->vmax_react, nbep_vec3_norm(s->vel[i]));
    if (was_still)
        w->woken++;
}


/* Sphere i's settle speed: SETTLE_SPEED_FACTOR times its rest speed. */
static double settle_speed(const nbep_state *s, size_t i, double dt)
{
    return SETTLE_SPEED_FACTOR * rest_speed(s, i, nbep_vec3_norm(s->acc[i]), dt);
}

/* Holds a supported sphere still when slower than the rest speed (see rest_speed). */
static bool try_hold(pred_ctx *c, nbep_state *s, size_t i, double dt)
{
    if (!supported(c, i) ||
        !(nbep_vec3_norm(s->vel[i]) <= rest_speed(s, i, nbep_vec3_norm(s->acc[i]), dt)))
        return false;
    s->vel[i] = nbep_vec3_make(0.0, 0.0, 0.0);
    c->rest[i].still = true;
    return true;
}

/* Sphere k meets an immobile face `who` (a plane, or a held sphere) whose normal towards it
 * is n. Caged: a face it met within tc (the TC model's time) before, and has not moved off
 * since (CAGE_TOUCH_REL), faces this one (n.n' < 0: a bounce off either heads into the other):
 * a gap exactly its diameter wide, a rigid cage, where the bounces between the faces take no
 * time, and the TC model, which makes them elastic, would keep them going for ever (a sphere
 * on the floor between a wall and a held sphere one diameter from it: a million reactions in
 * a step). The cage takes the speed against every face it still touches instead (CAGE_FACES:
 * a channel of three): k's velocity becomes the nearest that leaves them all
 * (nbep_contact_project; e = 0 against the cage), its speed along them stays. Energy: that
 * normal kinetic energy, which restitution would have taken as the bounces collapsed. The
 * faces' normals are kept from the meetings, so no other sphere's state is read (threads
 * react to other events meanwhile). Returns whether caged; records this meeting either way
 * (newest first; an older meeting with the same face is passed over). */
static bool caged(pred_ctx *c, nbep_state *s, size_t k, int32_t who, nbep_vec3 n, double t_abs,
                  double tc)
{
    if (!c->face)
        return false;
    face_met *f = &c->face[k * CAGE_FACES];
    nbep_vec3 nn[NBEP_CONTACT_MAX] = {n};
    int m = 1;
    bool opposed = false;
    for (int j = 0; j < CAGE_FACES; j++)
        if (f[j].who != who && t_abs - f[j].t <= tc &&
            nbep_vec3_dot(f[j].n, nbep_vec3_sub(s->pos[k], f[j].p)) <=
                CAGE_TOUCH_REL * s->radius[k]) {
            nn[m++] = f[j].n;
            opposed = opposed || nbep_vec3_dot(f[j].n, n) < 0.0;
        }
    for (int j = CAGE_FACES - 1; j > 0; j--)
        f[j] = f[j - 1];
    f[0] = (face_met){.t = t_abs, .n = n, .p = s->pos[k], .who = who};
    if (!opposed)
        return false;
    unsigned act;
    s->vel[k] = nbep_contact_project(s->vel[k], nn, m, &act);
    return true;
}

/* Whether held sphere m rests on sphere k. Such an m is no support for k to be held on: the
 * two would hold each other, and each one's landing (a reaction: the spheres resting on it
 * let go) would let the other go, which lands again at the same instant (grid mode's
 * 120-sphere pour at e = 0.9 went round such a pair 100000 times at one time and stopped,
 * "events do not resolve"). When k is free, m's entry for k is stale (k moved since m took
 * its load) and m's let-go is pending. */
static bool leans_on(const pred_ctx *c, size_t m, size_t k)
{
    return c->rest[m].still && rest_has_sphere(&c->rest[m], k);
}

/* The sphere contacts of r (free sphere k's) that rest on k themselves, taken out (leans_on).
 * Nothing to take out today: a sphere that is not held keeps planes only (rest_solve keeps
 * sphere contacts only when it holds, and every hold sets still), so this guards a change
 * that would let a free sphere keep a sphere contact (mutate.py: land-keeps-what-rests-on-it,
 * equivalent). */
static void drop_leaning(const pred_ctx *c, size_t k, rest_set *r)
{
    int n = 0;
    for (int q = 0; q < r->n; q++)
        if (r->who[q] >= 0 || !leans_on(c, (size_t)(-1 - r->who[q]), k)) {
            r->who[n] = r->who[q];
            r->ver[n++] = r->ver[q];
        }
    r->n = n;
}

/* A pocket (see land_on_held): the held spheres besides j that sphere k touches to within tol,
 * added to its contacts r (up to NBEP_CONTACT_MAX); for supports to hold k on (`holds`), not
 * those that rest on k (leans_on). */
typedef struct pocket {
    const pred_ctx *c;
    const nbep_state *s;
    size_t k, j;
    double tol;
    rest_set *r;
    bool holds;
} pocket;

static void pocket_one(void *u, uint32_t m)
{
    pocket *x = u;
    if (m == x->k || m == x->j || x->r->n >= NBEP_CONTACT_MAX || !x->c->rest[m].still ||
        (x->holds && leans_on(x->c, m, x->k)))
        return;
    double gap = nbep_vec3_norm(sep(x->c, x->s, m, x->k)) - (x->s->radius[m] + x->s->radius[x->k]);
    if (gap <= x->tol) {
        x->r->who[x->r->n] = -1 - (int32_t)m;
        x->r->ver[x->r->n++] = x->c->ver[m];
    }
}

/* Cells mode: k's neighbour list names every sphere that can touch it, and the loop is serial.
 * Rounds modes: every sphere, except those this round's events claim (other threads may be
 * changing them now; the claims were made before a barrier and stay until the next round). */
static void pocket_gather(const pred_ctx *c, const nbep_state *s, const thread_ws *w, size_t k,
                          size_t j, double tol, bool holds, rest_set *r)
{
    pocket x = {c, s, k, j, tol, r, holds};
    if (c->ev) {
        nbep_evloop_visit_block(c->ev, (uint32_t)k, pocket_one, &x);
        return;
    }
    for (size_t m = 0; m < s->n && r->n < NBEP_CONTACT_MAX; m++)
        if (atomic_load_explicit(&c->claim[w->par][m], memory_order_relaxed) == KEY_FREE)
            pocket_one(&x, (uint32_t)m);
}

/* The planes besides those of r that sphere k touches to within tol, added to r (up to
 * NBEP_CONTACT_MAX): a wall beside it is part of a pocket too (a sphere on the curve of a held
 * one, pressed against a wall by it: a wedge that the two hold together and neither alone). */
static void pocket_planes(const nbep_state *s, size_t k, double tol, rest_set *r)
{
    for (size_t p = 0; p < s->n_planes && r->n < NBEP_CONTACT_MAX; p++)
        if (!rest_has_plane(r, p) &&
            nbep_physics_plane_gap(s->plane_normal[p], s->plane_offset[p], s->pos[k],
                                   s->radius[k]) <= tol) {
            r->who[r->n] = (int32_t)p;
            r->ver[r->n++] = 0;
        }
}

/* After k bounced off held sphere j: k must leave j receding by the predictor's own test
 * (d.v >= 0, d from j to k; j does not move), or the same contact returns at zero time: the
 * bounce's v.n with the normalised n can disagree with it in the last bit (a sphere sliding
 * under a held one while gravity pulls it off). The kernel's pair response with j immobile
 * (d1 = 0, d2 = n) does nothing to a receding pair and applies its round-off tie push
 * (physics.c) to one closing by round-off. */
static void leave_held(const pred_ctx *c, nbep_state *s, size_t k, size_t j, double e)
{
    nbep_vec3 d = sep(c, s, j, k), v_j = ZERO3;
    double len = nbep_vec3_norm(d);
    if (!(len > 0.0) || !(nbep_vec3_dot(d, s->vel[k]) < 0.0))
        return;
    nbep_vec3 n = nbep_vec3_make(d.x / len, d.y / len, d.z / len);
    /* k's image that touches j (pos[k] itself without periodic axes: the same subtraction as
     * the predictor's) */
    const nbep_vec3 p_k = c->pb.any ? nbep_vec3_add(s->pos[j], d) : s->pos[k];
    (void)nbep_physics_respond_pair_along(s->pos[j], p_k, &v_j, &s->vel[k], s->mass[j],
                                          s->mass[k], e, ZERO3, n);
}

/* Sphere k, which has reacted JAM_HOLD times or more in this step, meets held sphere j slowly
 * (land_on_held), or meets any sphere while its planes carry it (j = NO_SPHERE): it is held
 * where it is, on its planes, j and what it touches (pocket_gather, pocket_planes, within
 * the settle tolerance). See JAM_HOLD. */
#define NO_SPHERE SIZE_MAX
static bool jam_hold(pred_ctx *c, nbep_state *s, thread_ws *w, size_t k, size_t j, double dt)
{
    if (!c->settle || !c->jam || c->jam[k].step != w->jam_step || c->jam[k].n < JAM_HOLD)
        return false;
    const double vs = settle_speed(s, k, dt), amag = nbep_vec3_norm(s->acc[k]);
    rest_set r = c->rest[k];
    drop_leaning(c, k, &r);
    if (j != NO_SPHERE && r.n < NBEP_CONTACT_MAX && !leans_on(c, j, k)) {
        r.who[r.n] = -1 - (int32_t)j;
        r.ver[r.n++] = c->ver[j];
    }
    pocket_gather(c, s, w, k, j, vs * vs / amag, true, &r);
    pocket_planes(s, k, vs * vs / amag, &r);
    r.still = true;
    c->rest[k] = r;
    s->vel[k] = ZERO3;
    c->aeff[k] = ZERO3;
    fire(c, w, s, k, false);
    return true;
}

/* Sphere k (not held) meets held sphere j at a normal speed no faster than the rest speed, or
 * one that j's pile carries (carried): it joins the held pile if pressed onto j, no faster
 * than the rest speed in all, and its contacts then leave it no motion; else it bounces off j
 * as off a wall (j is carried by the pile; the momentum, below m (1 + e) times the rest speed,
 * or the carry speed, goes to it as to a plane), or is
 * caged if the face it met before faces this one and it still touches that (caged).
 * Not held by its planes and j alone, it may be by the pocket they make with the other held
 * spheres it touches (pocket_gather). */
static void land_on_held(pred_ctx *c, nbep_state *s, double e, double dt, size_t k, size_t j,
                         double t_abs, double tc, thread_ws *w, nbep_counters *cnt)
{
    nbep_vec3 d = sep(c, s, j, k);
    double len = nbep_vec3_norm(d);
    nbep_vec3 n = nbep_vec3_make(d.x / len, d.y / len, d.z / len);
    double u = nbep_vec3_dot(s->vel[k], n), an = nbep_vec3_dot(c->aeff[k], n);
    rest_set r = c->rest[k];
    drop_leaning(c, k, &r);
    const double amag = nbep_vec3_norm(s->acc[k]), v_rest = rest_speed(s, k, amag, dt);
    /* not on a j that rests on k (leans_on): it bounces, and meets j again after j's let-go */
    if (an < 0.0 && fabs(u) <= v_rest && nbep_vec3_norm(s->vel[k]) <= v_rest &&
        r.n < NBEP_CONTACT_MAX && !leans_on(c, j, k)) {
        r.who[r.n] = -1 - (int32_t)j;
        r.ver[r.n++] = c->ver[j];
        const rest_set r0 = r;
        nbep_vec3 v = s->vel[k], a;
        bool held = rest_solve(c, s, k, &r, &v, &a, dt, true);
        if (!held) { /* a pocket: j with the other held spheres k touches (within twice the
                      * highest hop of the rest speed, |a| t_min^2) */
            r = r0;
            pocket_gather(c, s, w, k, j, v_rest * v_rest / amag, true, &r);
            pocket_planes(s, k, v_rest * v_rest / amag, &r);
            if (r.n > r0.n) {
                v = s->vel[k];
                held = rest_solve(c, s, k, &r, &v, &a, dt, true);
            }
        }
        if (held) {
            c->rest[k] = r;
            s->vel[k] = v;
            c->aeff[k] = a;
            fire(c, w, s, k, false);
            return;
        }
    }
    if (jam_hold(c, s, w, k, j, dt))
        return;
    const double e_k = tc_restitution(c, tc, e, t_abs, k, k);
    if (caged(c, s, k, -1 - (int32_t)j, n, t_abs, tc) ||
        nbep_physics_respond_plane(n, &s->vel[k], e_k))
        cnt->c[NBEP_COUNTER_SPHERE_COLLISIONS]++;
    update_rest(c, s, k, dt);
    min_bounce_held(c, s, dt, k, j, n);
    update_rest(c, s, k, dt);
    leave_held(c, s, k, j, e);
    fire(c, w, s, k, false);
}

/* Whether the faces of r (sphere i's contacts) take a push on i along m: m projected onto the
 * cone of motions they allow is nothing, to HOLD_SLOPE of |m| (the normals of sphere contacts
 * are known to a few 1e-6 rad: HOLD_SLOPE). */
static bool faces_take(const pred_ctx *c, const nbep_state *s, size_t i, const rest_set *r,
                       nbep_vec3 m)
{
    nbep_vec3 n[NBEP_CONTACT_MAX];
    rest_normals(c, s, i, r, n);
    unsigned act;
    return nbep_vec3_norm(nbep_contact_project(m, n, r->n, &act)) <=
           HOLD_SLOPE * nbep_vec3_norm(m);
}

/* Held sphere j carries the impact of free sphere k, closing at speed u along m (their line of
 * centres, from k to j): slow enough (no faster than a fall from physics.carry_drop of j's
 * radius), and pushed into the faces that hold j, its own contacts first, then with the held
 * spheres and planes it touches. */
static bool carried(const pred_ctx *c, const nbep_state *s, const thread_ws *w, size_t j,
                    size_t k, double u, nbep_vec3 m, double carry_drop, double dt)
{
    const double amag = nbep_vec3_norm(s->acc[j]);
    if (!(carry_drop > 0.0) || !(amag > 0.0) ||
        !(u <= sqrt(2.0 * amag * carry_drop * s->radius[j])))
        return false;
    rest_set r = c->rest[j];
    if (faces_take(c, s, j, &r, m))
        return true;
    const double vs = settle_speed(s, j, dt), reach = vs * vs / amag;
    pocket_gather(c, s, w, j, k, reach, false, &r);
    pocket_planes(s, j, reach, &r);
    return faces_take(c, s, j, &r, m);
}

static void react(pred_ctx *c, nbep_state *s, const nbep_scene *sc, double t_abs,
                  double t_local, uint32_t lo, uint32_t hi, const nbep_event *ev, thread_ws *w,
                  nbep_counters *cnt, nbep_thread_max *mx)
{
    const double e = sc->restitution, dt = sc->dt;
    advance_to(c, s, lo, t_local);
    const bool still_lo = c->rest && c->rest[lo].still;
    if (ev->kind == NBEP_EVENT_HORIZON) { /* image horizon: re-predicted from here */
        fire(c, w, s, lo, still_lo);
        return;
    }
    if (ev->kind == NBEP_EVENT_PLANE) {
        uint32_t p = UINT32_MAX - hi;
        nbep_vec3 n = s->plane_normal[p];
        double gap = nbep_physics_plane_gap(n, s->plane_offset[p], s->pos[lo], s->radius[lo]);
        note_overlap(mx, -gap, s->radius[lo]);
        const double vn0 = nbep_vec3_dot(n, s->vel[lo]);
        const double e_pl = tc_restitution(c, sc->tc, e, t_abs, lo, lo);
        if (caged(c, s, lo, (int32_t)p, n, t_abs, sc->tc) ||
            nbep_physics_respond_plane(n, &s->vel[lo], e_pl))
            cnt->c[NBEP_COUNTER_PLANE_COLLISIONS]++;
        /* SPEC /stats/wall_impulse: the normal momentum the plane received, pushed outward */
        nbep_xsum_add(&mx->wall[p], s->mass[lo] * (nbep_vec3_dot(n, s->vel[lo]) - vn0));
        update_rest(c, s, lo, dt);
        double an = nbep_vec3_dot(s->acc[lo], n), vn = nbep_vec3_dot(s->vel[lo], n);
        rest_set *r = c->rest ? &c->rest[lo] : NULL; /* NULL: nothing accelerates */
        /* a bounce shorter than tc would be elastic (TC) and never shrink: rest; and one that
         * the TC model made elastic (the sphere is squeezed: it met something within tc) rests
         * no faster than the rest speed, what the minimum bounce of its neighbours leaves it
         * with. A lone sphere's bounces are all kept down to the first rule. */
        if (r && an < 0.0 && vn >= 0.0 &&
            (2.0 * vn <= -an * fmax(NBEP_REST_FRACTION * dt, sc->tc) ||
             (e_pl != e && vn <= rest_speed(s, lo, -an, dt))) &&
            r->n < NBEP_CONTACT_MAX) {
            r->who[r->n] = (int32_t)p;
            r->ver[r->n++] = 0;
            rest_solve(c, s, lo, r, &s->vel[lo], &c->aeff[lo], dt, true);
        }
        fire(c, w, s, lo, still_lo);
        return;
    }
    advance_to(c, s, hi, t_local);
    const bool still_hi = c->rest && c->rest[hi].still;
    double sigma = s->radius[lo] + s->radius[hi];
    const nbep_vec3 r12 = sep(c, s, lo, hi);
    note_overlap(mx, sigma - nbep_vec3_norm(r12),
                 fmin(s->radius[lo], s->radius[hi]));
    const bool sup_lo = supported(c, lo), sup_hi = supported(c, hi);
    if (sup_lo != sup_hi) { /* a supported sphere slow enough is held when a free one meets it */
        size_t j = sup_lo ? lo : hi;
        if (!c->rest[j].still && try_hold(c, s, j, dt))
            fire(c, w, s, j, false);
    }
    /* one of them held, the other not (free, or sliding on planes): a slow meeting lands on
     * the held one, and so does one its pile carries (carried); any other is an ordinary
     * response below, which wakes it */
    if (c->rest && c->rest[lo].still != c->rest[hi].still) {
        size_t k = c->rest[lo].still ? hi : lo, j = c->rest[lo].still ? lo : hi;
        nbep_vec3 d = sep(c, s, j, k);
        double u = nbep_vec3_dot(s->vel[k], d) / nbep_vec3_norm(d);
        if (fabs(u) <= rest_speed(s, k, nbep_vec3_norm(s->acc[k]), dt) ||
            carried(c, s, w, j, k, -u, nbep_vec3_scale(d, -1.0), sc->carry_drop, dt)) {
            land_on_held(c, s, e, dt, k, j, t_abs, sc->tc, w, cnt);
            return;
        }
    }
    /* a jammed sphere that its planes carry is held where it is (JAM_HOLD: a row of spheres
     * that fits a box exactly passes its momentum to and fro at zero time); the other takes
     * no response and, unless held (as land_on_held leaves the held sphere), is predicted
     * again against it */
    for (int q = 0; c->rest && q < 2; q++) {
        const size_t k = q ? hi : lo, o = q ? lo : hi;
        if (!c->rest[k].still && supported(c, k) && jam_hold(c, s, w, k, NO_SPHERE, dt)) {
            if (!c->rest[o].still)
                fire(c, w, s, o, false);
            return;
        }
    }
    /* hi's image that touches lo (the same as pos[hi] without periodic axes) */
    const nbep_vec3 p_hi = c->pb.any ? nbep_vec3_add(s->pos[lo], r12) : s->pos[hi];
    const nbep_vec3 v_hi = s->vel[hi];
    /* spheres leaning on planes move only along them: the planes take their share (a free
     * pair keeps the paper's formula, bit for bit) */
    double len = nbep_vec3_norm(r12);
    nbep_vec3 n = len > 0.0 ? nbep_vec3_make(r12.x / len, r12.y / len, r12.z / len) : r12;
    bool leans = false;
    nbep_vec3 d_lo = plane_mobility(c, s, lo, nbep_vec3_scale(n, -1.0), &leans);
    nbep_vec3 d_hi = plane_mobility(c, s, hi, n, &leans);
    const double e_pair = tc_restitution(c, sc->tc, e, t_abs, lo, hi);
    const double m_lo = c->mass_all > 0.0 ? c->mass_all : s->mass[lo];
    const double m_hi = c->mass_all > 0.0 ? c->mass_all : s->mass[hi];
    if (leans ? nbep_physics_respond_pair_along(s->pos[lo], p_hi, &s->vel[lo], &s->vel[hi], m_lo,
                                                m_hi, e_pair, d_lo, d_hi)
              : nbep_physics_respond_pair(s->pos[lo], p_hi, &s->vel[lo], &s->vel[hi], m_lo,
                                          m_hi, e_pair))
        cnt->c[NBEP_COUNTER_SPHERE_COLLISIONS]++;
    min_bounce(c, s, dt, lo, hi);
    /* SPEC /stats/virial: r12 . dp2, dp2 the momentum hi received */
    nbep_xsum_add(&mx->virial,
                  nbep_vec3_dot(r12, nbep_vec3_scale(nbep_vec3_sub(s->vel[hi], v_hi), m_hi)));
    update_rest(c, s, lo, dt);
    update_rest(c, s, hi, dt);
    fire(c, w, s, lo, still_lo);
    fire(c, w, s, hi, still_hi);
}

/* Sphere i is held and a sphere it rests on has reacted since it took the load. */
static bool held_on_changed(const pred_ctx *c, size_t i)
{
    if (!c->rest || !c->rest[i].still)
        return false;
    const rest_set *r = &c->rest[i];
    for (int k = 0; k < r->n; k++)
        if (r->who[k] < 0 && r->ver[k] != c->ver[-1 - r->who[k]])
            return true;
    return false;
}

/* Held sphere i lets go of the sphere supports that reacted, at local time t_local; it fires
 * (moves again) unless what is left still holds it. */
static void let_go(pred_ctx *c, nbep_state *s, size_t i, double dt, double t_local, thread_ws *w)
{
    rest_set *r = &c->rest[i];
    rest_set k = {.n = 0};
    for (int j = 0; j < r->n; j++)
        if (r->who[j] >= 0 || r->ver[j] == c->ver[-1 - r->who[j]]) {
            k.who[k.n] = r->who[j];
            k.ver[k.n++] = r->ver[j];
        }
    *r = k;
    advance_to(c, s, i, t_local);
    if (!rest_solve(c, s, i, r, &s->vel[i], &c->aeff[i], dt, false))
        fire(c, w, s, i, true);
}

/* After a react phase that changed held spheres: every thread lets go of its own held spheres
 * whose sphere supports have reacted since they took the load, at the time of this round
 * (they have not moved: v = 0, a = 0). A sphere still held by what is left stays. Letting go
 * changes held spheres in turn, so it repeats round by round down the pile. Two sub-phases
 * (find, then change) so that no thread reads a response count another is writing. */
static void let_go_phase(pred_ctx *c, nbep_state *s, nbep_range own, nbep_barrier *bar,
                         double dt, double t_local, thread_ws *w)
{
    w->n_rel = 0;
    for (size_t i = own.lo; i < own.hi; i++)
        if (held_on_changed(c, i))
            w->rel[w->n_rel++] = (uint32_t)i;
    nbep_barrier_wait(bar);
    for (size_t m = 0; m < w->n_rel; m++)
        let_go(c, s, w->rel[m], dt, t_local, w);
    nbep_barrier_wait(bar);
}

/* ---- Settling (SETTLE_STEPS) ------------------------------------------------------------ */

/* The update, own sphere i at the step's end: counts the step if its highest speed stayed at or
 * below the settle speed, starts the next step's peak from here, and takes the snapshot that
 * settle_gather reads. Returns whether i is a candidate to settle. */
static bool settle_count(pred_ctx *c, const nbep_state *s, size_t i, double dt)
{
    settle_rec *x = &c->settle[i];
    const double v2 = nbep_vec3_norm2(s->vel[i]), vs = settle_speed(s, i, dt);
    const bool slow = vs > 0.0 && fmax(x->peak2, v2) <= vs * vs;
    x->slow = slow ? (x->slow < SETTLE_STEPS ? x->slow + 1 : SETTLE_STEPS) : 0;
    x->peak2 = v2;
    x->still = c->rest[i].still;
    x->cand = !x->still && x->slow >= SETTLE_STEPS;
    return x->cand;
}

/* What settle_gather gathers for sphere i: its supports r, each scored by the cosine between its
 * normal and i's acceleration (planes -2: kept first; the most nearly below kept when more
 * than NBEP_CONTACT_MAX touch). */
typedef struct settle_gather_ws {
    const pred_ctx *c;
    const nbep_state *s;
    size_t i;
    nbep_vec3 a;      /* i's acceleration, unit */
    double tol;       /* largest gap that counts as touching */
    int par;          /* candidates count as supports: all (-1), or those live at this parity */
    bool more;        /* more touched than r holds */
    rest_set r;
    double score[NBEP_CONTACT_MAX];
} settle_gather_ws;

static void settle_add(settle_gather_ws *g, int32_t who, double score)
{
    int k = g->r.n;
    if (k == NBEP_CONTACT_MAX) { /* replace the least nearly below, if this one is more so */
        g->more = true;
        k = 0;
        for (int m = 1; m < g->r.n; m++)
            if (g->score[m] > g->score[k])
                k = m;
        if (!(score < g->score[k]))
            return;
    } else {
        g->r.n++;
    }
    g->r.who[k] = who;
    g->score[k] = score;
}

/* Sphere j is a support of i if it is held, or a candidate that may settle in this step (the
 * snapshot: every candidate, or those still live after the round before), touches i within
 * tol and lies against i's acceleration. */
static void settle_one(void *u, uint32_t j)
{
    settle_gather_ws *g = u;
    const settle_rec *y = &g->c->settle[j];
    if (j == g->i || !(y->still || (y->cand && (g->par < 0 || y->live[g->par]))))
        return;
    const nbep_vec3 d = sep(g->c, g->s, j, g->i);
    const double len = nbep_vec3_norm(d);
    if (!(len - (g->s->radius[j] + g->s->radius[g->i]) <= g->tol))
        return;
    const double cosine = nbep_vec3_dot(d, g->a) / len;
    if (cosine < 0.0)
        settle_add(g, -1 - (int32_t)j, cosine);
}

/* Own candidate i, at the step's end: gathers its supports (settle_one, and the planes it
 * touches below it) into its record (sup, more). par as settle_gather_ws's. Reads other
 * spheres' positions, radii and snapshots only, which nothing writes in these sub-phases.
 * Returns whether it has any. */
static bool settle_gather(pred_ctx *c, const nbep_state *s, size_t i, double dt, int par)
{
    const double amag = nbep_vec3_norm(s->acc[i]), vs = settle_speed(s, i, dt);
    settle_gather_ws g = {.c = c, .s = s, .i = i, .a = nbep_vec3_scale(s->acc[i], 1.0 / amag),
                          .tol = vs * vs / amag, .par = par};
    for (size_t p = 0; p < s->n_planes; p++)
        if (nbep_vec3_dot(s->plane_normal[p], g.a) < 0.0 &&
            nbep_physics_plane_gap(s->plane_normal[p], s->plane_offset[p], s->pos[i],
                                   s->radius[i]) <= g.tol)
            settle_add(&g, (int32_t)p, -2.0);
    if (c->ev) {
        nbep_evloop_visit_block(c->ev, (uint32_t)i, settle_one, &g);
    } else if (c->use_grid) { /* the grid of the step's end (grid_prepare) */
        size_t lo[3], hi[3];
        nbep_grid_block(&c->grid, s->pos[i], s->radius[i] + c->rmax + g.tol, lo, hi);
        for (size_t z = lo[2]; z <= hi[2]; z++)
            for (size_t y = lo[1]; y <= hi[1]; y++)
                for (size_t x = lo[0]; x <= hi[0]; x++) {
                    size_t cell = nbep_grid_index(&c->grid, x, y, z);
                    for (size_t k = c->grid.start[cell]; k < c->grid.start[cell + 1]; k++)
                        settle_one(&g, c->grid.item[k]);
                }
    } else {
        for (size_t j = 0; j < s->n; j++)
            settle_one(&g, (uint32_t)j);
    }
    settle_rec *x = &c->settle[i];
    x->more = g.more;
    x->n_sup = g.r.n;
    for (int k = 0; k < g.r.n; k++)
        x->sup[k] = g.r.who[k];
    return g.r.n > 0;
}

/* Own candidate i, live after the round before (parity prev): drops the candidates among its
 * supports that were not live then (they have lost theirs: no support under them settles).
 * Its supports are then those settle_gather would find among what is still live: the same
 * list less those, unless it had left some out (more), when it gathers again. Returns whether
 * any is left. */
static bool settle_recheck(pred_ctx *c, const nbep_state *s, size_t i, double dt, int prev)
{
    settle_rec *x = &c->settle[i];
    uint8_t n = 0;
    for (int k = 0; k < x->n_sup; k++) {
        const int32_t who = x->sup[k];
        if (who >= 0 || c->settle[-1 - who].still || c->settle[-1 - who].live[prev])
            x->sup[n++] = who;
    }
    if (n == x->n_sup)
        return n > 0;
    if (x->more)
        return settle_gather(c, s, i, dt, prev);
    x->n_sup = n;
    return n > 0;
}

/* Every thread at a step's end, after a barrier that follows the update (settle_count): holds
 * the candidates whose supports end up held. Sub-phases, so that no thread reads what another
 * writes: each candidate gathers its supports among the planes, the held spheres and the
 * candidates (settle_gather); then, round after round, candidates whose supports have all
 * lost theirs lose them too (settle_recheck: a sphere on one that rests on a sliding sphere
 * is no more held than that one), until a round loses none (each round reads the round
 * before's snapshot, live[]: the same rounds on every thread and for any thread count; a
 * candidate never comes back, so there are at most as many rounds as candidates, and one more
 * than the longest chain that loses its supports, in practice); then those left are held where
 * they are, their response counts move on (their slots and every prediction naming them are
 * stale) and their block energies are taken again; then each stamps its sphere supports'
 * counts. Every held sphere thus rests on planes and held spheres only: never on one that goes
 * on moving (before, the candidate's own support was enough, and a sphere on a sphere that
 * failed to settle hung in the air). Candidates that support each other in a ring (possible
 * only where accelerations differ) keep each other. Returns whether any sphere was held. */
static bool settle_phases(nbep_sim *sim, pred_ctx *c, nbep_range own, thread_ws *w)
{
    if (!c->settle)
        return false;
    size_t cands = 0;
    for (int t = 0; t < c->nt; t++)
        cands += c->ws[t].n_settle;
    if (cands == 0)
        return false;
    nbep_state *s = &sim->st;
    nbep_barrier_wait(&c->bar); /* grid mode: the grid is placed */
    w->n_live[0] = w->n_lost[0] = 0;
    for (size_t i = own.lo; i < own.hi; i++) {
        if (!c->settle[i].cand)
            continue;
        const bool on = settle_gather(c, s, i, sim->dt, -1);
        c->settle[i].live[0] = on;
        w->n_live[0] += on;
        w->n_lost[0] += !on;
    }
    int round = 0;
    for (;;) {
        nbep_barrier_wait(&c->bar);
        size_t live = 0, lost = 0;
        for (int t = 0; t < c->nt; t++) {
            live += c->ws[t].n_live[round & 1];
            lost += c->ws[t].n_lost[round & 1];
        }
        if (live == 0)
            return false;
        if (lost == 0)
            break;
        round++; /* written at its parity, read by all after the barrier */
        const int prev = (round - 1) & 1, cur = round & 1;
        w->n_live[cur] = w->n_lost[cur] = 0;
        for (size_t i = own.lo; i < own.hi; i++) {
            settle_rec *x = &c->settle[i];
            if (!x->cand)
                continue;
            const bool on = x->live[prev] && settle_recheck(c, s, i, sim->dt, prev);
            x->live[cur] = on;
            w->n_live[cur] += on;
            w->n_lost[cur] += x->live[prev] && !on;
        }
    }
    w->n_settled = 0;
    for (size_t i = own.lo; i < own.hi; i++) {
        settle_rec *x = &c->settle[i];
        if (!x->cand || !x->live[round & 1])
            continue;
        rest_set *r = &c->rest[i];
        *r = (rest_set){.n = x->n_sup, .still = true};
        for (int k = 0; k < x->n_sup; k++)
            r->who[k] = x->sup[k];
        s->vel[i] = ZERO3;
        c->aeff[i] = ZERO3;
        x->held_now = true;
        c->ver[i]++;
        w->n_settled++;
    }
    if (w->n_settled > 0)
        nbep__sim_block_energy(sim, own);
    nbep_barrier_wait(&c->bar);
    for (size_t i = own.lo; w->n_settled > 0 && i < own.hi; i++) {
        if (!c->settle[i].held_now)
            continue;
        rest_set *r = &c->rest[i];
        for (int k = 0; k < r->n; k++)
            r->ver[k] = r->who[k] < 0 ? c->ver[-1 - r->who[k]] : 0;
        c->settle[i].held_now = false;
    }
    return true;
}

static void react_phase(pred_ctx *c, nbep_state *s, const nbep_scene *sc, int par, double T0,
                        double t_min, uint64_t stamp, thread_ws *w, nbep_counters *cnt,
                        nbep_thread_max *mx)
{
    w->n_fired = 0;
    w->par = par;
    for (size_t k = 0; k < w->n_cand; k++) {
        size_t i = w->cand[k];
        const nbep_event *ev = nbep_feq_slot(c->q, i);
        if (!c->order_step && ev->time != t_min)
            continue;
        cnt->c[NBEP_COUNTER_CHECKS]++; /* the paper's check() */
        uint32_t lo, hi;
        uint64_t key = event_key(i, ev, &lo, &hi);
        if (atomic_load_explicit(&c->claim[par][lo], memory_order_relaxed) != key)
            continue;
        if (ev->kind == NBEP_EVENT_SPHERE &&
            atomic_load_explicit(&c->claim[par][hi], memory_order_relaxed) != key)
            continue;
        /* step order: the two copies of a pair carry the same key, but their times may differ
         * in the last bits (each sphere predicted the pair from its own side); only a copy at
         * the claimed time reacts, so the reaction is the same for any thread count */
        if (c->order_step && !holds_time(c, ev, lo, hi))
            continue;
        /* Both copies of a pair hold the claims; one compare-and-swap lets one react.
         * relaxed: the other copy only needs the outcome, and the barrier after this phase
         * publishes the reaction's writes. */
        uint64_t seen = atomic_load_explicit(&c->reacted[lo], memory_order_relaxed);
        if (seen == stamp ||
            !atomic_compare_exchange_strong_explicit(&c->reacted[lo], &seen, stamp,
                                                     memory_order_relaxed,
                                                     memory_order_relaxed))
            continue;
        cnt->c[NBEP_COUNTER_REACTIONS]++;
        /* at t_min in time order; at its own time in step order */
        react(c, s, sc, ev->time, ev->time - T0, lo, hi, ev, w, cnt, mx);
    }
}

/* Grid mode, between a round's barriers: 1 + the lowest sphere any thread saw past
 * run.max_reactions (the same on every thread), 0 for none. Every thread's: a let-go in a
 * step's last round may have passed the limit on a thread that the next step's crew leaves
 * out. */
static uint32_t lowest_jammed(const pred_ctx *c)
{
    uint32_t jammed = 0;
    for (int t = 0; t < c->nt; t++)
        if (c->ws[t].jammed && (!jammed || c->ws[t].jammed < jammed))
            jammed = c->ws[t].jammed;
    return jammed;
}

/* Cells mode, after the event loop stopped in step `step`: 1 + the lowest sphere past
 * run.max_reactions, read from the counts (each thread's own `jammed` may name a sphere of a
 * team's speculative reaction that was undone), 0 for none. O(n), once, as the run fails. */
static uint32_t cells_jammed(const pred_ctx *c, size_t n, uint64_t step)
{
    for (size_t i = 0; c->jam && i < n; i++)
        if (c->jam[i].step == (uint32_t)step && c->jam[i].n > c->jam_max)
            return (uint32_t)i + 1;
    return 0;
}

/* run.max_reactions: sphere i reacted too often in one step, at about time t; the run stops. */
static void jam_fail(nbep_sim *sim, uint64_t step, size_t i, double t)
{
    nbep_diag_add(sim->diag, __FILE__, __LINE__,
                  "nbep: step %llu: sphere %zu reacted over %llu times in one step (t = %.17g, "
                  "run.max_reactions): jammed between walls and neighbours that nbep cannot hold "
                  "still (README, granular scenes: not solved yet); stopping",
                  (unsigned long long)step, i, (unsigned long long)sim->scene->max_reactions, t);
    sim->status = NBEP_ENUMERIC;
}

/* Cells mode without a box, every thread before a rebuild, each thread's centres' bounds in its
 * grid_lo, grid_hi (taken before the first step and at each step's end; a rebuild moves no
 * sphere before this): the cells laid out afresh over the centres' extent (fit_region). False
 * on every thread when out of memory (the run stops). */
static bool cells_fit(nbep_sim *sim, pred_ctx *c, int tid, nbep_counters *cnt)
{
    nbep_barrier_wait(&c->bar);
    if (tid == 0) {
        nbep_vec3 lo, hi;
        merged_bounds(c, &lo, &hi);
        fit_region(c, lo, hi);
        c->ev_failed = nbep_evloop_refit(c->ev, c->fit_lo, c->fit_hi, sim->diag) != NBEP_OK;
        cnt->c[NBEP_COUNTER_REFITS]++;
        if (c->ev_failed)
            sim->status = NBEP_ENOMEM;
    }
    nbep_barrier_wait(&c->bar);
    return !c->ev_failed;
}

/* Cells mode without a box, every thread after each thread has put its centres' bounds at the
 * step's end in its grid_lo, grid_hi (and a barrier): whether some centre has left the region
 * the cells cover. The same answer on every thread, for any thread count. */
static bool cells_outgrown(const pred_ctx *c)
{
    nbep_vec3 lo, hi;
    merged_bounds(c, &lo, &hi);
    return lo.x < c->fit_lo.x || lo.y < c->fit_lo.y || lo.z < c->fit_lo.z ||
           hi.x > c->fit_hi.x || hi.y > c->fit_hi.y || hi.z > c->fit_hi.z;
}

/* ---- run.neighbors = "cells": the algorithm's side of the event loop (evloop.h) ---------- */

/* Every this many events of one step, time must have advanced by more than STALL_FRACTION of
 * a step (as for rounds, STALL_ROUNDS): otherwise the loop is a cascade that does not resolve. */
#define STALL_EVENTS 1000000u

/* What the callbacks need: one per thread, T0 the current step's start. */
typedef struct cells_user {
    pred_ctx *c;
    nbep_state *s;
    const nbep_scene *sc;
    double T0;
    double t_local;           /* the current event's time in the step */
    thread_ws *w;
    nbep_counters *cnt;
    nbep_thread_max *mx;
} cells_user;

static nbep_event cells_planes(void *u, uint32_t i)
{
    cells_user *x = u;
    if (x->s->n_planes == 0) /* a periodic fluid: nothing to look at (cells mode has no image
                              * horizons) */
        return (nbep_event){.time = NBEP_NEVER, .kind = NBEP_EVENT_NONE};
    return predict_some(x->c, x->s, i, 0, 0, true, x->T0, x->w, x->cnt);
}

static void cells_pairs(void *u, uint32_t i, const uint32_t *js, size_t m, bool images,
                        nbep_event *best)
{
    cells_user *x = u;
    keep_pairs(best, x->c, x->s, i, effective_acc(x->c, x->s, i), js, m, images, x->T0, x->w);
    x->cnt->c[NBEP_COUNTER_PREDICTIONS] += m;
}

/* cells_pairs for a scene where nothing accelerates (c->free_flight: every acceleration zero,
 * so no contact ever rests or holds and every sphere flies straight): the same pairs, positions
 * and roots as keep_pairs, and the same winner as its keep_earlier, bit for bit (a drift
 * with zero acceleration is p + v h exactly, and ffp-contract is off), with savings that matter
 * in a dense fluid, where this loop is most of the run: no acceleration is loaded or applied;
 * no image is looked for when none can be needed; the best so far is kept as a time and a
 * partner, and only the winner's response count is read. Within one sphere's list partners are
 * distinct, so the order keep_earlier applies reduces to (time, then sphere events before
 * planes and horizons, then partner), which does not depend on the order pairs are tried in.
 *
 * Roots are the expensive part, and most are not needed: most closing pairs of a fluid pass
 * each other, which nbep_predict_pair_quadratic_bound tells without a root (only where the root
 * would say so too), and a closing pair's contact comes no earlier than that bound (strictly
 * below the computed root) and no later than twice it. So the bounds of a batch of partners
 * come first, then the root of the pair with the lowest bound, which sets a best that prunes
 * most of the others (a pair is skipped only when its bound is strictly later than the best:
 * the winner, ties included, is the one trying every pair would give). */
#define PAIR_BATCH 32

/* A closing pair of the batch: its partner's place in the list and its bound (from t0). */
typedef struct pair_try {
    double lb;
    uint32_t k;
} pair_try;

/* The relative motion of sphere i (at pi, vi, local time ti) and partner j at the later of the
 * two local times t0, j at its image when images; the pair's contact distance. */
static inline void pair_motion(const pred_ctx *c, const nbep_state *s, uint32_t i, nbep_vec3 pi,
                               nbep_vec3 vi, double ti, uint32_t j, bool images, nbep_vec3 *dp,
                               nbep_vec3 *dv, double *t0, double *sigma)
{
    const double tj = c->tau[j];
    *t0 = ti > tj ? ti : tj;
    nbep_vec3 pj = s->pos[j];
    if (images)
        pj = nbep_vec3_add(pj, neighbour_shift(c, s, i, j));
    const nbep_vec3 vj = s->vel[j];
    if (ti < *t0)
        pi = nbep_vec3_add(pi, nbep_vec3_scale(vi, *t0 - ti));
    if (tj < *t0)
        pj = nbep_vec3_add(pj, nbep_vec3_scale(vj, *t0 - tj));
    *dp = nbep_vec3_sub(pj, pi);
    *dv = nbep_vec3_sub(vj, vi);
    *sigma = c->sigma_all > 0.0 ? c->sigma_all : s->radius[i] + s->radius[j];
}

/* A batch of partners' motion, gathered from the sphere arrays into arrays of their own (one
 * per coordinate, 32-byte aligned, padded to whole vectors of four), so that the bounds run on
 * four pairs at once without a gather or a shuffle: the partners are scattered over the sphere
 * arrays, and computed straight from them the loop ran two pairs at a time, with half its
 * instructions moving partners' coordinates into vectors and back to the stack (cachegrind,
 * the N = 32000 fluid at phi = 0.50: 55 instructions a partner in its vector part, 73 to 102
 * in its scalar remainder). */
#define PAIR_LANES 4
typedef struct pair_gathered {
    alignas(32) double tj[PAIR_BATCH];
    alignas(32) double px[PAIR_BATCH];
    alignas(32) double py[PAIR_BATCH];
    alignas(32) double pz[PAIR_BATCH];
    alignas(32) double vx[PAIR_BATCH];
    alignas(32) double vy[PAIR_BATCH];
    alignas(32) double vz[PAIR_BATCH];
    alignas(32) double rj[PAIR_BATCH];
} pair_gathered;

/* Partners js[0..m) (m <= PAIR_BATCH) into g, and the padding up to whole vectors: a partner at
 * i's own place, time and motion (no relative motion: never closing, so its bound is +inf,
 * and every figure of it finite; no caller reads a padding's bound). The count gathered,
 * padding included. (The caller has requested every partner's lines first. This gather's
 * loads could stand in for those requests, 9 instructions a partner, 5 % of a collision's at
 * phi = 0.50, at the same time at N = 32000; but a load waits in the core until its line
 * comes and a prefetch does not, and at N = 256000 on two threads, where the partners come
 * from memory, runs without the requests measured 0.63 to 1.06 of the time with them, median
 * 0.83, on a host too noisy to be sure: kept.) */
static inline NBEP_ALWAYS_INLINE size_t pair_gather(const double *restrict tau,
                                                    const nbep_vec3 *restrict pos,
                                                    const nbep_vec3 *restrict vel,
                                                    const double *restrict radius, bool mono,
                                                    const uint32_t *restrict js, size_t m,
                                                    nbep_vec3 pi, nbep_vec3 vi, double ti,
                                                    double ri, pair_gathered *restrict g)
{
    size_t k = 0;
    for (; k < m; k++) {
        const uint32_t j = js[k];
        g->tj[k] = tau[j];
        g->px[k] = pos[j].x;
        g->py[k] = pos[j].y;
        g->pz[k] = pos[j].z;
        g->vx[k] = vel[j].x;
        g->vy[k] = vel[j].y;
        g->vz[k] = vel[j].z;
        g->rj[k] = mono ? ri : radius[j];
    }
    for (; k % PAIR_LANES != 0; k++) {
        g->tj[k] = ti;
        g->px[k] = pi.x;
        g->py[k] = pi.y;
        g->pz[k] = pi.z;
        g->vx[k] = vi.x;
        g->vy[k] = vi.y;
        g->vz[k] = vi.z;
        g->rj[k] = ri;
    }
    return k;
}

/* The bounds of the gathered partners g[0..m) (m a whole number of vectors) of sphere i (at pi,
 * vi, local time ti, radius ri): for each, the bound (from the step's start) of a closing pair
 * that may hit, +inf for one receding or certainly passing (nbep_predict_pair_quadratic_bound
 * of the motion pair_motion gives: a drift by zero time is the position itself, a shift by no
 * period the position itself), written without branches so that it runs on four pairs at
 * once where the CPU has AVX2. pb: the periodic box when images may be needed, else NULL.
 * Built in two copies (images or not), each free of what it does not need: most spheres are
 * far from every periodic face. (A fluid of one radius takes ri + rj = ri + ri, the contact
 * distance exactly, as pair_motion's sigma_all.) */
static inline NBEP_ALWAYS_INLINE void pair_bounds_with(const pair_gathered *restrict g, size_t m,
                                                       nbep_vec3 pi, nbep_vec3 vi, double ti,
                                                       double ri, const nbep_periodic *pb,
                                                       double *restrict out, const bool images)
{
    const double hx = images ? pb->half[0] : INFINITY, hy = images ? pb->half[1] : INFINITY,
                 hz = images ? pb->half[2] : INFINITY;
    const double lx = images ? pb->len[0] : 0.0, ly = images ? pb->len[1] : 0.0,
                 lz = images ? pb->len[2] : 0.0;
    for (size_t k = 0; k < m; k++) {
        const double tj = g->tj[k];
        const double t0 = ti > tj ? ti : tj;
        const double hi = t0 - ti, hj = t0 - tj;
        /* j's image nearest to i, from the stored positions, as neighbour_shift takes it */
        const double sx0 = g->px[k] - pi.x, sy0 = g->py[k] - pi.y, sz0 = g->pz[k] - pi.z;
        const double shx = sx0 > hx ? -lx : sx0 < -hx ? lx : 0.0;
        const double shy = sy0 > hy ? -ly : sy0 < -hy ? ly : 0.0;
        const double shz = sz0 > hz ? -lz : sz0 < -hz ? lz : 0.0;
        const double dpx = ((g->px[k] + shx) + g->vx[k] * hj) - (pi.x + vi.x * hi);
        const double dpy = ((g->py[k] + shy) + g->vy[k] * hj) - (pi.y + vi.y * hi);
        const double dpz = ((g->pz[k] + shz) + g->vz[k] * hj) - (pi.z + vi.z * hi);
        const double dvx = g->vx[k] - vi.x, dvy = g->vy[k] - vi.y, dvz = g->vz[k] - vi.z;
        const double lb = nbep_predict_pair_quadratic_bound(
            nbep_vec3_make(dpx, dpy, dpz), nbep_vec3_make(dvx, dvy, dvz), ri + g->rj[k]);
        out[k] = lb < NBEP_NEVER ? t0 + lb : NBEP_NEVER;
    }
}

/* pair_gather and pair_bounds_with's two copies are inlined into cells_pairs_free, which is
 * built twice (AVX2 and default) as a whole: a call to a clone of its own through the resolver
 * and its 13 arguments cost about 40 instructions, once per 11 partners (cachegrind, the
 * N = 32000 fluid at phi = 0.50: 3 % of all instructions per collision together with the
 * prefetch of every partner's version, which only the winner's read needs). */
NBEP_AVX2_CLONES static void cells_pairs_free(void *u, uint32_t i, const uint32_t *js,
                                              size_t m, bool images, nbep_event *best)
{
    cells_user *x = u;
    const pred_ctx *c = x->c;
    const nbep_state *s = x->s;
    const double T0 = x->T0, ti = c->tau[i];
    const nbep_vec3 pi = s->pos[i], vi = s->vel[i];
    for (size_t k = 0; k < m; k++) { /* the partners' lines, all requested before any is used */
        NBEP_PREFETCH(&c->tau[js[k]]);
        NBEP_PREFETCH(&s->pos[js[k]]);
        NBEP_PREFETCH(&s->vel[js[k]]);
    } /* (not their versions: only the winner's is read, once, at the end) */
    double best_t = best->kind == NBEP_EVENT_NONE ? NBEP_NEVER : best->time;
    /* ties: a sphere event ranks by partner, before any plane or horizon */
    uint32_t tie_j = best->kind == NBEP_EVENT_SPHERE ? best->partner : UINT32_MAX;
    bool found = false;
    pair_try tr[PAIR_BATCH];
    alignas(32) double lbs[PAIR_BATCH];
    pair_gathered g;
    const double ri = s->radius[i];
    for (size_t k0 = 0; k0 < m; k0 += PAIR_BATCH) {
        const size_t k1 = m - k0 < PAIR_BATCH ? m : k0 + PAIR_BATCH;
        size_t n = 0, first = 0;
        const size_t m4 = pair_gather(c->tau, s->pos, s->vel, s->radius, c->sigma_all > 0.0,
                                      js + k0, k1 - k0, pi, vi, ti, ri, &g);
        if (images)
            pair_bounds_with(&g, m4, pi, vi, ti, ri, &c->pb, lbs, true);
        else
            pair_bounds_with(&g, m4, pi, vi, ti, ri, NULL, lbs, false);
        for (size_t k = k0; k < k1; k++) { /* the closing pairs that may hit */
            if (!(lbs[k - k0] < INFINITY))
                continue;
            tr[n] = (pair_try){lbs[k - k0], (uint32_t)k};
            if (tr[n].lb < tr[first].lb)
                first = n;
            n++;
        }
        for (size_t q = 0; q < n; q++) { /* roots: the lowest bound first, then what it leaves */
            const pair_try *p = &tr[q == 0 ? first : q == first ? 0 : q];
            if (T0 + p->lb > best_t)
                continue;
            const uint32_t j = js[p->k];
            nbep_vec3 dp, dv;
            double t0, sigma;
            pair_motion(c, s, i, pi, vi, ti, j, images, &dp, &dv, &t0, &sigma);
            const double t = T0 + (t0 + nbep_predict_pair_quadratic(dp, dv, sigma));
            if (t < NBEP_NEVER && (t < best_t || (t == best_t && j < tie_j))) {
                best_t = t;
                tie_j = j;
                found = true;
            }
        }
    }
    if (found)
        *best = (nbep_event){best_t, tie_j, NBEP_EVENT_SPHERE, c->ver[i], c->ver[tie_j]};
    x->cnt->c[NBEP_COUNTER_PREDICTIONS] += m;
}

static bool cells_fresh(void *u, uint32_t i, const nbep_event *ev)
{
    const cells_user *x = u;
    return is_fresh(x->c, i, ev);
}

static void cells_let_go(void *u, uint32_t j)
{
    cells_user *x = u;
    if (held_on_changed(x->c, j))
        let_go(x->c, x->s, j, x->sc->dt, x->t_local, x->w);
}

/* One reaction, then, as let_go_phase does after a round that changed held spheres, the held
 * spheres resting on a changed one let go: they touch it, so they are in its block; each that
 * moves again is changed in turn (the list grows as the loop walks it). */
static size_t cells_react(void *u, uint32_t i, const nbep_event *ev, const uint32_t **changed,
                          bool *stop)
{
    cells_user *x = u;
    thread_ws *w = x->w;
    uint32_t lo, hi;
    (void)event_key(i, ev, &lo, &hi);
    w->n_fired = 0;
    /* in cells mode only this callback fires spheres (counts reactions), and the loop stops
     * at the first reaction that passes the limit, so the one thread starts every reaction
     * from jammed = 0; a team thread does too, for its note must be its reaction's (a
     * speculative one that passed the limit and was undone must not stop a later one) */
    w->jammed = 0;
    const uint64_t woken = w->woken;
    x->t_local = ev->time - x->T0;
    x->cnt->c[NBEP_COUNTER_REACTIONS]++;
    react(x->c, x->s, x->sc, ev->time, x->t_local, lo, hi, ev, w, x->cnt, x->mx);
    if (w->woken != woken)
        for (size_t k = 0; k < w->n_fired; k++)
            nbep_evloop_visit_block(x->c->ev, w->fired[k], cells_let_go, x);
    *stop = w->jammed != 0; /* run.max_reactions: the loop stops after this event */
    *changed = w->fired;
    return w->n_fired;
}

static void cells_flight(void *u, uint32_t i, double t, nbep_vec3 *p, nbep_vec3 *v,
                         nbep_vec3 *a)
{
    const cells_user *x = u;
    *p = x->s->pos[i];
    *v = x->s->vel[i];
    *a = effective_acc(x->c, x->s, i);
    double h = t - x->T0 - x->c->tau[i];
    if (h > 0.0)
        nbep_physics_drift(p, v, *a, h);
}

/* Sphere i leaves its cell at absolute time t: when its centre is then outside the box on a
 * periodic axis, it is brought to t and wrapped (image counted), so that its position stays
 * in its cell (cells.h). */
static void cells_wrap(void *u, uint32_t i, double t)
{
    const cells_user *x = u;
    nbep_vec3 p, v, a;
    cells_flight(u, i, t, &p, &v, &a);
    int32_t img[3] = {0, 0, 0};
    nbep_periodic_wrap(&x->c->pb, &p, img);
    if (img[0] == 0 && img[1] == 0 && img[2] == 0)
        return;
    advance_to(x->c, x->s, i, t - x->T0);
    nbep_periodic_wrap(&x->c->pb, &x->s->pos[i], &x->s->image[3 * (size_t)i]);
}

static void cells_save(void *u, uint32_t i, nbep_evloop_motion *m)
{
    const cells_user *x = u;
    const pred_ctx *c = x->c;
    *m = (nbep_evloop_motion){x->s->pos[i], x->s->vel[i], c->tau[i], c->ver[i],
                              {x->s->image[3 * (size_t)i], x->s->image[3 * (size_t)i + 1],
                               x->s->image[3 * (size_t)i + 2]},
                              {0, 0}};
    /* a dissipative free flight's reaction also moves the TC clock and the reaction count
     * of its spheres (react, fire): nothing else of them (no rest, settle or cage records) */
    _Static_assert(sizeof *c->t_last <= sizeof m->own[0] && sizeof *c->jam <= sizeof m->own[1],
                   "a sphere's clock and count fit the engine's words");
    if (c->t_last)
        memcpy(&m->own[0], &c->t_last[i], sizeof *c->t_last);
    if (c->jam)
        memcpy(&m->own[1], &c->jam[i], sizeof *c->jam);
}

static void cells_prefetch(const void *u, uint32_t i)
{
    const cells_user *x = u;
    NBEP_PREFETCH_W(&x->s->pos[i]);
    NBEP_PREFETCH_W(&x->s->vel[i]);
    NBEP_PREFETCH_W(&x->c->tau[i]);
    NBEP_PREFETCH_W(&x->c->ver[i]);
    NBEP_PREFETCH_W(&x->s->image[3 * (size_t)i]);
}

static void cells_restore(void *u, uint32_t i, const nbep_evloop_motion *m)
{
    const cells_user *x = u;
    x->s->pos[i] = m->pos;
    x->s->vel[i] = m->vel;
    x->c->tau[i] = m->tau;
    x->c->ver[i] = m->ver;
    for (int k = 0; k < 3; k++)
        x->s->image[3 * (size_t)i + (size_t)k] = m->image[k];
    if (x->c->t_last)
        memcpy(&x->c->t_last[i], &m->own[0], sizeof *x->c->t_last);
    if (x->c->jam)
        memcpy(&x->c->jam[i], &m->own[1], sizeof *x->c->jam);
}

/* A team context's counts and sums from zero, before it handles a place (on the thread that
 * handles it). */
static void cells_clear(void *uh)
{
    cells_user *h = uh;
    for (int k = 0; k < NBEP_COUNTER_COUNT; k++)
        h->cnt->c[k] = 0;
    h->mx->overlap = h->mx->overlap_rel = 0.0;
    nbep_xsum_clear(&h->mx->virial);
    for (size_t p = 0; p < h->s->n_planes; p++)
        nbep_xsum_clear(&h->mx->wall[p]);
}

/* The event of a team context (counted from zero in uh) added to the counts and sums of the
 * thread that handled it (u) when it stands (the sums exact, so their total over the threads
 * is the one thread's whoever handled what). */
static void cells_merge(void *u, const void *uh)
{
    cells_user *x = u;
    const cells_user *h = uh;
    nbep_thread_max *a = x->mx;
    const nbep_thread_max *b = h->mx;
    for (int k = 0; k < NBEP_COUNTER_COUNT; k++)
        x->cnt->c[k] += h->cnt->c[k];
    nbep_xsum_merge(&a->virial, &b->virial);
    a->overlap = fmax(a->overlap, b->overlap); /* both from 0, as note_overlap keeps them */
    a->overlap_rel = fmax(a->overlap_rel, b->overlap_rel);
    for (size_t p = 0; p < x->s->n_planes; p++)
        nbep_xsum_merge(&a->wall[p], &b->wall[p]);
}

static const nbep_evloop_ops cells_ops = {cells_planes,  cells_pairs,   cells_fresh,
                                          cells_react,   cells_flight,  cells_wrap,
                                          cells_save,    cells_restore, cells_clear,
                                          cells_merge,   cells_prefetch};
static const nbep_evloop_ops cells_ops_free = {cells_planes, cells_pairs_free, cells_fresh,
                                               cells_react,  cells_flight,     cells_wrap,
                                               cells_save,   cells_restore,    cells_clear,
                                               cells_merge,  cells_prefetch};

/* The team loop pays where other cores are close (it passes a few cache lines per event
 * between them), and loses where they are not or are busy with other work: the same fluid on
 * this project's 2-core virtual machine ran 1.5 times as fast as one thread in some runs and
 * 0.8 times in others. Results are the same bit for bit whatever the way, so the run measures
 * each (one thread, a pair, and the whole team where it has more than two threads) and takes
 * the fastest: every TEAM_PROBE-th step runs another way (a probe; with three ways, the other
 * two in turn). The way taken keeps its seconds per event as a running mean of its steps (half
 * the last step, half what it was); a probe's figure replaces the probed way's, which would
 * otherwise carry a probe from many steps before (the first, at the second step, runs while a
 * lattice start melts, on events a quarter cheaper than later: its figure kept the run probing
 * every TEAM_PROBE-th step, 5 probes in 80 steps of a fluid at N = 256000, phi = 0.30, each
 * costing 0.75 of a team step). A probe costs what the slower way loses: with the team 1.6
 * times as fast, one step in 8 run alone adds 7 % to the run's time. Where the fastest way is
 * at least TEAM_CLEAR times as fast as every other, they are probed every TEAM_PROBE_FAR-th
 * step only; the way taken is measured at every step, so a change that makes it slower is
 * seen at once. NBEP_TEAM in the environment, read as the run is made, fixes the choice
 * (tests, benchmarks): "always" the whole team, "never" (or 1) one thread, a count k >= 2 a
 * team of k threads (at most the run's and NBEP_EVLOOP_TEAM_MAX), "cycle" the ways in turn,
 * step by step, the whole team first (every change of way, for the tests). */
#define TEAM_PROBE 8
#define TEAM_PROBE_FAR 64
#define TEAM_CLEAR 1.25

#define TEAM_CYCLE (-2)

/* NBEP_TEAM: 1 always, -1 never, k >= 2 always with a team of k, TEAM_CYCLE, 0 (unset or
 * anything else) the fastest way. */
static int team_forced(void)
{
    const char *v = getenv("NBEP_TEAM");
    if (!v)
        return 0;
    if (strcmp(v, "always") == 0)
        return 1;
    if (strcmp(v, "never") == 0)
        return -1;
    if (strcmp(v, "cycle") == 0)
        return TEAM_CYCLE;
    char *end;
    const long k = strtol(v, &end, 10);
    if (end == v || *end != '\0' || k < 1)
        return 0;
    /* a team of one is one thread; a team is at most NBEP_EVLOOP_TEAM_MAX */
    return k == 1 ? -1 : k < NBEP_EVLOOP_TEAM_MAX ? (int)k : NBEP_EVLOOP_TEAM_MAX;
}

/* The fastest way measured (ties: the one with more threads). */
static int team_best(const pred_ctx *c)
{
    int best = c->team_ways - 1;
    for (int w = best - 1; w >= 0; w--)
        if (c->team_cost[w] < c->team_cost[best])
            best = w;
    return best;
}

/* Thread 0, after step `step` ran its events (`events` of them in `seconds`) way `way`: the
 * way of the next step. */
static void team_choose(pred_ctx *c, uint64_t step, int way, uint64_t events, double seconds)
{
    if (events > 0) {
        const double per = seconds / (double)events;
        const bool probed = way != team_best(c); /* a slower way */
        double *m = &c->team_cost[way];
        *m = *m > 0.0 && !probed ? 0.5 * (*m + per) : per;
    }
    int *next = &c->team_way[(step + 1) & 1];
    if (c->team_force == TEAM_CYCLE) {
        *next = way > 0 ? way - 1 : c->team_ways - 1;
        return;
    }
    if (c->team_force) {
        *next = c->team_force > 0 ? c->team_ways - 1 : 0;
        return;
    }
    for (int w = c->team_ways - 1; w >= 0; w--)
        if (c->team_cost[w] == 0.0) { /* each way measured once, the largest first */
            *next = w;
            return;
        }
    const int best = team_best(c);
    bool clear = true;
    for (int w = 0; w < c->team_ways; w++)
        clear &= w == best || c->team_cost[w] >= TEAM_CLEAR * c->team_cost[best];
    const uint64_t probe = clear ? TEAM_PROBE_FAR : TEAM_PROBE;
    if ((step + 1) % probe != 0) {
        *next = best;
        return;
    }
    /* the probes take the other ways in turn */
    const int k = (int)((step + 1) / probe % (uint64_t)(c->team_ways - 1));
    *next = (best + 1 + k) % c->team_ways;
}

/* Thread 0, after step `step` of grid mode ran way `way` in `seconds` (from its start to the
 * barrier after the update: a crew smaller than the run's leaves the others waiting, asleep
 * after a while, and they take their share of the update late; timed on its rounds alone, the
 * paper's box on a 16-core node took 1.17 times as long as with every thread): the way of the
 * next step, team_choose's, timed per step. Two differences, both from the same node, where
 * the box of 32768 spheres ran 1.19, 1.40 and 1.61 ms a step on 16, 2 and 1 threads and the
 * run's own choice took 1.4 times as long as 16 threads throughout:
 * - per step, not per event (round): much of a step does not depend on its rounds (the first
 *   round's look at every slot, the update), and the box has 20 to 40 rounds a step;
 * - a step whose way differs from the step before's is not timed, and the next runs the same
 *   way: after a change the sphere states, slots and candidate lists that the other crew
 *   wrote are still in its cores' caches, so a probe timed on its first step pays for the
 *   change, which a way kept for many steps pays once (our reading of why the box's run kept
 *   to the smaller crews). */
static void crew_choose(pred_ctx *c, uint64_t step, int way, double seconds)
{
    if (way != c->crew_last && c->team_force != TEAM_CYCLE) {
        c->crew_last = way;
        c->team_way[(step + 1) & 1] = way;
        return;
    }
    c->crew_last = way;
    team_choose(c, step, way, 1, seconds);
}

/* The steps of the cells mode, inside pred_run's parallel region. Thread 0 runs each step's
 * event loop, with threads 1.. in a team where the scene allows it (c->team, team_choose); all
 * threads share the rebuilds, the update to the step's end and the energy.
 * A rebuild (cells from positions, every slot predicted afresh: about the cost of n/2
 * collisions) happens at the first step and after every step that writes a frame to a file in
 * step with output.every, so that a run resumed from such a frame starts from exactly the state
 * this run continues from (bit-for-bit resume): the cell membership and the moments at which
 * slots were predicted depend on the run's history, the rebuild makes them depend only on the
 * frame. */
static void cells_steps(nbep_sim *sim, pred_ctx *c, int tid, nbep_range own, thread_ws *w)
{
    nbep_state *s = &sim->st;
    const nbep_evloop_ops *ops = c->free_flight ? &cells_ops_free : &cells_ops;
    bool rebuild = true;
    if (c->refit) /* for the first rebuild's cells_fit; each step's end takes them again */
        nbep_grid_bounds(s->pos, own.lo, own.hi, &w->grid_lo, &w->grid_hi);
    for (uint64_t step = sim->step_first; step <= sim->step_end; step++) {
        const int spar = (int)(step & 1);
        cells_user u = {c, s, sim->scene, (double)(step - 1) * sim->dt, 0.0, w,
                        &sim->counters[spar][tid], &sim->tmax[spar][tid]};
        const double T_end = (double)step * sim->dt;
        w->jam_step = (uint32_t)step;
        if (rebuild) { /* every sphere sits at T0 (tau = 0) */
            /* positions wrapped into a periodic box, as frames write them (output.c): the
             * run continues from what a resumed one reads */
            for (size_t i = own.lo; c->pb.any && i < own.hi; i++)
                nbep_periodic_wrap(&c->pb, &s->pos[i], &s->image[3 * i]);
            if (c->refit && !cells_fit(sim, c, tid, u.cnt))
                return;
            nbep_evloop_assign(c->ev, s->pos, own.lo, own.hi);
            nbep_barrier_wait(&c->bar);
            if (tid == 0)
                nbep_evloop_link(c->ev);
            nbep_barrier_wait(&c->bar);
            nbep_evloop_count(c->ev, own.lo, own.hi);
            nbep_barrier_wait(&c->bar);
            if (tid == 0)
                nbep_evloop_layout(c->ev);
            nbep_barrier_wait(&c->bar);
            nbep_evloop_predict(c->ev, ops, &u, own.lo, own.hi, u.T0);
            u.cnt->c[NBEP_COUNTER_CHECKS] += own.hi - own.lo;
            nbep_barrier_wait(&c->bar);
            if (tid == 0) {
                nbep_evloop_schedule(c->ev, u.T0);
                if (step == sim->step_first) { /* SPEC: first predictions are set-up time */
                    double now = nbep_now();
                    sim->setup_seconds += now - sim->t_start;
                    sim->t_start = sim->t_last_progress = now;
                }
            }
            rebuild = false;
        }
        /* the team loop's contexts, one per ring slot of its places, on each thread of the
         * team (with that thread's workspace), the counts and sums of a place apart, the
         * thread's own */
        cells_user ups[NBEP_EVLOOP_RING];
        void *us[NBEP_EVLOOP_RING];
        for (size_t m = 0; c->team && tid < c->team_size && m < NBEP_EVLOOP_RING; m++) {
            const size_t h = (size_t)tid * NBEP_EVLOOP_RING + m;
            ups[m] = (cells_user){c, s, sim->scene, u.T0, 0.0, w, &c->help_cnt[h], &c->help_mx[h]};
            us[m] = &ups[m];
        }
        const int way = c->team_way[step & 1], crew = c->team_crew[way];
        if (tid >= 1 && tid < crew)
            nbep_evloop_help(c->ev, ops, &u, us, tid, step);
        if (tid == 0) {
            nbep_evloop_tally tally = {0};
            double t_stuck = 0.0;
            uint32_t jammed;
            const double t_loop = nbep_now();
            c->ev_failed =
                !(crew > 1 ? nbep_evloop_run_lead(c->ev, ops, &u, us, crew, step, T_end,
                                                  STALL_EVENTS, STALL_FRACTION * sim->dt,
                                                  &tally, &t_stuck)
                           : nbep_evloop_run(c->ev, ops, &u, T_end, STALL_EVENTS,
                                             STALL_FRACTION * sim->dt, &tally, &t_stuck));
            if (c->team)
                team_choose(c, step, way, tally.events, nbep_now() - t_loop);
            u.cnt->c[NBEP_COUNTER_CHECKS] += tally.events;
            u.cnt->c[NBEP_COUNTER_AHEAD] += tally.ahead;
            u.cnt->c[NBEP_COUNTER_UNDONE] += tally.undone;
            if (c->ev_failed && nbep_evloop_failed(c->ev)) {
                nbep_diag_add(sim->diag, __FILE__, __LINE__,
                              "nbep: step %llu: no memory for the neighbour lists; stopping",
                              (unsigned long long)step);
                sim->status = NBEP_ENOMEM;
            } else if (c->ev_failed && (jammed = cells_jammed(c, s->n, step)) != 0) {
                jam_fail(sim, step, jammed - 1, t_stuck);
            } else if (c->ev_failed) {
                nbep_diag_add(sim->diag, __FILE__, __LINE__,
                              "nbep: step %llu: events at t = %.17g do not resolve "
                              "(endless zero-time reactions); stopping",
                              (unsigned long long)step, t_stuck);
                sim->status = NBEP_ENUMERIC;
            }
        }
        nbep_barrier_wait(&c->bar);
        if (c->ev_failed) /* written by thread 0 before the barrier */
            return;
        w->n_settle = 0;
        for (size_t i = own.lo; i < own.hi; i++) { /* update: every sphere to the step's end */
            double h = sim->dt - c->tau[i];
            if (h > 0.0)
                nbep_physics_drift(&s->pos[i], &s->vel[i], effective_acc(c, s, i), h);
            c->tau[i] = 0.0;
            if (c->settle)
                w->n_settle += settle_count(c, s, i, sim->dt);
        }
        if (c->refit)
            nbep_grid_bounds(s->pos, own.lo, own.hi, &w->grid_lo, &w->grid_hi);
        nbep__sim_block_energy(sim, own);
        nbep__sim_frame_overlap(sim, step, tid, own, &c->bar);
        nbep_barrier_wait(&c->bar);
        /* spheres held by settling move no more: every slot is predicted again (a rebuild) */
        const bool settled = settle_phases(sim, c, own, w);
        if (tid == 0)
            nbep__sim_end_step(sim, step);
        /* only frames written to a file can be resumed from (and, with settling or spheres
         * that left the cells, the next step's rebuild follows from the state, so a resumed
         * run takes it too) */
        rebuild = settled || (c->refit && cells_outgrown(c)) ||
                  (sim->opt.out && step % sim->scene->output_every == 0);
        nbep_barrier_wait(&c->bar);
        /* relaxed: the barrier above ordered thread 0's store of stop */
        if (atomic_load_explicit(&sim->stop, memory_order_relaxed))
            return;
    }
}

static void pred_run(nbep_sim *sim, void *p)
{
    pred_ctx *c = p;
#pragma omp parallel num_threads(sim->nt) default(none) shared(sim, c)
    {
        const int tid = nbep__thread_id();
        const int nt = sim->nt;
        nbep_state *s = &sim->st;
        const nbep_range own = nbep__range_split(s->n, tid, nt);
        thread_ws *w = &c->ws[tid];
        if (c->ev) {
            cells_steps(sim, c, tid, own, w);
            goto done;
        }
        if (c->use_grid)
            grid_prepare(c, s, tid, own, (double)(sim->step_first - 1) * sim->dt, sim->dt, true);
        /* OpenMP's own hand-over into and out of the region is invisible to ThreadSanitizer
         * (libgomp is not instrumented); crossing our barrier first and last makes every
         * write before the region visible to all threads, and theirs to the caller, through
         * C11 atomics it does see. Two crossings per run cost nothing. */
        nbep_barrier_wait(&c->bar);

        /* initial predictions: every slot starts invalid (paper: "initialize events"); a
         * resumed run has its slots already, and re-predicts its stale ones in its first step */
        if (!c->imported) {
            nbep_counters *cnt0 = &sim->counters[sim->step_first & 1][tid];
            const double T0 = (double)(sim->step_first - 1) * sim->dt;
            find_phase(c, own, nt, true, T0, w, cnt0);
            w->n_cand = 0;
            nbep_barrier_wait(&c->bar);
            redo_phase(c, s, own, tid, nt, &c->bar, T0, T0, w, cnt0, sim);
        }
        if (tid == 0) { /* SPEC: the first predictions belong to the set-up time */
            double now = nbep_now();
            sim->setup_seconds += now - sim->t_start;
            sim->t_start = sim->t_last_progress = now;
        }
        /* a stop signal during the initial predictions (redo_phase): the run ends at step 0,
         * its frame written, as a signal before them does (nbep_sim_run). relaxed: redo_phase's
         * last barrier ordered thread 0's store, and nothing stores stop until the steps */
        if (!c->imported && atomic_load_explicit(&sim->stop, memory_order_relaxed)) {
            if (tid == 0)
                sim->status = nbep_sim_stop_status(sim->opt.stop_signal);
            goto done;
        }

        for (uint64_t step = sim->step_first; step <= sim->step_end; step++) {
            const int spar = (int)(step & 1);
            nbep_counters *cnt = &sim->counters[spar][tid];
            nbep_thread_max *mx = &sim->tmax[spar][tid];
            const double T0 = (double)(step - 1) * sim->dt;
            const double T_end = (double)step * sim->dt;
            double t_check = T0;
            w->jam_step = (uint32_t)step;
            /* the held spheres woken so far as the rounds have acted on them (let_go_phase):
             * the crew's count where the last step's rounds ended, not every thread's count
             * now, which a let-go in the last round may have raised without its turn yet */
            uint64_t seen_woken = c->seen_before;
            const double t_step = nbep_now();
            /* the crew of this step's rounds after the first (c->crews), its barrier and each
             * one's share; the first round (every slot looked at, and every sphere whose slot
             * is stale or whose horizon has come re-predicted: a grid's horizon, every 1 to 64
             * steps, re-predicts them all) runs on every thread */
            const int way = c->crews ? c->team_way[step & 1] : 0;
            const int crew = c->crews ? c->team_crew[way] : nt;
            nbep_barrier *bar = c->crews ? &c->crew_bar[way] : &c->bar;
            const nbep_range mine = crew == nt ? own : nbep__range_split(s->n, tid, crew);
            bool quit = false;
            /* the rounds of the step, numbered from 0 on every thread of the crew: the claims'
             * parity, and past the rounds of the steps before (stamp0), a reaction's stamp */
            const uint64_t stamp0 = c->rounds_before;
            uint64_t round = 0;
            for (bool first = true;; first = false, round++) {
                const int par = (int)(round & 1);
                /* this round's threads so far, their barrier and each one's share */
                const int k_all = first ? nt : crew;
                nbep_barrier *b_all = first ? &c->bar : bar;
                const nbep_range share = first ? own : mine;
                /* the claim words of the previous round are reset while nobody reads them */
                for (size_t k = 0; k < w->n_claimed; k++)
                    atomic_store_explicit(&c->claim[par ^ 1][w->claimed[k]], KEY_FREE,
                                          memory_order_relaxed);
                w->n_claimed = 0;
                for (size_t k = 0; k < w->n_tclaimed; k++) /* step order's, the same way */
                    atomic_store_explicit(&c->tclaim[w->tclaimed[k]], KEY_FREE,
                                          memory_order_relaxed);
                w->n_tclaimed = 0;
                find_phase(c, share, crew, first, T_end, w, cnt);
                nbep_barrier_wait(b_all);
                /* relaxed: the barrier above ordered thread 0's store of stop */
                if (first && atomic_load_explicit(&sim->stop, memory_order_relaxed)) {
                    quit = true;
                    break;
                }
                redo_phase(c, s, share, tid, k_all, b_all, T0, T_end, w, cnt, NULL);
                w->t_min = cand_t_min(c, w);
                nbep_barrier_wait(b_all);
                /* the threads out of the crew are done: the rest of the step's rounds is the
                 * crew's (each t_min is read here by the crew alone, before its next write) */
                if (first && tid >= crew)
                    break;
                double t_min = INFINITY;
                for (int t = 0; t < k_all; t++)
                    t_min = fmin(t_min, c->ws[t].t_min);
                if (!(t_min < T_end))
                    break;
                if (first && crew < nt) {
                    /* the crew takes the candidates over, each thread those of its share from
                     * every thread's list (gathered in its redo list, free until the next
                     * round's find phase, and as long as its share) */
                    w->n_redo = 0;
                    for (int t = 0; t < nt; t++)
                        for (size_t q = 0; q < c->ws[t].n_cand; q++) {
                            const uint32_t i = c->ws[t].cand[q];
                            if (i >= mine.lo && i < mine.hi)
                                w->redo[w->n_redo++] = i;
                        }
                    nbep_barrier_wait(bar); /* every list read before any is replaced */
                    memcpy(w->cand, w->redo, w->n_redo * sizeof *w->cand);
                    w->n_cand = w->n_redo;
                    w->n_redo = 0;
                }
                if (round % STALL_ROUNDS == STALL_ROUNDS - 1 &&
                    !(t_min - t_check > STALL_FRACTION * sim->dt)) {
                    if (tid == 0) {
                        nbep_diag_add(sim->diag, __FILE__, __LINE__,
                                      "nbep: step %llu: events at t = %.17g do not resolve "
                                      "(endless zero-time reactions); stopping",
                                      (unsigned long long)step, t_min);
                        sim->status = NBEP_ENUMERIC;
                    }
                    quit = true;
                    break;
                }
                if (round % STALL_ROUNDS == STALL_ROUNDS - 1)
                    t_check = t_min;
                if (c->order_step) {
                    claim_time_phase(c, w);
                    nbep_barrier_wait(bar);
                }
                claim_phase(c, par, t_min, w);
                nbep_barrier_wait(bar);
                react_phase(c, s, sim->scene, par, T0, t_min, stamp0 + round + 1, w, cnt, mx);
                nbep_barrier_wait(bar);
                /* a limit passed by this round's reactions, or by the let-go after them (seen
                 * here, in the step it happened: found at the next reaction, it was reported
                 * 37 steps late in a review's scene) */
                uint32_t jammed = lowest_jammed(c);
                uint64_t woken = 0; /* every thread's: those out of the crew change none */
                for (int t = 0; t < nt; t++)
                    woken += c->ws[t].woken;
                if (!jammed && woken != seen_woken) { /* the same decision on every thread */
                    seen_woken = woken;
                    let_go_phase(c, s, mine, bar, sim->dt, t_min - T0, w);
                    jammed = lowest_jammed(c);
                }
                if (jammed) {
                    if (tid == 0)
                        jam_fail(sim, step, jammed - 1, t_min);
                    quit = true;
                    break;
                }
            }
            if (crew < nt) { /* the others learn whether the rounds stopped the run */
                if (tid == 0)
                    c->crew_quit = quit;
                nbep_barrier_wait(&c->bar);
                quit = c->crew_quit;
            }
            if (quit)
                goto done;
            if (tid == 0) { /* read at the next step's start, past the barriers of its end */
                c->rounds_before = stamp0 + round + 1;
                c->seen_before = seen_woken;
            }

            /* update (paper Section 4.3.1): every own sphere flies to the step's end; grid mode
             * also takes the speed bounds of the next step here, in parallel */
            double vmax = 0.0, amax = 0.0;
            w->n_settle = 0;
            for (size_t i = own.lo; i < own.hi; i++) {
                double h = sim->dt - c->tau[i];
                nbep_vec3 a = effective_acc(c, s, i);
                if (h > 0.0)
                    nbep_physics_drift(&s->pos[i], &s->vel[i], a, h);
                c->tau[i] = 0.0;
                if (c->pb.any) /* into the box, as frames are written (slots hold no positions) */
                    nbep_periodic_wrap(&c->pb, &s->pos[i], &s->image[3 * i]);
                if (c->use_grid) {
                    vmax = fmax(vmax, nbep_vec3_norm(s->vel[i]));
                    amax = fmax(amax, nbep_vec3_norm(a));
                }
                if (c->settle)
                    w->n_settle += settle_count(c, s, i, sim->dt);
            }
            w->vmax_end = vmax;
            w->amax_end = amax;
            nbep__sim_block_energy(sim, own);
            nbep__sim_frame_overlap(sim, step, tid, own, &c->bar);
            nbep_barrier_wait(&c->bar);
            /* the crew of the next step (crew_choose), from the seconds of this one's rounds
             * and update; the others read it past grid_prepare's barriers */
            if (tid == 0 && c->crews)
                crew_choose(c, step, way, nbep_now() - t_step);
            if (c->use_grid) /* all threads, from the positions at T_end */
                grid_prepare(c, s, tid, own, T_end, sim->dt, false);
            /* the speed bounds taken above stay bounds: held spheres only slow down */
            (void)settle_phases(sim, c, own, w);
            if (tid == 0) /* the others are in the next find phase, which reads no grid */
                nbep__sim_end_step(sim, step);
            /* no barrier: the next find phase only reads positions and writes queue slots,
             * which the hook does not touch; its stop request is read after that phase's
             * barrier */
        }
    done:
        nbep_barrier_wait(&c->bar);
    }
}

/* At a frame (all spheres at the step's end, thread 0 between barriers: slots are stable):
 * each sphere's slot as the next step will see it (stale ones as NONE, so that a resumed run
 * re-predicts exactly the spheres this run would) and its resting plane. */
static void pred_export(const void *p, const nbep_state *s, double *time, uint32_t *partner,
                        uint8_t *kind, int32_t *rest)
{
    const pred_ctx *c = p;
    for (size_t i = 0; i < s->n; i++) {
        const nbep_event *ev = nbep_feq_slot(c->q, i);
        bool fresh = is_fresh(c, i, ev);
        time[i] = fresh && ev->kind != NBEP_EVENT_NEVER ? ev->time : 0.0; /* never inf: STYLE */
        partner[i] = fresh ? ev->partner : 0;
        kind[i] = (uint8_t)(fresh ? ev->kind : NBEP_EVENT_NONE);
        rest[i] = NO_PLANE; /* the file keeps one plane: the first (see pred_import) */
        for (int k = c->rest ? c->rest[i].n - 1 : -1; k >= 0; k--)
            if (c->rest[i].who[k] >= 0)
                rest[i] = c->rest[i].who[k];
    }
}

/* A resumed run starts with every response count at 0, so the saved events are stored with
 * counts 0: fresh exactly where they were fresh when saved. */
static void pred_import(void *p, const nbep_resume *r)
{
    pred_ctx *c = p;
    for (size_t i = 0; i < r->n; i++) {
        /* A resumed run gets back one resting plane per sphere; other contacts (a second plane,
         * held spheres) are found again by zero-time events in its first step. */
        if (c->rest) { /* NULL: nothing accelerates, nothing rests (a file says -1) */
            c->rest[i] = (rest_set){.n = 0};
            if (r->rest[i] >= 0) {
                c->rest[i].who[0] = r->rest[i];
                c->rest[i].n = 1;
            }
            nbep_vec3 v = c->st->vel[i]; /* the frame's (nbep_resume_apply) */
            rest_solve(c, c->st, i, &c->rest[i], &v, &c->aeff[i], 0.0, false);
        }
        nbep_feq_remove(c->q, i);
        if (r->event_kind[i] == NBEP_EVENT_NEVER)
            nbep_feq_set_never(c->q, i, 0);
        else if (r->event_kind[i] == NBEP_EVENT_SPHERE || r->event_kind[i] == NBEP_EVENT_PLANE ||
                 r->event_kind[i] == NBEP_EVENT_HORIZON)
            nbep_feq_insert(c->q, i,
                            (nbep_event){r->event_time[i], r->event_partner[i],
                                         r->event_kind[i], 0, 0});
    }
    c->imported = true;
}

/* How a run on nt >= 2 threads shares its work, by the plan pred_create follows. */
static void pred_threads_use(const nbep_scene *sc, int nt, char *buf, size_t len)
{
    const pred_plan p = plan_of(sc, &sc->state, nt, team_forced());
    if (p.team)
        snprintf(buf, len,
                 "the event loop on a team of up to %d or on one, whichever the run measures "
                 "fastest (nothing accelerates); all %d share the rebuilds, the update and the "
                 "energy",
                 p.team_size, nt);
    else if (p.cells)
        snprintf(buf, len,
                 "the event loop on one (something accelerates: its contacts need the events in "
                 "order); all %d share the rebuilds, the update and the energy",
                 nt);
    else if (p.crews)
        snprintf(buf, len, "each step's rounds on %s, whichever the run measures fastest",
                 p.team_ways > 2 ? "1, 2 or all" : "1 or 2");
    else
        snprintf(buf, len, "all %d share each round (find, react, predict again)", nt);
}

const nbep_algo nbep__algo_predictive = {.name = "predictive",
                                         .exact_overlap = false,
                                         .create = pred_create,
                                         .run = pred_run,
                                         .destroy = pred_destroy,
                                         .bytes = pred_bytes,
                                         .threads_use = pred_threads_use,
                                         .export_events = pred_export,
                                         .import_events = pred_import};
