/* Tests of `nbep sweep` without MPI: the run list (replicas x the cartesian product of the
 * axes, in a stable order), the overrides and seed each run gets, the static split over
 * ranks, reusing complete runs, a failing combination that spares the others, the summary
 * files (summary.csv read as text, summary.h5 read with the HDF5 C API), and the whole
 * command. Decks are written into build/tests/tmp/; runs are a few steps of 8 spheres. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "nbep/output.h"
#include "nbep/scene.h"
#include "nbep/sim.h"
#include "nbep/sweep.h"
#include "nbep_test.h"
#include "build_info.h"

#define TMP "build/tests/tmp/"

/* The runs' common part; each test adds its own output file and sweep group. */
static const char deck_body[] =
    "run: { algorithm = \"predictive\"; steps = 20; dt = 1.0e-3; threads = 1; seed = 11; };\n"
    "physics: { gravity = [0.0, 0.0, -9.81]; restitution = 1.0; };\n"
    "box: { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0]; };\n"
    "spheres = ( { count = 8; radius = 0.05; mass = 1.0; place = \"random\"; speed = 1.0; } );\n";

/* Writes TMP NAME.deck with the common body, output.file = TMP NAME.h5 and extra (the sweep
 * group); removes an earlier NAME.sweep directory's files. Returns the deck's path. */
static const char *write_deck(const char *name, const char *extra, char *path, size_t len)
{
    snprintf(path, len, TMP "%s.deck", name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "%soutput: { file = \"" TMP "%s.h5\"; every = 10; };\n%s", deck_body, name,
            extra);
    assert_int_equal(fclose(f), 0);
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '" TMP "%s.sweep'", name);
    assert_int_equal(system(cmd), 0);
    return path;
}

/* The 1-based line of the file at path that holds needle (0: none). */
static unsigned line_of(const char *path, const char *needle)
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    char buf[1024];
    unsigned line = 0, at = 0;
    while (!at && fgets(buf, sizeof buf, f)) {
        line++;
        at = strstr(buf, needle) ? line : 0;
    }
    fclose(f);
    return at;
}

static int make_dir(const char *dir)
{
    return mkdir(dir, 0777) == 0 || errno == EEXIST ? 0 : -1;
}

static void plan_of(const char *deck, const char *const *ov, size_t n_ov, nbep_sweep_plan *p)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_status st = nbep_sweep_plan_create(deck, ov, n_ov, p, &d);
    if (st != NBEP_OK)
        nbep_diag_print(&d, stderr);
    assert_int_equal(st, NBEP_OK);
    nbep_diag_fini(&d);
}

static const char three_by_two[] =
    "sweep: { replicas = 3;\n"
    "  vary = ( { key = \"physics.restitution\"; values = [1.0, 0.75]; },\n"
    "           { key = \"physics.gravity\"; values = ( [0.0, 0.0, -9.81], [0.0, 0.0, -1.5],\n"
    "                                                   [0.0, -2.0, 0.0] ); } ); };\n";

/* ---- nbep check of a study (nbep_sweep_check) ---------------------------------------------- */

/* deck's study checked with budget_s: its report, and the status */
static nbep_status check_study(const char *deck, double budget_s, nbep_sweep_check_report *rep,
                               nbep_diag *d)
{
    nbep_scene sc;
    assert_int_equal(nbep_scene_load_from(deck, NULL, NULL, 0, NULL, &sc, d), NBEP_OK);
    const nbep_status st = nbep_sweep_check(deck, NULL, NULL, 0, &sc, budget_s, NULL, rep, d);
    assert_null(sc.sweep_axes); /* moved into the check's plan */
    nbep_scene_fini(&sc);
    return st;
}

/* Every run's scene is loaded as the run loads it: the output of each of the 18 runs, summed;
 * a run that a combination of two axes refuses (a count and a radius that each fit alone) is
 * named, and makes it a deck error; with no time to spend, only the first run is loaded, and
 * the report says so. */
static void test_a_check_of_a_study_loads_every_run(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_check_report rep;
    nbep_diag d;
    nbep_diag_init(&d);
    write_deck("sweep_check", three_by_two, deck, sizeof deck);
    assert_int_equal(check_study(deck, 60.0, &rep, &d), NBEP_OK);
    assert_int_equal(d.n_errors, 0);
    assert_int_equal(rep.n_runs, 18);
    assert_int_equal(rep.n_combos, 6);
    assert_int_equal(rep.replicas, 3);
    assert_int_equal(rep.checked, 18);
    assert_int_equal(rep.failed, 0);
    assert_false(rep.out_of_time);
    assert_string_equal(rep.dir, TMP "sweep_check.sweep");
    /* each run's file as nbep_output_bytes counts it for the deck with the run's restitution
     * (at 0.75 a predictive run also keeps its lasting state: /checkpoint/contacts; gravity
     * changes nothing written), and its sidecar, which names the run's file (run-0000.h5 as
     * long as any other) */
    nbep_scene one;
    assert_int_equal(nbep_scene_load_from(deck, NULL, NULL, 0, NULL, &one, &d), NBEP_OK);
    const double sidecar = nbep_output_sidecar_bytes(&one, TMP "sweep_check.sweep/run-0000.h5");
    double each[2];
    for (int k = 0; k < 2; k++) {
        one.restitution = k ? 0.75 : 1.0;
        each[k] = nbep_output_bytes(&one, nbep_sim_keeps_events(&one),
                                    nbep_sim_keeps_contacts(&one)) + sidecar;
    }
    nbep_scene_fini(&one);
    assert_true(sidecar > 0.0);
    assert_true(each[1] > each[0] && each[0] > 0.0);
    const double all = 9.0 * (each[0] + each[1]);
    assert_true(fabs(rep.output_bytes - all) <= 1e-9 * rep.output_bytes);
    assert_true(rep.memory_max > 0.0);
    /* no time: the first run only */
    assert_int_equal(check_study(deck, 0.0, &rep, &d), NBEP_OK);
    assert_int_equal(rep.checked, 1);
    assert_true(rep.out_of_time);
    assert_true(fabs(rep.output_bytes - each[0]) <= 1e-9 * each[0]); /* run 0: e = 1 */
    /* nbep check's line says so, and that the others are checked as they run (until
     * 2026-11-30 it read "the others are when they run") */
    char *text = NULL;
    size_t len = 0;
    FILE *m = open_memstream(&text, &len);
    assert_non_null(m);
    nbep_sweep_check_print(m, &rep);
    assert_int_equal(fclose(m), 0);
    assert_non_null(strstr(text, "\nsweep runs:      the first 1 of 18 loaded and placed in 0 s "
                                 "(the others are checked when they run); the largest needs "
                                 "about "));
    assert_non_null(strstr(text, "\nsweep output:    about "));
    /* a size as people read it (test_util): "29.1 MB", not "2.91e+01 MB" */
    char size[NBEP_BYTES_TEXT_MAX], line[128];
    snprintf(line, sizeof line,
             "\nsweep output:    about %s in all for those (the runs' files and their "
             "sidecars, summary.csv and summary.h5)\n",
             nbep_format_bytes(rep.output_bytes + rep.tables_bytes, size));
    assert_non_null(strstr(text, line));
    assert_null(strstr(text, "e+"));
    free(text);
    /* 8 spheres of radius 0.1 fit the unit box, so does 1 of 0.45; 8 of 0.45 do not: runs 3
     * and 7 (radius 0.45, count 8, each replica: seeds 11 and 12) */
    write_deck("sweep_check_combo",
               "sweep: { replicas = 2;\n"
               "  vary = ( { key = \"spheres.[0].radius\"; values = [0.1, 0.45]; },\n"
               "           { key = \"spheres.[0].count\"; values = [1, 8]; } ); };\n",
               deck, sizeof deck);
    nbep_diag_fini(&d);
    nbep_diag_init(&d);
    assert_int_equal(check_study(deck, 60.0, &rep, &d), NBEP_EDECK);
    assert_int_equal(rep.checked, 8);
    assert_int_equal(rep.failed, 2);
    assert_int_equal(d.n_errors, 2);
    assert_non_null(strstr(d.msg[0], "nbep: sweep run 3 (spheres.[0].radius=0.45 "
                                     "spheres.[0].count=8 seed=11) cannot run: "));
    assert_non_null(strstr(d.msg[1], "nbep: sweep run 7 (spheres.[0].radius=0.45 "
                                     "spheres.[0].count=8 seed=12) cannot run: "));
    nbep_diag_fini(&d);
}

