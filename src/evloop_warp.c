/* The cells engine's loop through the optimistic scheduler (nbep_evloop_set_scheduled,
 * NBEP_SCHEDULED): the engine as the scheduler's model, with what a slab must keep of each
 * event to undo it (docs/optimistic-design.md, *The engine on the scheduler*). On one slab: no
 * messages, and no rollbacks but those a test asks for (nbep_warp_roll_back, through the hooks
 * below: tests/test_sched_rollback.c), which call the restore below as a straggler will. With
 * slabs (NBEP_SLABS, the engine's per-slab calendars), on the call's threads (nbep_evloop_run_lead:
 * thread t runs slabs t, t + crew, ... in turns; one thread runs them all): each slab handles
 * its own spheres' entries in a world of its own (nbep_evloop_set_worlds), through a view of
 * the engine of its own (its workspace, its lists' moves in an arena of the pool, its own copy
 * of the cells: ghost.c), and
 * predicts only its own spheres; what its events change in a column beside another slab goes
 * there as a copy, a pair across a face's other sphere to its owner as a write, which predicts
 * it; a message stamped before what a slab has done sends it back; an expiry whose lists and
 * cells reach another slab's ends the window and is done at its meeting, on the lead alone
 * (docs/optimistic-design.md, *The engine on slabs, in turns* and *on threads*;
 * tests/test_sched_slabs.c). */
#include "evloop_impl.h"

#include <assert.h>
#include <math.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/warp.h"

/* The windows a step is cut into (of equal simulated time; a test may ask for fewer, so that
 * its small scenes have events enough in each). */
#ifndef WINDOWS_A_STEP
#define WINDOWS_A_STEP 64
#endif

/* The actions each slab takes in its turn, with slabs (each thread takes its own in turns); a
 * test's copy of this file (tests/test_sched_slabs.c) draws each turn's, and looks at what the
 * scheduler did as the loop is destroyed. */
#ifndef NBEP_SCHED_SLAB_TURN
#define NBEP_SCHED_SLAB_TURN(slab) ((size_t)64)
#endif
#ifndef NBEP_SCHED_DESTROY_HOOK
#define NBEP_SCHED_DESTROY_HOOK(x) ((void)0)
#endif

/* A test's copy of this file (tests/test_sched_rollback.c) runs the scheduler NBEP_SCHED_TURN
 * actions at a time and looks between turns (to roll back), at each event handled and at each
 * window's opening, and at each state restored; a build of nbep runs each window in one turn
 * and has nothing here. */
#ifndef NBEP_SCHED_TURN
#define NBEP_SCHED_TURN SIZE_MAX
#endif
#ifndef NBEP_SCHED_TURN_HOOK
#define NBEP_SCHED_TURN_HOOK(x) ((void)0)
#endif
#ifndef NBEP_SCHED_HANDLED_HOOK
#define NBEP_SCHED_HANDLED_HOOK(x, s) ((void)0)
#endif
#ifndef NBEP_SCHED_OPEN_HOOK
#define NBEP_SCHED_OPEN_HOOK(x) ((void)0)
#endif
/* tests/bench/bench_windows.c looks just before (after 0) and after (1) each meeting's cut, to
 * tell what the cuts undid from what the stragglers did */
#ifndef NBEP_SCHED_CUT_HOOK
#define NBEP_SCHED_CUT_HOOK(x, after) ((void)0)
#endif
#ifndef NBEP_SCHED_RESTORE_HOOK
#define NBEP_SCHED_RESTORE_HOOK(x, item) ((void)0)
#endif

/* The log's items: spheres 0 .. n - 1 (their states), then past them an expiry's list record,
 * a change of the ties' table and the run's counts (KEPT_ITEM(e, KEPT_LIST) ...). */
enum { KEPT_LIST, KEPT_TIE, KEPT_COUNTS };
#define KEPT_ITEM(e, kind) ((uint32_t)(e)->n + (uint32_t)(kind))

/* What the slab's log keeps of a sphere before an event changes it: its motion (the engine's
 * save: a free flight's event changes nothing else of it) and its slot. */
typedef struct {
    nbep_evloop_motion m;
    nbep_event slot;
} kept_sphere;

/* An expiry's list record: the workspace its commit read (copied: the engine's is the next
 * event's) and what the commit recorded. */
typedef struct {
    evl_ws ws;
    evl_unlist rec;
} kept_list;

/* The run's counts before an event: the caller's (ops mark) and the call's own tally and stall
 * count, kept under an item past the ties' (n + 2), so that a rollback counts its undone
 * events once (ops back) */
typedef struct {
    nbep_evloop_mark m;
    uint64_t events, reactions, exits, since;
    double t_mark;
} kept_counts;
_Static_assert(sizeof(kept_counts) <= sizeof(kept_sphere), "the counts fit a keep's room");

/* An entry's stamp where it is not a root: its sphere's (the entry is its calendar entry) */
typedef struct {
    uint32_t item;
    nbep_stamp s;
} tie_stamp;

/* What a change of the ties' table replaced, for a rollback to put back: sphere item's stamp
 * before (had: it had one there). Kept under an item past the expiries', its place as its
 * state (a stamp does not fit a sphere's keep). */
typedef struct {
    uint32_t item;
    bool had;
    nbep_stamp old;
} tie_undo;

/* A message between slabs: a sphere's new motion, from the event (or message) that gave it;
 * a copy for a slab whose spheres' lists hold it, or a write to its owner, which predicts it
 * (a pair across a face: the slab of the entry handled reacts both) */
enum { MSG_COPY, MSG_WRITE };
typedef struct {
    nbep_evloop_motion m;
    uint32_t kind;
} slab_msg;

/* A slab's side of the loop (one slab: side[0], the run's own context and arrays) */
typedef struct {
    nbep_evloop *e;         /* the engine it acts on: with slabs a view of the run's of its
                             * own (struct evl_sched's view), else the run's */
    void *u;                /* its world's context (the callbacks' u) */
    nbep_evloop_stall stall;
    nbep_evloop_tally tally;
    nbep_stamp last;        /* the stamp of the event handled last (its order's check) */
    bool has_last;
    /* blocked: its earliest entry, stamped `held`, is an expiry whose lists and cells reach
     * another slab's, done only at a meeting, between windows; past: it is at or past the
     * window's limit (as next last found them) */
    bool blocked, past;
    nbep_stamp held;
    /* cramped: the expiry stamped `held` found its slab's arena of the lists' pool too small
     * for its commit (sched_handle), and waits for the meeting, which gives it room */
    bool cramped;
    uint64_t cramps;        /* expiries so left, all windows (a test's count) */
    /* stopped: an event of the slab, stamped `stop` (at stop_t), stops the loop (stuck, a
     * reaction's stop; deep: a cascade deeper than a stamp holds, found at that entry, not
     * handled; oom: a walk or a reaction's copy out of memory, the loop failing there as the
     * serial loop's commit fails; handled: the event was handled, a stall's was not); it stands
     * while the slab's log holds it, else a rollback undid it */
    bool stopped, deep, oom, handled;
    nbep_stamp stop;
    double stop_t;
    /* the window's expiries, by their place in it (the log's item for them, past the
     * spheres', keeps that place) */
    kept_list *lists;
    size_t n_lists, cap_lists;
    /* the stamps of the entries made at the time of the event that made them (a tie in time:
     * cascade.h); every other entry's stamp is a root. Few (a cradle's row), those of an older
     * time never looked up (an entry's time is compared), all dropped between windows: every
     * entry they stamped was handled before its window's end (but at a meeting's cut:
     * window_closed). Each change kept (ties_undo,
     * the window's, by place), so that a rollback puts the table back. */
    tie_stamp *ties;
    size_t n_ties, cap_ties;
    tie_undo *ties_undo;
    size_t n_ties_undo, cap_ties_undo;
    /* owned, with slabs, n: the time of the slab's newest event (or message) that changed each
     * sphere of its world near another slab's (near_other), kept (keep_sphere), read-only where
     * none did (-inf); raised as the slab goes, and left as it was by a rollback (so at or past
     * the true one: a late message is taken for one read since more often than it should,
     * never less: sched_late) */
    double *touch;
    double now_t; /* the time of what the slab acts on (the stamp's) */
    /* owned, with slabs, cap_cols: whether each cell column across x is another slab's or
     * beside one (near_other's, made at each call's start: views_from_run) */
    bool *near_col;
    size_t cap_cols;
    /* owned, with slabs: the slab's own copy of the cells (ghost.c), which its view's walks and
     * ownership checks read instead of the run's, so that no slab reads cells another slab's
     * thread writes. Made from the run's at each call's start; exact on the slab's columns and
     * those beside them, kept so by its own expiries (which change only cells of its own that no
     * other slab keeps: an expiry reaching further waits for the meeting) and by the places of
     * the meetings' expiries (meet). The run's cells stay exact too: each expiry in a window
     * places its sphere there as well, in its slab's own cells, which no other thread reads or
     * writes within a window (sched_handle, sched_restore). */
    nbep_cells cells;
} evl_side;

