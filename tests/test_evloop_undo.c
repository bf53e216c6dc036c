/* An expiry's commit undone (evloop.c: nbep__evloop_apply_undoable, nbep__evloop_unapply, over
 * nblist.h's undrop and unappend and cells.h's put_back): the building block of list expiries
 * run ahead by an optimistic engine, which must put the lists and cells back as the serial run
 * has them, their order too (a list's order decides nothing in a fluid's predictions, but a
 * pile's let-go walks lists in order, and exact is what can be checked).
 *
 * This test compiles its own copy of the engine, whose expiry commits it takes over: the lists
 * and cells copied whole (every list's entries in order, every cell's members in order, every
 * list centre bit for bit), the commit applied with its record, undone, copied again and
 * compared, then applied again as the run would (so the run goes on as it would have). Then
 * as a rollback undoes them: six commits in a row applied (each expiry's walk seeing the lists
 * its predecessors left), the lists' pool compacted after each apply and each undo (every list
 * moved, its room cut to its fresh layout's), the six undone newest first and compared with
 * what was before the first, then applied again. In a periodic fluid at phi = 0.35 and a pile
 * settling in a box at e = 0.6 under gravity: every undo is what was before, the commits undone
 * include ones that moved their sphere to another cell, lost neighbours out of the middle of a
 * list and gained others; and the run with every commit undone and made again ends as the run
 * without, bit for bit (positions, velocities, collisions). One thread. */
struct nbep_evloop;
struct evl_ws;
static void take_apply(struct nbep_evloop *e, const struct evl_ws *w);
#define NBEP_EVLOOP_APPLY(e, w) take_apply(e, w)
#include "../src/nblist.c" /* (its compaction, to move every list between apply and undo) */
#include "../src/evloop.c"
#include "../src/evloop_team.c"

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"
#include "nbep_test_evloop.h"

static struct {
    bool undo;          /* take the commits over (else apply them as the engine does) */
    int batch;          /* commits applied before they are undone (newest first) */
    bool squeeze;       /* the pool compacted after each apply and each undo */
    uint64_t commits;   /* expiry commits undone */
    uint64_t batches;   /* ... in this many undos of `batch` */
    uint64_t differ;    /* undos that left something not as it was */
    uint64_t broken;    /* batches whose lists something else changed meanwhile (a step's full
                         * rebuild): dropped, not undone */
    uint64_t changed;   /* commits that changed the lists or cells (all: each moves its centre) */
    uint64_t moved;     /* ... that moved their sphere into another cell */
    uint64_t mid;       /* ... that took a lost neighbour's entry out of the middle of its list */
    uint64_t gained;    /* ... that entered a neighbour's list */
    uint64_t lost, was, near; /* their lost neighbours, old and new lists' entries, in all */
} seen;
enum { BATCH_MAX = 6 };
static words before, after, expect;
static evl_ws stack_w[BATCH_MAX]; /* the workspaces of the commits applied, copied (the engine
                                   * reuses its own for the next event) */
static evl_unlist stack_u[BATCH_MAX];
static int depth;

/* Every list moved and its room cut to a fresh layout's (the pool compacted). */
static void squeeze(nbep_evloop *e)
{
    size_t fresh = 0;
    for (size_t k = 0; k < e->nl.n; k++)
        fresh += nbep_nblist_room_for(e->nl.sp[k].cnt);
    assert_true(compact(&e->nl, fresh, 0));
}

static void take_apply(nbep_evloop *e, const evl_ws *w)
{
    if (!seen.undo) {
        apply(e, w);
        return;
    }
    if (depth > 0) { /* the lists as the batch's last commit left them, or the batch dropped */
        copy_of(e, &after);
        if (!same(&after, &expect)) {
            seen.broken++;
            depth = 0;
        }
    }
    if (depth == 0)
        copy_of(e, &before);
    evl_ws *v = &stack_w[depth];
    evl_unlist *u = &stack_u[depth];
    copy_ws(v, w);
    const uint32_t cell0 = e->cells.m[v->item].cell;
    nbep__evloop_apply_undoable(e, v, u);
    assert_false(e->failed);
    seen.moved += e->cells.m[v->item].cell != cell0;
    bool mid = false, gained = false;
    for (size_t k = 0, d = 0; k < v->n_was; k++)
        if (!v->kept[k]) {
            size_t m;
            (void)nbep_nblist_of(&e->nl, v->was[k], &m);
            mid |= u->drop_q[d++] < m; /* another entry took its place */
        }
    for (size_t k = 0; k < v->n_near; k++)
        gained |= v->gain[k];
    seen.mid += mid;
    seen.gained += gained;
    seen.lost += u->n_drop;
    seen.was += v->n_was;
    seen.near += v->n_near;
    copy_of(e, &after);
    seen.changed += !same(&after, depth == 0 ? &before : &expect);
    depth++;
    if (seen.squeeze)
        squeeze(e);
    if (depth < seen.batch) {
        copy_of(e, &expect);
        return;
    }
    for (int k = depth; k-- > 0;) { /* newest first, as a rollback */
        nbep__evloop_unapply(e, &stack_w[k], &stack_u[k]);
        assert_false(e->failed);
        if (seen.squeeze)
            squeeze(e);
    }
    copy_of(e, &after);
    seen.commits += (uint64_t)depth;
    seen.batches++;
    seen.differ += !same(&after, &before);
    for (int k = 0; k < depth; k++) /* as the run would have */
        apply(e, &stack_w[k]);
    depth = 0;
}