/* ---- the run list ------------------------------------------------------------------------ */

static void test_runs_are_replicas_times_the_product_of_the_axes(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_list", three_by_two, deck, sizeof deck), NULL, 0, &p);
    assert_int_equal(p.n_axes, 2);
    assert_int_equal(p.replicas, 3);
    assert_int_equal(p.n_combos, 2 * 3);
    assert_int_equal(p.n_runs, 3 * 2 * 3);
    nbep_sweep_plan_fini(&p);
}

static void test_replicas_are_outermost_and_the_last_axis_varies_fastest(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_order", three_by_two, deck, sizeof deck), NULL, 0, &p);
    /* Nested loops: for replica, for restitution (2), for gravity (3). */
    size_t run = 0;
    for (uint64_t r = 0; r < 3; r++)
        for (size_t e = 0; e < 2; e++)
            for (size_t g = 0; g < 3; g++, run++) {
                assert_int_equal(nbep_sweep_run_replica(&p, run), r);
                assert_int_equal(nbep_sweep_run_value(&p, run, 0), e);
                assert_int_equal(nbep_sweep_run_value(&p, run, 1), g);
            }
    nbep_sweep_plan_fini(&p);
}

static void test_every_combination_appears_once_per_replica(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_product", three_by_two, deck, sizeof deck), NULL, 0, &p);
    int seen[3][2][3] = {{{0}}};
    for (size_t run = 0; run < p.n_runs; run++)
        seen[nbep_sweep_run_replica(&p, run)][nbep_sweep_run_value(&p, run, 0)]
            [nbep_sweep_run_value(&p, run, 1)]++;
    for (int r = 0; r < 3; r++)
        for (int e = 0; e < 2; e++)
            for (int g = 0; g < 3; g++)
                assert_int_equal(seen[r][e][g], 1);
    nbep_sweep_plan_fini(&p);
}

static void test_a_run_gets_the_command_line_then_its_values_then_its_seed(void **state)
{
    (void)state;
    char deck[256];
    const char *cli[] = {"run.steps=30", "physics.restitution=0.5"};
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_overrides", three_by_two, deck, sizeof deck), cli, 2, &p);
    /* run 10 = replica 1 (10 / 6), combination 4: restitution index 1, gravity index 1 */
    char **ov;
    size_t n;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_run_overrides(&p, 10, &ov, &n, &d), NBEP_OK);
    assert_int_equal(n, 5);
    assert_string_equal(ov[0], "run.steps=30");
    assert_string_equal(ov[1], "physics.restitution=0.5");
    assert_string_equal(ov[2], "physics.restitution=0.75");
    assert_string_equal(ov[3], "physics.gravity=[0.0, 0.0, -1.5]");
    assert_string_equal(ov[4], "run.seed=12");
    nbep_sweep_overrides_free(ov, n);
    nbep_diag_fini(&d);
    nbep_sweep_plan_fini(&p);
}

static void test_replica_r_runs_with_the_decks_seed_plus_r(void **state)
{
    (void)state;
    char deck[256];
    const char *cli[] = {"run.seed=4711"};
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_seed", three_by_two, deck, sizeof deck), cli, 1, &p);
    for (size_t run = 0; run < p.n_runs; run++)
        assert_int_equal(nbep_sweep_run_seed(&p, run), 4711 + run / 6);
    nbep_sweep_plan_fini(&p);
}

static void test_a_deck_without_a_sweep_group_is_one_run(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_none", "", deck, sizeof deck), NULL, 0, &p);
    assert_int_equal(p.n_runs, 1);
    char **ov;
    size_t n;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_run_overrides(&p, 0, &ov, &n, &d), NBEP_OK);
    assert_int_equal(n, 1);
    assert_string_equal(ov[0], "run.seed=11");
    nbep_sweep_overrides_free(ov, n);
    nbep_diag_fini(&d);
    nbep_sweep_plan_fini(&p);
}

static void test_the_sweep_directory_is_the_output_name_with_sweep(void **state)
{
    (void)state;
    char deck[256];
    static const struct {
        const char *output, *dir;
    } cases[] = {{"output.file=\"results/box.h5\"", "results/box.sweep"},
                 {"output.file=\"results/box.sweep\"", "results/box.sweep"},
                 {"output.file=\"box\"", "box.sweep"}};
    write_deck("sweep_dir", "", deck, sizeof deck);
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        nbep_sweep_plan p;
        plan_of(deck, &cases[k].output, 1, &p);
        assert_string_equal(p.dir, cases[k].dir);
        nbep_sweep_plan_fini(&p);
    }
    nbep_sweep_plan p;
    plan_of(deck, NULL, 0, &p);
    assert_string_equal(p.dir, TMP "sweep_dir.sweep");
    nbep_sweep_plan_fini(&p);
}

static void test_run_files_have_four_digits_or_as_many_as_the_last_run_needs(void **state)
{
    (void)state;
    nbep_sweep_plan p = {.dir = "out.sweep", .n_runs = 18, .n_combos = 1};
    char *a = nbep_sweep_run_path(&p, 7);
    assert_string_equal(a, "out.sweep/run-0007.h5");
    p.n_runs = 123456;
    char *b = nbep_sweep_run_path(&p, 42);
    assert_string_equal(b, "out.sweep/run-000042.h5");
    free(a);
    free(b);
}

/* The sweep's plan of deck (with overrides set) is refused with exactly the n messages msg, and
 * the deck's own check (nbep check, nbep run) refuses it alike, before any run. */
static void assert_refused(const char *deck, const char *const *set, size_t n_set, size_t n,
                           const char *const *msg)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_sweep_plan p;
    assert_int_equal(nbep_sweep_plan_create(deck, set, n_set, &p, &d), NBEP_EDECK);
    assert_int_equal(d.n_errors, n);
    for (size_t k = 0; k < n; k++)
        assert_string_equal(d.msg[k], msg[k]);
    nbep_diag_fini(&d);
    nbep_scene sc;
    nbep_diag_init(&d);
    assert_int_equal(nbep_scene_load(deck, set, n_set, &sc, &d), NBEP_EDECK);
    assert_int_equal(d.n_errors, n);
    nbep_diag_fini(&d);
}

