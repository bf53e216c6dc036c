/* Collision response and energy (paper Section 5). Pure functions on values or index ranges:
 * no threads, no allocation, no state between calls.
 *
 * Departure from the paper: the sphere-sphere response is computed with the pair in a
 * canonical order (the sphere with the lexicographically smaller position plays "1"), so that
 * the result does not depend on which of the two a caller names first. Algorithms visit a
 * pair from either side depending on ownership and thread count, and frames must be bitwise
 * identical across thread counts (SPEC "Algorithms"). The formula as written here happens to
 * be symmetric in IEEE arithmetic already (swapping negates n and v1 - v2 exactly); the
 * canonical order makes that hold by construction, whatever shape the arithmetic takes. */
#include "nbep/physics.h"

#include <assert.h>
#include <float.h>
#include <math.h>

/* Departure from the paper (issue 9, round-off ties): "closing" has one definition that
 * prediction (predict.c: f'(0) = 2 dp.dv < 0, and n.v < 0 for a plane) and response share.
 * A response must leave the pair not closing by that very test; otherwise a pair that has
 * just responded is predicted to touch again at zero time and reacts forever (with e = 0 the
 * normal speed after the response is zero only to round-off of |v|, and its sign is a coin
 * toss). So after the formula, a residual closing speed, which can only be round-off, is
 * removed by a further push along the normal: at least DBL_EPSILON (|v1| + |v2|), doubled
 * until the test passes. It changes the kinetic energy by a few ulps of it. */
#define TIE_TRIES 64

/* Adds a normal speed du to the pair (shared by mass like a response, so momentum is kept)
 * until d.(v2 - v1) >= 0. */
static void leave_receding(nbep_vec3 d, double len, nbep_vec3 n, nbep_vec3 *v1, nbep_vec3 *v2,
                           double m1, double m2)
{
    double u = nbep_vec3_dot(d, nbep_vec3_sub(*v2, *v1));
    if (!(u < 0.0))
        return;
    double du = fmax(-u / len, DBL_EPSILON * (nbep_vec3_norm(*v1) + nbep_vec3_norm(*v2)));
    double m = m1 + m2;
    for (int k = 0; k < TIE_TRIES && u < 0.0; k++, du *= 2.0) {
        *v1 = nbep_vec3_axpy(*v1, -du * m2 / m, n);
        *v2 = nbep_vec3_axpy(*v2, du * m1 / m, n);
        u = nbep_vec3_dot(d, nbep_vec3_sub(*v2, *v1));
    }
}

/* |n|^2 - 1 of a normal n made unit by rounding (a vector over its rounded length), to about
 * 1e-32: each square's product and rounding error (fma), summed with their errors, less 1
 * (exact: the sum lies within [0.5, 2]). A rounded normal is a unit vector only to an ulp or
 * two, and a response that takes it for one changes the kinetic energy by 4 vn^2 (|n|^2 - 1)
 * at e = 1: on average a gain (|n|^2 - 1 came out +8.8e-17 over a million random pairs, and a
 * deck's plane is one fixed n: a (1, 1, 1) plane's bounces grew |v| by 4.7e-14 in 4607), so
 * an elastic fluid's energy drifted up in step with its collisions, 1.5e-18 of it each, past
 * 1e-12 in a million (a review, 2026-12-02). The responses take the part of the velocity
 * along n as (v.n) n (1 - excess), rounded once (add_once); 0 for an axis-aligned n, whose
 * responses keep their bits. */
static inline NBEP_ALWAYS_INLINE double unit_excess(nbep_vec3 n)
{
    const double px = n.x * n.x, py = n.y * n.y, pz = n.z * n.z;
    const double ex = fma(n.x, n.x, -px), ey = fma(n.y, n.y, -py), ez = fma(n.z, n.z, -pz);
    const double s1 = px + py, b1 = s1 - px, e1 = (px - (s1 - b1)) + (py - b1);
    const double s2 = s1 + pz, b2 = s2 - s1, e2 = (s1 - (s2 - b2)) + (pz - b2);
    return (s2 - 1.0) + (e1 + e2 + ex + ey + ez);
}

