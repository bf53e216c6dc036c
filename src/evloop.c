/* The cells engine: see evloop.h. */
#include "evloop.h"

#include <math.h>
#include <stdlib.h>

#include "nbep/calendar.h"
#include "nbep/cells.h"
#include "nbep/nblist.h"
#include "nbep/periodic.h"
#include "nbep/predict.h"

/* How far past contact distance plus skin a list still reaches: it covers the roundings of the
 * expiry time and of the centres' distance. An expiry time carries the rounding of an absolute
 * time (eps T, with T the run's time in any unit); a sphere at speed v strays eps T v past half
 * the skin by it, below 1e-6 of the contact distance for any run shorter than 1e9 times the
 * time a sphere takes to fly its own diameter. */
#define CUT_SLACK 1e-6

struct nbep_evloop {
    size_t n;
    nbep_calendar *cal;   /* owned */
    nbep_cells cells;     /* owned: cells of the list centres, at least `cut` wide; a
                           * member's place (cells.m[i].at) is where i's list was built */
    nbep_nblist nl;       /* owned */
    uint32_t *count;      /* owned, n: list lengths, at a full rebuild */
    /* a rebuild of one list (rebuild_one): near holds the new list, was the old one (n_was
     * entries, kept[k] set for those found again) */
    uint32_t *near, *was; /* owned, room for near_cap each */
    uint8_t *kept;        /* owned, room for near_cap */
    size_t near_cap, n_near, n_was;
    nbep_periodic pb;     /* the box's periodic geometry */
    double cut;           /* the list cutoff: contact distance plus skin, plus slack */
    double stray;         /* half the skin: how far a sphere goes before its list expires */
    double face_reach;    /* cut + stray, and a margin: see near_face */
    bool failed;          /* out of memory for a list: the run stops */
    bool stop;            /* nbep_evloop_stop: the run stops after the current event */
    nbep_feq *q;          /* borrowed */
    const uint64_t *ver;  /* borrowed */
};

nbep_status nbep_evloop_create(size_t n, nbep_vec3 lo, nbep_vec3 hi, double reach,
                               const bool *periodic, nbep_feq *q, const uint64_t *ver,
                               nbep_evloop **out, nbep_diag *d)
{
    nbep_evloop *e = calloc(1, sizeof *e);
    if (!e)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the cells engine");
    e->n = n;
    e->q = q;
    e->ver = ver;
    e->pb = nbep_periodic_make(periodic, lo, hi);
    /* the skin, cut down in a small periodic box so that three cells (sides of the cutoff)
     * fit across; the deck check keeps it at NBEP_NBLIST_SKIN_MIN */
    double skin = NBEP_NBLIST_SKIN * reach;
    for (int k = 0; k < 3; k++)
        if (e->pb.axis[k])
            skin = fmin(skin, e->pb.len[k] / (3.0 * (1.0 + CUT_SLACK)) - reach);
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
    e->cut = (reach + skin) * (1.0 + CUT_SLACK);
    e->face_reach = e->cut + 1.01 * e->stray;
    e->count = nbep_alloc_aligned(n ? n : 1, sizeof *e->count);
    e->near_cap = 64;
    e->near = malloc(e->near_cap * sizeof *e->near);
    e->was = malloc(e->near_cap * sizeof *e->was);
    e->kept = malloc(e->near_cap * sizeof *e->kept);
    nbep_status st = e->count && e->near && e->was && e->kept ? NBEP_OK : NBEP_ENOMEM;
    if (st != NBEP_OK)
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory for the cells engine");
    if (st == NBEP_OK)
        st = nbep_calendar_create(n, &e->cal, d);
    if (st == NBEP_OK)
        /* cells_init makes sides of 1.125 times the reach it is given, for the hysteresis of
         * moving members (cells.h); list centres stay put between rebuilds, so sides of the
         * cutoff itself suffice: a 27-cell block a third smaller to scan at each rebuild */
        st = nbep_cells_init(&e->cells, lo, hi, e->cut / 1.125, n, periodic, d);
    if (st == NBEP_OK)
        st = nbep_nblist_init(&e->nl, n, d);
    if (st != NBEP_OK) {
        nbep_evloop_destroy(&e);
        return st;
    }
    *out = e;
    return NBEP_OK;
}

