/* Contact times (paper Appendix 1): sphere-sphere as a closed-form quadratic when the two
 * accelerations are equal; when they differ, the quartic through GSL's polynomial solver (then
 * Newton-polished) or, where the acceleration bends the approach or the pair nearly touches, a
 * bracketing search on the quartic's monotone pieces, whichever bench_contact found faster at
 * equal accuracy; sphere-plane as a quadratic. The only user of GSL. */
#ifndef NBEP_PREDICT_H
#define NBEP_PREDICT_H

#include <float.h>
#include <math.h>
#include <stdbool.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

/* "No contact ahead". */
#define NBEP_NEVER INFINITY

/* Per-thread workspace for the quartic (GSL's companion-matrix solver and its coefficient and
 * root arrays), so that no call allocates. Create before any parallel region; one per thread;
 * not shared. create returns NBEP_OK or NBEP_ENOMEM (with a message in d) and writes *out only
 * on success; destroy is NULL-safe and NULLs the pointer. */
typedef struct nbep_predict_ws nbep_predict_ws;
NBEP_MUST_CHECK nbep_status nbep_predict_ws_create(nbep_predict_ws **out, nbep_diag *d);
/* Bytes nbep_predict_ws_create allocates itself (GSL's own workspace, a few hundred bytes in
 * the library, left out), for memory estimates. */
size_t nbep_predict_ws_bytes(void);
void nbep_predict_ws_destroy(nbep_predict_ws **ws);

/* All three return a time from now, t >= 0, finite or NBEP_NEVER, never NaN (inputs finite,
 * sigma > 0; any units, as long as products such as |dp| |dv| stay below ~1e150). Pure
 * functions: any number of threads may call them at once, the quartic each with its own
 * workspace. The contact is the earliest t >= 0 at which the two touch or overlap while
 * closing; for objects apart now, that is the first time the gap closes to zero. For
 * objects touching or overlapping now it is 0 if they close now (to the first order that is
 * not zero: a sphere at rest on a plane under gravity, or resting on a sphere under a
 * different acceleration, is pressed in now and gives 0; callers handle resting contact), else
 * the time at which they start closing again: the turn, if they are pulled back before they
 * come apart, or the return contact if they come apart first. */

/* A touching pair whose closing speed is at most this fraction of its relative speed closes
 * only by round-off, and slides instead (issue 9). A response leaves its own pair receding by
 * a push of at least DBL_EPSILON (|v1| + |v2|) along the normal (physics.c); a sphere caught
 * between two fixed neighbours that touch it from opposite sides is then left closing on the
 * other by about that much, and before this tolerance the two met it in turn at zero time for
 * ever (a 300-sphere pile: a sphere sliding between two held ones, a million reactions in a
 * step). 16 ulps covers that push with margin; a real contact closing this slowly would
 * overlap by at most about (16 ulps)^2 sigma, far below round-off of the position. */
#define NBEP_PREDICT_GRAZE (16.0 * DBL_EPSILON)

/* Earliest t >= 0 at which |dp + dv t| = sigma while closing (d|dp|/dt < 0), for a pair with
 * equal accelerations; dp = p2 - p1, dv = v2 - v1, sigma = r1 + r2. NBEP_NEVER when they do
 * not meet. A pair already touching or overlapping (|dp| <= sigma) and closing returns 0,
 * unless it closes only by round-off (|dp.dv| <= NBEP_PREDICT_GRAZE |dp| |dv|: it slides, see
 * there); receding or at rest, NBEP_NEVER (with equal accelerations it never turns back).
 * |dp|^2 - sigma^2 is computed compensated: a gap of 1e-12 sigma still gives about 15 digits. */
double nbep_predict_pair_quadratic(nbep_vec3 dp, nbep_vec3 dv, double sigma);

