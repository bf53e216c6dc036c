/* Tests of the exact sums (xsum.h): cases whose exact sum is known by construction (a
 * cancellation that plain addition loses, ties and the sticky bit of the last rounding,
 * subnormals, a sum past the largest double and back), sums in every order and split among
 * accumulators equal bit for bit, the passing of carries (a sum merged into itself until it
 * passes them many times), and random sums against an independent correctly rounded sum
 * (Shewchuk's partials with the final rounding of Python's math.fsum, written out below). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/xsum.h"
#include "nbep_test.h"

static double sum_of(const double *x, size_t n)
{
    nbep_xsum s = {0};
    for (size_t k = 0; k < n; k++)
        nbep_xsum_add(&s, x[k]);
    return nbep_xsum_value(&s);
}

/* doubles equal bit for bit (so +0 and -0 differ, and NaN equals NaN) */
static void assert_same(double a, double b)
{
    uint64_t ua, ub;
    memcpy(&ua, &a, sizeof ua);
    memcpy(&ub, &b, sizeof ub);
    if (ua != ub)
        fail_msg("%.17g (%016llx) != %.17g (%016llx)", a, (unsigned long long)ua, b,
                 (unsigned long long)ub);
}

static uint64_t rng_next(uint64_t *st)
{
    uint64_t x = *st; /* xorshift64* */
    x ^= x >> 12;
    x ^= x << 25;
    x ^= x >> 27;
    *st = x;
    return x * UINT64_C(2685821657736338717);
}

/* A random double of either sign, mantissa uniform, exponent uniform in [-e_span, e_span]. */
static double rng_double(uint64_t *st, int e_span)
{
    const double m = (double)(rng_next(st) >> 11) / 9007199254740992.0; /* [0, 1) */
    const int e = (int)(rng_next(st) % (uint64_t)(2 * e_span + 1)) - e_span;
    const double x = ldexp(0.5 + 0.5 * m, e);
    return rng_next(st) & 1 ? -x : x;
}

/* The correctly rounded sum by Shewchuk's exact partials (no two overlap) and the rounding of
 * Python's math.fsum, which adds them from the largest and corrects a half-way case that the
 * next partial breaks. Terms here stay far enough below DBL_MAX that no partial overflows. */
static double fsum_reference(const double *x, size_t n)
{
    double *p = malloc((n + 1) * sizeof *p);
    assert_non_null(p);
    size_t np = 0;
    for (size_t k = 0; k < n; k++) {
        double v = x[k];
        size_t i = 0;
        for (size_t j = 0; j < np; j++) {
            double y = p[j];
            if (fabs(v) < fabs(y)) {
                const double t = v;
                v = y;
                y = t;
            }
            const double hi = v + y, lo = y - (hi - v);
            if (lo != 0.0)
                p[i++] = lo;
            v = hi;
        }
        p[i] = v;
        np = i + 1;
    }
    double hi = 0.0;
    if (np > 0) {
        size_t m = np - 1;
        hi = p[m];
        double lo = 0.0;
        while (m > 0) {
            const double v = hi, y = p[--m];
            hi = v + y;
            lo = y - (hi - v);
            if (lo != 0.0)
                break;
        }
        if (m > 0 && ((lo < 0.0 && p[m - 1] < 0.0) || (lo > 0.0 && p[m - 1] > 0.0))) {
            const double y = lo * 2.0, v = hi + y;
            if (y == v - hi)
                hi = v;
        }
    }
    free(p);
    return hi;
}

static void test_a_cancellation_that_plain_addition_loses_is_exact(void **state)
{
    (void)state;
    const double x[] = {1e100, 1.0, -1e100};
    assert_same(x[0] + x[1] + x[2], 0.0); /* what the sums did before */
    assert_same(sum_of(x, 3), 1.0);
    const double y[] = {1.0, 1e-300, -1.0, 1e-300};
    assert_same(sum_of(y, 4), 2e-300);
    const double z[] = {0.1, 0.2, -0.3};
    /* the exact sum of the three doubles (they are not 0.1, 0.2, 0.3): what fsum says */
    assert_same(sum_of(z, 3), fsum_reference(z, 3));
    assert_true(sum_of(z, 3) != 0.0);
}

static void test_the_last_rounding_is_to_nearest_with_ties_to_even(void **state)
{
    (void)state;
    const double two53 = 9007199254740992.0; /* 2^53: the ulp is 2 above it */
    const double tie_down[] = {two53, 1.0};  /* 2^53 + 1: a tie, to the even 2^53 */
    assert_same(sum_of(tie_down, 2), two53);
    const double tie_up[] = {two53 + 2.0, 1.0}; /* 2^53 + 3: a tie, to the even 2^53 + 4 */
    assert_same(sum_of(tie_up, 2), two53 + 4.0);
    /* 2^53 + 1 + 2^-1000: past the tie by a bit far below the kept ones (the sticky bit) */
    const double sticky[] = {two53, 1.0, ldexp(1.0, -1000)};
    assert_same(sum_of(sticky, 3), two53 + 2.0);
    const double sticky_neg[] = {-two53, -1.0, -ldexp(1.0, -1000)};
    assert_same(sum_of(sticky_neg, 3), -(two53 + 2.0));
    /* 2^53 + 1 - 2^-1000: just below the tie */
    const double below[] = {two53, 1.0, -ldexp(1.0, -1000)};
    assert_same(sum_of(below, 3), two53);
}

