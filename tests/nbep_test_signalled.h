/* A run stopped by a signal that a test raises itself (test_team_faults, test_detect_stop: their
 * own copies of an algorithm, whose hooks raise it at a chosen event or row). Include after
 * <cmocka.h>. */
#ifndef NBEP_TEST_SIGNALLED_H
#define NBEP_TEST_SIGNALLED_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "nbep/sim.h"

/* sc run on nt threads with *signal as its stop signal (lowered first): its status, its
 * summary, whether a step was abandoned, and its final state in *fin; the step of its last
 * frame must be frame_step. */
static nbep_status nbep_test_run_signalled(const nbep_scene *sc, int nt, atomic_int *signal,
                                           nbep_summary *sum, bool *abandoned, nbep_state *fin,
                                           uint64_t frame_step)
{
    atomic_store_explicit(signal, 0, memory_order_relaxed);
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_sim_options opt = {.threads = nt, .stop_signal = signal};
    nbep_sim *sim = NULL;
    assert_int_equal(nbep_sim_create(sc, &opt, &sim, &d), NBEP_OK);
    const nbep_status st = nbep_sim_run(sim, &d);
    assert_int_equal(d.n_errors, 0); /* a signal's line is nbep_run's to write */
    nbep_sim_summary(sim, sum);
    uint64_t last;
    *abandoned = nbep_sim_abandoned(sim, &last);
    assert_int_equal(last, frame_step);
    assert_int_equal(nbep_state_copy(fin, nbep_sim_state(sim), &d), NBEP_OK);
    nbep_sim_destroy(&sim);
    nbep_diag_fini(&d);
    return st;
}

#endif
