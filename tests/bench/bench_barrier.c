/* Cost of one crossing of nbep_barrier against `#pragma omp barrier`, both inside one
 * `omp parallel` region (as in a run: one region, barriers between sub-phases), for 1, 2 and 4
 * threads. Prints '#' lines with the build and settings, then CSV, one line per thread count:
 * the median over repeats of ns per crossing for each barrier and their ratio.
 *
 *   bench_barrier [crossings [repeats]]     defaults: 1000000 and 5
 *
 * With more threads than processors every crossing waits for the scheduler, so those counts
 * time crossings / OVERSUBSCRIBED_DIVISOR (the crossings column says how many). Before timing,
 * each thread count checks that the barrier really holds everyone (see check_barrier). */
#include "nbep/barrier.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "build_info.h"

#ifdef _OPENMP
#include <omp.h>
#include "bench_util.h"

#define MAX_REPEATS 101
/* An oversubscribed crossing costs tens of microseconds (one scheduler pass per waiter), about
 * 100 times a crossing on free cores: time that many fewer to keep the run to seconds. */
#define OVERSUBSCRIBED_DIVISOR 100ul
/* Rounds of the correctness check before timing. */
#define CHECK_ROUNDS 2000ul

/* The answer first: each round every thread adds 1 to a counter, crosses, and must then see
 * exactly nt * round; a second crossing keeps the next round's adds out of this round's
 * reads. Returns the number of wrong reads (0 when the barrier holds). Relaxed atomics: the
 * barrier alone must order them. */
static unsigned long check_barrier(int nt)
{
    nbep_barrier bar;
    nbep_barrier_init(&bar, (unsigned)nt);
    atomic_ulong sum, wrong;
    atomic_init(&sum, 0ul);
    atomic_init(&wrong, 0ul);
#pragma omp parallel num_threads(nt) default(none) shared(bar, sum, wrong, nt)
    {
        for (unsigned long r = 1; r <= CHECK_ROUNDS; r++) {
            atomic_fetch_add_explicit(&sum, 1, memory_order_relaxed);
            nbep_barrier_wait(&bar);
            if (atomic_load_explicit(&sum, memory_order_relaxed) != (unsigned long)nt * r)
                atomic_fetch_add_explicit(&wrong, 1, memory_order_relaxed);
            nbep_barrier_wait(&bar);
        }
    }
    return atomic_load_explicit(&wrong, memory_order_relaxed);
}

/* Times `crossings` crossings of each barrier per repeat; per-crossing ns into ours/theirs.
 * Thread 0 reads the clock just after leaving the first and the last crossing's barrier. */
static void time_barriers(int nt, unsigned long crossings, int repeats, double *ours,
                          double *theirs)
{
    nbep_barrier bar;
    nbep_barrier_init(&bar, (unsigned)nt);
#pragma omp parallel num_threads(nt) default(none) shared(bar, nt, crossings, repeats, ours, theirs)
    {
        const int tid = omp_get_thread_num();
        for (int rep = 0; rep < repeats; rep++) {
            double t0 = 0.0;
#pragma omp barrier
            if (tid == 0)
                t0 = nbep_now();
            for (unsigned long i = 0; i < crossings; i++)
                nbep_barrier_wait(&bar);
            if (tid == 0)
                ours[rep] = 1e9 * (nbep_now() - t0) / (double)crossings;
#pragma omp barrier
            if (tid == 0)
                t0 = nbep_now();
            for (unsigned long i = 0; i < crossings; i++) {
#pragma omp barrier
            }
            if (tid == 0)
                theirs[rep] = 1e9 * (nbep_now() - t0) / (double)crossings;
        }
    }
}

static int parse_count(const char *s, unsigned long lo, unsigned long hi, unsigned long *out)
{
    char *end;
    unsigned long v = strtoul(s, &end, 10);
    if (*s == '\0' || *end != '\0' || v < lo || v > hi)
        return -1;
    *out = v;
    return 0;
}

int main(int argc, char **argv)
{
    unsigned long crossings = 1000000, repeats = 5;
    if (argc > 3 || (argc > 1 && parse_count(argv[1], 1, 1000000000ul, &crossings)) ||
        (argc > 2 && parse_count(argv[2], 1, MAX_REPEATS, &repeats))) {
        fprintf(stderr, "usage: %s [crossings (1..1e9) [repeats (1..%d)]]\n", argv[0],
                MAX_REPEATS);
        return 2;
    }
    const int procs = omp_get_num_procs();
    const char *wait_policy = getenv("OMP_WAIT_POLICY");
    printf("# bench_barrier nbep %s (%s) %s\n", NBEP_VERSION, NBEP_BUILD_COMMIT,
           NBEP_BUILD_FLAGS);
    printf("# processors %d, OMP_WAIT_POLICY=%s, repeats %lu, median ns per crossing\n", procs,
           wait_policy ? wait_policy : "(unset)", repeats);
    printf("threads,crossings,nbep_ns,omp_ns,nbep_over_omp\n");

    const int thread_counts[] = {1, 2, 4};
    for (size_t c = 0; c < sizeof thread_counts / sizeof thread_counts[0]; c++) {
        const int nt = thread_counts[c];
        unsigned long wrong = check_barrier(nt);
        if (wrong != 0) {
            fprintf(stderr, "bench_barrier: %d threads: the barrier let %lu stale reads through\n",
                    nt, wrong);
            return 1;
        }
        unsigned long n = crossings;
        if (nt > procs)
            n = n / OVERSUBSCRIBED_DIVISOR ? n / OVERSUBSCRIBED_DIVISOR : 1;
        double ours[MAX_REPEATS], theirs[MAX_REPEATS];
        time_barriers(nt, n, (int)repeats, ours, theirs);
        double m_ours = bench_median(ours, (int)repeats), m_theirs = bench_median(theirs, (int)repeats);
        printf("%d,%lu,%.1f,%.1f,%.3f\n", nt, n, m_ours, m_theirs, m_ours / m_theirs);
        fflush(stdout);
    }
    return 0;
}

#else

int main(void)
{
    fprintf(stderr, "bench_barrier: built without OpenMP (OMP=0); nothing to compare\n");
    return 0;
}

#endif
