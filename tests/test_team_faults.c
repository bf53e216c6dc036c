/* The cells engine's ways out of a fault, on one thread and in the team loop: a stall (events
 * that do not advance time: the stall check, nbep__evloop_advances) and a list expiry whose walk
 * runs out of memory. Neither happens in a scene a test can build on purpose (an elastic fluid
 * always advances; a walk's room grows with realloc), so this test compiles its own copy of the
 * engine (src/evloop.c and src/evloop_team.c) whose hooks make the stall check fail, or every
 * walk fail, from a time on. Both are functions of the event's time alone, so the one thread and
 * the team meet them at the same event in the calendar's order: the team, with events handled
 * ahead of it, must stop there as the one thread does, with its status, its message and its state
 * bit for bit (the places after the stopping one undone, the stopping one as the one thread left
 * it: not handled at a stall, handled but not committed at a failed walk). A failed walk in a
 * run with output, through `nbep run`'s pipeline: the file keeps every step done. The
 * scheduled loop's slabs (NBEP_SCHEDULED, NBEP_SLABS; src/evloop_warp.c, also compiled here)
 * must stop as the one thread does too, their slabs run ahead of each other cut back. */
#include <math.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>

struct nbep_evloop_stall;
static void stall_hook(struct nbep_evloop_stall *st, double t);
static double oom_from = INFINITY;
#define NBEP_EVLOOP_STALL_HOOK(st, t) stall_hook(st, t)
#define NBEP_EVLOOP_OOM_HOOK(i, t) ((void)(i), (t) >= oom_from)
struct evl_sched;
static void on_destroy(const struct evl_sched *x);
#define NBEP_SCHED_DESTROY_HOOK(x) on_destroy(x)
#include "../src/evloop.c"
#include "../src/evloop_team.c"
#include "../src/evloop_warp.c"

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/run.h"
#include "nbep/sim.h"
#include "nbep/summary.h"
#include "nbep_test.h"
#include "nbep_test_h5.h"
#include "nbep_test_scene.h"
#include "nbep_test_signalled.h"

/* From this time on the stall check fails at its next look (every STALL_LOOK events, or at
 * once where look_at_once is set: the slabs count their events apart, so that the 64th falls
 * elsewhere there): as though the events there stood still. */
static double stall_from = INFINITY;
static bool look_at_once;
#define STALL_LOOK 64
/* From this time on the run's stop signal is raised (SIGTERM), and the loop looks at it at
 * every event (it looks every NBEP_EVLOOP_STOP_EVERY events, more than a step of these scenes
 * holds): as though a job's time limit came then. */
static double signal_from = INFINITY;
static atomic_int test_signal;

static void stall_hook(nbep_evloop_stall *st, double t)
{
    /* looks every STALL_LOOK events only while a stall or a signal is armed: a lattice's start
     * has more than that many events at t = 0 (its first predictions' stale slots), which
     * would read as a stall to an unarmed run */
    if (stall_from == INFINITY && signal_from == INFINITY)
        return;
    st->events = STALL_LOOK;
    if (t >= stall_from) {
        st->events = look_at_once ? 1 : STALL_LOOK;
        st->dt = INFINITY;
    }
    if (t >= signal_from) {
        atomic_store_explicit(&test_signal, SIGTERM, memory_order_relaxed);
        st->looks = NBEP_EVLOOP_STOP_EVERY - 1;
    }
}

/* The events the scheduled loop's slabs undid, summed over the loops destroyed since reset */
static uint64_t undone;

static void on_destroy(const struct evl_sched *x)
{
    for (int k = 0; k < x->slabs; k++)
        undone += nbep_warp_tally_of(x->warp, k).undone;
}

/* The ways past one thread that must stop as it does: the team on 2, 3 and 4 threads (TEAMS),
 * then the scheduled loop (NBEP_SCHEDULED) on one slab (one thread), and its slabs
 * (NBEP_SLABS: 2 slabs in turns on one thread, 2 and 3 slabs on 2 threads, from SLABS on),
 * which run ahead of each other and are cut back to the stop where it stands
 * (src/evloop_warp.c; until 2026-12-07 a walk out of memory there ended the call with the
 * other slabs wherever they were). Way q's settings made (the teardown, faults_off, takes them
 * away); its thread count returned. */
