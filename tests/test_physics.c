/* Collision response and energy against independent formulas: the centre-of-mass reflection
 * for the pair response, conservation laws, the (1 - e^2) loss of a partly elastic collision,
 * and hand-summed energies. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "nbep/physics.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

static nbep_vec3 unit(nbep_vec3 a)
{
    return nbep_vec3_scale(a, 1.0 / nbep_vec3_norm(a));
}

static double kinetic(double m1, nbep_vec3 v1, double m2, nbep_vec3 v2)
{
    return 0.5 * m1 * nbep_vec3_dot(v1, v1) + 0.5 * m2 * nbep_vec3_dot(v2, v2);
}

static void assert_vec_close(nbep_vec3 a, nbep_vec3 b, double atol)
{
    assert_close(a.x, b.x, 0.0, atol);
    assert_close(a.y, b.y, 0.0, atol);
    assert_close(a.z, b.z, 0.0, atol);
}

/* In the centre-of-mass frame a collision reverses the normal component of each velocity,
 * scaled by e: u' = u - (1+e)(u.n) n. A different route to the paper's formula. */
static void com_reflection(nbep_vec3 n, nbep_vec3 v1, nbep_vec3 v2, double m1, double m2,
                           double e, nbep_vec3 *w1, nbep_vec3 *w2)
{
    nbep_vec3 vcm = nbep_vec3_scale(nbep_vec3_add(nbep_vec3_scale(v1, m1),
                                                  nbep_vec3_scale(v2, m2)), 1.0 / (m1 + m2));
    nbep_vec3 u1 = nbep_vec3_sub(v1, vcm), u2 = nbep_vec3_sub(v2, vcm);
    *w1 = nbep_vec3_add(vcm, nbep_vec3_axpy(u1, -(1.0 + e) * nbep_vec3_dot(u1, n), n));
    *w2 = nbep_vec3_add(vcm, nbep_vec3_axpy(u2, -(1.0 + e) * nbep_vec3_dot(u2, n), n));
}

static void test_head_on_equal_masses_exchange_velocities_when_elastic(void **state)
{
    (void)state;
    nbep_vec3 p1 = {1.37, -0.42, 2.11}, p2 = {2.21, -0.42, 2.11};    /* n = +x */
    nbep_vec3 v1 = {1.93, 0.0, 0.0}, v2 = {-0.71, 0.0, 0.0};
    assert_true(nbep_physics_respond_pair(p1, p2, &v1, &v2, 1.7, 1.7, 1.0));
    assert_vec_close(v1, (nbep_vec3){-0.71, 0.0, 0.0}, 1e-15);
    assert_vec_close(v2, (nbep_vec3){1.93, 0.0, 0.0}, 1e-15);
}

static void test_oblique_elastic_response_matches_the_centre_of_mass_reflection(void **state)
{
    (void)state;
    nbep_vec3 p1 = {0.31, 1.27, -0.55}, p2 = {0.93, 1.61, -0.12};
    nbep_vec3 v1 = {1.13, -0.27, 0.61}, v2 = {-0.48, 0.92, -0.33};
    double m1 = 2.7, m2 = 0.83;
    nbep_vec3 w1, w2;
    com_reflection(unit(nbep_vec3_sub(p2, p1)), v1, v2, m1, m2, 1.0, &w1, &w2);
    double ke0 = kinetic(m1, v1, m2, v2);
    nbep_vec3 mom0 = nbep_vec3_add(nbep_vec3_scale(v1, m1), nbep_vec3_scale(v2, m2));

    assert_true(nbep_physics_respond_pair(p1, p2, &v1, &v2, m1, m2, 1.0));
    assert_vec_close(v1, w1, 1e-14);
    assert_vec_close(v2, w2, 1e-14);
    assert_close(kinetic(m1, v1, m2, v2), ke0, 1e-14, 0.0);
    assert_vec_close(nbep_vec3_add(nbep_vec3_scale(v1, m1), nbep_vec3_scale(v2, m2)), mom0,
                     1e-14);
}

