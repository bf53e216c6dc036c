/* The run's documented contract checked end to end on real runs (SPEC "Output", "Summary"):
 * the frame schedule, the summary's energy drift and quiet steps recomputed from the frames,
 * the paper's check counter for naive, and grid mode judged by overlap on a gas whose speeds
 * spread over two decades. Every expected value comes from the frames (physics: kinetic plus
 * the potential -m a.x of a uniform field) or from counting, never from the code's formulas. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/sim.h"
#include "nbep/stats.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

#define MAX_FRAMES 4096

/* What the frames show: the step of each, its total energy, and whether any velocity changed
 * since the previous frame. */
typedef struct seen {
    size_t n_frames;
    int64_t step[MAX_FRAMES];
    double energy[MAX_FRAMES];
    bool changed[MAX_FRAMES];
    nbep_vec3 *vel;   /* the previous frame's velocities */
    nbep_vec3 pos[8]; /* the last frame's positions, for scenes of at most 8 spheres */
} seen;

static nbep_status see_frame(void *ctx, int64_t step, const nbep_state *s, nbep_diag *d)
{
    (void)d;
    seen *f = ctx;
    assert_true(f->n_frames < MAX_FRAMES);
    double e = 0.0;
    bool changed = false;
    for (size_t i = 0; i < s->n; i++) {
        const nbep_vec3 v = s->vel[i], a = s->acc[i], x = s->pos[i];
        e += 0.5 * s->mass[i] * (v.x * v.x + v.y * v.y + v.z * v.z) -
             s->mass[i] * (a.x * x.x + a.y * x.y + a.z * x.z);
        if (f->vel && (v.x != f->vel[i].x || v.y != f->vel[i].y || v.z != f->vel[i].z))
            changed = true;
    }
    if (!f->vel)
        assert_non_null(f->vel = malloc(s->n * sizeof *f->vel));
    memcpy(f->vel, s->vel, s->n * sizeof *s->vel);
    if (s->n <= 8)
        memcpy(f->pos, s->pos, s->n * sizeof *s->pos);
    f->step[f->n_frames] = step;
    f->energy[f->n_frames] = e;
    f->changed[f->n_frames] = changed;
    f->n_frames++;
    return NBEP_OK;
}

static nbep_summary run(const nbep_scene *sc, int nt, seen *f)
{
    return nbep_test_run(sc, nt, see_frame, f, NULL, NULL);
}

/* xorshift64: any fixed sequence will do; uniform in [0, 1). */
static double uniform(uint64_t *x)
{
    *x ^= *x << 13, *x ^= *x >> 7, *x ^= *x << 17;
    return (double)(*x >> 11) / 9007199254740992.0;
}

/* n spheres on a jittered lattice in a closed box of side L (6 planes), radius rf to 1.5 rf
 * of the lattice spacing h (rf <= 0.2: sites at least 0.6 h apart, so nothing overlaps at the
 * start), velocities of random direction with speeds v_lo 10^(2u) for u uniform: two decades
 * when spread is true, all v_lo*10 otherwise. */
static nbep_scene *box_gas_r(const char *algo, size_t n, double g, uint64_t steps, double dt,
                             double v_lo, bool spread, uint64_t seed, double rf)
{
    nbep_scene *sc = nbep_test_scene_new(n, 6, algo, steps, dt);
    const double L = 4.0;
    nbep_test_set_box(sc, L);
    size_t side = (size_t)ceil(cbrt((double)n));
    double h = L / (double)side;
    uint64_t x = 88172645463325252u ^ (seed * 0x9E3779B97F4A7C15u);
    for (size_t i = 0; i < n; i++) {
        double u[7];
        for (int k = 0; k < 7; k++)
            u[k] = uniform(&x);
        nbep_vec3 p = {h * ((double)(i % side) + 0.3 + 0.4 * u[0]),
                       h * ((double)(i / side % side) + 0.3 + 0.4 * u[1]),
                       h * ((double)(i / side / side) + 0.3 + 0.4 * u[2])};
        double cz = 2.0 * u[3] - 1.0, phi = 6.283185307179586 * u[4], sz = sqrt(1.0 - cz * cz);
        double speed = v_lo * pow(10.0, spread ? 2.0 * u[5] : 1.0);
        nbep_vec3 v = {speed * sz * cos(phi), speed * sz * sin(phi), speed * cz};
        nbep_test_set_sphere(sc, i, p, v, rf * h * (1.0 + 0.5 * u[6]), 1.0 + u[1],
                             (nbep_vec3){0, 0, -g});
    }
    return sc;
}

