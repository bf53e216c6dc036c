/* Helpers shared by the benchmark harnesses (built by `make bench` only). */
#ifndef NBEP_BENCH_UTIL_H
#define NBEP_BENCH_UTIL_H

#include <stdlib.h>

/* qsort order for doubles (NaN-free). */
static inline int bench_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median of v[0..n) (sorts v). */
static inline double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, bench_cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

#endif
