/* Helpers shared by the CMocka tests. Include after <cmocka.h>. */
#ifndef NBEP_TEST_H
#define NBEP_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* |actual - expected| <= atol + rtol |expected|, compared in double (cmocka 1.1's
 * assert_float_equal compares as float). */
#define assert_close(actual, expected, rtol, atol)                                           \
    do {                                                                                     \
        double a_ = (double)(actual), e_ = (double)(expected);                               \
        double tol_ = (double)(atol) + (double)(rtol) * fabs(e_);                            \
        if (!(fabs(a_ - e_) <= tol_))                                                        \
            fail_msg("%s = %.17g, expected %.17g (tolerance %.3g)", #actual, a_, e_, tol_); \
    } while (0)

/* A path under the build's scratch folder for one test's files, e.g. build/tests/tmp/NAME. */
static inline const char *nbep_test_tmp(const char *name, char *buf, size_t len)
{
    snprintf(buf, len, "build/tests/tmp/%s", name);
    return buf;
}

#endif