struct evl_sched {
    nbep_warp *warp;
    int slabs;
    evl_side *side;         /* owned, slabs */
    /* owned, with slabs: each slab's view of the engine, a copy of the run's made at each call
     * (nbep_evloop's fields are the run's: its calendars, cells, lists and slots are shared)
     * but for its own: its workspace ws[0][0], its world's response counts (ver), its slab
     * (own_slab), its failure, and its lists' view, whose moves go into an arena of the pool
     * of its own (nbep_nblist_arena), so that slabs may change their own spheres' lists at
     * once; room0: the lists' room when the arenas were handed out */
    nbep_evloop *view;
    size_t room0;
    void *const *wu;        /* borrowed, with slabs: each slab's world (nbep_evloop_set_worlds) */
    const uint64_t *const *wver;
    /* the call's */
    nbep_evloop *e;
    const nbep_evloop_ops *ops;
    void *u;
    nbep_evloop_stall *stall;
    bool stop;           /* no more events: stuck, a reaction's stop or a cascade too deep
                          * (t_stuck) */
    bool too_deep;       /* ... the last: a cascade deeper than a stamp holds */
    double t_stuck;
    uint64_t meetings;   /* expiries done at a meeting (with slabs) */
    uint64_t moves;      /* ... of those, the ones that moved their sphere to another slab */
    unsigned idle_windows; /* windows in a row cut back to keep nothing (meet) */
    double window_end;   /* the window's: a slab's entry held at or past it waits for a later
                          * window */
    /* threads (nbep_evloop_run_lead on slabs): crew of them, thread t running slabs t,
     * t + crew, ... in turns; the lead (thread 0) opens each window and publishes it in `go`
     * (call << 32 | the window's number, from 1; GO_QUIT at the call's end), every thread runs
     * its slabs till the window's work is done (the scheduler's meeting: nbep_warp_run), the
     * helpers count themselves in `arrived`, and the lead then meets on its own */
    int crew;
    alignas(NBEP_CACHELINE) _Atomic uint64_t go;
    alignas(NBEP_CACHELINE) _Atomic int arrived;
    /* the earliest entry held in this window: no slab handles an event at or past it, as the
     * meeting would cut the window back to it anyway (meet). Lowered by any slab's thread
     * under the lock, its time also in limit_t (+inf: none), which a slab reads first, taking
     * the lock only on a tie of times (at_limit); read freely at the meeting */
    alignas(NBEP_CACHELINE) atomic_flag lock;
    _Atomic double limit_t;
    nbep_stamp limit;
};

/* ---- the model's side (warp.h) ------------------------------------------------------------ */

static void lock_limit(struct evl_sched *x)
{
    for (unsigned k = 1; atomic_flag_test_and_set_explicit(&x->lock, memory_order_acquire); k++)
        nbep_spin_pause(k);
}

static void unlock_limit(struct evl_sched *x)
{
    atomic_flag_clear_explicit(&x->lock, memory_order_release);
}

/* Whether the window has a limit (at the meeting, or on the lead between windows) */
static bool has_limit(const struct evl_sched *x)
{
    return atomic_load_explicit(&x->limit_t, memory_order_relaxed) < INFINITY;
}

/* The window's limit lowered to stamp s where it is earlier (or set): no slab handles an event
 * at or past it. Any slab's thread. */
static void limit_to(struct evl_sched *x, const nbep_stamp *s)
{
    lock_limit(x);
    if (!has_limit(x) || nbep_cascade_cmp(s, &x->limit) < 0) {
        nbep_cascade_copy(&x->limit, s);
        atomic_store_explicit(&x->limit_t, s->t, memory_order_relaxed);
    }
    unlock_limit(x);
}

/* Whether stamp s is at or past the window's limit (past: after it). Any slab's thread: a
 * limit lowered meanwhile by another may be missed, which only lets this slab run on further,
 * to be cut back at the meeting (the limit only comes down in a window, so a slab that finds
 * itself at it is so). The stamp is read under the lock only where the times tie. */
static bool at_limit(struct evl_sched *x, const nbep_stamp *s, bool past)
{
    const double lt = atomic_load_explicit(&x->limit_t, memory_order_relaxed);
    if (s->t != lt || lt == INFINITY)
        return s->t > lt;
    lock_limit(x);
    const int c = nbep_cascade_cmp(s, &x->limit);
    unlock_limit(x);
    return past ? c > 0 : c >= 0;
}

/* No more events after slab's event stamped *s (at t; deep: a cascade too deep for its
 * stamps, found at that entry; handled: the event was handled, its reaction done): the slab
 * stops there, and the other slabs go on to it (the
 * limit); at the window's end, if it still stands, the call returns false with t in *t_stuck
 * (meet). */
static void stop_at(struct evl_sched *x, int slab, const nbep_stamp *s, double t, bool deep,
                    bool handled)
{
    evl_side *d = &x->side[slab];
    d->stopped = true;
    d->deep = deep;
    d->oom = false;
    d->handled = handled;
    nbep_cascade_copy(&d->stop, s);
    d->stop_t = t;
    if (x->slabs > 1) /* (one slab stops at its stop: nothing else runs on) */
        limit_to(x, s);
}

/* Whether slab's stop still stands: a rollback to or before its event undid it (a stop found
 * at an entry not handled, too deep, is found again by next where it is still the slab's
 * earliest). */
static bool stop_stands(struct evl_sched *x, int slab)
{
    evl_side *d = &x->side[slab];
    nbep_stamp last;
    if (d->stopped && !d->deep &&
        !(nbep_warp_last(x->warp, slab, &last) && nbep_cascade_cmp(&last, &d->stop) >= 0))
        d->stopped = false;
    return d->stopped;
}

/* Where sphere i's row is in the ties' table; n_ties where it has none. */
static size_t tie_of(const evl_side *d, uint32_t i)
{
    size_t k = 0;
    while (k < d->n_ties && d->ties[k].item != i)
        k++;
    return k;
}