/* The energy a collision removes is (1 - e^2) mu c^2 / 2, mu = m1 m2/(m1+m2), c the normal
 * closing speed; momentum is kept whatever e. */
static void test_partly_elastic_response_loses_one_minus_e_squared_of_normal_energy(void **state)
{
    (void)state;
    nbep_vec3 p1 = {0.31, 1.27, -0.55}, p2 = {0.93, 1.61, -0.12};
    double m1 = 2.7, m2 = 0.83;
    const double es[] = {0.0, 0.37, 0.81};
    for (size_t i = 0; i < sizeof es / sizeof es[0]; i++) {
        nbep_vec3 v1 = {1.13, -0.27, 0.61}, v2 = {-0.48, 0.92, -0.33};
        double c = nbep_vec3_dot(unit(nbep_vec3_sub(p2, p1)), nbep_vec3_sub(v1, v2));
        double mu = m1 * m2 / (m1 + m2);
        double ke0 = kinetic(m1, v1, m2, v2);
        nbep_vec3 mom0 = nbep_vec3_add(nbep_vec3_scale(v1, m1), nbep_vec3_scale(v2, m2));
        nbep_vec3 w1, w2;
        com_reflection(unit(nbep_vec3_sub(p2, p1)), v1, v2, m1, m2, es[i], &w1, &w2);

        assert_true(nbep_physics_respond_pair(p1, p2, &v1, &v2, m1, m2, es[i]));
        double lost = ke0 - kinetic(m1, v1, m2, v2);
        assert_close(lost, (1.0 - es[i] * es[i]) * 0.5 * mu * c * c, 1e-13, 0.0);
        assert_vec_close(nbep_vec3_add(nbep_vec3_scale(v1, m1), nbep_vec3_scale(v2, m2)), mom0,
                         1e-14);
        assert_vec_close(v1, w1, 1e-14);
        assert_vec_close(v2, w2, 1e-14);
    }
}

static void test_receding_pair_is_left_unchanged(void **state)
{
    (void)state;
    nbep_vec3 p1 = {0.31, 1.27, -0.55}, p2 = {0.93, 1.61, -0.12};
    const nbep_vec3 v1_in = {-1.13, 0.27, -0.61}, v2_in = {0.48, -0.92, 0.33};
    nbep_vec3 v1 = v1_in, v2 = v2_in;
    assert_false(nbep_physics_respond_pair(p1, p2, &v1, &v2, 2.7, 0.83, 1.0));
    assert_memory_equal(&v1, &v1_in, sizeof v1);
    assert_memory_equal(&v2, &v2_in, sizeof v2);
    /* Sliding past each other (no normal component) is not a collision either. */
    nbep_vec3 s1 = {0.0, 0.0, 1.0}, s2 = {0.0, 0.0, -1.0};
    nbep_vec3 q1 = {0.0, 0.0, 0.0}, q2 = {0.83, 0.0, 0.0};
    assert_false(nbep_physics_respond_pair(q1, q2, &s1, &s2, 1.0, 1.0, 1.0));
}

static void test_coincident_centres_have_no_normal_and_no_response(void **state)
{
    (void)state;
    nbep_vec3 p = {0.31, 1.27, -0.55};
    nbep_vec3 v1 = {1.13, -0.27, 0.61}, v2 = {-0.48, 0.92, -0.33};
    const nbep_vec3 v1_in = v1, v2_in = v2;
    assert_false(nbep_physics_respond_pair(p, p, &v1, &v2, 2.7, 0.83, 1.0));
    assert_memory_equal(&v1, &v1_in, sizeof v1);
    assert_memory_equal(&v2, &v2_in, sizeof v2);
}

/* splitmix64 */
static double uniform(uint64_t *s, double lo, double hi)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15u);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) * 0x1.0p-53;
}

/* Whichever sphere a caller names first, the same bits come out: frames must not depend on
 * which thread visits a pair. Positions share coordinates in some cases so that the ordering's
 * tie-breaks are exercised. */
