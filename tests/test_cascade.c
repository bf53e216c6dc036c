/* Stamps in the serial loop's order (src/cascade.c): by hand, a cradle's chain, siblings
 * between a child and its parent, a key made again after its subtree, a later time, the depth
 * bound; then against a plain model of the serial loop at one time (take the least key
 * pending; each event taken makes a few entries of random keys, some already taken, some
 * pending): the stamps of the entries taken rise strictly, in thousands of random cascades.
 * (tests/test_stamp_order.c checks the same on the cells engine itself.) */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "nbep/cascade.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

/* *by's entry made at (t, key) for item 7 (the item orders only entries of one key), which
 * must succeed */
static nbep_cascade made(const nbep_cascade *by, double t, uint64_t key)
{
    nbep_cascade c;
    assert_true(nbep_cascade_made(by, t, key, 7, &c));
    return c;
}

static void assert_before(const nbep_cascade *a, const nbep_cascade *b)
{
    assert_true(nbep_cascade_cmp(a, b) < 0);
    assert_true(nbep_cascade_cmp(b, a) > 0);
}

static void test_a_cradle_chain_goes_one_level_down_an_event(void **state)
{
    (void)state;
    /* keys (3,4), (2,3), (1,2), (0,1) at one time: each the child of the one before */
    const uint64_t k[4] = {3ull << 32 | 4, 2ull << 32 | 3, 1ull << 32 | 2, 0ull << 32 | 1};
    nbep_cascade c = nbep_cascade_root(0.5, k[0], 7);
    for (uint32_t j = 1; j < 4; j++) {
        const nbep_cascade next = made(&c, 0.5, k[j]);
        assert_int_equal(next.depth, j + 1);
        assert_true(next.level[j].key == k[j]);
        assert_memory_equal(next.level, c.level, j * sizeof *c.level);
        assert_before(&c, &next);
        c = next;
    }
    /* a later time: a root, after the whole cascade */
    const nbep_cascade later = made(&c, 0.75, 0);
    assert_int_equal(later.depth, 1);
    assert_true(later.level[0].key == 0 && later.t == 0.75);
    assert_before(&c, &later);
}

static void test_siblings_fall_between_their_parents_keys(void **state)
{
    (void)state;
    const nbep_cascade root = nbep_cascade_root(1.0, 100, 7);
    const nbep_cascade c30 = made(&root, 1.0, 30), c50 = made(&root, 1.0, 50);
    assert_before(&root, &c30);
    assert_before(&c30, &c50);
    /* c30's makings: 60 a sibling (between 50 and the root's next), 40 between 30 and 50,
     * 20 its child, 150 a new root, 100 the root made again after the root's whole subtree */
    const nbep_cascade s60 = made(&c30, 1.0, 60), s40 = made(&c30, 1.0, 40);
    const nbep_cascade c20 = made(&c30, 1.0, 20), r150 = made(&c30, 1.0, 150);
    const nbep_cascade again = made(&c30, 1.0, 100);
    assert_int_equal(s60.depth, 2);
    assert_int_equal(s40.depth, 2);
    assert_int_equal(c20.depth, 3);
    assert_int_equal(r150.depth, 1);
    assert_int_equal(again.depth, 1);
    assert_int_equal(again.level[0].again, 1);
    assert_before(&c30, &c20);
    assert_before(&c20, &s40);
    assert_before(&s40, &c50);
    assert_before(&c50, &s60);
    assert_before(&s60, &again);
    assert_before(&again, &r150);
    /* the same entry made by the event itself again: after its own children */
    const nbep_cascade self = made(&c30, 1.0, 30);
    assert_int_equal(self.level[1].again, 1);
    assert_before(&c20, &self);
    assert_before(&self, &s40);
    /* made in place */
    nbep_cascade x = c30;
    assert_true(nbep_cascade_made(&x, 1.0, 20, 7, &x));
    assert_int_equal(nbep_cascade_cmp(&x, &c20), 0);
    x = c20;
    assert_true(nbep_cascade_made(&x, 1.0, 60, 7, &x));
    assert_int_equal(nbep_cascade_cmp(&x, &s60), 0);
}

/* A pair's two entries share (t, key): the lower sphere's first, what its event makes before
 * the pair's key next, the higher sphere's after; made again, the higher one stays after. */
static void test_a_pairs_two_entries_hold_the_lower_spheres_subtree_between_them(void **state)
{
    (void)state;
    const uint64_t k = 5ull << 32 | 32;
    const nbep_cascade lo = nbep_cascade_root(0.8, k, 5), hi = nbep_cascade_root(0.8, k, 32);
    assert_before(&lo, &hi);
    nbep_cascade child;
    assert_true(nbep_cascade_made(&lo, 0.8, 2ull << 32 | 5, 5, &child));
    assert_int_equal(child.depth, 2);
    assert_before(&lo, &child);
    assert_before(&child, &hi);
    /* the child's event makes the higher sphere's entry again: a sibling of the lower one's */
    nbep_cascade hi_again;
    assert_true(nbep_cascade_made(&child, 0.8, k, 32, &hi_again));
    assert_int_equal(hi_again.depth, 1);
    assert_int_equal(nbep_cascade_cmp(&hi_again, &hi), 0);
    /* and the lower one's again: after its subtree, before the higher one's */
    nbep_cascade lo_again;
    assert_true(nbep_cascade_made(&child, 0.8, k, 5, &lo_again));
    assert_int_equal(lo_again.level[0].again, 1);
    assert_before(&child, &lo_again);
    assert_before(&lo_again, &hi);
}

