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
 *   TC model that ends inelastic collapse, and caged for a sphere between two fixed faces, all
 *   in pred_react.c, and pred_settle.c for settling. */
#include "pred_impl.h"

#include <stdlib.h>
#include <string.h>

#include "nbep/slabcal.h"

/* A look at each re-prediction of the rounds: the time found (raw), the time kept (kept) and
 * the round's time (t_now); tests/test_late_roots.c counts the late roots and checks that
 * none is kept behind the round (nbep_feq_not_before); a build of nbep has nothing here. */
#ifndef NBEP_PRED_PREDICTED_HOOK
#define NBEP_PRED_PREDICTED_HOOK(raw, kept, t_now) ((void)(raw), (void)(kept), (void)(t_now))
#endif

#define NO_PLANE (-1)
/* Re-predictions are shared out in chunks of this many spheres: each thread finds the best
 * event of every sphere of the chunk among its own partners, then the owners merge. The
 * chunk bounds the per-thread buffers (not O(n) per thread). */
#define CHUNK 512

/* Per-sphere flags, touched only by the sphere's owner. */
#define IN_CAND 1u
#define IN_REDO 2u
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
    free(c->jr.term);
    nbep__pred_cells_worlds_free(c);
    nbep_free_aligned(c->ver);
    nbep_free_aligned(c->tau);
    nbep_free_aligned(c->rest);
    nbep_free_aligned(c->aeff);
    nbep_free_aligned(c->t_last);
    nbep_free_aligned(c->face);
    nbep_free_aligned(c->settle);
    nbep_free_aligned(c->jam);
    free(c->lock_mark);
    free(c->unlocked);
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
            free(c->ws[t].lock);
            free(c->ws[t].claimed);
            free(c->ws[t].tclaimed);
            nbep_free_aligned(c->ws[t].part);
            nbep_predict_ws_destroy(&c->ws[t].pws);
        }
        nbep_free_aligned(c->ws);
    }
    free(c);
}

/* NBEP_TEAM, read as a run is made or estimated (pred_ways.c). */
static int team_forced(void)
{
    return nbep__pred_ways_forced(getenv("NBEP_TEAM"));
}

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
    int slabs;          /* cells mode: per-slab calendars (NBEP_SLABS; 1: one calendar) */
    bool scheduled;     /* cells mode: the loop through the scheduler (NBEP_SCHEDULED) */
    pred_ways ways;     /* the ways a step may run (grid mode's crews, cells mode's team) */
} pred_plan;

/* NBEP_SLABS, read as a run is made or estimated: the slabs of per-slab calendars in cells
 * mode (nbep_evloop_set_slabs: step 1 of docs/optimistic-design.md, for measuring what the
 * slabs' merge costs; the results are the same). Unset or below 2: one calendar; past
 * NBEP_SLABCAL_MAX: the run refuses it. */
static int slabs_asked(void)
{
    const char *v = getenv("NBEP_SLABS");
    if (!v)
        return 1;
    char *end;
    const long k = strtol(v, &end, 10);
    if (end == v || *end != '\0' || k < 2)
        return 1;
    return k > NBEP_SLABCAL_MAX ? NBEP_SLABCAL_MAX + 1 : (int)k;
}

/* NBEP_SCHEDULED=1, read as a run is made: cells mode's loop through the optimistic scheduler
 * (nbep_evloop_set_scheduled, for measuring what its bookkeeping costs the engine and what its
 * slabs gain on threads; the results are the same), in a free flight, the team off: on one
 * slab and one thread, or with NBEP_SLABS on that many, each in a world of its own
 * (nbep_evloop_set_worlds), on the run's threads (at most one a slab: pred_ctx slab_crew). */
static bool scheduled_asked(void)
{
    const char *v = getenv("NBEP_SCHEDULED");
    return v && strcmp(v, "1") == 0;
}

/* The plan of a run of scene sc from state st (the scene's, or a run's copy of it) on nt
 * threads, with NBEP_TEAM's choice team_force (team_forced). */