/* One component of v + s n (1 - excess), rounded once: the product's rounding error (fma)
 * and the sum's (TwoSum) kept with the excess's part, s n excess, and added to the rounded
 * sum last. In two roundings (v + s n, then the small part) the small part was lost to its
 * own rounding 35 to 45 % of the time, and not at random: a (1, 2, 3) plane's bounces still
 * gained 1.1e-17 of the energy each (a review); rounded once, none that 400000 bounces show. */
static inline NBEP_ALWAYS_INLINE double add_once(double v, double s, double n, double excess)
{
    const double p = s * n, ep = fma(s, n, -p);
    const double t = v + p, b = t - v, et = (v - (t - b)) + (p - b);
    return t + ((et + ep) - s * n * excess);
}

/* v + s n (1 - excess) by components (add_once); an axis-aligned n has no excess, and its
 * responses keep the plain axpy's bits (a -0 component too). */
static inline NBEP_ALWAYS_INLINE nbep_vec3 axpy_unit(nbep_vec3 v, double s, nbep_vec3 n,
                                                    double excess)
{
    if (excess == 0.0)
        return nbep_vec3_axpy(v, s, n);
    return (nbep_vec3){add_once(v.x, s, n.x, excess), add_once(v.y, s, n.y, excess),
                       add_once(v.z, s, n.z, excess)};
}

/* True when a comes before b in (x, y, z) lexicographic order. */
static bool vec3_lex_less(nbep_vec3 a, nbep_vec3 b)
{
    if (a.x != b.x)
        return a.x < b.x;
    if (a.y != b.y)
        return a.y < b.y;
    return a.z < b.z;
}

/* The paper's formula with sphere "1" fixed by the caller: n = (p2 - p1)/|p2 - p1|,
 * c = n.(v1 - v2); when c > 0, v1 -= m2 c (1+e) n/(m1+m2), v2 += m1 c (1+e) n/(m1+m2), each
 * times (1 - excess) for the rounded n's excess over unit length (unit_excess, axpy_unit). */
NBEP_FMA_CLONES static bool respond_ordered(nbep_vec3 p1, nbep_vec3 p2, nbep_vec3 *v1,
                                            nbep_vec3 *v2, double m1, double m2, double e)
{
    nbep_vec3 d = nbep_vec3_sub(p2, p1);
    double len = nbep_vec3_norm(d);
    if (!(len > 0.0))
        return false;                       /* coincident centres: no normal */
    /* Divide each component (not multiply by 1/len): one rounding instead of two. */
    nbep_vec3 n = {d.x / len, d.y / len, d.z / len};
    if (!(nbep_vec3_dot(d, nbep_vec3_sub(*v2, *v1)) < 0.0))
        return false;                       /* receding or sliding: no impulse */
    double c = nbep_vec3_dot(n, nbep_vec3_sub(*v1, *v2));
    if (c > 0.0) {                          /* else closing only to round-off */
        double k = c * (1.0 + e) / (m1 + m2);
        const double excess = unit_excess(n); /* the part along n is c n (1 - excess) */
        *v1 = axpy_unit(*v1, -m2 * k, n, excess);
        *v2 = axpy_unit(*v2, m1 * k, n, excess);
    }
    leave_receding(d, len, n, v1, v2, m1, m2);
    return true;
}

bool nbep_physics_respond_pair(nbep_vec3 p1, nbep_vec3 p2, nbep_vec3 *v1, nbep_vec3 *v2,
                               double m1, double m2, double e)
{
    assert(nbep_vec3_isfinite(p1) && nbep_vec3_isfinite(p2));
    assert(nbep_vec3_isfinite(*v1) && nbep_vec3_isfinite(*v2));
    assert(m1 > 0.0 && m2 > 0.0 && e >= 0.0 && e <= 1.0);
    if (vec3_lex_less(p2, p1))
        return respond_ordered(p2, p1, v2, v1, m2, m1, e);
    return respond_ordered(p1, p2, v1, v2, m1, m2, e);
}

