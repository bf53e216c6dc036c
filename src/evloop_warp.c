/* The cells engine's one-thread loop through the optimistic scheduler on one slab
 * (nbep_evloop_set_scheduled, NBEP_SCHEDULED): the engine as the scheduler's model, as the
 * optimistic engine will run it on each slab, with what a slab must keep of each event to undo
 * it, so that what that bookkeeping costs the real engine is measured, not modelled
 * (docs/optimistic-design.md, *The engine on the scheduler*). One slab: no messages, and no
 * rollbacks but those a test asks for (nbep_warp_roll_back, through the hooks below:
 * tests/test_sched_rollback.c), which call the restore below as a straggler will. */
#include "evloop_impl.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/warp.h"

/* The windows a step is cut into (of equal simulated time; a test may ask for fewer, so that
 * its small scenes have events enough in each). */
#ifndef WINDOWS_A_STEP
#define WINDOWS_A_STEP 64
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

struct evl_sched {
    nbep_warp *warp;
    /* the call's */
    nbep_evloop *e;
    const nbep_evloop_ops *ops;
    void *u;
    nbep_evloop_stall *stall;
    nbep_evloop_tally *tally;
    bool stop;           /* no more events: stuck, a reaction's stop or a cascade too deep
                          * (t_stuck) */
    bool too_deep;       /* ... the last: a cascade deeper than a stamp holds */
    double t_stuck;
    nbep_stamp last;     /* the stamp of the event handled last (its order's check) */
    bool has_last;
    /* the window's expiries, by their place in it (the log's item for them, past the
     * spheres', keeps that place) */
    kept_list *lists;
    size_t n_lists, cap_lists;
    /* the stamps of the entries made at the time of the event that made them (a tie in time:
     * cascade.h); every other entry's stamp is a root. Few (a cradle's row), those of an older
     * time never looked up (an entry's time is compared), all dropped between windows: every
     * entry they stamped was handled before its window's end. Each change kept (ties_undo,
     * the window's, by place), so that a rollback puts the table back. */
    tie_stamp *ties;
    size_t n_ties, cap_ties;
    tie_undo *ties_undo;
    size_t n_ties_undo, cap_ties_undo;
};

/* ---- the model's side (warp.h) ------------------------------------------------------------ */

/* No more events: the call returns false with t in *t_stuck (stuck, a reaction's stop, a
 * cascade at one time too deep for its stamps) */
static void stop_at(struct evl_sched *x, double t)
{
    x->stop = true;
    x->t_stuck = t;
}

/* Where sphere i's row is in the ties' table; n_ties where it has none. */
static size_t tie_of(const struct evl_sched *x, uint32_t i)
{
    size_t k = 0;
    while (k < x->n_ties && x->ties[k].item != i)
        k++;
    return k;
}

/* Row k out of the ties' table (the last one into its place). */
static void tie_drop(struct evl_sched *x, size_t k)
{
    x->ties[k] = x->ties[--x->n_ties];
}

static bool sched_next(void *arg, int slab, nbep_stamp *s)
{
    (void)slab;
    struct evl_sched *x = arg;
    nbep_evloop *e = x->e;
    uint32_t i;
    double t;
    if (x->stop || e->failed || !nbep_calendar_top(e->cal, &i, &t))
        return false;
    const nbep_event *ev = nbep_feq_slot(e->q, i);
    /* the lines its handle will read requested here, before the stamp's work: what the plain
     * loop requests (its lists, cells, the next two entries) and its spheres' motion, which
     * the handle's keep reads first (without these requests the scheduled loop took 1.3 to 1.4
     * times the plain loop's time at N = 256000, phi = 0.30; with them 1.1:
     * docs/optimistic-design.md, *The lines requested*) */
    nbep__evloop_prefetch_event(e, i, ev);
    if (x->ops->prefetch) {
        x->ops->prefetch(x->u, i);
        if (ev->kind == NBEP_EVENT_SPHERE)
            x->ops->prefetch(x->u, ev->partner);
    }
    const uint64_t key = nbep__evloop_slot_key(i, ev);
    nbep_cascade_set_root(s, t, key, i);
    const size_t k = tie_of(x, i);
    if (k < x->n_ties) { /* made at its maker's time, if for this entry */
        const nbep_stamp *c = &x->ties[k].s;
        if (c->t == t && c->level[c->depth - 1].key == key)
            nbep_cascade_copy(s, c);
    }
    if (!x->has_last) /* (after a rollback: the newest event that stands, if any) */
        x->has_last = nbep_warp_last(x->warp, 0, &x->last);
    /* the order's check: the stamps made where their entries were never go back, but where a
     * cascade at one time is deeper than a stamp holds (made_by), a root stamp does: the loop
     * stops there, too deep (nbep_evloop_too_deep: its own message) */
    if (x->has_last && nbep_cascade_cmp(s, &x->last) < 0) {
        x->too_deep = true;
        stop_at(x, t);
        return false;
    }
    return true;
}

