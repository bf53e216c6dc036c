/* run.order (issue 8, item 6): "time" (the default) reacts to a step's events earliest first,
 * re-predicting in between, which is exact; "step" is the paper's own step, every event that is
 * the earliest of both its spheres reacting at once, which is approximate where events shadow
 * each other. Tests: the setting parses and is refused where it does not apply; a shadowed
 * event, where time order gives the analytic answer and step order the paper's (worked out
 * below); and step order on crowded scenes: energy kept at e = 1, no pair reacting twice,
 * frames bitwise equal for 1, 2 and 4 threads, a settling pile that resolves. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "nbep/scene.h"
#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_h5.h"
#include "nbep_test_scene.h"

static const nbep_vec3 ZERO = {0.0, 0.0, 0.0};

/* ---- the setting ------------------------------------------------------------------------------ */

/* A small runnable deck with run.order on line 2 (order = NULL: no run.order at all). */
static const char *write_deck(const char *name, const char *order, char *path, size_t len)
{
    mkdir("build", 0777);
    mkdir("build/tests", 0777);
    mkdir("build/tests/tmp", 0777);
    nbep_test_tmp(name, path, len);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "run: { algorithm = \"predictive\"; steps = 10; dt = 1.0e-3; threads = 1;\n");
    if (order)
        fprintf(f, "       order = \"%s\";\n", order);
    fprintf(f, "};\nbox: { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0]; };\n"
               "spheres = ( { count = 8; radius = 0.1; mass = 1.0; place = \"lattice\"; "
               "speed = 1.0; } );\n");
    assert_int_equal(fclose(f), 0);
    return path;
}

/* Loads path with the overrides; returns the status, the scene's order in *step and the diag's
 * only message (if any) in msg. */
static nbep_status load(const char *path, const char *const *ov, size_t n_ov, bool *step,
                        char *msg, size_t len)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_scene sc;
    nbep_status st = nbep_scene_load(path, ov, n_ov, &sc, &d);
    msg[0] = '\0';
    if (st == NBEP_OK) {
        *step = sc.order_step;
        nbep_scene_fini(&sc);
    } else {
        assert_int_equal(d.n_errors, 1); /* one line, naming the deck line or the --set */
        snprintf(msg, len, "%s", d.msg[0]);
    }
    nbep_diag_fini(&d);
    return st;
}

static void test_order_defaults_to_time_and_step_is_taken_in_all_and_grid(void **state)
{
    (void)state;
    char path[256], msg[512];
    bool step = true;
    assert_int_equal(load(write_deck("order-none.deck", NULL, path, sizeof path), NULL, 0, &step,
                          msg, sizeof msg), NBEP_OK);
    assert_false(step);
    step = true;
    assert_int_equal(load(write_deck("order-time.deck", "time", path, sizeof path), NULL, 0,
                          &step, msg, sizeof msg), NBEP_OK);
    assert_false(step);
    write_deck("order-step.deck", "step", path, sizeof path);
    assert_int_equal(load(path, NULL, 0, &step, msg, sizeof msg), NBEP_OK);
    assert_true(step);
    const char *grid[] = {"run.neighbors=\"grid\""};
    step = false;
    assert_int_equal(load(path, grid, 1, &step, msg, sizeof msg), NBEP_OK);
    assert_true(step);
    /* --set reaches it like any other setting, and "time" undoes a deck's "step" */
    const char *to_step[] = {"run.order=\"step\""}, *to_time[] = {"run.order=\"time\""};
    step = false;
    assert_int_equal(load(write_deck("order-none.deck", NULL, path, sizeof path), to_step, 1,
                          &step, msg, sizeof msg), NBEP_OK);
    assert_true(step);
    assert_int_equal(load(write_deck("order-step.deck", "step", path, sizeof path), to_time, 1,
                          &step, msg, sizeof msg), NBEP_OK);
    assert_false(step);
}

/* The cells mode's event loop and the detection algorithms have no rounds to react at once
 * in: "step" there is a deck error, not a silent no-op, blamed on what the user typed of
 * run.order, run.algorithm and run.neighbors (the first typed), else run.order's deck line
 * (until 2026-11-30 always that line, a --set of run.neighbors or -a naive under a deck's step
 * order included). */