#define TEAMS 3
#define SLABS 4
#define WAYS 7
static int way(int q)
{
    if (q < TEAMS)
        return q + 2;
    setenv("NBEP_SCHEDULED", "1", 1);
    if (q < SLABS)
        return 1;
    setenv("NBEP_SLABS", q == WAYS - 1 ? "3" : "2", 1);
    return q == SLABS ? 1 : 2;
}

/* Every fault disarmed and every setting gone, also after a failed test (whose asserts leave
 * the function early) */
static int faults_off(void **state)
{
    (void)state;
    stall_from = oom_from = signal_from = INFINITY;
    look_at_once = false;
    unsetenv("NBEP_SCHEDULED");
    unsetenv("NBEP_SLABS");
    unsetenv("NBEP_TEAM");
    return 0;
}

/* An elastic periodic fluid at phi = 0.45 (the team handles most of its events ahead, undoing
 * some) that would run 6 steps of 0.03, stopped from t = 0.075 (its third step) by the fault
 * that *from arms: on 1 thread with status want and a message holding what, then the other
 * ways with the same status, message and state, events having gone ahead (the team's places,
 * the slabs' events undone). Twice: a stall's look every 64 events, where the team's count of
 * events must be one thread's, then at once, for the slabs too. */
static void team_stops_as_one_thread(double *from, nbep_status want, const char *what)
{
    nbep_scene *sc = nbep_test_periodic_fluid(nbep_test_scaled(12, 10), 0.45, 6, 0.03, 7);
    sc->output_every = 6;
    setenv("NBEP_TEAM", "always", 1);
    char ref[512], msg[512];
    uint64_t ahead;
    nbep_state fin1, fin;
    /* unarmed, the run ends: the fault is the hook's */
    assert_int_equal(nbep_test_run_to_end(sc, 2, msg, sizeof msg, &ahead, &fin), NBEP_OK);
    nbep_state_fini(&fin);
    for (int pass = 0; pass < 2; pass++) {
        look_at_once = pass == 1; /* (the first pass sets no scheduled way: way(q < TEAMS)) */
        *from = 0.075;
        uint64_t counts1[NBEP_COUNTER_COUNT], counts[NBEP_COUNTER_COUNT];
        assert_int_equal(
            nbep_test_run_to_end_counted(sc, 1, ref, sizeof ref, &ahead, &fin1, counts1), want);
        assert_non_null(strstr(ref, what));
        unsigned long long step = 0; /* a step from the one armed (the third) to the last */
        assert_int_equal(sscanf(ref, "nbep: step %llu:", &step), 1);
        assert_true(step >= 3 && step <= 6);
        assert_int_equal(ahead, 0);
        for (int q = 0; q < (pass == 0 ? TEAMS : WAYS); q++) {
            const int nt = way(q);
            undone = 0;
            assert_int_equal(
                nbep_test_run_to_end_counted(sc, nt, msg, sizeof msg, &ahead, &fin, counts), want);
            assert_string_equal(msg, ref);
            /* the counts to the fault one thread's (but the team's own, ahead and undone) */
            for (int k = 0; k < NBEP_COUNTER_COUNT; k++)
                if (k != NBEP_COUNTER_AHEAD && k != NBEP_COUNTER_UNDONE)
                    assert_int_equal(counts[k], counts1[k]);
            /* (ahead: the team's places handled ahead; the slabs' events undone) */
            assert_true(q < TEAMS ? ahead > 0 : q < SLABS || undone > 0);
            assert_memory_equal(fin.pos, fin1.pos, fin1.n * sizeof *fin1.pos);
            assert_memory_equal(fin.vel, fin1.vel, fin1.n * sizeof *fin1.vel);
            assert_memory_equal(fin.image, fin1.image, 3 * fin1.n * sizeof *fin1.image);
            nbep_state_fini(&fin);
        }
        nbep_state_fini(&fin1);
    }
    nbep_test_scene_free(&sc); /* (the fault and the settings: faults_off) */
}

