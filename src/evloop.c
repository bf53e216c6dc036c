/* The cells engine: see evloop.h. */
#include "evloop.h"

#include <math.h>
#include <stdalign.h>
#include <stdatomic.h>
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

/* One thread's side of an event (handle, then commit): the list a rebuild found and what the
 * event changed, held until its commit; for a speculative event (the team loop's), the
 * motion and slots it may change, kept to undo it. */
typedef struct evl_ws {
    /* a rebuild of one list (walk): near holds the new list, gain[k] set for the entries i's
     * old list lacked; was holds the old list (n_was entries), kept[k] set for those found again */
    uint32_t *near, *was;   /* owned, room for cap each */
    uint8_t *kept, *gain;   /* owned, room for cap each */
    size_t cap, n_near, n_was;
    bool oom;               /* the walk ran out of memory */
    /* the event handled, waiting for its commit */
    uint32_t item;
    bool rebuilt;           /* a list expiry: near is item's list, built around `at` */
    bool reacted;
    nbep_vec3 at;
    uint32_t *changed;      /* owned, room for chg_cap: the spheres the reaction changed */
    size_t n_changed, chg_cap;
    /* a speculative event's undo: the spheres it may change, as they were */
    uint32_t kept_id[2];
    nbep_evloop_motion kept_motion[2];
    nbep_event kept_slot[2];
    int n_kept;
} evl_ws;

struct nbep_evloop {
    size_t n;
    nbep_calendar *cal;   /* owned */
    nbep_cells cells;     /* owned: cells of the list centres, at least `cut` wide; a
                           * member's place (cells.m[i].at) is where i's list was built */
    nbep_nblist nl;       /* owned */
    uint32_t *count;      /* owned, n: list lengths, at a full rebuild */
    evl_ws ws[NBEP_EVLOOP_BATCH]; /* one per event of a team round (the one thread: ws[0]) */
    nbep_periodic pb;     /* the box's periodic geometry */
    double cut;           /* the list cutoff: contact distance plus skin, plus slack */
    double stray;         /* half the skin: how far a sphere goes before its list expires */
    double face_reach;    /* cut + stray, and a margin: see near_face */
    double apart2;        /* square of the distance between list centres beyond which two
                           * events touch no common sphere (nbep_evloop_run_lead) */
    bool failed;          /* out of memory for a list: the run stops */
    bool stop;            /* nbep_evloop_stop: the run stops after the current event */
    nbep_feq *q;          /* borrowed */
    const uint64_t *ver;  /* borrowed */
    /* a team round: its events in order (the spheres and their slots as they were) */
    uint32_t batch[NBEP_EVLOOP_BATCH];
    nbep_event batch_ev[NBEP_EVLOOP_BATCH];
    /* the other sphere each event's slot names (a pair's partner, fresh or stale; NO_SPHERE
     * for a plane or an expiry), and the cell coordinates of an expiry's list centre */
    uint32_t batch_other[NBEP_EVLOOP_BATCH];
    size_t batch_cell[NBEP_EVLOOP_BATCH][3];
    bool batch_walks[NBEP_EVLOOP_BATCH]; /* a list expiry: its handle walks the cells around
                                          * its sphere and its commit changes them */
    /* the list centres of the round's spheres so far (each place's own and other), for pick */
    double taken_x[2 * NBEP_EVLOOP_BATCH], taken_y[2 * NBEP_EVLOOP_BATCH],
        taken_z[2 * NBEP_EVLOOP_BATCH];
    /* the team loop's hand-over: the leader posts a round in one word, go = its number times
     * 256 plus how many events it has (0: the loop ends); either thread takes the next place
     * to handle from `next` (the round's number times NBEP_EVLOOP_BATCH plus the place) and
     * marks it handled (the round's number); the helper answers done = the go of the end */
    uint64_t round;       /* the leader's: the last round it numbered, posted or not */
    alignas(NBEP_CACHELINE) _Atomic uint64_t go;
    alignas(NBEP_CACHELINE) _Atomic uint64_t next;
    alignas(NBEP_CACHELINE) _Atomic uint64_t done;
    struct {
        alignas(NBEP_CACHELINE) _Atomic uint64_t round;
    } handled[NBEP_EVLOOP_BATCH];
};