static void test_swapping_the_spheres_gives_bitwise_the_same_velocities(void **state)
{
    (void)state;
    uint64_t s = 11;
    int responded = 0;
    for (int i = 0; i < 5000; i++) {
        nbep_vec3 p1 = {uniform(&s, -2, 2), uniform(&s, -2, 2), uniform(&s, -2, 2)};
        nbep_vec3 p2 = {uniform(&s, -2, 2), uniform(&s, -2, 2), uniform(&s, -2, 2)};
        if (i % 3 != 0)
            p2.x = p1.x;
        if (i % 3 == 2)
            p2.y = p1.y;
        nbep_vec3 v1 = {uniform(&s, -3, 3), uniform(&s, -3, 3), uniform(&s, -3, 3)};
        nbep_vec3 v2 = {uniform(&s, -3, 3), uniform(&s, -3, 3), uniform(&s, -3, 3)};
        double m1 = uniform(&s, 0.1, 5), m2 = uniform(&s, 0.1, 5), e = uniform(&s, 0, 1);
        nbep_vec3 a1 = v1, a2 = v2, b1 = v1, b2 = v2;
        bool ra = nbep_physics_respond_pair(p1, p2, &a1, &a2, m1, m2, e);
        bool rb = nbep_physics_respond_pair(p2, p1, &b2, &b1, m2, m1, e);
        assert_true(ra == rb);
        assert_memory_equal(&a1, &b1, sizeof a1);
        assert_memory_equal(&a2, &b2, sizeof a2);
        responded += ra;
    }
    assert_true(responded > 1000);
}

static void test_plane_response_reverses_the_normal_component_times_e(void **state)
{
    (void)state;
    nbep_vec3 n = unit((nbep_vec3){0.3, -0.2, 0.93});
    const double es[] = {1.0, 0.63, 0.0};
    for (size_t i = 0; i < sizeof es / sizeof es[0]; i++) {
        nbep_vec3 v = {1.1, -0.4, -2.3};
        double vn = nbep_vec3_dot(v, n);
        nbep_vec3 tangential = nbep_vec3_axpy(v, -vn, n);
        assert_true(nbep_physics_respond_plane(n, &v, es[i]));
        assert_close(nbep_vec3_dot(v, n), -es[i] * vn, 1e-14, 1e-15);
        assert_vec_close(nbep_vec3_axpy(v, -nbep_vec3_dot(v, n), n), tangential, 1e-15);
    }
}

/* At e = 0 against a plane across an axis the normal speed ends exactly 0: the sphere slides
 * on, in contact. The push that separates a pair still closing by round-off (TIE_TRIES) is
 * for a normal speed below 0 only; one at exactly 0 pushed off by an ulp's speed would hop. */
static void test_plane_response_at_e_0_ends_sliding_with_no_push(void **state)
{
    (void)state;
    const nbep_vec3 ns[3] = {{0.0, 0.0, 1.0}, {-1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}};
    for (int k = 0; k < 3; k++) {
        nbep_vec3 v = nbep_vec3_axpy((nbep_vec3){0.3, -0.7, 0.45}, -1.7, ns[k]);
        const nbep_vec3 slide = nbep_vec3_axpy(v, -nbep_vec3_dot(v, ns[k]), ns[k]);
        assert_true(nbep_physics_respond_plane(ns[k], &v, 0.0));
        assert_true(nbep_vec3_dot(v, ns[k]) == 0.0);
        assert_vec_close(v, slide, 0.0);
    }
}

static void test_plane_response_leaves_a_leaving_or_sliding_sphere_alone(void **state)
{
    (void)state;
    nbep_vec3 n = {0.0, 0.0, 1.0};
    const nbep_vec3 up = {0.3, -0.7, 1.2}, along = {0.3, -0.7, 0.0};
    nbep_vec3 v = up;
    assert_false(nbep_physics_respond_plane(n, &v, 0.8));
    assert_memory_equal(&v, &up, sizeof v);
    v = along;
    assert_false(nbep_physics_respond_plane(n, &v, 0.8));
    assert_memory_equal(&v, &along, sizeof v);
}

