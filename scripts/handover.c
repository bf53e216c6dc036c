/* How long a cache line takes to pass between the two cores that a 2-thread run uses: two
 * threads, pinned to the first two CPUs this process may run on (or to CPUs A and B), hand a
 * counter back and forth (each waits for the other's number, then writes the next). Prints the
 * median over `chunks` stretches of 100000 hand-overs of the nanoseconds one hand-over takes.
 * With --from A, one line "A B ns" for every other CPU B this process may run on: the CPUs
 * whose hand-over is short share a cache with A, and a team pinned there pays off best (README:
 * Running on a cluster).
 *
 *   cc -O2 -pthread scripts/handover.c -o handover
 *   ./handover [chunks]          the first two CPUs
 *   ./handover chunks A B        CPUs A and B
 *   ./handover --from A [chunks] A and each other CPU
 *
 * Used by scripts/bench-dense.sh beside each multi-thread run: the team loop passes a few
 * lines between its two threads for each event (README: Threads on dense scenes), so its speed
 * follows this figure. On this project's 2-core virtual machine it was 25 to 31 ns most of the
 * time and 155 to 170 ns in stretches of minutes (the two virtual CPUs then sat on cores that
 * share no cache), with nothing else running. Not part of nbep. */
#define _GNU_SOURCE
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PER_CHUNK 100000L
#define CHUNKS_MAX 64

static _Alignas(64) _Atomic long counter;
static long total;
static int cpus[2];
static cpu_set_t mine; /* the CPUs this process may run on */

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int pin(int cpu)
{
    cpu_set_t s;
    CPU_ZERO(&s);
    CPU_SET(cpu, &s);
    return pthread_setaffinity_np(pthread_self(), sizeof s, &s);
}

/* Hands over the odd numbers: waits for each, writes the next. */
static void *answer(void *arg)
{
    (void)arg;
    (void)pin(cpus[1]); /* unpinned, it still answers: no hang where pinning fails */
    for (long i = 1; i < total; i += 2) {
        while (atomic_load_explicit(&counter, memory_order_acquire) != i)
            ;
        atomic_store_explicit(&counter, i + 1, memory_order_release);
    }
    return NULL;
}

static int cmp(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median ns of one hand-over between cpus[0] and cpus[1]; < 0 when a thread cannot run. */
static double measure(int chunks)
{
    atomic_store(&counter, 0);
    total = chunks * PER_CHUNK;
    if (pin(cpus[0]) != 0)
        return -1.0;
    pthread_t t;
    if (pthread_create(&t, NULL, answer, NULL) != 0)
        return -1.0;
    double ns[CHUNKS_MAX] = {0};
    for (int k = 0; k < chunks; k++) { /* the even numbers, timed a chunk at a time */
        const double t0 = now();
        for (long i = k * PER_CHUNK; i < (k + 1) * PER_CHUNK; i += 2) {
            while (atomic_load_explicit(&counter, memory_order_acquire) != i)
                ;
            atomic_store_explicit(&counter, i + 1, memory_order_release);
        }
        ns[k] = (now() - t0) * 1e9 / PER_CHUNK;
    }
    pthread_join(t, NULL);
    qsort(ns, (size_t)chunks, sizeof ns[0], cmp);
    return ns[chunks / 2];
}

static int usage(void)
{
    fprintf(stderr, "usage: handover [chunks [A B]] | handover --from A [chunks]\n");
    return 2;
}

/* A CPU number this process may run on, or -1. */
static int cpu_arg(const char *a)
{
    char *end;
    const long c = strtol(a, &end, 10);
    return *end || c < 0 || c >= CPU_SETSIZE || !CPU_ISSET((int)c, &mine) ? -1 : (int)c;
}

int main(int argc, char **argv)
{
    if (sched_getaffinity(0, sizeof mine, &mine) != 0 || CPU_COUNT(&mine) < 2) {
        fprintf(stderr, "handover: needs two CPUs\n");
        return 2;
    }
    const bool from = argc > 1 && strcmp(argv[1], "--from") == 0;
    const char *chunks_arg = from ? (argc > 3 ? argv[3] : NULL) : (argc > 1 ? argv[1] : NULL);
    const int chunks = chunks_arg ? atoi(chunks_arg) : 5;
    if (chunks < 1 || chunks > CHUNKS_MAX) {
        fprintf(stderr, "handover: chunks must be 1 to %d\n", CHUNKS_MAX);
        return 2;
    }
    if (from) {
        if (argc < 3 || argc > 4 || (cpus[0] = cpu_arg(argv[2])) < 0)
            return usage();
        const int a = cpus[0];
        for (int b = 0; b < CPU_SETSIZE; b++) {
            if (b == a || !CPU_ISSET(b, &mine))
                continue;
            cpus[0] = a;
            cpus[1] = b;
            const double ns = measure(chunks);
            if (ns < 0)
                return fprintf(stderr, "handover: cannot run on CPUs %d and %d\n", a, b), 1;
            printf("%d %d %.1f\n", a, b, ns);
            fflush(stdout);
        }
        return 0;
    }
    if (argc == 4) {
        if ((cpus[0] = cpu_arg(argv[2])) < 0 || (cpus[1] = cpu_arg(argv[3])) < 0 ||
            cpus[0] == cpus[1])
            return usage();
    } else if (argc <= 2) {
        for (int c = 0, n = 0; n < 2; c++)
            if (CPU_ISSET(c, &mine))
                cpus[n++] = c;
    } else {
        return usage();
    }
    const double ns = measure(chunks);
    if (ns < 0) {
        fprintf(stderr, "handover: cannot run on CPUs %d and %d\n", cpus[0], cpus[1]);
        return 1;
    }
    printf("%.1f\n", ns);
    return 0;
}
