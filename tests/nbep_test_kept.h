/* A run kept to compare with another (tests/test_sched_rollback.c, tests/test_sched_slabs.c):
 * its summary, counters' totals, and the step rows of /stats/virial and /stats/wall_impulse. */
#ifndef NBEP_TEST_KEPT_H
#define NBEP_TEST_KEPT_H

#include <stdio.h>
#include <stdlib.h>

#include "nbep_test.h"
#include "nbep_test_h5.h"
#include "nbep_test_scene.h"

typedef struct {
    nbep_summary s;
    uint64_t counts[NBEP_COUNTER_COUNT];
    double *sums[2]; /* /stats/virial, /stats/wall_impulse (malloc'd) */
    size_t n[2];     /* their values */
} nbep_run_kept;

/* sc on nt threads into a temporary file named `name`, with its stats and one frame, the last
 * (each frame's checkpoint starts the lists afresh, and a frame a step would leave a short
 * step no list to expire): *r, and the final state into *fin */
static inline void nbep_test_run_kept(nbep_scene *sc, const char *name, int nt,
                                      nbep_run_kept *r, nbep_state *fin)
{
    sc->out_stats = true;
    sc->output_every = sc->steps;
    char path[256];
    nbep_test_tmp(name, path, sizeof path);
    r->s = nbep_test_run_to(sc, nt, NULL, NULL, path, fin, r->counts);
    r->sums[0] = nbep_test_h5_doubles(path, "/stats/virial", &r->n[0]);
    r->sums[1] = nbep_test_h5_doubles(path, "/stats/wall_impulse", &r->n[1]);
    remove(path);
}

/* b counted as a: every counter, the summary's counts, energies, maxima and pressure, the step
 * sums, bit for bit; frees b's sums */
static inline void nbep_test_same_kept(const nbep_run_kept *a, nbep_run_kept *b)
{
    for (int k = 0; k < NBEP_COUNTER_COUNT; k++)
        assert_int_equal(b->counts[k], a->counts[k]);
    assert_int_equal(b->s.checks, a->s.checks);
    assert_int_equal(b->s.predictions, a->s.predictions);
    assert_int_equal(b->s.sphere_collisions, a->s.sphere_collisions);
    assert_int_equal(b->s.plane_collisions, a->s.plane_collisions);
    const double x[] = {a->s.energy_final, a->s.max_overlap, a->s.max_overlap_rel,
                        a->s.pressure.value},
                 y[] = {b->s.energy_final, b->s.max_overlap, b->s.max_overlap_rel,
                        b->s.pressure.value};
    assert_memory_equal(x, y, sizeof x);
    assert_int_equal(b->s.pressure.known, a->s.pressure.known);
    for (int q = 0; q < 2; q++) {
        assert_int_equal(b->n[q], a->n[q]);
        if (a->n[q])
            assert_memory_equal(b->sums[q], a->sums[q], a->n[q] * sizeof *a->sums[q]);
        free(b->sums[q]);
        b->sums[q] = NULL;
    }
}

#endif
