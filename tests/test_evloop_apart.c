/* The team loop's apartness, checked at every place that joins the window, by means of its own.
 * Two events in flight at once must touch nothing in common (src/evloop_team.c, place_apart): no
 * sphere one writes may be read or written by the other, and no cell one's commit changes may be
 * read by the other's walk. Whether a breach of that does harm depends on the schedule (the two
 * events must run at the same moment and meet), so tests of the results (test_periodic) catch a
 * wrong apartness test only now and then: the mutants that measure the distance without the
 * periodic wrap, or that never compare two expiries' cells, survived runs of test_periodic while
 * other work shared the machine. Which places are in flight together does not depend on the
 * schedule: the leader alone fills the window, after each commit, in the calendar's order. So this
 * test compiles its own copy of the engine (src/evloop.c and src/evloop_team.c) with a hook at
 * each place's joining that checks, in doubles and through nbep_periodic_image rather than the
 * loop's float test, that its spheres' list centres are farther than `touch` from those of every
 * place in flight (what an event touches lies within touch of its spheres' centres: a breach of
 * this may do harm) and farther than twice touch (what the loop keeps, leaving a margin: a breach
 * of only this does no harm, but shows a test other than the one evloop_team.c describes; one that
 * forgets the wrap for a place's own sphere, say, which errs within touch only once the place's
 * other sphere is far), and, for two list expiries, that the cells one's commit changes (its cell
 * and the neighbour its new centre may enter) and the cells the other's walk reads (the blocks
 * around its cell's neighbours) share none, counted cell by cell. It also counts that the scenes
 * come close to both limits, across periodic faces too, so that a test which looked away would
 * fail. */
struct nbep_evloop;
static void audit_join(const struct nbep_evloop *e);
#define NBEP_EVLOOP_JOIN_HOOK(e) audit_join(e)
#include "../src/evloop.c"
#include "../src/evloop_team.c"

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

/* The relative rounding of the distances this test computes in doubles (a few units of 2^-52),
 * with room to spare: the loop's float test keeps list centres apart by twice touch plus its
 * own roundings' bound (set_near2), so a centre it let in is farther than twice touch. */
#define MARGIN_ROUNDING 1e-12

/* What the hook saw over a run: written by the leader's thread alone (it fills the window),
 * read after the run. */
static struct {
    uint64_t joins;      /* places that joined with others in flight */
    uint64_t pairs;      /* (joining sphere, sphere in flight) pairs */
    uint64_t too_near;   /* of those, list centres within touch (harm may follow) */
    uint64_t in_margin;  /* within twice touch, the distance the loop keeps (its margin) */
    uint64_t across;     /* pairs within 3 touch only the periodic way round */
    double least;        /* the least distance of a pair, over touch */
    uint64_t walks;      /* (joining expiry, expiry in flight) pairs */
    uint64_t clashes;    /* of those, a cell one's commit changes that the other's walk reads */
    size_t least_cells;  /* the least, over those pairs, of the cells apart along their
                          * farthest axis (the nearest way round on a periodic one) */
    uint64_t misread;    /* places the window took for an expiry or not, wrongly */
    uint64_t planes;     /* places that were a plane contact */
} seen;

static void seen_reset(void)
{
    memset(&seen, 0, sizeof seen);
    seen.least = INFINITY;
    seen.least_cells = SIZE_MAX;
}

/* What each place in flight touches, as this test reads it when the place joins (by ring
 * slot): its calendar entry's sphere, and from that sphere's slot (which the thread that
 * handles it reads, and which nothing writes between), the partner a sphere event names and
 * whether it is a list expiry. Not from the window's own record of them (batch, batch_other,
 * batch_walks), which a wrong decoding of the calendar key would spoil for this test too. */
static struct {
    uint32_t sphere[2];
    int n;
    bool walks;
} placed[RING];

static void record_place(const nbep_evloop *e, size_t k)
{
    const uint32_t i = e->batch_entry[k].item;
    const nbep_event ev = *nbep_feq_slot(e->q, i);
    placed[k].n = 0;
    placed[k].sphere[placed[k].n++] = i;
    if (ev.kind == NBEP_EVENT_SPHERE && ev.partner < e->n)
        placed[k].sphere[placed[k].n++] = ev.partner;
    placed[k].walks = ev.kind == NBEP_EVENT_HORIZON;
}

/* Cell a's index along one axis of dim cells, moved by da, wrapped on a periodic axis; -1 off
 * the end of one that is not. */
static long cell_step(size_t a, long da, size_t dim, bool periodic)
{
    const long d = (long)dim, x = (long)a + da;
    if (periodic)
        return ((x % d) + d) % d;
    return x >= 0 && x < d ? x : -1;
}

/* Whether, along one axis, a cell within one of a (what a commit in cell a changes: its cell
 * and the one its new centre may enter) is a cell within two of b (what a walk from cell b
 * reads: the blocks around the cell its new centre may enter). Counted cell by cell. */
static bool axis_meets(size_t a, size_t b, size_t dim, bool periodic)
{
    for (long i = -1; i <= 1; i++)
        for (long j = -2; j <= 2; j++) {
            const long x = cell_step(a, i, dim, periodic), y = cell_step(b, j, dim, periodic);
            if (x >= 0 && x == y)
                return true;
        }
    return false;
}

static void cell_coords(const nbep_cells *g, uint32_t i, size_t *c)
{
    size_t id = g->m[i].cell;
    for (int k = 0; k < 3; k++) {
        c[k] = id % g->dim[k];
        id /= g->dim[k];
    }
}

