/* NBEP_SCHEDULED=1 (src/evloop_warp.c): cells mode's one-thread loop through the optimistic
 * scheduler on one slab, each event handled as the scheduler's model handles it and what it
 * changes kept in the slab's log, so that the bookkeeping's cost on the real engine can be
 * measured. It must change nothing of the results: an elastic and a dissipative (e = 0.8, TC
 * model) periodic fluid at phi = 0.35 end the same bit for bit with it as without (positions,
 * velocities, every counter), also on 2 threads (the team off where it is asked); a scene that
 * accelerates (a pile) runs as without it. A Newton's cradle struck at its high-numbered end
 * makes entries at the time of the event that makes them and before it in (key, sphere), which
 * root stamps cannot order: the stamps made where the entries are made (cascade.h) hand them out
 * in the serial loop's order, and the cradle ends as without the scheduler; one whose cascade
 * is deeper than a stamp holds stops the scheduled loop with a message that says so, and
 * nothing aborts (the log's order check). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "nbep/cascade.h"
#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

/* sc on nt threads with and without NBEP_SCHEDULED: the same end, bit for bit, the same counts */
static void scheduled_the_same(const nbep_scene *sc, int nt)
{
    nbep_state plain, sched;
    uint64_t c0[NBEP_COUNTER_COUNT], c1[NBEP_COUNTER_COUNT];
    const nbep_summary s0 = nbep_test_run_counted(sc, nt, NULL, NULL, &plain, c0);
    assert_int_equal(setenv("NBEP_SCHEDULED", "1", 1), 0);
    const nbep_summary s1 = nbep_test_run_counted(sc, nt, NULL, NULL, &sched, c1);
    assert_int_equal(unsetenv("NBEP_SCHEDULED"), 0);
    assert_true(s0.sphere_collisions > 1000);
    assert_int_equal(s1.sphere_collisions, s0.sphere_collisions);
    assert_int_equal(s1.plane_collisions, s0.plane_collisions);
    for (int k = 0; k < NBEP_COUNTER_COUNT; k++)
        if (k != NBEP_COUNTER_AHEAD && k != NBEP_COUNTER_UNDONE) /* (the team's alone) */
            assert_true(c1[k] == c0[k]);
    /* on 2 threads (NBEP_TEAM=always) the team ran ahead without it, and not with it */
    assert_true(nt == 1 || (c0[NBEP_COUNTER_AHEAD] > 0 && c1[NBEP_COUNTER_AHEAD] == 0));
    nbep_test_same_end(&plain, &sched);
}

static void test_a_fluid_scheduled_runs_the_same(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(8, 0.35, 40, 0.02, 9);
    scheduled_the_same(sc, 1);
    assert_int_equal(setenv("NBEP_TEAM", "always", 1), 0);
    scheduled_the_same(sc, 2);
    assert_int_equal(unsetenv("NBEP_TEAM"), 0);
    sc->restitution = 0.8;
    sc->tc = 1e-3;
    scheduled_the_same(sc, 1);
    nbep_test_scene_free(&sc);
}

/* 27 spheres dropped in a box under gravity at e = 0.6: not free flight, so not scheduled */
static void test_a_pile_runs_as_without_it(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_scene_new(27, 6, "predictive", 300, 1e-3);
    sc->restitution = 0.6;
    sc->neighbors_cells = true;
    nbep_test_set_box_to(sc, (nbep_vec3){0.9, 0.9, 2.0});
    for (size_t i = 0; i < 27; i++)
        nbep_test_set_sphere(sc, i,
                             (nbep_vec3){0.15 + 0.3 * (double)(i % 3),
                                         0.15 + 0.3 * (double)(i / 3 % 3),
                                         0.3 + 0.45 * (double)(i / 9)},
                             (nbep_vec3){0.0, 0.0, 0.0}, 0.1, 1.0, (nbep_vec3){0, 0, -9.81});
    nbep_state plain, sched;
    const nbep_summary s0 = nbep_test_run(sc, 1, NULL, NULL, &plain, NULL);
    assert_int_equal(setenv("NBEP_SCHEDULED", "1", 1), 0);
    const nbep_summary s1 = nbep_test_run(sc, 1, NULL, NULL, &sched, NULL);
    assert_int_equal(unsetenv("NBEP_SCHEDULED"), 0);
    assert_true(s0.plane_collisions > 0);
    assert_int_equal(s1.plane_collisions, s0.plane_collisions);
    nbep_test_same_end(&plain, &sched);
    nbep_test_scene_free(&sc);
}

