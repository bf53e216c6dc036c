/* A signal within a step of the naive and seminaive algorithms (a job's time limit during a pass
 * over the pairs of tens of seconds): the pass looks at the stop signal as it goes, and the step
 * is abandoned on every thread at once, the run ending after the step before with that step's
 * state bit for bit (README, Faults). No scene a test can build makes a pass long enough for a
 * real signal to land in it on cue, so this test compiles its own copy of the algorithms
 * (src/algo_detect.c) whose hook raises the signal at a given row of a given step and makes the
 * pass look there: a function of the row alone, so every thread count meets it in the same
 * step. */
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

static bool look_hook(uint64_t step, size_t row);
#define NBEP_DETECT_LOOK_HOOK(step, row) look_hook(step, row)
#include "../src/algo_detect.c"

#include <stdarg.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"
#include "nbep_test_signalled.h"
#include "nbep_test_watchdog.h"

/* From row signal_row of step signal_step on, the run's stop signal is raised (SIGTERM) and the
 * pass looks at it after every row (it looks every LOOK_COST tests, more than a step of these
 * scenes makes): as though a job's time limit came then. */
static uint64_t signal_step = UINT64_MAX;
static size_t signal_row;
static atomic_int test_signal;

static bool look_hook(uint64_t step, size_t row)
{
    if (step != signal_step || row < signal_row)
        return false;
    atomic_store_explicit(&test_signal, SIGTERM, memory_order_relaxed);
    return true;
}

/* sc run on nt threads with test_signal as its stop signal (nbep_test_run_signalled) */
static nbep_status run_signalled(const nbep_scene *sc, int nt, nbep_summary *sum, bool *abandoned,
                                 nbep_state *fin, uint64_t frame_step)
{
    return nbep_test_run_signalled(sc, nt, &test_signal, sum, abandoned, fin, frame_step);
}

/* A closed-box fluid at phi = 0.35 under gravity (many collisions a step, with the walls too;
 * gravity, so that a step's drift changes velocities too) run by algo for 6 steps, frames every
 * 2, the signal raised in its third step at a row near the start, the
 * middle and the end of the pass (the first thread's rows, a later one's, the last one's): on
 * 1 to 4 threads the step is abandoned and the run ends as a run of 2 steps ends, its counts
 * (none of the abandoned step's), its last frame that of step 2, and its spheres where step 2
 * left them, bit for bit (the abandoned step's drift put back, nothing of its responses). */
static void abandons_as_two_steps_end(const char *algo, bool periodic)
{
    nbep_test_watchdog_arm(120, "test_detect_stop: a run did not end (threads that left an "
                                "abandoned step at different points wait at a barrier)\n");
    /* periodic: the image counts the abandoned step's flight moved (spheres falling through
     * the z faces) are put back too */
    nbep_scene *sc = periodic ? nbep_test_periodic_fluid(nbep_test_scaled(7, 5), 0.35, 2, 0.05, 5)
                              : nbep_test_fluid(nbep_test_scaled(7, 5), 0.35, 2, 0.05);
    sc->neighbors_cells = false;
    if (periodic) { /* the lowest layer 0.12 above the floor face: spheres falling at 0.07 to
                     * 0.7 cross it in the third step, the abandoned one */
        const double a = (sc->box_max.z - sc->box_min.z) / (double)nbep_test_scaled(7, 5);
        for (size_t i = 0; i < sc->state.n; i++)
            sc->state.pos[i].z += 0.12 - 0.5 * a;
    }
    snprintf(sc->algorithm, sizeof sc->algorithm, "%s", algo);
    sc->output_every = 2; /* frames at steps 0, 2, 4, 6: the last before the signal, 2 */
    const size_t n = sc->state.n;
    for (size_t i = 0; i < n; i++)
        sc->state.acc[i] = (nbep_vec3){0.0, 0.0, -9.81};
    nbep_summary two, sum;
    bool abandoned;
    nbep_state fin2, fin;
    assert_int_equal(run_signalled(sc, 1, &two, &abandoned, &fin2, 2), NBEP_OK);
    assert_false(abandoned);
    assert_true(two.collisions > 0);
    /* the overlaps the pass measures reach the summary: every radius is 0.5, so the relative
     * overlap is twice the absolute one, exactly */
    assert_true(two.max_overlap > 0.0);
    assert_true(two.max_overlap_rel == 2.0 * two.max_overlap);
    sc->steps = 6;
    const size_t rows[] = {0, n / 2, n - 2};
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; r++) {
        signal_step = 3;
        signal_row = rows[r];
        for (int nt = 1; nt <= 4; nt++) {
            assert_int_equal(run_signalled(sc, nt, &sum, &abandoned, &fin, 2), NBEP_ESIGTERM);
            assert_true(abandoned);
            assert_int_equal(sum.steps, 2);
            assert_int_equal(sum.collisions, two.collisions);
            assert_int_equal(sum.checks, two.checks);
            assert_int_equal(sum.quiet_steps, two.quiet_steps);
            assert_true(sum.max_overlap == two.max_overlap);
            assert_true(sum.energy_final == two.energy_final);
            assert_memory_equal(fin.pos, fin2.pos, n * sizeof *fin2.pos);
            assert_memory_equal(fin.vel, fin2.vel, n * sizeof *fin2.vel);
            assert_memory_equal(fin.image, fin2.image, 3 * n * sizeof *fin2.image);
            nbep_state_fini(&fin);
        }
    }
    /* unarmed, the same run ends: the stop is the hook's */
    signal_step = UINT64_MAX;
    assert_int_equal(run_signalled(sc, 2, &sum, &abandoned, &fin, 6), NBEP_OK);
    assert_false(abandoned);
    assert_int_equal(sum.steps, 6);
    nbep_state_fini(&fin);
    nbep_state_fini(&fin2);
    nbep_test_scene_free(&sc);
    nbep_test_watchdog_disarm();
}

