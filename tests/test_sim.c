/* End-to-end runs on scenes built in the test: analytic outcomes (a bounce, a head-on and an
 * oblique collision), conservation laws, exactly-once reactions across threads, and frames
 * bitwise identical for any thread count and between naive and seminaive. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/grid.h"
#include "nbep/sim.h"
#include "nbep/stats.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

/* Every frame's positions and velocities, appended. */
typedef nbep_test_frames frames;

/* Runs sc with nt threads; returns its summary, final state in *final (caller finis) and
 * frames in *fr (may be NULL). */
static uint64_t last_reactions;

static nbep_summary run(const nbep_scene *sc, int nt, nbep_state *final, frames *fr)
{
    return nbep_test_run(sc, nt, fr ? nbep_test_keep_frame : NULL, fr, final, &last_reactions);
}

static const nbep_vec3 ZERO = {0.0, 0.0, 0.0};

/* One sphere dropped from rest onto a floor under gravity g with restitution e: it lands at
 * t1 = sqrt(2 h / g), leaves with speed e g t1 and lands again 2 e t1 later. At T between the
 * landings its height is r + v1 (T - t1) - g (T - t1)^2 / 2 with v1 = e g t1. */
static void test_predictive_bounce_matches_the_analytic_flight(void **state)
{
    (void)state;
    const double g = 9.81, e = 0.83, r = 0.1, z0 = 2.37, dt = 1e-3;
    nbep_scene *sc = nbep_test_scene_new(1, 1, "predictive", 1000, dt);
    sc->restitution = e;
    nbep_test_set_plane(sc, 0, (nbep_vec3){0, 0, 1}, 0.0);
    nbep_test_set_sphere(sc, 0, (nbep_vec3){0.3, -0.2, z0}, ZERO, r, 1.7, (nbep_vec3){0, 0, -g});
    nbep_state fin;
    nbep_summary sum = run(sc, 1, &fin, NULL);
    double t1 = sqrt(2.0 * (z0 - r) / g), v1 = e * g * t1, T = 1000 * dt;
    assert_true(T > t1 && T < t1 + 2.0 * v1 / g);
    double z = r + v1 * (T - t1) - 0.5 * g * (T - t1) * (T - t1);
    /* exact up to round-off of a few free flights: 1e-12 relative to the drop height */
    assert_close(fin.pos[0].z, z, 0.0, 1e-12 * z0);
    assert_close(fin.vel[0].z, v1 - g * (T - t1), 0.0, 1e-12 * g);
    assert_int_equal(sum.plane_collisions, 1);
    assert_int_equal(sum.sphere_collisions, 0);
    nbep_state_fini(&fin);
    nbep_test_scene_free(&sc);
}

/* The naive algorithm detects the landing only after the sphere overlaps the floor, so its
 * height after the bounce lags by at most one step of fall: |error| <= v dt + g dt^2. */
static void test_naive_bounce_is_within_one_step_of_the_analytic_flight(void **state)
{
    (void)state;
    const double g = 9.81, e = 0.83, r = 0.1, z0 = 2.37, dt = 1e-3;
    nbep_scene *sc = nbep_test_scene_new(1, 1, "naive", 1000, dt);
    sc->restitution = e;
    nbep_test_set_plane(sc, 0, (nbep_vec3){0, 0, 1}, 0.0);
    nbep_test_set_sphere(sc, 0, (nbep_vec3){0.3, -0.2, z0}, ZERO, r, 1.7, (nbep_vec3){0, 0, -g});
    nbep_state fin;
    nbep_summary sum = run(sc, 1, &fin, NULL);
    double t1 = sqrt(2.0 * (z0 - r) / g), v1 = e * g * t1, T = 1000 * dt;
    double z = r + v1 * (T - t1) - 0.5 * g * (T - t1) * (T - t1);
    double vland = g * t1;
    assert_close(fin.pos[0].z, z, 0.0, 2.0 * (vland * dt + g * dt * dt));
    assert_int_equal(sum.plane_collisions, 1);
    nbep_state_fini(&fin);
    nbep_test_scene_free(&sc);
}

/* Head-on, equal masses, e = 1: the spheres exchange velocities at contact. Sphere 0 sits in
 * thread 0's range, sphere 300 in thread 1's (blocks of 256), and both slots name each other:
 * exactly one reaction must happen, on any number of threads. */
static void test_head_on_pair_across_threads_reacts_exactly_once(void **state)
{
    (void)state;
    const size_t n = 301;
    for (int nt = 1; nt <= 4; nt *= 2) {
        nbep_scene *sc = nbep_test_scene_new(n, 0, "predictive", 500, 1e-3);
        /* idle spheres far away, at rest, spaced apart */
        for (size_t i = 1; i < n - 1; i++)
            nbep_test_set_sphere(sc, i, (nbep_vec3){100.0 + 3.0 * (double)i, 50.0, 0.0}, ZERO, 0.5, 1.0,
                       ZERO);
        nbep_test_set_sphere(sc, 0, (nbep_vec3){-1.31, 0, 0}, (nbep_vec3){2.9, 0, 0}, 0.25, 1.3, ZERO);
        nbep_test_set_sphere(sc, n - 1, (nbep_vec3){1.17, 0, 0}, (nbep_vec3){-1.7, 0, 0}, 0.25, 1.3,
                   ZERO);
        nbep_state fin;
        nbep_summary sum = run(sc, nt, &fin, NULL);
        assert_int_equal(sum.sphere_collisions, 1);
        assert_int_equal(last_reactions, 1); /* both slots named the pair: one reaction */
        /* contact when the gap 2.48 - 0.5 closes at 4.6: tc = 1.98 / 4.6 */
        double tc = 1.98 / 4.6, T = 0.5;
        assert_close(fin.vel[0].x, -1.7, 1e-14, 0.0);
        assert_close(fin.vel[n - 1].x, 2.9, 1e-14, 0.0);
        assert_close(fin.pos[0].x, -1.31 + 2.9 * tc - 1.7 * (T - tc), 0.0, 1e-13);
        assert_close(fin.pos[n - 1].x, 1.17 - 1.7 * tc + 2.9 * (T - tc), 0.0, 1e-13);
        nbep_state_fini(&fin);
        nbep_test_scene_free(&sc);
    }
}

/* An oblique collision of unequal masses (e = 1): momentum and kinetic energy are conserved,
 * and the light sphere, at rest before, leaves along the line of centres at contact. */
