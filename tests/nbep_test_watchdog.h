/* A deadlock watchdog for tests of code that has no way out of a wait (the barrier): an alarm
 * that, if it goes off, prints why the test failed and exits 1, so that a hang is a failure
 * that says so rather than a wait for scripts/run-tests.sh's time limit. One at a time. Include
 * after <cmocka.h>. */
#ifndef NBEP_TEST_WATCHDOG_H
#define NBEP_TEST_WATCHDOG_H

#include <signal.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

static const char *nbep_test_watchdog_msg;
/* With a progress counter (nbep_test_watchdog_arm_progress), the alarm fails the test only when
 * the counter has not moved since the last alarm: a machine loaded by other work slows a run
 * down without failing it; a deadlock stops the counter. */
static const atomic_ulong *nbep_test_watchdog_progress;
static unsigned long nbep_test_watchdog_seen;
static unsigned nbep_test_watchdog_seconds;

static void nbep_test_watchdog_fire(int sig)
{
    (void)sig;
    if (nbep_test_watchdog_progress) { /* a lock-free atomic load is async-signal-safe */
        unsigned long now =
            atomic_load_explicit(nbep_test_watchdog_progress, memory_order_relaxed);
        if (now != nbep_test_watchdog_seen) {
            nbep_test_watchdog_seen = now;
            alarm(nbep_test_watchdog_seconds);
            return;
        }
    }
    /* write and strlen are async-signal-safe; the message was set before the alarm */
    ssize_t w = write(STDERR_FILENO, nbep_test_watchdog_msg, strlen(nbep_test_watchdog_msg));
    (void)w;
    _exit(1);
}

/* Fails the test with msg (a whole line, ending in a newline) after `seconds`. */
static inline void nbep_test_watchdog_arm(unsigned seconds, const char *msg)
{
    nbep_test_watchdog_msg = msg;
    nbep_test_watchdog_progress = NULL;
    struct sigaction sa = {0};
    sa.sa_handler = nbep_test_watchdog_fire;
    sigemptyset(&sa.sa_mask);
    assert_int_equal(sigaction(SIGALRM, &sa, NULL), 0);
    alarm(seconds);
}

/* Fails the test with msg once `progress` has not moved for `seconds`. */
static inline void nbep_test_watchdog_arm_progress(unsigned seconds, const char *msg,
                                                   const atomic_ulong *progress)
{
    nbep_test_watchdog_arm(seconds, msg);
    nbep_test_watchdog_seconds = seconds;
    nbep_test_watchdog_seen = atomic_load_explicit(progress, memory_order_relaxed);
    nbep_test_watchdog_progress = progress; /* last: the handler reads it */
}

static inline void nbep_test_watchdog_disarm(void)
{
    alarm(0);
    nbep_test_watchdog_progress = NULL;
}

#endif