double nbep_evloop_min_periodic_side(double reach)
{
    return 3.0 * (1.0 + NBEP_NBLIST_SKIN_MIN) * reach * (1.0 + CUT_SLACK);
}

void nbep_evloop_destroy(nbep_evloop **e)
{
    if (!e || !*e)
        return;
    nbep_calendar_destroy(&(*e)->cal);
    nbep_cells_fini(&(*e)->cells);
    nbep_nblist_fini(&(*e)->nl);
    nbep_free_aligned((*e)->count);
    free((*e)->kept);
    free((*e)->near);
    free((*e)->was);
    free(*e);
    *e = NULL;
}

size_t nbep_evloop_bytes(size_t n, double neighbours)
{
    return nbep_calendar_bytes(n) + nbep_cells_bytes(n) +
           nbep_nblist_bytes(n, (size_t)(neighbours * (double)n)) +
           n * sizeof(uint32_t);
}

bool nbep_evloop_failed(const nbep_evloop *e)
{
    return e->failed;
}

/* Calls f(e, i, j, arg) for every sphere j != i whose centre is within the cutoff of i's, from
 * the 27-cell block of i's cell (each at its image across periodic faces). */
static inline void near_centres(nbep_evloop *e, uint32_t i,
                                void (*f)(nbep_evloop *e, uint32_t i, uint32_t j, void *arg),
                                void *arg)
{
    const nbep_cells *g = &e->cells;
    nbep_cells_block b;
    nbep_cells_block_of(g, g->m[i].cell, &b);
    const nbep_vec3 ci = g->m[i].at;
    const double cut2 = e->cut * e->cut;
    for (int z = 0; z < b.cnt[2]; z++) {
        /* i's centre as seen from the block's cell: moved by the cell's period */
        const double az = b.per[2][z] ? ci.z - b.per[2][z] * e->pb.len[2] : ci.z;
        for (int y = 0; y < b.cnt[1]; y++) {
            const double ay = b.per[1][y] ? ci.y - b.per[1][y] * e->pb.len[1] : ci.y;
            const size_t row = (b.idx[2][z] * g->dim[1] + b.idx[1][y]) * g->dim[0];
            for (int x = 0; x < b.cnt[0]; x++) {
                const double ax = b.per[0][x] ? ci.x - b.per[0][x] * e->pb.len[0] : ci.x;
                for (uint32_t j = g->head[row + b.idx[0][x]]; j != NBEP_CELLS_NONE;
                     j = g->m[j].next) {
                    const nbep_vec3 cj = g->m[j].at;
                    const double dx = cj.x - ax, dy = cj.y - ay, dz = cj.z - az;
                    if (dx * dx + dy * dy + dz * dz < cut2 && j != i)
                        f(e, i, j, arg);
                }
            }
        }
    }
}

static void count_one(nbep_evloop *e, uint32_t i, uint32_t j, void *arg)
{
    (void)j;
    (void)arg;
    e->count[i]++;
}

static void fill_one(nbep_evloop *e, uint32_t i, uint32_t j, void *arg)
{
    (void)arg;
    nbep_nblist_fill(&e->nl, i, j);
}

/* Twice the room for rebuild_one's lists. */
static bool grow_near(nbep_evloop *e)
{
    size_t cap = 2 * e->near_cap;
    uint32_t *a = realloc(e->near, cap * sizeof *a);
    if (a)
        e->near = a;
    uint32_t *b = realloc(e->was, cap * sizeof *b);
    if (b)
        e->was = b;
    uint8_t *k = realloc(e->kept, cap * sizeof *k);
    if (k)
        e->kept = k;
    if (!a || !b || !k)
        return false;
    e->near_cap = cap;
    return true;
}

/* A sphere j near i during i's rebuild: into i's new list; into j's list too unless i was in
 * it already (j is among i's old neighbours, a handful looked through in cache: it is kept). */
static void gather_one(nbep_evloop *e, uint32_t i, uint32_t j, void *arg)
{
    (void)arg;
    size_t k = 0;
    while (k < e->n_was && e->was[k] != j)
        k++;
    if (k < e->n_was)
        e->kept[k] = 1;
    else if (!nbep_nblist_append(&e->nl, j, i))
        e->failed = true;
    if (e->n_near == e->near_cap && !grow_near(e)) {
        e->failed = true;
        return;
    }
    e->near[e->n_near++] = j;
}