static void test_energy_of_a_known_configuration_is_summed_by_hand(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_state s;
    assert_int_equal(nbep_state_init(&s, 3, 0, &d), NBEP_OK);
    const double m[3] = {1.3, 0.7, 2.1};
    const nbep_vec3 p[3] = {{0.5, 1.5, 2.5}, {-1.0, 0.25, 4.0}, {3.0, -2.0, 0.75}};
    const nbep_vec3 v[3] = {{1.0, -2.0, 0.5}, {0.0, 0.0, -3.0}, {0.25, 0.5, 1.5}};
    const nbep_vec3 a[3] = {{0.0, 0.0, -9.81}, {0.0, 0.0, -9.81}, {0.0, -1.0, 0.0}};
    for (int i = 0; i < 3; i++) {
        s.mass[i] = m[i];
        s.pos[i] = p[i];
        s.vel[i] = v[i];
        s.acc[i] = a[i];
    }
    /* m v.v/2: 1.3 * 5.25/2, 0.7 * 9/2, 2.1 * 2.5625/2; -m a.p: 1.3*9.81*2.5, 0.7*9.81*4,
     * 2.1 * 1 * (-2). */
    double ke = 1.3 * 5.25 / 2 + 0.7 * 9.0 / 2 + 2.1 * 2.5625 / 2;
    double pe = 1.3 * 9.81 * 2.5 + 0.7 * 9.81 * 4.0 + 2.1 * -2.0;
    double k = NAN, u = NAN;
    nbep_physics_energy(&s, 0, 3, &k, &u);
    assert_close(k, ke, 1e-14, 0.0);
    assert_close(u, pe, 1e-14, 0.0);
    nbep_physics_energy(&s, 1, 2, &k, &u);
    assert_close(k, 0.7 * 9.0 / 2, 1e-15, 0.0);
    assert_close(u, 0.7 * 9.81 * 4.0, 1e-15, 0.0);
    nbep_physics_energy(&s, 2, 2, &k, &u);
    assert_true(k == 0.0 && u == 0.0);
    /* in a periodic box the field acts on the unwrapped centre, pos + image * period, each
     * axis its own period (a box of sides 2, 5 and 7; one image along each of the spheres'
     * field axes, the third sphere's along y, where its field is) */
    s.period[0] = 2.0;
    s.period[1] = 5.0;
    s.period[2] = 7.0;
    const int32_t im[3][3] = {{1, 0, 0}, {0, 0, -1}, {0, 3, 2}};
    for (int i = 0; i < 3; i++)
        for (int k3 = 0; k3 < 3; k3++)
            s.image[3 * i + k3] = im[i][k3];
    nbep_physics_energy(&s, 0, 3, &k, &u);
    assert_close(k, ke, 1e-14, 0.0);
    assert_close(u, 1.3 * 9.81 * 2.5 + 0.7 * 9.81 * (4.0 - 7.0) + 2.1 * (-2.0 + 3 * 5.0), 1e-14,
                 0.0);
    nbep_state_fini(&s);
    nbep_diag_fini(&d);
}

/* physics.zero_momentum: by hand, three spheres of masses 1, 2 and 1 moving along x at 3, 0
 * and -1 have momentum 2 over mass 4, a centre of mass at 0.5; less it, 2.5, -0.5 and -1.5,
 * kinetic energy 3.125 + 0.25 + 1.125 = 4.5 against 5 before, so each velocity is scaled by
 * sqrt(5 / 4.5). The velocities' other components, zero, stay zero; relative velocities keep
 * their directions. Round-off: a few ulps of the largest term (1e-15 relative). */
