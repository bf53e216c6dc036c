/* A deadlock watchdog for tests of code that has no way out of a wait (the barrier): an alarm
 * that, if it goes off, prints why the test failed and exits 1, so that a hang is a failure
 * that says so rather than a wait for scripts/run-tests.sh's time limit. One at a time. Include
 * after <cmocka.h>. */
#ifndef NBEP_TEST_WATCHDOG_H
#define NBEP_TEST_WATCHDOG_H

#include <signal.h>
#include <string.h>
#include <unistd.h>

static const char *nbep_test_watchdog_msg;

static void nbep_test_watchdog_fire(int sig)
{
    (void)sig;
    /* write and strlen are async-signal-safe; the message was set before the alarm */
    ssize_t w = write(STDERR_FILENO, nbep_test_watchdog_msg, strlen(nbep_test_watchdog_msg));
    (void)w;
    _exit(1);
}

/* Fails the test with msg (a whole line, ending in a newline) after `seconds`. */
static inline void nbep_test_watchdog_arm(unsigned seconds, const char *msg)
{
    nbep_test_watchdog_msg = msg;
    struct sigaction sa = {0};
    sa.sa_handler = nbep_test_watchdog_fire;
    sigemptyset(&sa.sa_mask);
    assert_int_equal(sigaction(SIGALRM, &sa, NULL), 0);
    alarm(seconds);
}

static inline void nbep_test_watchdog_disarm(void)
{
    alarm(0);
}

#endif