static void test_oblique_unequal_masses_conserve_momentum_and_energy(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_scene_new(2, 0, "predictive", 2000, 1e-3);
    nbep_test_set_sphere(sc, 0, ZERO, (nbep_vec3){2.0, 0, 0}, 0.3, 3.0, ZERO);
    nbep_test_set_sphere(sc, 1, (nbep_vec3){2.0, 0.15, 0}, ZERO, 0.2, 1.0, ZERO);
    nbep_state fin;
    nbep_summary sum = run(sc, 1, &fin, NULL);
    assert_int_equal(sum.sphere_collisions, 1);
    nbep_vec3 p = nbep_vec3_add(nbep_vec3_scale(fin.vel[0], 3.0), fin.vel[1]);
    assert_close(p.x, 6.0, 1e-14, 0.0);
    assert_close(p.y, 0.0, 0.0, 1e-14);
    double ke = 0.5 * 3.0 * nbep_vec3_norm2(fin.vel[0]) + 0.5 * nbep_vec3_norm2(fin.vel[1]);
    assert_close(ke, 6.0, 1e-14, 0.0);
    /* line of centres at contact: dy = 0.15, dx = sqrt(0.25 - 0.0225) */
    double dx = sqrt(0.25 - 0.0225);
    assert_close(fin.vel[1].y / fin.vel[1].x, 0.15 / dx, 1e-12, 0.0);
    /* light sphere speed from 1-D elastic collision along the normal: 2 m1/(m1+m2) u_n */
    double un = 2.0 * dx / 0.5;
    assert_close(nbep_vec3_norm(fin.vel[1]), 2.0 * 3.0 / 4.0 * un, 1e-12, 0.0);
    nbep_state_fini(&fin);
    nbep_test_scene_free(&sc);
}

/* A gas of n spheres in a closed box, random but fixed positions (a lattice jittered by a
 * hash of the index) and velocities. */
static nbep_scene *gas(const char *algo, size_t n, double g, uint64_t steps)
{
    nbep_scene *sc = nbep_test_scene_new(n, 6, algo, steps, 2e-3);
    const double L = 4.0;
    nbep_test_set_box(sc, L);
    size_t side = (size_t)ceil(cbrt((double)n));
    double h = L / (double)side;
    uint64_t x = 88172645463325252u;
    for (size_t i = 0; i < n; i++) {
        double u[6];
        for (int k = 0; k < 6; k++)
            u[k] = nbep_test_uniform(&x);
        nbep_vec3 p = {h * ((double)(i % side) + 0.3 + 0.4 * u[0]),
                       h * ((double)(i / side % side) + 0.3 + 0.4 * u[1]),
                       h * ((double)(i / side / side) + 0.3 + 0.4 * u[2])};
        nbep_vec3 v = {6.0 * (u[3] - 0.5), 6.0 * (u[4] - 0.5), 6.0 * (u[5] - 0.5)};
        nbep_test_set_sphere(sc, i, p, v, 0.1 * h * (1.0 + 0.5 * u[0]), 1.0 + u[1], (nbep_vec3){0, 0, -g});
    }
    return sc;
}

static void frames_equal(const frames *a, const frames *b)
{
    assert_int_equal(a->n_frames, b->n_frames);
    assert_int_equal(a->n, b->n);
    assert_memory_equal(a->data, b->data, a->n_frames * 2 * a->n * sizeof *a->data);
}

static void same_frames_for_threads(const char *algo, size_t n, double g, const int *nts,
                                    size_t count)
{
    nbep_scene *sc = gas(algo, n, g, nbep_test_scaled(300, 40));
    frames ref = {0};
    nbep_summary s1 = run(sc, nts[0], NULL, &ref);
    assert_true(s1.collisions > 0); /* otherwise the comparison proves little */
    for (size_t k = 1; k < count; k++) {
        frames f = {0};
        nbep_summary sk = run(sc, nts[k], NULL, &f);
        frames_equal(&ref, &f);
        assert_int_equal(sk.collisions, s1.collisions);
        assert_int_equal(sk.checks, s1.checks);
        nbep_test_frames_free(&f);
    }
    nbep_test_frames_free(&ref);
    nbep_test_scene_free(&sc);
}

static void test_naive_frames_are_bitwise_equal_for_1_2_4_threads(void **state)
{
    (void)state;
    const int nts[] = {1, 2, 4};
    same_frames_for_threads("naive", nbep_test_scaled(700, 300), 9.81, nts, 3);
}

static void test_seminaive_frames_are_bitwise_equal_for_1_2_4_threads(void **state)
{
    (void)state;
    const int nts[] = {1, 2, 4};
    same_frames_for_threads("seminaive", nbep_test_scaled(700, 300), 9.81, nts, 3);
}

static void test_predictive_frames_are_bitwise_equal_for_1_2_4_8_threads(void **state)
{
    (void)state;
    const int nts[] = {1, 2, 4, 8};
    same_frames_for_threads("predictive", nbep_test_scaled(700, 300), 9.81, nts, 4);
}

/* More threads than detection rows: the rows are split by their pair tests, so two spheres on
 * 3 or 4 threads leave threads with none (naive's second row tests nothing; seminaive's rows
 * cost alike, and 2 rows cannot go round 3 threads). A thread without rows starts an empty
 * contact list, and the run is the 1-thread run bit for bit: the head-on pair meets once. */
static void test_detection_on_more_threads_than_rows_gives_the_one_thread_run(void **state)
{
    (void)state;
    const char *const algos[] = {"naive", "seminaive"};
    for (int a = 0; a < 2; a++) {
        nbep_scene *sc = nbep_test_scene_new(2, 0, algos[a], 500, 1e-3);
        nbep_test_set_sphere(sc, 0, (nbep_vec3){-1.31, 0, 0}, (nbep_vec3){2.9, 0, 0}, 0.25, 1.3,
                             ZERO);
        nbep_test_set_sphere(sc, 1, (nbep_vec3){1.17, 0, 0}, (nbep_vec3){-1.7, 0, 0}, 0.25, 1.3,
                             ZERO);
        frames ref = {0};
        nbep_summary s1 = run(sc, 1, NULL, &ref);
        assert_int_equal(s1.sphere_collisions, 1);
        for (int nt = 2; nt <= 4; nt++) {
            frames f = {0};
            nbep_summary sk = run(sc, nt, NULL, &f);
            frames_equal(&ref, &f);
            assert_int_equal(sk.sphere_collisions, 1);
            assert_int_equal(sk.checks, s1.checks);
            nbep_test_frames_free(&f);
        }
        nbep_test_frames_free(&ref);
        nbep_test_scene_free(&sc);
    }
}

/* The summary's clocks (SPEC: setup_seconds, the create and, for predictive, the first
 * predictions; wall_seconds, the steps) are spans within the run: neither below zero, both
 * together within the time measured around it. Their values are the machine's; what is held is
 * that each is a difference of two readings of the clock (a reading added instead, as a
 * mutant of the tenth draw did, reports twice the machine's uptime). */
static void test_the_set_up_and_stepping_clocks_lie_within_the_run(void **state)
{
    (void)state;
    const char *const algos[] = {"naive", "predictive"};
    for (int a = 0; a < 2; a++) {
        nbep_scene *sc = nbep_test_fluid(4, 0.3, 5, 0.01);
        snprintf(sc->algorithm, sizeof sc->algorithm, "%s", algos[a]);
        const double t0 = nbep_now();
        nbep_summary s = run(sc, 2, NULL, NULL);
        const double spent = nbep_now() - t0;
        if (!(s.setup_seconds >= 0.0 && s.wall_seconds >= 0.0 &&
              s.setup_seconds + s.wall_seconds <= spent))
            fail_msg("%s: setup %g s and steps %g s, in a run of %g s", algos[a],
                     s.setup_seconds, s.wall_seconds, spent);
        nbep_test_scene_free(&sc);
    }
}

