/* Aligned allocation and the spin-wait pause, shared by every module. */
#include "nbep/compiler.h"

#include <sched.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

void *nbep_alloc_aligned(size_t n, size_t size)
{
    if (size != 0 && n > SIZE_MAX / size)
        return NULL;
    size_t bytes = n * size;
    /* aligned_alloc wants a multiple of the alignment; never ask for 0 bytes. */
    bytes = (bytes + NBEP_CACHELINE - 1) / NBEP_CACHELINE * NBEP_CACHELINE;
    if (bytes == 0)
        bytes = NBEP_CACHELINE;
    void *p = aligned_alloc(NBEP_CACHELINE, bytes);
    if (p)
        memset(p, 0, bytes);
    return p;
}

void nbep_free_aligned(void *p)
{
    free(p);
}

double nbep_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void nbep_spin_pause(unsigned k)
{
    /* Yield every 1024 spins: with more threads than cores a pure spin would burn the
     * waiting thread's whole time slice while the thread it waits for cannot run. */
    if (k % 1024 == 0) {
        sched_yield();
        return;
    }
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}