/* A stall: the step fails at the event where the check first fails (status numeric, "events at
 * t = ... do not resolve", that event's time), before handling it, on every thread count. */
static void test_the_team_stops_at_a_stall_as_one_thread_does(void **state)
{
    (void)state;
    team_stops_as_one_thread(&stall_from, NBEP_ENUMERIC, "do not resolve");
}

/* A walk out of memory: the step fails at the first list expiry from then on, with "no memory
 * for the neighbour lists" (status out of memory), on every thread count. */
static void test_the_team_stops_at_a_failed_walk_as_one_thread_does(void **state)
{
    (void)state;
    team_stops_as_one_thread(&oom_from, NBEP_ENOMEM, "no memory for the neighbour lists");
}

/* sc run on nt threads with test_signal as its stop signal (nbep_test_run_signalled) */
static nbep_status run_signalled(const nbep_scene *sc, int nt, nbep_summary *sum, bool *abandoned,
                                 nbep_state *fin, uint64_t frame_step)
{
    return nbep_test_run_signalled(sc, nt, &test_signal, sum, abandoned, fin, frame_step);
}

/* A signal in the middle of a step's events (a job's time limit during a step far too long to
 * wait for): the loop abandons the step at the event where it looks (README, Faults), and the
 * run ends after the step before, as a run of that many steps ends (its collisions, checks and
 * predictions, none of the abandoned step's; its last frame the one before the signal), on one thread and in the team, where the events
 * handled ahead are undone and the state is the one thread's bit for bit. */
static void test_a_signal_abandons_the_step_on_any_thread_count(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(nbep_test_scaled(12, 10), 0.45, 6, 0.03, 7);
    sc->output_every = 2; /* frames at steps 0, 2, 4, 6: the last before the signal, 2 */
    setenv("NBEP_TEAM", "always", 1);
    nbep_summary two, ref, sum;
    bool abandoned;
    nbep_state fin1, fin;
    sc->steps = 2; /* the run that ends where the signalled one must */
    assert_int_equal(run_signalled(sc, 1, &two, &abandoned, &fin, 2), NBEP_OK);
    assert_false(abandoned);
    nbep_state_fini(&fin);
    sc->steps = 6;
    signal_from = 0.075; /* in the third step */
    assert_int_equal(run_signalled(sc, 1, &ref, &abandoned, &fin1, 2), NBEP_ESIGTERM);
    assert_true(abandoned);
    assert_int_equal(ref.steps, 2);
    assert_int_equal(ref.collisions, two.collisions);
    assert_int_equal(ref.checks, two.checks);
    assert_int_equal(ref.predictions, two.predictions);
    assert_true(two.collisions > 0);
    for (int q = 0; q < WAYS; q++) {
        const int nt = way(q);
        assert_int_equal(run_signalled(sc, nt, &sum, &abandoned, &fin, 2), NBEP_ESIGTERM);
        assert_true(abandoned);
        assert_int_equal(sum.steps, 2);
        assert_int_equal(sum.collisions, two.collisions);
        assert_int_equal(sum.checks, two.checks);
        assert_memory_equal(fin.pos, fin1.pos, fin1.n * sizeof *fin1.pos);
        assert_memory_equal(fin.vel, fin1.vel, fin1.n * sizeof *fin1.vel);
        nbep_state_fini(&fin);
    }
    nbep_state_fini(&fin1);
    nbep_test_scene_free(&sc);
}

/* A step out of memory (the algorithm's: a walk from t = 0.075, in the third of 6 steps, whose
 * frames come every 6) in a run through nbep's pipeline with output (what `nbep run` does): the
 * run fails for memory with one line naming the step, and the file keeps what the run did, the
 * stats rows of every step done before it (none was flushed by a frame: until 2026-12-07 they
 * were dropped) and a /summary that says it failed (none, until then: the fault was taken for a
 * write's); with the memory there, a resume takes the file up to the run's end. */