static void test_varying_the_seed_a_key_twice_or_a_key_and_its_part_is_a_deck_error(void **state)
{
    (void)state;
    char deck[256];
    write_deck("sweep_bad_axes",
               "sweep: { vary = ( { key = \"run.seed\"; values = [1, 2]; },\n"
               "  { key = \"physics.restitution\"; values = [1.0]; },\n"
               "  { key = \"physics.restitution\"; values = [0.5]; } ); };\n",
               deck, sizeof deck);
    const char *const axes[] = {
        TMP "sweep_bad_axes.deck:6: sweep.vary.[0].key: run.seed cannot be varied (the sweep "
            "sets it: replica r runs with run.seed + r)",
        TMP "sweep_bad_axes.deck:8: sweep.vary.[2].key: physics.restitution is already varied "
            "by sweep.vary.[1]"};
    assert_refused(deck, NULL, 0, 2, axes);
    /* a setting and a part of it (either first): every run would take the whole's value, and
     * the rows would name the part's values, which never ran (until 2026-12-01 both passed) */
    write_deck("sweep_nested_axes",
               "sweep: { vary = ( { key = \"physics.gravity.[2]\"; values = [-1.0, -2.0]; },\n"
               "  { key = \"physics.gravity\"; values = ( [0.0, 0.0, -9.81] ); },\n"
               "  { key = \"spheres.[0]\";\n"
               "    values = ( { count = 2; radius = 0.04; mass = 1.0; } ); },\n"
               "  { key = \"spheres.[0].radius\"; values = [0.04]; },\n"
               "  { key = \"physics.restitution\"; values = [1.0]; } ); };\n",
               deck, sizeof deck);
    const char *const nested[] = {
        TMP "sweep_nested_axes.deck:7: sweep.vary.[1].key: physics.gravity and "
            "physics.gravity.[2] (sweep.vary.[0]) vary the same setting, one inside the other; "
            "vary one of them",
        TMP "sweep_nested_axes.deck:10: sweep.vary.[3].key: spheres.[0].radius and spheres.[0] "
            "(sweep.vary.[2]) vary the same setting, one inside the other; vary one of them"};
    assert_refused(deck, NULL, 0, 2, nested);
    /* ... whatever the spelling of an index (the overrides take [02] as [2]) */
    write_deck("sweep_index_spelling",
               "sweep: { vary = ( { key = \"physics.gravity.[2]\"; values = [-1.0, -2.0]; },\n"
               "  { key = \"physics.gravity.[02]\"; values = [-5.0]; } ); };\n",
               deck, sizeof deck);
    const char *const spelt[] = {
        TMP "sweep_index_spelling.deck:7: sweep.vary.[1].key: physics.gravity.[02] is already "
            "varied by sweep.vary.[0]"};
    assert_refused(deck, NULL, 0, 1, spelt);
    /* a run.steps axis takes integers >= 0 only, each checked on its line, as run.steps (since
     * 2026-11-30 by the check of every value, in its words; before, by a check of its own) */
    write_deck("sweep_bad_steps",
               "sweep: { vary = ( { key = \"run.steps\";\n"
               "  values = ( 7, -2, 1.5 ); } ); };\n",
               deck, sizeof deck);
    const char *const steps[] = {
        TMP "sweep_bad_steps.deck:7: sweep.vary.[0].values.[1]: run.steps must be >= 0 (got -2)",
        TMP "sweep_bad_steps.deck:7: sweep.vary.[0].values.[2]: run.steps must be an integer "
            "(got 1.5)"};
    assert_refused(deck, NULL, 0, 2, steps);
    /* an axis whose path indexes an entry the deck lacks (each run would append one with that
     * setting alone: until 2026-11-30 every run failed, exit 1, and the check passed); an
     * entry the deck has, or one a --set made, may be varied */
    write_deck("sweep_bad_index",
               "sweep: { vary = ( { key = \"spheres.[1].radius\"; values = [0.1]; },\n"
               "  { key = \"planes.[0].point\"; values = ( [0.0, 0.0, 0.5] ); },\n"
               "  { key = \"spheres.[0].radius\"; values = [0.04, 0.06]; } ); };\n",
               deck, sizeof deck);
    const char *const index[] = {
        TMP "sweep_bad_index.deck:6: sweep.vary.[0].key: spheres has 1 entry: "
            "spheres.[1].radius names none (vary a setting the deck has)",
        TMP "sweep_bad_index.deck:7: sweep.vary.[1].key: planes has 0 entries: "
            "planes.[0].point names none (vary a setting the deck has)"};
    assert_refused(deck, NULL, 0, 2, index);
    const char *const made[] = {"planes.[0].normal=[0.0, 0.0, 1.0]",
                                "planes.[0].point=[0.0, 0.0, 0.0]",
                                "spheres.[1].count=2", "spheres.[1].radius=0.03",
                                "spheres.[1].mass=1.0"};
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_sweep_plan p;
    assert_int_equal(nbep_sweep_plan_create(deck, made, 5, &p, &d), NBEP_OK);
    assert_int_equal(p.n_axes, 3);
    nbep_sweep_plan_fini(&p);
    nbep_diag_fini(&d);
}

/* Every axis value is checked on its own against the deck and the command line, as a --set of
 * it, when the deck is (nbep check, nbep run, the sweep's plan): a value no run can take is a
 * deck error at the value's line, not a failed run after the others (until 2026-11-30 the
 * check passed and the sweep exited 1). Out of range, out of the window of magnitudes, of the
 * wrong type, against the deck's other settings (a box.max below its min, an algorithm a
 * periodic box cannot take), or given by a --set, which is then named; a problem of the deck
 * itself is said once, not once per value. */
static void test_a_bad_axis_value_is_refused_before_any_run(void **state)
{
    (void)state;
    char deck[256];
    write_deck("sweep_bad_values",
               "sweep: { vary = ( { key = \"run.dt\"; values = [1e-3, 1e-45]; },\n"
               "  { key = \"physics.restitution\"; values = ( 1.0,\n"
               "      1.5, \"x\" ); },\n"
               "  { key = \"box.max\"; values = ( [1.0, 1.0, 1.0], [2.0, -1.0, 1.0] ); } ); };\n",
               deck, sizeof deck);
    const char *const values[] = {
        TMP "sweep_bad_values.deck:6: sweep.vary.[0].values.[1]: run.dt must be 1e-40 to 1e40 "
            "in magnitude (got 1e-45); choose units that bring it within (README, The deck: "
            "units)",
        TMP "sweep_bad_values.deck:8: sweep.vary.[1].values.[1]: physics.restitution must be in "
            "[0, 1] (got 1.5)",
        TMP "sweep_bad_values.deck:8: sweep.vary.[1].values.[2]: physics.restitution must be a "
            "number (got \"x\")",
        TMP "sweep_bad_values.deck:9: sweep.vary.[2].values.[1]: box.min must be < box.max on "
            "every axis (got y: 0 >= -1)"};
    assert_refused(deck, NULL, 0, 4, values);
    /* good values pass: the same axes with the bad ones replaced */
    const char *const good[] = {"sweep.vary.[0].values.[1]=1e-4",
                                "sweep.vary.[1].values=[1.0, 0.5]",
                                "sweep.vary.[2].values.[1]=[2.0, 1.0, 1.0]"};
    nbep_sweep_plan p;
    plan_of(deck, good, 3, &p);
    assert_int_equal(p.n_runs, 2 * 2 * 2);
    nbep_sweep_plan_fini(&p);
    /* values a --set gave are named by it; the deck's own problem (here the command line's
     * restitution, which no axis replaces) is said once, not once per value */
    const char *const by_set[] = {"sweep.vary.[0].values=[1e-3, 1e-45]",
                                  "sweep.vary.[1].values.[2]=0.5", "run.steps=-1"};
    const char *const named[] = {
        "--set sweep.vary.[0].values=[1e-3, 1e-45]: sweep.vary.[0].values.[1]: run.dt must be "
        "1e-40 to 1e40 in magnitude (got 1e-45); choose units that bring it within (README, "
        "The deck: units)",
        "--set run.steps=-1: run.steps must be >= 0 (got -1)",
        TMP "sweep_bad_values.deck:8: sweep.vary.[1].values.[1]: physics.restitution must be in "
            "[0, 1] (got 1.5)",
        TMP "sweep_bad_values.deck:9: sweep.vary.[2].values.[1]: box.min must be < box.max on "
            "every axis (got y: 0 >= -1)"};
    assert_refused(deck, by_set, 3, 4, named);
    /* a value that breaks another setting of the deck says which value did */
    write_deck("sweep_bad_combination",
               "sweep: { vary = ( { key = \"run.neighbors\"; values = [\"cells\", "
               "\"grid\"]; } ); };\n",
               deck, sizeof deck);
    const char *const periodic[] = {"box.periodic=[true, true, true]"};
    const char *const other[] = {
        TMP "sweep_bad_combination.deck:6: sweep.vary.[0].values.[1]: with "
            "run.neighbors=\"grid\", --set box.periodic=[true, true, true]: box.periodic needs "
            "run.neighbors = \"cells\" or \"all\" with the predictive algorithm (got "
            "\"grid\"): grid mode does not handle periodic images"};
    assert_refused(deck, periodic, 1, 1, other);
}

/* More runs than a sweep takes (10^7) is a deck error at the sweep group's line, or at the
 * --set that asked for them, found before anything runs. */
static void test_too_many_runs_is_a_deck_error_at_the_sweep_group(void **state)
{
    (void)state;
    char deck[256];
    write_deck("sweep_too_many",
               "sweep: { replicas = 5000001;\n"
               "  vary = ( { key = \"physics.restitution\"; values = [1.0, 0.5]; } ); };\n",
               deck, sizeof deck);
    const char *const in_deck[] = {TMP "sweep_too_many.deck:6: sweep: replicas times the "
                                       "product of the axes' lengths is more than 10000000 runs"};
    assert_refused(deck, NULL, 0, 1, in_deck);
    write_deck("sweep_few", "", deck, sizeof deck);
    const char *set[] = {"sweep.replicas=10000001"};
    const char *const by_set[] = {"--set sweep.replicas=10000001: sweep: replicas times the "
                                  "product of the axes' lengths is more than 10000000 runs"};
    assert_refused(deck, set, 1, 1, by_set);
    /* a --set over the deck's own replicas: at the --set (until 2026-12-04 at the deck's sweep
     * line, a review) */
    write_deck("sweep_two", "sweep: { replicas = 2; };\n", deck, sizeof deck);
    const char *set_over[] = {"sweep.replicas=1000000000"};
    const char *const by_set_over[] = {"--set sweep.replicas=1000000000: sweep: replicas times "
                                       "the product of the axes' lengths is more than 10000000 "
                                       "runs"};
    assert_refused(deck, set_over, 1, 1, by_set_over);
}