/* Row k out of the ties' table (the last one into its place). */
static void tie_drop(evl_side *d, size_t k)
{
    d->ties[k] = d->ties[--d->n_ties];
}

/* The cell column of sphere i's list centre, and the columns across x. */
static size_t column_of(const nbep_evloop *e, uint32_t i, size_t *columns)
{
    *columns = e->cells.dim[0];
    return e->cells.m[i].cell % *columns;
}

/* Whether the expiry of sphere i at time t, of slab `slab`, reads and writes that slab's
 * lists and cells alone: every column of its span (nbep__evloop_expiry_span) is the slab's. */
static bool expiry_local(const struct evl_sched *x, int slab, uint32_t i, double t)
{
    int lo, hi;
    nbep__evloop_expiry_span(x->side[slab].e, x->ops, x->side[slab].u, i, t, &lo, &hi);
    size_t columns;
    const size_t c = column_of(x->side[slab].e, i, &columns);
    if (hi - lo + 1 > (int)columns) /* (around the whole box: every slab's) */
        return false;
    for (int dc = lo; dc <= hi; dc++) {
        const int s = nbep__evloop_column_slab(x->e, c, dc);
        if (s >= 0 && s != slab)
            return false;
    }
    return true;
}

static bool sched_next(void *arg, int slab, nbep_stamp *s)
{
    struct evl_sched *x = arg;
    evl_side *d = &x->side[slab];
    nbep_evloop *e = d->e;
    d->blocked = d->past = false;
    if (stop_stands(x, slab) && !d->deep)
        return false;
    d->stopped = false; /* (a stop too deep is found again below if it is still there) */
    nbep_calendar_entry c;
    if (e->failed ||
        !(e->slabcal ? nbep_slabcal_top(e->slabcal, slab, &c)
                     : nbep_calendar_top(e->cal, &c.item, &c.time)))
        return false;
    const uint32_t i = c.item;
    const double t = c.time;
    const nbep_event *ev = nbep_feq_slot(e->q, i);
    /* the lines its handle will read requested here, before the stamp's work: what the plain
     * loop requests (its lists, cells, the next two entries) and its spheres' motion, which
     * the handle's keep reads first (without these requests the scheduled loop took 1.3 to 1.4
     * times the plain loop's time at N = 256000, phi = 0.30; with them 1.1:
     * docs/optimistic-design.md, *The lines requested*) */
    nbep__evloop_prefetch_event(e, i, ev);
    if (x->ops->prefetch) {
        x->ops->prefetch(d->u, i);
        if (ev->kind == NBEP_EVENT_SPHERE)
            x->ops->prefetch(d->u, ev->partner);
    }
    const uint64_t key = nbep__evloop_slot_key(i, ev);
    nbep_cascade_set_root(s, t, key, i);
    const size_t k = tie_of(d, i);
    if (k < d->n_ties) { /* made at its maker's time, if for this entry */
        const nbep_stamp *m = &d->ties[k].s;
        if (m->t == t && m->level[m->depth - 1].key == key)
            nbep_cascade_copy(s, m);
    }
    if (!d->has_last) /* (after a rollback: the newest event that stands, if any) */
        d->has_last = nbep_warp_last(x->warp, slab, &d->last);
    /* the order's check: the stamps made where their entries were never go back, but where a
     * cascade at one time is deeper than a stamp holds (made_by), a root stamp does: the loop
     * stops there, too deep (nbep_evloop_too_deep: its own message) */
    if (d->has_last && nbep_cascade_cmp(s, &d->last) < 0) {
        stop_at(x, slab, s, t, true, false);
        return false;
    }
    /* an expiry reaching another slab's lists or cells waits for the meeting (sched_held),
     * and the window ends there for every slab (the limit) */
    if (x->slabs > 1 && t < x->window_end && ev->kind == NBEP_EVENT_HORIZON &&
        !at_limit(x, s, true) &&
        ((d->cramped && nbep_cascade_cmp(s, &d->held) == 0) || !expiry_local(x, slab, i, t))) {
        d->blocked = true;
        nbep_cascade_copy(&d->held, s);
        limit_to(x, s);
    }
    d->past = at_limit(x, s, false);
    return true;
}

/* The slab's earliest entry, which next has just given, is held till the meeting (at or past
 * the window's limit): it acts on what comes before it and then waits. */
static bool sched_held(void *arg, int slab)
{
    const struct evl_sched *x = arg;
    return x->side[slab].past;
}

/* Sphere j's new entry, made by the event stamped *by: its stamp kept where it is not a root
 * (at by's time), in place of any older one of j's. Where that stamp would be deeper than
 * NBEP_CASCADE_DEPTH (a cascade at one time through more than 8 spheres) none is kept: the
 * entry's root stamp then comes before the event that made it, and the next stops the loop
 * there (its order's check). What it replaces kept in the slab's log (keep: inside a window;
 * at a meeting nothing is kept: what it does stands). False without memory. */
static bool made_by(struct evl_sched *x, int slab, const nbep_stamp *by, uint32_t j, bool keep)
{
    evl_side *d = &x->side[slab];
    const nbep_event *slot = nbep_feq_slot(d->e->q, j);
    if (slot->time != by->t) /* later: a root (j's older stamp, if any, no longer its entry's) */
        return true;
    const size_t k = tie_of(d, j);
    if (k == d->n_ties &&
        !nbep_room_for_one((void **)&d->ties, &d->cap_ties, k, sizeof *d->ties))
        return false;
    if (keep) { /* what it replaces, kept (under the item past the expiries') */
        uint64_t *place = nbep_room_for_one((void **)&d->ties_undo, &d->cap_ties_undo,
                                            d->n_ties_undo, sizeof *d->ties_undo)
                              ? nbep_warp_keep_room(x->warp, slab, KEPT_ITEM(x->e, KEPT_TIE))
                              : NULL;
        if (!place)
            return false;
        *place = d->n_ties_undo;
        tie_undo *u = &d->ties_undo[d->n_ties_undo++];
        u->item = j;
        u->had = k < d->n_ties;
        if (u->had)
            nbep_cascade_copy(&u->old, &d->ties[k].s);
    }
    if (nbep_cascade_made(by, slot->time, nbep__evloop_slot_key(j, slot), j, &d->ties[k].s)) {
        d->ties[k].item = j;
        d->n_ties += k == d->n_ties;
    } else if (k < d->n_ties) { /* (too deep: j's older stamp is not its entry's either) */
        tie_drop(d, k);
    }
    return true;
}

/* Whether sphere i's list centre lies in a column of another slab or beside one: the spheres
 * whose changes read_since looks at (another slab's, and the slab's own beside its faces). A
 * centre moves into or out of those columns only at a meeting (an expiry moving it there
 * reaches another slab's columns), so within a window the set stays the same. The rest are
 * never noted: their lines, 2 an event, cost more than the rollbacks they would spare (with the
 * first sink's byte-wise turns, 1.1 times the time at N = 256000, where the array is 2 MB a
 * slab). */
static bool near_other(const struct evl_sched *x, int slab, uint32_t i)
{
    size_t columns;
    return x->side[slab].near_col[column_of(x->side[slab].e, i, &columns)];
}

