/* A jammed sphere is held only on something (jam_hold, src/pred_react.c): its contacts, the
 * held sphere it met, the held spheres and planes it touches. Where it met a held sphere that
 * rests on it and touched nothing else, it found nothing to be held on, and until 2026-12-05 it
 * was held all the same, with no contact at all: a sphere of radius 0.02 held 0.1 m above the
 * floor under one of 0.04 that rested on it (the tilted mixture below, at step 17). A hold with
 * no contacts is never seen in a frame (the next response that moves the sphere lets it go:
 * update_rest), so this test compiles its own copy of src/pred_react.c with a look at each
 * jam_hold: it met the case of nothing to be held on (a scene that did not could not fail),
 * and every sphere it held has contacts. The scene: 40 spheres of radius 0.02 and 40 of 0.04
 * poured at dt = 0.05 under gravity tilted into a corner, e = 0, grid mode, seed 1 (a helper's
 * granular sweep; test_settle.sh runs it a step further), one thread; 3 steps under valgrind,
 * for the memory alone.
 *
 * The same pour holds slow spheres by try_hold (a supported sphere slower than the rest speed
 * that a free one meets), and try_hold must hold only supported ones. Its one caller asks only
 * for supported spheres, so try_hold's own test of support could be turned round unseen (the
 * mutation log, pred_react.c:399: it then never holds, the piles settle otherwise, and frames
 * show only other collision counts); so this copy counts its holds too, wanting some, each of a
 * supported sphere. */
#include <stdint.h>
static uint64_t nothing_to_hold_on, jam_held, held_on_nothing;
#define NBEP_PRED_JAM_HOLD_HOOK(n) (nothing_to_hold_on += (n) == 0)
#define NBEP_PRED_HELD_HOOK(n) (jam_held++, held_on_nothing += (n) == 0)
static uint64_t slow_held, slow_held_unsupported;
#define NBEP_PRED_TRY_HOLD_HOOK(c, i) (slow_held++, slow_held_unsupported += !supported(c, i))
#include "../src/pred_react.c"

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>

#include "nbep/scene.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

static void test_a_jammed_sphere_is_held_only_on_something(void **state)
{
    (void)state;
    char deck[640];
    snprintf(deck, sizeof deck,
             "run: { algorithm = \"predictive\"; steps = %d; dt = 0.05; seed = 1;\n"
             "       neighbors = \"grid\"; };\n"
             "physics: { gravity = [2.0, 1.0, -9.0]; restitution = 0.0; };\n"
             "box: { min = [0.0, 0.0, 0.0]; max = [0.358, 0.358, 0.6]; };\n"
             "spheres = ( { count = 40; radius = 0.02; mass = 0.3; place = \"random\";\n"
             "              speed = 0.0; },\n"
             "            { count = 40; radius = 0.04; mass = 2.4; place = \"random\";\n"
             "              speed = 0.0; } );\n",
             (int)nbep_test_scaled(17, 3));
    nbep_scene sc;
    nbep_test_load_deck("hold-contacts.deck", deck, &sc);
    (void)nbep_test_run(&sc, 1, NULL, NULL, NULL, NULL);
    nbep_scene_fini(&sc);
    fprintf(stderr, "jammed spheres held: %llu, on nothing: %llu; nothing to be held on: %llu\n",
            (unsigned long long)jam_held, (unsigned long long)held_on_nothing,
            (unsigned long long)nothing_to_hold_on);
    fprintf(stderr, "slow supported spheres held: %llu, unsupported: %llu\n",
            (unsigned long long)slow_held, (unsigned long long)slow_held_unsupported);
    assert_int_equal(held_on_nothing, 0);
    assert_int_equal(slow_held_unsupported, 0);
    if (nbep_test_scaled(1, 0)) {
        assert_true(jam_held > 0);
        assert_true(nothing_to_hold_on > 0);
        assert_true(slow_held > 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_jammed_sphere_is_held_only_on_something),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
