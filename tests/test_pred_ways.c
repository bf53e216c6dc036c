/* Tests of the chooser of the ways a step's events run (src/pred_ways.c): cells mode's team
 * loop and grid mode's crews run each step on one thread, a pair or the whole team, whichever
 * the run has measured fastest, probing the others now and then. Results never depend on the
 * way (test_periodic and test_threads check the frames); what these check is the schedule:
 * which way each step gets for given costs, as the comments in pred_ways.c promise it. Costs
 * here are made up, per way, so the schedule is exact; no timing is measured. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "pred_impl.h"
#include "nbep_test.h"

#define EVENTS 1000u

#define TEAM 8 /* a team of 8 threads: three ways, 1, 2 and 8 threads */

/* Runs cells mode's steps first..last of a run whose way k costs cost(k, step) seconds an
 * event, as pred_cells.c does: step s runs w->probe[s & 1] on its first part (an eighth of its
 * events) when that is a way, then w->way[s & 1] on the rest, and the chooser sets step
 * s + 1's. The ways taken in ways[s] (s <= last), the probes in probes[s] (-1: none). */
typedef double (*cost_fn)(int way, uint64_t step);

static void run_parts(pred_ways *w, cost_fn cost, uint64_t first, uint64_t last, int *ways,
                      int *probes)
{
    for (uint64_t s = first; s <= last; s++) {
        const int way = w->way[s & 1], probe = w->probe[s & 1];
        assert_true(way >= 0 && way < (w->n > 0 ? w->n : 1));
        assert_true(probe >= -1 && probe < w->n && probe != way);
        ways[s] = way;
        probes[s] = probe;
        if (probe >= 0)
            nbep__pred_ways_note(w, probe, true, EVENTS / 8, cost(probe, s) * (EVENTS / 8));
        nbep__pred_ways_choose(w, s, way, EVENTS, cost(way, s) * EVENTS);
    }
}

#define STEPS_MAX 400

static void run_steps(pred_ways *w, cost_fn cost, uint64_t first, uint64_t last, int *ways)
{
    int probes[STEPS_MAX];
    assert_true(last < STEPS_MAX);
    run_parts(w, cost, first, last, ways, probes);
}

static void test_nbep_team_values_are_read_as_documented(void **state)
{
    (void)state;
    assert_int_equal(nbep__pred_ways_forced(NULL), PRED_WAYS_FREE);
    assert_int_equal(nbep__pred_ways_forced("always"), PRED_WAYS_ALWAYS);
    assert_int_equal(nbep__pred_ways_forced("never"), PRED_WAYS_NEVER);
    assert_int_equal(nbep__pred_ways_forced("cycle"), PRED_WAYS_CYCLE);
    assert_int_equal(nbep__pred_ways_forced("1"), PRED_WAYS_NEVER); /* a team of one */
    assert_int_equal(nbep__pred_ways_forced("2"), 2);
    assert_int_equal(nbep__pred_ways_forced("3"), 3);
    assert_int_equal(nbep__pred_ways_forced("100000"), NBEP_EVLOOP_TEAM_MAX);
    const char *free_ones[] = {"", "0", "-3", "2x", "x2", "Always"};
    for (size_t k = 0; k < sizeof free_ones / sizeof *free_ones; k++)
        assert_int_equal(nbep__pred_ways_forced(free_ones[k]), PRED_WAYS_FREE);
}

static void test_the_first_step_runs_the_largest_way_unless_never(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    assert_int_equal(w.way[0], 2);
    assert_int_equal(w.way[1], 2);
    assert_int_equal(w.crew[2], 8);
    assert_int_equal(w.last, -1);
    assert_int_equal(w.probe[0], -1);
    assert_int_equal(w.probe[1], -1);
    for (int k = 0; k < PRED_WAYS_MAX; k++)
        assert_true(w.cost[k] == 0.0);
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_NEVER);
    assert_int_equal(w.way[1], 0);
    nbep__pred_ways_init(&w, 0, PRED_WAYS_FREE); /* all pairs: nothing to choose */
    assert_int_equal(w.way[0], 0);
    assert_int_equal(w.way[1], 0);
}