/* Newton's cradle of k at rest (nbep_test_cradle, test_stamp_order's with r = 0.37): with
 * r = 0.37 the centres are rounded and a row of 12 splits after 4 levels; with r = 0.375 they
 * are exact, the whole row one cascade at one time */
static nbep_scene *cradle(size_t k, double r)
{
    return nbep_test_cradle(k, r, 1.3);
}

/* sc's cradle (k at rest) with and without the scheduler: the same end, bit for bit */
static void cradle_the_same(nbep_scene *sc, size_t k)
{
    nbep_state plain, sched;
    const nbep_summary s0 = nbep_test_run(sc, 1, NULL, NULL, &plain, NULL);
    assert_int_equal(setenv("NBEP_SCHEDULED", "1", 1), 0);
    const nbep_summary s1 = nbep_test_run(sc, 1, NULL, NULL, &sched, NULL);
    assert_int_equal(unsetenv("NBEP_SCHEDULED"), 0);
    assert_true(s0.sphere_collisions >= k); /* (k down the row; rounded, a few more) */
    assert_int_equal(s1.sphere_collisions, s0.sphere_collisions);
    nbep_test_same_end(&plain, &sched);
    nbep_test_scene_free(&sc);
}

/* Cradles of 4 (rounded, r = 0.37 and 0.25) and 8 (exact: a cascade 8 levels deep, the most a
 * stamp holds) at rest: the scheduler hands their entries out by the stamps made where they
 * were made (root stamps alone go back there, and the loop stopped as a stall before they
 * were), and they end as without it, bit for bit. With r = 0.25 a sphere's entry is made again
 * at the time it already holds one in the ties' table (replaced there, not added: a review's
 * experiment, 2026-12-07, where a table that added a second one stalled) */
static void test_a_cradle_runs_the_same_by_its_stamps(void **state)
{
    (void)state;
    cradle_the_same(cradle(4, 0.37), 4);
    cradle_the_same(cradle(4, 0.25), 4);
    cradle_the_same(cradle(NBEP_CASCADE_DEPTH, 0.375), NBEP_CASCADE_DEPTH);
}

/* A cradle of 9 at rest (exact): its cascade is deeper than a stamp holds
 * (NBEP_CASCADE_DEPTH); the scheduled loop stops there with a message that says so, and
 * nothing aborts (the log's order check), where the plain loop runs through */
static void test_a_cradle_past_the_depth_stops_it_as_a_stall(void **state)
{
    (void)state;
    nbep_scene *sc = cradle(NBEP_CASCADE_DEPTH + 1, 0.375);
    char msg[512];
    uint64_t ahead;
    nbep_state fin = {0};
    assert_int_equal(nbep_test_run_to_end(sc, 1, msg, sizeof msg, &ahead, &fin), NBEP_OK);
    nbep_state_fini(&fin);
    assert_int_equal(setenv("NBEP_SCHEDULED", "1", 1), 0);
    const nbep_status st = nbep_test_run_to_end(sc, 1, msg, sizeof msg, &ahead, &fin);
    assert_int_equal(unsetenv("NBEP_SCHEDULED"), 0);
    nbep_state_fini(&fin);
    assert_int_equal(st, NBEP_ENUMERIC);
    assert_non_null(strstr(msg, "a cascade at one time deeper than the 8 levels"));
    assert_null(strchr(msg, '\n'));
    nbep_test_scene_free(&sc);
}

/* After each test, failed or not: the settings it made gone, so that a failure in one does not
 * send the next one's plain runs through the scheduler too */
static int settings_gone(void **state)
{
    (void)state;
    return unsetenv("NBEP_SCHEDULED") | unsetenv("NBEP_TEAM");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_a_fluid_scheduled_runs_the_same, settings_gone),
        cmocka_unit_test_teardown(test_a_pile_runs_as_without_it, settings_gone),
        cmocka_unit_test_teardown(test_a_cradle_runs_the_same_by_its_stamps, settings_gone),
        cmocka_unit_test_teardown(test_a_cradle_past_the_depth_stops_it_as_a_stall,
                                  settings_gone),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