/* A cheap lower bound (no square root, no branch) on nbep_predict_pair_quadratic(dp, dv,
 * sigma), for loops that only want a pair's contact if it comes before the best one so far:
 * - NBEP_NEVER when the pair does not close (b = dp.dv >= 0: the root is NBEP_NEVER too), and
 *   when it certainly passes the other sphere: the discriminant b^2 - |dv|^2 c, c = |dp|^2 -
 *   sigma^2, computed plainly, is below minus a margin of 1e-12 of the magnitudes it is made
 *   of; its rounding, and that of either form the root takes (see there), stay below 16 ulps
 *   of those magnitudes (4e-15), so a pair called a miss here is a miss for the root too (one
 *   let through may still miss). Most closing pairs of a fluid pass each other.
 * - 0 when the pair touches or nearly (no bound: take the root);
 * - otherwise c / (-2 b), because the root is c / (-b + sqrt(b^2 - |dv|^2 c)) and the square
 *   root is at most -b. In floating point the root as computed can fall below c / (-2 b) by a
 *   few roundings (the sqrt, the sum, the division: under 4 ulps, 1e-15 relative); the bound is
 *   shrunk by 1e-12, far more than that, so a pair skipped for it is truly later. Nearer than
 *   |dp|^2 / 2 the root takes c compensated (it may be a tiny gap); c as computed here is then
 *   within about 5 ulps of |dp|^2 of the exact one, so c - 8 eps |dp|^2 (eps = 2^-52) is below
 *   both, and a bound still, where positive.
 * Written with selects only, so that a loop over partners runs several at once (vectorised). */
static inline double nbep_predict_pair_quadratic_bound(nbep_vec3 dp, nbep_vec3 dv, double sigma)
{
    const double b = dp.x * dv.x + dp.y * dv.y + dp.z * dv.z;
    const double pp = dp.x * dp.x + dp.y * dp.y + dp.z * dp.z;
    const double vv = dv.x * dv.x + dv.y * dv.y + dv.z * dv.z;
    double c = pp - sigma * sigma;
    const double bb = b * b, vc = vv * c;
    const bool hit = (b < 0.0) & !(bb - vc < -1e-12 * (bb + vv * (fabs(c) + pp)));
    c = c > 0.5 * pp ? c : c - 8.0 * 0x1p-52 * pp;
    const double den = hit ? -2.0 * b : 1.0; /* never 0: no branch around the division */
    const double q = c / den * (1.0 - 1e-12);
    return hit ? (c > 0.0 ? q : 0.0) : NBEP_NEVER;
}

/* The same for any relative acceleration da = a2 - a1: quadratic when da is exactly zero,
 * otherwise the smallest valid real root of the quartic |dp + dv t + da t^2/2|^2 = sigma^2,
 * polished by Newton (relative accuracy near 1e-15 except at grazing incidence, where the
 * answer's own sensitivity to the inputs limits it). Whether a pair that passes within
 * round-off of touching (about 1e-13 relative) meets is decided by the sign of the computed
 * gap. When da is so small that it changes nothing before 2^240 time units (|dv|/|da| beyond
 * ~1e72), the quadratic is used. ws is borrowed, written, and may be NULL only when da is zero. */
double nbep_predict_pair(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma,
                         nbep_predict_ws *ws);
/* nbep_predict_pair for a caller that wants the contact only if it comes before t_max (a loop
 * that keeps the earliest of a sphere's contacts: t_max the best so far, plus a margin for
 * ties): the same time when it does, and otherwise NBEP_NEVER or a time at or past t_max.
 * The slow search that accelerated, slowly approaching pairs take (a settling pile, a hopper)
 * then stops at t_max. t_max = INFINITY is nbep_predict_pair. */
double nbep_predict_pair_within(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma,
                                double t_max, nbep_predict_ws *ws);