/* The team a little faster than the pair, the pair than one thread: no way clearly ahead. */
static double close_costs(int way, uint64_t step)
{
    (void)step;
    return 1.0 - 0.1 * way;
}

static void test_each_way_is_measured_once_largest_first_then_the_fastest_is_taken(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    int ways[40], probes[40];
    run_parts(&w, close_costs, 1, 39, ways, probes);
    /* the team a whole step, the pair and one thread the first parts of the next two */
    const int probe_of[] = {0, -1, 1, 0, -1, -1, -1, -1};
    for (uint64_t s = 1; s < 8; s++) {
        assert_int_equal(ways[s], 2);
        assert_int_equal(probes[s], probe_of[s]);
    }
}

/* One thread fastest, the pair next, the team slowest (its cores far apart or busy). */
static double team_slow(int way, uint64_t step)
{
    (void)step;
    return 1.0 + 0.5 * way;
}

static void test_from_the_second_step_the_fastest_measured_way_is_taken(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    int ways[20], probes[20];
    run_parts(&w, team_slow, 1, 19, ways, probes);
    assert_int_equal(ways[1], 2);
    assert_int_equal(ways[2], 2); /* the only way measured */
    assert_int_equal(probes[2], 1);
    assert_int_equal(ways[3], 1); /* the pair's part was faster */
    assert_int_equal(probes[3], 0);
    for (uint64_t s = 4; s < 8; s++) {
        assert_int_equal(ways[s], 0);
        assert_int_equal(probes[s], -1);
    }
}

static void test_probes_come_every_eighth_step_taking_the_other_ways_in_turn(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    enum { LAST = 200 };
    int ways[LAST + 1], probes[LAST + 1];
    run_parts(&w, close_costs, 1, LAST, ways, probes);
    int n_probes[3] = {0, 0, 0}, last_probe = -1;
    for (uint64_t s = 4; s <= LAST; s++) {
        assert_int_equal(ways[s], 2); /* a probe is a step's first part only */
        if (s % 8 != 0) {
            assert_int_equal(probes[s], -1);
            continue;
        }
        assert_true(probes[s] == 0 || probes[s] == 1);
        assert_int_not_equal(probes[s], last_probe); /* in turn */
        last_probe = probes[s];
        n_probes[probes[s]]++;
    }
    assert_int_equal(n_probes[0] + n_probes[1], LAST / 8);
    assert_true(n_probes[0] >= LAST / 16 - 1 && n_probes[1] >= LAST / 16 - 1);
}

/* The team twice as fast as either other way: clear of them (TEAM_CLEAR). */
static double clear_costs(int way, uint64_t step)
{
    (void)step;
    return way == 2 ? 0.5 : 1.0;
}

static void test_a_clear_winner_is_probed_every_64th_step_only(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    enum { LAST = 300 };
    int ways[LAST + 1], probes[LAST + 1];
    run_parts(&w, clear_costs, 1, LAST, ways, probes);
    int n_probes = 0;
    for (uint64_t s = 4; s <= LAST; s++) {
        assert_int_equal(ways[s], 2);
        assert_int_equal(probes[s] >= 0, s % 64 == 0);
        n_probes += probes[s] >= 0;
    }
    assert_int_equal(n_probes, LAST / 64);
}

/* The team fastest until step 20, then four times as slow (another job took its cores). */
static double team_turns_slow(int way, uint64_t step)
{
    if (way == 2)
        return step <= 20 ? 0.5 : 2.0;
    return way == 1 ? 0.9 : 1.0;
}

static void test_a_way_that_turns_slower_is_left_at_once(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    int ways[31];
    run_steps(&w, team_turns_slow, 1, 30, ways);
    for (uint64_t s = 1; s <= 21; s++)
        assert_int_equal(ways[s], 2);
    /* step 21 measured the team at 2.0: its mean (0.5 + 2.0) / 2 is above the pair's 0.9 */
    assert_int_equal(ways[22], 1);
}

/* The team fastest; one noisy step of it (step 20) slower than the pair. */
static double one_noisy_step(int way, uint64_t step)
{
    if (way == 2)
        return step == 20 ? 1.2 : 0.5;
    return way == 1 ? 1.0 : 1.1;
}

