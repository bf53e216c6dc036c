/* The physics kernels every algorithm calls: free flight, sphere-sphere and sphere-plane
 * response (paper Section 5, restitution e) and energy. Pure functions on values; no
 * threads, no allocation. Contact times live in predict.h. */
#ifndef NBEP_PHYSICS_H
#define NBEP_PHYSICS_H

#include <stdbool.h>
#include <stddef.h>

#include "nbep/state.h"
#include "nbep/vec3.h"

/* Free flight for a time h under constant acceleration a:
 * p += v h + a h^2/2, v += a h. */
static inline void nbep_physics_drift(nbep_vec3 *p, nbep_vec3 *v, nbep_vec3 a, double h)
{
    double hh = 0.5 * h * h;
    p->x += v->x * h + a.x * hh;
    p->y += v->y * h + a.y * hh;
    p->z += v->z * h + a.z * hh;
    v->x += a.x * h;
    v->y += a.y * h;
    v->z += a.z * h;
}

/* Sphere-sphere response (paper Section 5): n is the unit vector from sphere 1 to sphere 2
 * (p2 - p1 normalised), c = n.(v1 - v2); when the pair closes by the test prediction uses,
 * (p2 - p1).(v2 - v1) < 0, v1 -= m2 c (1+e) n / (m1+m2), v2 += m1 c (1+e) n / (m1+m2) and
 * true is returned; otherwise nothing changes and false is returned (also when p1 == p2,
 * where n is undefined). Afterwards the pair never closes by that test (a residual of
 * round-off, e.g. with e = 0, is pushed out along n: see physics.c), so it is not predicted
 * to touch again at zero time. The result is bitwise the same whichever sphere is called "1". */
bool nbep_physics_respond_pair(nbep_vec3 p1, nbep_vec3 p2, nbep_vec3 *v1, nbep_vec3 *v2,
                               double m1, double m2, double e);

/* The response of a pair whose spheres lean on planes (issue 9): under an impulse J along
 * n = (p2 - p1)/|p2 - p1| sphere 1 moves by (J/m1) d1 and sphere 2 by (J/m2) d2, where d1
 * (d2) is what its frictionless plane contacts leave of -n (+n): the planes take the rest
 * and do no work, as the sphere does not move along their normals. With d1 = -n, d2 = n this
 * is nbep_physics_respond_pair. J makes the normal relative speed -e times what it was:
 * J = (1+e) c / (|d1|^2/m1 + |d2|^2/m2), since d1.n = -|d1|^2 and d2.n = |d2|^2 for a
 * projection onto a cone. With e = 1 kinetic energy is kept; momentum along the planes' normals
 * goes to them. Returns as nbep_physics_respond_pair; the same round-off tie rule applies
 * (along d1, d2). When both are zero (the pair cannot move along n at all) it responds freely.
 * *impulse is J as applied along d1 and d2 (so the planes took J (d1 + n) from sphere 1 and
 * J (d2 - n) from sphere 2), 0 where the pair responded freely or not at all. */
bool nbep_physics_respond_pair_along(nbep_vec3 p1, nbep_vec3 p2, nbep_vec3 *v1, nbep_vec3 *v2,
                                     double m1, double m2, double e, nbep_vec3 d1, nbep_vec3 d2,
                                     double *impulse);

/* SPEC /stats/virial's term for one pair's response, r12 . dp2 with r12 at contact: r12 the
 * line of centres from sphere 1 to sphere 2 as the response found it, dp2 the momentum sphere 2
 * received, sigma = r1 + r2. A response that happened overlapped (naive and seminaive find
 * contacts after the step's flight; the paper's step, run.order = "step", reacts to a shadowed
 * pair where it finds it) is taken at the touching distance, where it happens in SPEC's model:
 * r12 scaled to length sigma (the overlapped |r12| biases the pressure low, by the overlap).
 * 0 when p1 == p2 (no line of centres; the response did nothing). */
static inline double nbep_physics_virial_at_touch(nbep_vec3 r12, nbep_vec3 dp2, double sigma)
{
    const double dist = nbep_vec3_norm(r12);
    return dist > 0.0 ? nbep_vec3_dot(r12, dp2) * (sigma / dist) : 0.0;
}

/* Sphere-plane response: n is the plane's unit normal (into the live side); when v.n < 0,
 * v -= (1+e)(v.n) n and true is returned, else false. Afterwards v.n >= 0 exactly (a
 * round-off residual is pushed out, as for pairs). */
bool nbep_physics_respond_plane(nbep_vec3 n, nbep_vec3 *v, double e);

/* Signed gap between a sphere and a plane: n.p - offset - r (negative = overlapping). */
static inline double nbep_physics_plane_gap(nbep_vec3 n, double offset, nbep_vec3 p, double r)
{
    return nbep_vec3_dot(n, p) - offset - r;
}

/* Position projection for the detection algorithms (issue 9: spheres that rest must not sink):
 * a sphere found inside a plane is moved out along n to touch it; an overlapping pair is moved
 * apart along the line of centres to touch, each by the other's mass share (the centre of
 * mass stays). No change when not overlapping. */
void nbep_physics_separate_plane(nbep_vec3 n, double offset, nbep_vec3 *p, double r);
void nbep_physics_separate_pair(nbep_vec3 *p1, nbep_vec3 *p2, double r1, double r2, double m1,
                                double m2);

/* Kinetic (m v.v/2) and potential (-m a.p) energy of spheres [lo, hi), summed in index order
 * (so the same range always gives the same bits); p is the unwrapped centre in a periodic box
 * (pos + image * period), so that a sphere falling through a periodic face keeps its energy. */
void nbep_physics_energy(const nbep_state *s, size_t lo, size_t hi, double *kinetic,
                         double *potential);

/* Makes the spheres' total momentum zero: the centre of mass's velocity (sum m v / sum m) is
 * taken off every sphere's, and then all velocities are scaled by one factor to give back the
 * kinetic energy they had (a scaled set of velocities whose momentum is zero keeps it zero).
 * Nothing changes where no sphere moves. Sums in index order: the same bits every time. */
void nbep_physics_zero_momentum(nbep_state *s);

#endif
