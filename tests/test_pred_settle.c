/* Unit tests of settling's rules (src/pred_settle.c) on the predictive algorithm's own context,
 * made by nbep_sim_create for a granular scene (gravity, e = 0.5, all-pairs) and set by hand:
 * which steps count as slow, which spheres are candidates, which supports a candidate keeps,
 * and what a hold writes. test_granular and test_settle.sh show that piles come to rest; these
 * pin the rules those scenes pass through too rarely to fail on (a peak inside a step, a
 * sphere held already, more supports than a record holds, plane 0 among a candidate's supports
 * in a later round). And the lasting state these rules leave, as the algorithm exports it for
 * the file's checkpoint (each sphere's faces met, its own). One thread: the sub-phases'
 * barriers are then one thread's. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "pred_impl.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

#define G 9.81
#define DT 1.0e-3
#define FLOOR 0 /* plane 0: z = 0, facing up */

typedef struct fix {
    nbep_scene *sc;
    nbep_sim *sim;
    pred_ctx *c;
} fix;

/* n spheres, plane 0 the floor; each sphere is set with put, then fix_create. */
static void fix_scene(fix *f, size_t n)
{
    *f = (fix){.sc = nbep_test_scene_new(n, 1, "predictive", 100, DT)};
    f->sc->restitution = 0.5;
    nbep_test_set_plane(f->sc, FLOOR, (nbep_vec3){0.0, 0.0, 1.0}, 0.0);
}

/* Sphere i of mass 1 at p, at rest, under gravity. */
static void put(fix *f, size_t i, nbep_vec3 p, double r)
{
    nbep_test_set_sphere(f->sc, i, p, ZERO3, r, 1.0, (nbep_vec3){0.0, 0.0, -G});
}

static void fix_create(fix *f)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_sim_options opt = {.threads = 1};
    assert_int_equal(nbep_sim_create(f->sc, &opt, &f->sim, &d), NBEP_OK);
    nbep_diag_fini(&d);
    f->c = f->sim->algo_ctx;
    assert_non_null(f->c->settle); /* the model is there: gravity and e < 1 */
    assert_int_equal(f->c->nt, 1);
}

static void fix_free(fix *f)
{
    nbep_sim_destroy(&f->sim);
    nbep_test_scene_free(&f->sc);
}

/* Sphere i held on what `who` names (a plane, or -1 - j for sphere j), as the engine holds one:
 * no velocity and no acceleration. */
static void hold(fix *f, size_t i, int32_t who)
{
    f->c->rest[i] = (rest_set){.who = {who}, .n = 1, .still = true};
    f->sim->st.vel[i] = ZERO3;
    f->c->aeff[i] = ZERO3;
}

/* The update's count for every sphere at `steps` step ends in a row (nothing moves between
 * them); the candidates at the last, as the update leaves them for settle_phases. */
static size_t step_ends(fix *f, unsigned steps)
{
    size_t cands = 0;
    for (unsigned k = 0; k < steps; k++) {
        cands = 0;
        for (size_t i = 0; i < f->sim->st.n; i++)
            cands += nbep__pred_settle_count(f->c, &f->sim->st, i, DT);
    }
    f->c->ws[0].n_settle = cands;
    return cands;
}

static bool phases(fix *f)
{
    return nbep__pred_settle_phases(f->sim, f->c, (nbep_range){0, f->sim->st.n}, &f->c->ws[0]);
}

/* A step counts as slow only if the sphere's highest speed inside it, not only its speed at the
 * step's end, stayed at or below the settle speed: a sphere that hops on the floor and is slow
 * at each step's end is no candidate. */
static void test_a_fast_moment_inside_a_step_starts_the_window_again(void **state)
{
    (void)state;
    fix f;
    fix_scene(&f, 1);
    put(&f, 0, (nbep_vec3){0.0, 0.0, 0.01}, 0.01);
    fix_create(&f);
    nbep_state *s = &f.sim->st;
    const double vs = settle_speed(s, 0, DT);
    assert_true(vs > 0.0);
    assert_int_equal(step_ends(&f, SETTLE_STEPS - 1), 0);
    /* the last step of the window: fast at an event (settle_note, as advance_to and a
     * reaction call it), slow again at its end */
    s->vel[0] = (nbep_vec3){0.0, 0.0, 1.5 * vs};
    settle_note(f.c, s, 0);
    s->vel[0] = ZERO3;
    assert_false(nbep__pred_settle_count(f.c, s, 0, DT));
    assert_int_equal(f.c->settle[0].slow, 0);
    /* the window starts again: SETTLE_STEPS slow steps from here, the last one at exactly the
     * settle speed inside it (counts: at or below) */
    assert_int_equal(step_ends(&f, SETTLE_STEPS - 1), 0);
    s->vel[0] = (nbep_vec3){0.0, 0.0, vs};
    settle_note(f.c, s, 0);
    s->vel[0] = ZERO3;
    assert_true(nbep__pred_settle_count(f.c, s, 0, DT));
    fix_free(&f);
}

