/* The cells engine: see evloop.h. Its one-thread loop is here, its team loop in
 * evloop_team.c, and what they share in evloop_impl.h. */
#include "evloop_impl.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/predict.h"

/* How far past contact distance plus skin a list still reaches: it covers the roundings of the
 * expiry time, of the centres' distance and of locating a centre in the cells, which are laid
 * out for the cutoff (cells.h). An expiry time carries the rounding of an absolute time (eps T,
 * with T the run's time in any unit); a sphere at speed v strays eps T v past half the skin by
 * it, below 1e-6 of the contact distance for any run shorter than 1e9 times the time a sphere
 * takes to fly its own diameter. */
#define CUT_SLACK 1e-6

/* A look at each event once handled (w: what it found and changed; ev: its slot):
 * tests/bench/bench_parallelism.c compiles its own copy of this file that follows what every
 * event reads and writes; a build of nbep has nothing here. */
#ifndef NBEP_EVLOOP_HANDLED_HOOK
#define NBEP_EVLOOP_HANDLED_HOOK(e, w, ev) ((void)0)
#endif

/* A look at each prediction: the time found (raw), the time kept in the slot (kept) and now
 * (t); tests/test_late_roots.c counts the late roots and checks that none is kept behind now
 * (nbep_feq_not_before); a build of nbep has nothing here. */
#ifndef NBEP_EVLOOP_PREDICTED_HOOK
#define NBEP_EVLOOP_PREDICTED_HOOK(raw, kept, t) ((void)(raw), (void)(kept), (void)(t))
#endif

/* Whether the walk of sphere i's list expiry at time t runs out of memory as though its room
 * could not grow: tests/test_team_faults.c compiles its own copy of this file that makes every
 * walk past a time fail, so that the loops' way out of a failed walk is tested; a build of nbep
 * has nothing here. */
/* A test may look at each event before it is handled, with the callbacks and their context
 * (test_world_copy: the physics run on a world of copies beside the run) */
#ifndef NBEP_EVLOOP_BEFORE_HOOK
#define NBEP_EVLOOP_BEFORE_HOOK(e, ops, u, i, ev) ((void)0)
#endif
/* A test may act after each event of the one-thread loop is committed, between events (the
 * calendar holding exactly what is to come: test_evloop_rollback undoes events there) */
#ifndef NBEP_EVLOOP_COMMITTED_HOOK
#define NBEP_EVLOOP_COMMITTED_HOOK(e, ops, u) ((void)0)
#endif
/* A test may take an expiry's commit over (test_evloop_undo: applied, undone, compared with
 * what was, applied again) */
#ifndef NBEP_EVLOOP_APPLY
#define NBEP_EVLOOP_APPLY(e, w) apply(e, w)
#endif
#ifndef NBEP_EVLOOP_OOM_HOOK
#define NBEP_EVLOOP_OOM_HOOK(i, t) false
#endif

/* The room a walk's workspace starts with, in lists' members, and a look at a walk as it has
 * made room for i's old list of m members, from cap0: tests/test_evloop_lists.c compiles its
 * own copy that starts with room for 2, so that its walks grow the room by more than one
 * doubling, and checks each time that the list fits; a build of nbep has nothing here. */
#ifndef NBEP_EVLOOP_WS_CAP0
#define NBEP_EVLOOP_WS_CAP0 64
#endif
#ifndef NBEP_EVLOOP_WALK_HOOK
#define NBEP_EVLOOP_WALK_HOOK(w, m, cap0) ((void)0)
#endif

/* A walk's workspace's first room: lists' members, and changed cells */
#define WS_CHANGED0 8

static void ws_fini(evl_ws *w);

static bool ws_init(evl_ws *w)
{
    w->cap = NBEP_EVLOOP_WS_CAP0;
    w->near = malloc(w->cap * sizeof *w->near);
    w->was = malloc(w->cap * sizeof *w->was);
    w->kept = malloc(w->cap * sizeof *w->kept);
    w->gain = malloc(w->cap * sizeof *w->gain);
    w->chg_cap = WS_CHANGED0;
    w->changed = malloc(w->chg_cap * sizeof *w->changed);
    return w->near && w->was && w->kept && w->gain && w->changed;
}

bool nbep__evloop_ws_init(evl_ws *w)
{
    return ws_init(w);
}

void nbep__evloop_ws_fini(evl_ws *w)
{
    ws_fini(w);
}

/* The bytes ws_init allocates (nbep_evloop_bytes) */
static size_t ws_bytes(void)
{
    const evl_ws *w = NULL; /* for element sizes only: sizeof does not evaluate */
    return NBEP_EVLOOP_WS_CAP0 * (sizeof *w->near + sizeof *w->was + sizeof *w->kept +
                                  sizeof *w->gain) +
           WS_CHANGED0 * sizeof *w->changed;
}

static void ws_fini(evl_ws *w)
{
    free(w->near);
    free(w->was);
    free(w->kept);
    free(w->gain);
    free(w->changed);
}

/* Two events whose spheres' list centres are all farther apart than 2 touch (place_apart:
 * each event's own sphere and the other its slot names, checked themselves, however far
 * a stale slot's other may be) touch nothing in common. An event handled writes the motion
 * and slot of its spheres and reads those of their lists' members; committed, it writes
 * the lists of its spheres' old and new members. Members lie within the cutoff of a list
 * centre, and an expiry's new centre within (1 + LEAD) strays of the old (its sphere
 * strayed up to one, the new centre leads by LEAD), so what an event touches lies within
 * touch = cut + (1 + LEAD) stray of its spheres' centres, and two events whose spheres
 * are more than touch apart touch nothing in common (a written sphere is never read by the
 * other, a written list is never the other's own). Twice that leaves a wide margin for
 * the roundings of the centres (set_near2 adds those of the test's floats). */
static double apart(const nbep_evloop *e)
{
    return 2.0 * (e->cut + (1.0 + NBEP_NBLIST_LEAD) * e->stray);
}