static void test_a_step_out_of_memory_keeps_the_steps_done_in_the_file(void **state)
{
    (void)state;
    /* 12^3 spheres of diameter 1 at phi = 0.45: the fluid of team_stops_as_one_thread */
    const double side = cbrt(1728.0 * acos(-1.0) / 6.0 / 0.45);
    char deck[2048], deck_path[256], out[256];
    snprintf(deck, sizeof deck,
             "run: { algorithm = \"predictive\"; neighbors = \"cells\"; steps = 6; dt = 0.03;\n"
             "       threads = 1; seed = 7; };\n"
             "box: { min = [0.0, 0.0, 0.0]; max = [%.17g, %.17g, %.17g];\n"
             "       periodic = [true, true, true]; };\n"
             "spheres = ( { count = 1728; radius = 0.5; mass = 1.0; place = \"lattice\";\n"
             "              speed = 1.7320508075688772; } );\n"
             "output: { file = \"unused.h5\"; every = 6; stats = true; };\n",
             side, side, side);
    nbep_test_write_deck("team_faults_oom.deck", deck, deck_path, sizeof deck_path);
    nbep_test_tmp("team_faults_oom.h5", out, sizeof out);
    remove(out);

    oom_from = 0.075;
    const nbep_run_request rq = {.deck_path = deck_path, .output_path = out};
    nbep_run_result res;
    nbep_diag d;
    nbep_diag_init(&d);
    const nbep_status st = nbep_run(&rq, &res, &d);
    if (st != NBEP_ENOMEM)
        nbep_diag_print(&d, stderr);
    assert_int_equal(st, NBEP_ENOMEM);
    oom_from = INFINITY;
    assert_int_equal(d.n_errors, 1);
    assert_non_null(strstr(d.msg[0], "no memory for the neighbour lists"));
    unsigned long long step = 0;
    assert_int_equal(sscanf(d.msg[0], "nbep: step %llu:", &step), 1);
    assert_true(step >= 3 && step <= 6);
    nbep_diag_fini(&d);
    assert_int_equal(res.summary.steps, step - 1);
    assert_int_equal(res.summary.status, NBEP_SUMMARY_FAILED);

    size_t n = 0;
    double *steps = nbep_test_h5_doubles(out, "/stats/step", &n);
    assert_int_equal(n, step - 1);
    for (size_t k = 0; k < n; k++)
        assert_true(steps[k] == (double)(k + 1));
    free(steps);
    double *frames = nbep_test_h5_doubles(out, "/frames/step", &n);
    assert_int_equal(n, 1); /* the first frame only: the next was due at step 6 */
    free(frames);
    hid_t file = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    assert_true(H5Aexists_by_name(file, "/summary", "json", H5P_DEFAULT) > 0);
    H5Fclose(file);

    /* with the memory there, a resume takes it up from its last frame (step 0) to the end */
    const nbep_run_request again = {.deck_path = deck_path, .resume = out};
    nbep_diag_init(&d);
    assert_int_equal(nbep_run(&again, &res, &d), NBEP_OK);
    nbep_diag_fini(&d);
    assert_int_equal(res.resumed_from, 0);
    assert_int_equal(res.summary.status, NBEP_SUMMARY_COMPLETED);
    steps = nbep_test_h5_doubles(out, "/stats/step", &n);
    assert_int_equal(n, 6);
    for (size_t k = 0; k < n; k++)
        assert_true(steps[k] == (double)(k + 1));
    free(steps);
    remove(out);
    remove(deck_path);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_a_signal_abandons_the_step_on_any_thread_count,
                                  faults_off),
        cmocka_unit_test_teardown(test_the_team_stops_at_a_stall_as_one_thread_does, faults_off),
        cmocka_unit_test_teardown(test_the_team_stops_at_a_failed_walk_as_one_thread_does,
                                  faults_off),
        cmocka_unit_test_teardown(test_a_step_out_of_memory_keeps_the_steps_done_in_the_file,
                                  faults_off),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