static void test_zero_momentum_takes_off_the_centre_of_mass_and_keeps_the_energy(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_state s;
    assert_int_equal(nbep_state_init(&s, 3, 0, &d), NBEP_OK);
    const double m[3] = {1.0, 2.0, 1.0}, vx[3] = {3.0, 0.0, -1.0}, u[3] = {2.5, -0.5, -1.5};
    for (int i = 0; i < 3; i++) {
        s.mass[i] = m[i];
        s.vel[i] = nbep_vec3_make(vx[i], 0.0, 0.0);
    }
    nbep_physics_zero_momentum(&s);
    const double f = sqrt(5.0 / 4.5);
    for (int i = 0; i < 3; i++)
        assert_vec_close(s.vel[i], nbep_vec3_make(u[i] * f, 0.0, 0.0), 1e-15 * 3.0);
    double k = NAN, pe = NAN;
    nbep_physics_energy(&s, 0, 3, &k, &pe);
    assert_close(k, 5.0, 1e-15, 0.0);

    /* every sphere moving with the centre of mass: none moves after, and no factor is applied
     * to nothing (no NaN from 0/0) */
    for (int i = 0; i < 3; i++)
        s.vel[i] = nbep_vec3_make(1.0, -2.0, 0.5);
    nbep_physics_zero_momentum(&s);
    for (int i = 0; i < 3; i++)
        assert_vec_close(s.vel[i], nbep_vec3_make(0.0, 0.0, 0.0), 1e-15 * 2.0);
    /* none moving: unchanged */
    nbep_physics_zero_momentum(&s);
    for (int i = 0; i < 3; i++)
        assert_true(isfinite(s.vel[i].x) && isfinite(s.vel[i].y) && isfinite(s.vel[i].z));
    nbep_state_fini(&s);

    /* a gas of 1000 of mixed masses in random directions: total momentum at round-off of the
     * momenta summed (1e-13 of sum m |v|), energy kept (1e-13), and relative velocities
     * v_i - v_0 all scaled by one factor from the originals' */
    const size_t n = 1000;
    assert_int_equal(nbep_state_init(&s, n, 0, &d), NBEP_OK);
    nbep_vec3 *v0 = test_malloc(n * sizeof *v0);
    uint64_t x = 7;
    double e0 = 0.0, scale = 0.0;
    for (size_t i = 0; i < n; i++) {
        s.mass[i] = 0.5 + 1.5 * nbep_test_uniform(&x);
        v0[i] = s.vel[i] = nbep_test_random_velocity(&x, 1.0 + nbep_test_uniform(&x));
        e0 += 0.5 * s.mass[i] * nbep_vec3_dot(v0[i], v0[i]);
        scale += s.mass[i] * nbep_vec3_norm(v0[i]);
    }
    nbep_physics_zero_momentum(&s);
    nbep_vec3 p = nbep_vec3_make(0.0, 0.0, 0.0);
    for (size_t i = 0; i < n; i++)
        p = nbep_vec3_axpy(p, s.mass[i], s.vel[i]);
    assert_true(nbep_vec3_norm(p) <= 1e-13 * scale);
    nbep_physics_energy(&s, 0, n, &k, &pe);
    assert_close(k, e0, 1e-13, 0.0);
    const nbep_vec3 r0 = nbep_vec3_sub(v0[1], v0[0]), r = nbep_vec3_sub(s.vel[1], s.vel[0]);
    const double g = nbep_vec3_norm(r) / nbep_vec3_norm(r0);
    assert_true(g > 1.0); /* the centre of mass's energy given back to the rest */
    for (size_t i = 1; i < n; i++)
        assert_vec_close(nbep_vec3_sub(s.vel[i], s.vel[0]),
                         nbep_vec3_scale(nbep_vec3_sub(v0[i], v0[0]), g), 1e-13 * 4.0);
    test_free(v0);
    nbep_state_fini(&s);
    nbep_diag_fini(&d);
}

/* Free flight under constant acceleration, checked by kinematic identities rather than the
 * position formula: v - v0 = a h (the definition of constant acceleration), p - p0 = h (v0 + v)/2
 * (the displacement is the mean velocity times the time, exact for constant acceleration),
 * flying back by -h returns to the start, and E = m v.v/2 - m a.p is kept, all to round-off
 * (a few ulps of the largest term: 1e-15 relative, 1e-14 for the energy's cancellation). */
