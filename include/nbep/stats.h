/* Counters (X-macro list: the enum from one place), per-thread counter slots padded to a
 * cache line, and the per-step statistics row. The JSON summary's keys come from its own
 * table (summary.h) and the /stats columns from output.c's: both mix counters with derived
 * values (collisions = sphere + plane collisions), and `reactions` is internal. */
#ifndef NBEP_STATS_H
#define NBEP_STATS_H

#include <stdalign.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"

/* checks: pair tests (naive/seminaive: overlap tests; predictive: queue slots examined by
 * find plus check() calls); predictions: contact-time computations; collisions split by kind
 * (responses applied); reactions: events the predictive algorithm reacted to, whether or not
 * a response was applied (internal: shows that a pair is reacted to exactly once); ahead and
 * undone (internal): events the cells mode's team loop handled ahead of their turn on a second
 * thread that stood, and that it undid (evloop.h, nbep_evloop_run_lead); refits (internal):
 * the times the cells mode laid its cells out afresh over the spheres' extent, in a scene
 * without a box (algo_predictive.c, cells_fit). The second
 * column is the counter's lowercase name, for readers of this list. */
#define NBEP_COUNTER_LIST(X)                                                                 \
    X(CHECKS, "checks")                                                                      \
    X(PREDICTIONS, "predictions")                                                            \
    X(SPHERE_COLLISIONS, "sphere_collisions")                                                \
    X(PLANE_COLLISIONS, "plane_collisions")                                                  \
    X(REACTIONS, "reactions")                                                                \
    X(AHEAD, "ahead")                                                                        \
    X(UNDONE, "undone")                                                                      \
    X(REFITS, "refits")

enum nbep_counter {
#define NBEP_X_ENUM(name, key) NBEP_COUNTER_##name,
    NBEP_COUNTER_LIST(NBEP_X_ENUM)
#undef NBEP_X_ENUM
    NBEP_COUNTER_COUNT
};

/* One thread's counters, alone on its cache lines. */
typedef struct nbep_counters {
    alignas(NBEP_CACHELINE) uint64_t c[NBEP_COUNTER_COUNT];
} nbep_counters;

/* One row of /stats: the counters of one step and the state at its end. */
typedef struct nbep_step_stats {
    int64_t step;
    uint64_t checks, predictions, collisions;
    double kinetic_energy, potential_energy;
    double max_overlap;
    double virial;   /* sum of r12 . dp2 over the step's sphere collisions (SPEC) */
} nbep_step_stats;

#endif
