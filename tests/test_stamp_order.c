/* The cascade stamps (src/cascade.c) order the cells engine's events as its serial loop hands
 * them out: each event's stamp, made from the stamp of the event that predicted its entry, is
 * at or after the stamp of the event before. The optimistic scheme's scheduler needs that
 * (include/nbep/warp.h: its logs and its stragglers compare stamps), and the plain (time, key)
 * does not give it: an event at t may send a sphere into one it touches whose pair's key comes
 * first (a Newton's cradle numbered down the row away from the sphere that strikes it: keys
 * (3,4), then (2,3), (1,2), (0,1); its centres touch only to within an ulp, so some roots lie
 * behind now and are kept at now), and the serial loop takes that entry next.
 *
 * This test compiles its own copy of the engine with a look at every event handled: it makes
 * the stamps of the entries the event predicted (its sphere's, and those of the spheres its
 * reaction changed) from the event's own, and checks that the stamps of the events handled
 * never go back, while their (time, key) do (the scenes must meet such ties: a test that met
 * none could not fail). The scenes: the cradle (the same results on 1, 2 and 4 threads, the
 * last sphere leaving at the speed that came in), a periodic fluid at phi = 0.35 from a lattice,
 * an e = 0 pile under tilted gravity (test_late_roots's, where roots behind now are common) and
 * a pile settling at e = 0.6 with the TC model, on one thread. */
#include <stdint.h>
#include <stdlib.h>

#include "nbep/cascade.h"

static uint64_t handled, back, stamp_back, same_stamp, past_depth;
static uint32_t deepest;
static bool watching;
static double last_t;
static uint64_t last_key;
static nbep_cascade last_stamp;
/* the stamp of each sphere's entry as last predicted in an event, and whether one is known
 * (an entry predicted outside an event, as the setup's, is a root) */
static nbep_cascade *stamp_of;
static bool *known;
static size_t n_known;

static void look_reset(void)
{
    handled = back = stamp_back = same_stamp = past_depth = 0;
    deepest = 0;
    free(stamp_of);
    free(known);
    stamp_of = NULL;
    known = NULL;
    n_known = 0;
}

struct nbep_evloop;
static void look_handled(const struct nbep_evloop *e, const void *w, const void *ev);
#define NBEP_EVLOOP_HANDLED_HOOK(e, w, ev) look_handled((e), (w), (ev))
#include "../src/evloop.c"
#include "../src/evloop_team.c"

/* sphere x's entry, as its slot says, made by the event stamped *by */
static void made_by(const nbep_evloop *e, const nbep_cascade *by, uint32_t x)
{
    const nbep_event *slot = nbep_feq_slot(e->q, x);
    known[x] =
        nbep_cascade_made(by, slot->time, nbep__evloop_slot_key(x, slot), x, &stamp_of[x]);
    past_depth += !known[x];
}

static void look_handled(const nbep_evloop *e, const void *wv, const void *evv)
{
    if (!watching)
        return;
    const evl_ws *w = wv;
    const nbep_event *ev = evv;
    if (n_known != e->n) {
        free(stamp_of);
        free(known);
        n_known = e->n;
        stamp_of = malloc(n_known * sizeof *stamp_of);
        known = calloc(n_known, sizeof *known);
        assert(stamp_of && known);
    }
    const uint32_t i = w->item;
    const double t = ev->time;
    const uint64_t key = nbep__evloop_slot_key(i, ev);
    /* the stamp made with this entry, if it is the entry predicted then */
    const nbep_cascade *s = &stamp_of[i];
    const nbep_cascade_level *at = known[i] ? &s->level[s->depth - 1] : NULL;
    const bool same_entry = at && s->t == t && at->key == key && at->item == i;
    const nbep_cascade now = same_entry ? *s : nbep_cascade_root(t, key, i);
    if (handled > 0) {
        back += t < last_t || (t == last_t && key < last_key);
        const int c = nbep_cascade_cmp(&last_stamp, &now);
        stamp_back += c > 0;
        same_stamp += c == 0;
    }
    handled++;
    last_t = t;
    last_key = key;
    last_stamp = now;
    deepest = now.depth > deepest ? now.depth : deepest;
    for (size_t k = 0; k < w->n_changed; k++)
        if (w->changed[k] != i)
            made_by(e, &now, w->changed[k]);
    made_by(e, &now, i);
}

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>