static void test_step_order_is_refused_with_cells_naive_and_seminaive_and_typos(void **state)
{
    (void)state;
    char path[256], msg[512], want[768];
    bool step;
    const char *tail = "only their rounds can react to a step's events at once";
    /* all three in the deck (cells after the order, on its line): that line */
    write_deck("order-refused-deck.deck", "step\"; neighbors = \"cells", path, sizeof path);
    assert_int_equal(load(path, NULL, 0, &step, msg, sizeof msg), NBEP_EDECK);
    snprintf(want, sizeof want,
             "%s:2: run.order = \"step\" needs run.algorithm = \"predictive\" with "
             "run.neighbors = \"all\" or \"grid\" (got \"predictive\", \"cells\"): %s",
             path, tail);
    assert_string_equal(msg, want);
    /* the deck's step order, the mode typed: the --set */
    write_deck("order-refused.deck", "step", path, sizeof path);
    const char *cells[] = {"run.neighbors=\"cells\""};
    assert_int_equal(load(path, cells, 1, &step, msg, sizeof msg), NBEP_EDECK);
    snprintf(want, sizeof want,
             "--set run.neighbors=\"cells\": run.order = \"step\" needs run.algorithm = "
             "\"predictive\" with run.neighbors = \"all\" or \"grid\" (got \"predictive\", "
             "\"cells\"): %s",
             tail);
    assert_string_equal(msg, want);
    for (int k = 0; k < 2; k++) {
        const char *algo[] = {k ? "run.algorithm=\"seminaive\"" : "run.algorithm=\"naive\""};
        assert_int_equal(load(path, algo, 1, &step, msg, sizeof msg), NBEP_EDECK);
        snprintf(want, sizeof want,
                 "--set %s: run.order = \"step\" needs run.algorithm = \"predictive\" with "
                 "run.neighbors = \"all\" or \"grid\" (got \"%s\"): %s",
                 algo[0], k ? "seminaive" : "naive", tail);
        assert_string_equal(msg, want);
    }
    /* both typed: the first */
    write_deck("order-refused-none.deck", NULL, path, sizeof path);
    const char *both[][2] = {{"run.order=\"step\"", "run.algorithm=\"naive\""},
                             {"run.algorithm=\"naive\"", "run.order=\"step\""}};
    for (int k = 0; k < 2; k++) {
        assert_int_equal(load(path, both[k], 2, &step, msg, sizeof msg), NBEP_EDECK);
        snprintf(want, sizeof want, "--set %s: run.order = \"step\" needs", both[k][0]);
        assert_true(strncmp(msg, want, strlen(want)) == 0);
    }
    /* "time" is what every mode does anyway: accepted with cells */
    assert_int_equal(load(write_deck("order-time.deck", "time", path, sizeof path), cells, 1,
                          &step, msg, sizeof msg), NBEP_OK);
    const char *typo[] = {"run.order=\"paper\""};
    assert_int_equal(load(path, typo, 1, &step, msg, sizeof msg), NBEP_EDECK);
    assert_non_null(strstr(msg, "run.order must be one of \"time\", \"step\" (got \"paper\")"));
}

/* ---- a shadowed event --------------------------------------------------------------------- */

/* Four spheres on the x axis (diameter 1, mass 1, e = 1), one step of dt = 1:
 *   d at 0 (rest), a at 1.5 (v = -1), b at 3.5 (rest), c at 4.7 (v = -4).
 * At the step's start two events are known: c hits b at t = 0.05, and a hits d at 0.5. But b,
 * sent off at -4, catches a at t = 0.4, before a reaches d: a's event is shadowed.
 * Time order (exact): b-a at 0.4 (a at 1.0, b at 2.0: they swap, a -4, b -1); a-d at 0.425 (a
 * stops, d -4); b-a at 0.5 (b at 2.0 - 0.075 stops against a at rest at 1.0, a -1). At t = 1:
 * d -2.3, a 0.5, b 2.0, c 4.5; velocities -4, -1, 0, 0; four collisions, no overlap.
 * Step order (the paper's): round 1 reacts to both known events at once, c-b at 0.05 and a-d
 * at 0.5 (a stops at 1.0, d -1). Round 2 finds b and a from the later local time, 0.5: b is at
 * 3.5 - 4 x 0.45 = 1.7, overlapping a by 0.3 (0.6 of a radius) and closing, so they react
 * there (swap: a -4, b stops at 1.7); round 3: a at 1.0 touches d at 0.0 and catches it
 * (swap: d -4, a -1). At t = 1: d -2.0, a 0.5, b 1.7, c 4.5; the same velocities and count,
 * b and d 0.3 off, max_overlap_rel 0.6.
 * /stats/virial (SPEC: r12 . dp2, r12 at contact; on a line, sigma |dp| a collision): time
 * order 4 (c-b) + 3 (b-a) + 4 (a-d) + 1 (b-a) = 12; step order 4 (c-b) + 1 (a-d) + 4 (b-a,
 * found 0.7 apart: taken at the touching distance, 0.7 x 4 = 2.8 if not) + 3 (a-d) = 12. */