static void audit_join(const nbep_evloop *e)
{
    const size_t kj = e->tail % RING;
    record_place(e, kj);
    /* the window's own reading of the calendar key agrees: an expiry walks, nothing else does
     * (a contact with plane 0 had an expiry's key, and the loop held it to the cells' rule) */
    seen.misread += e->batch_walks[kj] != placed[kj].walks;
    seen.planes += nbep_feq_slot(e->q, e->batch_entry[kj].item)->kind == NBEP_EVENT_PLANE;
    if (e->head == e->tail)
        return;
    seen.joins++;
    const double touch = e->cut + (1.0 + NBEP_NBLIST_LEAD) * e->stray;
    const uint32_t *a = placed[kj].sphere;
    const int na = placed[kj].n;
    for (uint64_t p = e->head; p < e->tail; p++) {
        const size_t kp = p % RING;
        const uint32_t *b = placed[kp].sphere;
        const int nb = placed[kp].n;
        for (int q = 0; q < na; q++)
            for (int r = 0; r < nb; r++) {
                const nbep_vec3 raw = nbep_vec3_sub(e->cells.m[a[q]].at, e->cells.m[b[r]].at);
                const double dist = nbep_vec3_norm(nbep_periodic_image(&e->pb, raw));
                seen.pairs++;
                seen.too_near += !(dist > touch);
                seen.in_margin += !(dist > 2.0 * touch * (1.0 - MARGIN_ROUNDING));
                seen.least = fmin(seen.least, dist / touch);
                seen.across += dist < 3.0 * touch && !(nbep_vec3_norm(raw) < 3.0 * touch);
            }
        if (!(placed[kj].walks && placed[kp].walks))
            continue;
        seen.walks++;
        size_t ca[3], cb[3], far = 0;
        cell_coords(&e->cells, a[0], ca);
        cell_coords(&e->cells, b[0], cb);
        bool meets = true;
        for (int k = 0; k < 3; k++) {
            const bool wrap = e->cells.periodic[k];
            meets &= axis_meets(ca[k], cb[k], e->cells.dim[k], wrap) ||
                     axis_meets(cb[k], ca[k], e->cells.dim[k], wrap);
            size_t d = ca[k] > cb[k] ? ca[k] - cb[k] : cb[k] - ca[k];
            if (wrap && e->cells.dim[k] - d < d)
                d = e->cells.dim[k] - d;
            far = d > far ? d : far;
        }
        seen.clashes += meets;
        seen.least_cells = far < seen.least_cells ? far : seen.least_cells;
    }
}

/* Runs sc on 2 threads with the team loop at every step; its checks of apartness pass, and the
 * run came near them: places joined beside many in flight, some within 2.1 touch of one
 * (the loop's limit is 2 touch, and its float test's rounding margin is far below that), and
 * expiries 4 cells apart along their farthest axis (the least the loop lets join). */
static void run_audited(nbep_scene *sc, bool periodic)
{
    setenv("NBEP_TEAM", "always", 1);
    seen_reset();
    uint64_t counts[NBEP_COUNTER_COUNT];
    const nbep_summary s = nbep_test_run_counted(sc, 2, NULL, NULL, NULL, counts);
    unsetenv("NBEP_TEAM");
    assert_true(s.sphere_collisions > s.spheres);
    assert_true(counts[NBEP_COUNTER_AHEAD] > 0);
    assert_true(seen.joins > s.spheres);
    assert_int_equal(seen.too_near, 0);
    assert_int_equal(seen.in_margin, 0);
    assert_int_equal(seen.clashes, 0);
    assert_true(seen.least < 2.1);
    assert_true(seen.walks > 100);
    assert_int_equal(seen.least_cells, 4);
    assert_int_equal(seen.misread, 0);
    if (periodic)
        assert_true(seen.across > 100);
    if (sc->state.n_planes > 0) /* walls: plane contacts joined, plane 0's among them */
        assert_true(seen.planes > 100);
}

/* A dense periodic fluid, as test_periodic's team test has it: 9 cells of the list cutoff
 * across, so that expiries 4 cells apart the nearest way round are often across a face. */
static void test_places_in_flight_are_apart_in_a_periodic_fluid(void **state)
{
    (void)state;
    /* (small: 18 steps, as the dense skin of 0.5 walks fewer lists than 0.4 did in 12) */
    nbep_scene *sc = nbep_test_periodic_fluid(nbep_test_scaled(16, 12), 0.45,
                                              nbep_test_scaled(30, 18), 0.02, 3);
    run_audited(sc, true);
    nbep_test_scene_free(&sc);
}

/* The same in a closed box (walls, no wrap: list centres clamped near the faces). */
static void test_places_in_flight_are_apart_in_a_closed_box(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_fluid(nbep_test_scaled(16, 12), 0.40, nbep_test_scaled(30, 12),
                                     0.02);
    sc->neighbors_cells = true;
    run_audited(sc, false);
    nbep_test_scene_free(&sc);
}

/* Without a box: an expanding cluster (its cells cover the spheres' extent, laid out afresh
 * as it grows; list centres that left the region are clamped into the loop's floats, a
 * projection that only brings them closer). */
static void test_places_in_flight_are_apart_in_a_cluster_without_a_box(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_cluster("predictive", nbep_test_scaled(14, 12),
                                       nbep_test_scaled(60, 40));
    sc->neighbors_cells = true;
    run_audited(sc, false);
    nbep_test_scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_places_in_flight_are_apart_in_a_periodic_fluid),
        cmocka_unit_test(test_places_in_flight_are_apart_in_a_closed_box),
        cmocka_unit_test(test_places_in_flight_are_apart_in_a_cluster_without_a_box),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
