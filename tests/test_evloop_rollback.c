/* The cells engine rolled back (docs/optimistic-design.md, step 2: rollback of motion, slots,
 * calendar entries and lists): what the optimistic engine's slab does when a straggler comes,
 * done here to the real engine on one thread, with what its model will keep of each event.
 *
 * This test compiles its own copy of the engine with three looks: before an event is handled,
 * at an expiry's commit, after an event's commit. Now and then (every 41st event) it opens a
 * window: the whole state copied (every sphere's motion as the engine's save gives it, every
 * slot, every calendar entry, the lists and cells), then for each of the next K events (1 to
 * 24) it keeps what the event may change, as the model will: the motion and slot of its sphere
 * and, for a pair, of the other (a free flight's reaction changes those two alone), and for a
 * list expiry its commit's record (evloop.c's apply_undoable). After the K-th commit it undoes
 * them newest first: the list commits undone, the motions and slots put back, the spheres'
 * calendar entries made again from their slots. The state must then be the copy, bit for bit
 * (motions, slots, calendar entries, lists and cells), and the loop goes on from it, handling
 * the K events again (not kept: the same events, in the same order, if the rollback was exact).
 * A window that meets a step's end is dropped (the step's end moves every sphere). In a periodic
 * fluid at phi = 0.35, elastic and dissipative (e = 0.8, the TC model): many windows rolled
 * back, with expiries and reactions among the events undone, every one back to its copy, and the
 * run with the rollbacks ends where the run without them ends, bit for bit (positions and
 * velocities; the counts count the events handled again). */
struct nbep_evloop;
struct nbep_evloop_ops;
struct evl_ws;
#include <stdint.h>
#include "nbep/feq.h"
static void look_before(struct nbep_evloop *e, const struct nbep_evloop_ops *ops, void *u,
                        uint32_t i, const nbep_event *ev);
static void take_apply(struct nbep_evloop *e, const struct evl_ws *w);
static void look_committed(struct nbep_evloop *e, const struct nbep_evloop_ops *ops, void *u);
#define NBEP_EVLOOP_BEFORE_HOOK(e, ops, u, i, ev) look_before(e, ops, u, i, ev)
#define NBEP_EVLOOP_APPLY(e, w) take_apply(e, w)
#define NBEP_EVLOOP_COMMITTED_HOOK(e, ops, u) look_committed(e, ops, u)
#include "../src/evloop.c"
#include "../src/evloop_team.c"
#include "../src/pred_cells.c" /* (its context: a step's start, T0) */

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_evloop.h"
#include "nbep_test_scene.h"

enum { PERIOD = 41, K_MAX = 24 };

/* What one event may change, kept before it is handled. */
typedef struct {
    uint32_t id[2];
    int n;
    nbep_evloop_motion m[2];
    nbep_event slot[2];
    bool expiry;      /* a list expiry: its commit's record below */
    bool applied;     /* ... taken with its record */
    evl_ws ws;
    evl_unlist rec;
} kept;

/* The state at a window's start. */
typedef struct {
    nbep_evloop_motion *m;
    nbep_event *slot;
    bool *has;
    nbep_calendar_entry *entry;
    words lists;
    size_t cap;
} copy;

static struct {
    bool on;
    uint64_t events;     /* events looked at outside the replays */
    uint64_t windows;    /* rolled back */
    uint64_t dropped;    /* met a step's end */
    uint64_t undone, undone_expiries, undone_pairs;
    uint64_t differ;     /* rollbacks not back to their copy */
} seen;
static kept log_[K_MAX];
static int depth, k_want, replay;
static bool logging;     /* the event being handled is kept in log_[depth - 1] */
static double t0_window;
static copy at;
static void drop_window(void);

static void copy_make(const nbep_evloop *e, const nbep_evloop_ops *ops, void *u, copy *c)
{
    const size_t n = e->n;
    if (c->cap < n) {
        c->m = realloc(c->m, n * sizeof *c->m);
        c->slot = realloc(c->slot, n * sizeof *c->slot);
        c->has = realloc(c->has, n * sizeof *c->has);
        c->entry = realloc(c->entry, n * sizeof *c->entry);
        assert_true(c->m && c->slot && c->has && c->entry);
        c->cap = n;
    }
    for (uint32_t k = 0; k < n; k++) {
        memset(&c->m[k], 0, sizeof c->m[k]); /* (padding: the copies are compared whole) */
        ops->save(u, k, &c->m[k]);
        c->slot[k] = *nbep_feq_slot(e->q, k);
        memset(&c->entry[k], 0, sizeof c->entry[k]);
        c->has[k] = nbep_calendar_get(e->cal, k, &c->entry[k]);
    }
    copy_of(e, &c->lists);
}

/* Field by field, bits compared (a struct's padding is not the save's to set). */
#define SAME_FIELD(x, y, f) (memcmp(&(x).f, &(y).f, sizeof (x).f) == 0)
static bool copy_same(const copy *a, const copy *b, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        const nbep_evloop_motion *p = &a->m[k], *q = &b->m[k];
        const nbep_calendar_entry *x = &a->entry[k], *y = &b->entry[k];
        if (!SAME_FIELD(*p, *q, pos) || !SAME_FIELD(*p, *q, vel) || !SAME_FIELD(*p, *q, tau) ||
            p->ver != q->ver || !SAME_FIELD(*p, *q, image) || !SAME_FIELD(*p, *q, own) ||
            a->has[k] != b->has[k] ||
            (a->has[k] && (!SAME_FIELD(*x, *y, time) || x->key != y->key || x->item != y->item)))
            return false;
    }
    return memcmp(a->slot, b->slot, n * sizeof *a->slot) == 0 && same(&a->lists, &b->lists);
}