static pred_plan plan_of(const nbep_scene *sc, const nbep_state *st, int nt, int team_force)
{
    pred_plan p = {.n = st->n, .n_planes = st->n_planes, .nt = nt,
                   .free_flight = nbep_state_free_flight(st)};
    p.tc_model = nbep_scene_tc_model(sc);
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
        nbep__pred_ways_init(&p.ways, size, team_force);
    }
    if (p.cells) {
        /* the team loop: reactions in free flight change their own spheres only (nothing
         * rests, holds, settles or is caged without an acceleration): their motion, and at
         * e < 1 their TC clocks and reaction counts, which the loop keeps with the motion to
         * undo a speculative reaction (cells_save) */
        p.slabs = slabs_asked();
        p.scheduled = scheduled_asked() && p.free_flight && p.slabs <= NBEP_SLABCAL_MAX;
        /* (per-slab calendars are merged on one thread: the team loop keeps one calendar) */
        const bool can_team = nt >= 2 && p.free_flight && p.slabs < 2 && !p.scheduled;
        int size = nt < NBEP_EVLOOP_TEAM_MAX ? nt : NBEP_EVLOOP_TEAM_MAX;
        if (team_force >= 2 && team_force < size)
            size = team_force;
        p.team_size = can_team ? size : 1;
        p.team = p.team_size >= 2;
        nbep__pred_ways_init(&p.ways, p.team_size, team_force);
    }
    return p;
}

/* Thread t's share of the spheres, which sizes its workspaces: its own range and one, or in
 * grid mode its largest share in any crew it belongs to. */
static size_t plan_own(const pred_plan *p, int t)
{
    const nbep_range r = nbep__range_split(p->n, t, p->nt);
    size_t own = r.hi - r.lo + 1;
    for (int k = 0; p->crews && k < p->ways.n; k++)
        if (t < p->ways.crew[k]) {
            const nbep_range q = nbep__range_split(p->n, t, p->ways.crew[k]);
            own = own > q.hi - q.lo + 1 ? own : q.hi - q.lo + 1;
        }
    return own;
}

/* Rounds modes that settle, in time order: jammed bodies, made at a round's end on thread 0
 * (lock_phase). */
static bool plan_lock(const pred_plan *p)
{
    return p->rounds && p->settle_model && !p->order_step;
}

/* The room of thread t's list of fired spheres: 2 per reaction, 1 per let-go; cells mode: one
 * reaction's 3 and every held sphere letting go after it, on the thread that runs the event
 * loop (and a team's helper, or a thread of the scheduled loop's slabs, whose reactions change
 * their own two spheres only: free flight). */
static size_t plan_fired(const pred_plan *p, int t)
{
    if (p->rounds) /* thread 0: and every sphere, for the bodies of a lock_phase */
        return 3 * plan_own(p, t) + (t == 0 && plan_lock(p) ? p->n : 0);
    /* a team's helper, or a thread of the scheduled loop's slabs (their worlds' scratch: a
     * free flight's reaction fires its own two spheres) */
    const bool slab_thread = p->scheduled && p->slabs > 1 && t < p->slabs;
    return t == 0 ? p->n + 3 : (p->team && t < p->team_size) || slab_thread ? 3 : 1;
}