#include "nbep/scene.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

static const nbep_vec3 ZERO = {0.0, 0.0, 0.0};

/* The looks' counts of the last run, printed and checked: events handled, their stamps never
 * going back, none past the depth. */
static void assert_never_back(const char *what)
{
    fprintf(stderr, "%s: %llu events handled; (time, key) went back %llu times, the stamps %llu "
                    "(%llu equal to the one before); deepest %u levels, %llu past the depth\n",
            what, (unsigned long long)handled, (unsigned long long)back,
            (unsigned long long)stamp_back, (unsigned long long)same_stamp, deepest,
            (unsigned long long)past_depth);
    assert_true(handled > 0);
    assert_int_equal(stamp_back, 0);
    assert_int_equal(past_depth, 0);
}

/* Newton's cradle in cells mode (nbep_test_cradle): spheres 3, 2, 1, 0 (r 0.37, mass 1.1)
 * touching in a row along x at rest (centres 0.3 + 0.74 k, rounded: touching to within an ulp),
 * sphere 4 coming in at u from the side of sphere 3. */
static const double CRADLE_R = 0.37, CRADLE_U = 1.3;

static nbep_scene *cradle(void)
{
    return nbep_test_cradle(4, CRADLE_R, CRADLE_U);
}

static void test_a_cradle_struck_at_its_high_end_never_hands_out_an_older_stamp(void **state)
{
    (void)state;
    nbep_scene *sc = cradle();
    nbep_state ref = {0};
    for (int nt = 1; nt <= 4; nt *= 2) {
        nbep_state fin = {0};
        look_reset();
        watching = nt == 1; /* a team handles events ahead of their turn */
        const nbep_summary s = nbep_test_run(sc, nt, NULL, NULL, &fin, NULL);
        watching = false;
        assert_int_equal(s.sphere_collisions, 4);
        /* the speed runs down the row: equal masses, e = 1, each contact swaps velocities */
        for (size_t k = 1; k < 5; k++)
            assert_true(nbep_vec3_norm(fin.vel[k]) <= 4.0 * DBL_EPSILON * CRADLE_U);
        assert_close(fin.vel[0].x, CRADLE_U, 4.0 * DBL_EPSILON, 0.0);
        assert_close(s.energy_final, s.energy_initial, 4.0 * DBL_EPSILON, 0.0);
        assert_true(s.max_overlap_rel <= 1e-12);
        if (nt == 1) {
            assert_never_back("cradle, 1 thread");
            assert_true(back > 0); /* the scene met the case, or the test proves nothing */
            nbep_diag d;
            nbep_diag_init(&d);
            assert_int_equal(nbep_state_copy(&ref, &fin, &d), NBEP_OK);
            nbep_diag_fini(&d);
        } else {
            assert_memory_equal(fin.pos, ref.pos, fin.n * sizeof *fin.pos);
            assert_memory_equal(fin.vel, ref.vel, fin.n * sizeof *fin.vel);
        }
        nbep_state_fini(&fin);
    }
    nbep_state_fini(&ref);
    nbep_test_scene_free(&sc);
}

/* 6^3 spheres at phi = 0.35 on a lattice in a periodic box (nbep_test_fluid's, walls taken
 * away), 20 steps of 0.05 (4 under valgrind) */
static void test_a_periodic_fluid_never_hands_out_an_older_stamp(void **state)
{
    (void)state;
    nbep_scene *closed = nbep_test_fluid(6, 0.35, 20, 0.05);
    nbep_scene *sc = nbep_test_scene_new(closed->state.n, 0, "predictive",
                                         nbep_test_scaled(20, 4), 0.05);
    sc->neighbors_cells = true;
    sc->output_every = 5;
    nbep_test_set_periodic_box(sc, closed->box_max.x);
    for (size_t i = 0; i < sc->state.n; i++)
        nbep_test_set_sphere(sc, i, closed->state.pos[i], closed->state.vel[i], 0.5, 1.0, ZERO);
    nbep_test_scene_free(&closed);
    look_reset();
    watching = true;
    const nbep_summary s = nbep_test_run(sc, 1, NULL, NULL, NULL, NULL);
    watching = false;
    assert_true(s.sphere_collisions > 0);
    assert_never_back("periodic fluid, phi 0.35");
    nbep_test_scene_free(&sc);
}