/* A lower bound on nbep_predict_pair(dp, dv, da, sigma) for any relative acceleration, for
 * loops that only want a pair's contact if it comes before the best one so far (a quartic
 * root costs about a hundred times a quadratic one: a settling pile spent four fifths of its
 * time on roots it then discarded). |dp + dv t + da t^2/2| >= |dp| - |dv| t - |da| t^2/2, so
 * the pair cannot touch before |dv| t + |da| t^2/2 reaches the gap g = |dp| - sigma:
 * t = 2 g / (|dv| + sqrt(|dv|^2 + 2 |da| g)) (without cancellation); nor, looking along the
 * line of centres, before |dp| + (u.dv) t + (u.da) t^2/2 reaches sigma (below): the bound is
 * the later of the two.
 * - g is taken 1e-12 |dp| short, which lowers the bound by at least half of 1e-12 of itself
 *   (it grows as g, or as sqrt(g) where the acceleration rules, and |dp| > g): far more than
 *   the bound's own rounding (a few ulps, and that of |dp| in g) and than the computed root's
 *   error where the two can be close. They are close only for a pair closing head-on at the
 *   full relative speed, whose root is simple and Newton-polished to a few ulps (a grazing
 *   pair's double root, off by up to 1e-8, lies well beyond the bound). Without the shortfall
 *   the head-on bound came out an ulp above the root (tests/test_predict.c). So a pair skipped
 *   for it is truly later.
 * - 0 (no bound: take the root) where they touch or are within that shortfall of it, and where
 *   a nonzero component of dp, dv or da, or sigma, lies outside 2^-300 .. 2^300: their
 *   products would leave the normal range, where those roundings do not hold.
 * - NBEP_NEVER where the pair, apart, only draws apart (below; a pair that nothing moves among
 *   them), whose root is NBEP_NEVER as well. */
static inline bool nbep__predict_bound_scale(double x)
{
    return x == 0.0 || (fabs(x) >= 0x1p-300 && fabs(x) <= 0x1p300);
}

static inline double nbep_predict_pair_bound(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da,
                                             double sigma)
{
    /* every product below normal and finite, so that the roundings argued here hold: else no
     * bound (the root itself is scaled to any units; a bound from underflowed squares came out
     * above it) */
    const double c[9] = {dp.x, dp.y, dp.z, dv.x, dv.y, dv.z, da.x, da.y, da.z};
    for (int k = 0; k < 9; k++)
        if (!nbep__predict_bound_scale(c[k]))
            return 0.0;
    if (!nbep__predict_bound_scale(sigma))
        return 0.0;
    const double d = sqrt(dp.x * dp.x + dp.y * dp.y + dp.z * dp.z);
    const double g = d - sigma - 1e-12 * d;
    if (!(g > 0.0))
        return 0.0;
    /* never: |r(t)|^2 = |dp|^2 + 2 dp.dv t + (|dv|^2 + dp.da) t^2 + dv.da t^3 + |da|^2 t^4/4
     * grows for t >= 0 when those three coefficients are >= 0, which their computed values
     * tell where they exceed their rounding (under 4 eps of the sum of the products' sizes;
     * exactly 0 where a vector is 0, as for a pair at rest with the same acceleration) */
    const double e4 = 4.0 * 0x1p-52;
    const double pv = dp.x * dv.x + dp.y * dv.y + dp.z * dv.z;
    const double pa = dp.x * da.x + dp.y * da.y + dp.z * da.z;
    const double va = dv.x * da.x + dv.y * da.y + dv.z * da.z;
    const double vv = dv.x * dv.x + dv.y * dv.y + dv.z * dv.z;
    const double pv_size = fabs(dp.x * dv.x) + fabs(dp.y * dv.y) + fabs(dp.z * dv.z);
    const double pa_size = fabs(dp.x * da.x) + fabs(dp.y * da.y) + fabs(dp.z * da.z);
    const double va_size = fabs(dv.x * da.x) + fabs(dv.y * da.y) + fabs(dv.z * da.z);
    if (pv >= e4 * pv_size && vv + pa >= e4 * (vv + pa_size) && va >= e4 * va_size)
        return NBEP_NEVER;
    /* dv or da is not 0 (with both 0 the test above holds): den > 0 */
    const double a = sqrt(da.x * da.x + da.y * da.y + da.z * da.z), v = sqrt(vv);
    const double t_all = 2.0 * g / (v + sqrt(vv + 2.0 * a * g));
    /* Along the line of centres (unit u = dp / |dp|): |r(t)| >= u.r(t) = |dp| + p1 t + p2 t^2/2,
     * p1 = u.dv, p2 = u.da, so the pair cannot touch before g + p1 t + p2 t^2/2 first reaches
     * 0 either. Far tighter than t_all where the motions are not along u: a sphere falling past
     * a held one beside it (where t_all takes all of gravity towards it), or one that the
     * other's course carries sideways. A push apart along u (p2 > 0) is left out (taken as
     * 0, still a bound): the parabola is then a line or bends down, its first root simple,
     * and each form below adds numbers of one sign only (a few ulps).
     * The computed p1, p2 stand for the exact ones within 5 eps |dv| and 5 eps |da| (the sums
     * of products, each within 3 eps of its size, which is at most |dp| |dv|, |dp| |da|, over
     * |dp|), so the computed parabola stays below the exact one by at least the shortfall
     * 1e-12 |dp| less 5 eps (|dv| t + |da| t^2/2) while |dv| t + |da| t^2/2 <= C |dp|, C = 64:
     * 0.9e-12 |dp|. That moves the root by 0.9e-12 |dp| / |slope| >= 0.9e-12 t / (2 C), 30 ulps
     * of t, far more than the forms' roundings; the computed root lies within a few ulps of
     * the exact one where the two come close (a simple root, Newton-polished: a review's 80 M
     * fuzzed pairs found the bound 133 ulps below the root at the nearest, thrown apart and
     * pulled back to just inside the cap). Past t_cap (where that sum reaches C |dp|) the
     * errors are not bounded: the bound stops there. */
    const double t_cap = 2.0 * 64.0 * d / (v + sqrt(vv + 2.0 * 64.0 * a * d));
    const double p1 = pv / d, p2 = pa / d;
    const double ac = p2 < 0.0 ? -p2 : 0.0; /* the pull together along u */
    double t_line = t_cap;
    if (p1 <= 0.0 && (p1 < 0.0 || ac > 0.0))
        t_line = 2.0 * g / (-p1 + sqrt(p1 * p1 + 2.0 * ac * g));
    else if (p1 > 0.0 && ac > 0.0)
        t_line = (p1 + sqrt(p1 * p1 + 2.0 * ac * g)) / ac;
    t_line = t_line < t_cap ? t_line : t_cap;
    return t_line > t_all ? t_line : t_all;
}