/* The threshold of the team loop's apartness test (near_count), which reads list centres as
 * floats (half the width of doubles: the test over the window was a tenth of the leader's
 * time): the centres are more than apart(e) apart when their float distance's square exceeds
 * near2. A centre is stored as its offset from the low corner of the cells' region (pb: the
 * box, or the spheres' extent without one), clamped to `shore` past a side that is not
 * periodic (which moves no two centres closer: the clamp is a projection), so every
 * coordinate is at most m = side + 2 shore in size (a periodic one is wrapped, and
 * its list centre leads it by less than a stray, within shore). With u the float unit
 * roundoff: each stored coordinate is off by u m, their difference's rounding adds 2 u m, a
 * periodic side's rounding and its subtraction 2 u m more, and where the nearest way round is
 * chosen wrongly (the difference within those errors of half the side) the two ways differ
 * by twice that: 20 u m on an axis at most, 20 sqrt(3) u m in all. The squares and their sum
 * add a relative 5 u, covered by the factor 1 + 8 u; the result is rounded up. */
static void set_near2(nbep_evloop *e)
{
    const double u = 0x1p-24;
    e->shore = e->face_reach;
    double m = 0.0;
    for (int k = 0; k < 3; k++) {
        m = fmax(m, e->pb.len[k] + 2.0 * e->shore);
        e->len_f[k] = (float)e->pb.len[k];
        e->half_f[k] = (float)e->pb.half[k]; /* +inf where not periodic */
    }
    const double far = apart(e) + 20.0 * sqrt(3.0) * u * m;
    e->near2 = nextafterf((float)(far * far * (1.0 + 8.0 * u)), INFINITY);
}

nbep_status nbep_evloop_create(size_t n, nbep_vec3 lo, nbep_vec3 hi, double reach,
                               double skin_frac, const bool *periodic, int team, nbep_feq *q,
                               const uint64_t *ver, nbep_evloop **out, nbep_diag *d)
{
    assert(team >= 1 && team <= NBEP_EVLOOP_TEAM_MAX);
    /* aligned: its fields that the team's threads write start cache lines */
    nbep_evloop *e = nbep_alloc_aligned(1, sizeof *e);
    if (!e)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the cells engine");
    e->n = n;
    e->team = team;
    e->q = q;
    e->ver = ver;
    e->own_slab = -1;
    e->pb = nbep_periodic_make(periodic, lo, hi);
    double skin = nbep_evloop_skin_in(skin_frac, reach, periodic, lo, hi);
    if (reach > 0.0 && !(skin >= NBEP_NBLIST_SKIN_MIN * reach)) {
        nbep_evloop_destroy(&e);
        NBEP_FAIL(d, NBEP_EDECK,
                  "nbep: run.neighbors = \"cells\": a periodic side is shorter than %g (the "
                  "largest diameter %g times %g)",
                  nbep_evloop_min_periodic_side(reach), reach,
                  nbep_evloop_min_periodic_side(1.0));
    }
    skin = fmax(skin, 0.0);
    e->stray = 0.5 * skin;
    e->skin = skin;
    e->rad = NULL;
    e->reach = reach;
    e->cut = (reach + skin) * (1.0 + CUT_SLACK);
    e->face_reach = e->cut + 1.01 * e->stray;
    for (int k = 0; k < 3; k++) {
        e->face_lo[k] = e->pb.axis[k] ? e->pb.lo[k] : -INFINITY;
        e->face_hi[k] = e->pb.axis[k] ? e->pb.lo[k] + e->pb.len[k] : INFINITY;
    }
    /* places are numbered from 1: a mark of 0 is no place's */
    e->head = e->tail = e->fill_at = 1;
    atomic_init(&e->avail, 1);
    atomic_init(&e->next, 1);
    atomic_init(&e->quit, 0);
    for (int t = 0; t < NBEP_EVLOOP_TEAM_MAX; t++) {
        atomic_init(&e->done[t].word, 0);
        for (int k = 0; k < NBEP_EVLOOP_RING; k++)
            atomic_init(&e->ws[t][k].place, 0);
    }
    for (int k = 0; k < 2 * WINDOW; k++)
        e->taken_x[k] = e->taken_y[k] = e->taken_z[k] = INFINITY;
    set_near2(e);
    e->count = nbep_alloc_aligned(n ? n : 1, sizeof *e->count);
    bool ws_ok = true;
    for (int t = 0; t < team; t++)
        for (int k = 0; k < NBEP_EVLOOP_RING; k++)
            ws_ok &= ws_init(&e->ws[t][k]); /* each tried: ws_fini frees what any holds */
    nbep_status st = e->count && ws_ok ? NBEP_OK : NBEP_ENOMEM;
    if (st != NBEP_OK)
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory for the cells engine");
    if (st == NBEP_OK)
        st = nbep_calendar_create(n, &e->cal, d);
    if (st == NBEP_OK)
        st = nbep_cells_init(&e->cells, lo, hi, e->cut, n, periodic, d);
    if (st == NBEP_OK)
        st = nbep_nblist_init(&e->nl, n, d);
    if (st != NBEP_OK) {
        nbep_evloop_destroy(&e);
        return st;
    }
    *out = e;
    return NBEP_OK;
}

nbep_status nbep_evloop_refit(nbep_evloop *e, nbep_vec3 lo, nbep_vec3 hi, nbep_diag *d)
{
    assert(!e->pb.any);
    e->pb = nbep_periodic_make(NULL, lo, hi);
    set_near2(e);
    return nbep_cells_refit(&e->cells, lo, hi, e->cut, d);
}

