/* The cells engine's team loop (nbep_evloop_run_lead, nbep_evloop_help: evloop.h; README,
 * Threads on dense scenes): the leader fills a window of places, the calendar's next events
 * that touch nothing in common, which any thread of the team handles ahead of its turn; the
 * leader commits them in the calendar's order, undoing any that an earlier entry overtakes, so
 * that the results are the one-thread loop's (evloop.c) bit for bit. */
#include "evloop_impl.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

/* A look at the window each time a place joins it (places head .. tail - 1 in flight, place
 * tail joining): tests/test_evloop_apart.c compiles its own copy of this file with a check of
 * the places' apartness by means of its own; a build of nbep has nothing here. */
#ifndef NBEP_EVLOOP_JOIN_HOOK
#define NBEP_EVLOOP_JOIN_HOOK(e) ((void)0)
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
    float_centre(e, e->cells.m[e->batch[k].item].at, own);
    for (int q = 0; q < 3; q++)
        other[q] = own[q];
    if (e->batch[k].other != NO_SPHERE)
        float_centre(e, e->cells.m[e->batch[k].other].at, other);
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
    const uint32_t other = nbep__evloop_key_other(c.key, c.item);
    const bool walks = nbep__evloop_key_expiry(c.key, c.item);
    e->batch[k] = (evl_place){.item = c.item, .other = other < e->n ? other : NO_SPHERE,
                              .first = first};
    e->batch_walks[k] = walks;
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
    put_centres(e, e->tail, own, e->batch[k].other != NO_SPHERE ? other : NULL);
    e->cur = e->batch_entry[k];
    nbep_calendar_remove(e->cal, e->batch[k].item);
    if (e->batch[k].other != NO_SPHERE)
        nbep_calendar_remove(e->cal, e->batch[k].other);
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
    const uint32_t o = nbep__evloop_key_other(key, item);
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
    const uint32_t x[2] = {e->batch[k].item, e->batch[k].other};
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
    w->kept_id[w->n_kept++] = e->batch[k].item;
    if (e->batch[k].other != NO_SPHERE)
        w->kept_id[w->n_kept++] = e->batch[k].other;
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
    const nbep_event ev = *nbep_feq_slot(e->q, e->batch[k].item);
    evl_ws *w = &e->ws[t][k];
    /* the place handled here before (v - RING at the latest) is committed or undone: v is
     * below *seen, a value of avail this thread read with acquire (maybe in an earlier take),
     * which the leader stored with release once that place had left the window */
    settle(ops, w, own, us[k]);
    if (!e->batch[k].first) /* every other place may be undone */
        keep(e, w, k, ops, us[k]);
    ops->clear(us[k]); /* its counts from zero, on this thread */
    nbep__evloop_handle(e, w, ops, us[k], e->batch[k].item, &ev, ev.time, false);
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
    nbep__evloop_schedule_one(e, e->batch[k].item);
    if (e->batch[k].other != NO_SPHERE)
        nbep__evloop_schedule_one(e, e->batch[k].other);
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
            nbep__evloop_prefetch_event(e, c.item, &ev);
            if (!nbep__evloop_advances(stall, c.time)) {
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
        if (!e->batch[k].first) {
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
            if (!nbep__evloop_advances(stall, tm)) {
                undo_from(e, ops, u, us, s);
                tally->events++;
                *t_stuck = tm;
                return false;
            }
        }
        /* it stands: counted, and its counts and sums are its handler's to add (settle) */
        tally->events++;
        nbep__evloop_count_handled(tally, w);
        w->stood = s;
        if (w->stop) { /* its reaction stopped the run: as the one thread stops after it
                        * (nbep_evloop_run), its changes kept, nothing after it (a speculative
                        * place's stop that does not stand is undone with it, never seen here) */
            undo_from(e, ops, u, us, s + 1);
            nbep_calendar_set(e->cal, e->batch[k].item, e->batch_entry[k].time,
                              e->batch_entry[k].key); /* its entry back, as it was */
            if (e->batch[k].other != NO_SPHERE) /* and its other's, from its slot */
                nbep__evloop_schedule_one(e, e->batch[k].other);
            *t_stuck = e->batch_entry[k].time; /* its slot's time */
            return false;
        }
        /* a commit that would make the pool of lists move waits until no list is read */
        if (w->rebuilt &&
            nbep_nblist_spare(&e->nl) < nbep_nblist_need(&e->nl, w->n_near, w->n_near))
            for (uint64_t p = s + 1; p < e->tail; p++)
                wait_handled(e, ops, u, us, p);
        phase(PH_COMMIT);
        nbep__evloop_commit(e, w);
        if (e->failed) {
            undo_from(e, ops, u, us, s + 1);
            return false;
        }
        /* its other's entry back if the reaction did not set it (a stale slot's other) */
        if (e->batch[k].other != NO_SPHERE && !nbep__evloop_commit_sets(w, e->batch[k].other))
            nbep__evloop_schedule_one(e, e->batch[k].other);
        tally->ahead += !e->batch[k].first;
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
    if (e->sched) { /* the scheduled loop's slabs on threads (evloop_warp.c) */
        if (!e->failed)
            return nbep__evloop_run_scheduled(e, ops, u, crew, call, t_end, stall, tally,
                                              t_stuck);
        nbep_evloop_release(e, call); /* (its helpers wait for the call's end) */
        return false;
    }
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
    if (e->sched) {
        nbep__evloop_sched_help(e, t, call);
        return;
    }
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