static void test_free_flight_follows_the_kinematic_formula_and_keeps_energy(void **state)
{
    (void)state;
    nbep_vec3 p0 = {0.31, 1.27, -0.55}, v0 = {1.13, -0.27, 0.61}, a = {0.2, -0.1, -9.81};
    nbep_vec3 p = p0, v = v0;
    double h = 0.0137;
    nbep_physics_drift(&p, &v, a, h);
    nbep_vec3 dv = nbep_vec3_sub(v, v0), dp = nbep_vec3_sub(p, p0);
    assert_vec_close(dv, nbep_vec3_scale(a, h), 1e-13);
    assert_vec_close(dp, nbep_vec3_scale(nbep_vec3_add(v0, v), 0.5 * h), 1e-13);
    nbep_vec3 pb = p, vb = v;
    nbep_physics_drift(&pb, &vb, a, -h);
    assert_vec_close(pb, p0, 1e-15);
    assert_vec_close(vb, v0, 1e-15);
    double e0 = 0.5 * nbep_vec3_dot(v0, v0) - nbep_vec3_dot(a, p0);
    double e1 = 0.5 * nbep_vec3_dot(v, v) - nbep_vec3_dot(a, p);
    assert_close(e1, e0, 1e-14, 0.0);
}

/* The gap of a sphere to a plane, from a point built at a known height: q on the plane (its
 * foot, offset n, moved along the plane by two vectors orthogonal to n) raised by d along n
 * is d from the plane, so its gap is d - r; below the plane it is negative. */
/* A deterministic stream of doubles in (-1, 1) (xorshift64*), for the bias tests below. */
static double next_uniform(uint64_t *x)
{
    *x ^= *x >> 12;
    *x ^= *x << 25;
    *x ^= *x >> 27;
    return (double)((*x * 2685821657736338717ull) >> 11) * 0x1p-52 - 1.0;
}

static nbep_vec3 next_vec(uint64_t *x)
{
    const double a = next_uniform(x), b = next_uniform(x), c = next_uniform(x);
    return (nbep_vec3){a, b, c};
}

static long double kinetic_ld(nbep_vec3 v)
{
    return (long double)v.x * v.x + (long double)v.y * v.y + (long double)v.z * v.z;
}

/* Elastic responses keep the kinetic energy on average to far below round-off of one: the mean
 * relative change over 200000 random contacts (normals made as the pair's are, a vector over
 * its rounded length), and over 200000 bounces off each of five planes whose normals are made
 * as a deck's, is below 2e-18. A rounded normal is a unit vector only to an ulp or two,
 * |n|^2 - 1 was positive on average, and a response along it (taken as unit) added 3.2e-17 of
 * the energy per collision here, and 1.2e-16 to 3.6e-16 per bounce off each plane but two:
 * an elastic fluid's drift grew linearly with its collisions, past 1e-12 in a million (a
 * review, 2026-12-02). With the excess taken in a second rounding, 3.6e-18 and up to
 * 1.4e-17 (a (1, 2, 3) plane); rounded once, below 7e-19. Each change is some 1e-16 at
 * random, so a mean of 200000 is known to a few 1e-19. */