/* Each slab's near_col for the call's columns; false without memory. */
static bool near_cols_make(struct evl_sched *x)
{
    const size_t columns = x->e->cells.dim[0];
    for (int k = 0; k < x->slabs; k++) {
        evl_side *d = &x->side[k];
        if (d->cap_cols < columns) {
            bool *m = realloc(d->near_col, columns * sizeof *m);
            if (!m)
                return false;
            d->near_col = m;
            d->cap_cols = columns;
        }
        for (size_t c = 0; c < columns; c++) {
            d->near_col[c] = false;
            for (int dc = -1; dc <= 1; dc++) {
                const int s = nbep__evloop_column_slab(x->e, c, dc);
                d->near_col[c] |= s >= 0 && s != k;
            }
        }
    }
    return true;
}

/* Sphere i's state into slab's log before the event changes it (its slot too where it is the
 * slab's own: another slab's is its owner's). */
static bool keep_sphere(struct evl_sched *x, int slab, uint32_t i)
{
    kept_sphere *k = nbep_warp_keep_room(x->warp, slab, i);
    if (!k)
        return false;
    evl_side *d = &x->side[slab];
    if (d->touch && near_other(x, slab, i))
        d->touch[i] = d->now_t;
    x->ops->save(d->u, i, &k->m);
    if (nbep__evloop_owned(d->e, i))
        k->slot = *nbep_feq_slot(d->e->q, i);
    return true;
}

/* The counts into the log before the event adds to them (none where the caller keeps none). */
static bool keep_counts(struct evl_sched *x, int slab)
{
    if (!x->ops->mark)
        return true;
    evl_side *d = &x->side[slab];
    kept_counts *k = nbep_warp_keep_room(x->warp, slab, KEPT_ITEM(x->e, KEPT_COUNTS));
    if (!k)
        return false;
    k->events = d->tally.events;
    k->reactions = d->tally.reactions;
    k->exits = d->tally.exits;
    k->since = d->stall.since;
    k->t_mark = d->stall.t_mark;
    return x->ops->mark(d->u, &k->m); /* (false: the record is whole all the same) */
}

/* The room for the window's next expiry record; NULL without memory. */
static kept_list *next_list(evl_side *d)
{
    const size_t cap0 = d->cap_lists;
    if (!nbep_room_for_one((void **)&d->lists, &d->cap_lists, d->n_lists, sizeof *d->lists))
        return NULL;
    /* new records zeroed: their copies' arrays are made at their first use */
    memset(d->lists + cap0, 0, (d->cap_lists - cap0) * sizeof *d->lists);
    return &d->lists[d->n_lists];
}

/* Slab's own sphere i, just changed: its new motion sent as a copy to each other slab whose
 * spheres' lists may hold it (those of the columns beside its own), but `skip`. */
static bool send_copies(struct evl_sched *x, int slab, uint32_t i, int skip)
{
    size_t columns;
    const size_t c = column_of(x->side[slab].e, i, &columns);
    int sent = -1;
    for (int dc = -1; dc <= 1; dc += 2) {
        const int to = nbep__evloop_column_slab(x->e, c, dc);
        if (to < 0 || to == slab || to == skip || to == sent)
            continue;
        slab_msg msg = {.kind = MSG_COPY};
        x->ops->save(x->side[slab].u, i, &msg.m);
        if (!nbep_warp_send(x->warp, slab, to, i, &msg))
            return false;
        sent = to;
    }
    return true;
}

/* What slab's event (its handle on w) changed, told: each own sphere's new motion copied to
 * the slabs beside it, then each other slab's sphere's written to its owner, which predicts
 * it (after the copies, so that the owner predicts it from the event's motion of the rest). */
static bool send_changes(struct evl_sched *x, int slab, const evl_ws *w)
{
    const nbep_evloop *e = x->side[slab].e;
    for (size_t k = 0; k < w->n_changed; k++)
        if (nbep__evloop_owned(e, w->changed[k]) && !send_copies(x, slab, w->changed[k], -1))
            return false;
    for (size_t k = 0; k < w->n_changed; k++) {
        const uint32_t j = w->changed[k];
        if (nbep__evloop_owned(e, j))
            continue;
        slab_msg msg = {.kind = MSG_WRITE};
        x->ops->save(x->side[slab].u, j, &msg.m);
        if (!nbep_warp_send(x->warp, slab, nbep__evloop_sphere_slab(x->e, j), j, &msg))
            return false;
    }
    return true;
}

static void sched_handle(void *arg, int slab, const nbep_stamp *s)
{
    struct evl_sched *x = arg;
    evl_side *d = &x->side[slab];
    nbep_evloop *e = d->e;
    const uint32_t i = s->level[s->depth - 1].item; /* (the entry's: the path's last level) */
    const double t = s->t;
    const nbep_event ev = *nbep_feq_slot(e->q, i);
    NBEP_SCHED_HANDLED_HOOK(x, s);
    nbep_cascade_copy(&d->last, s);
    d->has_last = true;
    d->now_t = t;
    if (!keep_counts(x, slab)) {
        e->failed = true;
        return;
    }
    d->tally.events++;
    if (!nbep__evloop_advances(&d->stall, t)) { /* (as the serial loop: before handling it) */
        stop_at(x, slab, s, t, false, false);
        return;
    }
    /* what it may change: its sphere and, for a pair, the other (a free flight's reaction
     * changes those two alone, as the team loop's undo keeps) */
    if (!keep_sphere(x, slab, i) || (ev.kind == NBEP_EVENT_SPHERE && ev.partner != i &&
                                     !keep_sphere(x, slab, ev.partner))) {
        e->failed = true;
        return;
    }
    evl_ws *w = &e->ws[0][0];
    nbep__evloop_handle(e, w, x->ops, d->u, i, &ev, t, true);
    nbep__evloop_count_handled(&d->tally, w);
    /* (out of memory: the serial loop fails at this event, before its commit, with what came
     * before it done and nothing after; a slab's failure here would end the call with the other
     * slabs wherever they were, ahead of it or behind, so it is a stop, and fails at the
     * meeting where it stands) */
    if (w->stop || w->oom) {
        stop_at(x, slab, s, t, false, true);
        d->oom = w->oom;
        return;
    }
    /* An expiry whose commit may move lists past its slab's arena of the lists' pool (the
     * bound of nblist.h: most never move one) is left undone, its slot put back (what else it
     * did, its counts, the meeting's cut undoes: it is at the limit), and waits for the
     * meeting, which has the pool to itself (meet: the arenas renewed). */
    if (x->slabs > 1 && w->rebuilt &&
        nbep_nblist_spare(&e->nl) < nbep_nblist_need(&e->nl, w->n_near, w->n_near)) {
        nbep_feq_put(e->q, i, ev);
        d->blocked = d->cramped = true;
        d->cramps++;
        nbep_cascade_copy(&d->held, s);
        limit_to(x, s);
        return;
    }
    /* the stamps of the entries it made (as the commit sets them: the changed spheres', then
     * its own; another slab's sphere is its owner's to predict) */
    bool room = true;
    for (size_t k = 0; k < w->n_changed && room; k++)
        room = w->changed[k] == i || !nbep__evloop_owned(e, w->changed[k]) ||
               made_by(x, slab, s, w->changed[k], true);
    if (!room || !made_by(x, slab, s, i, true) ||
        (x->slabs > 1 && w->reacted && !send_changes(x, slab, w))) {
        e->failed = true;
        return;
    }
    if (!w->rebuilt) {
        nbep__evloop_commit(e, w);
        return;
    }
    /* an expiry: its list record kept under an item past the spheres', its place in the
     * window as its state */
    kept_list *l = next_list(d);
    uint64_t *place = l && nbep__evloop_ws_copy_lists(&l->ws, w)
                          ? nbep_warp_keep_room(x->warp, slab, KEPT_ITEM(e, KEPT_LIST))
                          : NULL;
    if (!place) {
        e->failed = true;
        return;
    }
    *place = d->n_lists++;
    nbep__evloop_commit_undoable(e, w, &l->rec);
    if (x->slabs > 1 && !e->failed) /* (the run's cells too: see evl_side's cells) */
        nbep_cells_place(&x->e->cells, i, w->at, w->at_cell);
}