/* Sphere i's list from scratch, its centre now at c: it leaves the lists of the neighbours it
 * loses and enters those of the ones it gains; those it keeps (most: it moved by half a skin)
 * are not touched. */
static void rebuild_one(nbep_evloop *e, uint32_t i, nbep_vec3 c)
{
    size_t m;
    const uint32_t *old = nbep_nblist_of(&e->nl, i, &m);
    while (m > e->near_cap)
        if (!grow_near(e)) {
            e->failed = true;
            return;
        }
    for (size_t k = 0; k < m; k++) { /* a copy: appends below may move the pool */
        e->was[k] = old[k];
        e->kept[k] = 0;
    }
    e->n_was = m;
    nbep_cells_place(&e->cells, i, c);
    e->n_near = 0;
    near_centres(e, i, gather_one, NULL);
    for (size_t k = 0; k < m; k++)
        if (!e->kept[k]) /* lost */
            nbep_nblist_drop(&e->nl, e->was[k], i);
    nbep_nblist_clear(&e->nl, i);
    for (size_t k = 0; k < e->n_near && !e->failed; k++)
        if (!nbep_nblist_append(&e->nl, i, e->near[k]))
            e->failed = true;
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
        near_centres(e, (uint32_t)i, count_one, NULL);
    }
}

void nbep_evloop_layout(nbep_evloop *e)
{
    if (!nbep_nblist_layout(&e->nl, e->count))
        e->failed = true;
}

/* The calendar's tie key: the pair (lower sphere high, higher low), the same in both spheres'
 * slots; a plane contact or a cell exit ranks after every pair of its sphere. */
