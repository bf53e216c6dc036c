/* A spinning barrier on C11 atomics (paper Section 4.1, Procedure 4) that is safe to reuse
 * back to back: the paper's counts threads down and back up on one counter, so a fast thread
 * can re-enter the next wait before the others have left the previous one. This one rearms
 * the counter before advancing a round number that waiters watch (sense reversal by round).
 * A waiter spins for a short while (a round of the paper's step takes microseconds) and then
 * sleeps until the round advances: in the cells mode the other threads wait out a whole step's
 * serial event loop, which spinning turned into a second core burnt for nothing (and taken
 * from any other job on the machine). */
#ifndef NBEP_BARRIER_H
#define NBEP_BARRIER_H

#include <stdalign.h>
#include <stdatomic.h>

#include "nbep/compiler.h"

typedef struct nbep_barrier {
    alignas(NBEP_CACHELINE) atomic_uint left;    /* arrivals still missing this round */
    atomic_uint sleepers;                        /* waiters that may be asleep on round */
    atomic_ulong sleeps;                         /* times a waiter went to sleep (for tests) */
    alignas(NBEP_CACHELINE) atomic_uint round;   /* advanced by the last arrival */
    unsigned n;
} nbep_barrier;

/* Spins (nbep_spin_pause) a waiter makes before it sleeps: some hundreds of microseconds, far
 * above a round of the paper's step and far below a dense scene's event loop. */
#define NBEP_BARRIER_SPINS (1u << 14)

/* For n >= 1 threads. */
void nbep_barrier_init(nbep_barrier *b, unsigned n);
/* Blocks until all n threads have called it; publishes every thread's writes before it to
 * every thread after it (acquire/release). Reusable immediately. */
void nbep_barrier_wait(nbep_barrier *b);

#endif
