/* Periodic boundaries (SPEC contract 2, box.periodic): the box [lo, hi) repeats along each
 * periodic axis with period len = hi - lo. The one place that knows the geometry: the minimum
 * image of a separation, wrapping a position into the box while counting the images crossed,
 * and the shift of a neighbouring copy of the box. Pure functions on values; no allocation, no
 * threads. A scene without periodic axes gets a geometry whose functions change nothing. */
#ifndef NBEP_PERIODIC_H
#define NBEP_PERIODIC_H

#include <stdbool.h>
#include <stdint.h>

#include "nbep/vec3.h"

typedef struct nbep_periodic {
    bool axis[3];   /* periodic along x, y, z */
    bool any;       /* some axis is */
    double lo[3];   /* the box's lower corner */
    double len[3];  /* its side (> 0 on periodic axes) */
    double half[3]; /* len / 2 on periodic axes, INFINITY on the others (so that a test
                     * against it needs no branch on the axis) */
} nbep_periodic;

/* The geometry of the box [lo, hi] with the periodic axes `axis` (NULL: none). */
nbep_periodic nbep_periodic_make(const bool axis[3], nbep_vec3 lo, nbep_vec3 hi);

/* The minimum image of the separation d: on each periodic axis, d minus the multiple of len
 * nearest to it, so that |d| <= len/2 there (a tie, |d| = len/2 exactly, where either image is
 * as near, takes the other sign: the rounding is half away from zero). Other axes are
 * unchanged. */
nbep_vec3 nbep_periodic_image(const nbep_periodic *pb, nbep_vec3 d);

/* Wraps *p into [lo, lo + len) on each periodic axis and adds to image[k] the number of
 * periods removed, so that p + image * len is unchanged (up to the rounding of p's shift).
 * Idempotent: a position already inside is not touched. Non-finite coordinates are left.
 * False where an axis's count would leave int32 (a sphere that crossed the box 2^31 times):
 * that axis is left as it was, outside the box, the unwrapped point the same; the frame's
 * writer refuses it (nbep_output_frame), and the algorithms carry it on meanwhile. */
bool nbep_periodic_wrap(const nbep_periodic *pb, nbep_vec3 *p, int32_t image[3]);

/* Whether p lies inside [lo, lo + len) on every periodic axis, by nbep_periodic_wrap's own test
 * (so that it would leave p as it is): the common case, tested inline without a call. False
 * for a non-finite coordinate on a periodic axis (which the wrap leaves too). */
static inline bool nbep_periodic_inside(const nbep_periodic *pb, nbep_vec3 p)
{
    const double x[3] = {p.x, p.y, p.z};
    bool in = true;
    for (int k = 0; k < 3; k++) {
        const double u = x[k] - pb->lo[k];
        in &= !pb->axis[k] || (u >= 0.0 && u < pb->len[k]);
    }
    return in;
}

/* The periods to add to the end of the separation d to reach its minimum image: cells[k] =
 * -round(d_k / len_k) on periodic axes, 0 elsewhere, so that d + nbep_periodic_shift(cells) is
 * the minimum image (with whole periods, exactly representable shifts). */
void nbep_periodic_nearest(const nbep_periodic *pb, nbep_vec3 d, int cells[3]);

/* nbep_periodic_shift of nbep_periodic_nearest(d) for a separation within one and a half
 * periods of its minimum image on every periodic axis (a pair of neighbours, whose stored
 * positions are never a whole box apart): compares instead of divisions, for inner loops.
 * Equal to the general one except at |d_k| = len_k / 2 exactly, where either image is as near. */
static inline nbep_vec3 nbep_periodic_near_shift(const nbep_periodic *pb, nbep_vec3 d)
{
    return nbep_vec3_make(d.x > pb->half[0] ? -pb->len[0] : d.x < -pb->half[0] ? pb->len[0] : 0.0,
                          d.y > pb->half[1] ? -pb->len[1] : d.y < -pb->half[1] ? pb->len[1] : 0.0,
                          d.z > pb->half[2] ? -pb->len[2] : d.z < -pb->half[2] ? pb->len[2] : 0.0);
}

/* nbep_periodic_image for a separation within one and a half periods of its minimum image on
 * every periodic axis (two spheres in contact): compares instead of a division and a rounding,
 * for the response of every collision. Equal to the general one except at |d_k| = len_k / 2
 * exactly, where either image is as near. */
static inline double nbep_periodic_near_image_1(double d, double half, double len)
{
    return d > half ? d - len : d < -half ? d + len : d;
}
static inline nbep_vec3 nbep_periodic_near_image(const nbep_periodic *pb, nbep_vec3 d)
{
    return nbep_vec3_make(nbep_periodic_near_image_1(d.x, pb->half[0], pb->len[0]),
                          nbep_periodic_near_image_1(d.y, pb->half[1], pb->len[1]),
                          nbep_periodic_near_image_1(d.z, pb->half[2], pb->len[2]));
}

/* The horizon of the minimum image: while neither sphere of a pair strays more than this from
 * where the pair was last compared (per axis), the image that was nearest then is the only
 * one that can touch (contact distance up to sigma): (min over periodic sides of len/2 - sigma)
 * / 4; INFINITY without periodic axes. */
double nbep_periodic_reach(const nbep_periodic *pb, double sigma);
/* nbep_periodic_reach where each partner is compared at its 27 images around the nearest (the
 * nearest shifted by -1, 0 or +1 period along each periodic axis): (min over periodic sides of
 * 1.5 len - sigma) / 4. */
double nbep_periodic_reach_wide(const nbep_periodic *pb, double sigma);

/* The displacement of the copy of the box `cells` periods away: cells[k] * len[k] per axis
 * (0 on non-periodic axes). */
nbep_vec3 nbep_periodic_shift(const nbep_periodic *pb, const int cells[3]);

#endif