/* Sphere j's new entry, made by the event stamped *by: its stamp kept where it is not a root
 * (at by's time), in place of any older one of j's. Where that stamp would be deeper than
 * NBEP_CASCADE_DEPTH (a cascade at one time through more than 8 spheres) none is kept: the
 * entry's root stamp then comes before the event that made it, and the next stops the loop
 * there (its order's check). False without memory. */
static bool made_by(struct evl_sched *x, const nbep_stamp *by, uint32_t j)
{
    const nbep_event *slot = nbep_feq_slot(x->e->q, j);
    if (slot->time != by->t) /* later: a root (j's older stamp, if any, no longer its entry's) */
        return true;
    const size_t k = tie_of(x, j);
    if (k == x->n_ties &&
        !nbep_room_for_one((void **)&x->ties, &x->cap_ties, k, sizeof *x->ties))
        return false;
    /* what it replaces, kept (under the item past the expiries') */
    uint64_t *place = nbep_room_for_one((void **)&x->ties_undo, &x->cap_ties_undo,
                                        x->n_ties_undo, sizeof *x->ties_undo)
                          ? nbep_warp_keep_room(x->warp, 0, KEPT_ITEM(x->e, KEPT_TIE))
                          : NULL;
    if (!place)
        return false;
    *place = x->n_ties_undo;
    tie_undo *u = &x->ties_undo[x->n_ties_undo++];
    u->item = j;
    u->had = k < x->n_ties;
    if (u->had)
        nbep_cascade_copy(&u->old, &x->ties[k].s);
    if (nbep_cascade_made(by, slot->time, nbep__evloop_slot_key(j, slot), j, &x->ties[k].s)) {
        x->ties[k].item = j;
        x->n_ties += k == x->n_ties;
    } else if (k < x->n_ties) { /* (too deep: j's older stamp is not its entry's either) */
        tie_drop(x, k);
    }
    return true;
}

/* Sphere i's state into the log before the event changes it. */
static bool keep_sphere(struct evl_sched *x, uint32_t i)
{
    kept_sphere *k = nbep_warp_keep_room(x->warp, 0, i);
    if (!k)
        return false;
    x->ops->save(x->u, i, &k->m);
    k->slot = *nbep_feq_slot(x->e->q, i);
    return true;
}

/* The counts into the log before the event adds to them (none where the caller keeps none). */
static bool keep_counts(struct evl_sched *x)
{
    if (!x->ops->mark)
        return true;
    kept_counts *k = nbep_warp_keep_room(x->warp, 0, KEPT_ITEM(x->e, KEPT_COUNTS));
    if (!k)
        return false;
    k->events = x->tally->events;
    k->reactions = x->tally->reactions;
    k->exits = x->tally->exits;
    k->since = x->stall->since;
    k->t_mark = x->stall->t_mark;
    return x->ops->mark(x->u, &k->m); /* (false: the record is whole all the same) */
}

/* The room for the window's next expiry record; NULL without memory. */
static kept_list *next_list(struct evl_sched *x)
{
    const size_t cap0 = x->cap_lists;
    if (!nbep_room_for_one((void **)&x->lists, &x->cap_lists, x->n_lists, sizeof *x->lists))
        return NULL;
    /* new records zeroed: their copies' arrays are made at their first use */
    memset(x->lists + cap0, 0, (x->cap_lists - cap0) * sizeof *x->lists);
    return &x->lists[x->n_lists];
}

