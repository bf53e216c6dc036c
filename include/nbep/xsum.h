/* Exact sums of doubles (the step's virial and wall impulses, SPEC /stats): every term is
 * added exactly into a fixed-point accumulator wide enough for any finite double, so the sum
 * does not depend on the order of its terms or on how they were split among threads, and its
 * value is the exact sum rounded once, to nearest. Grid mode decides which thread reacts to a
 * pair by a compare-and-swap race, and each thread sums its own reactions: with plain doubles
 * the step's virial then changed in its last bits from run to run and with the thread count.
 *
 * The accumulator is 2^-1074 (the least subnormal) times a signed integer held in
 * NBEP_XSUM_LIMBS limbs of 32 bits, each kept in an int64_t so that a limb takes many
 * additions of less than 2^32 before its carries need passing on (nbep_xsum_add and
 * nbep_xsum_merge do that every 2^29 terms: BATCH in xsum.c). All zero bytes is the empty
 * sum. Infinities and NaN are summed apart, as doubles, and win: a sum with one is that sum. */
#ifndef NBEP_XSUM_H
#define NBEP_XSUM_H

#include <stdint.h>

/* bits 0 .. 2097 of 2^-1074 units hold every finite double (2^1024 = 2^2098 units) with a
 * 53-bit mantissa shifted by up to 31 within its limb: 67 limbs, and one more for the carries
 * and the sign of a sum that would overflow a double */
#define NBEP_XSUM_LIMBS 68

typedef struct nbep_xsum {
    int64_t limb[NBEP_XSUM_LIMBS];
    int32_t lo, hi;  /* the limbs written since the last clear (lo > hi: none; 0, 0 at zero) */
    uint32_t adds;   /* terms added since the carries were last passed on */
    double special;  /* the sum of the infinities and NaNs added (0 without) */
} nbep_xsum;

/* 0, the empty sum, in a sum that holds one (zero bytes, or what these functions left): the
 * limbs written since the last clear are zeroed, not all. */
void nbep_xsum_clear(nbep_xsum *s);

/* s += x, exactly (x finite), or into the special sum (x infinite or NaN). */
void nbep_xsum_add(nbep_xsum *s, double x);

/* a += b, exactly. */
void nbep_xsum_merge(nbep_xsum *a, const nbep_xsum *b);

/* The sum rounded to the nearest double (ties to even; an exact sum beyond the largest double
 * is an infinity of its sign). */
double nbep_xsum_value(const nbep_xsum *s);

#endif