/* Earliest t >= 0 at which a sphere's gap to a plane, g(t) = gap + vn t + an t^2/2, reaches
 * zero while closing (g'(t) < 0). gap = n.p - offset - r, vn = n.v, an = n.a. NBEP_NEVER when
 * it never does. Touching or overlapping (gap <= 0) and closing (vn < 0) returns 0, and so
 * does gap <= 0, vn = 0, an < 0: a sphere resting on the plane under gravity is pressed into
 * it right now (callers handle resting contact). Overlapping and leaving (vn > 0, an < 0):
 * the return contact, or the turn t = vn/-an if it is pulled back before it gets out. */
double nbep_predict_plane(double gap, double vn, double an);

/* A sphere touching a plane and closing on it by no more than this fraction of its speed
 * slides (nbep_predict_plane_contact). Wider than NBEP_PREDICT_GRAZE because the push that
 * leaves a pair receding (physics.c: DBL_EPSILON (|v1| + |v2|), doubled until the pair's test
 * passes) lands on the plane through the pair's normal: a sphere caged between a wall and a
 * held sphere was pushed into the wall by 1.1e-14 of its speed (50 ulps) and met the two in
 * turn a million times in a step (a 300-sphere pour, step 1771). Sliding into the plane that
 * slowly overlaps it by 1e-12 of the distance travelled: 1e-15 m over a step of a 1 m/s
 * sphere at dt = 1e-3, far below round-off of its position. */
#define NBEP_PREDICT_GRAZE_PLANE 1e-12

/* nbep_predict_plane for a sphere moving at `speed` (|v|): touching or overlapping (gap <= 0)
 * and closing only by round-off (-vn <= NBEP_PREDICT_GRAZE_PLANE speed), it slides along the
 * plane (vn taken as 0), as a pair does (see NBEP_PREDICT_GRAZE). Issue 9: a sphere caught
 * between a wall and a held sphere, the cage's projection leaving it closing on the wall by
 * 1e-18 of its speed and the held sphere's tie push giving that back, met the wall at zero
 * time a million times in one step (a 300-sphere pour, step 1305). */
double nbep_predict_plane_contact(double gap, double vn, double an, double speed);

#endif