/* The bytes pred_create allocates for a run of sc on nt threads, by the same plan: the
 * algorithm's part of nbep check's memory estimate (cells mode: lists of ESTIMATE_NEIGHBOURS;
 * GSL's part of each thread's quartic workspace, a few hundred bytes, left out), exact but
 * for those (tests/test_memory_plan.c counts create's allocations against it). */
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
    const bool lock = plan_lock(&p); /* jammed bodies */
    if (lock)
        bytes += n * (sizeof *c->lock_mark + sizeof *c->unlocked);
    bytes += (size_t)nt * sizeof *c->ws;
    for (int t = 0; t < nt; t++) {
        const size_t own = plan_own(&p, t);
        bytes += plan_fired(&p, t) * sizeof *w->fired + CHUNK * sizeof *w->part +
                 nbep_predict_ws_bytes();
        if (p.rounds)
            bytes += own * (sizeof *w->cand + sizeof *w->redo + sizeof *w->rel +
                            2 * sizeof *w->claimed);
        if (lock)
            bytes += own * sizeof *w->lock;
        if (p.order_step)
            bytes += 2 * own * sizeof *w->tclaimed;
    }
    if (p.use_grid)
        bytes += nbep_grid_bytes(n);
    if (p.cells)
        bytes += nbep_evloop_bytes(n, ESTIMATE_NEIGHBOURS, p.team_size, p.slabs);
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
    const int force = team_forced();
    /* what to allocate: the same plan as pred_bytes counts (keep the two in step) */
    const pred_plan p = plan_of(sim->scene, &sim->st, sim->nt, force);
    c->free_flight = p.free_flight;
    c->ver = nbep_alloc_aligned(n, sizeof *c->ver);
    c->tau = nbep_alloc_aligned(n, sizeof *c->tau);
    if (!p.free_flight) {
        c->rest = nbep_alloc_aligned(n, sizeof *c->rest);
        c->aeff = nbep_alloc_aligned(n, sizeof *c->aeff);
        c->hold_slow = sim->scene->restitution < 1.0;
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
    if (plan_lock(&p)) { /* jammed bodies (lock_phase) */
        c->lock_mark = calloc(n ? n : 1, sizeof *c->lock_mark);
        c->unlocked = calloc(n ? n : 1, sizeof *c->unlocked);
    }
    if (!c->ver || !c->tau || (!p.free_flight && (!c->rest || !c->aeff)) ||
        (plan_lock(&p) && (!c->lock_mark || !c->unlocked)) ||
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
    c->ways = p.ways;
    for (int w = 0; c->crews && w < c->ways.n; w++)
        nbep_barrier_init(&c->crew_bar[w], (unsigned)c->ways.crew[w]);
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
    c->rmax = nbep_state_max_radius(&sim->st);
    c->rmax_other = 0.0;
    size_t n_big = 0, big = SIZE_MAX; /* the spheres of the largest radius, and the last */
    for (size_t i = 0; i < n; i++) {
        mono &= sim->st.radius[i] == sim->st.radius[0];
        same_mass &= sim->st.mass[i] == sim->st.mass[0];
        if (sim->st.radius[i] == c->rmax) {
            n_big++;
            big = i;
        } else {
            c->rmax_other = fmax(c->rmax_other, sim->st.radius[i]);
        }
    }
    c->sigma_all = n > 0 && mono ? sim->st.radius[0] + sim->st.radius[0] : 0.0;
    c->mass_all = n > 0 && same_mass ? sim->st.mass[0] : 0.0;
    c->image_horizon = c->pb.any && !c->use_grid && !sim->scene->neighbors_cells;
    c->big = n_big == 1 ? big : SIZE_MAX; /* two or more: every sphere meets one as large */
    /* 27 images a partner cost 27 predictions; worth it where the nearest image's reach is
     * under a 27th of the wide one (only near SPEC's limit of two diameters: (L/2 - 2 r) <
     * (1.5 L - 2 r) / 27 for L < 2.15 diameters) */
    c->image_wide = c->image_horizon && nbep_periodic_reach(&c->pb, 2.0 * c->rmax) <
                                            nbep_periodic_reach_wide(&c->pb, 2.0 * c->rmax) / 27.0;
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
        const double skin = nbep_scene_list_skin(sim->scene, &sim->st);
        st = nbep_evloop_create(n, sim->scene->box_min, sim->scene->box_max, 2.0 * c->rmax,
                                skin, c->pb.axis, c->team_size, c->q, c->ver, &c->ev, d);
        if (st == NBEP_OK && !mono) /* a mixture: each pair's list reach its own */
            nbep_evloop_set_radii(c->ev, sim->st.radius);
        if (st == NBEP_OK && p.slabs > NBEP_SLABCAL_MAX) {
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: NBEP_SLABS asks for more than %d slabs",
                          NBEP_SLABCAL_MAX);
            st = NBEP_EDECK;
        } else {
            if (st == NBEP_OK && p.slabs >= 2)
                st = nbep_evloop_set_slabs(c->ev, p.slabs, d);
            if (st == NBEP_OK && p.scheduled) { /* (on the slabs, with them) */
                st = nbep_evloop_set_scheduled(c->ev, d);
                c->scheduled = st == NBEP_OK;
                c->slabs = p.slabs;
                c->slab_crew = p.slabs > 1 ? (p.nt < p.slabs ? p.nt : p.slabs) : 1;
            }
        }
        c->team = st == NBEP_OK && p.team;
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
    atomic_init(&c->stop_seen, 0);
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
            if (c->lock_mark)
                w->lock = malloc((own ? own : 1) * sizeof *w->lock);
        }
        if (c->order_step)
            w->tclaimed = malloc(2 * own * sizeof *w->tclaimed);
        if (!w->fired || !w->part ||
            (rounds && (!w->cand || !w->redo || !w->rel || !w->claimed)) ||
            (c->lock_mark && !w->lock) ||
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
 * slots left unpredicted are never used: the run ends at step 0, whose frame is written).
 * Otherwise it updates the progress line with the part made (a line every 10 s in a log, a
 * live one on a terminal, as the steps' own: they showed nothing for those 25 s).
 * t_now: the time of the round whose reactions changed them (the step's start before its
 * first round); no event is placed before it (nbep_feq_not_before). */
static void redo_phase(pred_ctx *c, const nbep_state *s, nbep_range own, int tid, int crew,
                       nbep_barrier *bar, double T0, double T_end, double t_now, thread_ws *w,
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
                    *out = nbep__pred_predict_some(c, s, o->redo[k], own.lo, own.hi, tid == 0,
                                                   T0, w, cnt);
                else if ((base + k) % (size_t)crew == (size_t)tid) /* grid: one thread */
                    *out = nbep__pred_predict_grid(c, s, o->redo[k], T0, V, w, cnt); /* each */
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
                const double raw = best.time;
                best.time = nbep_feq_not_before(best.time, t_now);
                NBEP_PRED_PREDICTED_HOOK(raw, best.time, t_now);
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
        else if (setup && tid == 0) /* chunks of equal cost: the part made is end / total */
            nbep__sim_progress_setup(setup, (double)end / (double)total);
        nbep_barrier_wait(bar);
        /* relaxed: the barrier above ordered thread 0's store */
        if (setup && atomic_load_explicit(&setup->stop, memory_order_relaxed))
            return;
    }
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
        if (nbep__pred_held_on_changed(c, i))
            w->rel[w->n_rel++] = (uint32_t)i;
    nbep_barrier_wait(bar);
    for (size_t m = 0; m < w->n_rel; m++)
        nbep__pred_let_go(c, s, w->rel[m], dt, t_local, w);
    nbep_barrier_wait(bar);
}