static uint64_t slot_key(uint32_t i, const nbep_event *ev)
{
    uint32_t a = i, b = UINT32_MAX;
    if (ev->kind == NBEP_EVENT_SPHERE) {
        a = i < ev->partner ? i : ev->partner;
        b = i < ev->partner ? ev->partner : i;
    } else if (ev->kind == NBEP_EVENT_PLANE) {
        b = UINT32_MAX - ev->partner;
    }
    return (uint64_t)a << 32 | b;
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

/* Whether a neighbour of sphere i may have to be taken at an image across a periodic face: its
 * list centre is within the reach of a face on a periodic axis. Every listed j has its centre
 * within the cutoff of i's and its position within the stray of its centre, so when i's centre
 * is farther than cutoff + stray from both faces of every periodic axis, every neighbour
 * flies inside the box near i and its nearest image is itself (a margin of a hundredth of the
 * stray covers the roundings). */
static bool near_face(const nbep_evloop *e, uint32_t i)
{
    if (!e->pb.any)
        return false;
    const nbep_vec3 ci = e->cells.m[i].at;
    const double c[3] = {ci.x, ci.y, ci.z};
    for (int k = 0; k < 3; k++)
        if (e->pb.axis[k] && !(c[k] - e->pb.lo[k] > e->face_reach &&
                               e->pb.lo[k] + e->pb.len[k] - c[k] > e->face_reach))
            return true;
    return false;
}

/* Sphere i's slot from scratch at time t: planes, the spheres of its list, its list's expiry. */
static void predict_one(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                        double t)
{
    nbep_event best = ops->planes(u, i);
    /* the expiry before the pairs: a pair that comes later cannot win, so its root is skipped
     * (pairs ranks a pair before a plane or an expiry at the same time, as the slot key
     * does; the winner is the one trying the expiry last would give) */
    nbep_vec3 p, v, a;
    ops->flight(u, i, t, &p, &v, &a);
    double t_exit = t + stray_time(nbep_vec3_sub(p, e->cells.m[i].at), v, a, e->stray);
    if (t_exit < NBEP_NEVER && (best.kind == NBEP_EVENT_NONE || t_exit < best.time))
        best = (nbep_event){t_exit, 0, NBEP_EVENT_HORIZON, e->ver[i], 0};
    size_t m;
    const uint32_t *js = nbep_nblist_of(&e->nl, i, &m);
    if (m > 0)
        ops->pairs(u, i, js, m, near_face(e, i), &best);
    if (best.kind == NBEP_EVENT_NONE)
        best = (nbep_event){.time = INFINITY, .kind = NBEP_EVENT_NEVER, .ver_self = e->ver[i]};
    nbep_feq_put(e->q, i, best); /* from scratch: whatever the slot held goes */
}

/* The calendar entry of sphere i from its slot. */
static void schedule_one(nbep_evloop *e, uint32_t i)
{
    const nbep_event *ev = nbep_feq_slot(e->q, i);
    if (ev->kind == NBEP_EVENT_SPHERE || ev->kind == NBEP_EVENT_PLANE ||
        ev->kind == NBEP_EVENT_HORIZON)
        nbep_calendar_set(e->cal, i, ev->time, slot_key(i, ev));
    else
        nbep_calendar_remove(e->cal, i);
}

void nbep_evloop_predict(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, size_t lo,
                         size_t hi, double t)
{
    if (e->failed)
        return;
    for (size_t i = lo; i < hi; i++) /* own lists first: a prediction reads only its own */
        near_centres(e, (uint32_t)i, fill_one, NULL);
    for (size_t i = lo; i < hi; i++)
        predict_one(e, ops, u, (uint32_t)i, t);
}

void nbep_evloop_schedule(nbep_evloop *e, double t)
{
    nbep_calendar_clear(e->cal);
    for (size_t i = 0; i < e->n; i++)
        schedule_one(e, (uint32_t)i);
    nbep_calendar_retune(e->cal, t);
}

void nbep_evloop_stop(nbep_evloop *e)
{
    e->stop = true;
}

bool nbep_evloop_run(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, double t_end,
                     uint64_t stall_events, double stall_dt, nbep_evloop_tally *tally,
                     double *t_stuck)
{
    if (e->failed) /* a rebuild ran out of memory */
        return false;
    uint64_t since = 0;
    double t_mark = -INFINITY;
    uint32_t i;
    double t;
    while (nbep_calendar_top(e->cal, &i, &t) && t < t_end) {
        const nbep_event ev = *nbep_feq_slot(e->q, i);
        /* what this event and the next ones will read, requested now (no effect on results):
         * the first line of its list (from the list's record, which the event before requested
         * with the runners-up), its place, its partner's list record and place, and the
         * runners-up' slots, places and list records */
        NBEP_PREFETCH(&e->nl.pool[e->nl.sp[i].off]);
        NBEP_PREFETCH(&e->cells.m[i]);
        if (ev.kind == NBEP_EVENT_SPHERE) {
            NBEP_PREFETCH(&e->nl.sp[ev.partner]);
            NBEP_PREFETCH(&e->cells.m[ev.partner]);
        }
        uint32_t next[2];
        int n_next;
        nbep_calendar_runners_up(e->cal, next, &n_next);
        for (int k = 0; k < n_next; k++) {
            NBEP_PREFETCH(nbep_feq_slot(e->q, next[k]));
            NBEP_PREFETCH(&e->cells.m[next[k]]);
            NBEP_PREFETCH(&e->nl.sp[next[k]]);
        }
        tally->events++;
        if (++since >= stall_events) {
            if (!(t - t_mark > stall_dt)) {
                *t_stuck = t;
                return false;
            }
            t_mark = t;
            since = 0;
        }
        if (ev.kind == NBEP_EVENT_HORIZON) {
            nbep_vec3 p, v, a;
            if (e->pb.any) /* a centre past a periodic face enters through the other */
                ops->wrap(u, i, t);
            ops->flight(u, i, t, &p, &v, &a);
            rebuild_one(e, i, p);
            if (e->failed)
                return false;
            tally->exits++;
        } else if (ops->fresh(u, i, &ev)) {
            const uint32_t *changed;
            size_t m = ops->react(u, i, &ev, &changed);
            tally->reactions++;
            if (e->stop) {
                *t_stuck = t;
                return false;
            }
            for (size_t k = 0; k < m; k++)
                if (changed[k] != i) {
                    predict_one(e, ops, u, changed[k], t);
                    schedule_one(e, changed[k]);
                }
        }
        /* in every case (exit, stale slot, reaction) i looks again from now */
        predict_one(e, ops, u, i, t);
        schedule_one(e, i);
    }
    return true;
}