static void test_subnormals_zeros_and_the_largest_doubles_are_exact(void **state)
{
    (void)state;
    const double tiny = ldexp(1.0, -1074);
    const double t3[] = {tiny, tiny, tiny};
    assert_same(sum_of(t3, 3), 3.0 * tiny);
    const double t3_neg[] = {-tiny, -tiny, -tiny}; /* a negative sum to its last unit */
    assert_same(sum_of(t3_neg, 3), -3.0 * tiny);
    const double edge[] = {DBL_MIN, -tiny}; /* the largest subnormal */
    assert_same(sum_of(edge, 2), DBL_MIN - tiny);
    const double zeros[] = {0.0, -0.0, 0.0};
    assert_same(sum_of(zeros, 3), 0.0);
    assert_same(sum_of(NULL, 0), 0.0);
    /* past the largest double and back: exact in between */
    const double big[] = {DBL_MAX, DBL_MAX, -DBL_MAX};
    assert_same(sum_of(big, 3), DBL_MAX);
    const double over[] = {DBL_MAX, DBL_MAX};
    assert_same(sum_of(over, 2), HUGE_VAL);
    const double under[] = {-DBL_MAX, -DBL_MAX};
    assert_same(sum_of(under, 2), -HUGE_VAL);
    /* DBL_MAX plus half its ulp: a tie, to the even DBL_MAX (the rounding, not overflow) */
    const double half_ulp[] = {DBL_MAX, ldexp(1.0, 970)};
    assert_same(sum_of(half_ulp, 2), HUGE_VAL);
    const double less[] = {DBL_MAX, ldexp(1.0, 969)};
    assert_same(sum_of(less, 2), DBL_MAX);
}

static void test_infinities_and_nan_are_the_sum(void **state)
{
    (void)state;
    const double inf[] = {1.0, HUGE_VAL, -5.0};
    assert_same(sum_of(inf, 3), HUGE_VAL);
    const double both[] = {HUGE_VAL, 1.0, -HUGE_VAL};
    assert_true(isnan(sum_of(both, 3)));
    const double nan[] = {1.0, NAN};
    assert_true(isnan(sum_of(nan, 2)));
}

static void test_every_order_and_split_gives_the_same_bits(void **state)
{
    (void)state;
    enum { N = 4000 };
    double *x = malloc(N * sizeof *x);
    assert_non_null(x);
    uint64_t st = 0x9e3779b97f4a7c15u;
    for (int trial = 0; trial < 20; trial++) {
        const int span = trial % 2 ? 60 : 1000;
        for (size_t k = 0; k < N; k++)
            x[k] = rng_double(&st, span);
        const double forward = sum_of(x, N);
        assert_same(forward, fsum_reference(x, N));
        /* reversed */
        nbep_xsum r = {0};
        for (size_t k = N; k-- > 0;)
            nbep_xsum_add(&r, x[k]);
        assert_same(nbep_xsum_value(&r), forward);
        /* dealt to 7 accumulators by a random choice, merged in a random order of 3 */
        nbep_xsum part[7];
        memset(part, 0, sizeof part); /* zero bytes: the empty sum */
        for (size_t k = 0; k < N; k++)
            nbep_xsum_add(&part[rng_next(&st) % 7], x[k]);
        nbep_xsum all = {0};
        const int order[3][7] = {{0, 1, 2, 3, 4, 5, 6}, {6, 5, 4, 3, 2, 1, 0}, {3, 0, 6, 1, 5, 2, 4}};
        const int o = (int)(rng_next(&st) % 3);
        for (int p = 0; p < 7; p++)
            nbep_xsum_merge(&all, &part[order[o][p]]);
        assert_same(nbep_xsum_value(&all), forward);
        /* cleared and used again: as new */
        nbep_xsum_clear(&all);
        nbep_xsum_add(&all, x[0]);
        assert_same(nbep_xsum_value(&all), x[0]);
    }
    free(x);
}

/* Sums of many terms: merging a sum into itself doubles it and its count of terms, so 60
 * doublings pass the carries on many times (a term count far past 2^31). */