/* The threads' detection rows (split_rows): contiguous shares covering every row once, whose
 * pair tests add up to the whole and come within one row's tests of an even share each, for
 * naive (row i costs the planes and n - 1 - i pairs, so the first threads take fewer rows) and
 * seminaive (a flat 8 a row), with and without planes, on 1 to 4 threads. A split that put
 * every row on thread 0 (the eleventh draw's `/ nt` as `* nt`) changed no result, only made
 * every thread count as slow as one. */
static void test_detection_rows_split_into_even_shares_of_the_pair_tests(void **state)
{
    (void)state;
    const size_t ns[] = {1, 2, 3, 7, 100, 1000, 4096};
    for (int bvh = 0; bvh < 2; bvh++)
        for (size_t np = 0; np <= 6; np += 6)
            for (size_t u = 0; u < sizeof ns / sizeof *ns; u++)
                for (int nt = 1; nt <= 4; nt++) {
                    const size_t n = ns[u];
                    contact_list lists[4];
                    detect_ctx ctx = {.use_bvh = bvh, .lists = lists};
                    split_rows(&ctx, n, np, nt);
                    double total = 0.0;
                    for (size_t i = 0; i < n; i++)
                        total += (double)row_cost(bvh, n, np, i);
                    /* the dearest row: the first (naive), or any (seminaive) */
                    const double row = (double)row_cost(bvh, n, np, 0);
                    uint64_t sum = 0;
                    size_t at = 0;
                    for (int t = 0; t < nt; t++) {
                        if (lists[t].row_lo != at || lists[t].row_hi < at ||
                            fabs((double)lists[t].cost - total / nt) > row)
                            fail_msg("%s, %zu spheres, %zu planes, %d threads: thread %d has "
                                     "rows %zu to %zu (after %zu), %llu tests of %g",
                                     bvh ? "seminaive" : "naive", n, np, nt, t,
                                     lists[t].row_lo, lists[t].row_hi, at,
                                     (unsigned long long)lists[t].cost, total);
                        at = lists[t].row_hi;
                        sum += lists[t].cost;
                    }
                    assert_int_equal(at, n);
                    assert_true((double)sum == total);
                }
}

static void test_naive_abandons_a_step_signalled_in_its_pass(void **state)
{
    (void)state;
    abandons_as_two_steps_end("naive", false);
    abandons_as_two_steps_end("naive", true);
}

static void test_seminaive_abandons_a_step_signalled_in_its_pass(void **state)
{
    (void)state;
    abandons_as_two_steps_end("seminaive", false);
    abandons_as_two_steps_end("seminaive", true);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_detection_rows_split_into_even_shares_of_the_pair_tests),
        cmocka_unit_test(test_naive_abandons_a_step_signalled_in_its_pass),
        cmocka_unit_test(test_seminaive_abandons_a_step_signalled_in_its_pass),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