/* A held sphere is no candidate, however long it has been still: it keeps the supports it was
 * held on and its response count (a new hold would make every prediction naming it stale),
 * while a slow sphere resting on it is held on it. */
static void test_a_held_sphere_is_no_candidate_and_keeps_its_hold(void **state)
{
    (void)state;
    fix f;
    fix_scene(&f, 2);
    const double r = 0.01;
    put(&f, 0, (nbep_vec3){0.0, 0.0, r}, r);
    put(&f, 1, (nbep_vec3){0.0, 0.0, 3.0 * r}, r);
    fix_create(&f);
    hold(&f, 0, FLOOR);
    f.c->rest[0].ver[0] = 7; /* any mark: a hold would set it from the floor's (0) */
    const uint64_t ver0 = f.c->ver[0];
    for (unsigned k = 0; k < 2 * SETTLE_STEPS; k++)
        assert_false(nbep__pred_settle_count(f.c, &f.sim->st, 0, DT));
    assert_int_equal(step_ends(&f, SETTLE_STEPS), 1); /* sphere 1 only */
    assert_false(f.c->settle[0].cand);
    assert_true(f.c->settle[1].cand);
    assert_true(phases(&f));
    assert_int_equal(f.c->ver[0], ver0);
    assert_int_equal(f.c->rest[0].n, 1);
    assert_int_equal(f.c->rest[0].who[0], FLOOR);
    assert_int_equal(f.c->rest[0].ver[0], 7);
    const rest_set *r1 = &f.c->rest[1];
    assert_true(r1->still);
    assert_int_equal(r1->n, 1);
    assert_int_equal(r1->who[0], -1 - 0);
    assert_int_equal(r1->ver[0], ver0);
    fix_free(&f);
}

/* Sphere 0 (radius 1) at (0, 0, 5), touching spheres 1..n-1 (radius 0.25) below it, each at
 * its polar angle from straight below and its azimuth (degrees). */
static void put_on_supports(fix *f, size_t n, const double *polar, const double *azim)
{
    const double R = 1.0, r = 0.25, d = R + r, deg = atan(1.0) / 45.0;
    const nbep_vec3 top = {0.0, 0.0, 5.0};
    put(f, 0, top, R);
    for (size_t j = 1; j < n; j++) {
        const double th = polar[j] * deg, ph = azim[j] * deg;
        nbep_vec3 u = {sin(th) * cos(ph), sin(th) * sin(ph), -cos(th)};
        put(f, j, nbep_vec3_add(top, nbep_vec3_scale(u, d)), r);
    }
}

/* h holds spheres from..to-1 as supports, each with its count as the tests set it (10 + j). */
static void held_on(const rest_set *h, size_t from, size_t to)
{
    for (size_t j = from; j < to; j++) {
        assert_true(rest_has_sphere(h, j));
        for (int k = 0; k < h->n; k++)
            if (h->who[k] == -1 - (int32_t)j)
                assert_int_equal(h->ver[k], 10 + j);
    }
}

/* A candidate touching more supports than a record holds (NBEP_CONTACT_MAX = 4) keeps the most
 * nearly below it: a large sphere on five small held ones, one of them far to the side and met
 * first (index 1), the others straight below and at 40 degrees all round. The side one goes;
 * the hold writes no velocity, no acceleration, a new response count, the supports' counts
 * and the sphere's block energy. */
static void test_of_more_supports_than_a_record_holds_the_most_nearly_below_are_kept(
    void **state)
{
    (void)state;
    assert_int_equal(NBEP_CONTACT_MAX, 4);
    fix f;
    fix_scene(&f, 6);
    /* polar angle from straight below and azimuth of each support 1..5, degrees */
    const double polar[6] = {0, 75, 0, 40, 40, 40}, azim[6] = {0, 60, 0, 0, 120, 240};
    put_on_supports(&f, 6, polar, azim);
    fix_create(&f);
    nbep_state *s = &f.sim->st;
    /* sphere 0 slow but moving, so that its block energy changes when it is held */
    s->vel[0] = (nbep_vec3){0.5 * settle_speed(s, 0, DT), 0.0, 0.0};
    for (size_t j = 1; j < 6; j++) {
        hold(&f, j, FLOOR); /* held (only that counts here, not on what) */
        f.c->ver[j] = 10 + j;
    }
    nbep__sim_block_energy(f.sim, (nbep_range){0, s->n});
    const double ke_before = f.sim->block_ke[0];
    assert_true(ke_before > 0.0);
    const uint64_t ver0 = f.c->ver[0];
    f.c->aeff[0] = s->acc[0];
    assert_int_equal(step_ends(&f, SETTLE_STEPS), 1);
    assert_true(phases(&f));

    const rest_set *h = &f.c->rest[0];
    assert_true(h->still);
    assert_true(f.c->settle[0].more);
    assert_int_equal(h->n, 4);
    assert_false(rest_has_sphere(h, 1));
    held_on(h, 2, 6);
    assert_true(nbep_vec3_norm2(s->vel[0]) == 0.0);
    assert_true(nbep_vec3_norm2(f.c->aeff[0]) == 0.0);
    assert_int_equal(f.c->ver[0], ver0 + 1);
    double ke, pe;
    nbep_physics_energy(s, 0, s->n, &ke, &pe);
    assert_true(ke == 0.0);
    assert_true(f.sim->block_ke[0] == ke); /* taken again: not ke_before */
    fix_free(&f);
}