double nbep_evloop_skin_in(double skin_frac, double reach, const bool *periodic, nbep_vec3 lo,
                           nbep_vec3 hi)
{
    const double len[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    double skin = skin_frac * reach;
    for (int k = 0; periodic && k < 3; k++)
        if (periodic[k])
            skin = fmin(skin, len[k] / (3.0 * (1.0 + CUT_SLACK)) - reach);
    return skin;
}

double nbep_evloop_min_periodic_side(double reach)
{
    return 3.0 * (1.0 + NBEP_NBLIST_SKIN_MIN) * reach * (1.0 + CUT_SLACK);
}

void nbep_evloop_set_radii(nbep_evloop *e, const double *radius)
{
    e->rad = radius;
}

nbep_status nbep_evloop_set_slabs(nbep_evloop *e, int slabs, nbep_diag *d)
{
    assert(e->team == 1 && !e->slabcal);
    if (slabs < 2)
        return NBEP_OK;
    const nbep_status st = nbep_slabcal_create(e->n, slabs, &e->slabcal, d);
    if (st == NBEP_OK) /* the slabs' calendars instead of the one */
        nbep_calendar_destroy(&e->cal);
    return st;
}

void nbep_evloop_destroy(nbep_evloop **e)
{
    if (!e || !*e)
        return;
    nbep_calendar_destroy(&(*e)->cal);
    nbep_slabcal_destroy(&(*e)->slabcal);
    nbep_cells_fini(&(*e)->cells);
    nbep_nblist_fini(&(*e)->nl);
    nbep_free_aligned((*e)->count);
    nbep__evloop_sched_destroy(&(*e)->sched);
    for (int t = 0; t < NBEP_EVLOOP_TEAM_MAX; t++) /* (those never made are zero) */
        for (int k = 0; k < NBEP_EVLOOP_RING; k++)
            ws_fini(&(*e)->ws[t][k]);
    nbep_free_aligned(*e);
    *e = NULL;
}

size_t nbep_evloop_bytes(size_t n, double neighbours, int team, int slabs)
{
    return sizeof(nbep_evloop) + nbep_calendar_bytes(n) + nbep_cells_bytes(n) +
           (slabs >= 2 ? nbep_slabcal_bytes(n, slabs) - nbep_calendar_bytes(n) : 0) +
           nbep_nblist_bytes(n, (size_t)(neighbours * (double)n)) +
           (n ? n : 1) * sizeof(uint32_t) + (size_t)team * NBEP_EVLOOP_RING * ws_bytes();
}

bool nbep_evloop_failed(const nbep_evloop *e)
{
    return e->failed;
}

/* Sphere i and j's cutoff where each pair's own is taken (e->rad): their contact distance plus
 * the skin, plus the slack. No larger than e->cut for any pair (the sums grow with the radii,
 * and e->cut's reach is twice the largest radius), and the same for (i, j) as for (j, i). */
static inline double pair_cut(const nbep_evloop *e, double ri, double rj)
{
    return (ri + rj + e->skin) * (1.0 + CUT_SLACK);
}

/* Calls f(e, i, j, arg) for every sphere j != i whose place is within the cutoff of ci (the
 * pair's own where e->rad is set: pair_cut), from
 * the 27-cell block of cell `cell` (each at its image across periodic faces). Reads the cells
 * only (and the radii, where the pair's own cutoff is taken). A cell of the block whose slab is
 * farther than the cutoff from ci (nbep_cells_gap2; i's farthest one, with the largest radius,
 * where each pair has its own) is
 * skipped, members unread: with cells as wide as the cutoff that is about a quarter of the
 * block, its corners and edges away from ci (the same spheres found in the same order; at
 * phi = 0.30 a collision's L1 misses fell by 5.7 % and its L2 misses by 3.6 %, cachegrind). */
#ifndef NEAR_BATCH /* (test_evloop_lists sets a smaller one, so that its flush runs often) */
#define NEAR_BATCH 64
#endif
static inline void near_centres(const nbep_evloop *e, uint32_t i, nbep_vec3 ci, size_t cell,
                                void (*f)(const nbep_evloop *e, uint32_t i, uint32_t j,
                                          void *arg),
                                void *arg)
{
    const nbep_cells *g = &e->cells;
    nbep_cells_block b;
    nbep_cells_block_of(g, cell, &b);
    const double *rad = e->rad;
    const double ri = rad ? rad[i] : 0.0;
    const double cut_i = rad ? pair_cut(e, ri, 0.5 * e->reach) : e->cut;
    const double cut2 = cut_i * cut_i;
    /* per axis and cell of the block: ci as seen from the cell (moved by its period), and the
     * square of its gap to the cell's slab */
    const double c[3] = {ci.x, ci.y, ci.z};
    double a[3][3], gap2[3][3];
    for (int k = 0; k < 3; k++)
        for (int q = 0; q < b.cnt[k]; q++) {
            a[k][q] = b.per[k][q] ? c[k] - b.per[k][q] * e->pb.len[k] : c[k];
            gap2[k][q] = nbep_cells_gap2(g, k, b.idx[k][q], a[k][q]);
        }
    /* the block's first members and ci as seen from each cell, all requested before any is
     * read: a cell holds one or two members in a fluid, so the walk is mostly these first
     * loads, which then overlap instead of following each other */
    uint32_t first[27];
    nbep_vec3 from[27];
    int nc = 0;
    for (int z = 0; z < b.cnt[2]; z++) {
        if (!(gap2[2][z] < cut2))
            continue;
        for (int y = 0; y < b.cnt[1]; y++) {
            const double gyz = gap2[2][z] + gap2[1][y];
            if (!(gyz < cut2))
                continue;
            const size_t row = (b.idx[2][z] * g->dim[1] + b.idx[1][y]) * g->dim[0];
            for (int x = 0; x < b.cnt[0]; x++) {
                if (!(gyz + gap2[0][x] < cut2))
                    continue;
                const uint32_t j = g->head[row + b.idx[0][x]];
                if (j == NBEP_CELLS_NONE)
                    continue;
                NBEP_PREFETCH(&g->m[j]);
                first[nc] = j;
                from[nc++] = nbep_vec3_make(a[0][x], a[1][y], a[2][z]);
            }
        }
    }
    /* the second members too, found from the first ones' links (requested above, so these
     * loads overlap): otherwise each cell's second member is a miss that waits for its first.
     * Measured (paired resumed runs, one thread, medians): 1.038 times the collisions a second
     * at N = 256000, phi = 0.30, where the members come from memory; 1.000 and 1.002 at
     * N = 32000, phi = 0.30 and 0.50, where they are in the cache (a third member a level
     * further: no better) */
    for (int q = 0; q < nc; q++) {
        const uint32_t j = g->m[first[q]].next;
        if (j != NBEP_CELLS_NONE)
            NBEP_PREFETCH(&g->m[j]);
    }
    /* The members within the cutoff are noted without a branch (each written, kept by the
     * count's step) and passed to f in batches, in the same order: whether a member is in
     * or out is a coin toss the CPU cannot predict, and as a branch it was most of a walk's
     * time (perf, the N = 32000 fluid at phi = 0.30, where a collision has 0.77 expiries) */
    uint32_t near[NEAR_BATCH];
    size_t nn = 0;
    for (int q = 0; q < nc; q++) {
        const nbep_vec3 p = from[q];
        for (uint32_t j = first[q]; j != NBEP_CELLS_NONE; j = g->m[j].next) {
            const nbep_vec3 cj = g->m[j].at;
            const double dx = cj.x - p.x, dy = cj.y - p.y, dz = cj.z - p.z;
            /* the pair's own cutoff in a mixture (one-size scenes pay a test the CPU
             * predicts: 0.984 of the time before it, paired resumed runs of the N = 32000
             * fluid at phi = 0.50, 8 pairs; a second loop would spare them it) */
            const double cut_ij = rad ? pair_cut(e, ri, rad[j]) : cut_i;
            near[nn] = j;
            nn += (dx * dx + dy * dy + dz * dz < cut_ij * cut_ij) & (j != i);
            if (nn == NEAR_BATCH) {
                for (size_t k = 0; k < nn; k++)
                    f(e, i, near[k], arg);
                nn = 0;
            }
        }
    }
    for (size_t k = 0; k < nn; k++)
        f(e, i, near[k], arg);
}

/* near_centres around i's own place (a full rebuild: every place is where it will be) */
static inline void near_own(nbep_evloop *e, uint32_t i,
                            void (*f)(const nbep_evloop *e, uint32_t i, uint32_t j, void *arg))
{
    near_centres(e, i, e->cells.m[i].at, e->cells.m[i].cell, f, NULL);
}

static void count_one(const nbep_evloop *e, uint32_t i, uint32_t j, void *arg)
{
    (void)j;
    (void)arg;
    e->count[i]++; /* the array, not the engine, is written: one thread per i */
}

static void fill_one(const nbep_evloop *e, uint32_t i, uint32_t j, void *arg)
{
    (void)arg;
    /* i's own list only (nbep_nblist_fill: threads fill disjoint spheres' lists) */
    nbep_nblist_fill((nbep_nblist *)&e->nl, i, j);
}

/* Twice the room for a walk's lists. */
static bool grow_ws(evl_ws *w)
{
    size_t cap = 2 * w->cap;
    uint32_t *a = realloc(w->near, cap * sizeof *a);
    if (a)
        w->near = a;
    uint32_t *b = realloc(w->was, cap * sizeof *b);
    if (b)
        w->was = b;
    uint8_t *k = realloc(w->kept, cap * sizeof *k);
    if (k)
        w->kept = k;
    uint8_t *g = realloc(w->gain, cap * sizeof *g);
    if (g)
        w->gain = g;
    if (!a || !b || !k || !g)
        return false;
    w->cap = cap;
    return true;
}

bool nbep__evloop_ws_copy_lists(evl_ws *d, const evl_ws *w)
{
    if (!d->near && d->cap == 0) /* (a zeroed copy: its first growth makes its arrays) */
        d->cap = NBEP_EVLOOP_WS_CAP0 / 2;
    while (!d->near || d->cap < w->n_near || d->cap < w->n_was)
        if (!grow_ws(d))
            return false;
    d->item = w->item;
    d->rebuilt = w->rebuilt;
    d->at = w->at;
    d->at_cell = w->at_cell;
    d->n_near = w->n_near;
    d->n_was = w->n_was;
    memcpy(d->near, w->near, w->n_near * sizeof *w->near);
    memcpy(d->gain, w->gain, w->n_near * sizeof *w->gain);
    memcpy(d->was, w->was, w->n_was * sizeof *w->was);
    memcpy(d->kept, w->kept, w->n_was * sizeof *w->kept);
    return true;
}

void nbep__evloop_ws_copy_fini(evl_ws *d)
{
    ws_fini(d);
    memset(d, 0, sizeof *d);
}

/* A sphere j near i during i's walk: into the new list, marked gained unless i's old list has
 * it (a handful looked through in cache: it is kept). */
static void gather_one(const nbep_evloop *e, uint32_t i, uint32_t j, void *arg)
{
    (void)e;
    (void)i;
    evl_ws *w = arg;
    size_t k = w->n_was; /* its place in the old list (each sphere at most once there): a
                          * pass over the whole list, without the early exit whose branch the
                          * CPU could not predict */
    for (size_t q = 0; q < w->n_was; q++)
        k = w->was[q] == j ? q : k;
    if (k < w->n_was)
        w->kept[k] = 1;
    if (w->n_near == w->cap && !grow_ws(w)) {
        w->oom = true;
        return;
    }
    w->gain[w->n_near] = k == w->n_was;
    w->near[w->n_near++] = j;
}

/* Sphere i's new list around c, found (w->near) but not yet entered: reads the cells and i's
 * list only, so that threads may walk at once (what it changes waits for apply). */
static void walk(const nbep_evloop *e, evl_ws *w, uint32_t i, nbep_vec3 c)
{
    size_t m;
    const uint32_t *old = nbep_nblist_of(&e->nl, i, &m);
    w->oom = false;
    const size_t cap0 = w->cap;
    while (m > w->cap)
        if (!grow_ws(w)) {
            w->oom = true;
            return;
        }
    NBEP_EVLOOP_WALK_HOOK(w, m, cap0);
    (void)cap0;
    for (size_t k = 0; k < m; k++) {
        w->was[k] = old[k];
        w->kept[k] = 0;
    }
    w->n_was = m;
    w->n_near = 0;
    w->at_cell = nbep_cells_locate(&e->cells, c);
    near_centres(e, i, c, w->at_cell, gather_one, w);
}

/* The walk on w entered: its sphere placed at the new centre (in the cell the walk found); it
 * enters the lists of the neighbours it gains and leaves those of the ones it loses; those it
 * keeps (most: it moved by half a skin) are not touched. One thread, no other walking. With
 * u, what undoes it is recorded there (nbep__evloop_apply_undoable); without (a constant
 * NULL: the loops' commits), nothing is. With sp (a constant NULL but for
 * nbep__evloop_apply_part), only the neighbours' lists whose slab sp names is `slab` change:
 * the others' changes go to their slabs as list messages (listmsg.c). */
static inline NBEP_ALWAYS_INLINE void apply_rec(nbep_evloop *e, const evl_ws *w, evl_unlist *u,
                                                const evl_split *sp, int slab)
{
    const uint32_t i = w->item;
    if (u) {
        u->at = e->cells.m[i].at;
        u->cell = e->cells.m[i].cell;
        u->prev = e->cells.prev[i];
        u->n_drop = 0;
        while (u->cap < w->n_was)
            if (!nbep_room_grow((void **)&u->drop_q, &u->cap, u->cap, sizeof *u->drop_q)) {
                e->failed = true;
                return;
            }
    }
    nbep_cells_place(&e->cells, i, w->at, w->at_cell);
    for (size_t k = 0; k < w->n_near && !e->failed; k++)
        if (w->gain[k] && (!sp || sp->near[k] == slab) &&
            !nbep_nblist_append(&e->nl, w->near[k], i))
            e->failed = true;
    for (size_t k = 0; k < w->n_was; k++)
        if (!w->kept[k] && (!sp || sp->was[k] == slab)) { /* lost */
            const uint32_t q = nbep_nblist_drop(&e->nl, w->was[k], i);
            if (u)
                u->drop_q[u->n_drop++] = q;
        }
    if (!nbep_nblist_set(&e->nl, i, w->near, e->failed ? 0 : w->n_near))
        e->failed = true;
}

static void apply(nbep_evloop *e, const evl_ws *w)
{
    apply_rec(e, w, NULL, NULL, 0);
}

void nbep__evloop_apply_undoable(nbep_evloop *e, const evl_ws *w, evl_unlist *u)
{
    assert(w->rebuilt);
    apply_rec(e, w, u, NULL, 0);
}

void nbep__evloop_apply_part(nbep_evloop *e, const evl_ws *w, evl_unlist *u,
                             const evl_split *sp, int slab)
{
    assert(w->rebuilt && sp);
    apply_rec(e, w, u, sp, slab);
}

/* apply_rec's steps undone in the opposite order, each exactly (nblist.h, cells.h): i's own
 * list back (was: i's list when its walk read it, which nothing changed before the commit:
 * the walk's own invariant), i back in the lists it left, each at its place, then out of those
 * it entered (it is their last entry), then its centre and cell back. With sp, the lists of
 * slab `slab` alone, as apply_rec changed them. */
static void unapply_rec(nbep_evloop *e, const evl_ws *w, const evl_unlist *u,
                        const evl_split *sp, int slab)
{
    const uint32_t i = w->item;
    if (e->failed) /* (a commit out of memory may have stopped part way: nothing to undo by;
                    * the run stops) */
        return;
    if (!nbep_nblist_set(&e->nl, i, w->was, w->n_was)) {
        e->failed = true;
        return;
    }
    size_t d = u->n_drop;
    for (size_t k = w->n_was; k-- > 0;)
        if (!w->kept[k] && (!sp || sp->was[k] == slab)) {
            const uint32_t q = u->drop_q[--d];
            if (q != UINT32_MAX && !nbep_nblist_undrop(&e->nl, w->was[k], i, q)) {
                e->failed = true;
                return;
            }
        }
    assert(d == 0);
    for (size_t k = w->n_near; k-- > 0;)
        if (w->gain[k] && (!sp || sp->near[k] == slab))
            nbep_nblist_unappend(&e->nl, w->near[k], i);
    nbep_cells_put_back(&e->cells, i, u->at, u->cell, u->prev);
}

void nbep__evloop_unapply(nbep_evloop *e, const evl_ws *w, const evl_unlist *u)
{
    unapply_rec(e, w, u, NULL, 0);
}

void nbep__evloop_unapply_part(nbep_evloop *e, const evl_ws *w, const evl_unlist *u,
                               const evl_split *sp, int slab)
{
    assert(sp);
    unapply_rec(e, w, u, sp, slab);
}

void nbep__evloop_unlist_fini(evl_unlist *u)
{
    free(u->drop_q);
    *u = (evl_unlist){0};
}

void nbep_evloop_assign(nbep_evloop *e, const nbep_vec3 *pos, size_t lo, size_t hi)
{
    nbep_cells_assign(&e->cells, pos, lo, hi);
}

void nbep_evloop_link(nbep_evloop *e)
{
    nbep_cells_link(&e->cells);
}

void nbep_evloop_count(nbep_evloop *e, size_t lo, size_t hi)
{
    for (size_t i = lo; i < hi; i++) {
        e->count[i] = 0;
        near_own(e, (uint32_t)i, count_one);
    }
}

void nbep_evloop_layout(nbep_evloop *e)
{
    if (!nbep_nblist_layout(&e->nl, e->count))
        e->failed = true;
}

void nbep_evloop_visit_block(const nbep_evloop *e, uint32_t i,
                             void (*visit)(void *u, uint32_t j), void *u)
{
    size_t m;
    const uint32_t *js = nbep_nblist_of(&e->nl, i, &m);
    visit(u, i);
    for (size_t k = 0; k < m; k++)
        visit(u, js[k]);
}

/* Requests the lines of sphere i's list (no effect on results). */
static inline NBEP_ALWAYS_INLINE void prefetch_list(const nbep_evloop *e, uint32_t i)
{
    const nbep_nblist_span sp = e->nl.sp[i];
    if (sp.cnt == 0)
        return;
    const char *a = (const char *)&e->nl.pool[sp.off];
    const char *z = (const char *)&e->nl.pool[sp.off + sp.cnt - 1]; /* the last entry */
    for (; a < z; a += NBEP_CACHELINE)
        NBEP_PREFETCH(a);
    NBEP_PREFETCH(z);
}

/* Requests what the commit of the walk on w writes (no effect on results): the lists of the
 * neighbours it loses and the records of those it gains, while the prediction from the new
 * list runs. In the one thread's loop the commit comes right after it, and each of these was
 * a miss there: nbep_nblist_drop's search of a lost neighbour's list was 5.2 % of the loop's
 * samples, 1.2 % with this (perf, the N = 32000, phi = 0.30 fluid resumed at t = 2 for 6 time
 * units); the loop took 0.990 of the time (scripts/ab-pair.sh, medians of 8 and 10 paired runs;
 * also requesting the old list's members' records before the walk: 0.998 of this, dropped). */
static void prefetch_apply(const nbep_evloop *e, const evl_ws *w)
{
    for (size_t k = 0; k < w->n_was; k++)
        if (!w->kept[k]) {
            const nbep_nblist_span sp = e->nl.sp[w->was[k]];
            NBEP_PREFETCH_W(&e->nl.pool[sp.off]);
            if (sp.cnt > 0)
                NBEP_PREFETCH_W(&e->nl.pool[sp.off + sp.cnt - 1]);
        }
    for (size_t k = 0; k < w->n_near; k++)
        if (w->gain[k])
            NBEP_PREFETCH_W(&e->nl.sp[w->near[k]]);
}

/* Time from now until a centre at d from where its list was built, flying with v and a, is
 * `stray` away: the exact root without acceleration; with one, the root of the bound
 * |d| + |v| s + |a| s^2 / 2, which comes no later (an early rebuild costs a little, a late one
 * would miss a pair). 0 when already there; NBEP_NEVER when it does not move. */
static double stray_time(nbep_vec3 d, nbep_vec3 v, nbep_vec3 a, double stray)
{
    const double vv = nbep_vec3_dot(v, v);
    if (a.x == 0.0 && a.y == 0.0 && a.z == 0.0) {
        if (vv == 0.0)
            return NBEP_NEVER;
        const double b = nbep_vec3_dot(d, v), c = nbep_vec3_dot(d, d) - stray * stray;
        if (!(c < 0.0))
            return 0.0;
        const double root = sqrt(b * b - vv * c); /* c < 0: positive, and at least |b| */
        /* the positive root (-b + root) / vv, in the form that does not cancel */
        return b > 0.0 ? -c / (b + root) : (root - b) / vv;
    }
    const double left = stray - nbep_vec3_norm(d);
    if (!(left > 0.0))
        return 0.0;
    const double sv = sqrt(vv), sa = nbep_vec3_norm(a);
    return 2.0 * left / (sv + sqrt(sv * sv + 2.0 * sa * left));
}

/* Where a list rebuilt for a sphere at p, flying with v and a, is centred. A list lasts while
 * its sphere stays within the stray of the centre, and any centre will do (the list holds
 * the spheres whose centres are within the cutoff of it): one ahead of the sphere along its
 * flight, NBEP_NBLIST_LEAD strays, lets it fly (1 + NBEP_NBLIST_LEAD) strays before the list
 * expires instead of one, if nothing deflects it. Only for straight flight (with an
 * acceleration the expiry is found from a bound that a centre ahead would shorten). Wrapped
 * into a periodic box; stray_time takes the sphere's offset from it the nearest way round. */
static nbep_vec3 list_centre(const nbep_evloop *e, nbep_vec3 p, nbep_vec3 v, nbep_vec3 a)
{
    const double speed = nbep_vec3_norm(v);
    if (!(a.x == 0.0 && a.y == 0.0 && a.z == 0.0) || !(speed > 0.0))
        return p;
    nbep_vec3 c = nbep_vec3_add(p, nbep_vec3_scale(v, NBEP_NBLIST_LEAD * e->stray / speed));
    if (e->pb.any) {
        int32_t img[3] = {0, 0, 0};
        nbep_periodic_wrap(&e->pb, &c, img);
    }
    return c;
}

/* Whether a neighbour of sphere i may have to be taken at an image across a periodic face: its
 * list centre is within the reach of a face on a periodic axis. Every listed j has its centre
 * within the cutoff of i's and its position within the stray of its centre, so when i's centre
 * is farther than cutoff + stray from both faces of every periodic axis, every neighbour
 * flies inside the box near i and its nearest image is itself (a margin of a hundredth of the
 * stray covers the roundings). */
static bool near_face(const nbep_evloop *e, nbep_vec3 ci)
{
    /* six comparisons without a branch (an axis that is not periodic has infinite faces, which
     * no centre is near; a loop over the axes with its tests ran at 28 instructions a call) */
    const double *lo = e->face_lo, *hi = e->face_hi, r = e->face_reach;
    return !((ci.x - lo[0] > r) & (hi[0] - ci.x > r) & (ci.y - lo[1] > r) & (hi[1] - ci.y > r) &
             (ci.z - lo[2] > r) & (hi[2] - ci.z > r));
}

/* Sphere i's slot from scratch at time t: planes, the m spheres js of its list (built around
 * ci), the list's expiry. Writes i's slot only. */
static void predict_with(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                         double t, const uint32_t *js, size_t m, nbep_vec3 ci)
{
    nbep_event best = ops->planes(u, i);
    /* the expiry before the pairs: a pair that comes later cannot win, so its root is skipped
     * (pairs ranks a pair before a plane or an expiry at the same time, as the slot key
     * does; the winner is the one trying the expiry last would give) */
    nbep_vec3 p, v, a;
    ops->flight(u, i, t, &p, &v, &a);
    nbep_vec3 d = nbep_vec3_sub(p, ci);
    if (e->pb.any) /* the nearest way round: the centre may be wrapped while p is not */
        d = nbep_vec3_add(d, nbep_periodic_near_shift(&e->pb, d));
    double t_exit = t + stray_time(d, v, a, e->stray);
    if (t_exit < NBEP_NEVER && (best.kind == NBEP_EVENT_NONE || t_exit < best.time))
        best = (nbep_event){t_exit, 0, NBEP_EVENT_HORIZON, e->ver[i], 0};
    if (m > 0)
        ops->pairs(u, i, js, m, near_face(e, ci), &best);
    if (best.kind == NBEP_EVENT_NONE)
        best = (nbep_event){.time = INFINITY, .kind = NBEP_EVENT_NEVER, .ver_self = e->ver[i]};
    const double raw = best.time;
    best.time = nbep_feq_not_before(best.time, t);
    NBEP_EVLOOP_PREDICTED_HOOK(raw, best.time, t);
    nbep_feq_put(e->q, i, best); /* from scratch: whatever the slot held goes */
}

/* predict_with i's own list and place */
static void predict_one(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                        double t)
{
    size_t m;
    const uint32_t *js = nbep_nblist_of(&e->nl, i, &m);
    predict_with(e, ops, u, i, t, js, m, e->cells.m[i].at);
}

/* The calendar entry of sphere i from its slot, in *c: false when the slot holds nothing to
 * come out (the sphere has no entry). */
static bool slot_entry(const nbep_evloop *e, uint32_t i, nbep_calendar_entry *c)
{
    const nbep_event *ev = nbep_feq_slot(e->q, i);
    *c = (nbep_calendar_entry){ev->time, nbep__evloop_slot_key(i, ev), i};
    return ev->kind == NBEP_EVENT_SPHERE || ev->kind == NBEP_EVENT_PLANE ||
           ev->kind == NBEP_EVENT_HORIZON;
}

/* The slab of sphere i: that of its list centre's cell column across x (the cells are the
 * centres', and a centre moves only at its list's expiry, whose commit enters i anew). */
static int sphere_slab(const nbep_evloop *e, uint32_t i)
{
    return nbep__evloop_slab_in(e, i, nbep_slabcal_slabs(e->slabcal));
}

void nbep__evloop_expiry_span(const nbep_evloop *e, const nbep_evloop_ops *ops, void *u,
                              uint32_t i, double t, int *lo, int *hi)
{
    nbep_vec3 p, v, a;
    ops->flight(u, i, t, &p, &v, &a);
    const nbep_vec3 c = list_centre(e, p, v, a);
    const size_t columns = e->cells.dim[0];
    const long c0 = (long)(e->cells.m[i].cell % columns);
    /* (the centre a hair either way along x: the walk's own flight, wrapped, may round it
     * across a column's side) */
    const double hair = 1e-9 * e->cells.h[0];
    *lo = *hi = 0;
    for (int side = -1; side <= 1; side += 2) {
        nbep_vec3 q = c;
        q.x += side * hair;
        if (e->pb.axis[0]) {
            int32_t img[3] = {0, 0, 0};
            nbep_periodic_wrap(&e->pb, &q, img);
        }
        long d = (long)(nbep_cells_locate(&e->cells, q) % columns) - c0;
        if (e->pb.axis[0] && 2 * d > (long)columns) /* the short way round a periodic x */
            d -= (long)columns;
        else if (e->pb.axis[0] && 2 * d < -(long)columns)
            d += (long)columns;
        *lo = d < *lo ? (int)d : *lo;
        *hi = d > *hi ? (int)d : *hi;
    }
    *lo -= 1;
    *hi += 1;
}

int nbep__evloop_sphere_slab(const nbep_evloop *e, uint32_t i)
{
    return sphere_slab(e, i);
}

void nbep__evloop_predict_own(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                              double t)
{
    predict_one(e, ops, u, i, t);
}

/* Whether sphere i is the engine's to predict and enter: always, but on the scheduled loop's
 * slabs (own_slab), where only the slab's own spheres are. */
static inline NBEP_ALWAYS_INLINE bool owned(const nbep_evloop *e, uint32_t i)
{
    return e->own_slab < 0 || sphere_slab(e, i) == e->own_slab;
}

bool nbep__evloop_owned(const nbep_evloop *e, uint32_t i)
{
    return owned(e, i);
}

/* Whether the engine's world follows sphere j's changes: always, but on the scheduled loop's
 * slabs, where a slab is sent a copy of another slab's sphere only while that sphere's list
 * centre lies in a column beside one of its own (evloop_warp.c, send_copies). Whether it does
 * stays the same within a window: a centre moves into or out of those columns only at an
 * expiry whose span reaches the slab, done at a meeting. */
static inline NBEP_ALWAYS_INLINE bool followed(const nbep_evloop *e, uint32_t j)
{
    if (e->own_slab < 0)
        return true;
    const size_t c = e->cells.m[j].cell % e->cells.dim[0];
    for (int dc = -1; dc <= 1; dc++)
        if (nbep__evloop_column_slab(e, c, dc) == e->own_slab)
            return true;
    return false;
}

/* Entry c set in the calendar, or its item's taken out (set false); with slabs, in its slab's
 * calendar, whose room may have to grow: without memory for it the run fails (e->failed). */
static void enter(nbep_evloop *e, bool set, nbep_calendar_entry c)
{
    if (e->slabcal) {
        if (!set)
            nbep_slabcal_remove(e->slabcal, c.item);
        else if (!nbep_slabcal_set(e->slabcal, sphere_slab(e, c.item), c.item, c.time, c.key))
            e->failed = true;
        return;
    }
    if (set)
        nbep_calendar_set(e->cal, c.item, c.time, c.key);
    else
        nbep_calendar_remove(e->cal, c.item);
}

/* The calendar entry of sphere i from its slot. */
void nbep__evloop_schedule_one(nbep_evloop *e, uint32_t i)
{
    nbep_calendar_entry c;
    const bool set = slot_entry(e, i, &c);
    enter(e, set, c);
}

void nbep_evloop_predict(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, size_t lo,
                         size_t hi, double t)
{
    if (e->failed)
        return;
    for (size_t i = lo; i < hi; i++) /* own lists first: a prediction reads only its own */
        near_own(e, (uint32_t)i, fill_one);
    for (size_t i = lo; i < hi; i++)
        predict_one(e, ops, u, (uint32_t)i, t);
}

void nbep_evloop_schedule(nbep_evloop *e, double t)
{
    if (e->slabcal)
        nbep_slabcal_clear(e->slabcal);
    else
        nbep_calendar_clear(e->cal);
    for (size_t i = 0; i < e->n; i++)
        nbep__evloop_schedule_one(e, (uint32_t)i);
    if (e->slabcal)
        nbep_slabcal_retune(e->slabcal, t);
    else
        nbep_calendar_retune(e->cal, t);
}

/* Entry k of w's calendar entries: sphere i's, from its slot. */
static void note_one(const nbep_evloop *e, evl_ws *w, size_t k, uint32_t i)
{
    nbep_calendar_entry c;
    w->next_set[k] = slot_entry(e, i, &c);
    w->next_item[k] = i;
    w->next_time[k] = c.time;
    w->next_key[k] = c.key;
}

/* The calendar entries that the commit of the event handled on w sets, from the slots its
 * handle wrote (this thread's: read here, they are at hand), in the order the commit sets
 * them: the changed spheres' other than the event's own, then its own. */
static void note_next(const nbep_evloop *e, evl_ws *w)
{
    size_t n = 0;
    for (size_t k = 0; k < w->n_changed && n < NEXT_MAX; k++)
        if (w->changed[k] != w->item && owned(e, w->changed[k]))
            note_one(e, w, n++, w->changed[k]);
    if (n + 1 > NEXT_MAX) { /* more than NEXT_MAX (not with one pair): the slots, at commit */
        w->n_next = NEXT_ALL;
        return;
    }
    note_one(e, w, n, w->item);
    w->n_next = (uint8_t)(n + 1);
}

/* The event in i's slot (ev, at time t), handled on workspace w: the motion and the slots of
 * the spheres it involves are written (an expiry also finds its sphere's new list); the lists,
 * the cells and the calendar wait for commit. A stale slot is predicted again; an expiry wraps
 * its sphere into a periodic box if it left it and predicts it from its new list; a contact
 * reacts and every sphere the reaction changed is predicted again. */
void nbep__evloop_handle(nbep_evloop *e, evl_ws *w, const nbep_evloop_ops *ops, void *u, uint32_t i,
                   const nbep_event *ev, double t, bool commits)
{
    NBEP_EVLOOP_BEFORE_HOOK(e, ops, u, i, ev);
    w->item = i;
    w->rebuilt = w->reacted = w->stop = w->oom = false;
    w->n_changed = 0;
    w->n_next = 0;
    if (ev->kind == NBEP_EVENT_HORIZON) {
        nbep_vec3 p, v, a;
        if (e->pb.any) /* a centre past a periodic face enters through the other */
            ops->wrap(u, i, t, &p, &v, &a);
        else
            ops->flight(u, i, t, &p, &v, &a);
        const nbep_vec3 c = list_centre(e, p, v, a);
        walk(e, w, i, c);
        if (w->oom || NBEP_EVLOOP_OOM_HOOK(i, t)) {
            w->oom = true;
            return;
        }
        w->rebuilt = true;
        w->at = c;
        if (commits) /* the lists it leaves and the records of those it enters */
            prefetch_apply(e, w);
        predict_with(e, ops, u, i, t, w->near, w->n_near, c);
        note_next(e, w);
        NBEP_EVLOOP_HANDLED_HOOK(e, w, ev);
        return;
    }
    /* read if the event is fresh (another slab's sphere's list is its own to read) */
    if (ev->kind == NBEP_EVENT_SPHERE && owned(e, ev->partner))
        prefetch_list(e, ev->partner);
    /* (on slabs, a pair whose other sphere this slab's world no longer follows is stale: its
     * copy there may be older than its last change, and a fresh pair's list centres are
     * within the cutoff, a column, of each other, so its other sphere's is beside this slab) */
    if (ops->fresh(u, i, ev) && (ev->kind != NBEP_EVENT_SPHERE || followed(e, ev->partner))) {
        w->reacted = true;
        const uint32_t *changed;
        const size_t m = ops->react(u, i, ev, &changed, &w->stop);
        if (w->stop) /* the run stops after it: nothing predicted, nothing to commit */
            return;
        /* a copy: the callback's array is the thread's, and a team thread handles several
         * events before they are committed */
        while (m > w->chg_cap) {
            uint32_t *a = realloc(w->changed, 2 * w->chg_cap * sizeof *a);
            if (!a) {
                w->oom = true;
                return;
            }
            w->changed = a;
            w->chg_cap *= 2;
        }
        for (size_t k = 0; k < m; k++)
            w->changed[k] = changed[k];
        w->n_changed = m;
        for (size_t k = 0; k < w->n_changed; k++)
            if (w->changed[k] != i && owned(e, w->changed[k]))
                predict_one(e, ops, u, w->changed[k], t);
    }
    /* in every other case (stale slot, reaction) i looks again from now */
    predict_one(e, ops, u, i, t);
    note_next(e, w);
    NBEP_EVLOOP_HANDLED_HOOK(e, w, ev);
}

/* What handle left waiting: the new list entered (recorded in rec where not NULL: an
 * expiry's commit that may be undone), the changed spheres' calendar entries set. */
static inline NBEP_ALWAYS_INLINE void commit_rec(nbep_evloop *e, const evl_ws *w,
                                                 evl_unlist *rec)
{
    if (w->oom)
        e->failed = true;
    if (w->rebuilt && rec)
        apply_rec(e, w, rec, NULL, 0);
    else if (w->rebuilt)
        NBEP_EVLOOP_APPLY(e, w);
    if (e->failed)
        return;
    if (w->n_next != NEXT_ALL) {
        for (size_t k = 0; k < w->n_next; k++)
            enter(e, w->next_set[k],
                  (nbep_calendar_entry){w->next_time[k], w->next_key[k], w->next_item[k]});
        return;
    }
    for (size_t k = 0; k < w->n_changed; k++)
        if (w->changed[k] != w->item && owned(e, w->changed[k]))
            nbep__evloop_schedule_one(e, w->changed[k]);
    nbep__evloop_schedule_one(e, w->item);
}

void nbep__evloop_commit(nbep_evloop *e, const evl_ws *w)
{
    commit_rec(e, w, NULL);
}

void nbep__evloop_commit_undoable(nbep_evloop *e, const evl_ws *w, evl_unlist *rec)
{
    commit_rec(e, w, rec);
}

/* One event of the one-thread loop: sphere i's, at t. False when the run stops at it (stuck,
 * a reaction's stop, or no memory). */
static inline NBEP_ALWAYS_INLINE bool run_one(nbep_evloop *e, evl_ws *w,
                                              const nbep_evloop_ops *ops, void *u, uint32_t i,
                                              double t, nbep_evloop_stall *stall,
                                              nbep_evloop_tally *tally, double *t_stuck)
{
    const nbep_event ev = *nbep_feq_slot(e->q, i);
    nbep__evloop_prefetch_event(e, i, &ev);
    tally->events++;
    if (!nbep__evloop_advances(stall, t)) {
        *t_stuck = t;
        return false;
    }
    nbep__evloop_handle(e, w, ops, u, i, &ev, t, true);
    nbep__evloop_count_handled(tally, w);
    if (w->stop) {
        *t_stuck = t;
        return false;
    }
    nbep__evloop_commit(e, w);
    NBEP_EVLOOP_COMMITTED_HOOK(e, ops, u);
    return !e->failed;
}

bool nbep_evloop_run(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, double t_end,
                     nbep_evloop_stall *stall, nbep_evloop_tally *tally, double *t_stuck)
{
    if (e->failed) /* a rebuild ran out of memory */
        return false;
    if (e->sched) /* NBEP_SCHEDULED: through the optimistic scheduler (evloop_warp.c) */
        return nbep__evloop_run_scheduled(e, ops, u, 1, 0, t_end, stall, tally, t_stuck);
    evl_ws *w = &e->ws[0][0];
    if (e->slabcal) { /* the slabs' earliest entries merged: the one calendar's order */
        nbep_calendar_entry c;
        while (nbep_slabcal_first(e->slabcal, &c) && c.time < t_end)
            if (!run_one(e, w, ops, u, c.item, c.time, stall, tally, t_stuck))
                return false;
        return true;
    }
    uint32_t i;
    double t;
    while (nbep_calendar_top(e->cal, &i, &t) && t < t_end)
        if (!run_one(e, w, ops, u, i, t, stall, tally, t_stuck))
            return false;
    return true;
}