static void look_before(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                        const nbep_event *ev)
{
    logging = false;
    if (!seen.on)
        return;
    if (replay > 0) { /* an event undone, handled again */
        replay--;
        return;
    }
    const double T0 = ((const cells_user *)u)->T0;
    if (depth > 0 && T0 != t0_window)
        drop_window();
    if (depth == 0) {
        if (seen.events++ % PERIOD != 0)
            return;
        k_want = 1 + (int)(seen.windows % K_MAX);
        copy_make(e, ops, u, &at);
        t0_window = T0;
    }
    kept *L = &log_[depth++];
    L->n = 0;
    L->id[L->n++] = i;
    if (ev->kind == NBEP_EVENT_SPHERE && ev->partner != i)
        L->id[L->n++] = ev->partner;
    for (int q = 0; q < L->n; q++) {
        memset(&L->m[q], 0, sizeof L->m[q]);
        ops->save(u, L->id[q], &L->m[q]);
        L->slot[q] = *nbep_feq_slot(e->q, L->id[q]);
    }
    L->expiry = ev->kind == NBEP_EVENT_HORIZON;
    L->applied = false;
    logging = true;
}

static void take_apply(nbep_evloop *e, const evl_ws *w)
{
    if (!logging) {
        apply(e, w);
        return;
    }
    kept *L = &log_[depth - 1];
    copy_ws(&L->ws, w);
    nbep__evloop_apply_undoable(e, &L->ws, &L->rec);
    L->applied = true;
}

/* The step's end: it moves every sphere, so a window open across it is dropped (its events
 * stand). The loop returns at the step's end, so the next look before is the next step's. */
static void drop_window(void)
{
    seen.dropped++;
    depth = 0;
}

static void look_committed(nbep_evloop *e, const nbep_evloop_ops *ops, void *u)
{
    if (!logging)
        return;
    logging = false;
    if (depth < k_want)
        return;
    /* newest first: each event's list commit undone, its spheres' motions and slots back */
    for (int k = depth; k-- > 0;) {
        kept *L = &log_[k];
        if (L->applied)
            nbep__evloop_unapply(e, &L->ws, &L->rec);
        for (int q = L->n; q-- > 0;) {
            ops->restore(u, L->id[q], &L->m[q]);
            nbep_feq_put(e->q, L->id[q], L->slot[q]);
        }
        seen.undone_expiries += L->expiry;
        seen.undone_pairs += L->n == 2;
    }
    assert_false(e->failed);
    /* the calendar entries of every sphere touched, from their slots as they are again */
    for (int k = 0; k < depth; k++)
        for (int q = 0; q < log_[k].n; q++)
            nbep__evloop_schedule_one(e, log_[k].id[q]);
    copy back = {0};
    copy_make(e, ops, u, &back);
    seen.differ += !copy_same(&back, &at, e->n);
    free(back.m);
    free(back.slot);
    free(back.has);
    free(back.entry);
    free(back.lists.w);
    seen.windows++;
    seen.undone += (uint64_t)depth;
    replay = depth;
    depth = 0;
}

/* sc on one thread without rollbacks and with them: every rollback back to its copy, many of
 * them with expiries and pairs undone, and the same end, bit for bit. */
static void rolled_back_and_the_same(const nbep_scene *sc, uint64_t least)
{
    nbep_state plain, rolled;
    memset(&seen, 0, sizeof seen);
    depth = replay = 0;
    const nbep_summary s0 = nbep_test_run(sc, 1, NULL, NULL, &plain, NULL);
    seen.on = true;
    const nbep_summary s1 = nbep_test_run(sc, 1, NULL, NULL, &rolled, NULL);
    seen.on = false;
    fprintf(stderr,
            "%llu windows rolled back (%llu events undone: %llu pairs, %llu expiries), %llu not "
            "back to their copy, %llu dropped at a step's end; %llu and %llu collisions\n",
            (unsigned long long)seen.windows, (unsigned long long)seen.undone,
            (unsigned long long)seen.undone_pairs, (unsigned long long)seen.undone_expiries,
            (unsigned long long)seen.differ, (unsigned long long)seen.dropped,
            (unsigned long long)s0.sphere_collisions, (unsigned long long)s1.sphere_collisions);
    assert_int_equal(seen.differ, 0);
    assert_true(seen.windows >= least);
    assert_true(seen.undone_pairs > seen.windows && seen.undone_expiries > seen.windows / 4);
    /* the events handled again counted again */
    assert_true(s1.sphere_collisions > s0.sphere_collisions);
    nbep_test_same_end(&plain, &rolled);
}

static void test_an_elastic_fluid_rolled_back_runs_the_same(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(8, 0.35, 40, 0.02, 7);
    rolled_back_and_the_same(sc, 60);
    nbep_test_scene_free(&sc);
}

/* e = 0.8 with the TC model: the motion kept holds the TC clock and the reaction count too */
static void test_a_dissipative_fluid_rolled_back_runs_the_same(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(8, 0.35, 40, 0.02, 8);
    sc->restitution = 0.8;
    sc->tc = 1e-3;
    rolled_back_and_the_same(sc, 60);
    nbep_test_scene_free(&sc);
}

static int teardown(void **state)
{
    (void)state;
    for (int k = 0; k < K_MAX; k++) {
        nbep__evloop_ws_copy_fini(&log_[k].ws);
        nbep__evloop_unlist_fini(&log_[k].rec);
    }
    free(at.m);
    free(at.slot);
    free(at.has);
    free(at.entry);
    free(at.lists.w);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_elastic_fluid_rolled_back_runs_the_same),
        cmocka_unit_test(test_a_dissipative_fluid_rolled_back_runs_the_same),
    };
    return cmocka_run_group_tests(tests, NULL, teardown);
}
