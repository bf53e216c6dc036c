/* Periodic geometry: see periodic.h. */
#include "nbep/periodic.h"

#include <math.h>
#include <string.h>

nbep_periodic nbep_periodic_make(const bool axis[3], nbep_vec3 lo, nbep_vec3 hi)
{
    nbep_periodic pb;
    memset(&pb, 0, sizeof pb);
    const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    for (int k = 0; k < 3; k++) {
        pb.axis[k] = axis && axis[k];
        pb.any = pb.any || pb.axis[k];
        pb.lo[k] = l[k];
        pb.len[k] = h[k] - l[k];
        pb.half[k] = pb.axis[k] ? 0.5 * pb.len[k] : INFINITY;
    }
    return pb;
}

/* One axis of the minimum image: d - len * round(d / len), with round-half-away-from-zero so
 * that the result does not depend on the rounding mode. */
static double image_1(double d, double len)
{
    double m = round(d / len);
    return m != 0.0 ? d - m * len : d;
}

nbep_vec3 nbep_periodic_image(const nbep_periodic *pb, nbep_vec3 d)
{
    if (pb->axis[0])
        d.x = image_1(d.x, pb->len[0]);
    if (pb->axis[1])
        d.y = image_1(d.y, pb->len[1]);
    if (pb->axis[2])
        d.z = image_1(d.z, pb->len[2]);
    return d;
}

/* One axis of the wrap. floor gives the periods to remove; rounding of x - m len can leave the
 * result a hair outside [lo, lo + len): one more step either way fixes that. A step up that
 * rounds onto lo + len (the point lay within half an ulp below a face) is at the upper face,
 * which belongs to the next copy: it becomes lo, one more period removed (set to lo alone, the
 * count kept, the point it stood for moved a whole period down). A count that would leave
 * int32 (SPEC's /frames/image; until 2026-12-03 it overflowed, undefined behaviour, and a move
 * of 1e9 periods or more was left unwrapped without a word) leaves x and the count as they
 * were, which still give the same unwrapped point: false. */
static bool wrap_1(double *x, double lo, double len, int32_t *image)
{
    double u = *x - lo;
    if (!isfinite(u) || (u >= 0.0 && u < len))
        return true;
    double m = floor(u / len);
    double y = *x - m * len;
    if (y >= lo + len) {
        y -= len;
        m += 1.0;
    } else if (y < lo) {
        y += len;
        m -= 1.0;
    }
    if (y >= lo + len) {
        y = lo;
        m += 1.0;
    }
    const double count = (double)*image + m; /* exact while |m| < 2^52; else far out anyway */
    if (!(count >= (double)INT32_MIN && count <= (double)INT32_MAX))
        return false;
    *x = y;
    *image = (int32_t)count;
    return true;
}

bool nbep_periodic_wrap(const nbep_periodic *pb, nbep_vec3 *p, int32_t image[3])
{
    bool ok = true;
    if (pb->axis[0])
        ok = wrap_1(&p->x, pb->lo[0], pb->len[0], &image[0]) && ok;
    if (pb->axis[1])
        ok = wrap_1(&p->y, pb->lo[1], pb->len[1], &image[1]) && ok;
    if (pb->axis[2])
        ok = wrap_1(&p->z, pb->lo[2], pb->len[2], &image[2]) && ok;
    return ok;
}

void nbep_periodic_nearest(const nbep_periodic *pb, nbep_vec3 d, int cells[3])
{
    const double x[3] = {d.x, d.y, d.z};
    for (int k = 0; k < 3; k++)
        cells[k] = pb->axis[k] ? -(int)round(x[k] / pb->len[k]) : 0;
}

/* (min over periodic sides of f len - sigma) / 4, INFINITY without periodic axes: the reach
 * when a touching image must stay within f len of the images compared. Two spheres each within
 * D of its anchor move at most 2 D each between their comparison and a contact, 4 D together;
 * the touching image is within sigma then, so within sigma + 4 D at the comparison. */
static double reach_within(const nbep_periodic *pb, double f, double sigma)
{
    double r = INFINITY;
    for (int k = 0; k < 3; k++)
        if (pb->axis[k])
            r = fmin(r, (f * pb->len[k] - sigma) / 4.0);
    return r;
}

/* The nearest image is the touching one while that is at most len/2 away. */
double nbep_periodic_reach(const nbep_periodic *pb, double sigma)
{
    return reach_within(pb, 0.5, sigma);
}

/* With the 27 images around the nearest compared (each axis's -1, 0 and +1 periods from it), a
 * touching image lies a period or more from the nearest only past 1.5 len. */
double nbep_periodic_reach_wide(const nbep_periodic *pb, double sigma)
{
    return reach_within(pb, 1.5, sigma);
}

nbep_vec3 nbep_periodic_shift(const nbep_periodic *pb, const int cells[3])
{
    return nbep_vec3_make(pb->axis[0] ? cells[0] * pb->len[0] : 0.0,
                          pb->axis[1] ? cells[1] * pb->len[1] : 0.0,
                          pb->axis[2] ? cells[2] * pb->len[2] : 0.0);
}
