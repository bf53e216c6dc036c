/* The barrier's rearm order, tested deterministically. The race the order guards against
 * (src/barrier.c: the last arrival rearms `left` before it advances `round`) needs the last
 * arrival to stall between its two stores, which preemption does too rarely for a test to rely
 * on (test_barrier's random stalls catch the wrong order in about 3 runs of 4). This test
 * compiles its own copy of src/barrier.c with a pause exactly there, standing for that stall.
 * In the right order the waiters still spin during the pause and nothing can go wrong. In the
 * wrong order (advance, then rearm) a waiter leaves during the pause, enters the next wait and
 * decrements `left`; the late rearm erases that decrement, so the next wait never completes. A
 * watchdog turns that deadlock into a failure that says so. */
#define _DEFAULT_SOURCE /* nanosleep, alarm */
#include <signal.h>
#include <time.h>
#include <unistd.h>

/* 0.2 ms: far longer than a spinning waiter takes to see the new round and re-enter */
static void between_stores(void)
{
    struct timespec ts = {0, 200000L};
    nanosleep(&ts, NULL);
}
#define NBEP_BARRIER_BETWEEN_STORES() between_stores()
#include "../src/barrier.c"

#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>

#include "nbep_test_watchdog.h"

#define ROUNDS 300u       /* 300 pauses: 60 ms when right */
#define DEADLOCK_SECONDS 20u

static nbep_barrier bar;
static atomic_uint crossings; /* waits completed, all threads */

static void *worker(void *arg)
{
    (void)arg;
    for (unsigned r = 0; r < ROUNDS; r++) {
        nbep_barrier_wait(&bar);
        atomic_fetch_add_explicit(&crossings, 1, memory_order_relaxed);
    }
    return NULL;
}

static void run_threads(unsigned n)
{
    nbep_test_watchdog_arm(DEADLOCK_SECONDS,
                           "\nFAIL barrier_rearm: threads still waiting after 20 s: a waiter's "
                           "decrement was lost to a late rearm (deadlock)\n");
    nbep_barrier_init(&bar, n);
    atomic_store_explicit(&crossings, 0, memory_order_relaxed);
    pthread_t t[4];
    for (unsigned k = 0; k < n; k++)
        assert_int_equal(pthread_create(&t[k], NULL, worker, NULL), 0);
    for (unsigned k = 0; k < n; k++)
        assert_int_equal(pthread_join(t[k], NULL), 0);
    nbep_test_watchdog_disarm();
    assert_int_equal(atomic_load_explicit(&crossings, memory_order_relaxed), n * ROUNDS);
    /* the invariant between waits (barrier.c): left == n */
    assert_int_equal(atomic_load_explicit(&bar.left, memory_order_relaxed), n);
}

static void test_a_stalled_last_arrival_never_loses_a_waiter_two_threads(void **state)
{
    (void)state;
    run_threads(2);
}

static void test_a_stalled_last_arrival_never_loses_a_waiter_four_threads(void **state)
{
    (void)state;
    run_threads(4);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_stalled_last_arrival_never_loses_a_waiter_two_threads),
        cmocka_unit_test(test_a_stalled_last_arrival_never_loses_a_waiter_four_threads),
    };
    return cmocka_run_group_tests_name("barrier_rearm", tests, NULL, NULL);
}