static void test_a_steps_axis_sets_each_runs_expected_steps(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_steps",
                       "sweep: { vary = ( { key = \"run.steps\"; values = ( 7, 30L ); } ); };\n",
                       deck, sizeof deck),
            NULL, 0, &p);
    assert_int_equal(nbep_sweep_run_steps(&p, 0), 7);
    assert_int_equal(nbep_sweep_run_steps(&p, 1), 30);
    nbep_sweep_plan_fini(&p);
}

static void test_ranks_take_runs_in_rounds_of_alternating_direction(void **state)
{
    (void)state;
    /* 2 ranks: rounds (0,1) (3,2) (4,5) (7,6) */
    static const int owner2[8] = {0, 1, 1, 0, 0, 1, 1, 0};
    for (size_t run = 0; run < 8; run++) {
        assert_int_equal(nbep_sweep_run_owner(run, owner2[run], 2), true);
        assert_int_equal(nbep_sweep_run_owner(run, 1 - owner2[run], 2), false);
    }
    /* any rank count: each run has exactly one owner, and the counts differ by at most 1 */
    for (int ranks = 1; ranks <= 5; ranks++) {
        size_t count[5] = {0};
        for (size_t run = 0; run < 23; run++) {
            int owners = 0;
            for (int q = 0; q < ranks; q++)
                if (nbep_sweep_run_owner(run, q, ranks)) {
                    owners++;
                    count[q]++;
                }
            assert_int_equal(owners, 1);
        }
        for (int q = 0; q < ranks; q++)
            assert_true(count[q] == 23 / (size_t)ranks || count[q] == 23 / (size_t)ranks + 1);
    }
}

/* ---- reusing complete runs ----------------------------------------------------------------- */

static void test_a_summary_reads_back_field_by_field(void **state)
{
    (void)state;
    nbep_summary s = {.algorithm = "seminaive", .threads = 3, .spheres = 4097, .planes = 7,
                      .steps = 1234, .dt = 0.00125, .setup_seconds = 0.0317,
                      .wall_seconds = 1.4375, .steps_per_second = 858.4347826,
                      .checks = 9876543210ull, .predictions = 17, .collisions = 19,
                      .sphere_collisions = 11, .plane_collisions = 8, .quiet_steps = 1200,
                      .energy_initial = -3.17, .energy_final = -3.1700001,
                      .energy_rel_drift = -3.1545741324921e-08, .max_overlap = 2.5e-13,
                      .max_overlap_rel = 5e-12, .peak_rss_bytes = 123456789};
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    nbep_summary r;
    assert_true(nbep_summary_from_json(json, &r));
    assert_string_equal(r.algorithm, "seminaive");
    assert_int_equal(r.threads, 3);
    assert_int_equal(r.spheres, 4097);
    assert_int_equal(r.steps, 1234);
    assert_int_equal(r.checks, 9876543210ull);
    assert_int_equal(r.quiet_steps, 1200);
    assert_int_equal(r.peak_rss_bytes, 123456789);
    assert_true(r.dt == s.dt && r.energy_final == s.energy_final); /* %.17g round-trips */
    assert_true(r.energy_rel_drift == s.energy_rel_drift && r.max_overlap == s.max_overlap);
    assert_false(nbep_summary_from_json("{\"format\": \"nbep-summary-1\"}", &r));
    assert_false(nbep_summary_from_json("not json", &r));
    free(json);
}

static nbep_sweep_result *execute(const nbep_sweep_plan *p, const atomic_int *stop,
                                  nbep_status want)
{
    nbep_sweep_result *res = calloc(p->n_runs, sizeof *res);
    assert_non_null(res);
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(make_dir(p->dir), 0);
    const nbep_sweep_exec ex = {.rank = 0, .n_ranks = 1, .stop_signal = stop, .quiet = true};
    assert_int_equal(nbep_sweep_execute(p, &ex, res), want);
    nbep_diag_fini(&d);
    return res;
}

static bool complete(const nbep_sweep_plan *p, size_t run, uint64_t steps, const char *extra)
{
    char **ov;
    size_t n;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_run_overrides(p, run, &ov, &n, &d), NBEP_OK);
    if (extra) { /* replace the run's own seed */
        free(ov[n - 1]);
        ov[n - 1] = strdup(extra);
    }
    char *path = nbep_sweep_run_path(p, run);
    bool done = nbep_sweep_run_complete(path, ov, n, steps, NULL);
    free(path);
    nbep_sweep_overrides_free(ov, n);
    nbep_diag_fini(&d);
    return done;
}

static void test_a_run_is_complete_only_with_its_overrides_and_all_its_steps(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_complete",
                       "sweep: { vary = ( { key = \"physics.restitution\"; values = [0.9]; } ); "
                       "replicas = 2; };\n",
                       deck, sizeof deck),
            NULL, 0, &p);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].outcome, NBEP_SWEEP_OK);
    assert_true(complete(&p, 0, 20, NULL));
    assert_false(complete(&p, 0, 40, NULL));                /* the deck now asks for more */
    assert_false(complete(&p, 0, 20, "run.seed=99"));       /* another run's parameters */
    char *path = nbep_sweep_run_path(&p, 1);
    assert_true(complete(&p, 1, 20, NULL));
    assert_int_equal(remove(path), 0);
    assert_false(complete(&p, 1, 20, NULL));                /* no file */
    FILE *f = fopen(path, "w");                             /* a file that is not HDF5 */
    fputs("garbage\n", f);
    fclose(f);
    assert_false(complete(&p, 1, 20, NULL));
    free(path);
    free(res);
    nbep_sweep_plan_fini(&p);
}

static void test_thread_count_and_output_name_do_not_make_a_run_different(void **state)
{
    (void)state;
    char deck[256];
    const char *cli[] = {"run.threads=1", "output.file=\"" TMP "sweep_neutral.h5\""};
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_neutral", "", deck, sizeof deck), cli, 2, &p);
    free(execute(&p, NULL, NBEP_OK));
    char *path = nbep_sweep_run_path(&p, 0);
    char *same[] = {"run.threads = 2", "run.seed=11"};
    char *other[] = {"run.threads=1", "physics.restitution=0.5", "run.seed=11"};
    char *reordered[] = {"run.seed=11", "output.file=\"" TMP "sweep_neutral.sweep\""};
    /* the step count says how far a run goes, not how: judged by the summary's steps */
    char *steps[] = {"run.steps=20", "run.seed=11"};
    assert_true(nbep_sweep_run_complete(path, same, 2, 20, NULL));
    assert_true(nbep_sweep_run_complete(path, same + 1, 1, 20, NULL));
    assert_true(nbep_sweep_run_complete(path, reordered, 2, 20, NULL));
    assert_true(nbep_sweep_run_complete(path, steps, 2, 20, NULL));
    assert_false(nbep_sweep_run_complete(path, steps, 2, 30, NULL));
    assert_false(nbep_sweep_run_complete(path, other, 3, 20, NULL));
    free(path);
    nbep_sweep_plan_fini(&p);
}

/* ... but where run.threads is an axis (a study of thread counts, whose rows' timings are its
 * results) the thread count makes a run different: a study run again with another value
 * reuses only the runs whose count it kept (until 2026-12-01 the 2-thread run was reused for
 * the row of 4, its threads column 2). */
