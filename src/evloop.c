/* The cells engine: see evloop.h. */
#include "evloop.h"

#include <assert.h>
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

/* A look at the window each time a place joins it (places head .. tail - 1 in flight, place
 * tail joining): tests/test_evloop_apart.c compiles its own copy of this file with a check of
 * the places' apartness by means of its own; a build of nbep has nothing here. */
#ifndef NBEP_EVLOOP_JOIN_HOOK
#define NBEP_EVLOOP_JOIN_HOOK(e) ((void)0)
#endif
/* A look at each event once handled (w: what it found and changed; ev: its slot):
 * tests/bench/bench_parallelism.c compiles its own copy of this file that follows what every
 * event reads and writes; a build of nbep has nothing here. */
#ifndef NBEP_EVLOOP_HANDLED_HOOK
#define NBEP_EVLOOP_HANDLED_HOOK(e, w, ev) ((void)0)
#endif

/* The team loop's leader's phases, for a look at where its time goes: tests/bench/bench_leader.c
 * compiles its own copy of this file whose hook notes the time at each change of phase and
 * returns the phase before it; a build of nbep has nothing here. */
enum {
    PH_WAIT,   /* waiting for a place to be handled, with none left to take */
    PH_HANDLE, /* handling places itself while it waits for one (a place found handled at the
                * first look is no wait: the look stays in the phase that looked) */
    PH_STAND,  /* whether the window's first place stands (with the look for its taker) */
    PH_COMMIT, /* committing it */
    PH_FILL,   /* adding places to the window */
    PH_UNDO,   /* undoing places (their waits are handle and wait) */
    PH_START,  /* an empty window's first place, and the fill that follows it */
    PH_COUNT
};
#ifndef NBEP_EVLOOP_PHASE_HOOK
#define NBEP_EVLOOP_PHASE_HOOK(p) 0
#endif
static inline NBEP_ALWAYS_INLINE int phase(int p)
{
    (void)p;
    return NBEP_EVLOOP_PHASE_HOOK(p);
}

/* The team loop's places in flight at most: enough that a helper finds one to take while the
 * leader commits (a window of 12 to 32 ran within the noise of this one at N = 256000,
 * phi = 0.30, with one helper; more helpers may want more, unmeasured). */
#define WINDOW 16

/* The calendar entries an event's workspace holds for its commit (a pair's two spheres), and
 * the mark of more. */
#define NEXT_MAX 2
#define NEXT_ALL UINT8_MAX

/* One thread's side of an event (handle, then commit): the list a rebuild found and what the
 * event changed, held until its commit; for a speculative event (the team loop's), the
 * motion and slots it may change, kept to undo it. */