static nbep_scene *box_gas(const char *algo, size_t n, double g, uint64_t steps, double dt,
                           double v_lo, bool spread, uint64_t seed)
{
    return box_gas_r(algo, n, g, steps, dt, v_lo, spread, seed, 0.1);
}

/* ---- frame schedule ---------------------------------------------------------------------- */

/* SPEC: "a frame at step 0, every `every` steps, and the last step". 23 steps with every = 10
 * give frames at 0, 10, 20 and 23, for each algorithm; and with every = 1, one per step. */
static void test_frames_come_at_zero_every_tenth_step_and_the_last(void **state)
{
    (void)state;
    const char *algos[] = {"naive", "seminaive", "predictive"};
    for (int a = 0; a < 3; a++) {
        nbep_scene *sc = box_gas(algos[a], 27, 9.81, 23, 1e-3, 0.5, false, 1);
        sc->output_every = 10;
        seen f = {0};
        nbep_summary s = run(sc, 2, &f);
        assert_int_equal(f.n_frames, 4);
        assert_int_equal(f.step[0], 0);
        assert_int_equal(f.step[1], 10);
        assert_int_equal(f.step[2], 20);
        assert_int_equal(f.step[3], 23);
        assert_int_equal(s.steps, 23);
        free(f.vel);
        nbep_test_scene_free(&sc);
    }
}

/* ---- summary from the frames ------------------------------------------------------------- */

/* energy_rel_drift = (E_final - E_initial) / |E_initial| with E from the first and last
 * frames. With e = 0.8 naive loses energy at every collision, so the drift is negative and
 * far above round-off: a sign error cannot hide. The two energies are sums of the same terms
 * in possibly another order, so they agree to ~n ulps of the largest term; 1e-12 of |E|
 * bounds that for these few hundred spheres. */
static void test_energy_drift_is_recomputed_from_the_first_and_last_frames(void **state)
{
    (void)state;
    const char *algos[] = {"naive", "predictive"};
    for (int a = 0; a < 2; a++) {
        nbep_scene *sc = box_gas(algos[a], 216, 9.81, 23, 2e-3, 0.6, true, 2);
        sc->output_every = 10;
        sc->restitution = 0.8;
        seen f = {0};
        nbep_summary s = run(sc, 2, &f);
        assert_int_equal(f.n_frames, 4);
        assert_true(s.collisions > 0);
        double e0 = f.energy[0], e1 = f.energy[f.n_frames - 1];
        assert_close(s.energy_initial, e0, 1e-12, 0.0);
        assert_close(s.energy_final, e1, 1e-12, 0.0);
        assert_true(e1 < e0); /* inelastic: energy is lost */
        assert_close(s.energy_rel_drift, (e1 - e0) / fabs(e0), 0.0, 2e-12);
        assert_true(s.energy_rel_drift < -1e-9);
        free(f.vel);
        nbep_test_scene_free(&sc);
    }
}

/* quiet_steps counts the steps without a collision. Without gravity a velocity changes only
 * in a collision (every response changes one: the predictive algorithm reacts only to closing
 * contacts), so with a frame every step the quiet steps are the frames after step 0 in which
 * no velocity changed; collisions happen in some steps and not in others here. */
