/* The ring of sites that tests/test_warp.c and tests/bench/bench_warp.c run through the
 * optimistic scheduler (src/warp.c): the hashes that make an event's new value and its next
 * time, what an event keeps of a site to undo, and what a message says. */
#ifndef NBEP_WARP_RING_H
#define NBEP_WARP_RING_H

#include <stdint.h>
#include <string.h>

enum { RING_WRITE = 1, RING_COPY = 2 };

typedef struct {
    uint64_t val;
    double next;
} ring_state; /* what an event changes of a site, kept to undo */

typedef struct {
    uint64_t val;
    double next;
    uint64_t kind; /* RING_WRITE (a site of the receiver's, with its next time) or RING_COPY */
} ring_note;

static inline uint64_t ring_mix64(uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* A site's new value from its neighbours', its own and the time. */
static inline uint64_t ring_mix(uint64_t a, uint64_t b, uint64_t c, double t)
{
    uint64_t tb;
    memcpy(&tb, &t, sizeof tb);
    return ring_mix64(a ^ ring_mix64(b ^ ring_mix64(c ^ ring_mix64(tb))));
}

/* A time to the next event: 0.05 to 1.05, from a value's top bits. */
static inline double ring_gap(uint64_t v)
{
    return 0.05 + (double)(v >> 11) * 0x1p-53;
}

/* The salt of a write across: the neighbour's new value is ring_mix(v, its own, RING_SALT, t). */
#define RING_SALT 0x5851F42D4C957F2Dull

#endif