static nbep_scene *shadow_scene(bool step)
{
    nbep_scene *sc = nbep_test_scene_new(4, 0, "predictive", 1, 1.0);
    sc->order_step = step;
    const double x[4] = {0.0, 1.5, 3.5, 4.7}, v[4] = {0.0, -1.0, 0.0, -4.0};
    for (size_t i = 0; i < 4; i++)
        nbep_test_set_sphere(sc, i, (nbep_vec3){x[i], 0, 0}, (nbep_vec3){v[i], 0, 0}, 0.5, 1.0,
                             ZERO);
    return sc;
}

static void check_shadow(bool step, const double *want_x, double want_overlap)
{
    nbep_scene *sc = shadow_scene(step);
    sc->out_stats = true;
    nbep_state fin;
    uint64_t counts[NBEP_COUNTER_COUNT];
    char path[256];
    nbep_test_tmp(step ? "shadow-step.h5" : "shadow-time.h5", path, sizeof path);
    nbep_summary sum = nbep_test_run_to(sc, 1, NULL, NULL, path, &fin, counts);
    const uint64_t reactions = counts[NBEP_COUNTER_REACTIONS];
    size_t rows = 0;
    double *virial = nbep_test_h5_doubles(path, "/stats/virial", &rows);
    assert_int_equal(rows, 1);
    assert_close(virial[0], 12.0, 1e-14, 0.0); /* sums of small integers, to round-off */
    free(virial);
    remove(path);
    const double want_v[4] = {-4.0, -1.0, 0.0, 0.0};
    for (size_t i = 0; i < 4; i++) {
        assert_close(fin.pos[i].x, want_x[i], 0.0, 1e-12);
        assert_close(fin.vel[i].x, want_v[i], 0.0, 1e-12);
        assert_true(fin.pos[i].y == 0.0 && fin.pos[i].z == 0.0);
    }
    assert_int_equal(sum.sphere_collisions, 4);
    assert_int_equal(reactions, 4); /* each pair once, though both its slots named it */
    assert_close(sum.max_overlap_rel, want_overlap, 0.0, 1e-12);
    assert_close(sum.energy_final, sum.energy_initial, 1e-15, 0.0);
    nbep_state_fini(&fin);
    nbep_test_scene_free(&sc);
}

static void test_a_shadowed_event_time_order_gives_the_analytic_answer(void **state)
{
    (void)state;
    const double x[4] = {-2.3, 0.5, 2.0, 4.5};
    check_shadow(false, x, 0.0);
}

static void test_a_shadowed_event_step_order_gives_the_papers_answer(void **state)
{
    (void)state;
    const double x[4] = {-2.0, 0.5, 1.7, 4.5};
    check_shadow(true, x, 0.6);
}

/* ---- crowded scenes ----------------------------------------------------------------------- */


static void frames_equal(const nbep_test_frames *a, const nbep_test_frames *b)
{
    assert_int_equal(a->n_frames, b->n_frames);
    assert_int_equal(a->n, b->n);
    assert_memory_equal(a->data, b->data, a->n_frames * 2 * a->n * sizeof *a->data);
}

static bool all_finite(const nbep_test_frames *f)
{
    for (size_t k = 0; k < f->n_frames * 2 * f->n; k++)
        if (!nbep_vec3_isfinite(f->data[k]))
            return false;
    return true;
}

/* A fluid at phi = 0.5 with dt = 0.05 (about two collisions per sphere per step): step order
 * reacts to many events per round, some shadowed (overlaps well above round-off, so the test
 * does exercise the approximation), yet every reaction is a collision (no pair twice, none
 * receding), e = 1 keeps the energy to round-off, nothing blows up, and the frames are the
 * same bits for 1, 2 and 4 threads (the spheres span four blocks of 256: pairs across
 * threads). In the paper's all-pairs mode and in grid mode. */