bool nbep_physics_respond_pair_along(nbep_vec3 p1, nbep_vec3 p2, nbep_vec3 *v1, nbep_vec3 *v2,
                                     double m1, double m2, double e, nbep_vec3 d1, nbep_vec3 d2,
                                     double *impulse)
{
    *impulse = 0.0;
    assert(nbep_vec3_isfinite(p1) && nbep_vec3_isfinite(p2));
    assert(nbep_vec3_isfinite(*v1) && nbep_vec3_isfinite(*v2));
    assert(m1 > 0.0 && m2 > 0.0 && e >= 0.0 && e <= 1.0);
    double w = nbep_vec3_dot(d1, d1) / m1 + nbep_vec3_dot(d2, d2) / m2;
    if (!(w > 0.0))
        return nbep_physics_respond_pair(p1, p2, v1, v2, m1, m2, e);
    nbep_vec3 d = nbep_vec3_sub(p2, p1);
    double len = nbep_vec3_norm(d);
    if (!(len > 0.0))
        return false;                       /* coincident centres: no normal */
    nbep_vec3 n = {d.x / len, d.y / len, d.z / len};
    double u = nbep_vec3_dot(d, nbep_vec3_sub(*v2, *v1));
    if (!(u < 0.0))
        return false;                       /* receding or sliding: no impulse */
    double c = nbep_vec3_dot(n, nbep_vec3_sub(*v1, *v2));
    double J = c > 0.0 ? c * (1.0 + e) / w : 0.0; /* else closing only to round-off */
    /* see TIE_TRIES: then J grows by at least DBL_EPSILON (|v1| + |v2|) / w, doubled */
    double dJ = DBL_EPSILON * (nbep_vec3_norm(*v1) + nbep_vec3_norm(*v2)) / w;
    nbep_vec3 a1 = *v1, a2 = *v2;
    for (int k = 0; k < TIE_TRIES; k++) {
        *v1 = nbep_vec3_axpy(a1, J / m1, d1);
        *v2 = nbep_vec3_axpy(a2, J / m2, d2);
        u = nbep_vec3_dot(d, nbep_vec3_sub(*v2, *v1));
        if (!(u < 0.0) || k == TIE_TRIES - 1)
            break; /* (J stays the one applied) */
        J += fmax(-u / len / w, dJ);
        dJ *= 2.0;
    }
    /* The planes do no work only while the spheres move along them. A sphere that moves across
     * a contact's normal (a jammed body's sphere keeps the walls the body touched, and may
     * meet a sphere before its motion has come to them) is moved by J d, and where d is nearly
     * across n, J ~ c / |d|^2 gains it energy ~ (c / |d|)^2: a sphere so shot off at 1.9 m/s,
     * closing at 1e-8 m/s with |d| = 3e-9 (test_settle.sh, the bouncing row). Energy never
     * grows in a response with e <= 1: where it would, the pair responds as a free one
     * instead. The tolerance, 1e-9 of the pair's energy, is far above the round-off of the
     * sums (a few ulps) and of the tie push above (a few ulps of |v|, doubled a few times),
     * and far below a gain that matters. */
    const double ke0 = m1 * nbep_vec3_dot(a1, a1) + m2 * nbep_vec3_dot(a2, a2),
                 ke1 = m1 * nbep_vec3_dot(*v1, *v1) + m2 * nbep_vec3_dot(*v2, *v2);
    if (!(ke1 <= ke0 * (1.0 + 1e-9))) { /* (NaN too) */
        *v1 = a1;
        *v2 = a2;
        return nbep_physics_respond_pair(p1, p2, v1, v2, m1, m2, e);
    }
    *impulse = J;
    return true;
}