/* 60 spheres poured into a box under gravity tilted into a corner, e = 0 (test_late_roots's
 * cells pile: it meets roots behind now), 16 steps of 0.05 (3 under valgrind) */
static void test_a_pile_at_e_0_never_hands_out_an_older_stamp(void **state)
{
    (void)state;
    char deck[640];
    snprintf(deck, sizeof deck,
             "run: { algorithm = \"predictive\"; steps = %d; dt = 0.05; seed = 6;\n"
             "       neighbors = \"cells\"; };\n"
             "physics: { gravity = [1.0, 0.5, -9.7]; restitution = 0.0; };\n"
             "box: { min = [0.0, 0.0, 0.0]; max = [0.322, 0.322, 0.606]; };\n"
             "spheres = ( { count = 60; radius = 0.03; mass = 1.0; place = \"random\";\n"
             "              speed = 0.0; } );\n"
             "output: { every = 1; };\n",
             (int)nbep_test_scaled(16, 3));
    nbep_scene sc;
    nbep_test_load_deck("stamp-order.deck", deck, &sc);
    look_reset();
    watching = true;
    const nbep_summary s = nbep_test_run(&sc, 1, NULL, NULL, NULL, NULL);
    watching = false;
    nbep_scene_fini(&sc);
    assert_true(s.sphere_collisions > 0);
    assert_never_back("pile, e = 0");
    if (nbep_test_scaled(1, 0)) /* (under valgrind, 3 steps: for the memory alone) */
        assert_true(back > 0);
}

/* 27 spheres of unequal masses dropped in a box under gravity, e = 0.6, the TC model on
 * (test_extremes's small pile, less bouncy): they land, lean on one another and settle, held
 * spheres and lasting contacts; 600 steps of 1e-3 (about a thousand events: valgrind too) */
static void test_a_settling_pile_never_hands_out_an_older_stamp(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_scene_new(27, 6, "predictive", 600, 1e-3);
    sc->restitution = 0.6;
    sc->tc = 1e-6;
    sc->neighbors_cells = true;
    sc->output_every = 50;
    nbep_test_set_box_to(sc, (nbep_vec3){0.9, 0.9, 2.0});
    for (size_t i = 0; i < 27; i++) {
        const double x = 0.15 + 0.3 * (double)(i % 3), y = 0.15 + 0.3 * (double)(i / 3 % 3);
        const double z = 0.3 + 0.45 * (double)(i / 9), w = 0.1 * sin(1.7 * (double)i);
        nbep_test_set_sphere(sc, i, (nbep_vec3){x, y, z}, (nbep_vec3){w, -0.5 * w, 0.0}, 0.1,
                             1.0 + 0.01 * (double)i, (nbep_vec3){0, 0, -9.81});
    }
    look_reset();
    watching = true;
    const nbep_summary s = nbep_test_run(sc, 1, NULL, NULL, NULL, NULL);
    watching = false;
    nbep_test_scene_free(&sc);
    assert_true(s.sphere_collisions > 0 && s.plane_collisions > 0);
    assert_never_back("settling pile, e = 0.6");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_cradle_struck_at_its_high_end_never_hands_out_an_older_stamp),
        cmocka_unit_test(test_a_periodic_fluid_never_hands_out_an_older_stamp),
        cmocka_unit_test(test_a_pile_at_e_0_never_hands_out_an_older_stamp),
        cmocka_unit_test(test_a_settling_pile_never_hands_out_an_older_stamp),
    };
    const int failed = cmocka_run_group_tests(tests, NULL, NULL);
    look_reset();
    return failed;
}