static bool ws_init(evl_ws *w)
{
    w->cap = 64;
    w->near = malloc(w->cap * sizeof *w->near);
    w->was = malloc(w->cap * sizeof *w->was);
    w->kept = malloc(w->cap * sizeof *w->kept);
    w->gain = malloc(w->cap * sizeof *w->gain);
    w->chg_cap = 8;
    w->changed = malloc(w->chg_cap * sizeof *w->changed);
    return w->near && w->was && w->kept && w->gain && w->changed;
}

static void ws_fini(evl_ws *w)
{
    free(w->near);
    free(w->was);
    free(w->kept);
    free(w->gain);
    free(w->changed);
}

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
    /* two events whose spheres' list centres are all farther apart than this (place_apart:
     * each event's own sphere and the other its slot names, checked themselves, however far
     * a stale slot's other may be) touch nothing in common. An event handled writes the motion
     * and slot of its spheres and reads those of their lists' members; committed, it writes
     * the lists of its spheres' old and new members. Members lie within the cutoff of a list
     * centre, and an expiry's new centre within (1 + LEAD) strays of the old (its sphere
     * strayed up to one, the new centre leads by LEAD), so what an event touches lies within
     * touch = cut + (1 + LEAD) stray of its spheres' centres, and two events whose spheres
     * are more than touch apart touch nothing in common (a written sphere is never read by the
     * other, a written list is never the other's own). Twice that leaves a wide margin for
     * the roundings. */
    const double touch = e->cut + (1.0 + NBEP_NBLIST_LEAD) * e->stray;
    e->apart2 = (2.0 * touch) * (2.0 * touch);
    atomic_init(&e->go, 0);
    atomic_init(&e->next, 0);
    atomic_init(&e->done, 0);
    for (int k = 0; k < NBEP_EVLOOP_BATCH; k++)
        atomic_init(&e->handled[k].round, 0);
    e->count = nbep_alloc_aligned(n ? n : 1, sizeof *e->count);
    bool ws_ok = true;
    for (int k = 0; k < NBEP_EVLOOP_BATCH; k++)
        ws_ok &= ws_init(&e->ws[k]);
    nbep_status st = e->count && ws_ok ? NBEP_OK : NBEP_ENOMEM;
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
    for (int k = 0; k < NBEP_EVLOOP_BATCH; k++)
        ws_fini(&(*e)->ws[k]);
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

/* Calls f(e, i, j, arg) for every sphere j != i whose place is within the cutoff of ci, from
 * the 27-cell block of cell `cell` (each at its image across periodic faces). Reads the cells
 * only. */