/* A message from slab `from`: sphere `item`'s new motion, put in this slab's world; a write (a
 * pair across a face that `from` reacted to) also predicts it here, its owner, as the serial
 * loop predicts a reaction's spheres, and copies it on to the slabs beside it but `from`. */
static void sched_apply(void *arg, int slab, int from, const nbep_stamp *s, uint32_t item,
                        const void *data)
{
    struct evl_sched *x = arg;
    evl_side *d = &x->side[slab];
    nbep_evloop *e = d->e;
    slab_msg msg;
    memcpy(&msg, data, sizeof msg);
    /* (a late one, stamped before the newest event: that stays the order's check's; where the
     * newest is not known, after a rollback, next reads it from the log, where a late one's
     * record has sunk below it: a review found a late copy taken for the newest there) */
    if (d->has_last && nbep_cascade_cmp(s, &d->last) >= 0)
        nbep_cascade_copy(&d->last, s);
    d->now_t = s->t;
    /* a copy changes no count, so it keeps none: the counts a rollback puts back are those
     * before the earliest event it undoes all the same (a late copy's record sinks below
     * events after it, whose counts it could not keep) */
    if ((msg.kind != MSG_COPY && !keep_counts(x, slab)) || !keep_sphere(x, slab, item)) {
        e->failed = true;
        return;
    }
    x->ops->restore(d->u, item, &msg.m);
    if (msg.kind != MSG_WRITE)
        return;
    assert(nbep__evloop_owned(e, item));
    nbep__evloop_predict_own(e, x->ops, d->u, item, s->t);
    if (!made_by(x, slab, s, item, true) || !send_copies(x, slab, item, from)) {
        e->failed = true;
        return;
    }
    nbep__evloop_schedule_one(e, item);
}

/* Whether slab's world read or changed sphere j (another slab's, near the face) at or after
 * time t: whether an event or message of the slab since changed j, or changed a sphere of its
 * own whose list may hold j. Such a sphere's list centre lies within a list's cutoff of j's, so
 * in the 27-cell block of j's cell (nbep_evloop's walk finds lists there), in the slab's own
 * columns; what else an event reads of j it reads in predicting its spheres (j in their lists)
 * or checking its partner (kept). The cells of the slab's own columns change only by the
 * slab's own expiries (one reaching another slab's waits for the meeting), so its thread reads
 * them while the others run; j's cell too (its expiry is near a face: a meeting's). */
static bool read_since(const struct evl_sched *x, int slab, uint32_t j, double t)
{
    const evl_side *d = &x->side[slab];
    if (d->touch[j] >= t)
        return true;
    const nbep_cells *g = &d->e->cells;
    nbep_cells_block b;
    nbep_cells_block_of(g, g->m[j].cell, &b);
    const size_t columns = g->dim[0];
    for (int q = 0; q < b.cnt[0]; q++) {
        if (nbep_slabcal_slab_of(b.idx[0][q], columns, x->slabs) != slab)
            continue;
        for (int z = 0; z < b.cnt[2]; z++)
            for (int y = 0; y < b.cnt[1]; y++) {
                const size_t cell =
                    (b.idx[2][z] * g->dim[1] + b.idx[1][y]) * columns + b.idx[0][q];
                for (uint32_t k = g->head[cell]; k != NBEP_CELLS_NONE; k = g->m[k].next)
                    if (d->touch[k] >= t)
                        return true;
            }
    }
    return false;
}

/* A message come after events stamped at or after it (warp.h's late): acted on without a
 * rollback where it is a copy of another slab's sphere that nothing the slab did since read
 * (a copy changes that sphere's motion in this world alone). A write (a pair across a face:
 * its sphere predicted here, at its time, from its neighbours as they were) always rolls back.
 * Compared by time alone, not stamp: at a tie of times it rolls back. */
static bool sched_late(void *arg, int slab, const nbep_stamp *s, uint32_t item, const void *data)
{
    const struct evl_sched *x = arg;
    slab_msg msg;
    memcpy(&msg, data, sizeof msg);
    return msg.kind == MSG_COPY && x->side[slab].touch && !read_since(x, slab, item, s->t);
}

/* A rollback's undo of one kept state, newest first: an expiry's lists, or a sphere's motion,
 * slot and calendar entry (from the slot put back; another slab's sphere's motion alone). */
static void sched_restore(void *arg, int slab, uint32_t item, const void *state)
{
    struct evl_sched *x = arg;
    evl_side *d = &x->side[slab];
    nbep_evloop *e = d->e;
    NBEP_SCHED_RESTORE_HOOK(x, item);
    /* a rollback: the order's check goes on from the newest event that stands (sched_next asks
     * the log; a stop whose event was undone no longer stands there either: stop_stands) */
    d->has_last = false;
    if (item == KEPT_ITEM(e, KEPT_COUNTS)) { /* the counts as they were before the event */
        const kept_counts *k = state;
        x->ops->back(d->u, &k->m);
        d->tally.events = k->events;
        d->tally.reactions = k->reactions;
        d->tally.exits = k->exits;
        d->stall.since = k->since;
        d->stall.t_mark = k->t_mark;
        return;
    }
    uint64_t place;
    if (item == KEPT_ITEM(e, KEPT_LIST)) {
        memcpy(&place, state, sizeof place);
        assert(place + 1 == d->n_lists);
        const kept_list *l = &d->lists[place];
        nbep__evloop_unapply(e, &l->ws, &l->rec);
        if (x->slabs > 1 && !e->failed) /* (and in the run's cells: the same cells there) */
            nbep_cells_put_back(&x->e->cells, l->ws.item, l->rec.at, l->rec.cell, l->rec.prev);
        d->n_lists = place;
        return;
    }
    if (item == KEPT_ITEM(e, KEPT_TIE)) { /* a change of the ties' table: a stamp back */
        memcpy(&place, state, sizeof place);
        assert(place + 1 == d->n_ties_undo);
        const tie_undo *u = &d->ties_undo[place];
        d->n_ties_undo = place;
        const size_t k = tie_of(d, u->item);
        if (!u->had) { /* (it had none: its stamp out) */
            if (k < d->n_ties)
                tie_drop(d, k);
            return;
        }
        if (k == d->n_ties) /* (a stamp too deep took it out: room is there, it was held) */
            d->n_ties++;
        d->ties[k].item = u->item;
        nbep_cascade_copy(&d->ties[k].s, &u->old);
        return;
    }
    const kept_sphere *k = state;
    x->ops->restore(d->u, item, &k->m);
    if (!nbep__evloop_owned(e, item))
        return;
    nbep_feq_put(e->q, item, k->slot);
    nbep__evloop_schedule_one(e, item);
}

/* A window's end (and a call's start): every event so far stands, so its expiries' records,
 * its ties (every entry they stamped is handled) and what would undo them, and the caller's
 * record for undoing its counts (ops settle) are dropped. A window cut short at a meeting
 * (cut) keeps the ties: the entries at the cut's time after it (a cascade the cut went into)
 * are still to come. */