typedef struct evl_ws {
    /* the event handled, waiting for its commit, and what the commit reads first, on one
     * cache line (the team's leader waits for it and reads it from another core; a
     * workspace starts a line): in the team loop, the number of the place last handled on it
     * (stored last, with release: what handle wrote is then there to read); the calendar
     * entries to set, the changed spheres' then item's, from the slots handle wrote (n_next
     * of them; NEXT_ALL where there were more than NEXT_MAX: the commit reads them from the
     * slots), each set or, where next_set is false, taken out */
    alignas(NBEP_CACHELINE) _Atomic uint64_t place;
    uint32_t item;
    bool rebuilt;           /* a list expiry: near is item's list, built around `at` */
    bool reacted;
    bool stop;              /* the reaction asked the run to stop after it (ops react) */
    bool oom;               /* out of memory for the walk or the copy of `changed` */
    uint8_t n_next;
    uint32_t next_item[NEXT_MAX];
    bool next_set[NEXT_MAX];
    double next_time[NEXT_MAX];
    uint64_t next_key[NEXT_MAX];
    /* the team loop: the number of the place last handled here once it stood, written by the
     * leader as it commits the place (on the line after the one it reads first, which for a
     * pair's event it reads no more of: it writes without waiting for it), and whether the
     * handler has yet to add that place's counts and sums (its context's) to its own
     * (pending: the handler's alone). The handler reads `stood` before it handles another
     * place here, published after the write, or at the call's end, after quit: so the leader
     * reads none of a helper's counts (settle) */
    uint64_t stood;
    bool pending;
    /* a rebuild of one list (walk): near holds the new list, gain[k] set for the entries i's
     * old list lacked; was holds the old list (n_was entries), kept[k] set for those found
     * again */
    uint32_t *near, *was;   /* owned, room for cap each */
    uint8_t *kept, *gain;   /* owned, room for cap each */
    size_t cap, n_near, n_was;
    nbep_vec3 at;           /* the new list's centre, and its cell (nbep_cells_locate) */
    size_t at_cell;
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
    /* one per ring slot of the team loop and thread, the leader's [0] and helper t's [t]
     * (t < team): a place's workspace is its taker's, written by it alone, so that its lines
     * pass to another core only where the leader reads what a helper handled (one thread:
     * ws[0][0]) */
    evl_ws ws[NBEP_EVLOOP_TEAM_MAX][NBEP_EVLOOP_RING];
    int team;             /* the threads that may run the loop together (create) */
    int crew;             /* the leader's alone: the threads of this call (run_lead) */
    nbep_periodic pb;     /* the box's periodic geometry */
    double cut;           /* the list cutoff: contact distance plus skin, plus slack */
    double stray;         /* half the skin: how far a sphere goes before its list expires */
    double face_reach;    /* cut + stray, and a margin: see near_face */
    double face_lo[3], face_hi[3]; /* near_face's faces: a periodic axis's low and high
                                    * sides, -inf and +inf on any other */
    bool failed;          /* out of memory for a list: the run stops */
    nbep_feq *q;          /* borrowed */
    const uint64_t *ver;  /* borrowed */
    /* the team loop's window: the places handled ahead and not yet committed, numbered in
     * order (place s lives in ring slot s % NBEP_EVLOOP_RING). Written by the leader and read
     * by both threads: each one's sphere, the other sphere its slot names (a pair's partner,
     * fresh or stale; NO_SPHERE for a plane or an expiry), and whether it was the calendar's
     * earliest when the window was empty (it stands, and is neither kept nor checked) */
    alignas(NBEP_CACHELINE) uint32_t batch[NBEP_EVLOOP_RING];
    uint32_t batch_other[NBEP_EVLOOP_RING];
    bool batch_first[NBEP_EVLOOP_RING];
    /* the leader's alone (a line that another core reads makes each write to it wait): the
     * list centres of the window's spheres as floats (place p's own at 2 (p % WINDOW), its
     * other's next; +inf for none), for the places that join (place_apart); whether each
     * place is a list expiry (its handle walks the cells around its sphere and its commit
     * changes them) and then the cell coordinates of its list centre; each place's calendar
     * entry, taken out while it is in flight, and the window's last (cur); the window, places
     * head .. tail - 1, more looked for once head reaches fill_at */
    alignas(NBEP_CACHELINE) float taken_x[2 * WINDOW];
    alignas(NBEP_CACHELINE) float taken_y[2 * WINDOW];
    alignas(NBEP_CACHELINE) float taken_z[2 * WINDOW];
    float near2;          /* the square of the distance beyond which two events touch nothing
                           * in common, for those float centres (set_near2) */
    float len_f[3], half_f[3]; /* the periodic sides and their halves (+inf: not periodic) */
    double shore;         /* how far a centre is taken past a side that is not periodic */
    bool batch_walks[NBEP_EVLOOP_RING];
    size_t batch_cell[NBEP_EVLOOP_RING][3];
    nbep_calendar_entry batch_entry[NBEP_EVLOOP_RING], cur;
    uint64_t head, tail, fill_at;
    uint64_t lead_seen;   /* the leader's last reading of avail (take_one) */
    /* the hand-over: the leader publishes places up to avail; any thread of the team takes
     * the next place to handle from `next` and marks it handled (its number, in its
     * workspace's `place`); the leader posts the end of a call in quit (the call's number),
     * helper t answers it in done[t].word */
    alignas(NBEP_CACHELINE) _Atomic uint64_t avail;
    alignas(NBEP_CACHELINE) _Atomic uint64_t next;
    alignas(NBEP_CACHELINE) _Atomic uint64_t quit;
    struct {
        alignas(NBEP_CACHELINE) _Atomic uint64_t word;
    } done[NBEP_EVLOOP_TEAM_MAX];
};

_Static_assert(offsetof(evl_ws, next_key) + sizeof((evl_ws *)0)->next_key <= NBEP_CACHELINE,
               "what a commit reads first is on one cache line");

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

/* The reach the cells are laid out for: cells_init makes sides of 1.125 times the reach it is
 * given, for the hysteresis of moving members (cells.h); list centres stay put between
 * rebuilds, so sides of the cutoff itself suffice: a 27-cell block a third smaller to scan at
 * each rebuild. */