/* Seminaive pre-filters naive's tests but must find, and answer, exactly the same pairs in
 * the same order: the frames are bitwise the naive ones, with fewer checks. */
static void test_seminaive_frames_equal_naive_frames_with_fewer_checks(void **state)
{
    (void)state;
    size_t n = nbep_test_scaled(800, 300);
    nbep_scene *a = gas("naive", n, 9.81, nbep_test_scaled(200, 30));
    nbep_scene *b = gas("seminaive", n, 9.81, nbep_test_scaled(200, 30));
    frames fa = {0}, fb = {0};
    nbep_summary sa = run(a, 2, NULL, &fa), sb = run(b, 2, NULL, &fb);
    frames_equal(&fa, &fb);
    assert_int_equal(sa.collisions, sb.collisions);
    assert_true(sb.checks < sa.checks);
    nbep_test_frames_free(&fa), nbep_test_frames_free(&fb);
    nbep_test_scene_free(&a), nbep_test_scene_free(&b);
}

/* The detection algorithms on a crowded scene (a closed-box fluid at phi = 0.35, where every
 * sphere meets several others each step and many overlaps are found in one step): seminaive
 * still finds and answers naive's pairs in naive's order (the frames bit for bit, fewer
 * checks), on 1, 2 and 4 threads alike; elastic responses keep the energy to round-off; and
 * the spheres stay in the box (overlaps are theirs by design: they detect after the move). */
static void test_detection_on_a_crowded_fluid_is_exact_across_threads_and_keeps_energy(
    void **state)
{
    (void)state;
    const size_t side = nbep_test_scaled(7, 5);
    const uint64_t steps = nbep_test_scaled(60, 40);
    frames ref = {0};
    nbep_summary s_ref = {0};
    const char *algos[] = {"naive", "seminaive"};
    for (int a = 0; a < 2; a++)
        for (int nt = 1; nt <= 4; nt *= 2) {
            nbep_scene *sc = nbep_test_fluid(side, 0.35, steps, 0.01);
            snprintf(sc->algorithm, sizeof sc->algorithm, "%s", algos[a]);
            frames f = {0};
            nbep_state fin;
            nbep_summary s = run(sc, nt, &fin, &f);
            assert_true(s.sphere_collisions > 2 * s.spheres); /* crowded: many meetings */
            assert_close(s.energy_final, s.energy_initial, 1e-12, 0.0);
            for (size_t i = 0; i < fin.n; i++) {
                const double p[3] = {fin.pos[i].x, fin.pos[i].y, fin.pos[i].z};
                const double lo[3] = {sc->box_min.x, sc->box_min.y, sc->box_min.z};
                const double hi[3] = {sc->box_max.x, sc->box_max.y, sc->box_max.z};
                for (int k = 0; k < 3; k++)
                    assert_true(p[k] > lo[k] && p[k] < hi[k]);
            }
            nbep_state_fini(&fin);
            if (a == 0 && nt == 1) {
                ref = f;
                s_ref = s;
            } else {
                frames_equal(&ref, &f);
                assert_int_equal(s.collisions, s_ref.collisions);
                if (a == 1)
                    assert_true(s.checks < s_ref.checks);
                else
                    assert_int_equal(s.checks, s_ref.checks);
                nbep_test_frames_free(&f);
            }
            nbep_test_scene_free(&sc);
        }
    nbep_test_frames_free(&ref);
}

/* Elastic responses conserve kinetic energy exactly whatever the positions, so a naive gas
 * without gravity keeps its energy to round-off: each response changes it by a few ulps, so
 * after C collisions the relative drift is about sqrt(C) * 1e-16; 1e-12 leaves room. */
static void test_naive_gas_without_gravity_conserves_energy(void **state)
{
    (void)state;
    nbep_scene *sc = gas("naive", nbep_test_scaled(500, 200), 0.0, nbep_test_scaled(400, 60));
    nbep_summary s = run(sc, 2, NULL, NULL);
    assert_true(s.collisions > 10);
    assert_close(s.energy_final, s.energy_initial, 1e-12, 0.0);
    nbep_test_scene_free(&sc);
}

/* The predictive algorithm advances each pair to its contact time, so under gravity too the
 * energy (kinetic + potential) is conserved to round-off: each event moves it by a few ulps of
 * the largest term (the potential, m g L), so 1e-11 bounds the drift of thousands of events. */
static void test_predictive_gas_under_gravity_conserves_energy(void **state)
{
    (void)state;
    nbep_scene *sc = gas("predictive", nbep_test_scaled(500, 200), 9.81, nbep_test_scaled(1000, 100));
    nbep_summary s = run(sc, 2, NULL, NULL);
    assert_true(s.collisions > nbep_test_scaled(100, 10));
    assert_close(s.energy_final, s.energy_initial, 1e-11, 0.0);
    /* and nothing overlaps beyond round-off: 1e-9 of the smaller radius */
    assert_true(s.max_overlap_rel < 1e-9);
    nbep_test_scene_free(&sc);
}

/* The predictive and the naive gas agree on a run in which collisions do happen, to within
 * what naive's detection after the fact allows. It reacts up to one step late, the pair having
 * flown on by at most 2 v dt (v: the largest speed), and at positions overlapping by up to
 * that, so its normal is off by up to 2 v dt / sigma_min radians and the velocities leave off
 * by up to 2 v times that; over the rest of the run T that makes a sphere at most
 * 2 v dt + T 2 v (2 v dt / sigma_min) from its predictive self (most spheres collide at most
 * once in so short a run). A wrong response or a missed collision moves a sphere by about v T
 * instead, far beyond the bound. The runs must also count the same collisions. */
static void test_predictive_and_naive_agree_on_a_short_gas_run(void **state)
{
    (void)state;
    const size_t n = 512;
    const uint64_t steps = 1000;
    const double dt = 2e-4, T = (double)steps * dt;
    nbep_scene *a = gas("naive", n, 0.0, steps);
    nbep_scene *b = gas("predictive", n, 0.0, steps);
    a->dt = b->dt = dt;
    nbep_state fa, fb;
    nbep_summary sa = run(a, 1, &fa, NULL), sb = run(b, 1, &fb, NULL);
    assert_true(sb.sphere_collisions >= 20); /* collisions do happen */
    assert_int_equal(sa.sphere_collisions, sb.sphere_collisions);
    assert_int_equal(sa.plane_collisions, sb.plane_collisions);
    double v = 0.0, sigma_min = INFINITY;
    for (size_t i = 0; i < n; i++) {
        v = fmax(v, fmax(nbep_vec3_norm(fa.vel[i]), nbep_vec3_norm(fb.vel[i])));
        v = fmax(v, nbep_vec3_norm(a->state.vel[i]));
        sigma_min = fmin(sigma_min, 2.0 * a->state.radius[i]);
    }
    const double tol = 2.0 * v * dt + T * 2.0 * v * (2.0 * v * dt / sigma_min);
    size_t moved = 0;
    for (size_t i = 0; i < fa.n; i++) {
        double d = nbep_vec3_norm(nbep_vec3_sub(fa.pos[i], fb.pos[i]));
        moved += d > 1e-12;
        if (!(d <= tol))
            fail_msg("sphere %zu: naive and predictive %.3g apart (bound %.3g)", i, d, tol);
    }
    assert_true(moved > 0); /* the collisions did change something */
    nbep_state_fini(&fa), nbep_state_fini(&fb);
    nbep_test_scene_free(&a), nbep_test_scene_free(&b);
}

