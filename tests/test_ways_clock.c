/* The clocks that choose how many threads run a step (pred_ways.c): grid mode's crews are
 * chosen from each step's seconds (nbep__pred_ways_choose_crew) and the cells mode's team from
 * each event loop call's (nbep__pred_ways_note while probing, nbep__pred_ways_choose after).
 * Every figure handed over must be a span of that step or call: not below zero, and within the
 * time measured around the whole run. A figure that is not (the eleventh draw's
 * `nbep_now() - t_step` as `+`: twice the machine's uptime) changes no result, since any crew
 * gives the same bits, but makes the choice blind: the crews were switched every two steps
 * whatever their speed, and a run pinned to one core took 1.2 to 1.5 times as long. This binary
 * is linked with the three wrapped (Makefile: -Wl,--wrap), so the calls from algo_predictive.c
 * and pred_cells.c are seen here on their way to pred_ways.c. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "nbep/compiler.h"
#include "pred_impl.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

void __real_nbep__pred_ways_choose_crew(pred_ways *w, uint64_t step, int way, double seconds);
void __real_nbep__pred_ways_choose(pred_ways *w, uint64_t step, int way, uint64_t events,
                                   double seconds);
void __real_nbep__pred_ways_note(pred_ways *w, int way, bool probe, uint64_t events,
                                 double seconds);
void __wrap_nbep__pred_ways_choose_crew(pred_ways *w, uint64_t step, int way, double seconds);
void __wrap_nbep__pred_ways_choose(pred_ways *w, uint64_t step, int way, uint64_t events,
                                   double seconds);
void __wrap_nbep__pred_ways_note(pred_ways *w, int way, bool probe, uint64_t events,
                                 double seconds);

/* what the run handed over: the calls, and the least and most seconds */
static uint64_t seen;
static double seen_min, seen_max;

static void seen_start(void)
{
    seen = 0;
    seen_min = INFINITY;
    seen_max = -INFINITY;
}

static void see(double seconds)
{
    seen++;
    seen_min = fmin(seen_min, seconds);
    seen_max = fmax(seen_max, seconds);
}

void __wrap_nbep__pred_ways_choose_crew(pred_ways *w, uint64_t step, int way, double seconds)
{
    see(seconds);
    __real_nbep__pred_ways_choose_crew(w, step, way, seconds);
}

void __wrap_nbep__pred_ways_choose(pred_ways *w, uint64_t step, int way, uint64_t events,
                                   double seconds)
{
    see(seconds);
    __real_nbep__pred_ways_choose(w, step, way, events, seconds);
}

void __wrap_nbep__pred_ways_note(pred_ways *w, int way, bool probe, uint64_t events,
                                 double seconds)
{
    see(seconds);
    __real_nbep__pred_ways_note(w, way, probe, events, seconds);
}

/* sc on 2 threads: each figure handed over within the run's time, at least `least` of them */
static void check_clock(nbep_scene *sc, uint64_t least, const char *what)
{
    seen_start();
    const double t0 = nbep_now();
    nbep_summary s = nbep_test_run(sc, 2, NULL, NULL, NULL, NULL);
    const double whole = nbep_now() - t0;
    assert_true(s.collisions > 0);
    if (seen < least || !(seen_min >= 0.0 && seen_max <= whole))
        fail_msg("%s: %llu figures (at least %llu wanted) from %g to %g s, in a run of %g s",
                 what, (unsigned long long)seen, (unsigned long long)least, seen_min, seen_max,
                 whole);
}

static void test_grid_crews_are_chosen_by_their_steps_own_seconds(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_fluid(6, 0.30, 40, 0.05);
    sc->neighbors_grid = true;
    check_clock(sc, 40, "grid mode's crews"); /* one a step */
    nbep_test_scene_free(&sc);
}

static void test_the_cells_team_is_chosen_by_its_calls_own_seconds(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(8, 0.30, 40, 0.02, 3);
    check_clock(sc, 40, "the cells mode's team"); /* one a call, a call or more a step */
    nbep_test_scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_crews_are_chosen_by_their_steps_own_seconds),
        cmocka_unit_test(test_the_cells_team_is_chosen_by_its_calls_own_seconds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