/* sc run on one thread, then again with every expiry's commit undone and made again, `batch`
 * at a time (the pool compacted between where `squeeze`): each undo left what was, the runs end
 * the same bit for bit, and the undos met every kind of change (at least `least` commits). */
static void undone_and_the_same(const nbep_scene *sc, uint64_t least, int batch, bool squeeze)
{
    nbep_state plain, undone;
    memset(&seen, 0, sizeof seen);
    depth = 0;
    const nbep_summary s0 = nbep_test_run(sc, 1, NULL, NULL, &plain, NULL);
    seen.undo = true;
    seen.batch = batch;
    seen.squeeze = squeeze;
    const nbep_summary s1 = nbep_test_run(sc, 1, NULL, NULL, &undone, NULL);
    seen.undo = false;
    fprintf(stderr,
            "%d at a time%s: %llu commits undone in %llu undos (%llu changed, %llu moved cell, "
            "%llu out of a list's middle, %llu gained), %llu undos not as they were, %llu "
            "batches dropped; %llu collisions; per commit %.2f neighbours lost, lists of %.1f "
            "before and %.1f after\n",
            batch, squeeze ? ", the pool compacted between" : "",
            (unsigned long long)seen.commits, (unsigned long long)seen.batches,
            (unsigned long long)seen.changed, (unsigned long long)seen.moved,
            (unsigned long long)seen.mid, (unsigned long long)seen.gained,
            (unsigned long long)seen.differ, (unsigned long long)seen.broken,
            (unsigned long long)(s1.sphere_collisions + s1.plane_collisions),
            (double)seen.lost / (double)seen.commits, (double)seen.was / (double)seen.commits,
            (double)seen.near / (double)seen.commits);
    assert_int_equal(seen.differ, 0);
    assert_true(seen.commits >= least);
    assert_true(seen.batches * (uint64_t)batch == seen.commits);
    assert_true(seen.changed >= seen.commits);
    assert_true(seen.moved > 0 && seen.mid > 0 && seen.gained > 0);
    assert_true(s0.sphere_collisions > 0);
    assert_int_equal(s1.sphere_collisions, s0.sphere_collisions);
    assert_int_equal(s1.plane_collisions, s0.plane_collisions);
    nbep_test_same_end(&plain, &undone);
}

/* A periodic fluid at phi = 0.35: 8^3 spheres, lists across every face, 1.2 time units (a
 * tenth of a second; under valgrind, for the memory, a few seconds: not scaled down, so that
 * every kind of change is met there too). */
static void test_a_fluids_list_commits_undo_exactly(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(8, 0.35, 60, 0.02, 3);
    undone_and_the_same(sc, 1000, 1, false);
    undone_and_the_same(sc, 1000, BATCH_MAX, true);
    nbep_test_scene_free(&sc);
}

/* 64 spheres of unequal masses dropped into a box under gravity, e = 0.6: they land, lean on
 * one another and settle (lists of a pile: held spheres let go along them). */
static void test_a_piles_list_commits_undo_exactly(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_evloop_pile();
    undone_and_the_same(sc, 400, 1, false);
    undone_and_the_same(sc, 300, BATCH_MAX, true);
    nbep_test_scene_free(&sc);
}

static int teardown(void **state)
{
    (void)state;
    free(before.w);
    free(after.w);
    free(expect.w);
    for (int k = 0; k < BATCH_MAX; k++) {
        nbep__evloop_ws_copy_fini(&stack_w[k]);
        nbep__evloop_unlist_fini(&stack_u[k]);
    }
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_fluids_list_commits_undo_exactly),
        cmocka_unit_test(test_a_piles_list_commits_undo_exactly),
    };
    return cmocka_run_group_tests(tests, NULL, teardown);
}