static void test_one_slow_step_of_the_fastest_way_does_not_turn_the_run(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    int ways[31];
    run_steps(&w, one_noisy_step, 1, 30, ways);
    /* its running mean after step 20 is about 0.85, still below the pair's 1.0 */
    assert_int_equal(ways[20], 2);
    assert_int_equal(ways[21], 2);
}

/* The pair measured slow at the start (a lattice melting), fast later: only a probe, whose
 * figure replaces the old one, can tell. */
static double pair_gets_faster(int way, uint64_t step)
{
    if (way == 1)
        return step < 10 ? 3.0 : 0.4;
    return way == 2 ? 1.0 : 3.0;
}

static void test_a_probe_replaces_the_probed_ways_figure(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    int ways[140], probes[140];
    run_parts(&w, pair_gets_faster, 1, 139, ways, probes);
    /* the team clear of the others (3.0 >= 1.25 x 1.0): the first probe at step 64 */
    for (uint64_t s = 4; s <= 64; s++) {
        assert_int_equal(ways[s], 2);
        assert_int_equal(probes[s], s == 64 ? 1 : -1); /* in turn, the pair first */
    }
    for (uint64_t s = 65; s < 72; s++)
        assert_int_equal(ways[s], 1);
}

static void test_a_first_part_replaces_its_ways_figure_and_the_rest_is_averaged(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    nbep__pred_ways_choose(&w, 1, 2, EVENTS, 1.0 * EVENTS);
    nbep__pred_ways_note(&w, 1, true, EVENTS, 3.0 * EVENTS);
    nbep__pred_ways_note(&w, 1, true, EVENTS, 2.0 * EVENTS);
    assert_true(w.cost[1] == 2.0);
    nbep__pred_ways_choose(&w, 2, 2, EVENTS, 2.0 * EVENTS);
    assert_true(w.cost[2] == 1.5);
}

static double equal_costs(int way, uint64_t step)
{
    (void)way;
    (void)step;
    return 1.0;
}

static void test_ties_go_to_the_way_with_more_threads(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    int ways[16];
    run_steps(&w, equal_costs, 1, 15, ways);
    for (uint64_t s = 4; s < 8; s++)
        assert_int_equal(ways[s], 2);
    int probes[16];
    nbep__pred_ways_init(&w, 2, PRED_WAYS_FREE); /* two ways: one thread or a pair */
    run_parts(&w, equal_costs, 1, 15, ways, probes);
    for (uint64_t s = 1; s < 16; s++)
        assert_int_equal(ways[s], 1);
    for (uint64_t s = 1; s < 16; s++) /* one thread's first part in step 2, then its probes */
        assert_int_equal(probes[s], s == 2 || s == 8 ? 0 : -1);
}

static void test_never_always_a_count_and_cycle_fix_the_way(void **state)
{
    (void)state;
    pred_ways w;
    int ways[20], probes[20];
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_NEVER);
    run_parts(&w, clear_costs, 1, 19, ways, probes);
    for (uint64_t s = 1; s <= 19; s++) {
        assert_int_equal(ways[s], 0);
        assert_int_equal(probes[s], -1);
    }
    const int forced[] = {PRED_WAYS_ALWAYS, 3};
    for (size_t f = 0; f < 2; f++) {
        nbep__pred_ways_init(&w, TEAM, forced[f]);
        run_parts(&w, close_costs, 1, 19, ways, probes); /* the team never fastest: taken */
        for (uint64_t s = 1; s <= 19; s++) {
            assert_int_equal(ways[s], 2);
            assert_int_equal(probes[s], -1);
        }
    }
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_CYCLE);
    run_parts(&w, clear_costs, 1, 19, ways, probes);
    assert_int_equal(probes[1], -1);
    for (uint64_t s = 1; s <= 19; s++) { /* the whole team first, then down, in turn */
        assert_int_equal(ways[s], (int)(2 - (s - 1) % 3));
        if (s > 1) /* the first part: the way after the step's own */
            assert_int_equal(probes[s], (ways[s] + 2) % 3);
    }
    nbep__pred_ways_init(&w, 2, PRED_WAYS_CYCLE); /* two ways: each the other's first part */
    run_parts(&w, clear_costs, 1, 9, ways, probes);
    for (uint64_t s = 2; s <= 9; s++) {
        assert_int_equal(ways[s], (int)(1 - (s - 1) % 2));
        assert_int_equal(probes[s], 1 - ways[s]);
    }
}