NBEP_FMA_CLONES bool nbep_physics_respond_plane(nbep_vec3 n, nbep_vec3 *v, double e)
{
    assert(nbep_vec3_isfinite(n) && nbep_vec3_isfinite(*v));
    double vn = nbep_vec3_dot(*v, n);
    if (!(vn < 0.0))
        return false;                       /* moving along or away from the plane */
    /* the part along n is vn n (1 - excess), as in respond_ordered */
    *v = axpy_unit(*v, -(1.0 + e) * vn, n, unit_excess(n));
    /* see TIE_TRIES: the same closing test as nbep_predict_plane, n.v < 0 */
    double du = DBL_EPSILON * nbep_vec3_norm(*v);
    for (int k = 0; k < TIE_TRIES && nbep_vec3_dot(*v, n) < 0.0; k++, du *= 2.0)
        *v = nbep_vec3_axpy(*v, fmax(-nbep_vec3_dot(*v, n), du), n);
    return true;
}

void nbep_physics_separate_plane(nbep_vec3 n, double offset, nbep_vec3 *p, double r)
{
    double gap = nbep_physics_plane_gap(n, offset, *p, r);
    if (gap < 0.0)
        *p = nbep_vec3_axpy(*p, -gap, n);
}

void nbep_physics_separate_pair(nbep_vec3 *p1, nbep_vec3 *p2, double r1, double r2, double m1,
                                double m2)
{
    nbep_vec3 d = nbep_vec3_sub(*p2, *p1);
    double len = nbep_vec3_norm(d), ov = r1 + r2 - len;
    if (!(len > 0.0) || !(ov > 0.0))
        return;
    nbep_vec3 n = {d.x / len, d.y / len, d.z / len};
    double m = m1 + m2;
    *p1 = nbep_vec3_axpy(*p1, -ov * m2 / m, n);
    *p2 = nbep_vec3_axpy(*p2, ov * m1 / m, n);
}

void nbep_physics_zero_momentum(nbep_state *s)
{
    double mass = 0.0;
    nbep_vec3 p = nbep_vec3_make(0.0, 0.0, 0.0);
    for (size_t i = 0; i < s->n; i++) {
        mass += s->mass[i];
        p = nbep_vec3_axpy(p, s->mass[i], s->vel[i]);
    }
    if (!(mass > 0.0))
        return;
    const nbep_vec3 vc = nbep_vec3_scale(p, 1.0 / mass);
    double before, after, pe;
    nbep_physics_energy(s, 0, s->n, &before, &pe);
    for (size_t i = 0; i < s->n; i++)
        s->vel[i] = nbep_vec3_sub(s->vel[i], vc);
    nbep_physics_energy(s, 0, s->n, &after, &pe);
    /* after = before - M |vc|^2 / 2 > 0 unless every sphere moved with vc (then none moves now,
     * and no factor brings the energy back) */
    if (!(after > 0.0) || after == before)
        return;
    const double f = sqrt(before / after);
    for (size_t i = 0; i < s->n; i++)
        s->vel[i] = nbep_vec3_scale(s->vel[i], f);
}

void nbep_physics_energy(const nbep_state *s, size_t lo, size_t hi, double *kinetic,
                         double *potential)
{
    assert(lo <= hi && hi <= s->n);
    double ke = 0.0, pe = 0.0;
    for (size_t i = lo; i < hi; i++) {
        double m = s->mass[i];
        ke += 0.5 * m * nbep_vec3_dot(s->vel[i], s->vel[i]);
        pe -= m * nbep_vec3_dot(s->acc[i], s->pos[i]);
        const int32_t *im = s->image + 3 * i;
        if (im[0] | im[1] | im[2]) /* a periodic box: the field acts on the unwrapped centre */
            pe -= m * nbep_vec3_dot(s->acc[i], nbep_vec3_make(im[0] * s->period[0],
                                                              im[1] * s->period[1],
                                                              im[2] * s->period[2]));
    }
    *kinetic = ke;
    *potential = pe;
}
