/* Cost of the seminaive pre-filter per step: one BVH build, then one query per sphere, for
 * n = 1024 .. 32768 uniform random spheres of radius 0.5 in a cube at packing fraction 0.05 (a
 * gas, as in the paper's runs). Beside it, the naive all-pairs box test the filter replaces,
 * reported as a ratio. Each size is checked first: the tree's candidate pairs must be exactly
 * the pairs whose boxes touch, counted by the all-pairs loop.
 *
 * Usage: bench_bvh [N_MAX]  (default 32768). CSV on stdout, medians of repeats, one thread. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "build_info.h"
#include "nbep/bvh.h"
#include "bench_util.h"

#define PACKING_FRACTION 0.05
#define RADIUS 0.5
/* Repeats per timing: enough for a stable median, bounded so the largest size stays quick. */
#define MAX_REPEATS 31
#define TIME_BUDGET_S 0.5

static uint64_t rng_next(uint64_t *x)
{
    uint64_t z = (*x += UINT64_C(0x9e3779b97f4a7c15));
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}

static double rng_unit(uint64_t *x)
{
    return (double)(rng_next(x) >> 11) * 0x1.0p-53;
}

typedef struct tally {
    const nbep_state *s;
    size_t i;
    uint64_t candidates, overlaps;
} tally;

static void count_pair(void *ctx, uint32_t j)
{
    tally *t = ctx;
    t->candidates++;
    nbep_vec3 dp = nbep_vec3_sub(t->s->pos[j], t->s->pos[t->i]);
    double sigma = t->s->radius[j] + t->s->radius[t->i];
    t->overlaps += nbep_vec3_dot(dp, dp) <= sigma * sigma;   /* the caller's exact test */
}

/* One step's queries; returns nodes examined, tallies candidates and overlaps. */
static uint64_t query_all(const nbep_bvh *b, const nbep_state *s, tally *t)
{
    uint64_t examined = 0;
    *t = (tally){.s = s};
    for (size_t i = 0; i < s->n; i++) {
        t->i = i;
        examined += nbep_bvh_query_later(b, s, i, count_pair, t);
    }
    return examined;
}

/* The naive filter: every later sphere's box against sphere i's. Returns the touching pairs. */
static uint64_t naive_box_pairs(const nbep_state *s)
{
    uint64_t pairs = 0;
    for (size_t i = 0; i < s->n; i++) {
        nbep_vec3 p = s->pos[i];
        double r = s->radius[i];
        for (size_t j = i + 1; j < s->n; j++) {
            nbep_vec3 q = s->pos[j];
            double rj = s->radius[j];
            pairs += p.x - r <= q.x + rj && q.x - rj <= p.x + r && p.y - r <= q.y + rj &&
                     q.y - rj <= p.y + r && p.z - r <= q.z + rj && q.z - rj <= p.z + r;
        }
    }
    return pairs;
}

int main(int argc, char **argv)
{
    size_t n_top = argc > 1 ? (size_t)strtoull(argv[1], NULL, 10) : 32768;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_state s = {0};
    nbep_bvh *b = NULL;
    int rc = 1;
    if (nbep_bvh_create(n_top, &b, &d) != NBEP_OK)
        goto done;
    printf("# bench_bvh: nbep %s, %s, 1 thread, packing fraction %g, radius %g\n", NBEP_VERSION,
           NBEP_BUILD_FLAGS, PACKING_FRACTION, RADIUS);
    printf("n,build_ms,query_ms,build_over_query,nodes_per_query,candidates_per_sphere,"
           "overlaps_per_sphere,depth,naive_ms,naive_over_bvh\n");
    for (size_t n = 1024; n <= n_top; n *= 2) {
        nbep_state_fini(&s);
        if (nbep_state_init(&s, n, 0, &d) != NBEP_OK)
            goto done;
        double sphere_volume = 4.0 / 3.0 * acos(-1.0) * RADIUS * RADIUS * RADIUS;
        double side = cbrt((double)n * sphere_volume / PACKING_FRACTION);
        uint64_t x = 20240917 + n;
        for (size_t i = 0; i < n; i++) {
            s.pos[i] = nbep_vec3_make(side * rng_unit(&x), side * rng_unit(&x),
                                      side * rng_unit(&x));
            s.radius[i] = RADIUS;
        }
        /* Check the answer before timing anything. */
        nbep_bvh_build(b, &s);
        if (nbep_bvh_check(b, &s, &d) != 0)
            goto done;
        tally t;
        uint64_t examined = query_all(b, &s, &t);
        double t0 = nbep_now();
        uint64_t want = naive_box_pairs(&s);
        double naive_once = nbep_now() - t0;
        if (t.candidates != want) {
            fprintf(stderr, "bench_bvh: n = %zu: %llu candidate pairs, all-pairs finds %llu\n", n,
                    (unsigned long long)t.candidates, (unsigned long long)want);
            goto done;
        }
        double build[MAX_REPEATS], queries[MAX_REPEATS], naive[MAX_REPEATS];
        int reps = 0;
        for (double start = nbep_now(); reps < MAX_REPEATS && (reps < 5 || nbep_now() - start <
                                                                            TIME_BUDGET_S);
             reps++) {
            t0 = nbep_now();
            nbep_bvh_build(b, &s);
            double t1 = nbep_now();
            query_all(b, &s, &t);
            build[reps] = t1 - t0;
            queries[reps] = nbep_now() - t1;
        }
        /* The all-pairs loop is slow at large n: as many repeats as the budget allows. */
        int reps_naive = 1;
        naive[0] = naive_once;
        for (double start = nbep_now(); reps_naive < MAX_REPEATS && nbep_now() - start < TIME_BUDGET_S;
             reps_naive++) {
            t0 = nbep_now();
            if (naive_box_pairs(&s) != want)
                goto done;
            naive[reps_naive] = nbep_now() - t0;
        }
        double build_ms = 1e3 * bench_median(build, reps), query_ms = 1e3 * bench_median(queries, reps);
        double naive_ms = 1e3 * bench_median(naive, reps_naive);
        printf("%zu,%.4g,%.4g,%.3f,%.1f,%.3f,%.3f,%zu,%.4g,%.1f\n", n, build_ms, query_ms,
               build_ms / query_ms, (double)examined / (double)n,
               (double)t.candidates / (double)n, (double)t.overlaps / (double)n,
               nbep_bvh_depth(b), naive_ms, naive_ms / (build_ms + query_ms));
        fflush(stdout);
    }
    rc = 0;
done:
    if (rc != 0)
        nbep_diag_print(&d, stderr);
    nbep_bvh_destroy(&b);
    nbep_state_fini(&s);
    nbep_diag_fini(&d);
    return rc;
}
