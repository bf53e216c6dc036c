/* run.neighbors = "cells": the predictive algorithm's side of the in-step event loop
 * (evloop.h): the loop's callbacks (predict from a list, react, fly, wrap, save and restore
 * for the team loop), the pair loop of a scene in free flight, and the steps (rebuilds, the
 * loop on one thread or a team, the update). */
#include "pred_impl.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/cascade.h"

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
 * a step (as for rounds, STALL_ROUNDS, pred_impl.h): otherwise the loop is a cascade that does
 * not resolve, or one that creeps on by round-off. */
#define STALL_EVENTS 1000000u

/* A rebuild's predictions (about the cost of n/2 collisions: 0.5 s of the first step's second
 * of set-up for 2 million spheres on one thread here) are made this many spheres of a
 * thread's range at a time, each after a look at the stop signal: a few milliseconds' worth,
 * so a job's SIGTERM during the first predictions of tens of millions of spheres, seconds,
 * ends the run at once. A prediction reads only its own sphere's list, so the chunks predict
 * what one call over the range does. */
#define PREDICT_LOOK 16384u

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
    return nbep__pred_predict_some(x->c, x->s, i, 0, 0, true, x->T0, x->w, x->cnt);
}

static void cells_pairs(void *u, uint32_t i, const uint32_t *js, size_t m, bool images,
                        nbep_event *best)
{
    cells_user *x = u;
    nbep__pred_keep_pairs(best, x->c, x->s, i, effective_acc(x->c, x->s, i), js, m, images,
                          x->T0, x->w);
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
        /* the closing pairs that may hit, kept without a branch (each written, kept by the
         * count's step; the lowest bound's place by selects): half a fluid's pairs close and
         * which half is a coin toss, and as branches this loop took a tenth of the time at
         * phi = 0.50 (perf; 0.90 of the time without them, paired, the same bits) */
        double first_lb = INFINITY;
        for (size_t k = k0; k < k1; k++) {
            const double lb = lbs[k - k0];
            tr[n] = (pair_try){lb, (uint32_t)k};
            first = lb < first_lb ? n : first;
            first_lb = lb < first_lb ? lb : first_lb;
            n += lb < INFINITY;
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
    if (nbep__pred_held_on_changed(x->c, j))
        nbep__pred_let_go(x->c, x->s, j, x->sc->dt, x->t_local, x->w);
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
    nbep__pred_react(x->c, x->s, x->sc, ev->time, x->t_local, lo, hi, ev, w, x->cnt, x->mx);
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

/* Sphere i's list expires at absolute time t in a periodic box: it is brought to t, and
 * wrapped (image counted) when its centre is then outside the box on a periodic axis, so that
 * its position stays in its cell (cells.h); its flight at t (cells_flight's, bit for bit: a
 * sphere brought to t flies for no time). Brought to t even inside: a pair near a periodic face
 * is taken at the image nearest by the stored positions (pair_bounds_with, neighbour_shift),
 * which a sphere flying without a collision left behind by as much as it flew; brought at each
 * expiry, they stay within a list's reach of the spheres' own (until 2026-11-30 only a sphere
 * that left the box was: within a step of a period's flight, a pair was taken at another image
 * and passed through, tests/test_periodic.c). Not noted for settling (advance_to's
 * settle_note): a speed at an expiry is no event's. */
static void cells_wrap(void *u, uint32_t i, double t, nbep_vec3 *p, nbep_vec3 *v, nbep_vec3 *a)
{
    const cells_user *x = u;
    cells_flight(u, i, t, p, v, a);
    /* a non-finite position stays as it is (the wrap leaves it too) */
    if (!(isfinite(p->x) && isfinite(p->y) && isfinite(p->z)))
        return;
    x->s->pos[i] = *p;
    x->s->vel[i] = *v;
    x->c->tau[i] = t - x->T0;
    if (!nbep_periodic_inside(&x->c->pb, *p)) {
        nbep_periodic_wrap(&x->c->pb, &x->s->pos[i], &x->s->image[3 * (size_t)i]);
        *p = x->s->pos[i];
    }
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

/* What the scheduled loop keeps of a context's counts before each event (nbep_evloop_mark):
 * the counters, the overlaps' maxima and how many terms its sums' journal held. */
typedef struct cells_mark {
    uint64_t c[NBEP_COUNTER_COUNT];
    double overlap, overlap_rel;
    uint64_t terms;
} cells_mark;
_Static_assert(sizeof(cells_mark) <= sizeof(nbep_evloop_mark),
               "a context's mark fits the engine's");

static bool cells_mark_counts(const void *u, nbep_evloop_mark *m)
{
    const cells_user *x = u;
    const nbep_sum_journal *j = x->mx->jr;
    cells_mark k = {.overlap = x->mx->overlap,
                    .overlap_rel = x->mx->overlap_rel,
                    .terms = j ? j->n : 0};
    memcpy(k.c, x->cnt->c, sizeof k.c);
    memcpy(m, &k, sizeof k);
    return !j || !j->oom;
}

/* A rollback's: the counts as they were at m, the sums' terms added since taken out again
 * (newest first; each undone exactly, the sums being exact) */
static void cells_back(void *u, const nbep_evloop_mark *m)
{
    cells_user *x = u;
    cells_mark k;
    memcpy(&k, m, sizeof k);
    memcpy(x->cnt->c, k.c, sizeof k.c);
    x->mx->overlap = k.overlap;
    x->mx->overlap_rel = k.overlap_rel;
    nbep_sum_journal *j = x->mx->jr;
    assert(!j || j->n >= k.terms); /* (marks are of this window's journal) */
    if (j)
        nbep__pred_sums_back(j, k.terms);
}

/* A window's end: every event so far stands, none of its terms will be taken out */
static void cells_settle(void *u)
{
    const cells_user *x = u;
    if (x->mx->jr)
        x->mx->jr->n = 0;
}

#define CELLS_OPS(pairs_fn)                                                                  \
    {.planes = cells_planes, .pairs = (pairs_fn), .fresh = cells_fresh, .react = cells_react,   \
     .flight = cells_flight, .wrap = cells_wrap, .save = cells_save, .restore = cells_restore,   \
     .clear = cells_clear, .merge = cells_merge, .prefetch = cells_prefetch,                    \
     .mark = cells_mark_counts, .back = cells_back, .settle = cells_settle}
static const nbep_evloop_ops cells_ops = CELLS_OPS(cells_pairs);
static const nbep_evloop_ops cells_ops_free = CELLS_OPS(cells_pairs_free);
#undef CELLS_OPS

/* The scheduled loop's world of one slab (NBEP_SCHEDULED on NBEP_SLABS: evloop.h,
 * nbep_evloop_set_worlds): the context's structs copied at each call, their motion arrays (as
 * cells_save keeps them) the world's own, its counts and sums apart (merged into thread 0's at
 * the call's end, exactly), its sums' journal its own. Its workspace is a copy of thread 0's
 * but for its scratch (the reactions' list of changed spheres, the quartic's workspace), which
 * is the thread's that runs it (slab k on thread k % slab_crew), shared by that thread's slabs,
 * which take turns there: a reaction writes its scratch arrays before it reads them. */
typedef struct cells_world {
    pred_ctx c;
    nbep_state s;
    thread_ws w;
    nbep_counters cnt;
    nbep_thread_max mx;
    cells_user u;
    nbep_vec3 *pos, *vel;
    int32_t *image;
    double *tau, *t_last;
    uint64_t *ver;
    jam_count *jam;
    nbep_xsum *wall;
    nbep_sum_journal jr;
} cells_world;

void nbep__pred_cells_worlds_free(pred_ctx *c)
{
    for (int k = 0; k < c->n_worlds; k++) {
        cells_world *a = &c->worlds[k];
        free(a->pos);
        free(a->vel);
        free(a->image);
        free(a->tau);
        free(a->t_last);
        free(a->ver);
        free(a->jam);
        free(a->wall);
        free(a->jr.term);
    }
    nbep_free_aligned(c->worlds);
    free(c->world_u);
    free((void *)c->world_ver);
    c->worlds = NULL;
    c->world_u = NULL;
    c->world_ver = NULL;
    c->n_worlds = 0;
}

/* Thread 0, before a scheduled call on slabs: the worlds (made at the first) set to the call's
 * context u and given to the engine. False without memory (the worlds then freed). */
static bool cells_worlds(pred_ctx *c, const cells_user *u, int slabs, int crew)
{
    const size_t n = u->s->n, np = u->s->n_planes;
    if (!c->worlds) {
        c->worlds = nbep_alloc_aligned((size_t)slabs, sizeof *c->worlds);
        c->world_u = malloc((size_t)slabs * sizeof *c->world_u);
        c->world_ver = malloc((size_t)slabs * sizeof *c->world_ver);
        if (c->worlds) { /* (zeroed, so that a part made frees what it holds) */
            memset(c->worlds, 0, (size_t)slabs * sizeof *c->worlds);
            c->n_worlds = slabs;
        }
        if (!c->worlds || !c->world_u || !c->world_ver) {
            nbep__pred_cells_worlds_free(c);
            return false;
        }
        bool ok = true;
        for (int k = 0; k < slabs; k++) {
            cells_world *a = &c->worlds[k];
            a->pos = malloc(n * sizeof *a->pos);
            a->vel = malloc(n * sizeof *a->vel);
            a->image = malloc(3 * n * sizeof *a->image);
            a->tau = malloc(n * sizeof *a->tau);
            a->ver = malloc(n * sizeof *a->ver);
            a->t_last = c->t_last ? malloc(n * sizeof *a->t_last) : NULL;
            a->jam = c->jam ? malloc(n * sizeof *a->jam) : NULL;
            a->wall = calloc(np + 1, sizeof *a->wall);
            ok = ok && a->pos && a->vel && a->image && a->tau && a->ver && a->wall &&
                 (!c->t_last || a->t_last) && (!c->jam || a->jam);
        }
        if (!ok) {
            nbep__pred_cells_worlds_free(c);
            return false;
        }
    }
    for (int k = 0; k < slabs; k++) {
        cells_world *a = &c->worlds[k];
        memcpy(&a->c, c, sizeof a->c);
        a->s = *u->s;
        /* thread 0's step (jam_step), with the scratch of the thread that runs it (a helper's
         * own fields are its own to write meanwhile: it set its jam_step at its step's start,
         * which thread 0 may have passed first) */
        a->w = *u->w;
        a->w.fired = c->ws[k % crew].fired;
        a->w.pws = c->ws[k % crew].pws;
        a->s.pos = a->pos;
        a->s.vel = a->vel;
        a->s.image = a->image;
        a->c.tau = a->tau;
        a->c.ver = a->ver;
        a->c.t_last = a->t_last;
        a->c.jam = a->jam;
        a->mx = (nbep_thread_max){.wall = a->wall, .jr = &a->jr};
        a->jr.n = 0;
        a->jr.oom = false;
        a->u = *u;
        a->u.c = &a->c;
        a->u.s = &a->s;
        a->u.w = &a->w;
        a->u.cnt = &a->cnt;
        a->u.mx = &a->mx;
        c->world_u[k] = &a->u;
        c->world_ver[k] = a->ver;
    }
    nbep_evloop_set_worlds(c->ev, c->world_u, c->world_ver);
    return true;
}

/* The events of step `step` before t_end, every thread: those of way `way` (a probe when
 * `probe`: the step's first part) run them, thread 0 leading, through the team loop's call
 * `call` (unlike every other part's) where the way has more than one thread. Thread 0 then
 * notes the way's seconds per event (pred_ways.c), and sets *failed (the part's own flag: the
 * threads that sit out the second part read the first's while thread 0 runs the second), on
 * failure with the run's status and message. */
static void cells_part(nbep_sim *sim, pred_ctx *c, int tid, cells_user *u, void *const *us,
                       const nbep_evloop_ops *ops, int way, bool probe, uint64_t call,
                       double t_end, nbep_evloop_stall *stall, uint64_t step, bool *failed)
{
    /* (the scheduled loop's slabs run on threads of their own count) */
    const int crew = c->scheduled && c->slabs > 1 ? c->slab_crew : c->ways.crew[way];
    if (tid >= 1 && tid < crew)
        nbep_evloop_help(c->ev, ops, u, us, tid, call);
    if (tid != 0)
        return;
    nbep_evloop_tally tally = {0};
    double t_stuck = 0.0;
    uint32_t jammed;
    const double t_loop = nbep_now();
    /* the scheduled loop's sums record their terms while it runs (a rollback takes them out) */
    u->mx->jr = c->scheduled ? &c->jr : NULL;
    if (c->scheduled && c->slabs > 1 && !cells_worlds(c, u, c->slabs, crew)) {
        if (crew > 1) /* (the helpers are waiting for the call) */
            nbep_evloop_release(c->ev, call);
        nbep_diag_add(sim->diag, __FILE__, __LINE__,
                      "nbep: step %llu: no memory for the scheduled loop's worlds on slabs "
                      "(NBEP_SCHEDULED, a setting for measuring: run without it); stopping",
                      (unsigned long long)step);
        sim->status = NBEP_ENOMEM;
        *failed = true;
        return;
    }
    const bool ran = crew > 1 ? nbep_evloop_run_lead(c->ev, ops, u, us, crew, call, t_end, stall,
                                                     &tally, &t_stuck)
                              : nbep_evloop_run(c->ev, ops, u, t_end, stall, &tally, &t_stuck);
    u->mx->jr = NULL;
    /* (a term its journal could not record, at the call's last event too: this step fails) */
    bool no_journal = c->scheduled && c->jr.oom;
    for (int k = 0; k < c->n_worlds; k++)
        no_journal |= c->worlds[k].jr.oom;
    const bool fail = !ran || no_journal;
    *failed = fail;
    if (c->team && probe)
        nbep__pred_ways_note(&c->ways, way, true, tally.events, nbep_now() - t_loop);
    else if (c->team)
        nbep__pred_ways_choose(&c->ways, step, way, tally.events, nbep_now() - t_loop);
    u->cnt->c[NBEP_COUNTER_CHECKS] += tally.events;
    u->cnt->c[NBEP_COUNTER_AHEAD] += tally.ahead;
    u->cnt->c[NBEP_COUNTER_UNDONE] += tally.undone;
    if (fail && stall->stopped) {
        /* a signal during a step's events: the step is abandoned (its rows, frame and counts
         * never made), the run ends after the step before (nbep_sim_run) */
        nbep__sim_abandon(sim);
    } else if (no_journal) {
        nbep_diag_add(sim->diag, __FILE__, __LINE__,
                      "nbep: step %llu: no memory for the scheduled loop's record of the step's "
                      "sums (NBEP_SCHEDULED, a setting for measuring: run without it); stopping",
                      (unsigned long long)step);
        sim->status = NBEP_ENOMEM;
    } else if (fail && nbep_evloop_failed(c->ev)) {
        nbep_diag_add(sim->diag, __FILE__, __LINE__,
                      "nbep: step %llu: no memory for the neighbour lists or the event "
                      "calendars; stopping",
                      (unsigned long long)step);
        sim->status = NBEP_ENOMEM;
    } else if (fail && (jammed = cells_jammed(c, sim->st.n, step)) != 0) {
        nbep__pred_jam_fail(sim, step, jammed - 1, t_stuck);
    } else if (fail && nbep_evloop_too_deep(c->ev)) {
        nbep_diag_add(sim->diag, __FILE__, __LINE__,
                      "nbep: step %llu: the events at t = %.17g are a cascade at one time "
                      "deeper than the %d levels the scheduled loop's stamps hold "
                      "(NBEP_SCHEDULED, a setting for measuring: run without it); stopping",
                      (unsigned long long)step, t_stuck, NBEP_CASCADE_DEPTH);
        sim->status = NBEP_ENUMERIC;
    } else if (fail) {
        nbep_diag_add(sim->diag, __FILE__, __LINE__, STALL_MESSAGE, (unsigned long long)step,
                      t_stuck, STALL_FRACTION, STALL_EVENTS, "events");
        sim->status = NBEP_ENUMERIC;
    }
}

/* The step a loop's look (nbep_evloop_stall) is in, for the progress within it. */
typedef struct cells_look {
    nbep_sim *sim;
    uint64_t step;
} cells_look;

/* Thread 0 (the loop's, or the team's leader), at an event at time t of a look's step. */
static void cells_on_look(void *ctx, double t)
{
    const cells_look *l = ctx;
    nbep__sim_progress_within(l->sim, l->step, t);
}

/* The steps of the cells mode, inside pred_run's parallel region. Thread 0 runs each step's
 * event loop, with threads 1.. in a team where the scene allows it (c->team, pred_ways.c); all
 * threads share the rebuilds, the update to the step's end and the energy. A step that probes
 * another way runs its events in two parts (cells_part).
 * A rebuild (cells from positions, every slot predicted afresh: about the cost of n/2
 * collisions) happens at the first step and after every step that writes a frame to a file in
 * step with output.every, so that a run resumed from such a frame starts from exactly the state
 * this run continues from (bit-for-bit resume): the cell membership and the moments at which
 * slots were predicted depend on the run's history, the rebuild makes them depend only on the
 * frame. */
void nbep__pred_cells_steps(nbep_sim *sim, pred_ctx *c, int tid, nbep_range own, thread_ws *w)
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
            for (size_t lo = own.lo; lo < own.hi; lo += PREDICT_LOOK) {
                /* relaxed, as every look at it: the handler passes no other data */
                if (nbep_sim_stop_status(sim->opt.stop_signal) != NBEP_OK) {
                    atomic_store_explicit(&c->stop_seen, 1, memory_order_relaxed);
                    break;
                }
                nbep_evloop_predict(c->ev, ops, &u, lo,
                                    own.hi - lo > PREDICT_LOOK ? lo + PREDICT_LOOK : own.hi,
                                    u.T0);
            }
            u.cnt->c[NBEP_COUNTER_CHECKS] += own.hi - own.lo;
            nbep_barrier_wait(&c->bar);
            /* a signal among them: the step is abandoned, as a signal among its events
             * abandons it (cells_part), before any event (the spheres as the step before left
             * them, wrapped as its frame has them); the run ends after the step before, which
             * at the first step is step 0. relaxed: the barrier above ordered every store of
             * stop_seen, and none comes until the run ends, so all threads leave or none */
            if (atomic_load_explicit(&c->stop_seen, memory_order_relaxed)) {
                if (tid == 0 && step == sim->step_first)
                    nbep__sim_setup_done(sim);
                if (tid == 0)
                    nbep__sim_abandon(sim);
                return;
            }
            if (tid == 0) {
                nbep_evloop_schedule(c->ev, u.T0);
                if (step == sim->step_first) /* SPEC: first predictions are set-up time */
                    nbep__sim_setup_done(sim);
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
        /* the step's events, on the threads of its way; a probe of another way first runs
         * those of the step's first part (pred_ways.c), behind a barrier: its threads have
         * left the team loop before the rest's enter it */
        cells_look look = {sim, step};
        nbep_evloop_stall stall = NBEP_EVLOOP_STALL(STALL_EVENTS, STALL_FRACTION * sim->dt,
                                                    sim->opt.stop_signal, cells_on_look, &look);
        const int probe = c->ways.probe[step & 1];
        if (probe >= 0) {
            cells_part(sim, c, tid, &u, us, ops, probe, true, 2 * step,
                       u.T0 + PRED_WAYS_PART * sim->dt, &stall, step, &c->part_failed);
            nbep_barrier_wait(&c->bar);
            if (c->part_failed) /* written by thread 0 before the barrier */
                return;
        }
        cells_part(sim, c, tid, &u, us, ops, c->ways.way[step & 1], false, 2 * step + 1, T_end,
                   &stall, step, &c->ev_failed);
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
                w->n_settle += nbep__pred_settle_count(c, s, i, sim->dt);
        }
        if (c->refit)
            nbep_grid_bounds(s->pos, own.lo, own.hi, &w->grid_lo, &w->grid_hi);
        nbep__sim_block_energy(sim, own);
        nbep__sim_frame_overlap(sim, step, tid, own, &c->bar);
        nbep_barrier_wait(&c->bar);
        /* spheres held by settling move no more: every slot is predicted again (a rebuild) */
        const bool settled = nbep__pred_settle_phases(sim, c, own, w);
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