static void window_closed(struct evl_sched *x, bool cut)
{
    for (int k = 0; k < x->slabs; k++) {
        evl_side *d = &x->side[k];
        d->n_lists = d->n_ties_undo = 0;
        d->cramped = false;
        if (!cut)
            d->n_ties = 0;
        if (x->ops->settle)
            x->ops->settle(d->u);
    }
}

static const nbep_warp_ops SCHED_OPS = {sched_next,    sched_handle, sched_apply,
                                        sched_restore, sched_held,   sched_late};

/* ---- the slabs' views of the engine, and their arenas of the lists' pool ------------------ */

/* The pool entries each slab's arena holds at least: a 16th of the pool among the slabs, and
 * room for a few hundred moves of long lists (an expiry whose commit may move more than its
 * slab's arena still holds waits for the meeting: sched_handle). A test's copy of this file
 * may make them tiny, so that expiries wait so. */
#define NBEP_SCHED_ARENA_DEFAULT(pool_len, slabs) (4096 + (pool_len) / (16 * (size_t)(slabs)))
#ifndef NBEP_SCHED_ARENA
#define NBEP_SCHED_ARENA NBEP_SCHED_ARENA_DEFAULT
#endif

static void views_free(struct evl_sched *x)
{
    if (!x->view)
        return;
    for (int k = 0; k < x->slabs; k++)
        nbep__evloop_ws_fini(&x->view[k].ws[0][0]);
    nbep_free_aligned(x->view);
    x->view = NULL;
}

/* Each slab's view given an arena of the pool's spare, `extra` entries more than
 * NBEP_SCHED_ARENA (one thread, no view in use). Without memory for the spare: none (every
 * expiry that would move a list then waits for the meeting) and the engine failed. */
static void arenas_give(struct evl_sched *x, size_t extra)
{
    nbep_nblist *l = &x->e->nl;
    size_t a = NBEP_SCHED_ARENA(l->pool_len, x->slabs) + extra;
    if (!nbep_nblist_make_spare(l, a * (size_t)x->slabs)) {
        x->e->failed = true;
        a = 0;
    }
    const size_t lo = l->pool_len;
    for (int k = 0; k < x->slabs; k++)
        nbep_nblist_arena(l, lo + (size_t)k * a, lo + (size_t)(k + 1) * a, &x->view[k].nl);
    l->pool_len = lo + (size_t)x->slabs * a; /* (handed out) */
    x->room0 = l->room;
}

/* What the views' lists changed of the pool's counts, added back (one thread, no view in
 * use); what the last arena did not use given back, the rest of the arenas' spare given up
 * (a later compaction takes it back). */
static void arenas_back(struct evl_sched *x)
{
    nbep_nblist *l = &x->e->nl;
    for (int k = 0; k < x->slabs; k++)
        nbep_nblist_arena_back(l, &x->view[k].nl, x->room0);
    l->pool_len = x->view[x->slabs - 1].nl.pool_len;
    x->room0 = l->room;
}

/* With slabs, the call's start: each slab's view a copy of the run's engine but for its own
 * workspace, world, slab and arena. */
static void views_from_run(struct evl_sched *x)
{
    for (int k = 0; k < x->slabs; k++) {
        nbep_evloop *v = &x->view[k];
        evl_ws ws;
        memcpy(&ws, &v->ws[0][0], sizeof ws);
        memcpy(v, x->e, sizeof *v);
        memcpy(&v->ws[0][0], &ws, sizeof ws);
        v->own_slab = k;
        v->ver = x->wver[k];
        v->failed = false;
        x->side[k].e = v;
        if (nbep__ghost_copy(&x->side[k].cells, &x->e->cells))
            v->cells = x->side[k].cells;
        else /* (the loop does not start: views_failed) */
            x->e->failed = true;
    }
    if (!near_cols_make(x))
        x->e->failed = true;
    arenas_give(x, 0);
}

/* Whether a view failed (out of memory), folded into the run's engine. */
static bool views_failed(struct evl_sched *x)
{
    for (int k = 0; k < x->slabs && x->view; k++)
        x->e->failed |= x->view[k].failed;
    return x->e->failed;
}

/* ---- the engine's side -------------------------------------------------------------------- */

static void views_free(struct evl_sched *x);

nbep_status nbep_evloop_set_scheduled(nbep_evloop *e, nbep_diag *d)
{
    assert(!e->sched && e->team == 1 && e->n <= UINT32_MAX - KEPT_COUNTS);
    struct evl_sched *x = nbep_alloc_aligned(1, sizeof *x);
    if (x) {
        memset(x, 0, sizeof *x);
        atomic_init(&x->go, 0);
        atomic_init(&x->arrived, 0);
        atomic_flag_clear(&x->lock);
        atomic_init(&x->limit_t, INFINITY);
    }
    const int slabs = e->slabcal ? nbep_slabcal_slabs(e->slabcal) : 1;
    if (x)
        x->side = calloc((size_t)slabs, sizeof *x->side);
    if (!x || !x->side) {
        nbep_free_aligned(x);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory for the scheduled loop (NBEP_SCHEDULED)");
    }
    x->slabs = slabs;
    bool views = true;
    if (slabs > 1) {
        x->view = nbep_alloc_aligned((size_t)slabs, sizeof *x->view);
        if (x->view)
            memset(x->view, 0, (size_t)slabs * sizeof *x->view);
        for (int k = 0; k < slabs && x->view; k++)
            views &= nbep__evloop_ws_init(&x->view[k].ws[0][0]);
        views &= x->view != NULL;
        for (int k = 0; k < slabs && views; k++) {
            double *touch = malloc((e->n ? e->n : 1) * sizeof *touch);
            views = touch != NULL;
            for (size_t i = 0; i < e->n && views; i++)
                touch[i] = -INFINITY;
            x->side[k].touch = touch;
        }
    }
    if (!views) {
        views_free(x);
        for (int k = 0; k < slabs; k++)
            free(x->side[k].touch);
        free(x->side);
        nbep_free_aligned(x);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory for the scheduled loop (NBEP_SCHEDULED)");
    }
    /* (boxes of 1024 messages: a window sends far fewer on two slabs; a full box costs a
     * wait, not a failure) */
    const nbep_status st = nbep_warp_create(slabs, sizeof(kept_sphere), sizeof(slab_msg),
                                            slabs > 1 ? 1024 : 16, &SCHED_OPS, x, &x->warp, d);
    if (st != NBEP_OK) {
        views_free(x);
        for (int k = 0; k < slabs; k++)
            free(x->side[k].touch);
        free(x->side);
        nbep_free_aligned(x);
        return st;
    }
    e->sched = x;
    return NBEP_OK;
}

void nbep_evloop_set_worlds(nbep_evloop *e, void *const *wu, const uint64_t *const *wver)
{
    assert(e->sched && e->sched->slabs > 1);
    e->sched->wu = wu;
    e->sched->wver = wver;
}

bool nbep_evloop_too_deep(const nbep_evloop *e)
{
    return e->sched && e->sched->too_deep;
}

void nbep__evloop_sched_destroy(struct evl_sched **s)
{
    if (!s || !*s)
        return;
    struct evl_sched *x = *s;
    NBEP_SCHED_DESTROY_HOOK(x);
    nbep_warp_destroy(&x->warp);
    for (int m = 0; m < x->slabs; m++) {
        evl_side *d = &x->side[m];
        for (size_t k = 0; k < d->cap_lists; k++) {
            nbep__evloop_ws_copy_fini(&d->lists[k].ws);
            nbep__evloop_unlist_fini(&d->lists[k].rec);
        }
        free(d->lists);
        free(d->ties);
        free(d->ties_undo);
        free(d->touch);
        free(d->near_col);
        nbep_cells_fini(&d->cells);
    }
    views_free(x);
    free(x->side);
    nbep_free_aligned(x);
    *s = NULL;
}