static void test_a_thread_count_axis_makes_a_run_different(void **state)
{
    (void)state;
    char deck[256];
    write_deck("sweep_threads_axis",
               "sweep: { vary = ( { key = \"run.threads\"; values = [1, 2]; } ); };\n", deck,
               sizeof deck);
    nbep_sweep_plan p;
    plan_of(deck, NULL, 0, &p);
    free(execute(&p, NULL, NBEP_OK));
    nbep_sweep_plan_fini(&p);
    const char *cli[] = {"sweep.vary.[0].values=[1, 4]"};
    plan_of(deck, cli, 1, &p);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].reused, 1);
    assert_int_equal(res[1].reused, 0);
    assert_int_equal(res[1].summary.threads, 4);
    free(res);
    nbep_sweep_plan_fini(&p);
    /* a --set of run.threads, which the axis overrides, changes no run: both reused (until
     * 2026-12-01, for a day, it made the study run again; a review) */
    const char *cli3[] = {"sweep.vary.[0].values=[1, 4]", "run.threads=3"};
    plan_of(deck, cli3, 2, &p);
    res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].reused, 1);
    assert_int_equal(res[1].reused, 1);
    free(res);
    nbep_sweep_plan_fini(&p);
}

static void test_a_run_killed_before_its_summary_is_not_complete(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_killed", "", deck, sizeof deck), NULL, 0, &p);
    assert_int_equal(make_dir(p.dir), 0);
    /* what a kill -9 leaves: the layout and a frame, no /summary json */
    char **ov;
    size_t n;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_run_overrides(&p, 0, &ov, &n, &d), NBEP_OK);
    nbep_scene sc;
    assert_int_equal(nbep_scene_load(deck, (const char *const *)ov, n, &sc, &d), NBEP_OK);
    char *path = nbep_sweep_run_path(&p, 0);
    nbep_output *o;
    assert_int_equal(nbep_output_create(path, &sc, 1, &o, &d), NBEP_OK);
    assert_int_equal(nbep_output_frame(o, 0, sc.dt, &sc.state, &d), NBEP_OK);
    assert_int_equal(nbep_output_close(&o, NULL, &d), NBEP_OK);
    assert_false(nbep_sweep_run_complete(path, ov, n, 20, NULL));
    /* the sweep runs it again from scratch and then it is complete */
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].outcome, NBEP_SWEEP_OK);
    assert_int_equal(res[0].reused, 0);
    assert_true(nbep_sweep_run_complete(path, ov, n, 20, NULL));
    free(res);
    free(path);
    nbep_scene_fini(&sc);
    nbep_sweep_overrides_free(ov, n);
    nbep_diag_fini(&d);
    nbep_sweep_plan_fini(&p);
}

/* Replaces the /summary json attribute of the run file at path with text. */
static void set_summary_json(const char *path, const char *text)
{
    hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
    assert_true(f >= 0);
    hid_t g = H5Gopen2(f, "/summary", H5P_DEFAULT);
    assert_true(g >= 0);
    assert_true(H5Adelete(g, "json") >= 0);
    hid_t type = H5Tcopy(H5T_C_S1), space = H5Screate(H5S_SCALAR);
    assert_true(H5Tset_size(type, H5T_VARIABLE) >= 0);
    hid_t a = H5Acreate2(g, "json", type, space, H5P_DEFAULT, H5P_DEFAULT);
    assert_true(a >= 0);
    assert_true(H5Awrite(a, type, &text) >= 0);
    H5Aclose(a);
    H5Sclose(space);
    H5Tclose(type);
    H5Gclose(g);
    assert_true(H5Fclose(f) >= 0);
}

/* A run's file whose summary counts all its steps is complete only when it says it completed:
 * one stopped by a signal in its last step (exit 143 or 130, its row said interrupted) or one
 * that failed is run again. A summary of an nbep before the status key (no status, no
 * steps_requested) is judged as then, by its steps. */
static void test_a_run_is_complete_only_when_its_summary_says_it_completed(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_status", "", deck, sizeof deck), NULL, 0, &p);
    assert_int_equal(make_dir(p.dir), 0);
    char **ov;
    size_t n;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_run_overrides(&p, 0, &ov, &n, &d), NBEP_OK);
    nbep_scene sc;
    assert_int_equal(nbep_scene_load(deck, (const char *const *)ov, n, &sc, &d), NBEP_OK);
    char *path = nbep_sweep_run_path(&p, 0);
    static const struct {
        nbep_summary_status status;
        uint64_t steps;
        bool complete;
    } cases[] = {
        {NBEP_SUMMARY_COMPLETED, 20, true},    {NBEP_SUMMARY_TERMINATED, 20, false},
        {NBEP_SUMMARY_INTERRUPTED, 20, false}, {NBEP_SUMMARY_FAILED, 20, false},
        {NBEP_SUMMARY_COMPLETED, 19, false},   {NBEP_SUMMARY_UNKNOWN, 20, true},
        {NBEP_SUMMARY_UNKNOWN, 19, false},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        nbep_summary sum = {.algorithm = "predictive", .threads = 1, .spheres = 8,
                            .planes = 6, .steps = cases[k].steps, .dt = 1e-3,
                            .status = cases[k].status,
                            .steps_requested = {.known = true, .value = 20}};
        nbep_output *o;
        assert_int_equal(nbep_output_create(path, &sc, 1, &o, &d), NBEP_OK);
        assert_int_equal(nbep_output_frame(o, 0, sc.dt, &sc.state, &d), NBEP_OK);
        assert_int_equal(nbep_output_close(&o, &sum, &d), NBEP_OK);
        if (cases[k].status == NBEP_SUMMARY_UNKNOWN) {
            /* as an older nbep wrote it: the same keys up to pressure, the last then */
            char *json = nbep_summary_to_json(&sum);
            assert_non_null(json);
            char *tail = strstr(json, ", \"status\": ");
            assert_non_null(tail);
            strcpy(tail, "}\n");
            set_summary_json(path, json);
            free(json);
        }
        nbep_summary got;
        memset(&got, 0, sizeof got);
        if (nbep_sweep_run_complete(path, ov, n, 20, &got) != cases[k].complete)
            fail_msg("case %zu (status %d, %llu steps): complete is not %d", k,
                     (int)cases[k].status, (unsigned long long)cases[k].steps,
                     (int)cases[k].complete);
        if (cases[k].complete)
            assert_int_equal(got.status, cases[k].status);
    }
    /* the sweep runs a terminated one again, and its row is then ok and its own */
    nbep_summary sum = {.algorithm = "predictive", .threads = 1, .spheres = 8, .planes = 6,
                        .steps = 20, .dt = 1e-3, .status = NBEP_SUMMARY_TERMINATED};
    nbep_output *o;
    assert_int_equal(nbep_output_create(path, &sc, 1, &o, &d), NBEP_OK);
    assert_int_equal(nbep_output_frame(o, 0, sc.dt, &sc.state, &d), NBEP_OK);
    assert_int_equal(nbep_output_close(&o, &sum, &d), NBEP_OK);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].outcome, NBEP_SWEEP_OK);
    assert_int_equal(res[0].reused, 0);
    assert_int_equal(res[0].summary.status, NBEP_SUMMARY_COMPLETED);
    assert_true(nbep_sweep_run_complete(path, ov, n, 20, NULL));
    free(res);
    free(path);
    nbep_scene_fini(&sc);
    nbep_sweep_overrides_free(ov, n);
    nbep_diag_fini(&d);
    nbep_sweep_plan_fini(&p);
}

/* ---- running and the summary --------------------------------------------------------------- */

/* A study whose middle value fails its runs, and only at run time: a radius of 0.45 passes the
 * deck's check of each value (test_a_bad_axis_value_is_refused_before_any_run), but 8 such
 * spheres do not fit in the unit box, which only placing them finds. Until 2026-11-30 a
 * restitution of 1.5 served, which that check now refuses. */
static const char with_failing_value[] =
    "sweep: { replicas = 2;\n"
    "  vary = ( { key = \"spheres.[0].radius\"; values = [0.05, 0.45, 0.04]; } ); };\n";
/* what its failing runs say, at the axis's line (its `vary` line, the 7th of the deck that
 * write_deck makes: deck_body's 4, the output line, "sweep: {"; until 2026-11-30 at the
 * group's line in deck_body, 4, which the user had not touched) */
#define FAILING_VALUE_ERROR                                                                    \
    ":7: sweep.vary.[0]: spheres.[0]: could not place 8 spheres of radius 0.45 in the region: " \
    "placed 1 (packing fraction 0.38)"

