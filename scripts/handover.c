/* How long a cache line takes to pass between the two cores that a 2-thread run uses: two
 * threads, pinned to the first two CPUs this process may run on, hand a counter back and forth
 * (each waits for the other's number, then writes the next). Prints the median over `chunks`
 * stretches of 100000 hand-overs of the nanoseconds one hand-over takes.
 *
 *   cc -O2 -pthread scripts/handover.c -o handover && ./handover [chunks]
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
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define PER_CHUNK 100000L
#define CHUNKS_MAX 64

static _Alignas(64) _Atomic long counter;
static long total;
static int cpus[2];

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void pin(int cpu)
{
    cpu_set_t s;
    CPU_ZERO(&s);
    CPU_SET(cpu, &s);
    pthread_setaffinity_np(pthread_self(), sizeof s, &s);
}

/* Hands over the odd numbers: waits for each, writes the next. */
static void *answer(void *arg)
{
    (void)arg;
    pin(cpus[1]);
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

int main(int argc, char **argv)
{
    const int chunks = argc > 1 ? atoi(argv[1]) : 5;
    if (chunks < 1 || chunks > CHUNKS_MAX) {
        fprintf(stderr, "handover: chunks must be 1 to %d\n", CHUNKS_MAX);
        return 2;
    }
    cpu_set_t mine;
    if (sched_getaffinity(0, sizeof mine, &mine) != 0 || CPU_COUNT(&mine) < 2) {
        fprintf(stderr, "handover: needs two CPUs\n");
        return 2;
    }
    for (int c = 0, n = 0; n < 2; c++)
        if (CPU_ISSET(c, &mine))
            cpus[n++] = c;
    total = chunks * PER_CHUNK;
    pin(cpus[0]);
    pthread_t t;
    if (pthread_create(&t, NULL, answer, NULL) != 0) {
        fprintf(stderr, "handover: no thread\n");
        return 2;
    }
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
    printf("%.1f\n", ns[chunks / 2]);
    return 0;
}