static void test_step_order_crowded_fluid_keeps_energy_and_is_thread_independent(void **state)
{
    (void)state;
    const size_t side = nbep_test_scaled(10, 7), n = side * side * side;
    for (int grid = 0; grid < 2; grid++) {
        nbep_scene *sc = nbep_test_fluid(side, 0.5, nbep_test_scaled(grid ? 10 : 4, 3), 0.05);
        sc->neighbors_grid = grid;
        sc->order_step = true;
        nbep_test_frames ref = {0};
        uint64_t r1 = 0;
        nbep_summary s1 = nbep_test_run(sc, 1, nbep_test_keep_frame, &ref, NULL, &r1);
        assert_true(s1.sphere_collisions > n / 2);
        assert_int_equal(r1, s1.collisions);
        assert_true(s1.max_overlap_rel > 1e-3 && s1.max_overlap_rel < 1.0);
        assert_close(s1.energy_final, s1.energy_initial, 1e-12, 0.0);
        assert_true(all_finite(&ref));
        for (int nt = 2; nt <= 4; nt *= 2) {
            nbep_test_frames f = {0};
            uint64_t rk = 0;
            nbep_summary sk = nbep_test_run(sc, nt, nbep_test_keep_frame, &f, NULL, &rk);
            frames_equal(&ref, &f);
            assert_int_equal(sk.collisions, s1.collisions);
            assert_int_equal(rk, r1);
            nbep_test_frames_free(&f);
        }
        nbep_test_frames_free(&ref);
        nbep_test_scene_free(&sc);
    }
}

/* A sphere between two walls a diameter apart hits one each step, at the step's middle, each
 * step the mirror of the last: so every step after the first does the same rounds and the same
 * checks. A round's stamp (which stops a sphere reacting twice in one round) must be new every
 * round of the run; a next step that reused the last one's stamps (a mutant of the seed-14
 * draw: the rounds before counted down) put the sphere's first reaction of a step off by a
 * round, 5 checks and 3 in turn where each step does 3, with every frame the same. */
static void test_each_mirrored_step_of_a_lone_bounce_does_the_same_checks(void **state)
{
    (void)state;
    nbep_scene sc;
    nbep_test_load_deck("lone-bounce.deck",
                        "run: { algorithm = \"predictive\"; steps = 1; dt = 1.0; };\n"
                        "physics: { restitution = 1.0; };\n"
                        "box: { min = [0.0, 0.0, 0.0]; max = [2.0, 2.0, 2.0]; };\n"
                        "spheres = ( { position = [1.0, 1.0, 1.0]; velocity = [1.0, 0.0, 0.0];\n"
                        "              radius = 0.5; mass = 1.0; } );\n",
                        &sc);
    uint64_t checks[7];
    for (int n = 1; n <= 6; n++) {
        sc.steps = (uint64_t)n;
        const nbep_summary s = nbep_test_run(&sc, 1, NULL, NULL, NULL, NULL);
        assert_int_equal(s.plane_collisions, n);
        checks[n] = s.checks;
    }
    for (int n = 2; n < 6; n++)
        if (checks[n + 1] - checks[n] != checks[n] - checks[n - 1])
            fail_msg("steps %d and %d of the bounce did %llu and %llu checks", n, n + 1,
                     (unsigned long long)(checks[n] - checks[n - 1]),
                     (unsigned long long)(checks[n + 1] - checks[n]));
    assert_true(checks[2] > checks[1]);
    nbep_scene_fini(&sc);
}

/* What the trade is, on the same fluid: step order runs a step in far fewer rounds, so it
 * does far fewer of the paper's checks (one per candidate per round); time order stays exact.
 * Step order's shadowed events cost collisions: a pair found overlapping but already receding
 * is one that never collided (here it finds about two thirds of them; docs/accuracy.md). */
static void test_step_order_checks_far_less_and_loses_collisions_to_shadowing(void **state)
{
    (void)state;
    const size_t side = nbep_test_scaled(10, 7);
    nbep_scene *sc = nbep_test_fluid(side, 0.5, nbep_test_scaled(10, 3), 0.05);
    sc->neighbors_grid = true;
    nbep_summary t = nbep_test_run(sc, 1, NULL, NULL, NULL, NULL);
    sc->order_step = true;
    nbep_summary s = nbep_test_run(sc, 1, NULL, NULL, NULL, NULL);
    assert_true(t.max_overlap_rel < 1e-9);
    assert_true(s.max_overlap_rel > 1e-3);
    assert_true(s.checks * 10 < t.checks);
    assert_true(s.sphere_collisions < t.sphere_collisions);
    assert_true(2 * s.sphere_collisions > t.sphere_collisions);
    nbep_test_scene_free(&sc);
}