static void test_quiet_steps_are_the_steps_where_no_velocity_changed(void **state)
{
    (void)state;
    nbep_scene *sc = box_gas("predictive", 125, 0.0, 200, 1e-3, 0.3, true, 3);
    seen f = {0};
    nbep_summary s = run(sc, 2, &f);
    assert_int_equal(f.n_frames, 201);
    uint64_t quiet = 0;
    for (size_t k = 1; k < f.n_frames; k++)
        quiet += !f.changed[k];
    assert_true(quiet > 0 && quiet < 200);
    assert_int_equal(s.quiet_steps, quiet);
    free(f.vel);
    nbep_test_scene_free(&sc);
}

/* SPEC: naive's checks are its sphere-sphere and sphere-plane overlap tests, all of them every
 * step: n (n - 1) / 2 + n np per step, whatever happens. */
static void test_naive_checks_every_pair_and_every_sphere_plane_once_per_step(void **state)
{
    (void)state;
    const size_t n = 64, np = 6;
    const uint64_t steps = 37;
    for (int nt = 1; nt <= 2; nt++) {
        nbep_scene *sc = box_gas("naive", n, 9.81, steps, 2e-3, 0.6, true, 4);
        seen f = {0};
        nbep_summary s = run(sc, nt, &f);
        assert_int_equal(s.checks, steps * (n * (n - 1) / 2 + n * np));
        free(f.vel);
        nbep_test_scene_free(&sc);
    }
}

/* ---- simultaneous events sharing a sphere ------------------------------------------------ */

/* A and C close on B at rest from both sides, mirror images of each other, so both contacts
 * come at exactly the same time and share B. Each sphere may take part in one reaction at a
 * time (paper: the claim); reacting to both at once from B's old velocity would lose momentum.
 * Equal masses, e = 1: the binary collisions in turn hand the motion through, ending with A and
 * C flying apart at -v and +v and B at rest; momentum 0 and energy m v^2 throughout. */
static void test_two_contacts_at_the_same_time_on_one_sphere_keep_momentum(void **state)
{
    (void)state;
    for (int nt = 1; nt <= 2; nt++) {
        const double v = 1.5, r = 0.1, m = 2.0;
        nbep_scene *sc = nbep_test_scene_new(3, 0, "predictive", 100, 1e-3);
        const nbep_vec3 a0 = {0, 0, 0};
        /* B is the last index, so it is the second sphere of both pairs (either pair's
         * first sphere is claimed by that pair alone) */
        nbep_test_set_sphere(sc, 0, (nbep_vec3){-0.3, 0, 0}, (nbep_vec3){v, 0, 0}, r, m, a0);
        nbep_test_set_sphere(sc, 2, (nbep_vec3){0, 0, 0}, (nbep_vec3){0, 0, 0}, r, m, a0);
        nbep_test_set_sphere(sc, 1, (nbep_vec3){0.3, 0, 0}, (nbep_vec3){-v, 0, 0}, r, m, a0);
        seen f = {0};
        nbep_summary s = run(sc, nt, &f);
        assert_true(s.sphere_collisions >= 2);
        /* final frame's velocities: momentum 0, energy m v^2, and the outcome above; round-off
         * of a few responses: 1e-12 of v */
        const nbep_vec3 *vel = f.vel;
        double px = m * (vel[0].x + vel[1].x + vel[2].x);
        assert_close(px, 0.0, 0.0, 1e-12 * m * v);
        assert_close(s.energy_final, m * v * v, 1e-12, 0.0);
        assert_close(vel[0].x, -v, 0.0, 1e-12 * v);
        assert_close(vel[2].x, 0.0, 0.0, 1e-12 * v);
        assert_close(vel[1].x, v, 0.0, 1e-12 * v);
        free(f.vel);
        nbep_test_scene_free(&sc);
    }
}