static void test_a_cascade_past_the_depth_is_refused_and_leaves_the_stamp(void **state)
{
    (void)state;
    nbep_cascade c = nbep_cascade_root(2.0, 1000, 7);
    for (uint32_t j = 1; j < NBEP_CASCADE_DEPTH; j++)
        c = made(&c, 2.0, 1000 - j);
    assert_int_equal(c.depth, NBEP_CASCADE_DEPTH);
    nbep_cascade out = nbep_cascade_root(9.0, 9, 7);
    const nbep_cascade was = out;
    assert_false(nbep_cascade_made(&c, 2.0, 1, 7, &out));
    assert_int_equal(nbep_cascade_cmp(&out, &was), 0); /* (its other levels unwritten) */
    assert_true(out.t == 9.0 && out.depth == 1 && out.level[0].key == 9 && out.level[0].item == 7);
    /* a sibling or a later time still fits */
    assert_true(nbep_cascade_made(&c, 2.0, 1000 - NBEP_CASCADE_DEPTH + 2, 7, &out));
    assert_int_equal(out.depth, NBEP_CASCADE_DEPTH - 1);
    assert_true(nbep_cascade_made(&c, 2.5, 1, 7, &out));
    assert_int_equal(out.depth, 1);
}

/* The plain serial loop at one time: ITEMS items, each with one entry pending at most, of a key
 * from KEYS (so that two items share keys, as a pair's two spheres do); an item's entry made
 * while pending is made again (its key and stamp the new maker's, as a sphere's slot predicted
 * anew). Start from a few roots; take the least (key, item) pending, check its stamp rises
 * strictly over the one taken before, and make 0 to 3 entries of random items and keys. */
enum { ITEMS = 40, KEYS = 24, TRIALS = 4000, TAKEN_MAX = 400 };

static uint64_t rng = 0x9E3779B97F4A7C15u;
static uint32_t below(uint32_t n)
{
    rng ^= rng << 13, rng ^= rng >> 7, rng ^= rng << 17;
    return (uint32_t)((rng >> 11) % n);
}

static void test_the_stamps_rise_along_a_model_of_the_serial_loop(void **state)
{
    (void)state;
    size_t taken_all = 0, deep = 0, made_again = 0, max_depth = 0, twins = 0;
    for (int trial = 0; trial < TRIALS; trial++) {
        bool pending[ITEMS] = {false};
        uint64_t key[ITEMS];
        nbep_cascade stamp[ITEMS];
        for (int r = 0; r < 3; r++) {
            const uint32_t i = below(ITEMS);
            pending[i] = true;
            key[i] = below(KEYS);
            stamp[i] = nbep_cascade_root(0.0, key[i], i);
        }
        nbep_cascade last = {0};
        uint64_t last_key = 0;
        bool refused = false;
        for (size_t taken = 0; taken < TAKEN_MAX && !refused; taken++) {
            uint32_t i = ITEMS;
            for (uint32_t j = 0; j < ITEMS; j++) /* the least (key, item): j rises */
                if (pending[j] && (i == ITEMS || key[j] < key[i]))
                    i = j;
            if (i == ITEMS)
                break;
            pending[i] = false;
            const nbep_cascade now = stamp[i];
            if (taken > 0) {
                assert_true(nbep_cascade_cmp(&last, &now) < 0);
                twins += key[i] == last_key;
            }
            last = now;
            last_key = key[i];
            taken_all++;
            max_depth = now.depth > max_depth ? now.depth : max_depth;
            for (uint32_t m = below(4); m > 0; m--) {
                const uint32_t j = below(ITEMS), k = below(KEYS);
                nbep_cascade c;
                if (!nbep_cascade_made(&now, 0.0, k, j, &c)) {
                    deep++;
                    refused = true; /* the scheduler's window would end here */
                    break;
                }
                made_again += c.level[c.depth - 1].again > 0;
                pending[j] = true;
                key[j] = k;
                stamp[j] = c;
            }
        }
    }
    fprintf(stderr, "%zu entries taken in %d cascades; %zu made again; %zu after one of the "
                    "same key; deepest %zu levels; %zu cascades past the depth\n",
            taken_all, TRIALS, made_again, twins, max_depth, deep);
    /* the model met every case: depth, entries made again, shared keys, the bound */
    assert_true(max_depth == NBEP_CASCADE_DEPTH && made_again > 0 && twins > 0 && deep > 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_cradle_chain_goes_one_level_down_an_event),
        cmocka_unit_test(test_siblings_fall_between_their_parents_keys),
        cmocka_unit_test(test_a_pairs_two_entries_hold_the_lower_spheres_subtree_between_them),
        cmocka_unit_test(test_a_cascade_past_the_depth_is_refused_and_leaves_the_stamp),
        cmocka_unit_test(test_the_stamps_rise_along_a_model_of_the_serial_loop),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