/* A sphere named by two events of the step reacts to the earlier, not to the one with the
 * lower pair key. On the x axis (diameter 1, mass 1): sphere 0 at rest at 0, sphere 2 at 1.2
 * moving -2 (hits 0 at t = 0.1), sphere 1 at -1.3 moving +1 (would hit 0 at 0.3; the pair
 * (0, 1) has the lower key). No reaction here creates an event earlier than one already
 * reacted to, so nothing is shadowed and step order must give time order's frames bit for
 * bit: one event per round, each as a serial event-driven code takes them. */
static void test_step_order_reacts_to_a_spheres_earliest_event_not_its_lowest_pair(void **state)
{
    (void)state;
    nbep_test_frames f[2] = {{0}};
    nbep_summary sum[2];
    for (int step = 0; step < 2; step++) {
        nbep_scene *sc = nbep_test_scene_new(3, 0, "predictive", 4, 0.25);
        sc->order_step = step;
        const double x[3] = {0.0, -1.3, 1.2}, v[3] = {0.0, 1.0, -2.0};
        for (size_t i = 0; i < 3; i++)
            nbep_test_set_sphere(sc, i, (nbep_vec3){x[i], 0, 0}, (nbep_vec3){v[i], 0, 0}, 0.5,
                                 1.0, ZERO);
        sum[step] = nbep_test_run(sc, 1, nbep_test_keep_frame, &f[step], NULL, NULL);
        nbep_test_scene_free(&sc);
    }
    assert_true(sum[0].sphere_collisions >= 3); /* 2-0, 0-1, 0-2 again */
    assert_int_equal(sum[1].sphere_collisions, sum[0].sphere_collisions);
    assert_true(sum[1].max_overlap_rel < 1e-12);
    frames_equal(&f[0], &f[1]);
    nbep_test_frames_free(&f[0]);
    nbep_test_frames_free(&f[1]);
}

/* A pile settling under gravity with e = 0.6 in grid mode, step order: resting and held
 * contacts, letting go, all reacted to in rounds of many events: the run must resolve (no
 * stall), energy only falls, nothing overlaps by half a radius, and 1 and 2 threads give the
 * same bits. */
static void test_step_order_pile_settles_and_is_thread_independent(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_fluid(nbep_test_scaled(6, 4), 0.3, nbep_test_scaled(100, 60), 5e-3);
    sc->neighbors_grid = true;
    sc->order_step = true;
    sc->restitution = 0.6;
    for (size_t i = 0; i < sc->state.n; i++)
        sc->state.acc[i] = (nbep_vec3){0, 0, -9.81};
    nbep_test_frames ref = {0}, f2 = {0};
    nbep_summary s1 = nbep_test_run(sc, 1, nbep_test_keep_frame, &ref, NULL, NULL);
    nbep_summary s2 = nbep_test_run(sc, 2, nbep_test_keep_frame, &f2, NULL, NULL);
    frames_equal(&ref, &f2);
    assert_true(all_finite(&ref));
    assert_true(s1.collisions > s1.spheres);
    assert_int_equal(s2.collisions, s1.collisions);
    assert_true(s1.max_overlap_rel < 0.5);
    assert_true(s1.energy_final < s1.energy_initial);
    nbep_test_frames_free(&ref);
    nbep_test_frames_free(&f2);
    nbep_test_scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_order_defaults_to_time_and_step_is_taken_in_all_and_grid),
        cmocka_unit_test(test_step_order_is_refused_with_cells_naive_and_seminaive_and_typos),
        cmocka_unit_test(test_a_shadowed_event_time_order_gives_the_analytic_answer),
        cmocka_unit_test(test_a_shadowed_event_step_order_gives_the_papers_answer),
        cmocka_unit_test(test_step_order_crowded_fluid_keeps_energy_and_is_thread_independent),
        cmocka_unit_test(test_step_order_checks_far_less_and_loses_collisions_to_shadowing),
        cmocka_unit_test(test_each_mirrored_step_of_a_lone_bounce_does_the_same_checks),
        cmocka_unit_test(test_step_order_reacts_to_a_spheres_earliest_event_not_its_lowest_pair),
        cmocka_unit_test(test_step_order_pile_settles_and_is_thread_independent),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