/* Plane 0 stays a support in the rounds after the first: a large sphere on the floor (plane 0)
 * also touches a small one below its centre that hangs in the air. The small one has no
 * support and is lost in the first round; in the next the large one drops it and is held on
 * the floor alone. (Planes are who >= 0 and spheres who < 0: plane 0 taken for a sphere would
 * read the record before sphere 0's. The records here sit after a zeroed guard, so that such
 * a read says "not held, not live" instead of whatever lies before the array.) */
static void test_plane_zero_stays_a_support_in_a_later_round(void **state)
{
    (void)state;
    fix f;
    fix_scene(&f, 2);
    const double R = 1.0, r = 0.2, z = 0.5;
    put(&f, 0, (nbep_vec3){0.0, 0.0, R}, R);
    put(&f, 1, (nbep_vec3){sqrt((R + r) * (R + r) - (R - z) * (R - z)), 0.0, z}, r);
    fix_create(&f);
    settle_rec *own = f.c->settle, *guarded = calloc(3, sizeof *guarded);
    assert_non_null(guarded);
    memcpy(guarded + 1, own, 2 * sizeof *own);
    f.c->settle = guarded + 1;
    assert_int_equal(step_ends(&f, SETTLE_STEPS), 2);
    const bool held = phases(&f);
    const settle_rec x0 = f.c->settle[0];
    f.c->settle = own;
    free(guarded);

    assert_true(held);
    assert_int_equal(x0.n_sup, 1);
    assert_int_equal(x0.sup[0], FLOOR);
    const rest_set *h = &f.c->rest[0];
    assert_true(h->still);
    assert_int_equal(h->n, 1);
    assert_int_equal(h->who[0], FLOOR);
    assert_false(f.c->rest[1].still);
    fix_free(&f);
}

/* A jammed body whose walk starts at a sphere without acceleration of its own (in a scene
 * where the others fall): its settle speed is 0, so its touching tolerance is 0 (jam_lock:
 * "touching to 0, not 0/0"), and a sphere in the jam that touches it exactly joins the body
 * and moves on with it; at 0/0, NaN, no sphere past the pair would. Three spheres of radius
 * 0.5 in a row, 1 apart (touching to the last bit), in mid-air; all three in the jam. */
static void test_a_jam_from_a_sphere_without_acceleration_takes_in_one_touching_it(void **state)
{
    (void)state;
    fix f;
    fix_scene(&f, 3);
    put(&f, 0, (nbep_vec3){0.0, 0.0, 5.0}, 0.5);
    put(&f, 1, (nbep_vec3){1.0, 0.0, 5.0}, 0.5);
    put(&f, 2, (nbep_vec3){-1.0, 0.0, 5.0}, 0.5);
    f.sc->state.acc[0] = ZERO3;
    f.sc->state.vel[0] = (nbep_vec3){1.0, 0.0, 0.0};
    f.sc->state.vel[1] = (nbep_vec3){-1.0, 0.0, 0.0};
    f.sc->state.vel[2] = (nbep_vec3){0.5, 0.0, 0.0};
    fix_create(&f);
    pred_ctx *c = f.c;
    thread_ws *w = &c->ws[0];
    for (size_t k = 0; k < 3; k++) /* jammed: the reactions that make a jam, this step */
        c->jam[k] = (jam_count){.step = w->jam_step, .n = NBEP_JAM_HOLD};
    w->lock[0] = (uint64_t)0 << 32 | 1u; /* the pair 0, 1 met (lo 0: no acceleration) */
    w->n_lock = 1;
    nbep_state *s = &f.sim->st;
    nbep__pred_lock_phase(c, s, 1, DT, 0.0, w);
    /* one body of the three: the mean velocity by mass, sphere 2's too */
    const double v = (1.0 - 1.0 + 0.5) / 3.0;
    for (size_t k = 0; k < 3; k++)
        if (!(fabs(s->vel[k].x - v) <= 1e-15 && s->vel[k].y == 0.0))
            fail_msg("sphere %zu after the lock: velocity (%.17g, %.17g, %.17g), the body's "
                     "x %.17g", k, s->vel[k].x, s->vel[k].y, s->vel[k].z, v);
    fix_free(&f);
}