/* The earliest entry of every slab, in *c: false when none has one. */
static bool top_of_all(const struct evl_sched *x, nbep_calendar_entry *c)
{
    return x->e->slabcal ? nbep_slabcal_first(x->e->slabcal, c)
                         : nbep_calendar_top(x->e->cal, &c->item, &c->time);
}

/* With slabs, the call's start: each slab's world a copy of the run's motion, its counts from
 * zero. */
static void worlds_from_run(struct evl_sched *x)
{
    const nbep_evloop_ops *ops = x->ops;
    for (int k = 0; k < x->slabs; k++) {
        evl_side *d = &x->side[k];
        d->u = x->wu[k];
        ops->clear(d->u);
    }
    for (uint32_t i = 0; i < x->e->n; i++) {
        nbep_evloop_motion m;
        ops->save(x->u, i, &m);
        for (int k = 0; k < x->slabs; k++)
            ops->restore(x->side[k].u, i, &m);
    }
}

/* With slabs, the call's end: each sphere's motion its owner's, the counts and sums the
 * slabs' (exact: the same whichever slab added what). */
static void run_from_worlds(struct evl_sched *x)
{
    const nbep_evloop_ops *ops = x->ops;
    for (uint32_t i = 0; i < x->e->n; i++) {
        nbep_evloop_motion m;
        ops->save(x->side[nbep__evloop_sphere_slab(x->e, i)].u, i, &m);
        ops->restore(x->u, i, &m);
    }
    for (int k = 0; k < x->slabs; k++)
        ops->merge(x->u, x->side[k].u);
}

/* Sphere i's motion in slab's world copied into every other slab's (between windows). */
static void copied_to_all(struct evl_sched *x, int slab, uint32_t i)
{
    nbep_evloop_motion m;
    x->ops->save(x->side[slab].u, i, &m);
    for (int k = 0; k < x->slabs; k++)
        if (k != slab)
            x->ops->restore(x->side[k].u, i, &m);
}

/* A stop that stands ends the call with its event's reaction done in its slab's world alone
 * (a stopping event sends nothing): its spheres' motion copied into every world, so that each
 * owner's world holds it at the call's end (a helper's review found a pair across a face's
 * other sphere coming back without its reaction, and its reaction count lost). */
static void stopped_copied(struct evl_sched *x, int slab)
{
    const evl_side *d = &x->side[slab];
    /* (not handled, found at its entry or at the stall check: nothing changed, and its pair's
     * other sphere's copy here may be older than its owner's) */
    if (!d->handled)
        return;
    const uint32_t i = d->stop.level[d->stop.depth - 1].item;
    const nbep_event *ev = nbep_feq_slot(x->e->q, i); /* (a stop commits nothing: its slot) */
    copied_to_all(x, slab, i);
    if (ev->kind == NBEP_EVENT_SPHERE)
        copied_to_all(x, slab, ev->partner);
}

/* The meeting's own work, with slabs: where a slab held an expiry that reaches another slab's
 * lists or cells before the window's end, the window ends at the earliest such (the limit):
 * every slab goes back to it (nbep_warp_cut: all that was done at or after it undone), and
 * where that expiry is still its slab's earliest entry (a message before it may have changed
 * that) it is done there, between windows, in its slab's world, its sphere's motion copied to
 * every world (its list's members, and maybe its owner, are now other slabs' too). False where
 * nothing was held. */
static bool meet(struct evl_sched *x)
{
    /* a stop that stands at the limit (on slabs: every slab has done all before it) or, on one
     * slab, anywhere: the call ends there, what was done past it undone (the stopping event
     * itself stands, as in the serial loop, but for one found too deep at its entry, not
     * handled) */
    for (int k = 0; k < x->slabs; k++) {
        const evl_side *d = &x->side[k];
        if (stop_stands(x, k) &&
            (x->slabs == 1 || nbep_cascade_cmp(&d->stop, &x->limit) == 0)) {
            if (x->slabs > 1) { /* (one slab has done nothing past its stop) */
                nbep_warp_cut(x->warp, &d->stop, !d->deep);
                stopped_copied(x, k);
            }
            window_closed(x, false);
            x->stop = true;
            x->e->failed |= d->oom;
            x->too_deep = d->deep;
            x->t_stuck = d->stop_t;
            return true;
        }
    }
    if (!has_limit(x))
        return false;
    nbep_stamp held;
    nbep_cascade_copy(&held, &x->limit);
    NBEP_SCHED_CUT_HOOK(x, 0);
    nbep_warp_cut(x->warp, &held, false);
    NBEP_SCHED_CUT_HOOK(x, 1);
    int slab = -1;
    for (int k = 0; k < x->slabs; k++)
        if (x->side[k].blocked && nbep_cascade_cmp(&x->side[k].held, &held) == 0)
            slab = k;
    bool kept = slab >= 0;
    for (int k = 0; k < x->slabs; k++) {
        nbep_stamp last;
        kept |= nbep_warp_last(x->warp, k, &last);
    }
    window_closed(x, true);
    /* A window that keeps nothing would come again the same (the turns are the same): where
     * its limit was a stop too deep, found ahead and undone since (a review's reasoning, not
     * met in any run), the loop stops there as too deep rather than run for ever. */
    x->idle_windows = kept ? 0 : x->idle_windows + 1;
    if (x->idle_windows >= 2) {
        x->stop = x->too_deep = true;
        x->t_stuck = held.t;
        return true;
    }
    if (slab < 0)
        return true;
    evl_side *d = &x->side[slab];
    nbep_evloop *e = d->e;
    const uint32_t i = held.level[held.depth - 1].item;
    const nbep_event ev = *nbep_feq_slot(e->q, i);
    assert(ev.kind == NBEP_EVENT_HORIZON);
    x->meetings++;
    nbep_cascade_copy(&d->last, &held);
    d->has_last = true;
    d->blocked = false;
    d->tally.events++;
    if (!nbep__evloop_advances(&d->stall, held.t)) { /* (between windows: the call ends) */
        x->stop = true;
        x->t_stuck = held.t;
        return true;
    }
    evl_ws *w = &e->ws[0][0];
    e->own_slab = -1; /* (its lists and cells are every slab's: one thread here) */
    /* its walk and commit on the run's cells, exact everywhere (the slab's copy is not exact
     * two columns into another slab, where a move's walk reads) */
    const uint32_t was = x->e->cells.m[i].cell;
    if (x->slabs > 1)
        e->cells = x->e->cells;
    nbep__evloop_handle(e, w, x->ops, d->u, i, &ev, held.t, true);
    nbep__evloop_count_handled(&d->tally, w);
    /* (room for its commit in its slab's arena, where it held too little: the arenas given out
     * again, with that much more) */
    if (x->slabs > 1 && w->rebuilt && !w->oom) {
        const size_t need = nbep_nblist_need(&e->nl, w->n_near, w->n_near);
        if (nbep_nblist_spare(&e->nl) < need) {
            arenas_back(x);
            arenas_give(x, need);
        }
    }
    nbep__evloop_commit(e, w);
    e->own_slab = x->slabs > 1 ? slab : -1;
    if (x->slabs > 1)
        e->cells = d->cells;
    if (views_failed(x))
        return true;
    /* its place made in every slab's cells that keep its old cell or its new one (each slab is
     * at the meeting: at once, for good) */
    const nbep_cells *g = &x->e->cells;
    const uint64_t to = x->slabs > 1 && w->rebuilt
                            ? nbep__ghost_receivers(g, x->slabs, -1, was, g->m[i].cell)
                            : 0;
    for (int k = 0; k < x->slabs; k++)
        if (to >> k & 1) {
            evl_cellmsg m = {.item = i, .at = g->m[i].at, .cell = g->m[i].cell};
            nbep__ghost_apply(&x->side[k].cells, &m);
        }
    copied_to_all(x, slab, i);
    /* Where it moved its sphere to another slab, its prediction read its new list's members
     * in the old slab's world, where those beside the new one's columns are not kept (no
     * copies come from a column that is not beside another slab): its slot is predicted again
     * in its new slab's world, which keeps them all, uncounted (the one counted read as many
     * members), and its entry set again. */
    const int owner = nbep__evloop_sphere_slab(e, i);
    if (owner != slab) {
        x->moves++;
        evl_side *o = &x->side[owner];
        nbep_evloop_mark before;
        const bool marked = !x->ops->mark || x->ops->mark(o->u, &before);
        nbep__evloop_predict_own(o->e, x->ops, o->u, i, held.t);
        if (x->ops->back)
            x->ops->back(o->u, &before);
        nbep__evloop_schedule_one(o->e, i);
        if (!marked) {
            e->failed = true;
            return true;
        }
    }
    /* (its entry's stamp in its owner's table) */
    if (!made_by(x, owner, &held, i, false))
        e->failed = true;
    return true;
}

