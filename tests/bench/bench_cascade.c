/* Cost of the cascade stamps (src/cascade.c): what the engine would add to each prediction
 * (a stamp made from its maker's) and the scheduler to each comparison, against the same loop
 * without them (a random number and a sum: what every pass does). Three passes: stamps made at
 * a later time than their maker (roots: nearly every entry of a fluid), made at the same time
 * (children and siblings in a cascade of depth 1 to 4), and compared (two roots, then their
 * order). Prints '#' lines, then CSV: the pass, ns a stamp over the bare loop (median over
 * repeats), and the range.
 *
 *   bench_cascade [stamps [repeats]]     defaults: 20000000 and 5 */
#include "nbep/cascade.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "bench_util.h"
#include "build_info.h"

enum { MAX_REPEATS = 101, PASSES = 4 };

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static uint64_t next(uint64_t *x)
{
    *x ^= *x << 13, *x ^= *x >> 7, *x ^= *x << 17;
    return *x;
}

/* Pass p over n stamps: seconds; *sink keeps the results alive. */
static double pass(int p, unsigned long n, double *sink)
{
    uint64_t x = 0x9E3779B97F4A7C15u;
    nbep_cascade c[4];
    c[0] = nbep_cascade_root(1.0, 1ull << 40, 3);
    for (int d = 1; d < 4; d++) /* a path of depth 4: keys falling */
        if (!nbep_cascade_made(&c[d - 1], 1.0, (1ull << 40) >> d, 3, &c[d]))
            abort();
    double s = 0.0;
    const double t0 = now();
    for (unsigned long k = 0; k < n; k++) {
        const uint64_t r = next(&x);
        nbep_cascade out;
        switch (p) {
        case 0: /* the bare loop */
            s += (double)(r & 1023);
            break;
        case 1: /* a root: an entry at a later time */
            (void)nbep_cascade_made(&c[r & 3], 1.0 + (double)(r & 1023) * 1e-3 + 1e-3, r >> 24,
                                    (uint32_t)r, &out);
            s += out.t;
            break;
        case 2: /* at the maker's time: a child or a sibling somewhere on the path */
            if (nbep_cascade_made(&c[r & 3], 1.0, (r >> 20) & ((1ull << 42) - 1), (uint32_t)r,
                                  &out))
                s += (double)out.depth;
            break;
        default: { /* two roots made and compared */
            const nbep_cascade a = nbep_cascade_root(1.0, r >> 40, 1);
            const nbep_cascade b = nbep_cascade_root(1.0, r & 0xffffff, 2);
            s += nbep_cascade_cmp(&a, &b);
        }
        }
    }
    const double t1 = now();
    *sink += s;
    return t1 - t0;
}

int main(int argc, char **argv)
{
    const unsigned long stamps = argc > 1 ? strtoul(argv[1], NULL, 10) : 20000000ul;
    const int repeats = argc > 2 ? atoi(argv[2]) : 5;
    if (stamps < 1 || repeats < 1 || repeats > MAX_REPEATS) {
        fprintf(stderr, "usage: bench_cascade [stamps (>= 1) [repeats (1 to %d)]]\n",
                MAX_REPEATS);
        return 2;
    }
    printf("# bench_cascade: nbep %s (%s), %s; %d levels a stamp, %zu bytes\n", NBEP_VERSION,
           NBEP_BUILD_COMMIT, NBEP_BUILD_FLAGS, NBEP_CASCADE_DEPTH, sizeof(nbep_cascade));
    printf("pass,ns_per_stamp,ns_min,ns_max\n");
    static const char *const names[PASSES] = {"bare loop", "made: a root", "made: in a cascade",
                                              "two roots and their order"};
    double t[PASSES][MAX_REPEATS], sink = 0.0;
    for (int r = 0; r < repeats; r++) /* interleaved: a slow spell falls on every pass */
        for (int p = 0; p < PASSES; p++)
            t[p][r] = pass(p, stamps, &sink) / (double)stamps * 1e9;
    double bare = bench_median(t[0], repeats);
    for (int p = 0; p < PASSES; p++) {
        const double med = bench_median(t[p], repeats); /* sorted now */
        const double less = p == 0 ? 0.0 : bare;
        printf("%s,%.2f,%.2f,%.2f\n", names[p], med - less, t[p][0] - less,
               t[p][repeats - 1] - less);
    }
    printf("# the bare loop's line is its own cost, the others' over it; checksum %g\n", sink);
    return 0;
}