static double cells_reach(const nbep_evloop *e)
{
    return e->cut / 1.125;
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
        st = nbep_cells_init(&e->cells, lo, hi, cells_reach(e), n, periodic, d);
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
    return nbep_cells_refit(&e->cells, lo, hi, cells_reach(e), d);
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

void nbep_evloop_destroy(nbep_evloop **e)
{
    if (!e || !*e)
        return;
    nbep_calendar_destroy(&(*e)->cal);
    nbep_cells_fini(&(*e)->cells);
    nbep_nblist_fini(&(*e)->nl);
    nbep_free_aligned((*e)->count);
    for (int t = 0; t < NBEP_EVLOOP_TEAM_MAX; t++) /* (those never made are zero) */
        for (int k = 0; k < NBEP_EVLOOP_RING; k++)
            ws_fini(&(*e)->ws[t][k]);
    nbep_free_aligned(*e);
    *e = NULL;
}

size_t nbep_evloop_bytes(size_t n, double neighbours)
{
    return sizeof(nbep_evloop) + nbep_calendar_bytes(n) + nbep_cells_bytes(n) +
           nbep_nblist_bytes(n, (size_t)(neighbours * (double)n)) +
           n * sizeof(uint32_t);
}

bool nbep_evloop_failed(const nbep_evloop *e)
{
    return e->failed;
}

/* Calls f(e, i, j, arg) for every sphere j != i whose place is within the cutoff of ci, from
 * the 27-cell block of cell `cell` (each at its image across periodic faces). Reads the cells
 * only. A cell of the block whose slab is farther than the cutoff from ci (nbep_cells_gap2) is
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
    const double cut2 = e->cut * e->cut;
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
            near[nn] = j;
            nn += (dx * dx + dy * dy + dz * dz < cut2) & (j != i);
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
    w->at_cell = nbep_cells_locate(&e->cells, c);
    near_centres(e, i, c, w->at_cell, gather_one, w);
}

/* The walk on w entered: its sphere placed at the new centre (in the cell the walk found); it
 * enters the lists of the neighbours it gains and leaves those of the ones it loses; those it
 * keeps (most: it moved by half a skin) are not touched. One thread, no other walking. */
static void apply(nbep_evloop *e, const evl_ws *w)
{
    const uint32_t i = w->item;
    nbep_cells_place(&e->cells, i, w->at, w->at_cell);
    for (size_t k = 0; k < w->n_near && !e->failed; k++)
        if (w->gain[k] && !nbep_nblist_append(&e->nl, w->near[k], i))
            e->failed = true;
    for (size_t k = 0; k < w->n_was; k++)
        if (!w->kept[k]) /* lost */
            nbep_nblist_drop(&e->nl, w->was[k], i);
    if (!nbep_nblist_set(&e->nl, i, w->near, e->failed ? 0 : w->n_near))
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
    *c = (nbep_calendar_entry){ev->time, slot_key(i, ev), i};
    return ev->kind == NBEP_EVENT_SPHERE || ev->kind == NBEP_EVENT_PLANE ||
           ev->kind == NBEP_EVENT_HORIZON;
}

/* Entry c set in the calendar, or its item's taken out (set false). */
static void enter(nbep_evloop *e, bool set, nbep_calendar_entry c)
{
    if (set)
        nbep_calendar_set(e->cal, c.item, c.time, c.key);
    else
        nbep_calendar_remove(e->cal, c.item);
}

/* The calendar entry of sphere i from its slot. */
static void schedule_one(nbep_evloop *e, uint32_t i)
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
    nbep_calendar_clear(e->cal);
    for (size_t i = 0; i < e->n; i++)
        schedule_one(e, (uint32_t)i);
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
        if (w->changed[k] != w->item)
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
static void handle(nbep_evloop *e, evl_ws *w, const nbep_evloop_ops *ops, void *u, uint32_t i,
                   const nbep_event *ev, double t)
{
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
        if (w->oom)
            return;
        w->rebuilt = true;
        w->at = c;
        predict_with(e, ops, u, i, t, w->near, w->n_near, c);
        note_next(e, w);
        NBEP_EVLOOP_HANDLED_HOOK(e, w, ev);
        return;
    }
    if (ev->kind == NBEP_EVENT_SPHERE) /* read if the event is fresh */
        prefetch_list(e, ev->partner);
    if (ops->fresh(u, i, ev)) {
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
            if (w->changed[k] != i)
                predict_one(e, ops, u, w->changed[k], t);
    }
    /* in every other case (stale slot, reaction) i looks again from now */
    predict_one(e, ops, u, i, t);
    note_next(e, w);
    NBEP_EVLOOP_HANDLED_HOOK(e, w, ev);
}

/* What handle left waiting: the new list entered, the changed spheres' calendar entries set. */
static void commit(nbep_evloop *e, const evl_ws *w)
{
    if (w->oom)
        e->failed = true;
    if (w->rebuilt)
        apply(e, w);
    if (e->failed)
        return;
    if (w->n_next != NEXT_ALL) {
        for (size_t k = 0; k < w->n_next; k++)
            enter(e, w->next_set[k],
                  (nbep_calendar_entry){w->next_time[k], w->next_key[k], w->next_item[k]});
        return;
    }
    for (size_t k = 0; k < w->n_changed; k++)
        if (w->changed[k] != w->item)
            schedule_one(e, w->changed[k]);
    schedule_one(e, w->item);
}

/* Whether the commit of the event handled on w set sphere j's calendar entry. */
static bool commit_sets(const evl_ws *w, uint32_t j)
{
    bool set = j == w->item;
    if (w->n_next != NEXT_ALL)
        for (size_t k = 0; k < w->n_next; k++)
            set |= w->next_item[k] == j;
    else
        for (size_t k = 0; k < w->n_changed; k++)
            set |= w->changed[k] == j;
    return set;
}

/* Counts one event at time t towards the stall check: false when st->events events in a row
 * have not advanced time by more than st->dt. */