static void test_carries_are_passed_on_without_loss(void **state)
{
    (void)state;
    uint64_t st = 12345;
    for (int trial = 0; trial < 50; trial++) {
        double x[5];
        for (int k = 0; k < 5; k++)
            x[k] = rng_double(&st, 400);
        nbep_xsum s = {0};
        for (int k = 0; k < 5; k++)
            nbep_xsum_add(&s, x[k]);
        const double one = nbep_xsum_value(&s);
        for (int d = 0; d < 60; d++) {
            nbep_xsum copy = s;
            nbep_xsum_merge(&s, &copy);
            nbep_xsum_add(&s, 0.0); /* a zero term changes nothing */
        }
        assert_same(nbep_xsum_value(&s), ldexp(one, 60));
        /* and back to zero: each term times 2^60 taken away */
        for (int k = 0; k < 5; k++)
            nbep_xsum_add(&s, -ldexp(x[k], 60));
        assert_same(nbep_xsum_value(&s), 0.0);
    }
}

/* The sticky bit reaches the lowest limb: 2^53 + 1 + 2^-1074 is past the tie by the least
 * subnormal alone, so it rounds up to 2^53 + 2 (and its negative down), not to the even 2^53. */
static void test_the_sticky_bit_sees_the_least_subnormal(void **state)
{
    (void)state;
    const double two53 = 9007199254740992.0, tiny = ldexp(1.0, -1074);
    const double up[] = {two53, 1.0, tiny};
    assert_same(sum_of(up, 3), two53 + 2.0);
    const double down[] = {-two53, -1.0, -tiny};
    assert_same(sum_of(down, 3), -(two53 + 2.0));
    /* and a term that cancels it is gone from the sticky bit too */
    const double gone[] = {two53, 1.0, tiny, -tiny};
    assert_same(sum_of(gone, 4), two53);
}

/* A sum cleared and used again is the empty sum whatever it held: its highest limb and its
 * infinities too. Each term x then x and -x again over the limbs it wrote before: 1 exactly;
 * after an infinity, 2. */
static void test_a_cleared_sum_keeps_nothing_of_what_it_held(void **state)
{
    (void)state;
    uint64_t st = 777;
    for (int trial = 0; trial < 200; trial++) {
        const double x = rng_double(&st, 1000);
        nbep_xsum s = {0};
        nbep_xsum_add(&s, x);
        nbep_xsum_add(&s, 3.0 * x);
        nbep_xsum_clear(&s);
        assert_same(nbep_xsum_value(&s), 0.0);
        nbep_xsum_add(&s, 1.0);
        nbep_xsum_add(&s, x);
        nbep_xsum_add(&s, -x);
        assert_same(nbep_xsum_value(&s), 1.0);
    }
    nbep_xsum s = {0};
    nbep_xsum_add(&s, HUGE_VAL);
    nbep_xsum_add(&s, 1.0);
    nbep_xsum_clear(&s);
    nbep_xsum_add(&s, 2.0);
    assert_same(nbep_xsum_value(&s), 2.0);
    nbep_xsum_add(&s, NAN);
    nbep_xsum_clear(&s);
    assert_same(nbep_xsum_value(&s), 0.0);
}

/* A thread's part that met an infinity or NaN passes it on when merged, also a part that holds
 * nothing else (no limb written) and into a sum that holds nothing. */
static void test_a_merged_infinity_or_nan_is_the_sum(void **state)
{
    (void)state;
    nbep_xsum a = {0}, b = {0}, e = {0};
    nbep_xsum_add(&a, 1.0);
    nbep_xsum_add(&b, -HUGE_VAL);
    nbep_xsum_merge(&a, &b);
    assert_same(nbep_xsum_value(&a), -HUGE_VAL);
    nbep_xsum_merge(&e, &b); /* nothing into nothing but the infinity */
    assert_same(nbep_xsum_value(&e), -HUGE_VAL);
    nbep_xsum c = {0};
    nbep_xsum_add(&c, 2.0);
    nbep_xsum_add(&c, HUGE_VAL);
    nbep_xsum_merge(&a, &c); /* -inf + inf */
    assert_true(isnan(nbep_xsum_value(&a)));
    nbep_xsum n = {0}, m = {0};
    nbep_xsum_add(&n, NAN);
    nbep_xsum_add(&m, 5.0);
    nbep_xsum_merge(&m, &n);
    assert_true(isnan(nbep_xsum_value(&m)));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_cancellation_that_plain_addition_loses_is_exact),
        cmocka_unit_test(test_the_last_rounding_is_to_nearest_with_ties_to_even),
        cmocka_unit_test(test_subnormals_zeros_and_the_largest_doubles_are_exact),
        cmocka_unit_test(test_infinities_and_nan_are_the_sum),
        cmocka_unit_test(test_every_order_and_split_gives_the_same_bits),
        cmocka_unit_test(test_carries_are_passed_on_without_loss),
        cmocka_unit_test(test_the_sticky_bit_sees_the_least_subnormal),
        cmocka_unit_test(test_a_cleared_sum_keeps_nothing_of_what_it_held),
        cmocka_unit_test(test_a_merged_infinity_or_nan_is_the_sum),
    };
    return cmocka_run_group_tests_name("xsum", tests, NULL, NULL);
}