static void test_a_failing_combination_spares_the_other_runs(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_fail", with_failing_value, deck, sizeof deck), NULL, 0, &p);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    for (size_t run = 0; run < 6; run++) {
        bool bad = run % 3 == 1; /* radius 0.45 */
        assert_int_equal(res[run].outcome, bad ? NBEP_SWEEP_FAILED : NBEP_SWEEP_OK);
        assert_int_equal(res[run].exit_code, bad ? 2 : 0);
        assert_int_equal(res[run].has_summary, !bad);
        if (bad) {
            char want[512];
            snprintf(want, sizeof want, "%s" FAILING_VALUE_ERROR, deck);
            assert_int_equal(line_of(deck, "vary"), 7);
            assert_string_equal(res[run].error, want);
        }
        else {
            assert_int_equal(res[run].summary.steps, 20);
            assert_int_equal(res[run].summary.status, NBEP_SUMMARY_COMPLETED);
            assert_true(res[run].summary.steps_requested.known);
            assert_int_equal(res[run].summary.steps_requested.value, 20);
        }
        char *path = nbep_sweep_run_path(&p, run);
        assert_int_equal(access(path, F_OK) == 0, !bad);
        free(path);
    }
    free(res);
    nbep_sweep_plan_fini(&p);
}

/* Two single spheres 1.2 apart, radius 0.5: a radius of 0.8 (an axis value) makes them overlap,
 * which only their placement at run time finds. */
static const char *write_overlap_deck(const char *name, const char *values, char *path,
                                      size_t len)
{
    snprintf(path, len, TMP "%s.deck", name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f,
            "run: { steps = 20; dt = 1.0e-3; threads = 1; };\n"
            "spheres = ( { position = [0.0, 0.0, 0.0]; radius = 0.5; mass = 1.0; },\n"
            "            { position = [1.2, 0.0, 0.0]; radius = 0.5; mass = 1.0; } );\n"
            "output: { file = \"" TMP "%s.h5\"; every = 10; };\n"
            "sweep: { vary = ( { key = \"spheres.[0].radius\";\n"
            "                    values = %s; } ); };\n",
            name, values);
    assert_int_equal(fclose(f), 0);
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '" TMP "%s.sweep'", name);
    assert_int_equal(system(cmd), 0);
    return path;
}

/* An axis value that a --set gave (sweep.vary.[0].values.[1]=0.8, the deck's list kept) and
 * that fails its run is named without the deck's line, which holds another value: the label
 * says the axis only. (Until 2026-11-30 a restitution of 1.5 served, which the deck's check
 * now refuses before any run.) */
static void test_a_failing_value_from_the_command_line_names_no_deck_line(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    const char *const ov[] = {"sweep.vary.[0].values.[1]=0.8"};
    plan_of(write_overlap_deck("sweep_fail_set", "[0.5, 0.4]", deck, sizeof deck), ov, 1, &p);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].outcome, NBEP_SWEEP_OK);
    assert_int_equal(res[1].outcome, NBEP_SWEEP_FAILED);
    char want[512];
    snprintf(want, sizeof want,
             "%s: sweep.vary.[0]: spheres.[1] (sphere 1) overlaps spheres.[0] (sphere 0) by 0.1",
             deck);
    assert_string_equal(res[1].error, want);
    free(res);
    nbep_sweep_plan_fini(&p);
}

/* A value that makes spheres overlap at t0 (a radius) fails its run naming the axis, as any
 * value the run rejects: until 2026-11-30 the overlap named the deck's line of the sphere's
 * position, which holds no value of the sweep's. */
static void test_an_overlap_a_value_makes_names_the_axis(void **state)
{
    (void)state;
    char deck[256];
    write_overlap_deck("sweep_fail_overlap", "[0.5, 0.8]", deck, sizeof deck);
    nbep_sweep_plan p;
    plan_of(deck, NULL, 0, &p);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].outcome, NBEP_SWEEP_OK);
    assert_int_equal(res[1].outcome, NBEP_SWEEP_FAILED);
    assert_int_equal(res[1].exit_code, 2);
    char want[512];
    const unsigned line = line_of(deck, "values = [0.5, 0.8]");
    assert_int_equal(line, 6);
    snprintf(want, sizeof want,
             "%s:%u: sweep.vary.[0]: spheres.[1] (sphere 1) overlaps spheres.[0] (sphere 0) by 0.1",
             deck, line);
    assert_string_equal(res[1].error, want);
    free(res);
    nbep_sweep_plan_fini(&p);
}

static void test_a_restarted_sweep_reuses_complete_runs(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_restart", with_failing_value, deck, sizeof deck), NULL, 0, &p);
    free(execute(&p, NULL, NBEP_OK));
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    for (size_t run = 0; run < 6; run++) {
        bool bad = run % 3 == 1;
        assert_int_equal(res[run].outcome, bad ? NBEP_SWEEP_FAILED : NBEP_SWEEP_OK);
        assert_int_equal(res[run].reused, !bad);
        if (!bad) { /* the file's summary, read back */
            assert_int_equal(res[run].summary.steps, 20);
            assert_int_equal(res[run].summary.status, NBEP_SUMMARY_COMPLETED);
            assert_int_equal(res[run].summary.steps_requested.value, 20);
        }
    }
    free(res);
    nbep_sweep_plan_fini(&p);
}

static void test_a_stop_signal_before_a_run_leaves_it_not_run(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_stop", with_failing_value, deck, sizeof deck), NULL, 0, &p);
    atomic_int stop;
    atomic_init(&stop, SIGINT);
    nbep_sweep_result *res = execute(&p, &stop, NBEP_ESIGINT);
    for (size_t run = 0; run < p.n_runs; run++) {
        assert_int_equal(res[run].outcome, NBEP_SWEEP_NOT_RUN);
        assert_int_equal(res[run].rank, -1);
    }
    free(res);
    nbep_sweep_plan_fini(&p);
}

/* The file's lines (at most 16), each malloc'd; returns the count. */
static size_t read_lines(const char *path, char *lines[16])
{
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t n = 0;
    char buf[4096];
    while (n < 16 && fgets(buf, sizeof buf, f)) {
        buf[strcspn(buf, "\n")] = '\0';
        lines[n++] = strdup(buf);
    }
    fclose(f);
    return n;
}

/* Field k of a CSV line (no quoted commas before it), into buf. */
static const char *csv_field(const char *line, int k, char *buf, size_t len)
{
    for (; k > 0; k--) {
        line = strchr(line, ',');
        assert_non_null(line);
        line++;
    }
    size_t n = strcspn(line, ",");
    snprintf(buf, len, "%.*s", (int)(n < len ? n : len - 1), line);
    return buf;
}

static void test_summary_csv_has_a_row_per_run_in_run_order(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_csv", with_failing_value, deck, sizeof deck), NULL, 0, &p);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_write_summary(&p, res, 1, 2.5, NULL, &d), NBEP_OK);
    char *lines[16];
    size_t n = read_lines(TMP "sweep_csv.sweep/summary.csv", lines);
    assert_int_equal(n, 1 + 6);
    assert_string_equal(lines[0],
                        "run,replica,seed,rank,spheres.[0].radius,status,exit_code,reused,"
                        "seconds,file,algorithm,threads,spheres,planes,steps,dt,setup_seconds,"
                        "wall_seconds,steps_per_second,checks,predictions,collisions,"
                        "sphere_collisions,plane_collisions,quiet_steps,energy_initial,"
                        "energy_final,energy_rel_drift,max_overlap,max_overlap_rel,"
                        "peak_rss_bytes,pressure,steps_requested,error");
    static const char *const radius[3] = {"0.05", "0.45", "0.04"};
    char f[128], want[64];
    for (size_t run = 0; run < 6; run++) {
        const char *row = lines[1 + run];
        bool bad = run % 3 == 1;
        snprintf(want, sizeof want, "%zu", run);
        assert_string_equal(csv_field(row, 0, f, sizeof f), want);
        snprintf(want, sizeof want, "%zu", run / 3);
        assert_string_equal(csv_field(row, 1, f, sizeof f), want);
        snprintf(want, sizeof want, "%zu", 11 + run / 3);
        assert_string_equal(csv_field(row, 2, f, sizeof f), want);
        assert_string_equal(csv_field(row, 3, f, sizeof f), "0");
        assert_string_equal(csv_field(row, 4, f, sizeof f), radius[run % 3]);
        assert_string_equal(csv_field(row, 5, f, sizeof f), bad ? "failed" : "ok");
        assert_string_equal(csv_field(row, 6, f, sizeof f), bad ? "2" : "0");
        snprintf(want, sizeof want, "run-%04zu.h5", run);
        assert_string_equal(csv_field(row, 9, f, sizeof f), bad ? "" : want);
        assert_string_equal(csv_field(row, 10, f, sizeof f), bad ? "" : "predictive");
        assert_string_equal(csv_field(row, 12, f, sizeof f), bad ? "" : "8");
        assert_string_equal(csv_field(row, 14, f, sizeof f), bad ? "" : "20");
        if (bad)
            assert_non_null(strstr(row, ".deck" FAILING_VALUE_ERROR));
        else
            assert_int_equal(row[strlen(row) - 1], ',');   /* empty error */
        assert_string_equal(csv_field(row, 31, f, sizeof f), "");   /* pressure: null */
        assert_string_equal(csv_field(row, 32, f, sizeof f), bad ? "" : "20"); /* requested */
    }
    for (size_t k = 0; k < n; k++)
        free(lines[k]);
    free(res);
    nbep_diag_fini(&d);
    nbep_sweep_plan_fini(&p);
}