static bool advances(nbep_evloop_stall *st, double t)
{
    if (++st->since >= st->events) {
        if (!(t - st->t_mark > st->dt))
            return false;
        st->t_mark = t;
        st->since = 0;
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
    nbep_calendar_runners_up(e->cal, next, NULL, &n_next);
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
                     nbep_evloop_stall *stall, nbep_evloop_tally *tally, double *t_stuck)
{
    if (e->failed) /* a rebuild ran out of memory */
        return false;
    evl_ws *w = &e->ws[0][0];
    uint32_t i;
    double t;
    while (nbep_calendar_top(e->cal, &i, &t) && t < t_end) {
        const nbep_event ev = *nbep_feq_slot(e->q, i);
        prefetch_event(e, i, &ev);
        tally->events++;
        if (!advances(stall, t)) {
            *t_stuck = t;
            return false;
        }
        handle(e, w, ops, u, i, &ev, t);
        count_handled(tally, w);
        if (w->stop) {
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

#define NO_SPHERE UINT32_MAX
#define RING NBEP_EVLOOP_RING
_Static_assert((RING & (RING - 1)) == 0, "the ring's size is a power of 2");

_Static_assert(WINDOW <= RING, "a window fits the ring");
/* The window is filled again once this many of its slots are free, not after every commit
 * (2 to 8 ran within the noise of each other; filling whenever the helper had at most 2 or 4
 * places left to take, which reads its counter's line each commit, no better). */
#define FILL_FREE 2

/* A list centre as place_apart's floats (set_near2): from the box's low corner, clamped to
 * `shore` past a side that is not periodic. */
static void float_centre(const nbep_evloop *e, nbep_vec3 c, float *f)
{
    const double x[3] = {c.x - e->pb.lo[0], c.y - e->pb.lo[1], c.z - e->pb.lo[2]};
    for (int k = 0; k < 3; k++)
        f[k] = (float)(e->pb.axis[k] ? x[k]
                                     : fmin(fmax(x[k], -e->shore), e->pb.len[k] + e->shore));
}

/* How many of the centres taken at ring entries [lo, hi) are near centre a or centre b
 * (set_near2: within the distance beyond which events on them touch nothing in common), in a
 * periodic box the nearest way round: 0 when events on their spheres and on a's and b's touch
 * nothing in common (an event with one sphere passes it twice). Without branches, the taken
 * centres read once for both. A free ring slot's centres are +inf, far from every centre. */
static inline NBEP_ALWAYS_INLINE int near_span(const nbep_evloop *e, const float *a,
                                               const float *b, size_t lo, size_t hi)
{
    const float hx = e->half_f[0], hy = e->half_f[1], hz = e->half_f[2];
    const float lx = e->len_f[0], ly = e->len_f[1], lz = e->len_f[2];
    const float near2 = e->near2;
    const float *restrict tx = e->taken_x, *restrict ty = e->taken_y, *restrict tz = e->taken_z;
    int near = 0;
    for (size_t k = lo; k < hi; k++) {
        float dx = fabsf(a[0] - tx[k]), dy = fabsf(a[1] - ty[k]), dz = fabsf(a[2] - tz[k]);
        float ex = fabsf(b[0] - tx[k]), ey = fabsf(b[1] - ty[k]), ez = fabsf(b[2] - tz[k]);
        dx = dx > hx ? lx - dx : dx; /* half is +inf on an axis that is not periodic */
        dy = dy > hy ? ly - dy : dy;
        dz = dz > hz ? lz - dz : dz;
        ex = ex > hx ? lx - ex : ex;
        ey = ey > hy ? ly - ey : ey;
        ez = ez > hz ? lz - ez : ez;
        near += !(dx * dx + dy * dy + dz * dz > near2);
        near += !(ex * ex + ey * ey + ez * ez > near2);
    }
    return near;
}

/* near_span over every entry (a free one's are +inf): one pass of a fixed length, in floats,
 * 16 a vector (this test over the window's centres in doubles, in runs that followed the
 * window round the ring, was a tenth of the leader's time). */
NBEP_AVX512_CLONES static int near_count(const nbep_evloop *e, const float *a, const float *b)
{
    return near_span(e, a, b, 0, 2 * WINDOW);
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

/* The list centres of place s's sphere (own) and of the other its slot names (other; its
 * own again when it names none), as place_apart's floats. */
static void place_centres(const nbep_evloop *e, uint64_t s, float *own, float *other)
{
    const size_t k = s % RING;
    float_centre(e, e->cells.m[e->batch[k]].at, own);
    for (int q = 0; q < 3; q++)
        other[q] = own[q];
    if (e->batch_other[k] != NO_SPHERE)
        float_centre(e, e->cells.m[e->batch_other[k]].at, other);
}

/* Whether the places at ring slots a and k are both list expiries whose cells are not apart
 * (only an expiry reads the cells of other spheres, in its walk, and only an expiry's commit
 * changes cells). */
static bool cells_clash(const nbep_evloop *e, size_t a, size_t k)
{
    return e->batch_walks[a] && e->batch_walks[k] &&
           !cells_apart(e, e->batch_cell[a], e->batch_cell[k]);
}

/* Whether place s (set, not yet in the window; own and other its centres, place_centres) is
 * apart from every place in flight: both its spheres (the one whose entry it is and the other
 * its slot names) clear of both of each one's, and no clash of cells (cells_clash; an
 * expiry's slot names no other sphere). When it is not, *after is the last place it touches,
 * whose commit it must wait for. The window's centres in one pass, and the cells of those
 * that walk when s walks; the place it touches, place by place, only when that finds one (a
 * place in every hundred at N = 256000, phi 0.30, where two in five of those that join
 * walk). */
static bool place_apart(const nbep_evloop *e, uint64_t s, const float *own, const float *other,
                        uint64_t *after)
{
    const size_t a = s % RING;
    bool apart = !near_count(e, own, other);
    if (apart && e->batch_walks[a])
        for (uint64_t p = e->head; p < e->tail; p++)
            apart &= !cells_clash(e, a, p % RING);
    if (apart)
        return true;
    *after = e->tail - 1; /* (the loop finds one: what the pass found is one place's) */
    for (uint64_t p = e->head; p < e->tail; p++)
        if (cells_clash(e, a, p % RING) ||
            near_span(e, own, other, 2 * (p % WINDOW), 2 * (p % WINDOW) + 2))
            *after = p;
    return false;
}

/* Place p's centres as place_apart's arrays hold them (at 2 (p % WINDOW) and the next: the
 * places in flight are at most WINDOW consecutive numbers): own and other (NULL: none, +inf,
 * far from every centre). */
static void put_centres(nbep_evloop *e, uint64_t p, const float *own, const float *other)
{
    static const float none[3] = {INFINITY, INFINITY, INFINITY};
    const float *c[2] = {own ? own : none, other ? other : none};
    const size_t j = 2 * (p % WINDOW);
    for (int q = 0; q < 2; q++) {
        e->taken_x[j + q] = c[q][0];
        e->taken_y[j + q] = c[q][1];
        e->taken_z[j + q] = c[q][2];
    }
}

/* Place s is the calendar entry c: its sphere, the other sphere its key names, whether it is
 * a list expiry (walks), and then the cell of its list centre. */
static void set_place(nbep_evloop *e, uint64_t s, nbep_calendar_entry c, bool first)
{
    const size_t k = s % RING;
    const uint32_t other = key_other(c.key, c.item);
    const bool walks = key_expiry(c.key, c.item);
    e->batch[k] = c.item;
    e->batch_walks[k] = walks;
    e->batch_first[k] = first;
    e->batch_other[k] = other < e->n ? other : NO_SPHERE;
    e->batch_entry[k] = c;
    if (walks)
        cell_xyz(e, c.item, e->batch_cell[k]);
}

/* The place set at the window's tail (own and other its centres, place_centres) joins it: its
 * centres taken, its entry and its other sphere's taken out of the calendar (no place joins
 * on a sphere in flight: its entry is not there to be found; the other's comes after this
 * one, as every entry left does, and the place's commit or undo sets it again). */
static void join(nbep_evloop *e, const float *own, const float *other)
{
    const size_t k = e->tail % RING;
    NBEP_EVLOOP_JOIN_HOOK(e);
    put_centres(e, e->tail, own, e->batch_other[k] != NO_SPHERE ? other : NULL);
    e->cur = e->batch_entry[k];
    nbep_calendar_remove(e->cal, e->batch[k]);
    if (e->batch_other[k] != NO_SPHERE)
        nbep_calendar_remove(e->cal, e->batch_other[k]);
    e->tail++;
}

/* Place s leaves the window (committed or undone): its centres are no longer taken. */
static void drop_place(nbep_evloop *e, uint64_t s)
{
    put_centres(e, s, NULL, NULL);
}

/* Requests the list centres of the spheres of the calendar entry (item, key) (no effect on
 * results): place_apart reads them. */
static void prefetch_centres(const nbep_evloop *e, uint32_t item, uint64_t key)
{
    NBEP_PREFETCH(&e->cells.m[item]);
    const uint32_t o = key_other(key, item);
    if (o < e->n) {
        NBEP_PREFETCH(&e->cells.m[o]);
        nbep_calendar_prefetch(e->cal, o); /* join takes its entry out */
    }
}

/* Requests the centres of the calendar's runners-up (no effect on results): fill reads them
 * next, or the fill after. */
static void prefetch_next(const nbep_evloop *e)
{
    uint32_t next[2];
    uint64_t keys[2];
    int n_next;
    nbep_calendar_runners_up(e->cal, next, keys, &n_next);
    for (int k = 0; k < n_next; k++)
        prefetch_centres(e, next[k], keys[k]);
}

/* Adds places to the window behind those in flight, from the calendar's earliest entries,
 * which it takes out (a place's entry goes back at its commit or undo, with the others'):
 * each next one that is apart from every place in flight (place_apart: both its spheres, the
 * one whose entry it is and the other its slot names, against both of every place in flight:
 * the other may be far when the slot is stale, and a far sphere must not be read, kept or put
 * back while another event writes it) and comes before t_end (join takes its other sphere's
 * entry out too: the pair's commit or undo sets it again). It stops at the
 * first that is not (it must wait for the commit of what it touches) and sets when to look
 * again (fill_at). An entry before the window's last (`cur`; a commit's new entry) means a
 * place in flight will not stand: nothing is taken until the window is undone. Reads the
 * calendar and the list centres only, which only the leader writes: each place's slot is read
 * by the thread that handles it. */
static void fill(nbep_evloop *e, double t_end)
{
    nbep_calendar_entry c;
    for (;; prefetch_next(e)) {
        if (!nbep_calendar_first(e->cal, &c)) {
            e->fill_at = e->head + 1;
            return;
        }
        if (!nbep_calendar_before(e->cur, c)) {
            e->fill_at = UINT64_MAX;
            return;
        }
        if (e->tail - e->head >= WINDOW) {
            e->fill_at = e->head + 1;
            prefetch_centres(e, c.item, c.key); /* the next fill's first */
            return;
        }
        if (!(c.time < t_end)) {
            e->fill_at = UINT64_MAX;
            return;
        }
        set_place(e, e->tail, c, false);
        float own[3], other[3];
        place_centres(e, e->tail, own, other);
        uint64_t after;
        if (!place_apart(e, e->tail, own, other, &after)) {
            e->fill_at = after + 1;
            return;
        }
        NBEP_PREFETCH(nbep_feq_slot(e->q, c.item));
        NBEP_PREFETCH(&e->nl.sp[c.item]);
        join(e, own, other);
    }
}

/* Requests what place s's handle reads and writes first (no effect on results): the slots,
 * list records and motion (ops prefetch) of its spheres, and when `list`, the first line of
 * its sphere's list, found from the record (which an earlier request should have brought: a
 * record that is not there stalls the thread). The one-thread loop requests the same for the
 * events after the current one (prefetch_event); without it, a team thread met each of these
 * as a miss: the team loop on one core ran 1.23 times the one-thread loop's time. */
static inline NBEP_ALWAYS_INLINE void prefetch_place(const nbep_evloop *e,
                                                     const nbep_evloop_ops *ops,
                                                     void *const *us, uint64_t s, bool list)
{
    const size_t k = s % RING;
    const uint32_t x[2] = {e->batch[k], e->batch_other[k]};
    for (int q = 0; q < 2; q++)
        if (x[q] != NO_SPHERE) {
            NBEP_PREFETCH_W(nbep_feq_slot(e->q, x[q]));
            NBEP_PREFETCH(&e->nl.sp[x[q]]);
            ops->prefetch(us[k], x[q]);
        }
    if (list)
        NBEP_PREFETCH(&e->nl.pool[e->nl.sp[x[0]].off]);
}

/* Keeps on w what the event at ring slot k may change, to undo it: the motion and slot of its
 * sphere and of the other its slot names (fill's batch_other, from the calendar key). */
static void keep(nbep_evloop *e, evl_ws *w, size_t k, const nbep_evloop_ops *ops, void *u)
{
    w->n_kept = 0;
    w->kept_id[w->n_kept++] = e->batch[k];
    if (e->batch_other[k] != NO_SPHERE)
        w->kept_id[w->n_kept++] = e->batch_other[k];
    for (int q = 0; q < w->n_kept; q++) {
        ops->save(u, w->kept_id[q], &w->kept_motion[q]);
        w->kept_slot[q] = *nbep_feq_slot(e->q, w->kept_id[q]);
    }
}

/* A speculative event undone: the spheres it changed as they were, their slots too (the
 * calendar, the lists and the cells were not touched); its counts are never merged (the next
 * place handled on its context clears them). */
static void undo(nbep_evloop *e, const evl_ws *w, const nbep_evloop_ops *ops, void *uk)
{
    for (int k = w->n_kept - 1; k >= 0; k--) {
        ops->restore(uk, w->kept_id[k], &w->kept_motion[k]);
        nbep_feq_put(e->q, w->kept_id[k], w->kept_slot[k]);
    }
}

/* The counts and sums of the place last handled on w (context uw) added to the handler's own
 * (own) if it stood, once: each place's are added by the thread that handled it, whose lines
 * they are, and the run's sums are exact (xsum.h) and its counts integers, so the totals are
 * the one thread's whichever thread adds what, in whatever order. Called by the handler only,
 * once the place is committed or undone. */
static void settle(const nbep_evloop_ops *ops, evl_ws *w, void *own, void *uw)
{
    if (!w->pending)
        return;
    if (w->stood == atomic_load_explicit(&w->place, memory_order_relaxed))
        ops->merge(own, uw);
    w->pending = false;
}

/* settle for each of thread t's workspaces, at the call's end (every place is committed or
 * undone). */
static void settle_all(nbep_evloop *e, const nbep_evloop_ops *ops, void *own, void *const *us,
                       int t)
{
    for (size_t k = 0; k < RING; k++)
        settle(ops, &e->ws[t][k], own, us[k]);
}

/* Takes the next published place to handle and handles it on the workspace of thread t (0
 * the leader, t > 0 helper t) and context us of its slot: false when none is left. *seen is
 * the calling thread's last reading of avail, read again only when the next place is past it
 * (avail never goes down, and a place below it was published before that reading: an undo
 * moves `next` to the window's tail, past every place it withdrew), so that a thread meets
 * the leader's line once for several places. */
static bool take_one(nbep_evloop *e, const nbep_evloop_ops *ops, void *own, void *const *us,
                     uint64_t *seen, int t)
{
    uint64_t v = atomic_load_explicit(&e->next, memory_order_relaxed), n = *seen;
    do {
        if (v >= n) { /* the places up to n */
            n = *seen = atomic_load_explicit(&e->avail, memory_order_acquire);
            if (v >= n)
                return false;
        }
    } while (!atomic_compare_exchange_weak_explicit(&e->next, &v, v + 1, memory_order_relaxed,
                                                    memory_order_relaxed));
    if (v + 1 < n)
        prefetch_place(e, ops, us, v + 1, true);
    if (v + 2 < n)
        prefetch_place(e, ops, us, v + 2, false);
    const size_t k = v % RING;
    /* its slot, as the calendar entry that made it a place was set from: no place in flight
     * writes it (the places are apart), so the copy is the taker's own, read here */
    const nbep_event ev = *nbep_feq_slot(e->q, e->batch[k]);
    evl_ws *w = &e->ws[t][k];
    /* the place handled here before (v - RING at the latest) is committed or undone: v is
     * below *seen, a value of avail this thread read with acquire (maybe in an earlier take),
     * which the leader stored with release once that place had left the window */
    settle(ops, w, own, us[k]);
    if (!e->batch_first[k]) /* every other place may be undone */
        keep(e, w, k, ops, us[k]);
    ops->clear(us[k]); /* its counts from zero, on this thread */
    handle(e, w, ops, us[k], e->batch[k], &ev, ev.time);
    w->pending = true;
    atomic_store_explicit(&w->place, v, memory_order_release);
    return true;
}

/* Requests a list's record (not deep), or what it leads to (deep): the lines of the list that
 * an entry is appended to or dropped from (no effect on results). */
static inline NBEP_ALWAYS_INLINE void prefetch_record(const nbep_evloop *e, uint32_t j,
                                                     bool deep)
{
    if (!deep) {
        NBEP_PREFETCH_W(&e->nl.sp[j]);
        return;
    }
    const nbep_nblist_span sp = e->nl.sp[j];
    NBEP_PREFETCH_W(&e->nl.pool[sp.off]);
    if (sp.cnt > 0)
        NBEP_PREFETCH_W(&e->nl.pool[sp.off + sp.cnt - 1]);
}

/* Requests what the leader's commit of the event handled on w writes (no effect on results),
 * in two stages, the first (not deep) a commit ahead: the calendar's lists that its entries
 * join (the two lines of a set that missed most: its list's head and the entry there) and,
 * for a rebuilt list, the records and then the lists of the spheres whose lists it enters or
 * leaves, and its own. The handle knew them a while before, maybe on another core. */
static void prefetch_commit(const nbep_evloop *e, const evl_ws *w, bool deep)
{
    if (w->n_next != NEXT_ALL)
        for (size_t k = 0; k < w->n_next; k++)
            if (w->next_set[k])
                nbep_calendar_prefetch_set(e->cal, w->next_time[k], deep);
    if (!w->rebuilt)
        return;
    prefetch_record(e, w->item, deep);
    for (size_t k = 0; k < w->n_near; k++)
        if (w->gain[k])
            prefetch_record(e, w->near[k], deep);
    for (size_t k = 0; k < w->n_was; k++)
        if (!w->kept[k])
            prefetch_record(e, w->was[k], deep);
}

/* The thread that handled place s, if it has been handled: 0 the leader, t the helper t, -1
 * not yet. The leader's mark is its own line; a helper's is read with acquire (what its
 * handle wrote is then there to read). */
static int handled_by(const nbep_evloop *e, uint64_t s)
{
    const size_t k = s % RING;
    if (atomic_load_explicit(&e->ws[0][k].place, memory_order_relaxed) == s)
        return 0;
    for (int t = 1; t < e->crew; t++)
        if (atomic_load_explicit(&e->ws[t][k].place, memory_order_acquire) == s)
            return t;
    return -1;
}

/* The leader waits for place s to be handled, handling places meanwhile: the thread that
 * handled it (handled_by). Once none is left to take, it stops looking at `next` until it
 * returns: only the leader publishes places, so none comes meanwhile, and each look would pull
 * the line of the counter that the helpers write as they take each place. */
static int wait_handled(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                        uint64_t s)
{
    int t = handled_by(e, s);
    if (t >= 0)
        return t;
    bool dry = false;
    const int was = phase(PH_HANDLE);
    for (unsigned k = 1; (t = handled_by(e, s)) < 0; k++) {
        if (!dry && take_one(e, ops, u, us, &e->lead_seen, 0))
            continue;
        if (!dry)
            phase(PH_WAIT);
        dry = true;
        nbep_spin_pause(k);
    }
    phase(was);
    return t;
}

/* The calendar entries of place s's spheres set again from their slots (join took them
 * out). */
static void put_back(nbep_evloop *e, uint64_t s)
{
    const size_t k = s % RING;
    schedule_one(e, e->batch[k]);
    if (e->batch_other[k] != NO_SPHERE)
        schedule_one(e, e->batch_other[k]);
}

/* Places s.. of the window undone, and the window emptied (place s - 1, if in it, is the
 * leader's to finish): those not yet taken are taken from the threads (`next` moves past
 * them), those taken are undone once handled. Returns how many were undone. */
static uint64_t undo_from(nbep_evloop *e, const nbep_evloop_ops *ops, void *u,
                          void *const *us, uint64_t s)
{
    const int was = phase(PH_UNDO);
    const uint64_t taken = atomic_exchange_explicit(&e->next, e->tail, memory_order_relaxed);
    for (uint64_t p = s; p < taken; p++) {
        const int t = wait_handled(e, ops, u, us, p);
        undo(e, &e->ws[t][p % RING], ops, us[p % RING]);
    }
    for (uint64_t p = s; p < e->tail; p++) /* the entries taken out go back, as they were */
        put_back(e, p);
    for (uint64_t p = e->head; p < e->tail; p++)
        drop_place(e, p);
    /* the next place is numbered past these: the marks of those taken are theirs */
    e->head = e->fill_at = e->tail;
    phase(was);
    return e->tail - s;
}

/* The window's first place, when nothing is in flight: the calendar's earliest entry c, which
 * stands (the one thread would handle it next, from the same state). */
static void start(nbep_evloop *e, nbep_calendar_entry c, double t_end)
{
    set_place(e, e->tail, c, true);
    float own[3], other[3];
    place_centres(e, e->tail, own, other);
    join(e, own, other);
    fill(e, t_end);
}

static bool lead(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                 double t_end, nbep_evloop_stall *stall, nbep_evloop_tally *tally,
                 double *t_stuck)
{
    for (;;) {
        if (e->head == e->tail) {
            phase(PH_START);
            nbep_calendar_entry c;
            if (!(nbep_calendar_first(e->cal, &c) && c.time < t_end))
                return true;
            const nbep_event ev = *nbep_feq_slot(e->q, c.item);
            prefetch_event(e, c.item, &ev);
            if (!advances(stall, c.time)) {
                tally->events++;
                *t_stuck = c.time;
                return false;
            }
            start(e, c, t_end);
            atomic_store_explicit(&e->avail, e->tail, memory_order_release);
        }
        /* the places in order, as they are handled: each stands when it is then the earliest
         * (the one thread would handle it next, from the same state: no event before it
         * touched its spheres) */
        phase(PH_STAND);
        const uint64_t s = e->head;
        const size_t k = s % RING;
        const int by = wait_handled(e, ops, u, us, s);
        evl_ws *w = &e->ws[by][k];
        /* the next place's commit prepared during this one's, when it is handled already */
        const int next_by = s + 1 < e->tail ? handled_by(e, s + 1) : -1;
        const evl_ws *w_next = next_by >= 0 ? &e->ws[next_by][(s + 1) % RING] : NULL;
        if (w_next)
            prefetch_commit(e, w_next, false);
        if (!e->batch_first[k]) {
            /* the calendar holds every entry but those of the window's places and their
             * others, which all come after this one: it is the earliest if the calendar's
             * earliest comes after it */
            nbep_calendar_entry top;
            const double tm = e->batch_entry[k].time;
            if (nbep_calendar_first(e->cal, &top) &&
                nbep_calendar_before(top, e->batch_entry[k])) {
                tally->undone += undo_from(e, ops, u, us, s);
                continue;
            }
            if (!advances(stall, tm)) {
                undo_from(e, ops, u, us, s);
                tally->events++;
                *t_stuck = tm;
                return false;
            }
        }
        /* it stands: counted, and its counts and sums are its handler's to add (settle) */
        tally->events++;
        count_handled(tally, w);
        w->stood = s;
        if (w->stop) { /* its reaction stopped the run: as the one thread stops after it
                        * (nbep_evloop_run), its changes kept, nothing after it (a speculative
                        * place's stop that does not stand is undone with it, never seen here) */
            undo_from(e, ops, u, us, s + 1);
            nbep_calendar_set(e->cal, e->batch[k], e->batch_entry[k].time,
                              e->batch_entry[k].key); /* its entry back, as it was */
            if (e->batch_other[k] != NO_SPHERE) /* and its other's, from its slot */
                schedule_one(e, e->batch_other[k]);
            *t_stuck = e->batch_entry[k].time; /* its slot's time */
            return false;
        }
        /* a commit that would make the pool of lists move waits until no list is read */
        if (w->rebuilt &&
            nbep_nblist_spare(&e->nl) < nbep_nblist_need(&e->nl, w->n_near, w->n_near))
            for (uint64_t p = s + 1; p < e->tail; p++)
                wait_handled(e, ops, u, us, p);
        phase(PH_COMMIT);
        commit(e, w);
        if (e->failed) {
            undo_from(e, ops, u, us, s + 1);
            return false;
        }
        /* its other's entry back if the reaction did not set it (a stale slot's other) */
        if (e->batch_other[k] != NO_SPHERE && !commit_sets(w, e->batch_other[k]))
            schedule_one(e, e->batch_other[k]);
        tally->ahead += !e->batch_first[k];
        if (w_next)
            prefetch_commit(e, w_next, true);
        drop_place(e, s);
        e->head++;
        /* more places, once the threads are about to run out of them (a guess that changes
         * only what is handled ahead, never what stands) */
        if (e->head < e->tail && e->head >= e->fill_at &&
            e->tail - e->head <= WINDOW - FILL_FREE) {
            phase(PH_FILL);
            fill(e, t_end);
            atomic_store_explicit(&e->avail, e->tail, memory_order_release);
        }
    }
}

bool nbep_evloop_run_lead(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                          int crew, uint64_t call, double t_end, nbep_evloop_stall *stall,
                          nbep_evloop_tally *tally, double *t_stuck)
{
    assert(crew >= 2 && crew <= e->team && call > 0);
    e->crew = crew;
    phase(PH_START);
    bool ok = !e->failed && lead(e, ops, u, us, t_end, stall, tally, t_stuck);
    phase(PH_COUNT); /* out of the loop */
    settle_all(e, ops, u, us, 0);
    /* the helpers return (each has handled every place it took: each was waited for), each
     * with the counts and sums of the places it handled that stood added to its own */
    atomic_store_explicit(&e->quit, call, memory_order_release);
    for (int t = 1; t < crew; t++)
        for (unsigned k = 1; atomic_load_explicit(&e->done[t].word, memory_order_acquire) != call;
             k++)
            nbep_spin_pause(k);
    return ok;
}

void nbep_evloop_help(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                      int t, uint64_t call)
{
    assert(t >= 1 && t < e->team && call > 0);
    uint64_t avail_seen = 0;
    for (unsigned k = 1;; k++) {
        if (take_one(e, ops, u, us, &avail_seen, t)) {
            k = 0;
            continue;
        }
        /* the leader may have ended the call before this thread came: quit names it, and
         * no earlier call (a helper that sat out calls finds theirs there) */
        if (atomic_load_explicit(&e->quit, memory_order_acquire) == call) {
            settle_all(e, ops, u, us, t); /* the leader wrote every `stood` before quit */
            atomic_store_explicit(&e->done[t].word, call, memory_order_release);
            return;
        }
        nbep_spin_pause(k);
    }
}