static void react_phase(pred_ctx *c, nbep_state *s, const nbep_scene *sc, int par, double T0,
                        double t_min, uint64_t stamp, thread_ws *w, nbep_counters *cnt,
                        nbep_thread_max *mx)
{
    w->n_fired = 0;
    w->n_lock = 0;
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
        nbep__pred_react(c, s, sc, ev->time, ev->time - T0, lo, hi, ev, w, cnt, mx);
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
            nbep__pred_cells_steps(sim, c, tid, own, w);
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
            redo_phase(c, s, own, tid, nt, &c->bar, T0, T0, T0, w, cnt0, sim);
        }
        if (tid == 0) /* SPEC: the first predictions belong to the set-up time */
            nbep__sim_setup_done(sim);
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
            const int way = c->crews ? c->ways.way[step & 1] : 0;
            const int crew = c->crews ? c->ways.crew[way] : nt;
            nbep_barrier *bar = c->crews ? &c->crew_bar[way] : &c->bar;
            const nbep_range mine = crew == nt ? own : nbep__range_split(s->n, tid, crew);
            bool quit = false;
            /* the rounds of the step, numbered from 0 on every thread of the crew: the claims'
             * parity, and past the rounds of the steps before (stamp0), a reaction's stamp */
            const uint64_t stamp0 = c->rounds_before;
            uint64_t round = 0;
            /* the last round's time (step order reacts each event at its own time, in any
             * order: no floor) */
            double t_round = c->order_step ? -INFINITY : T0;
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
                redo_phase(c, s, share, tid, k_all, b_all, T0, T_end, t_round, w, cnt, NULL);
                w->t_min = cand_t_min(c, w);
                /* thread 0 looks at the stop signal; the crew reads what it found past the
                 * barrier (relaxed: the barrier orders it) */
                const bool look = round % STOP_ROUNDS == STOP_ROUNDS - 1;
                if (look && tid == 0 && nbep_sim_stop_status(sim->opt.stop_signal) != NBEP_OK)
                    atomic_store_explicit(&c->stop_seen, 1, memory_order_relaxed);
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
                if (look && atomic_load_explicit(&c->stop_seen, memory_order_relaxed)) {
                    /* a signal during the step's rounds: the step is abandoned (no row,
                     * frame or counts of it), the run ends after the step before */
                    if (tid == 0)
                        nbep__sim_abandon(sim);
                    quit = true;
                    break;
                }
                if (look && tid == 0) /* the progress within a long step */
                    nbep__sim_progress_within(sim, step, t_min);
                if (round % STALL_ROUNDS == STALL_ROUNDS - 1 &&
                    !(t_min - t_check > STALL_FRACTION * sim->dt)) {
                    if (tid == 0) {
                        nbep_diag_add(sim->diag, __FILE__, __LINE__, STALL_MESSAGE,
                                      (unsigned long long)step, t_min, STALL_FRACTION,
                                      STALL_ROUNDS, "rounds");
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
                if (!c->order_step)
                    t_round = t_min;
                nbep_barrier_wait(bar);
                /* pairs that lock (lockable) that met: their bodies, by thread 0 alone (a body
                 * reaches spheres other threads own), the same decision on every thread of
                 * the crew; the crew's lists only, each reset at this round's react phase (a
                 * thread out of the crew keeps the list of its last round in an earlier step's
                 * crew) */
                size_t locks = 0;
                for (int t = 0; t < crew; t++)
                    locks += c->ws[t].n_lock;
                if (locks) {
                    if (tid == 0)
                        nbep__pred_lock_phase(c, s, crew, sim->dt, t_min - T0, w);
                    nbep_barrier_wait(bar);
                }
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
                        nbep__pred_jam_fail(sim, step, jammed - 1, t_min);
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
                    w->n_settle += nbep__pred_settle_count(c, s, i, sim->dt);
            }
            w->vmax_end = vmax;
            w->amax_end = amax;
            nbep__sim_block_energy(sim, own);
            nbep__sim_frame_overlap(sim, step, tid, own, &c->bar);
            nbep_barrier_wait(&c->bar);
            /* the crew of the next step (pred_ways.c), from the seconds of this one's rounds
             * and update; the others read it past grid_prepare's barriers */
            if (tid == 0 && c->crews)
                nbep__pred_ways_choose_crew(&c->ways, step, way, nbep_now() - t_step);
            if (c->use_grid) /* all threads, from the positions at T_end */
                grid_prepare(c, s, tid, own, T_end, sim->dt, false);
            /* the speed bounds taken above stay bounds: held spheres only slow down */
            (void)nbep__pred_settle_phases(sim, c, own, w);
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

/* Whether the run carries lasting state that no frame holds (nbep_contact_rec): the TC clocks
 * (e < 1, physics.tc > 0) or settling (e < 1 under accelerations), and with them the contacts
 * that hold spheres. An elastic run finds its contacts again from one plane a sphere (an
 * elastic sphere is never held: its bounces stay). */
static bool pred_keeps_contacts(const nbep_scene *sc, const nbep_state *st)
{
    const pred_plan p = plan_of(sc, st, 1, 0);
    return p.tc_model || p.settle_model; /* pred_create's t_last and settle */
}

/* settle_speed over the spheres, where the run settles (pred_create's settle) */
static bool pred_settle_speeds(const nbep_scene *sc, double *lo, double *hi, unsigned *steps)
{
    if (!plan_of(sc, &sc->state, 1, 0).settle_model)
        return false;
    *steps = SETTLE_STEPS;
    *lo = INFINITY;
    *hi = 0.0;
    for (size_t i = 0; i < sc->state.n; i++) {
        const double v = settle_speed(&sc->state, i, sc->dt);
        *lo = fmin(*lo, v);
        *hi = fmax(*hi, v);
    }
    return sc->state.n > 0;
}

_Static_assert(sizeof(nbep_vec3) == 3 * sizeof(double), "a record's vectors are nbep_vec3's");

/* At a frame (pred_export's moment): spheres [lo, hi)'s lasting state. A support's response
 * count is kept as whether it has changed since the support took the load: a resumed run
 * starts every count at 0 (pred_import). */
static void pred_contacts(const void *p, size_t lo, size_t hi, nbep_contact_rec *out)
{
    const pred_ctx *c = p;
    for (size_t i = lo; i < hi; i++) {
        nbep_contact_rec *x = &out[i - lo];
        *x = (nbep_contact_rec){0};
        if (c->t_last && c->t_last[i] > -INFINITY) {
            x->t_last = c->t_last[i];
            x->has_last = 1;
        }
        for (int f = 0; f < CAGE_FACES; f++) {
            const face_met *m = c->face ? &c->face[i * CAGE_FACES + f] : NULL;
            x->face_who[f] = INT32_MIN;
            if (!m || m->t == -INFINITY) /* none (yet) */
                continue;
            x->face_t[f] = m->t;
            memcpy(x->face_n[f], &m->n, sizeof x->face_n[f]);
            memcpy(x->face_p[f], &m->p, sizeof x->face_p[f]);
            x->face_who[f] = m->who;
        }
        if (c->rest) {
            const rest_set *r = &c->rest[i];
            memcpy(x->aeff, &c->aeff[i], sizeof x->aeff);
            x->rest_n = r->n;
            x->rest_still = r->still;
            for (int k = 0; k < r->n; k++) {
                x->rest_who[k] = r->who[k];
                x->rest_current[k] = r->who[k] < 0 && r->ver[k] == c->ver[-1 - r->who[k]];
            }
        }
        if (c->settle) {
            x->peak2 = c->settle[i].peak2;
            x->slow = c->settle[i].slow;
        }
    }
}

/* Sphere i's lasting state from a file's record: the inverse of pred_contacts, counts at 0. A
 * support that had changed gets a count no response reaches, so it stays changed. */
static void import_contacts(pred_ctx *c, size_t i, const nbep_contact_rec *x)
{
    if (c->t_last)
        c->t_last[i] = x->has_last ? x->t_last : -INFINITY;
    for (int f = 0; c->face && f < CAGE_FACES; f++) {
        face_met *m = &c->face[i * CAGE_FACES + f];
        *m = (face_met){.t = -INFINITY, .who = INT32_MIN};
        if (x->face_who[f] == INT32_MIN)
            continue;
        m->t = x->face_t[f];
        memcpy(&m->n, x->face_n[f], sizeof m->n);
        memcpy(&m->p, x->face_p[f], sizeof m->p);
        m->who = x->face_who[f];
    }
    if (c->rest) {
        rest_set *r = &c->rest[i];
        *r = (rest_set){.n = x->rest_n < NBEP_CONTACT_MAX ? x->rest_n : NBEP_CONTACT_MAX,
                        .still = x->rest_still != 0};
        for (int k = 0; k < r->n; k++) {
            r->who[k] = x->rest_who[k];
            r->ver[k] = r->who[k] >= 0 || x->rest_current[k] ? 0 : UINT64_MAX;
        }
        memcpy(&c->aeff[i], x->aeff, sizeof c->aeff[i]);
    }
    if (c->settle)
        c->settle[i] = (settle_rec){.peak2 = x->peak2, .slow = x->slow};
}

/* A resumed run starts with every response count at 0, so the saved events are stored with
 * counts 0: fresh exactly where they were fresh when saved. */
static void pred_import(void *p, const nbep_resume *r)
{
    pred_ctx *c = p;
    for (size_t i = 0; i < r->n; i++) {
        if (r->contacts) {
            import_contacts(c, i, &r->contacts[i]);
        } else if (c->rest) { /* NULL: nothing accelerates, nothing rests (a file says -1) */
            /* A file without the lasting state (an elastic run's, or one made before
             * 2026-11-30) gives back one resting plane per sphere; other contacts (a second
             * plane, held spheres) are found again by zero-time events in its first step. */
            c->rest[i] = (rest_set){.n = 0};
            if (r->rest[i] >= 0) {
                c->rest[i].who[0] = r->rest[i];
                c->rest[i].n = 1;
            }
            nbep_vec3 v = c->st->vel[i]; /* the frame's (nbep_resume_apply) */
            nbep__pred_rest_solve(c, c->st, i, &c->rest[i], &v, &c->aeff[i], 0.0, false,
                                  c->hold_slow);
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
    else if (p.cells && p.slabs >= 2 && p.scheduled)
        snprintf(buf, len,
                 "the event loop through the optimistic scheduler on %d slabs (NBEP_SCHEDULED, "
                 "NBEP_SLABS), on %d of them, each taking its slabs in turns; all %d share the "
                 "rebuilds, the update and the energy",
                 p.slabs, nt < p.slabs ? nt : p.slabs, nt);
    else if (p.cells && p.slabs >= 2)
        snprintf(buf, len,
                 "the event loop on one, its calendar cut into %d slabs (NBEP_SLABS); all %d "
                 "share the rebuilds, the update and the energy",
                 p.slabs, nt);
    else if (p.cells)
        snprintf(buf, len,
                 "the event loop on one (something accelerates: its contacts need the events in "
                 "order); all %d share the rebuilds, the update and the energy",
                 nt);
    else if (p.crews)
        snprintf(buf, len, "each step's rounds on %s, whichever the run measures fastest",
                 p.ways.n > 2 ? "1, 2 or all" : "1 or 2");
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
                                         .keeps_contacts = pred_keeps_contacts,
                                         .export_contacts = pred_contacts,
                                         .settle_speeds = pred_settle_speeds,
                                         .import_events = pred_import};