/* run.neighbors = "grid" (beyond the paper) tests only nearby partners before a horizon; it
 * must find the same collisions as the paper's all-pairs re-prediction, keep energy and
 * overlaps at round-off, and give the same bits for any thread count. */
static void test_grid_predictive_finds_the_same_collisions_as_all_pairs(void **state)
{
    (void)state;
    size_t n = nbep_test_scaled(700, 300);
    uint64_t steps = nbep_test_scaled(300, 60);
    nbep_scene *a = gas("predictive", n, 9.81, steps);
    nbep_scene *g = gas("predictive", n, 9.81, steps);
    g->neighbors_grid = true;
    nbep_summary sa = run(a, 1, NULL, NULL), sg = run(g, 1, NULL, NULL);
    assert_true(sa.collisions > 10);
    assert_int_equal(sg.sphere_collisions, sa.sphere_collisions);
    assert_int_equal(sg.plane_collisions, sa.plane_collisions);
    assert_true(sg.predictions < sa.predictions / 2); /* it tests far fewer partners */
    assert_close(sg.energy_final, sg.energy_initial, 1e-11, 0.0);
    assert_true(sg.max_overlap_rel < 1e-9);
    nbep_test_scene_free(&a), nbep_test_scene_free(&g);
}

/* The same, where the horizon's reach matters: spheres so fast (up to 150 m/s, 0.15 per step,
 * about two cells of the grid) that partners several cells away can meet within one step.
 * Judged by overlap (a missed collision leaves a pair inside each other), not by equal
 * collision counts, which round-off can change in a chaotic gas. All speeds here are alike;
 * test_run_contract.c has the gas over two decades of speed in which a reach that leaves out
 * either sphere's travel shows (scripts/mutate.py). */
static void test_grid_predictive_finds_fast_partners_several_cells_away(void **state)
{
    (void)state;
    const size_t n = nbep_test_scaled(1000, 343);
    nbep_scene *sc[2];
    nbep_summary sum[2];
    for (int k = 0; k < 2; k++) {
        sc[k] = gas("predictive", n, 0.0, nbep_test_scaled(60, 40));
        sc[k]->dt = 1e-3;
        sc[k]->neighbors_grid = k == 1;
        for (size_t i = 0; i < n; i++) {
            sc[k]->state.vel[i] = nbep_vec3_scale(sc[k]->state.vel[i], 50.0);
            sc[k]->state.radius[i] *= 0.2;
        }
        sum[k] = run(sc[k], 1, NULL, NULL);
    }
    assert_true(sum[0].sphere_collisions > nbep_test_scaled(20, 3));
    assert_true(sum[1].sphere_collisions > nbep_test_scaled(20, 3));
    assert_true(sum[0].max_overlap_rel < 1e-9);
    assert_true(sum[1].max_overlap_rel < 1e-9);
    nbep_test_scene_free(&sc[0]), nbep_test_scene_free(&sc[1]);
}

static void test_grid_predictive_frames_are_bitwise_equal_for_1_2_4_threads(void **state)
{
    (void)state;
    nbep_scene *sc = gas("predictive", nbep_test_scaled(700, 300), 9.81, nbep_test_scaled(300, 40));
    sc->neighbors_grid = true;
    frames ref = {0};
    nbep_summary s1 = run(sc, 1, NULL, &ref);
    assert_true(s1.collisions > 0);
    for (int nt = 2; nt <= 4; nt *= 2) {
        frames f = {0};
        nbep_summary sk = run(sc, nt, NULL, &f);
        frames_equal(&ref, &f);
        assert_int_equal(sk.predictions, s1.predictions);
        nbep_test_frames_free(&f);
    }
    nbep_test_frames_free(&ref);
    nbep_test_scene_free(&sc);
}


/* run.neighbors = "cells" (beyond the paper): the step's events one at a time from a calendar,
 * re-predictions over cell lists. The same collisions as the paper's all-pairs mode on the gas
 * of spheres of many radii and masses (under gravity g), energy and overlaps at round-off, far
 * fewer predictions. */
static void cells_finds_the_same_collisions_as_all_pairs(double g)
{
    size_t n = nbep_test_scaled(700, 300);
    uint64_t steps = nbep_test_scaled(300, 60);
    nbep_scene *a = gas("predictive", n, g, steps);
    nbep_scene *c = gas("predictive", n, g, steps);
    c->neighbors_cells = true;
    nbep_summary sa = run(a, 1, NULL, NULL), sc = run(c, 1, NULL, NULL);
    assert_true(sa.sphere_collisions > 10 && sa.plane_collisions > 10);
    assert_int_equal(sc.sphere_collisions, sa.sphere_collisions);
    assert_int_equal(sc.plane_collisions, sa.plane_collisions);
    assert_true(sc.predictions < sa.predictions / 2);
    /* round-off: each of some thousand events moves the energy by a few ulps */
    assert_close(sc.energy_final, sc.energy_initial, 1e-11, 0.0);
    assert_close(sc.energy_final, sa.energy_final, 1e-11, 0.0);
    assert_true(sc.max_overlap_rel < 1e-9);
    nbep_test_scene_free(&a), nbep_test_scene_free(&c);
}

static void test_cells_predictive_finds_the_same_collisions_as_all_pairs(void **state)
{
    (void)state;
    cells_finds_the_same_collisions_as_all_pairs(9.81);
}

/* Without gravity cells mode takes its free-flight partner loop (bounds of four pairs at once
 * from the partners' gathered motion): the same collisions still, with walls and radii that
 * differ by half from sphere to sphere. (A wrong contact distance there passes in a gas this
 * thin, where the other sphere's slot finds most pairs: the fluid of two radii below tells.) */
static void test_cells_predictive_free_flight_finds_the_same_collisions_as_all_pairs(void **state)
{
    (void)state;
    cells_finds_the_same_collisions_as_all_pairs(0.0);
}


/* A fluid at phi = 0.35: thousands of collisions per step, no overlap beyond round-off,
 * energy kept, the same collisions as grid mode over a short stretch (before round-off
 * differences could reorder any events), and frames bitwise equal for 1, 2 and 4 threads. */
