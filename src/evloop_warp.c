/* The cells engine's one-thread loop through the optimistic scheduler on one slab
 * (nbep_evloop_set_scheduled, NBEP_SCHEDULED): the engine as the scheduler's model, as the
 * optimistic engine will run it on each slab, with what a slab must keep of each event to undo
 * it, so that what that bookkeeping costs the real engine is measured, not modelled
 * (docs/optimistic-design.md, *The engine on the scheduler*). One slab: no messages, no
 * rollbacks (the restore below is what a rollback will call: tests/test_evloop_rollback.c
 * undoes the same kept states on the engine by hand). */
#include "evloop_impl.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/warp.h"

/* The windows a step is cut into (of equal simulated time). */
#define WINDOWS_A_STEP 64

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

struct evl_sched {
    nbep_warp *warp;
    /* the call's */
    nbep_evloop *e;
    const nbep_evloop_ops *ops;
    void *u;
    nbep_evloop_stall *stall;
    nbep_evloop_tally *tally;
    bool stop;           /* no more events: stuck, a reaction's stop or a tie (t_stuck) */
    double t_stuck;
    nbep_stamp last;     /* the stamp of the event handled last (its order's check) */
    bool has_last;
    /* the window's expiries, by their place in it (the log's item for them, past the
     * spheres', keeps that place) */
    kept_list *lists;
    size_t n_lists, cap_lists;
};

/* ---- the model's side (warp.h) ------------------------------------------------------------ */

/* No more events: the call returns false with t in *t_stuck (stuck, a reaction's stop, a tie) */
static void stop_at(struct evl_sched *x, double t)
{
    x->stop = true;
    x->t_stuck = t;
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
    nbep_cascade_set_root(s, t, nbep__evloop_slot_key(i, nbep_feq_slot(e->q, i)), i);
    /* an entry made at the time of the event that made it, before it in (key, item): the
     * serial loop takes it next, and a root stamp would put it before what was done (the
     * cascade stamps of the engine's model order it: not made here yet) */
    if (x->has_last && nbep_cascade_cmp(s, &x->last) < 0) {
        stop_at(x, t);
        return false;
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
    const uint32_t i = s->level[0].item;
    const double t = s->t;
    const nbep_event ev = *nbep_feq_slot(e->q, i);
    nbep_cascade_copy(&x->last, s);
    x->has_last = true;
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
    if (!w->rebuilt || w->oom) {
        nbep__evloop_commit(e, w);
        return;
    }
    /* an expiry: its list record kept under an item past the spheres', its place in the
     * window as its state */
    kept_list *l = next_list(x);
    uint64_t *place = l && nbep__evloop_ws_copy_lists(&l->ws, w)
                          ? nbep_warp_keep_room(x->warp, 0, (uint32_t)e->n)
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
    if (item == (uint32_t)e->n) {
        uint64_t place;
        memcpy(&place, state, sizeof place);
        assert(place + 1 == x->n_lists);
        nbep__evloop_unapply(e, &x->lists[place].ws, &x->lists[place].rec);
        x->n_lists = place;
        return;
    }
    const kept_sphere *k = state;
    x->ops->restore(x->u, item, &k->m);
    nbep_feq_put(e->q, item, k->slot);
    nbep__evloop_schedule_one(e, item);
}

static const nbep_warp_ops SCHED_OPS = {sched_next, sched_handle, sched_apply, sched_restore};

/* ---- the engine's side -------------------------------------------------------------------- */

nbep_status nbep_evloop_set_scheduled(nbep_evloop *e, nbep_diag *d)
{
    assert(!e->sched && !e->slabcal && e->team == 1 && e->n < UINT32_MAX);
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
    x->stop = false;
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
        while (!nbep_warp_run(x->warp, 0, SIZE_MAX)) {
        }
        x->n_lists = 0;
    }
    if (nbep_warp_failed(x->warp))
        e->failed = true;
    if (x->stop)
        *t_stuck = x->t_stuck;
    return !x->stop && !e->failed;
}
