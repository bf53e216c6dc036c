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
} nbep_periodic;

/* The geometry of the box [lo, hi] with the periodic axes `axis` (NULL: none). */
nbep_periodic nbep_periodic_make(const bool axis[3], nbep_vec3 lo, nbep_vec3 hi);

/* The minimum image of the separation d: on each periodic axis, d minus the multiple of len
 * nearest to it, so that |d| <= len/2 there (ties, |d| = len/2 exactly, keep their sign).
 * Other axes are unchanged. */
nbep_vec3 nbep_periodic_image(const nbep_periodic *pb, nbep_vec3 d);

/* Wraps *p into [lo, lo + len) on each periodic axis and adds to image[k] the number of
 * periods removed, so that p + image * len is unchanged (up to the rounding of p's shift).
 * Idempotent: a position already inside is not touched. Non-finite coordinates are left. */
void nbep_periodic_wrap(const nbep_periodic *pb, nbep_vec3 *p, int32_t image[3]);

/* The periods to add to the end of the separation d to reach its minimum image: cells[k] =
 * -round(d_k / len_k) on periodic axes, 0 elsewhere, so that d + nbep_periodic_shift(cells) is
 * the minimum image (with whole periods, exactly representable shifts). */
void nbep_periodic_nearest(const nbep_periodic *pb, nbep_vec3 d, int cells[3]);

/* The horizon of the minimum image: while neither sphere of a pair strays more than this from
 * where the pair was last compared (per axis), the image that was nearest then is the only
 * one that can touch (contact distance up to sigma): (min over periodic sides of len/2 - sigma)
 * / 4; INFINITY without periodic axes. */
double nbep_periodic_reach(const nbep_periodic *pb, double sigma);

/* The displacement of the copy of the box `cells` periods away: cells[k] * len[k] per axis
 * (0 on non-periodic axes). */
nbep_vec3 nbep_periodic_shift(const nbep_periodic *pb, const int cells[3]);

#endif