static void test_cells_predictive_dense_fluid_is_exact_and_thread_independent(void **state)
{
    (void)state;
    size_t side = nbep_test_scaled(10, 7);
    nbep_scene *sc = nbep_test_fluid(side, 0.35, 10, 0.01);
    sc->neighbors_cells = true;
    frames ref = {0};
    nbep_summary s1 = run(sc, 1, NULL, &ref);
    size_t n = side * side * side;
    /* Enskog: about 13 collisions per sphere per unit time at phi = 0.35, so some 0.65 n
     * pair collisions in 0.1; fewer from the ordered lattice start */
    assert_true(s1.sphere_collisions > n / 4);
    assert_true(s1.max_overlap_rel < 1e-9);
    assert_close(s1.energy_final, s1.energy_initial, 1e-12, 0.0);
    for (int nt = 2; nt <= 4; nt *= 2) {
        frames f = {0};
        nbep_summary sk = run(sc, nt, NULL, &f);
        frames_equal(&ref, &f);
        assert_int_equal(sk.collisions, s1.collisions);
        nbep_test_frames_free(&f);
    }
    nbep_test_scene_free(&sc);
    nbep_test_frames_free(&ref);
    nbep_scene *g = nbep_test_fluid(side, 0.35, 10, 0.01);
    g->neighbors_grid = true;
    nbep_summary sg = run(g, 1, NULL, NULL);
    assert_int_equal(sg.sphere_collisions, s1.sphere_collisions);
    assert_int_equal(sg.plane_collisions, s1.plane_collisions);
    nbep_test_scene_free(&g);
}

/* The same fluid with every other sphere shrunk to radius 0.4 (packing fraction 0.34), over
 * 0.4 time units: cells mode's free-flight partner loop takes each pair's own contact distance,
 * so it finds the collisions that grid mode finds, one for one (3700 at 1000 spheres; round-off
 * has not reordered any events by then), with no overlap. A small sphere that took twice its
 * own radius for every pair would miss a large partner met at an impact parameter between the
 * two, unless the large one's slot found it: 20 such were missed, and overlaps reached 21 %
 * of a diameter. */
static nbep_scene *fluid_of_two_radii(size_t side)
{
    nbep_scene *sc = nbep_test_fluid(side, 0.45, 40, 0.01);
    for (size_t i = 1; i < sc->state.n; i += 2)
        sc->state.radius[i] = 0.4;
    return sc;
}

static void test_cells_predictive_fluid_of_two_radii_matches_grid_mode(void **state)
{
    (void)state;
    size_t side = nbep_test_scaled(10, 7);
    nbep_scene *c = fluid_of_two_radii(side), *g = fluid_of_two_radii(side);
    c->neighbors_cells = true;
    g->neighbors_grid = true;
    nbep_summary sc = run(c, 1, NULL, NULL), sg = run(g, 1, NULL, NULL);
    assert_true(sc.sphere_collisions > side * side * side / 4);
    assert_int_equal(sc.sphere_collisions, sg.sphere_collisions);
    assert_true(sc.max_overlap_rel < 1e-9);
    assert_close(sc.energy_final, sc.energy_initial, 1e-12, 0.0);
    nbep_test_scene_free(&c), nbep_test_scene_free(&g);
}

/* A longer run of the same fluid (many list expiries, each placing its sphere in a cell anew;
 * rebuilds at every frame): still exact. */
static void test_cells_predictive_dense_fluid_keeps_energy_over_a_longer_run(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_fluid(nbep_test_scaled(12, 8), 0.45, nbep_test_scaled(200, 60), 0.02);
    sc->neighbors_cells = true;
    sc->output_every = 7;
    nbep_summary s = run(sc, 2, NULL, NULL);
    assert_true(s.sphere_collisions > 10 * s.spheres);
    assert_true(s.max_overlap_rel < 1e-9);
    /* a few ulps per collision, over ~1e5 collisions */
    assert_close(s.energy_final, s.energy_initial, 1e-10, 0.0);
    nbep_test_scene_free(&sc);
}

/* A pile settling under gravity with e < 1 in cells mode: resting contacts on the floor and
 * on each other must resolve (no stall, no overlap), energy only goes down, and the threads
 * give the same bits. */
static void test_cells_predictive_pile_settles_under_gravity(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_fluid(nbep_test_scaled(6, 4), 0.3, nbep_test_scaled(100, 60), 5e-3);
    sc->neighbors_cells = true;
    sc->restitution = 0.6;
    for (size_t i = 0; i < sc->state.n; i++)
        sc->state.acc[i] = (nbep_vec3){0, 0, -9.81};
    frames ref = {0}, f2 = {0};
    nbep_summary s1 = run(sc, 1, NULL, &ref);
    nbep_summary s2 = run(sc, 2, NULL, &f2);
    frames_equal(&ref, &f2);
    assert_true(s1.collisions > s1.spheres);
    assert_true(s1.max_overlap_rel < 1e-6);
    assert_true(s1.energy_final < s1.energy_initial);
    assert_int_equal(s2.collisions, s1.collisions);
    nbep_test_frames_free(&ref);
    nbep_test_frames_free(&f2);
    nbep_test_scene_free(&sc);
}

/* Per-slab calendars (NBEP_SLABS, step 1 of docs/optimistic-design.md: the calendar cut into
 * slabs across x, their earliest entries merged on one thread) hand out the events in the one
 * calendar's order, so runs on 2, 3 and 4 slabs, on one thread and on two (where they take
 * the one-thread loop: the team keeps one calendar), give the one-calendar run's frames and
 * counts bit for bit: a periodic fluid at phi = 0.35 (spheres change slab as they cross the
 * cuts and the periodic faces), a pile settling under gravity with e = 0.6 in a box, and the
 * same pile falling across x onto the wall at its low end (SIDEWAYS: the spheres crowd into
 * the low slab, which outgrows its room and grows mid-run, the others giving their local
 * numbers back). test_memory_plan checks that the slabs are made and hold the entries. */