/* `go`'s word: the call's (its low 32 bits) and the window's number, or GO_QUIT */
#define GO_QUIT UINT32_MAX
static uint64_t go_word(uint64_t call, uint32_t window)
{
    return (call & UINT32_MAX) << 32 | window;
}

/* Thread t's slabs, in turns, till the window's work is done (every slab's, all mail). */
static void run_slabs_of(struct evl_sched *x, int t)
{
    for (bool done = false; !done;) {
        done = true;
        /* (on one slab its run ends with the window's work; on more, each runs a turn in turn) */
        for (int k = t; k < x->slabs; k += x->crew)
            done &= nbep_warp_run(x->warp, k,
                                  x->slabs > 1 ? NBEP_SCHED_SLAB_TURN(k) : NBEP_SCHED_TURN);
        if (!done)
            NBEP_SCHED_TURN_HOOK(x);
    }
}

void nbep__evloop_sched_help(nbep_evloop *e, int t, uint64_t call)
{
    struct evl_sched *x = e->sched;
    uint32_t seen = 0;
    for (;;) {
        uint64_t g;
        for (unsigned k = 1; ((g = atomic_load_explicit(&x->go, memory_order_acquire)) >> 32) !=
                                 (call & UINT32_MAX) ||
                             (uint32_t)g == seen;
             k++)
            nbep_spin_pause(k);
        if ((uint32_t)g == GO_QUIT)
            return;
        seen = (uint32_t)g;
        if (t < x->crew) { /* (a thread past the call's crew has no slab, and is not waited
                            * for: nbep_evloop_run_lead) */
            run_slabs_of(x, t);
            atomic_fetch_add_explicit(&x->arrived, 1, memory_order_release);
        }
    }
}

void nbep_evloop_release(nbep_evloop *e, uint64_t call)
{
    if (e->sched) /* (the helpers wait for the call's end: it comes at once) */
        atomic_store_explicit(&e->sched->go, go_word(call, GO_QUIT), memory_order_release);
}

bool nbep__evloop_run_scheduled(nbep_evloop *e, const nbep_evloop_ops *ops, void *u,
                                int crew, uint64_t call, double t_end, nbep_evloop_stall *stall,
                                nbep_evloop_tally *tally, double *t_stuck)
{
    struct evl_sched *x = e->sched;
    assert(crew >= 1 && (crew == 1 || x->slabs > 1));
    x->crew = crew < x->slabs ? crew : x->slabs;
    x->e = e;
    x->ops = ops;
    x->u = u;
    x->stall = stall;
    x->stop = x->too_deep = false;
    x->idle_windows = 0;
    if (x->slabs > 1) {
        worlds_from_run(x);
        views_from_run(x);
    } else {
        x->side[0].u = u;
        x->side[0].e = e;
    }
    for (int k = 0; k < x->slabs; k++) { /* (each slab's stall check counts its own events) */
        x->side[k].stall = *stall;
        if (k % x->crew != 0) /* (the progress is the lead's to tell) */
            x->side[k].stall.on_look = NULL;
        x->side[k].tally = (nbep_evloop_tally){0};
        x->side[k].has_last = x->side[k].blocked = x->side[k].stopped = false;
    }
    window_closed(x, false); /* (a call before that stopped inside its window left them) */
    /* windows of a WINDOWS_A_STEP-th of what is left of the call's span from its first event
     * (a step, or its part; what each window did stands at its end): their logs, a few hundred
     * events' in a dense fluid, stay in the caches (the whole step's, written once and never
     * read, cost a miss of the last level a few times an event). A width that would not move a
     * window's end past its first event (0, or lost to rounding) makes the rest one window.
     * With slabs a window may end sooner, at an expiry reaching across (meet). */
    nbep_calendar_entry c;
    double width = 0.0;
    if (top_of_all(x, &c) && c.time < t_end)
        width = (t_end - c.time) / WINDOWS_A_STEP;
    uint32_t window = 0;
    while (!x->stop && !views_failed(x) && !nbep_warp_failed(x->warp) && top_of_all(x, &c) &&
           c.time < t_end) {
        const double end = c.time + width;
        x->window_end = end > c.time ? fmin(end, t_end) : t_end;
        atomic_store_explicit(&x->limit_t, INFINITY, memory_order_relaxed);
        nbep_warp_open(x->warp, x->window_end);
        NBEP_SCHED_OPEN_HOOK(x);
        if (x->crew > 1) { /* (what the lead wrote above published with the window) */
            atomic_store_explicit(&x->arrived, 0, memory_order_relaxed);
            atomic_store_explicit(&x->go, go_word(call, ++window), memory_order_release);
        }
        run_slabs_of(x, 0);
        for (unsigned k = 1; x->crew > 1 && atomic_load_explicit(&x->arrived, memory_order_acquire) <
                                                x->crew - 1;
             k++)
            nbep_spin_pause(k);
        if (!nbep_warp_failed(x->warp) && !meet(x))
            window_closed(x, false);
    }
    if (x->crew > 1) /* (the helpers return) */
        atomic_store_explicit(&x->go, go_word(call, GO_QUIT), memory_order_release);
    if (nbep_warp_failed(x->warp))
        e->failed = true;
    if (x->slabs > 1) {
        views_failed(x);
        arenas_back(x);
        run_from_worlds(x);
    }
    stall->since = x->side[0].stall.since; /* (the count carried to a call's next part) */
    stall->t_mark = x->side[0].stall.t_mark;
    stall->looks = x->side[0].stall.looks;
    for (int k = 0; k < x->slabs; k++) {
        stall->stopped |= x->side[k].stall.stopped;
        tally->events += x->side[k].tally.events;
        tally->reactions += x->side[k].tally.reactions;
        tally->exits += x->side[k].tally.exits;
    }
    if (x->stop)
        *t_stuck = x->t_stuck;
    return !x->stop && !e->failed;
}
