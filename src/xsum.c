/* Exact sums of doubles in a fixed-point accumulator (xsum.h). */
#include "nbep/xsum.h"

#include <math.h>
#include <stdbool.h>
#include <string.h>

#define LIMB_BITS 32
#define LIMB_MASK UINT64_C(0xffffffff)
#define TOP (NBEP_XSUM_LIMBS - 1)

/* Terms (or merged batches) between passes of the carries: each term adds less than 2^32 to
 * a limb, a pass leaves each limb within 2^31, and a merge adds two accumulators' limbs, so a
 * limb stays within 2 * 2^29 * 2^32 + 2^32 < 2^63. */
#define BATCH (UINT32_C(1) << 29)

void nbep_xsum_clear(nbep_xsum *s)
{
    for (int32_t k = s->lo; k <= s->hi; k++)
        s->limb[k] = 0;
    s->lo = NBEP_XSUM_LIMBS;
    s->hi = -1;
    s->adds = 0;
    s->special = 0.0;
}

static void widen(nbep_xsum *s, int32_t lo, int32_t hi)
{
    if (s->lo > s->hi) { /* empty */
        s->lo = lo;
        s->hi = hi;
        return;
    }
    if (lo < s->lo)
        s->lo = lo;
    if (hi > s->hi)
        s->hi = hi;
}

/* Each limb of the range into [-2^31, 2^31), the excess carried up (balanced digits: a
 * negative sum carries no -1 up through every limb above it, as digits in [0, 2^32) would).
 * The top limb keeps what reaches it: no double's sum comes near its range. */
static void carry(nbep_xsum *s)
{
    for (int32_t k = s->lo; k <= s->hi && k < TOP; k++) {
        const int64_t v = s->limb[k];
        /* floor((v + 2^31) / 2^32), from the bits (exact-width integers are two's
         * complement) rather than >> of a negative value, which C leaves to the compiler */
        const int64_t low = (int64_t)(((uint64_t)v + (UINT64_C(1) << 31)) & LIMB_MASK) -
                            (INT64_C(1) << 31);
        const int64_t c = (v - low) / (INT64_C(1) << LIMB_BITS); /* exact */
        s->limb[k] = low;
        if (c != 0) {
            s->limb[k + 1] += c;
            if (k + 1 > s->hi)
                s->hi = k + 1;
        }
    }
    s->adds = 1; /* every limb within one term's size again */
}

void nbep_xsum_add(nbep_xsum *s, double x)
{
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    const int ex = (int)((bits >> 52) & 0x7ff);
    uint64_t m = bits & ((UINT64_C(1) << 52) - 1);
    if (ex == 0x7ff) {
        s->special += x;
        return;
    }
    if (ex == 0) { /* zero or subnormal: m units of 2^-1074 */
        if (m == 0)
            return;
    } else {
        m |= UINT64_C(1) << 52; /* m 2^(ex - 1075) = m 2^(ex - 1) units */
    }
    const int off = ex == 0 ? 0 : ex - 1;
    const int32_t k = off / LIMB_BITS;
    const int sh = off % LIMB_BITS;
    /* m << sh, up to 84 bits, in three pieces of 32, 32 and 20 bits */
    const int64_t p0 = (int64_t)((m << sh) & LIMB_MASK);
    const uint64_t rest = sh == 0 ? m >> LIMB_BITS : m >> (LIMB_BITS - sh);
    const int64_t p1 = (int64_t)(rest & LIMB_MASK), p2 = (int64_t)(rest >> LIMB_BITS);
    if (bits >> 63) {
        s->limb[k] -= p0;
        s->limb[k + 1] -= p1;
        s->limb[k + 2] -= p2;
    } else {
        s->limb[k] += p0;
        s->limb[k + 1] += p1;
        s->limb[k + 2] += p2;
    }
    widen(s, k, k + 2);
    if (++s->adds >= BATCH)
        carry(s);
}

void nbep_xsum_merge(nbep_xsum *a, const nbep_xsum *b)
{
    a->special += b->special;
    if (b->lo > b->hi)
        return;
    for (int32_t k = b->lo; k <= b->hi; k++)
        a->limb[k] += b->limb[k];
    widen(a, b->lo, b->hi);
    a->adds += b->adds;
    if (a->adds >= BATCH)
        carry(a);
}

double nbep_xsum_value(const nbep_xsum *s)
{
    if (s->special != 0.0) /* an infinity, or NaN (which differs from everything) */
        return s->special;
    if (s->lo > s->hi)
        return 0.0;
    /* digits in [0, 2^32) from the bottom up; the top limb takes the signed rest */
    uint64_t d[NBEP_XSUM_LIMBS] = {0};
    int64_t c = 0;
    for (int32_t k = s->lo; k < TOP; k++) {
        const int64_t v = (k <= s->hi ? s->limb[k] : 0) + c;
        const int64_t low = (int64_t)((uint64_t)v & LIMB_MASK);
        c = (v - low) / (INT64_C(1) << LIMB_BITS);
        d[k] = (uint64_t)low;
        if (c == 0 && k >= s->hi)
            break;
    }
    const int64_t top = s->limb[TOP] + c;
    const bool negative = top < 0;
    if (negative) { /* the magnitude: two's complement of the digits */
        uint64_t one = 1; /* -D = ~D + 1 */
        for (int32_t k = 0; k < TOP; k++) {
            d[k] = ((~d[k]) & LIMB_MASK) + one;
            one = d[k] >> LIMB_BITS;
            d[k] &= LIMB_MASK;
        }
        /* the sum is top 2^(32 TOP) + D, of magnitude 2^(32 TOP) - D below the top limb only
         * for top = -1 and D > 0 (then ~D + 1 carries nothing out) */
        if (top != -1 || one != 0)
            return -HUGE_VAL;
    } else if (top > 0) {
        return HUGE_VAL;
    }
    int32_t h = TOP - 1;
    while (h >= 0 && d[h] == 0)
        h--;
    if (h < 0)
        return 0.0;
    double v;
    if (h <= 1) { /* below 2^64 units: an integer that converts with one rounding */
        v = ldexp((double)((d[1] << LIMB_BITS) | d[0]), -1074);
    } else {
        /* the 64 bits from the highest set one, and a sticky last bit for all below them:
         * the conversion keeps 53 and rounds on the other 11, so the sticky bit decides
         * only what lies wholly below them, as the exact value would */
        int b = LIMB_BITS;
        while (!(d[h] >> (b - 1)))
            b--;
        uint64_t w = (d[h] << (64 - b)) | (d[h - 1] << (LIMB_BITS - b)) | (d[h - 2] >> b);
        bool sticky = (d[h - 2] & ((UINT64_C(1) << b) - 1)) != 0;
        for (int32_t k = h - 3; k >= 0 && !sticky; k--)
            sticky = d[k] != 0;
        v = ldexp((double)(w | (uint64_t)sticky), LIMB_BITS * h + b - 64 - 1074);
    }
    return negative ? -v : v;
}