#define SIDEWAYS ((nbep_vec3){-40.0, 0.0, 0.0})
static void test_cells_per_slab_calendars_give_the_one_calendar_run(void **state)
{
    (void)state;
    const char *const names[3] = {"fluid", "pile", "pile falling across x"};
    nbep_scene *scenes[3] = {
        nbep_test_periodic_fluid(nbep_test_scaled(9, 6), 0.35, 30, 0.01, 5),
        nbep_test_fluid(nbep_test_scaled(6, 4), 0.3, 60, 5e-3),
        nbep_test_fluid(nbep_test_scaled(6, 4), 0.3, 60, 5e-3)};
    for (int k = 1; k < 3; k++) {
        scenes[k]->neighbors_cells = true;
        scenes[k]->restitution = 0.6;
        for (size_t i = 0; i < scenes[k]->state.n; i++)
            scenes[k]->state.acc[i] = k == 1 ? (nbep_vec3){0, 0, -9.81} : SIDEWAYS;
    }
    for (int k = 0; k < 3; k++) {
        frames ref = {0};
        nbep_summary s1 = run(scenes[k], 1, NULL, &ref);
        if (s1.collisions <= s1.spheres) /* enough events that an order error would show */
            fail_msg("%s: %llu collisions of %llu spheres", names[k],
                     (unsigned long long)s1.collisions, (unsigned long long)s1.spheres);
        for (int slabs = 2; slabs <= 4; slabs++)
            for (int nt = 1; nt <= 2; nt++) {
                char v[8];
                snprintf(v, sizeof v, "%d", slabs);
                setenv("NBEP_SLABS", v, 1);
                frames f = {0};
                nbep_summary sk = run(scenes[k], nt, NULL, &f);
                unsetenv("NBEP_SLABS");
                frames_equal(&ref, &f);
                if (sk.collisions != s1.collisions || sk.checks != s1.checks ||
                    sk.predictions != s1.predictions)
                    fail_msg("%s, %d slabs, %d thread(s): %llu collisions, %llu checks, %llu "
                             "predictions; one calendar %llu, %llu, %llu",
                             names[k], slabs, nt,
                             (unsigned long long)sk.collisions, (unsigned long long)sk.checks,
                             (unsigned long long)sk.predictions,
                             (unsigned long long)s1.collisions, (unsigned long long)s1.checks,
                             (unsigned long long)s1.predictions);
                nbep_test_frames_free(&f);
            }
        nbep_test_frames_free(&ref);
        nbep_test_scene_free(&scenes[k]);
    }
    /* more slabs than a sphere's slab byte numbers: refused, naming the setting */
    nbep_scene *sc = nbep_test_periodic_fluid(6, 0.3, 1, 0.01, 5);
    setenv("NBEP_SLABS", "65", 1);
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_sim_options opt = {.threads = 1};
    nbep_sim *sim = NULL;
    assert_int_equal(nbep_sim_create(sc, &opt, &sim, &d), NBEP_EDECK);
    unsetenv("NBEP_SLABS");
    assert_null(sim);
    assert_int_equal(d.n_errors, 1);
    assert_non_null(strstr(d.msg[0], "NBEP_SLABS asks for more than 64 slabs"));
    nbep_diag_fini(&d);
    nbep_test_scene_free(&sc);
}

/* A scene without a box in cells mode: the cells cover the spheres' extent instead, laid out
 * afresh at each rebuild (counted as refits). Where walls given as planes keep the spheres in,
 * that layout changes nothing: the gas above, under gravity, with its box's walls as planes
 * only, gives the boxed run's frames bit for bit (on 2 threads, its bounds from both). */
static void test_cells_without_a_box_gives_the_boxed_frames(void **state)
{
    (void)state;
    const size_t n = nbep_test_scaled(700, 300);
    const uint64_t steps = nbep_test_scaled(300, 60);
    nbep_scene *b = gas("predictive", n, 9.81, steps), *p = gas("predictive", n, 9.81, steps);
    b->neighbors_cells = p->neighbors_cells = true;
    p->has_box = false;
    /* radii 1.9 times gas()'s (packing 0.0076 to 0.052: the largest pair still clear of its
     * neighbours' 0.6 h), so that the boxed gas is not sparse: both take the skin of 0.4, as a
     * scene without a box does (its lists' reach changes the rounding of the events' times) */
    for (size_t i = 0; i < n; i++) {
        b->state.radius[i] *= 1.9;
        p->state.radius[i] *= 1.9;
    }
    assert_true(nbep_scene_list_skin(b, &b->state) == nbep_scene_list_skin(p, &p->state));
    frames fb = {0}, fp = {0};
    uint64_t cb[NBEP_COUNTER_COUNT], cp[NBEP_COUNTER_COUNT];
    nbep_summary sb = nbep_test_run_counted(b, 1, nbep_test_keep_frame, &fb, NULL, cb);
    nbep_summary sp = nbep_test_run_counted(p, 2, nbep_test_keep_frame, &fp, NULL, cp);
    assert_true(sb.sphere_collisions > 10 && sb.plane_collisions > 10);
    frames_equal(&fb, &fp);
    assert_int_equal(sp.collisions, sb.collisions);
    assert_int_equal(cb[NBEP_COUNTER_REFITS], 0);
    assert_true(cp[NBEP_COUNTER_REFITS] >= 1);
    nbep_test_frames_free(&fb), nbep_test_frames_free(&fp);
    nbep_test_scene_free(&b), nbep_test_scene_free(&p);
}

/* The cluster expands out of any region the cells cover: each step whose spheres have left it
 * rebuilds over their new extent. The same collisions as the paper's all-pairs mode, energy and
 * overlaps at round-off, frames bitwise equal for 1, 2 and 4 threads (the team runs it: elastic,
 * nothing accelerating), and the region grows geometrically (by an eighth of the extent on each
 * side): a few refits while the extent grows several times, not one a step. */
static void test_cells_without_a_box_follows_an_expanding_cluster(void **state)
{
    (void)state;
    const size_t side = nbep_test_scaled(8, 6);
    const uint64_t steps = nbep_test_scaled(200, 120);
    nbep_scene *c = nbep_test_cluster("predictive", side, steps),
               *a = nbep_test_cluster("predictive", side, steps);
    c->neighbors_cells = true;
    c->output_every = steps; /* no rebuilds but the refits and the first */
    frames ref = {0};
    uint64_t counts[NBEP_COUNTER_COUNT];
    nbep_state fin;
    nbep_summary s1 = nbep_test_run_counted(c, 1, nbep_test_keep_frame, &ref, &fin, counts);
    nbep_summary sa = run(a, 1, NULL, NULL);
    assert_true(s1.sphere_collisions > 2 * s1.spheres);
    assert_int_equal(s1.sphere_collisions, sa.sphere_collisions);
    assert_true(s1.max_overlap_rel < 1e-9);
    assert_close(s1.energy_final, s1.energy_initial, 1e-12, 0.0);
    /* the extent at the end, several times the start's (side * 1.25 across) */
    nbep_vec3 lo, hi;
    nbep_grid_bounds(fin.pos, 0, fin.n, &lo, &hi);
    assert_true(hi.x - lo.x > 3.0 * 1.25 * (double)side);
    const uint64_t refits = counts[NBEP_COUNTER_REFITS];
    assert_true(refits >= 4 && refits <= steps / 10);
    nbep_state_fini(&fin);
    for (int nt = 2; nt <= 4; nt *= 2) {
        frames f = {0};
        nbep_summary sk = nbep_test_run_counted(c, nt, nbep_test_keep_frame, &f, NULL, counts);
        frames_equal(&ref, &f);
        assert_int_equal(sk.predictions, s1.predictions);
        assert_int_equal(counts[NBEP_COUNTER_REFITS], refits);
        assert_true(counts[NBEP_COUNTER_AHEAD] > 0); /* the team ran events ahead */
        nbep_test_frames_free(&f);
    }
    nbep_test_frames_free(&ref);
    nbep_test_scene_free(&c), nbep_test_scene_free(&a);
}