static inline void near_centres(const nbep_evloop *e, uint32_t i, nbep_vec3 ci, size_t cell,
                                void (*f)(const nbep_evloop *e, uint32_t i, uint32_t j,
                                          void *arg),
                                void *arg)
{
    const nbep_cells *g = &e->cells;
    nbep_cells_block b;
    nbep_cells_block_of(g, cell, &b);
    const double cut2 = e->cut * e->cut;
    /* the block's first members and ci as seen from each cell (moved by the cell's period),
     * all requested before any is read: a cell holds one or two members in a fluid, so the
     * walk is mostly these first loads, which then overlap instead of following each other */
    uint32_t first[27];
    nbep_vec3 from[27];
    int nc = 0;
    for (int z = 0; z < b.cnt[2]; z++) {
        const double az = b.per[2][z] ? ci.z - b.per[2][z] * e->pb.len[2] : ci.z;
        for (int y = 0; y < b.cnt[1]; y++) {
            const double ay = b.per[1][y] ? ci.y - b.per[1][y] * e->pb.len[1] : ci.y;
            const size_t row = (b.idx[2][z] * g->dim[1] + b.idx[1][y]) * g->dim[0];
            for (int x = 0; x < b.cnt[0]; x++) {
                const double ax = b.per[0][x] ? ci.x - b.per[0][x] * e->pb.len[0] : ci.x;
                const uint32_t j = g->head[row + b.idx[0][x]];
                if (j == NBEP_CELLS_NONE)
                    continue;
                NBEP_PREFETCH(&g->m[j]);
                first[nc] = j;
                from[nc++] = nbep_vec3_make(ax, ay, az);
            }
        }
    }
    for (int q = 0; q < nc; q++) {
        const nbep_vec3 a = from[q];
        for (uint32_t j = first[q]; j != NBEP_CELLS_NONE; j = g->m[j].next) {
            const nbep_vec3 cj = g->m[j].at;
            const double dx = cj.x - a.x, dy = cj.y - a.y, dz = cj.z - a.z;
            if (dx * dx + dy * dy + dz * dz < cut2 && j != i)
                f(e, i, j, arg);
        }
    }
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

/* A sphere j near i during i's walk: into the new list, marked gained unless i's old list has
 * it (a handful looked through in cache: it is kept). */
static void gather_one(const nbep_evloop *e, uint32_t i, uint32_t j, void *arg)
{
    (void)e;
    (void)i;
    evl_ws *w = arg;
    size_t k = 0;
    while (k < w->n_was && w->was[k] != j)
        k++;
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
    while (m > w->cap)
        if (!grow_ws(w)) {
            w->oom = true;
            return;
        }
    for (size_t k = 0; k < m; k++) {
        w->was[k] = old[k];
        w->kept[k] = 0;
    }
    w->n_was = m;
    w->n_near = 0;
    near_centres(e, i, c, nbep_cells_locate(&e->cells, c), gather_one, w);
}

/* The walk's list entered: i placed at c; it enters the lists of the neighbours it gains and
 * leaves those of the ones it loses; those it keeps (most: it moved by half a skin) are not
 * touched. One thread, no other walking. */
static void apply(nbep_evloop *e, const evl_ws *w, uint32_t i, nbep_vec3 c)
{
    nbep_cells_place(&e->cells, i, c);
    for (size_t k = 0; k < w->n_near && !e->failed; k++)
        if (w->gain[k] && !nbep_nblist_append(&e->nl, w->near[k], i))
            e->failed = true;
    for (size_t k = 0; k < w->n_was; k++)
        if (!w->kept[k]) /* lost */
            nbep_nblist_drop(&e->nl, w->was[k], i);
    nbep_nblist_clear(&e->nl, i);
    for (size_t k = 0; k < w->n_near && !e->failed; k++)
        if (!nbep_nblist_append(&e->nl, i, w->near[k]))
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
        near_own(e, (uint32_t)i, count_one);
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

/* What slot_key(i, ev) says back: the other sphere of a pair (an index at or past n for a plane
 * or an expiry: UINT32_MAX - plane or UINT32_MAX), and whether it is an expiry. */
static uint32_t key_other(uint64_t key, uint32_t i)
{
    const uint32_t a = (uint32_t)(key >> 32), b = (uint32_t)key;
    return a == i ? b : a;
}
static bool key_expiry(uint64_t key, uint32_t i)
{
    return key == ((uint64_t)i << 32 | UINT32_MAX);
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
    if (!e->pb.any)
        return false;
    const double c[3] = {ci.x, ci.y, ci.z};
    for (int k = 0; k < 3; k++)
        if (e->pb.axis[k] && !(c[k] - e->pb.lo[k] > e->face_reach &&
                               e->pb.lo[k] + e->pb.len[k] - c[k] > e->face_reach))
            return true;
    return false;
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
        near_own(e, (uint32_t)i, fill_one);
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

/* The event in i's slot (ev, at time t), handled on workspace w: the motion and the slots of
 * the spheres it involves are written (an expiry also finds its sphere's new list); the lists,
 * the cells and the calendar wait for commit. A stale slot is predicted again; an expiry wraps
 * its sphere into a periodic box if it left it and predicts it from its new list; a contact
 * reacts and every sphere the reaction changed is predicted again. */
static void handle(nbep_evloop *e, evl_ws *w, const nbep_evloop_ops *ops, void *u, uint32_t i,
                   const nbep_event *ev, double t)
{
    w->item = i;
    w->rebuilt = w->reacted = w->oom = false;
    w->n_changed = 0;
    if (ev->kind == NBEP_EVENT_HORIZON) {
        nbep_vec3 p, v, a;
        if (e->pb.any) /* a centre past a periodic face enters through the other */
            ops->wrap(u, i, t);
        ops->flight(u, i, t, &p, &v, &a);
        const nbep_vec3 c = list_centre(e, p, v, a);
        walk(e, w, i, c);
        if (w->oom)
            return;
        w->rebuilt = true;
        w->at = c;
        predict_with(e, ops, u, i, t, w->near, w->n_near, c);
        return;
    }
    if (ev->kind == NBEP_EVENT_SPHERE) /* read if the event is fresh */
        prefetch_list(e, ev->partner);
    if (ops->fresh(u, i, ev)) {
        w->reacted = true;
        const uint32_t *changed;
        const size_t m = ops->react(u, i, ev, &changed);
        if (e->stop)
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
            if (w->changed[k] != i)
                predict_one(e, ops, u, w->changed[k], t);
    }
    /* in every other case (stale slot, reaction) i looks again from now */
    predict_one(e, ops, u, i, t);
}

/* What handle left waiting: the new list entered, the changed spheres' calendar entries set. */
static void commit(nbep_evloop *e, const evl_ws *w)
{
    if (w->oom)
        e->failed = true;
    if (w->rebuilt)
        apply(e, w, w->item, w->at);
    if (e->failed)
        return;
    for (size_t k = 0; k < w->n_changed; k++)
        if (w->changed[k] != w->item)
            schedule_one(e, w->changed[k]);
    schedule_one(e, w->item);
}

/* Counts one event at time t towards the stall check: false when `stall_events` events in a row
 * have not advanced time by more than stall_dt. */
static bool advances(uint64_t *since, double *t_mark, double t, uint64_t stall_events,
                     double stall_dt)
{
    if (++*since >= stall_events) {
        if (!(t - *t_mark > stall_dt))
            return false;
        *t_mark = t;
        *since = 0;
    }
    return true;
}

/* Requests what the event of sphere i (slot ev) and the next ones will read (no effect on
 * results): the first line of its list (from the list's record, which the event before
 * requested with the runners-up), its place, its partner's list record and place, and the
 * runners-up' slots, places and list records. */
static void prefetch_event(const nbep_evloop *e, uint32_t i, const nbep_event *ev)
{
    NBEP_PREFETCH(&e->nl.pool[e->nl.sp[i].off]);
    NBEP_PREFETCH(&e->cells.m[i]);
    if (ev->kind == NBEP_EVENT_SPHERE) {
        NBEP_PREFETCH(&e->nl.sp[ev->partner]);
        NBEP_PREFETCH(&e->cells.m[ev->partner]);
        nbep_calendar_prefetch(e->cal, ev->partner); /* moved at the commit if it is fresh */
    }
    uint32_t next[2];
    int n_next;
    nbep_calendar_runners_up(e->cal, next, &n_next);
    for (int k = 0; k < n_next; k++) {
        NBEP_PREFETCH(nbep_feq_slot(e->q, next[k]));
        NBEP_PREFETCH(&e->cells.m[next[k]]);
        NBEP_PREFETCH(&e->nl.sp[next[k]]);
    }
}

static void count_handled(nbep_evloop_tally *tally, const evl_ws *w)
{
    tally->exits += w->rebuilt;
    tally->reactions += w->reacted;
}

bool nbep_evloop_run(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, double t_end,
                     uint64_t stall_events, double stall_dt, nbep_evloop_tally *tally,
                     double *t_stuck)
{
    if (e->failed) /* a rebuild ran out of memory */
        return false;
    uint64_t since = 0;
    double t_mark = -INFINITY;
    evl_ws *w = &e->ws[0];
    uint32_t i;
    double t;
    while (nbep_calendar_top(e->cal, &i, &t) && t < t_end) {
        const nbep_event ev = *nbep_feq_slot(e->q, i);
        prefetch_event(e, i, &ev);
        tally->events++;
        if (!advances(&since, &t_mark, t, stall_events, stall_dt)) {
            *t_stuck = t;
            return false;
        }
        handle(e, w, ops, u, i, &ev, t);
        count_handled(tally, w);
        if (e->stop) {
            *t_stuck = t;
            return false;
        }
        commit(e, w);
        if (e->failed)
            return false;
    }
    return true;
}

/* ---- the team loop (nbep_evloop_run_lead, nbep_evloop_help) -------------------------------- */

#define GO_SHIFT 8 /* go = round << GO_SHIFT | events */
_Static_assert(NBEP_EVLOOP_BATCH < (1 << GO_SHIFT), "a round's size fits below GO_SHIFT");

/* Whether list centre c is more than sqrt(apart2) from each of the first nt centres taken
 * for the round (pick), in a periodic box the nearest way round: then events on their spheres
 * touch nothing in common. One pass without branches over the taken centres (up to 32),
 * counting those too near: a count vectorises where a running minimum of doubles does not
 * (this loop was most of pick's time, a tenth of the leader's). */
NBEP_AVX2_CLONES static bool clear_of(const nbep_evloop *e, nbep_vec3 c, size_t nt)
{
    const double hx = e->pb.half[0], hy = e->pb.half[1], hz = e->pb.half[2];
    const double lx = e->pb.len[0], ly = e->pb.len[1], lz = e->pb.len[2];
    const double apart2 = e->apart2;
    const double *restrict tx = e->taken_x, *restrict ty = e->taken_y, *restrict tz = e->taken_z;
    int near = 0;
    for (size_t k = 0; k < nt; k++) {
        double dx = fabs(c.x - tx[k]), dy = fabs(c.y - ty[k]), dz = fabs(c.z - tz[k]);
        dx = dx > hx ? lx - dx : dx; /* half is +inf on an axis that is not periodic */
        dy = dy > hy ? ly - dy : dy;
        dz = dz > hz ? lz - dz : dz;
        near += !(dx * dx + dy * dy + dz * dz > apart2);
    }
    return near == 0;
}

/* Whether the cells that a commit of an event in cell a changes (a's cell and, for a rebuilt
 * list, the one next to it that its new centre is in) lie outside the cells a walk of an event
 * in cell b reads (the blocks around b's cell and its neighbours): 4 cells apart along some
 * axis, the nearest way round on a periodic one. */
static bool cells_apart(const nbep_evloop *e, const size_t *a, const size_t *b)
{
    for (int k = 0; k < 3; k++) {
        size_t d = a[k] > b[k] ? a[k] - b[k] : b[k] - a[k];
        if (e->cells.periodic[k] && d > e->cells.dim[k] - d)
            d = e->cells.dim[k] - d;
        if (d >= 4)
            return true;
    }
    return false;
}

static void cell_xyz(const nbep_evloop *e, uint32_t i, size_t *xyz)
{
    const size_t c = e->cells.m[i].cell, nx = e->cells.dim[0], ny = e->cells.dim[1];
    xyz[0] = c % nx;
    xyz[1] = c / nx % ny;
    xyz[2] = c / (nx * ny);
}

#define NO_SPHERE UINT32_MAX

/* Whether round place m is apart from every place before it: both its spheres (its own and
 * the one its slot names) clear of both spheres of every earlier place in what they touch
 * (clear_of: nt centres taken so far), and, when it and an earlier place are both list
 * expiries, in their cells (only an expiry reads the cells of other spheres, in its walk, and
 * only an expiry's commit changes cells; an expiry's slot names no other sphere). */
static bool place_apart(const nbep_evloop *e, size_t m, size_t nt)
{
    if (e->batch_walks[m])
        for (size_t k = 0; k < m; k++)
            if (e->batch_walks[k] && !cells_apart(e, e->batch_cell[k], e->batch_cell[m]))
                return false;
    if (!clear_of(e, e->cells.m[e->batch[m]].at, nt))
        return false;
    return e->batch_other[m] == NO_SPHERE ||
           clear_of(e, e->cells.m[e->batch_other[m]].at, nt);
}

/* The centres of place m's spheres taken, after the nt before them; returns the new count. */
static size_t take_centres(nbep_evloop *e, size_t m, size_t nt)
{
    const uint32_t s[2] = {e->batch[m], e->batch_other[m]};
    for (int k = 0; k < 2; k++)
        if (s[k] != NO_SPHERE) {
            const nbep_vec3 c = e->cells.m[s[k]].at;
            e->taken_x[nt] = c.x;
            e->taken_y[nt] = c.y;
            e->taken_z[nt] = c.z;
            nt++;
        }
    return nt;
}

/* Round place m is sphere x with the event its slot (key) names: the other sphere, whether
 * it is a list expiry (walks), and then the cell of its list centre. */
static void set_place(nbep_evloop *e, size_t m, uint32_t x, uint32_t other, bool walks)
{
    e->batch[m] = x;
    e->batch_walks[m] = walks;
    e->batch_other[m] = other < e->n ? other : NO_SPHERE;
    if (walks)
        cell_xyz(e, x, e->batch_cell[m]);
}

/* A round's events: the earliest (sphere i, slot ev) and those that follow it in the calendar
 * while each is apart from all before it (place_apart: both its spheres, the one whose entry
 * it is and the other its slot names, against both of every event before it: the other may be
 * far when the slot is stale, and a far sphere must not be read, kept or put back while
 * another event writes it), and comes before t_end; the entries of the other sphere of the
 * round's pair events are passed over (the pair's reaction moves them; a pair's key names both
 * spheres, slot_key). Reads the calendar and the list centres only: each event's slot is read
 * by the thread that handles it. Returns how many. */
static size_t pick(nbep_evloop *e, uint32_t i, const nbep_event *ev, double t_end)
{
    e->batch_ev[0] = *ev;
    set_place(e, 0, i, ev->kind == NBEP_EVENT_SPHERE ? ev->partner : NO_SPHERE,
              ev->kind == NBEP_EVENT_HORIZON);
    size_t n = 1, n_skip = 0, nt = take_centres(e, 0, 0);
    /* enough entries for a full round and the partners' entries it passes over */
    enum { FRONT = 2 * NBEP_EVLOOP_BATCH };
    uint32_t skip[NBEP_EVLOOP_BATCH], front[FRONT], other[FRONT];
    double times[FRONT];
    uint64_t keys[FRONT];
    if (e->batch_other[0] != NO_SPHERE)
        skip[n_skip++] = e->batch_other[0];
    const size_t nf = nbep_calendar_front(e->cal, front, times, keys, FRONT);
    for (size_t f = 0; f < nf; f++) { /* the places of both spheres (the key names the
                                       * other), all requested before the first is used */
        other[f] = key_other(keys[f], front[f]);
        NBEP_PREFETCH(&e->cells.m[front[f]]);
        if (other[f] < e->n)
            NBEP_PREFETCH(&e->cells.m[other[f]]);
    }
    for (size_t f = 0; f < nf && n < NBEP_EVLOOP_BATCH; f++) {
        const uint32_t x = front[f];
        bool passed = false;
        for (size_t k = 0; k < n_skip; k++)
            passed |= skip[k] == x;
        if (passed)
            continue;
        if (!(times[f] < t_end))
            break;
        set_place(e, n, x, other[f], key_expiry(keys[f], x));
        if (!place_apart(e, n, nt))
            return n;
        nt = take_centres(e, n, nt);
        if (e->batch_other[n] != NO_SPHERE)
            skip[n_skip++] = e->batch_other[n];
        NBEP_PREFETCH(nbep_feq_slot(e->q, x));
        NBEP_PREFETCH(&e->nl.sp[x]);
        n++;
    }
    return n;
}

/* Requests what round place m's handle reads first (no effect on results): the slot and list
 * record of its sphere, the first line of its list (from the record, which pick requested),
 * and the other sphere's record. The one-thread loop requests the same for the events after
 * the current one (prefetch_event); without it, a team thread met each of these as a miss:
 * the team loop on one core ran 1.23 times the one-thread loop's time. */
static inline NBEP_ALWAYS_INLINE void prefetch_place(const nbep_evloop *e, size_t m)
{
    const uint32_t x = e->batch[m];
    NBEP_PREFETCH(nbep_feq_slot(e->q, x));
    NBEP_PREFETCH(&e->nl.pool[e->nl.sp[x].off]);
    if (e->batch_other[m] != NO_SPHERE)
        NBEP_PREFETCH(&e->nl.sp[e->batch_other[m]]);
}

/* Keeps what the event at round place m may change, to undo it: the motion and slot of its
 * sphere and of the other its slot names (pick's batch_other, from the calendar key). */
static void keep(nbep_evloop *e, size_t m, const nbep_evloop_ops *ops, void *u)
{
    evl_ws *w = &e->ws[m];
    w->n_kept = 0;
    w->kept_id[w->n_kept++] = e->batch[m];
    if (e->batch_other[m] != NO_SPHERE)
        w->kept_id[w->n_kept++] = e->batch_other[m];
    for (int k = 0; k < w->n_kept; k++) {
        ops->save(u, w->kept_id[k], &w->kept_motion[k]);
        w->kept_slot[k] = *nbep_feq_slot(e->q, w->kept_id[k]);
    }
}

/* A speculative event undone: the spheres it changed as they were, their slots too (the
 * calendar, the lists and the cells were not touched), its counts dropped. */
static void undo(nbep_evloop *e, const evl_ws *w, const nbep_evloop_ops *ops, void *u,
                 void *uk)
{
    for (int k = w->n_kept - 1; k >= 0; k--) {
        ops->restore(uk, w->kept_id[k], &w->kept_motion[k]);
        nbep_feq_put(e->q, w->kept_id[k], w->kept_slot[k]);
    }
    ops->merge(u, uk, false);
}

/* Takes the next place of round `round` (n places) to handle and handles it: false when none
 * is left. */
static bool take_one(nbep_evloop *e, const nbep_evloop_ops *ops, void *const *us,
                     uint64_t round, size_t n)
{
    uint64_t v = atomic_load_explicit(&e->next, memory_order_relaxed);
    do {
        if (v / NBEP_EVLOOP_BATCH != round || v % NBEP_EVLOOP_BATCH >= n)
            return false;
    } while (!atomic_compare_exchange_weak_explicit(&e->next, &v, v + 1, memory_order_relaxed,
                                                    memory_order_relaxed));
    const size_t m = v % NBEP_EVLOOP_BATCH;
    for (size_t q = m + 1; q < n && q < m + 3; q++)
        prefetch_place(e, q);
    if (m > 0) { /* every event but the round's first (read by pick) may be undone */
        e->batch_ev[m] = *nbep_feq_slot(e->q, e->batch[m]);
        keep(e, m, ops, us[m]);
    }
    handle(e, &e->ws[m], ops, us[m], e->batch[m], &e->batch_ev[m], e->batch_ev[m].time);
    atomic_store_explicit(&e->handled[m].round, round, memory_order_release);
    return true;
}

/* The leader waits for place m of the round to be handled, handling places meanwhile. */
static void wait_handled(nbep_evloop *e, const nbep_evloop_ops *ops, void *const *us,
                         uint64_t round, size_t n, size_t m)
{
    for (unsigned k = 1;
         atomic_load_explicit(&e->handled[m].round, memory_order_acquire) != round; k++)
        if (!take_one(e, ops, us, round, n))
            nbep_spin_pause(k);
}

/* Places m.. of the round undone, once every one is handled. */
static void undo_from(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                      uint64_t round, size_t n, size_t m)
{
    for (size_t q = m; q < n; q++) {
        wait_handled(e, ops, us, round, n, q);
        undo(e, &e->ws[q], ops, u, us[q]);
    }
}

static bool lead(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                 double t_end, uint64_t stall_events, double stall_dt, nbep_evloop_tally *tally,
                 double *t_stuck, uint64_t *round)
{
    uint64_t since = 0;
    double t_mark = -INFINITY;
    uint32_t i;
    double t;
    while (nbep_calendar_top(e->cal, &i, &t) && t < t_end) {
        const nbep_event ev = *nbep_feq_slot(e->q, i);
        prefetch_event(e, i, &ev);
        if (!advances(&since, &t_mark, t, stall_events, stall_dt)) {
            tally->events++;
            *t_stuck = t;
            return false;
        }
        const size_t n = pick(e, i, &ev, t_end);
        const uint64_t r = ++*round;
        atomic_store_explicit(&e->next, r * NBEP_EVLOOP_BATCH, memory_order_relaxed);
        if (n > 1) /* the places and the events, published to the helper */
            atomic_store_explicit(&e->go, r << GO_SHIFT | n, memory_order_release);
        /* the events in order, as they are handled: each stands when it is then the earliest
         * (the one thread would handle it next, from the same state: no event before it
         * touched its spheres) */
        for (size_t m = 0; m < n; m++) {
            wait_handled(e, ops, us, r, n, m);
            const evl_ws *w = &e->ws[m];
            if (m > 0) {
                uint32_t im;
                double tm;
                if (!(nbep_calendar_top(e->cal, &im, &tm) && im == e->batch[m] && tm < t_end)) {
                    undo_from(e, ops, u, us, r, n, m);
                    tally->undone += n - m;
                    break;
                }
                if (!advances(&since, &t_mark, tm, stall_events, stall_dt)) {
                    undo_from(e, ops, u, us, r, n, m);
                    tally->events++;
                    *t_stuck = tm;
                    return false;
                }
            }
            if (e->stop) { /* not in the scenes a team runs (no reaction there stops the run;
                            * a helper's stop would also be a race on e->stop) */
                undo_from(e, ops, u, us, r, n, m + 1);
                *t_stuck = e->batch_ev[m].time;
                return false;
            }
            /* a commit that would make the pool of lists move waits until no list is read */
            if (w->rebuilt && nbep_nblist_spare(&e->nl) <
                                  nbep_nblist_need(&e->nl, w->n_near, w->n_near))
                for (size_t q = m + 1; q < n; q++)
                    wait_handled(e, ops, us, r, n, q);
            tally->events++;
            count_handled(tally, w);
            ops->merge(u, us[m], true);
            commit(e, w);
            if (e->failed) {
                undo_from(e, ops, u, us, r, n, m + 1);
                return false;
            }
            tally->ahead += m > 0;
        }
    }
    return true;
}

bool nbep_evloop_run_lead(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                          double t_end, uint64_t stall_events, double stall_dt,
                          nbep_evloop_tally *tally, double *t_stuck)
{
    bool ok = !e->failed && lead(e, ops, u, us, t_end, stall_events, stall_dt, tally, t_stuck,
                                 &e->round);
    /* the helper returns (it has handled every place it took: each was waited for) */
    const uint64_t end = ++e->round << GO_SHIFT;
    atomic_store_explicit(&e->go, end, memory_order_release);
    for (unsigned k = 1; atomic_load_explicit(&e->done, memory_order_acquire) != end; k++)
        nbep_spin_pause(k);
    return ok;
}

void nbep_evloop_help(nbep_evloop *e, const nbep_evloop_ops *ops, void *const *us)
{
    uint64_t seen = atomic_load_explicit(&e->done, memory_order_relaxed); /* its own stores */
    for (;;) {
        uint64_t go;
        for (unsigned k = 1; (go = atomic_load_explicit(&e->go, memory_order_acquire)) == seen;
             k++)
            nbep_spin_pause(k);
        seen = go;
        const size_t n = go & ((1u << GO_SHIFT) - 1);
        if (n == 0) {
            atomic_store_explicit(&e->done, go, memory_order_release);
            return;
        }
        while (take_one(e, ops, us, go >> GO_SHIFT, n))
            ;
    }
}
