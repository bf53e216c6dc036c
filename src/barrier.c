/* A reusable spinning barrier on C11 atomics (paper Section 4.1; STYLE 6).
 *
 * Departure from the paper's Procedure 4 (fetch_sub; spin while the count is above zero;
 * fetch_add): its one counter serves both as "who has arrived" and "who has left", so a fast
 * thread that leaves and re-enters the next wait before a slow one has seen the count reach
 * zero decrements it again and either runs ahead into the next sub-phase or leaves the slow
 * one spinning forever. Here the arrival counter `left` is rearmed by the last arrival alone,
 * before it advances `round`, the number every waiter watches; a waiter leaves as soon as the
 * round differs from the one it entered in, and by then `left` is already full again for the
 * next wait. `left` and `round` sit on separate cache lines so that arrivals writing `left`
 * do not keep invalidating the line the waiters spin on.
 *
 * After NBEP_BARRIER_SPINS spins a waiter sleeps on `round` (nbep_word_wait). The last arrival
 * wakes the sleepers after advancing it, and only when `sleepers` says there may be some: the
 * waiter counts itself in before it looks at `round` a last time, the last arrival advances
 * `round` before it looks at `sleepers`, all four sequentially consistent, so at least one of
 * them sees the other's write (no waiter sleeps through its round); the kernel's own compare
 * covers an advance between the waiter's last look and its sleep.
 *
 * Invariant between waits: left == n. The round number wraps; only its change is watched. */
#include "nbep/barrier.h"

#include <assert.h>

/* A pause between the last arrival's two stores, for tests/test_barrier_rearm.c only (it
 * compiles its own copy of this file): the moment a descheduled thread would stall there. */
#ifndef NBEP_BARRIER_BETWEEN_STORES
#define NBEP_BARRIER_BETWEEN_STORES() ((void)0)
#endif

void nbep_barrier_init(nbep_barrier *b, unsigned n)
{
    assert(b && n >= 1);
    /* Release stores rather than atomic_init: the threads that will wait may be pooled ones
     * that OpenMP hands work to by means ThreadSanitizer cannot see; the acquire load that
     * starts every wait then orders this initialisation (and everything before it) first. */
    b->n = n;
    atomic_store_explicit(&b->sleepers, 0u, memory_order_release);
    atomic_store_explicit(&b->sleeps, 0ul, memory_order_release);
    atomic_store_explicit(&b->left, n, memory_order_release);
    atomic_store_explicit(&b->round, 0u, memory_order_release);
}

void nbep_barrier_wait(nbep_barrier *b)
{
    /* `round` cannot advance before we arrive (`left` cannot reach zero without our
     * decrement), and we have already seen its current value: we either advanced it ourselves
     * or read it with the acquire load that let us out of the previous wait; coherence forbids
     * reading an older value after that. Relaxed would do for that; acquire also orders the
     * barrier's initialisation before a thread's first wait (see nbep_barrier_init). */
    const unsigned r = atomic_load_explicit(&b->round, memory_order_acquire);
    /* acq_rel: the release half publishes this thread's writes before the barrier; the
     * acquire half lets the last arrival see everyone's, since the fetch_subs of one round
     * form a release sequence that its read of 1 completes. */
    if (atomic_fetch_sub_explicit(&b->left, 1, memory_order_acq_rel) == 1) {
        /* Relaxed: published by the release store below, which every waiter acquires before
         * it can re-enter and decrement `left` again. */
        atomic_store_explicit(&b->left, b->n, memory_order_relaxed);
        NBEP_BARRIER_BETWEEN_STORES();
        /* Release (and sequentially consistent, for the sleepers below): passes on everything
         * the last arrival acquired (all threads' writes) and the rearmed `left`; pairs with
         * the waiters' acquire loads. */
        atomic_store_explicit(&b->round, r + 1u, memory_order_seq_cst);
        if (atomic_load_explicit(&b->sleepers, memory_order_seq_cst) != 0u)
            nbep_word_wake_all(&b->round);
    } else {
        /* Acquire (the sequentially consistent loads below too): pairs with the release store
         * of the new round, so writes before the barrier in any thread happen before our code
         * after it. */
        for (unsigned k = 1; k < NBEP_BARRIER_SPINS; k++) {
            if (atomic_load_explicit(&b->round, memory_order_acquire) != r)
                return;
            nbep_spin_pause(k); /* cpu pause; sched_yield() every 1024th */
        }
        /* long enough: sleep until the round advances (see the top of the file) */
        atomic_fetch_add_explicit(&b->sleepers, 1u, memory_order_seq_cst);
        atomic_fetch_add_explicit(&b->sleeps, 1ul, memory_order_relaxed);
        while (atomic_load_explicit(&b->round, memory_order_seq_cst) == r)
            nbep_word_wait(&b->round, r);
        /* relaxed: a count that lags only costs a last arrival a wake with no one to wake */
        atomic_fetch_sub_explicit(&b->sleepers, 1u, memory_order_relaxed);
    }
}