/* Two spheres flying apart along x at speed 1 each, from 2 apart to 2 + 2 T (100 times as far at
 * T = 100): the region the cells cover grows with the extent, by an eighth of it on each side
 * at each refit (at least two diameters, 2 here), so it follows in about 4 refits while the
 * two diameters are the larger pad (extent up to 16, 4 more each time) and log(202 / 16) /
 * log(1.25) = 11.4 more: some 17, where a fixed pad would take one per 4 of extent, about 50. */
static void test_cells_without_a_box_region_grows_geometrically(void **state)
{
    (void)state;
    const uint64_t steps = 2000;
    nbep_scene *sc = nbep_test_scene_new(2, 0, "predictive", steps, 0.05);
    sc->neighbors_cells = true;
    sc->output_every = steps;
    nbep_test_set_sphere(sc, 0, (nbep_vec3){-1, 0, 0}, (nbep_vec3){-1, 0, 0}, 0.5, 1.0, ZERO);
    nbep_test_set_sphere(sc, 1, (nbep_vec3){1, 0, 0}, (nbep_vec3){1, 0, 0}, 0.5, 1.0, ZERO);
    uint64_t counts[NBEP_COUNTER_COUNT];
    nbep_state fin;
    nbep_summary s = nbep_test_run_counted(sc, 1, NULL, NULL, &fin, counts);
    assert_int_equal(s.collisions, 0);
    assert_close(fin.pos[1].x - fin.pos[0].x, 202.0, 1e-12, 0.0);
    assert_true(counts[NBEP_COUNTER_REFITS] >= 12 && counts[NBEP_COUNTER_REFITS] <= 20);
    nbep_state_fini(&fin);
    nbep_test_scene_free(&sc);
}

/* A contact past half of what the best event so far leaves. Grid and cells modes solve a pair
 * only up to the time at which it could still beat, or tie with, the sphere's best event so
 * far (beat_cap in src/pred_find.c; the slow search that pairs accelerating differently
 * take stops there). Here two spheres stacked on a vertical line, both from rest and flying
 * sideways alike at u towards a wall, fall with different accelerations (gB below, gA > gB
 * above), so the upper one catches the lower: their gap s closes as (gA - gB) t^2 / 2,
 * touching at tc = sqrt(2 s / (gA - gB)), head on along z (their relative velocity is 0, so
 * the pair takes the search). Each sphere's best before the pair is its wall contact at
 * tw = 1.25 tc (in grid mode the horizon where that is earlier, no earlier than the step's end
 * T, past tc): a limit below 0.8 of the way to it (half of it: scripts/mutate.py's
 * beat-cap-short) misses tc from both sides, and the two fly into each other (no collision, an
 * overlap of a quarter of s at T, in grid and cells modes alike). The run, one step, ends at
 * T = 1.125 tc, after tc and before the wall: the collision exchanges the two vertical
 * velocities (equal masses, e = 1) and leaves the sideways ones; the same in all three modes
 * (the all-pairs mode solves every pair without a limit). */
static void test_predictive_modes_find_a_contact_past_half_the_wall_time(void **state)
{
    (void)state;
    const double r = 0.5, s = 0.02, gB = 1.0, gA = 2.0, u = 0.1, zB = 3.0, x0 = 1.0;
    const double tc = sqrt(2.0 * s / (gA - gB)), tw = 1.25 * tc, T = 1.125 * tc;
    const double zA = zB + 2.0 * r + s, xwall = x0 + r + u * tw;
    /* at contact: heights and vertical velocities; after it, the velocities exchanged */
    const double zBc = zB - 0.5 * gB * tc * tc, zAc = zA - 0.5 * gA * tc * tc;
    const double vBc = -gB * tc, vAc = -gA * tc, h = T - tc;
    const double zBT = zBc + vAc * h - 0.5 * gB * h * h, zAT = zAc + vBc * h - 0.5 * gA * h * h;
    for (int mode = 0; mode < 3; mode++) { /* all pairs, grid, cells */
        nbep_scene *sc = nbep_test_scene_new(2, 1, "predictive", 1, T);
        sc->neighbors_grid = mode == 1;
        sc->neighbors_cells = mode == 2;
        nbep_test_set_plane(sc, 0, (nbep_vec3){-1, 0, 0}, -xwall);
        nbep_test_set_sphere(sc, 0, (nbep_vec3){x0, 0, zB}, (nbep_vec3){u, 0, 0}, r, 1.0,
                             (nbep_vec3){0, 0, -gB});
        nbep_test_set_sphere(sc, 1, (nbep_vec3){x0, 0, zA}, (nbep_vec3){u, 0, 0}, r, 1.0,
                             (nbep_vec3){0, 0, -gA});
        nbep_state fin;
        nbep_summary sum = run(sc, 1, &fin, NULL);
        assert_int_equal(sum.sphere_collisions, 1);
        assert_int_equal(sum.plane_collisions, 0);
        assert_true(sum.max_overlap_rel < 1e-9);
        for (size_t i = 0; i < 2; i++) {
            assert_close(fin.pos[i].x, x0 + u * T, 0.0, 1e-14);
            assert_close(fin.vel[i].x, u, 1e-14, 0.0);
        }
        assert_close(fin.pos[0].z, zBT, 0.0, 1e-13);
        assert_close(fin.pos[1].z, zAT, 0.0, 1e-13);
        assert_close(fin.vel[0].z, vAc - gB * h, 0.0, 1e-13);
        assert_close(fin.vel[1].z, vBc - gA * h, 0.0, 1e-13);
        nbep_state_fini(&fin);
        nbep_test_scene_free(&sc);
    }
}

/* A pair contact tied with a plane contact found before it. Grid and cells modes solve a pair
 * only up to the sphere's best event so far plus a margin of 16 ulps (beat_cap in
 * src/pred_find.c), so that a contact that rounds to the same time still ties; without
 * the margin it is lost whenever its exact time lies above the double the two round to. The
 * times here are exact fractions. Two spheres, X and its mirror image Y across x = 0 (radius
 * 1/2, e = 1/2, TC model with tc = 1e-6), each 1/8 above the floor and falling at 3/16 with no
 * vertical acceleration: they land at exactly 2/3. Along x they close head on under
 * accelerations +-3/8, each from 1/8 short of x = 0 at 1/16, X's gap to x = 0 being
 * q(t) = 1/8 - t/16 - 3 t^2/16 = (3/16)(2/3 - t)(1 + t): they touch at 2/3 too, on an approach
 * the acceleration bends (the pair takes the bracketing search). Both also move along y at 1/16
 * into a wall, which they meet at t_r = 1365/2048, so each is predicted again there, 1/6144
 * before the contacts. 2/3 is not a double: it lies a third of an ulp above the double D it
 * rounds to, so the floor's time and the pair's both round to D, a tie, the floor found first
 * (planes before pairs), while the pair's root from t_r lies that third of an ulp (some 1400 of
 * its own ulps) past D - t_r, far beyond its round-off: a cap at D - t_r ends the search short
 * of it, and the floor wins. By the tie rule (keep_earlier) a sphere event comes before a plane
 * event at one time, so the pair reacts first, with e, and then the floors, within tc of it,
 * elastically; the other way round (scripts/mutate.py's beat-cap-no-margin) the floors take e
 * and the pair bounces elastically. So at T = 11/16, after a flight of h = T - 2/3, X has
 * vx = -e 5/16 + 3/8 h and vz = +3/16 (Y the mirror image), in all three modes (the all-pairs
 * mode solves every pair without a limit). */