/* A let-go keeps the supports that did not react: a large sphere held on four small held
 * ones (three at 40 degrees all round, one straight below), whose one below reacted (its
 * response count moved on). nbep__pred_let_go drops that one only; the three left carry the
 * sphere's weight, so it stays held on them, their counts as they were. (The piles reach a
 * let-go with a second sphere support too rarely to fail on a check that dropped them all.) */
static void test_a_let_go_keeps_the_supports_that_did_not_react(void **state)
{
    (void)state;
    fix f;
    fix_scene(&f, 5);
    const double polar[5] = {0, 40, 40, 40, 0}, azim[5] = {0, 0, 120, 240, 0};
    put_on_supports(&f, 5, polar, azim);
    fix_create(&f);
    nbep_state *s = &f.sim->st;
    rest_set held = {.n = 4, .still = true};
    for (size_t j = 1; j < 5; j++) {
        hold(&f, j, FLOOR);
        f.c->ver[j] = 10 + j;
        held.who[j - 1] = -1 - (int32_t)j;
        held.ver[j - 1] = 10 + j;
    }
    hold(&f, 0, FLOOR);
    f.c->rest[0] = held;
    f.c->ver[4]++; /* the one below reacted */
    nbep__pred_let_go(f.c, s, 0, DT, 0.0, &f.c->ws[0]);
    const rest_set *h = &f.c->rest[0];
    assert_true(h->still);
    assert_int_equal(h->n, 3);
    assert_false(rest_has_sphere(h, 4));
    held_on(h, 1, 4);
    assert_true(nbep_vec3_norm2(s->vel[0]) == 0.0);
    fix_free(&f);
}

/* The faces a sphere met (the TC model's cage) go to the file's lasting state as its own: the
 * algorithm's export (export_contacts, what /checkpoint/contacts keeps and a resume reads back)
 * gives each sphere the faces of its own record, newest first, and none where it met none.
 * Five spheres, each with its own faces set by hand (some with fewer than CAGE_FACES). */
static void test_each_sphere_exports_the_faces_it_met(void **state)
{
    (void)state;
    fix f;
    const size_t n = 5;
    fix_scene(&f, n);
    f.sc->tc = 1e-4; /* the TC model, and under gravity its cage */
    for (size_t i = 0; i < n; i++)
        put(&f, i, (nbep_vec3){0.1 * (double)i, 0.0, 0.02}, 0.01);
    fix_create(&f);
    assert_non_null(f.c->face);
    assert_non_null(f.sim->algo->export_contacts);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < CAGE_FACES; k++) {
            face_met *m = &f.c->face[i * CAGE_FACES + k];
            if ((size_t)k > i % CAGE_FACES) { /* sphere i met i % CAGE_FACES + 1 faces */
                *m = (face_met){.t = -INFINITY, .who = INT32_MIN};
                continue;
            }
            *m = (face_met){.t = 0.5 - 0.01 * (double)(10 * i + (size_t)k),
                            .n = {0.0, 0.0, 1.0},
                            .p = {0.1 * (double)i, 0.0, 0.01},
                            .who = k == 0 ? FLOOR : -1 - (int32_t)((i + 1) % n)};
        }
    nbep_contact_rec rec[5];
    f.sim->algo->export_contacts(f.c, 0, n, rec);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < CAGE_FACES; k++) {
            const face_met *m = &f.c->face[i * CAGE_FACES + k];
            const bool met = m->t > -INFINITY;
            if (rec[i].face_who[k] != (met ? m->who : INT32_MIN) ||
                (met && (rec[i].face_t[k] != m->t || rec[i].face_p[k][0] != m->p.x)))
                fail_msg("sphere %zu, face %d: exported who %d at %g, met %d at %g", i, k,
                         (int)rec[i].face_who[k], rec[i].face_t[k], (int)m->who, m->t);
        }
    fix_free(&f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_fast_moment_inside_a_step_starts_the_window_again),
        cmocka_unit_test(test_a_held_sphere_is_no_candidate_and_keeps_its_hold),
        cmocka_unit_test(test_of_more_supports_than_a_record_holds_the_most_nearly_below_are_kept),
        cmocka_unit_test(test_plane_zero_stays_a_support_in_a_later_round),
        cmocka_unit_test(test_a_jam_from_a_sphere_without_acceleration_takes_in_one_touching_it),
        cmocka_unit_test(test_a_let_go_keeps_the_supports_that_did_not_react),
        cmocka_unit_test(test_each_sphere_exports_the_faces_it_met),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