/* SPEC: predictive's checks are "queue slots examined by find plus check() calls"; predictions
 * are contact-time computations. Counted by hand on a scene whose events are known (README
 * "Algorithms" and src/algo_predictive.c: find examines every slot at set-up and in each
 * step's first round, and in a later round the candidates left; check() looks at each slot
 * whose event is at the round's earliest time; a re-prediction computes a time with every
 * other sphere and every plane):
 * spheres 0 and 1 meet head-on along y at t = 0.4 (step 2), sphere 2 meets the plane x = 0 at
 * t = 0.9 (step 4), nothing else ever meets. So
 *   checks      = (S + 1) n          every slot at set-up and in each step's first round
 *               + 2 + 2              the pair: both copies checked, then both re-examined
 *               + 1 + 1              the plane contact: one slot checked, then re-examined
 *   predictions = n (n - 1 + np)     set-up
 *               + 2 (n - 1 + np)     the pair re-predicted
 *               + (n - 1 + np)       sphere 2 re-predicted
 * the same for any thread count (each thread counts its own slots and partners). */
static void test_predictive_checks_and_predictions_follow_spec_on_a_counted_scene(void **state)
{
    (void)state;
    const uint64_t S = 8, n = 3, np = 1;
    for (int nt = 1; nt <= 3; nt++) {
        nbep_scene *sc = nbep_test_scene_new(n, np, "predictive", S, 0.25);
        const nbep_vec3 a0 = {0, 0, 0};
        nbep_test_set_plane(sc, 0, (nbep_vec3){1, 0, 0}, 0.0);
        nbep_test_set_sphere(sc, 0, (nbep_vec3){1, -0.5, 0}, (nbep_vec3){0, 1, 0}, 0.1, 1, a0);
        nbep_test_set_sphere(sc, 1, (nbep_vec3){1, 0.5, 0}, (nbep_vec3){0, -1, 0}, 0.1, 1, a0);
        nbep_test_set_sphere(sc, 2, (nbep_vec3){1, 0, 5}, (nbep_vec3){-1, 0, 0}, 0.1, 1, a0);
        seen f = {0};
        nbep_summary s = run(sc, nt, &f);
        assert_int_equal(s.sphere_collisions, 1);
        assert_int_equal(s.plane_collisions, 1);
        assert_int_equal(s.checks, (S + 1) * n + 4 + 2);
        assert_int_equal(s.predictions, (n + 2 + 1) * (n - 1 + np));
        free(f.vel);
        nbep_test_scene_free(&sc);
    }
}

/* Two contacts at exactly the same time on one sphere B (index 2), from spheres of lower index:
 * README "Algorithms": simultaneous events sharing a sphere react one at a time in pair-key
 * order, the same for any thread count. The first contact's sphere A (index 0) only finds its
 * event during the step (after bouncing off the plane x = 0 at t = 0.875), after C (index 1),
 * whose event was known from the start, so an engine that reacted to both at once would take
 * them in the order it found them. Every number is a short binary fraction, so the contact times
 * are exact: A from x = 1 at -1 (bounce at 0.875, back at +1), B at rest at x = 2, C from
 * x = 4.75 at -1; radii 1/8: both contacts at t = 2.5. Masses A = C = 1, B = 3, e = 1; the 1-D
 * elastic collision v1' = ((m1 - m2) v1 + 2 m2 v2) / (m1 + m2), in key order:
 *   (A,B): A 1, B 0      -> A -1/2, B 1/2
 *   (C,B): C -1, B 1/2   -> B -1/4, C 5/4      (then A and B recede: done)
 * and free flight to t = 4: A at 1.75 - 1.5/2 = 1, B at 2 - 1.5/4 = 1.625, C at 2.25 + 1.5 * 5/4
 * = 4.125. (In the other order A would end at -5/4, reach the plane at t = 3.8 and come back.)
 * Exact binary fractions throughout; 1e-12 of the speed allows a few roundings anyway. */