static void test_predictive_modes_break_a_pair_plane_tie_for_the_pair(void **state)
{
    (void)state;
    const double r = 0.5, e = 0.5, a = 3.0 / 8.0, q0 = 1.0 / 8.0, u = 1.0 / 16.0;
    const double g0 = 1.0 / 8.0, w = 3.0 / 16.0, vy = 1.0 / 16.0, tr = 1365.0 / 2048.0;
    const double T = 11.0 / 16.0, t1 = 2.0 / 3.0, h = T - t1;
    /* the scene's premise, from the exact values: 2/3 - D (from 2 - 3 D, which fma gives
     * exactly) is far more than the round-off the pair's root search allows for at its limit
     * (ROOT_TOL: about 32 ulps of the time from t_r, for this approach) */
    const double above = -fma(3.0, t1, -2.0) / 3.0;
    assert_true(above > 64.0 * DBL_EPSILON * (t1 - tr));
    /* at the contact: X at x = -r moving at vx0 + a 2/3 = 5/16; after the pair (with e) and
     * the floor (elastic) */
    const double vxc = u + a * 2.0 / 3.0, vx = -e * vxc + a * h;
    const double x = -r - e * vxc * h + 0.5 * a * h * h, z = r + w * h;
    const double y = vy * tr - e * vy * (T - tr); /* at the wall at tr, back at e vy since */
    for (int mode = 0; mode < 3; mode++) { /* all pairs, grid, cells */
        nbep_scene *sc = nbep_test_scene_new(2, 2, "predictive", 1, T);
        sc->neighbors_grid = mode == 1;
        sc->neighbors_cells = mode == 2;
        sc->restitution = e;
        sc->tc = 1e-6;
        nbep_test_set_plane(sc, 0, (nbep_vec3){0, 0, 1}, 0.0);
        nbep_test_set_plane(sc, 1, (nbep_vec3){0, -1, 0}, -(r + vy * tr));
        nbep_test_set_sphere(sc, 0, (nbep_vec3){-r - q0, 0.0, r + g0}, (nbep_vec3){u, vy, -w}, r,
                             1.0, (nbep_vec3){a, 0, 0});
        nbep_test_set_sphere(sc, 1, (nbep_vec3){r + q0, 0.0, r + g0}, (nbep_vec3){-u, vy, -w}, r,
                             1.0, (nbep_vec3){-a, 0, 0});
        nbep_state fin;
        nbep_summary sum = run(sc, 1, &fin, NULL);
        assert_int_equal(sum.sphere_collisions, 1);
        assert_int_equal(sum.plane_collisions, 4); /* the wall and the floor, each sphere */
        /* round-off of a few flights and responses of numbers below 1, the contacts found
         * within an ulp of 2/3: some 1e-16; 1e-12 relative is far above it and far below what
         * swapped restitutions change (vx by 0.16, vz by a factor 2) */
        for (size_t i = 0; i < 2; i++) {
            const double sx = i == 0 ? 1.0 : -1.0;
            assert_close(fin.vel[i].x, sx * vx, 1e-12, 0.0);
            assert_close(fin.vel[i].y, -e * vy, 1e-12, 0.0);
            assert_close(fin.vel[i].z, w, 1e-12, 0.0);
            assert_close(fin.pos[i].x, sx * x, 1e-12, 0.0);
            assert_close(fin.pos[i].y, y, 1e-12, 0.0);
            assert_close(fin.pos[i].z, z, 1e-12, 0.0);
        }
        nbep_state_fini(&fin);
        nbep_test_scene_free(&sc);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_predictive_bounce_matches_the_analytic_flight),
        cmocka_unit_test(test_naive_bounce_is_within_one_step_of_the_analytic_flight),
        cmocka_unit_test(test_head_on_pair_across_threads_reacts_exactly_once),
        cmocka_unit_test(test_oblique_unequal_masses_conserve_momentum_and_energy),
        cmocka_unit_test(test_naive_frames_are_bitwise_equal_for_1_2_4_threads),
        cmocka_unit_test(test_seminaive_frames_are_bitwise_equal_for_1_2_4_threads),
        cmocka_unit_test(test_predictive_frames_are_bitwise_equal_for_1_2_4_8_threads),
        cmocka_unit_test(test_seminaive_frames_equal_naive_frames_with_fewer_checks),
        cmocka_unit_test(test_detection_on_more_threads_than_rows_gives_the_one_thread_run),
        cmocka_unit_test(test_the_set_up_and_stepping_clocks_lie_within_the_run),
        cmocka_unit_test(test_detection_on_a_crowded_fluid_is_exact_across_threads_and_keeps_energy),
        cmocka_unit_test(test_naive_gas_without_gravity_conserves_energy),
        cmocka_unit_test(test_predictive_gas_under_gravity_conserves_energy),
        cmocka_unit_test(test_predictive_and_naive_agree_on_a_short_gas_run),
        cmocka_unit_test(test_grid_predictive_finds_the_same_collisions_as_all_pairs),
        cmocka_unit_test(test_grid_predictive_finds_fast_partners_several_cells_away),
        cmocka_unit_test(test_grid_predictive_frames_are_bitwise_equal_for_1_2_4_threads),
        cmocka_unit_test(test_cells_predictive_finds_the_same_collisions_as_all_pairs),
        cmocka_unit_test(test_cells_predictive_free_flight_finds_the_same_collisions_as_all_pairs),
        cmocka_unit_test(test_cells_predictive_dense_fluid_is_exact_and_thread_independent),
        cmocka_unit_test(test_cells_predictive_fluid_of_two_radii_matches_grid_mode),
        cmocka_unit_test(test_cells_predictive_dense_fluid_keeps_energy_over_a_longer_run),
        cmocka_unit_test(test_cells_predictive_pile_settles_under_gravity),
        cmocka_unit_test(test_cells_per_slab_calendars_give_the_one_calendar_run),
        cmocka_unit_test(test_cells_without_a_box_gives_the_boxed_frames),
        cmocka_unit_test(test_cells_without_a_box_follows_an_expanding_cluster),
        cmocka_unit_test(test_cells_without_a_box_region_grows_geometrically),
        cmocka_unit_test(test_predictive_modes_find_a_contact_past_half_the_wall_time),
        cmocka_unit_test(test_predictive_modes_break_a_pair_plane_tie_for_the_pair),
    };
    return cmocka_run_group_tests_name("sim", tests, NULL, NULL);
}