static void test_a_step_without_events_measures_nothing(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    nbep__pred_ways_choose(&w, 1, 2, 0, 1.0);
    assert_true(w.cost[2] == 0.0);
    assert_int_equal(w.way[0], 2); /* still unmeasured: the team again, whole */
    assert_int_equal(w.probe[0], -1);
    nbep__pred_ways_note(&w, 1, true, 0, 1.0);
    assert_true(w.cost[1] == 0.0);
}

static void test_a_steps_way_is_written_for_the_next_step_only(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    for (uint64_t s = 1; s < 40; s++) {
        /* other threads may still read them */
        const int now = w.way[s & 1], probe = w.probe[s & 1];
        if (probe >= 0)
            nbep__pred_ways_note(&w, probe, true, EVENTS, close_costs(probe, s) * EVENTS);
        nbep__pred_ways_choose(&w, s, now, EVENTS, close_costs(now, s) * EVENTS);
        assert_int_equal(w.way[s & 1], now);
        assert_int_equal(w.probe[s & 1], probe);
    }
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    for (uint64_t s = 1; s < 40; s++) {
        const int now = w.way[s & 1];
        nbep__pred_ways_choose_crew(&w, s, now, close_costs(now, s));
        assert_int_equal(w.way[s & 1], now);
    }
}

/* Grid mode times whole steps, and a step whose way differs from the step before's is not
 * timed: the next runs the same way, and is. */
static void test_grid_crews_time_only_the_second_step_of_a_way(void **state)
{
    (void)state;
    pred_ways w;
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_FREE);
    int ways[40];
    for (uint64_t s = 1; s < 40; s++) {
        ways[s] = w.way[s & 1];
        const double before = w.cost[ways[s]];
        const bool changed = ways[s] != w.last;
        nbep__pred_ways_choose_crew(&w, s, ways[s], close_costs(ways[s], s));
        if (changed)
            assert_true(w.cost[ways[s]] == before);
        else
            assert_true(w.cost[ways[s]] != 0.0);
        assert_int_equal(w.probe[(s + 1) & 1], -1); /* whole steps only */
    }
    const int first[] = {2, 2, 1, 1, 0, 0, 2, 2};
    for (size_t s = 1; s <= 8; s++)
        assert_int_equal(ways[s], first[s - 1]);
    nbep__pred_ways_init(&w, TEAM, PRED_WAYS_CYCLE); /* every step a change, for tests */
    for (uint64_t s = 1; s < 10; s++) {
        ways[s] = w.way[s & 1];
        nbep__pred_ways_choose_crew(&w, s, ways[s], 1.0);
        assert_int_equal(ways[s], (int)(2 - (s - 1) % 3));
        assert_int_equal(w.probe[(s + 1) & 1], -1);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_nbep_team_values_are_read_as_documented),
        cmocka_unit_test(test_the_first_step_runs_the_largest_way_unless_never),
        cmocka_unit_test(test_each_way_is_measured_once_largest_first_then_the_fastest_is_taken),
        cmocka_unit_test(test_from_the_second_step_the_fastest_measured_way_is_taken),
        cmocka_unit_test(test_probes_come_every_eighth_step_taking_the_other_ways_in_turn),
        cmocka_unit_test(test_a_clear_winner_is_probed_every_64th_step_only),
        cmocka_unit_test(test_a_way_that_turns_slower_is_left_at_once),
        cmocka_unit_test(test_one_slow_step_of_the_fastest_way_does_not_turn_the_run),
        cmocka_unit_test(test_a_probe_replaces_the_probed_ways_figure),
        cmocka_unit_test(test_a_first_part_replaces_its_ways_figure_and_the_rest_is_averaged),
        cmocka_unit_test(test_ties_go_to_the_way_with_more_threads),
        cmocka_unit_test(test_never_always_a_count_and_cycle_fix_the_way),
        cmocka_unit_test(test_a_step_without_events_measures_nothing),
        cmocka_unit_test(test_a_steps_way_is_written_for_the_next_step_only),
        cmocka_unit_test(test_grid_crews_time_only_the_second_step_of_a_way),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