static void test_simultaneous_contacts_sharing_a_sphere_react_in_pair_key_order(void **state)
{
    (void)state;
    for (int nt = 1; nt <= 3; nt++) {
        nbep_scene *sc = nbep_test_scene_new(3, 1, "predictive", 1, 4.0);
        const nbep_vec3 a0 = {0, 0, 0};
        nbep_test_set_plane(sc, 0, (nbep_vec3){1, 0, 0}, 0.0);
        nbep_test_set_sphere(sc, 0, (nbep_vec3){1, 0, 0}, (nbep_vec3){-1, 0, 0}, 0.125, 1, a0);
        nbep_test_set_sphere(sc, 1, (nbep_vec3){4.75, 0, 0}, (nbep_vec3){-1, 0, 0}, 0.125, 1, a0);
        nbep_test_set_sphere(sc, 2, (nbep_vec3){2, 0, 0}, (nbep_vec3){0, 0, 0}, 0.125, 3, a0);
        seen f = {0};
        nbep_summary s = run(sc, nt, &f);
        assert_int_equal(s.plane_collisions, 1);
        assert_int_equal(s.sphere_collisions, 2);
        const double want_v[3] = {-0.5, 1.25, -0.25}, want_x[3] = {1.0, 4.125, 1.625};
        for (int i = 0; i < 3; i++) {
            assert_close(f.vel[i].x, want_v[i], 0.0, 1e-12);
            assert_close(f.pos[i].x, want_x[i], 0.0, 1e-12);
        }
        assert_close(s.energy_final, 1.0, 1e-12, 0.0); /* (1 + 1)/2 before, kept (e = 1) */
        free(f.vel);
        nbep_test_scene_free(&sc);
    }
}

/* README "Physics, granular" (physics.tc): a collision within tc of the previous collision of
 * either sphere (planes included) is elastic. On a line, no gravity, radii 0.1, masses 1,
 * e = 0.5, tc = 0.012: B (index 1) at x = 0.2 and A (index 0) at x = 0.415 both move at -1
 * towards the plane x = 0. In order:
 *   t = 0.1    B hits the plane, its first collision: inelastic, B -> +0.5
 *   t = 0.11   A meets B (gap 0.015 closed at 1.5): B's last was 0.01 ago, so elastic (A has
 *              none): they swap, A +0.5, B -1
 *   t = 0.115  B hits the plane again, 0.005 after its last: elastic, B -> +1
 *   t = 0.13   B catches A (gap 0.0075 at 0.5): their last were 0.015 and 0.02 ago, more than
 *              tc: inelastic, centre-of-mass speed 0.75, A -> 0.75 + 0.5 * 0.25 = 0.875,
 *              B -> 0.75 - 0.5 * 0.25 = 0.625
 * then both fly off. Every margin to tc is at least 0.002, far above round-off of the times. */
static void test_tc_model_makes_a_collision_within_tc_of_either_spheres_last_one_elastic(
    void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_scene_new(2, 1, "predictive", 40, 0.005);
    const nbep_vec3 a0 = {0, 0, 0};
    sc->restitution = 0.5;
    sc->tc = 0.012;
    nbep_test_set_plane(sc, 0, (nbep_vec3){1, 0, 0}, 0.0);
    nbep_test_set_sphere(sc, 0, (nbep_vec3){0.415, 0, 0}, (nbep_vec3){-1, 0, 0}, 0.1, 1, a0);
    nbep_test_set_sphere(sc, 1, (nbep_vec3){0.2, 0, 0}, (nbep_vec3){-1, 0, 0}, 0.1, 1, a0);
    seen f = {0};
    nbep_summary s = run(sc, 1, &f);
    assert_int_equal(s.plane_collisions, 2);
    assert_int_equal(s.sphere_collisions, 2);
    /* a few roundings of speeds of order 1 */
    assert_close(f.vel[0].x, 0.875, 0.0, 1e-12);
    assert_close(f.vel[1].x, 0.625, 0.0, 1e-12);
    free(f.vel);
    nbep_test_scene_free(&sc);
}