static void sched_handle(void *arg, int slab, const nbep_stamp *s)
{
    (void)slab;
    struct evl_sched *x = arg;
    nbep_evloop *e = x->e;
    const uint32_t i = s->level[s->depth - 1].item; /* (the entry's: the path's last level) */
    const double t = s->t;
    const nbep_event ev = *nbep_feq_slot(e->q, i);
    NBEP_SCHED_HANDLED_HOOK(x, s);
    nbep_cascade_copy(&x->last, s);
    x->has_last = true;
    if (!keep_counts(x)) {
        e->failed = true;
        return;
    }
    x->tally->events++;
    if (!nbep__evloop_advances(x->stall, t)) {
        stop_at(x, t);
        return;
    }
    /* what it may change: its sphere and, for a pair, the other (a free flight's reaction
     * changes those two alone, as the team loop's undo keeps) */
    if (!keep_sphere(x, i) ||
        (ev.kind == NBEP_EVENT_SPHERE && ev.partner != i && !keep_sphere(x, ev.partner))) {
        e->failed = true;
        return;
    }
    evl_ws *w = &e->ws[0][0];
    nbep__evloop_handle(e, w, x->ops, x->u, i, &ev, t, true);
    nbep__evloop_count_handled(x->tally, w);
    if (w->stop) {
        stop_at(x, t);
        return;
    }
    /* the stamps of the entries it made (as the commit sets them: the changed spheres', then
     * its own) */
    bool room = true;
    for (size_t k = 0; k < w->n_changed && room; k++)
        room = w->changed[k] == i || made_by(x, s, w->changed[k]);
    if (!room || !made_by(x, s, i)) {
        e->failed = true;
        return;
    }
    if (!w->rebuilt || w->oom) {
        nbep__evloop_commit(e, w);
        return;
    }
    /* an expiry: its list record kept under an item past the spheres', its place in the
     * window as its state */
    kept_list *l = next_list(x);
    uint64_t *place = l && nbep__evloop_ws_copy_lists(&l->ws, w)
                          ? nbep_warp_keep_room(x->warp, 0, KEPT_ITEM(e, KEPT_LIST))
                          : NULL;
    if (!place) {
        e->failed = true;
        return;
    }
    *place = x->n_lists++;
    nbep__evloop_commit_undoable(e, w, &l->rec);
}

static void sched_apply(void *arg, int slab, int from, const nbep_stamp *s, uint32_t item,
                        const void *data)
{
    (void)arg, (void)slab, (void)from, (void)s, (void)item, (void)data;
    assert(!"one slab: no messages");
}

/* A rollback's undo of one kept state, newest first: an expiry's lists, or a sphere's motion,
 * slot and calendar entry (from the slot put back). */
static void sched_restore(void *arg, int slab, uint32_t item, const void *state)
{
    (void)slab;
    struct evl_sched *x = arg;
    nbep_evloop *e = x->e;
    NBEP_SCHED_RESTORE_HOOK(x, item);
    /* a rollback: the order's check goes on from the newest event that stands (sched_next asks
     * the log), and what stopped the loop may have been undone (a stop comes back with the
     * event that made it, handled again) */
    x->has_last = false;
    x->stop = false;
    if (item == KEPT_ITEM(e, KEPT_COUNTS)) { /* the counts as they were before the event */
        const kept_counts *k = state;
        x->ops->back(x->u, &k->m);
        x->tally->events = k->events;
        x->tally->reactions = k->reactions;
        x->tally->exits = k->exits;
        x->stall->since = k->since;
        x->stall->t_mark = k->t_mark;
        return;
    }
    uint64_t place;
    if (item == KEPT_ITEM(e, KEPT_LIST)) {
        memcpy(&place, state, sizeof place);
        assert(place + 1 == x->n_lists);
        nbep__evloop_unapply(e, &x->lists[place].ws, &x->lists[place].rec);
        x->n_lists = place;
        return;
    }
    if (item == KEPT_ITEM(e, KEPT_TIE)) { /* a change of the ties' table: a stamp back */
        memcpy(&place, state, sizeof place);
        assert(place + 1 == x->n_ties_undo);
        const tie_undo *u = &x->ties_undo[place];
        x->n_ties_undo = place;
        const size_t k = tie_of(x, u->item);
        if (!u->had) { /* (it had none: its stamp out) */
            if (k < x->n_ties)
                tie_drop(x, k);
            return;
        }
        if (k == x->n_ties) /* (a stamp too deep took it out: room is there, it was held) */
            x->n_ties++;
        x->ties[k].item = u->item;
        nbep_cascade_copy(&x->ties[k].s, &u->old);
        return;
    }
    const kept_sphere *k = state;
    x->ops->restore(x->u, item, &k->m);
    nbep_feq_put(e->q, item, k->slot);
    nbep__evloop_schedule_one(e, item);
}