/* A run an older nbep finished (its summary without status and steps_requested) is reused, and
 * its row shows what that summary says: steps_requested empty, as for any key a row lacks,
 * not 0; the status column says ok. */
static void test_an_older_nbeps_finished_run_is_reused_with_steps_requested_empty(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_older", "", deck, sizeof deck), NULL, 0, &p);
    free(execute(&p, NULL, NBEP_OK));
    /* its summary as an older nbep wrote it: everything up to pressure */
    char *path = nbep_sweep_run_path(&p, 0), **ov;
    size_t n;
    nbep_summary sum;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_run_overrides(&p, 0, &ov, &n, &d), NBEP_OK);
    assert_true(nbep_sweep_run_complete(path, ov, n, 20, &sum));
    char *json = nbep_summary_to_json(&sum);
    assert_non_null(json);
    strcpy(strstr(json, ", \"status\": "), "}\n");
    set_summary_json(path, json);
    free(json);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    assert_int_equal(res[0].outcome, NBEP_SWEEP_OK);
    assert_int_equal(res[0].reused, 1);
    assert_int_equal(res[0].summary.status, NBEP_SUMMARY_UNKNOWN);
    assert_false(res[0].summary.steps_requested.known);
    assert_int_equal(nbep_sweep_write_summary(&p, res, 1, 1.0, NULL, &d), NBEP_OK);
    char *lines[16];
    assert_int_equal(read_lines(TMP "sweep_older.sweep/summary.csv", lines), 2);
    char f[64];
    assert_string_equal(csv_field(lines[0], 4, f, sizeof f), "status");
    assert_string_equal(csv_field(lines[1], 4, f, sizeof f), "ok");
    assert_string_equal(csv_field(lines[0], 13, f, sizeof f), "steps");
    assert_string_equal(csv_field(lines[1], 13, f, sizeof f), "20");
    assert_string_equal(csv_field(lines[0], 31, f, sizeof f), "steps_requested");
    assert_string_equal(csv_field(lines[1], 31, f, sizeof f), "");
    free(lines[0]);
    free(lines[1]);
    nbep_diag_fini(&d);
    free(res);
    free(path);
    nbep_sweep_overrides_free(ov, n);
    nbep_sweep_plan_fini(&p);
}

/* The integer attribute `name` of the file's root. */
static int64_t int_attr(hid_t file, const char *name)
{
    int64_t v = -1;
    hid_t a = H5Aopen(file, name, H5P_DEFAULT);
    assert_true(a >= 0 && H5Aread(a, H5T_NATIVE_INT64, &v) >= 0);
    H5Aclose(a);
    return v;
}

/* Asserts that the text attribute `name` of the file's root is `want`. */
static void text_attr_is(hid_t file, const char *name, const char *want)
{
    hid_t a = H5Aopen(file, name, H5P_DEFAULT);
    assert_true(a >= 0);
    hid_t type = H5Aget_type(a);
    assert_int_equal(H5Tget_class(type), H5T_STRING);
    char *v = NULL;
    if (H5Tis_variable_str(type) > 0) {
        hid_t str = H5Tcopy(H5T_C_S1);
        H5Tset_size(str, H5T_VARIABLE);
        assert_true(H5Aread(a, str, &v) >= 0);
        assert_string_equal(v, want);
        H5free_memory(v);
        H5Tclose(str);
    } else {
        const size_t n = H5Tget_size(type);
        v = calloc(n + 1, 1);
        assert_non_null(v);
        assert_true(H5Aread(a, type, v) >= 0);
        assert_string_equal(v, want);
        free(v);
    }
    H5Tclose(type);
    H5Aclose(a);
}