/* README "Physics, granular": a held sphere is let go as soon as a sphere it rests on reacts.
 * A stack on the floor of a box, at rest and touching: B (index 1) on the floor, A (index 0) on
 * B; C (index 2, mass 1/2) slides along the floor at 3 m/s and hits B at t = 0.31 / 3. B leaves
 * at 2 m/s (1-D elastic: 2 m_C u / (m_B + m_C)); since 2^2 > g (r_A + r_B), B's top drops away
 * faster than A falls, so A touches nothing until the floor (0.2 s later) and falls freely
 * from rest at the instant of the hit: at T = 0.2, z_A = 0.3 - g (T - 0.31/3)^2 / 2. Held
 * spheres in the round mode (all pairs) and in cells mode. Round-off of a few flights: 1e-12. */
static void test_a_held_sphere_falls_freely_once_its_support_is_knocked_away(void **state)
{
    (void)state;
    const double g = 9.81, T = 0.2, t_hit = 0.31 / 3.0;
    for (int cells = 0; cells <= 1; cells++)
        for (int nt = 1; nt <= 2; nt++) {
            nbep_scene *sc = nbep_test_scene_new(3, 6, "predictive", 20, 0.01);
            const double L = 2.0;
            sc->neighbors_cells = cells;
            sc->tc = 1e-6;
            nbep_test_set_box(sc, L);
            const nbep_vec3 down = {0, 0, -g}, rest = {0, 0, 0};
            nbep_test_set_sphere(sc, 0, (nbep_vec3){1, 1, 0.3}, rest, 0.1, 1, down);
            nbep_test_set_sphere(sc, 1, (nbep_vec3){1, 1, 0.1}, rest, 0.1, 1, down);
            nbep_test_set_sphere(sc, 2, (nbep_vec3){0.49, 1, 0.1}, (nbep_vec3){3, 0, 0}, 0.1, 0.5,
                                 down);
            seen f = {0};
            nbep_summary s = run(sc, nt, &f);
            assert_int_equal(s.sphere_collisions, 1);
            assert_close(f.pos[0].z, 0.3 - 0.5 * g * (T - t_hit) * (T - t_hit), 0.0, 1e-12);
            assert_close(f.pos[0].x, 1.0, 0.0, 1e-12);
            assert_close(f.vel[1].x, 2.0, 0.0, 1e-12);
            free(f.vel);
            nbep_test_scene_free(&sc);
        }
}

/* ---- grid mode --------------------------------------------------------------------------- */

/* run.neighbors = "grid" tests only the partners that can reach a sphere before the horizon.
 * A reach that forgets either sphere's travel lets some pair pass into each other, an overlap
 * of a sizeable fraction of a radius, whereas the predictive algorithm keeps overlaps at
 * round-off (1e-9 of the smaller radius, as in test_sim). A miss needs an unlucky geometry
 * (both spheres near cell faces, closing fast), so each scene runs over many seeds and every
 * one must stay at round-off. Measured on this tree with the reach's partner term left out:
 * 12 of 40 seeds of the two-decade gas overlap (up to 7 % of a radius); with the sphere's own
 * term left out, 3 of 40 seeds of the equal-speed gas do (the partner term, the fastest speed,
 * covers a slow sphere's own travel, so only two fast spheres closing head-on show it). */
static void assert_grid_overlaps_at_round_off(double v_lo, bool spread, int seeds)
{
    const size_t n = nbep_test_scaled(1000, 343);
    for (int seed = 1; seed <= seeds; seed++) {
        nbep_scene *sc = box_gas_r("predictive", n, 0.0, nbep_test_scaled(60, 20), 2e-3, v_lo, spread,
                                   (uint64_t)seed + 100, 0.2);
        sc->neighbors_grid = true;
        sc->output_every = 1; /* overlaps are measured at frames: every step */
        seen f = {0};
        nbep_summary s = run(sc, 1, &f);
        assert_true(s.sphere_collisions > 0);
        if (!(s.max_overlap_rel < 1e-9))
            fail_msg("seed %d: grid mode let spheres overlap by %.3g of a radius", seed,
                     s.max_overlap_rel);
        free(f.vel);
        nbep_test_scene_free(&sc);
    }
}