static void test_elastic_responses_add_no_energy_on_average(void **state)
{
    (void)state;
    const int N = 200000;
    uint64_t x = 88172645463325252ull;
    long double pair = 0.0L, plane = 0.0L;
    for (int i = 0; i < N; i++) {
        const nbep_vec3 d = next_vec(&x), p2 = unit(d);
        nbep_vec3 v1 = next_vec(&x), v2 = next_vec(&x);
        const long double e0 = kinetic_ld(v1) + kinetic_ld(v2);
        if (nbep_physics_respond_pair((nbep_vec3){0, 0, 0}, p2, &v1, &v2, 1.0, 1.0, 1.0))
            pair += (kinetic_ld(v1) + kinetic_ld(v2) - e0) / e0;
        const nbep_vec3 n = unit(next_vec(&x));
        nbep_vec3 v = next_vec(&x);
        const long double k0 = kinetic_ld(v);
        if (nbep_vec3_dot(v, n) > 0.0)
            v = nbep_vec3_scale(v, -1.0); /* heading into the plane */
        if (nbep_physics_respond_plane(n, &v, 1.0))
            plane += (kinetic_ld(v) - k0) / k0;
    }
    print_message("mean relative energy change: pair %.3Le, plane %.3Le\n", pair / N,
                  plane / N);
    assert_true(fabsl(pair / N) < 2e-18L);
    assert_true(fabsl(plane / N) < 2e-18L);
    /* a deck's plane is one normal for every bounce, made as scene.c makes it (over its
     * largest component, then over its rounded length): its |n|^2 - 1 is one value, whose
     * sign every bounce shared, (1, 1, 1) among them */
    const nbep_vec3 decks[] = {{1, 1, 1}, {1, 2, 3}, {0, 1, 1}, {-1, 0.5, 2}, {3, -7, 1}};
    for (size_t k = 0; k < sizeof decks / sizeof *decks; k++) {
        const double big = fmax(fabs(decks[k].x), fmax(fabs(decks[k].y), fabs(decks[k].z)));
        const nbep_vec3 u = nbep_vec3_scale(decks[k], 1.0 / big);
        const nbep_vec3 n = {u.x / nbep_vec3_norm(u), u.y / nbep_vec3_norm(u),
                             u.z / nbep_vec3_norm(u)};
        long double one = 0.0L;
        for (int i = 0; i < N; i++) {
            nbep_vec3 v = next_vec(&x);
            const long double k0 = kinetic_ld(v);
            if (nbep_vec3_dot(v, n) > 0.0)
                v = nbep_vec3_scale(v, -1.0);
            if (nbep_physics_respond_plane(n, &v, 1.0))
                one += (kinetic_ld(v) - k0) / k0;
        }
        print_message("plane (%g, %g, %g): %.3Le\n", decks[k].x, decks[k].y, decks[k].z,
                      one / N);
        assert_true(fabsl(one / N) < 2e-18L);
    }
}

static void test_plane_gap_is_signed_distance_less_radius(void **state)
{
    (void)state;
    const nbep_vec3 n = {0.0, 0.6, 0.8}, u1 = {1.0, 0.0, 0.0}, u2 = {0.0, 0.8, -0.6};
    const double offset = 0.9, r = 0.35;
    const double heights[3] = {2.5, 0.35, -0.2};
    for (int k = 0; k < 3; k++) {
        nbep_vec3 q = nbep_vec3_add(nbep_vec3_scale(n, offset),
                                    nbep_vec3_add(nbep_vec3_scale(u1, 1.7),
                                                  nbep_vec3_scale(u2, -0.4)));
        nbep_vec3 p = nbep_vec3_axpy(q, heights[k], n);
        assert_close(nbep_physics_plane_gap(n, offset, p, r), heights[k] - r, 0.0, 1e-15);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_head_on_equal_masses_exchange_velocities_when_elastic),
        cmocka_unit_test(test_oblique_elastic_response_matches_the_centre_of_mass_reflection),
        cmocka_unit_test(test_partly_elastic_response_loses_one_minus_e_squared_of_normal_energy),
        cmocka_unit_test(test_receding_pair_is_left_unchanged),
        cmocka_unit_test(test_coincident_centres_have_no_normal_and_no_response),
        cmocka_unit_test(test_swapping_the_spheres_gives_bitwise_the_same_velocities),
        cmocka_unit_test(test_plane_response_reverses_the_normal_component_times_e),
        cmocka_unit_test(test_plane_response_at_e_0_ends_sliding_with_no_push),
        cmocka_unit_test(test_plane_response_leaves_a_leaving_or_sliding_sphere_alone),
        cmocka_unit_test(test_energy_of_a_known_configuration_is_summed_by_hand),
        cmocka_unit_test(test_zero_momentum_takes_off_the_centre_of_mass_and_keeps_the_energy),
        cmocka_unit_test(test_free_flight_follows_the_kinematic_formula_and_keeps_energy),
        cmocka_unit_test(test_plane_gap_is_signed_distance_less_radius),
        cmocka_unit_test(test_elastic_responses_add_no_energy_on_average),
    };
    return cmocka_run_group_tests_name("physics", tests, NULL, NULL);
}