/* A window's end (and a call's start): every event so far stands, so its expiries' records,
 * its ties (every entry they stamped is handled) and what would undo them, and the caller's
 * record for undoing its counts (ops settle) are dropped. */
static void window_closed(struct evl_sched *x)
{
    x->n_lists = x->n_ties = x->n_ties_undo = 0;
    if (x->ops->settle)
        x->ops->settle(x->u);
}

static const nbep_warp_ops SCHED_OPS = {sched_next, sched_handle, sched_apply, sched_restore};

/* ---- the engine's side -------------------------------------------------------------------- */

nbep_status nbep_evloop_set_scheduled(nbep_evloop *e, nbep_diag *d)
{
    assert(!e->sched && !e->slabcal && e->team == 1 && e->n <= UINT32_MAX - KEPT_COUNTS);
    struct evl_sched *x = calloc(1, sizeof *x);
    if (!x)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory for the scheduled loop (NBEP_SCHEDULED)");
    /* (messages: none on one slab; the smallest size the mail takes) */
    const nbep_status st =
        nbep_warp_create(1, sizeof(kept_sphere), 8, 16, &SCHED_OPS, x, &x->warp, d);
    if (st != NBEP_OK) {
        free(x);
        return st;
    }
    e->sched = x;
    return NBEP_OK;
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
    nbep_warp_destroy(&x->warp);
    for (size_t k = 0; k < x->cap_lists; k++) {
        nbep__evloop_ws_copy_fini(&x->lists[k].ws);
        nbep__evloop_unlist_fini(&x->lists[k].rec);
    }
    free(x->lists);
    free(x->ties);
    free(x->ties_undo);
    free(x);
    *s = NULL;
}

bool nbep__evloop_run_scheduled(nbep_evloop *e, const nbep_evloop_ops *ops, void *u,
                                double t_end, nbep_evloop_stall *stall,
                                nbep_evloop_tally *tally, double *t_stuck)
{
    struct evl_sched *x = e->sched;
    x->e = e;
    x->ops = ops;
    x->u = u;
    x->stall = stall;
    x->tally = tally;
    x->stop = x->too_deep = false;
    window_closed(x); /* (a call before that stopped inside its window left them) */
    /* windows of a WINDOWS_A_STEP-th of what is left of the call's span from its first event
     * (a step, or its part; what each window did stands at its end): their logs, a few hundred
     * events' in a dense fluid, stay in the caches (the whole step's, written once and never
     * read, cost a miss of the last level a few times an event). A width that would not move a
     * window's end past its first event (0, or lost to rounding) makes the rest one window. */
    uint32_t i;
    double t, width = 0.0;
    if (nbep_calendar_top(e->cal, &i, &t) && t < t_end)
        width = (t_end - t) / WINDOWS_A_STEP;
    while (!x->stop && !e->failed && !nbep_warp_failed(x->warp) &&
           nbep_calendar_top(e->cal, &i, &t) && t < t_end) {
        const double end = t + width;
        nbep_warp_open(x->warp, end > t ? fmin(end, t_end) : t_end);
        NBEP_SCHED_OPEN_HOOK(x);
        while (!nbep_warp_run(x->warp, 0, NBEP_SCHED_TURN))
            NBEP_SCHED_TURN_HOOK(x);
        window_closed(x);
    }
    if (nbep_warp_failed(x->warp))
        e->failed = true;
    if (x->stop)
        *t_stuck = x->t_stuck;
    return !x->stop && !e->failed;
}