/* Speeds 1 to 100 m/s, log-uniform: a slow sphere's own travel is tiny and a fast partner's
 * is up to half a cell per horizon. */
static void test_grid_mode_keeps_overlaps_at_round_off_with_speeds_over_two_decades(void **state)
{
    (void)state;
    assert_grid_overlaps_at_round_off(1.0, true, (int)nbep_test_scaled(40, 2));
}

/* Every sphere at 10 m/s: head-on pairs of fast spheres, where each sphere's own travel
 * matters as much as its partner's. */
static void test_grid_mode_keeps_overlaps_at_round_off_with_equal_fast_speeds(void **state)
{
    (void)state;
    assert_grid_overlaps_at_round_off(1.0, false, (int)nbep_test_scaled(80, 2));
}

/* The overlap the detecting algorithms find is the one there is: spheres of radii 0.5 and
 * 0.3 closing head-on at 2, from 1.3 apart, are 0.7 apart after a step of 0.3, overlapping
 * by 0.1 (relative to the smaller radius: 1/3) when naive and seminaive find them; in a
 * periodic box, by the minimum image, the pair across a face. The summary's max_overlap (SPEC) and its
 * relative form hold that to round-off (1e-12: the positions' few roundings at size 1). */
static void test_naive_and_seminaive_report_the_overlap_they_find(void **state)
{
    (void)state;
    const char *const algos[] = {"naive", "seminaive"};
    for (int a = 0; a < 2; a++)
        for (int periodic = 0; periodic < 2; periodic++) {
            nbep_scene *sc = nbep_test_scene_new(2, 0, algos[a], 2, 0.3);
            /* periodic: side 10, the pair 1.3 apart across the x faces (at 9.35 and 0.65) */
            const double x0 = periodic ? 9.35 : 0.0, x1 = periodic ? 0.65 : 1.3;
            nbep_test_set_sphere(sc, 0, nbep_vec3_make(x0, 5.0, 5.0),
                                 nbep_vec3_make(1.0, 0.0, 0.0), 0.5, 1.0,
                                 nbep_vec3_make(0.0, 0.0, 0.0));
            nbep_test_set_sphere(sc, 1, nbep_vec3_make(x1, 5.0, 5.0),
                                 nbep_vec3_make(-1.0, 0.0, 0.0), 0.3, 1.0,
                                 nbep_vec3_make(0.0, 0.0, 0.0));
            if (periodic)
                nbep_test_set_periodic_box(sc, 10.0);
            const nbep_summary sum = nbep_test_run(sc, 1, NULL, NULL, NULL, NULL);
            if (sum.sphere_collisions != 1 || fabs(sum.max_overlap - 0.1) > 1e-12 ||
                fabs(sum.max_overlap_rel - 1.0 / 3.0) > 1e-12)
                fail_msg("%s%s: %llu collisions, max_overlap %.17g (want 0.1), relative %.17g "
                         "(want 1/3)", algos[a], periodic ? ", periodic" : "",
                         (unsigned long long)sum.sphere_collisions, sum.max_overlap,
                         sum.max_overlap_rel);
            nbep_test_scene_free(&sc);
        }
}

/* The frame a signal's stop writes, failing (a full disk as SIGTERM comes at a job's time
 * limit): the run reports the write's failure, whose line says what was lost, not the
 * signal, whose status says the file holds the step it stopped at. A frame hook stands in for
 * the file (its failure goes the same way as a write's: sim.c, emit_frame): step 1's frame
 * raises the signal, which the predictive algorithm's step 2 (a few rounds, none of which
 * looks at the signal) leaves to its end, and step 2's frame, the stop's, fails. */
typedef struct signal_then_fail {
    atomic_int *stop;
    int sig;
    size_t frames;
} signal_then_fail;

static nbep_status signal_then_fail_frame(void *ctx, int64_t step, const nbep_state *s,
                                          nbep_diag *d)
{
    (void)s;
    signal_then_fail *f = ctx;
    f->frames++;
    if (step == 1)
        atomic_store_explicit(f->stop, f->sig, memory_order_relaxed);
    if (step < 2)
        return NBEP_OK;
    NBEP_FAIL(d, NBEP_EIO, "test: no room for frame %lld", (long long)step);
}

