/* The record of the terms added to a thread's sums while the scheduled loop runs
 * (nbep__pred_sum_add, nbep__pred_sums_back in src/pred_impl.h): a rollback takes the terms of
 * its undone events out again, and each sum must then be what it was before them, bit for bit:
 * its value and every later sum made from it (a term handled again is added again). Finite
 * terms go by their negations (the sums are exact, xsum.h), infinite and NaN ones (summed
 * apart, as a double: inf - inf would leave NaN) by the sum's special part put back. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pred_impl.h"
#include "nbep_test.h"

static uint64_t rng = 0x243F6A8885A308D3u;
static uint64_t next_u64(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

/* a finite double of any size and sign: subnormals, the largest, round numbers and noise */
static double any_term(void)
{
    const uint64_t r = next_u64();
    switch (r % 6) {
    case 0:
        return ldexp((double)(r >> 11) / 9007199254740992.0, (int)(r % 2098) - 1074);
    case 1:
        return (r & 64 ? -1.0 : 1.0) * DBL_MIN * (double)(r % 1000) * DBL_EPSILON;
    case 2:
        return (r & 64 ? -1.0 : 1.0) * DBL_MAX * ((double)(r % 997) / 1000.0);
    case 3:
        return (double)((int64_t)(r % 2001) - 1000) / 8.0;
    default: {
        double x;
        uint64_t b = r & ~(UINT64_C(0x7ff) << 52);
        b |= (uint64_t)((r >> 40) % 0x7ff) << 52; /* any exponent but inf/NaN's */
        memcpy(&x, &b, sizeof x);
        return x;
    }
    }
}

/* a and b the same sum: the same value now, and after the same further terms */
static void same_sum(nbep_xsum a, nbep_xsum b)
{
    const double va = nbep_xsum_value(&a), vb = nbep_xsum_value(&b);
    assert_memory_equal(&va, &vb, sizeof va);
    for (int k = 0; k < 8; k++) {
        const double x = any_term();
        nbep_xsum_add(&a, x);
        nbep_xsum_add(&b, x);
        const double wa = nbep_xsum_value(&a), wb = nbep_xsum_value(&b);
        assert_memory_equal(&wa, &wb, sizeof wa);
    }
}

static void test_finite_terms_taken_back_leave_the_sums_as_before(void **state)
{
    (void)state;
    nbep_sum_journal j = {0};
    nbep_thread_max mx = {.jr = &j};
    for (int trial = 0; trial < 2000; trial++) {
        nbep_xsum s[2] = {{.adds = 0}, {.adds = 0}}, before[2];
        for (int k = 0; k < (int)(next_u64() % 20); k++) /* (what stood before: not recorded) */
            nbep_xsum_add(&s[next_u64() & 1], any_term());
        memcpy(before, s, sizeof s);
        const size_t to = j.n;
        const int m = 1 + (int)(next_u64() % 12);
        for (int k = 0; k < m; k++)
            nbep__pred_sum_add(&mx, &s[next_u64() & 1], any_term());
        assert_int_equal(j.n, to + (size_t)m);
        nbep__pred_sums_back(&j, to);
        assert_int_equal(j.n, to);
        same_sum(s[0], before[0]);
        same_sum(s[1], before[1]);
    }
    free(j.term);
}

static void test_an_infinity_or_nan_taken_back_leaves_the_sum_as_before(void **state)
{
    (void)state;
    const double special[] = {INFINITY, -INFINITY, NAN};
    for (int had = 0; had < 4; had++) /* the sum's special part before: none, or one of three */
        for (int q = 0; q < 3; q++) {
            nbep_sum_journal j = {0};
            nbep_thread_max mx = {.jr = &j};
            nbep_xsum s = {.adds = 0};
            nbep_xsum_add(&s, 1.5);
            if (had)
                nbep_xsum_add(&s, special[had - 1]);
            const nbep_xsum before = s;
            nbep__pred_sum_add(&mx, &s, 2.0);
            nbep__pred_sum_add(&mx, &s, special[q]);
            nbep__pred_sum_add(&mx, &s, -special[q]); /* (inf - inf: NaN, summed apart) */
            nbep__pred_sums_back(&j, 0);
            assert_memory_equal(&s.special, &before.special, sizeof s.special);
            same_sum(s, before);
            free(j.term);
        }
}

static void test_no_journal_records_nothing(void **state)
{
    (void)state;
    nbep_thread_max mx = {.jr = NULL};
    nbep_xsum s = {.adds = 0}, t = {.adds = 0};
    nbep__pred_sum_add(&mx, &s, 0.25);
    nbep_xsum_add(&t, 0.25);
    same_sum(s, t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_finite_terms_taken_back_leave_the_sums_as_before),
        cmocka_unit_test(test_an_infinity_or_nan_taken_back_leaves_the_sum_as_before),
        cmocka_unit_test(test_no_journal_records_nothing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