/* Reads member `name` of every row of /runs as `type` into buf (n rows of size each). */
static void read_member(hid_t ds, const char *name, hid_t type, void *buf)
{
    hid_t mem = H5Tcreate(H5T_COMPOUND, H5Tget_size(type));
    assert_true(mem >= 0);
    assert_true(H5Tinsert(mem, name, 0, type) >= 0);
    assert_true(H5Dread(ds, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
    H5Tclose(mem);
}

static void test_summary_h5_holds_the_same_table(void **state)
{
    (void)state;
    char deck[256];
    nbep_sweep_plan p;
    plan_of(write_deck("sweep_h5", with_failing_value, deck, sizeof deck), NULL, 0, &p);
    nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_sweep_write_summary(&p, res, 3, 2.5, NULL, &d), NBEP_OK);
    hid_t file = H5Fopen(TMP "sweep_h5.sweep/summary.h5", H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    hid_t ds = H5Dopen2(file, "/runs", H5P_DEFAULT);
    assert_true(ds >= 0);
    hid_t type = H5Dget_type(ds), space = H5Dget_space(ds);
    hsize_t rows;
    assert_int_equal(H5Sget_simple_extent_dims(space, &rows, NULL), 1);
    assert_int_equal(rows, 6);
    assert_int_equal(H5Tget_nmembers(type), 34);   /* the CSV's 34 columns */
    char *m0 = H5Tget_member_name(type, 0), *m4 = H5Tget_member_name(type, 4);
    assert_string_equal(m0, "run");
    assert_string_equal(m4, "spheres.[0].radius");
    H5free_memory(m0);
    H5free_memory(m4);
    /* whole columns stored as 64-bit integers: counts past 2^31 (a run's checks, collisions)
     * must not be clamped */
    for (unsigned k = 0; k < 2; k++) {
        static const char *const whole[2] = {"run", "seed"};
        hid_t mt = H5Tget_member_type(type, (unsigned)H5Tget_member_index(type, whole[k]));
        assert_int_equal(H5Tget_class(mt), H5T_INTEGER);
        assert_int_equal(H5Tget_size(mt), 8);
        H5Tclose(mt);
    }

    int64_t run[6], steps[6], seed[6], requested[6];
    double drift[6];
    char *status[6], *value[6];
    hid_t str = H5Tcopy(H5T_C_S1);
    H5Tset_size(str, H5T_VARIABLE);
    read_member(ds, "run", H5T_NATIVE_INT64, run);
    read_member(ds, "seed", H5T_NATIVE_INT64, seed);
    read_member(ds, "steps", H5T_NATIVE_INT64, steps);
    read_member(ds, "steps_requested", H5T_NATIVE_INT64, requested);
    read_member(ds, "energy_rel_drift", H5T_NATIVE_DOUBLE, drift);
    read_member(ds, "status", str, status);
    read_member(ds, "spheres.[0].radius", str, value);
    static const char *const radius[3] = {"0.05", "0.45", "0.04"};
    for (size_t r = 0; r < 6; r++) {
        bool bad = r % 3 == 1;
        assert_int_equal(run[r], (int64_t)r);
        assert_int_equal(seed[r], 11 + (int64_t)r / 3);
        assert_int_equal(steps[r], bad ? 0 : 20);
        assert_int_equal(requested[r], bad ? 0 : 20);
        assert_true(bad ? isnan(drift[r]) : drift[r] == res[r].summary.energy_rel_drift);
        assert_string_equal(status[r], bad ? "failed" : "ok");
        assert_string_equal(value[r], radius[r % 3]);
        H5free_memory(status[r]);
        H5free_memory(value[r]);
    }
    /* every root attribute README lists, each the plan's: 2 replicas of 3 values, 6 runs, on
     * the 3 ranks and in the 2.5 s given, from this deck (a mutant that wrote the runs'
     * count as the replicas, or left the last attribute out, passed) */
    assert_int_equal(int_attr(file, "ranks"), 3);
    assert_int_equal(int_attr(file, "replicas"), 2);
    assert_int_equal(int_attr(file, "runs"), 6);
    hid_t a = H5Aopen(file, "wall_seconds", H5P_DEFAULT);
    double wall = 0.0;
    assert_true(a >= 0 && H5Aread(a, H5T_NATIVE_DOUBLE, &wall) >= 0);
    assert_true(wall == 2.5);
    H5Aclose(a);
    text_attr_is(file, "format", "nbep-sweep-1");
    text_attr_is(file, "version", NBEP_VERSION);
    text_attr_is(file, "deck_path", deck);
    text_attr_is(file, "deck", p.deck_text);
    text_attr_is(file, "overrides", "");
    text_attr_is(file, "axes", "spheres.[0].radius");
    text_attr_is(file, "build_flags", NBEP_BUILD_FLAGS);
    H5Tclose(str);
    H5Tclose(type);
    H5Sclose(space);
    H5Dclose(ds);
    H5Fclose(file);
    free(res);
    nbep_diag_fini(&d);
    nbep_sweep_plan_fini(&p);
}

/* nbep check's size of a study's tables (nbep_sweep_tables_bytes, in its `sweep output` line)
 * against the summary.csv and summary.h5 written after its runs: within 15 %, for 18 runs of two
 * axes (one of vectors, quoted in the CSV) and for 2 and 200 runs of none. Until 2026-11-30
 * nbep check left the tables out. */
static void test_the_tables_size_is_known_before_the_runs(void **state)
{
    (void)state;
    static const struct {
        const char *name, *sweep;
    } cases[] = {
        {"sweep_tables_axes", three_by_two},
        {"sweep_tables_two", "sweep: { replicas = 2; };\n"},
        {"sweep_tables_many", "sweep: { replicas = 200; };\n"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char deck[256], path[512];
        nbep_sweep_plan p;
        plan_of(write_deck(cases[c].name, cases[c].sweep, deck, sizeof deck), NULL, 0, &p);
        nbep_sweep_result *res = execute(&p, NULL, NBEP_OK);
        nbep_diag d;
        nbep_diag_init(&d);
        assert_int_equal(nbep_sweep_write_summary(&p, res, 1, 2.5, NULL, &d), NBEP_OK);
        double written = 0.0;
        for (int k = 0; k < 2; k++) {
            struct stat st;
            snprintf(path, sizeof path, "%s/summary.%s", p.dir, k ? "h5" : "csv");
            assert_int_equal(stat(path, &st), 0);
            written += (double)st.st_size;
        }
        const double est = nbep_sweep_tables_bytes(&p);
        if (!(fabs(est - written) <= 0.15 * written))
            fail_msg("%s: %zu runs: tables estimated at %.0f bytes, written %.0f", cases[c].name,
                     p.n_runs, est, written);
        free(res);
        nbep_diag_fini(&d);
        nbep_sweep_plan_fini(&p);
    }
}

/* ---- the whole command --------------------------------------------------------------------- */

static void test_the_command_reports_failed_runs_and_exits_1(void **state)
{
    (void)state;
    char deck[256];
    write_deck("sweep_main", with_failing_value, deck, sizeof deck);
    nbep_cli cli = {.cmd = NBEP_CMD_SWEEP, .path = deck, .quiet = true,
                    .summary = TMP "sweep_main.json"};
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_status st = nbep_sweep_main(&cli, NULL, &d);
    assert_int_equal(nbep_status_exit_code(st), 1);
    assert_int_equal(d.n_errors, 1);
    assert_string_equal(d.msg[0], "nbep: sweep: 4 of 6 runs complete, 2 failed (run 1, 4; "
                                  "errors in " TMP "sweep_main.sweep/summary.csv)");
    char *lines[16];
    size_t n = read_lines(TMP "sweep_main.json", lines);
    assert_int_equal(n, 1);
    assert_non_null(strstr(lines[0], "\"format\": \"nbep-sweep-summary-1\""));
    assert_non_null(strstr(lines[0], "\"runs\": 6, \"ok\": 4, \"failed\": 2, \"interrupted\": 0, "
                                     "\"not_run\": 0, \"reused\": 0, \"ranks\": 1"));
    free(lines[0]);
    assert_int_equal(access(TMP "sweep_main.sweep/summary.h5", F_OK), 0);
    nbep_diag_fini(&d);
}

static void test_a_bad_deck_stops_the_command_before_any_run(void **state)
{
    (void)state;
    char deck[256];
    write_deck("sweep_baddeck", "sweep: { replicas = 0; };\n", deck, sizeof deck);
    nbep_cli cli = {.cmd = NBEP_CMD_SWEEP, .path = deck, .quiet = true};
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_status_exit_code(nbep_sweep_main(&cli, NULL, &d)), 2);
    assert_true(d.n_errors >= 1);
    assert_non_null(strstr(d.msg[0], "sweep.replicas"));
    assert_int_equal(access(TMP "sweep_baddeck.sweep", F_OK), -1);   /* nothing made */
    nbep_diag_fini(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_check_of_a_study_loads_every_run),
        cmocka_unit_test(test_runs_are_replicas_times_the_product_of_the_axes),
        cmocka_unit_test(test_replicas_are_outermost_and_the_last_axis_varies_fastest),
        cmocka_unit_test(test_every_combination_appears_once_per_replica),
        cmocka_unit_test(test_a_run_gets_the_command_line_then_its_values_then_its_seed),
        cmocka_unit_test(test_replica_r_runs_with_the_decks_seed_plus_r),
        cmocka_unit_test(test_a_deck_without_a_sweep_group_is_one_run),
        cmocka_unit_test(test_the_sweep_directory_is_the_output_name_with_sweep),
        cmocka_unit_test(test_run_files_have_four_digits_or_as_many_as_the_last_run_needs),
        cmocka_unit_test(test_varying_the_seed_a_key_twice_or_a_key_and_its_part_is_a_deck_error),
        cmocka_unit_test(test_a_bad_axis_value_is_refused_before_any_run),
        cmocka_unit_test(test_too_many_runs_is_a_deck_error_at_the_sweep_group),
        cmocka_unit_test(test_a_steps_axis_sets_each_runs_expected_steps),
        cmocka_unit_test(test_ranks_take_runs_in_rounds_of_alternating_direction),
        cmocka_unit_test(test_a_summary_reads_back_field_by_field),
        cmocka_unit_test(test_a_run_is_complete_only_with_its_overrides_and_all_its_steps),
        cmocka_unit_test(test_thread_count_and_output_name_do_not_make_a_run_different),
        cmocka_unit_test(test_a_thread_count_axis_makes_a_run_different),
        cmocka_unit_test(test_a_run_killed_before_its_summary_is_not_complete),
        cmocka_unit_test(test_a_run_is_complete_only_when_its_summary_says_it_completed),
        cmocka_unit_test(test_an_older_nbeps_finished_run_is_reused_with_steps_requested_empty),
        cmocka_unit_test(test_a_failing_combination_spares_the_other_runs),
        cmocka_unit_test(test_a_failing_value_from_the_command_line_names_no_deck_line),
        cmocka_unit_test(test_an_overlap_a_value_makes_names_the_axis),
        cmocka_unit_test(test_a_restarted_sweep_reuses_complete_runs),
        cmocka_unit_test(test_a_stop_signal_before_a_run_leaves_it_not_run),
        cmocka_unit_test(test_summary_csv_has_a_row_per_run_in_run_order),
        cmocka_unit_test(test_summary_h5_holds_the_same_table),
        cmocka_unit_test(test_the_tables_size_is_known_before_the_runs),
        cmocka_unit_test(test_the_command_reports_failed_runs_and_exits_1),
        cmocka_unit_test(test_a_bad_deck_stops_the_command_before_any_run),
    };
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    return cmocka_run_group_tests_name("sweep", tests, NULL, NULL);
}