static void test_a_frame_that_fails_at_a_signals_stop_reports_the_failure(void **state)
{
    (void)state;
    const char *const modes[] = {"all", "grid", "cells"};
    for (int m = 0; m < 3; m++)
        for (int sig = 0; sig < 2; sig++) {
            nbep_scene *sc = nbep_test_scene_new(2, 0, "predictive", 20, 0.01);
            sc->neighbors_grid = m == 1;
            sc->neighbors_cells = m == 2;
            nbep_test_set_sphere(sc, 0, nbep_vec3_make(0.0, 0.0, 0.0),
                                 nbep_vec3_make(1.0, 0.0, 0.0), 0.5, 1.0,
                                 nbep_vec3_make(0.0, 0.0, 0.0));
            nbep_test_set_sphere(sc, 1, nbep_vec3_make(3.0, 0.0, 0.0),
                                 nbep_vec3_make(-1.0, 0.0, 0.0), 0.5, 1.0,
                                 nbep_vec3_make(0.0, 0.0, 0.0));
            sc->output_every = 1;
            atomic_int stop;
            atomic_init(&stop, 0);
            signal_then_fail f = {.stop = &stop, .sig = sig ? 2 : 15}; /* SIGINT, SIGTERM */
            nbep_diag d;
            nbep_diag_init(&d);
            nbep_sim_options opt = {.threads = 1, .stop_signal = &stop,
                                    .on_frame = signal_then_fail_frame, .on_frame_ctx = &f};
            nbep_sim *sim = NULL;
            assert_int_equal(nbep_sim_create(sc, &opt, &sim, &d), NBEP_OK);
            const nbep_status st = nbep_sim_run(sim, &d);
            if (st != NBEP_EIO || f.frames != 3 || d.n_errors != 1 ||
                !strstr(d.msg[0], "no room for frame 2"))
                fail_msg("%s, %s before a failing frame: status %d (I/O error: %d), %zu frames, "
                         "%zu lines, %s", modes[m], sig ? "SIGINT" : "SIGTERM", (int)st,
                         (int)NBEP_EIO, f.frames, d.n_errors, d.n_errors ? d.msg[0] : "");
            nbep_sim_destroy(&sim);
            nbep_diag_fini(&d);
            nbep_test_scene_free(&sc);
        }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_frames_come_at_zero_every_tenth_step_and_the_last),
        cmocka_unit_test(test_a_frame_that_fails_at_a_signals_stop_reports_the_failure),
        cmocka_unit_test(test_naive_and_seminaive_report_the_overlap_they_find),
        cmocka_unit_test(test_energy_drift_is_recomputed_from_the_first_and_last_frames),
        cmocka_unit_test(test_quiet_steps_are_the_steps_where_no_velocity_changed),
        cmocka_unit_test(test_naive_checks_every_pair_and_every_sphere_plane_once_per_step),
        cmocka_unit_test(test_two_contacts_at_the_same_time_on_one_sphere_keep_momentum),
        cmocka_unit_test(test_predictive_checks_and_predictions_follow_spec_on_a_counted_scene),
        cmocka_unit_test(test_simultaneous_contacts_sharing_a_sphere_react_in_pair_key_order),
        cmocka_unit_test(test_tc_model_makes_a_collision_within_tc_of_either_spheres_last_one_elastic),
        cmocka_unit_test(test_a_held_sphere_falls_freely_once_its_support_is_knocked_away),
        cmocka_unit_test(test_grid_mode_keeps_overlaps_at_round_off_with_speeds_over_two_decades),
        cmocka_unit_test(test_grid_mode_keeps_overlaps_at_round_off_with_equal_fast_speeds),
    };
    return cmocka_run_group_tests_name("run_contract", tests, NULL, NULL);
}
