/* Tests of the per-slab calendars (slabcal.h): the merged earliest entry is one calendar's,
 * entry for entry, under random sets (to random slabs, so entries move between slabs and slabs
 * outgrow their rooms), removals, clears and retunes, with ties in time and key; ties within
 * a slab by item, not by local number; each entry lives in one slab; the slabs of cell
 * columns; refusals. A growth's refused memory is test_memory_plan's. The engine's use (frames
 * bit for bit for any slab count) is test_sim's. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "nbep/slabcal.h"
#include "nbep_test.h"

static nbep_slabcal *make(size_t n, int slabs)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_slabcal *s = NULL;
    assert_int_equal(nbep_slabcal_create(n, slabs, &s, &d), NBEP_OK);
    nbep_diag_fini(&d);
    return s;
}

/* An entry set, which must be taken (slabs grow as their items need). */
static void put(nbep_slabcal *s, int slab, uint32_t item, double time, uint64_t key)
{
    assert_true(nbep_slabcal_set(s, slab, item, time, key));
}

static uint64_t lcg(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return *x >> 33;
}

/* A random slab, but for every third thousand operations slab 0 (most entries crowd into it
 * then, past its first room, so it grows, and later its local numbers are given back). */
static int herd(uint64_t *x, int op, int slabs)
{
    const int k = (int)(lcg(x) % (uint64_t)slabs);
    return (op / 1000) % 3 == 1 ? 0 : k;
}

/* Both give the same earliest entry, or both none. */
static void same_first(nbep_slabcal *s, nbep_calendar *one, int slabs, int op)
{
    nbep_calendar_entry a, b;
    const bool has_a = nbep_slabcal_first(s, &a), has_b = nbep_calendar_first(one, &b);
    if (has_a != has_b || (has_a && (a.item != b.item || a.time != b.time || a.key != b.key)))
        fail_msg("%d slabs, op %d: merged first %s (item %u, t %.17g, key %llu), one "
                 "calendar's %s (item %u, t %.17g, key %llu)",
                 slabs, op, has_a ? "" : "none", has_a ? a.item : 0u, has_a ? a.time : 0.0,
                 has_a ? (unsigned long long)a.key : 0ull, has_b ? "" : "none",
                 has_b ? b.item : 0u, has_b ? b.time : 0.0,
                 has_b ? (unsigned long long)b.key : 0ull);
}

/* The reference is one calendar under the same operations (test_calendar holds it to a brute
 * force minimum). Times come from a few values and keys from a few, so that ties in time and
 * in (time, key) are common; a set names a random slab, so most sets of an item with an entry
 * move it to another slab, as an expiry moves a sphere's entry when its list centre crosses
 * into another slab. After every operation the merged first is the reference's, and every
 * 97th the invariants hold; at the end both drain in the same order. */
static void test_the_merged_first_is_one_calendars_under_random_operations(void **state)
{
    (void)state;
    enum { N = 150, OPS = 12000 };
    for (int slabs = 2; slabs <= 5; slabs++) {
        nbep_slabcal *s = make(N, slabs);
        const size_t room = nbep_slabcal_room_of(s, 0);
        nbep_diag d;
        nbep_diag_init(&d);
        nbep_calendar *one = NULL;
        assert_int_equal(nbep_calendar_create(N, &one, &d), NBEP_OK);
        nbep_diag_fini(&d);
        uint64_t x = 777 + (uint64_t)slabs;
        double now = 0.0;
        for (int op = 0; op < OPS; op++) {
            const uint32_t i = (uint32_t)(lcg(&x) % N);
            const uint64_t what = lcg(&x) % 100;
            if (what < 20) {
                nbep_slabcal_remove(s, i);
                nbep_calendar_remove(one, i);
            } else if (what == 20 && (op / 1000) % 3 != 1) { /* (no clear in a herd) */
                nbep_slabcal_clear(s);
                nbep_calendar_clear(one);
            } else if (what == 21) {
                nbep_slabcal_retune(s, now);
                nbep_calendar_retune(one, now);
            } else if (what < 30) { /* the earliest handled: a later entry for its item */
                nbep_calendar_entry e;
                if (nbep_slabcal_first(s, &e)) {
                    now = e.time;
                    const double t = now + 0.25 * (double)(1 + lcg(&x) % 8);
                    const uint64_t key = lcg(&x) % 3;
                    const int slab = herd(&x, op, slabs);
                    put(s, slab, e.item, t, key);
                    nbep_calendar_set(one, e.item, t, key);
                }
            } else {
                const double t = now + 0.25 * (double)(lcg(&x) % 12);
                const uint64_t key = lcg(&x) % 3;
                const int slab = herd(&x, op, slabs);
                put(s, slab, i, t, key);
                nbep_calendar_set(one, i, t, key);
                assert_int_equal(nbep_slabcal_slab(s, i), slab);
            }
            same_first(s, one, slabs, op);
            assert_int_equal(nbep_slabcal_size(s), nbep_calendar_size(one));
            if (op % 97 == 0)
                assert_int_equal(nbep_slabcal_check(s), 0);
        }
        size_t drained = 0;
        nbep_calendar_entry e;
        while (nbep_slabcal_first(s, &e)) {
            same_first(s, one, slabs, OPS + (int)drained);
            nbep_slabcal_remove(s, e.item);
            nbep_calendar_remove(one, e.item);
            assert_int_equal(nbep_slabcal_slab(s, e.item), -1);
            drained++;
        }
        assert_false(nbep_calendar_first(one, &e));
        assert_int_equal(nbep_slabcal_check(s), 0);
        if (nbep_slabcal_room_of(s, 0) <= room) /* the herds grew slab 0 */
            fail_msg("%d slabs: slab 0's room %zu, its first %zu", slabs,
                     nbep_slabcal_room_of(s, 0), room);
        nbep_calendar_destroy(&one);
        nbep_slabcal_destroy(&s);
        assert_null(s);
    }
}

/* An entry set in another slab leaves its first: it is held once, by the slab named last, and
 * the slab it left no longer gives it (nor its kept earliest). */
static void test_an_entry_set_in_another_slab_moves_there(void **state)
{
    (void)state;
    nbep_slabcal *s = make(4, 3);
    nbep_calendar_entry e;
    assert_false(nbep_slabcal_first(s, &e));
    put(s, 0, 2, 1.0, 0);
    put(s, 1, 3, 2.0, 0);
    assert_true(nbep_slabcal_first(s, &e));
    assert_int_equal(e.item, 2);
    put(s, 2, 2, 3.0, 0); /* later, elsewhere: 3 comes first now */
    assert_int_equal(nbep_slabcal_slab(s, 2), 2);
    assert_int_equal(nbep_slabcal_size_of(s, 0), 0);
    assert_int_equal(nbep_slabcal_size_of(s, 2), 1);
    assert_int_equal(nbep_slabcal_size(s), 2);
    assert_true(nbep_slabcal_first(s, &e));
    assert_int_equal(e.item, 3);
    assert_true(e.time == 2.0);
    put(s, 1, 2, 0.5, 0); /* earlier, in 3's slab */
    assert_true(nbep_slabcal_first(s, &e));
    assert_int_equal(e.item, 2);
    assert_int_equal(nbep_slabcal_size_of(s, 2), 0);
    assert_int_equal(nbep_slabcal_check(s), 0);
    nbep_slabcal_remove(s, 0); /* none: harmless */
    nbep_slabcal_clear(s);
    assert_false(nbep_slabcal_first(s, &e));
    assert_int_equal(nbep_slabcal_slab(s, 2), -1);
    assert_int_equal(nbep_slabcal_check(s), 0);
    nbep_slabcal_destroy(&s);
    nbep_slabcal_destroy(&s); /* NULL-safe */
}

/* Equal times across slabs come out by key, then by item, whichever slab holds them. */
static void test_ties_across_slabs_come_out_by_key_then_item(void **state)
{
    (void)state;
    nbep_slabcal *s = make(6, 3);
    const uint64_t keys[6] = {5, 1, 5, 1, 0, 9};
    for (uint32_t i = 0; i < 6; i++)
        put(s, (int)(5 - i) % 3, i, 1.0, keys[i]);
    const uint32_t order[6] = {4, 1, 3, 0, 2, 5};
    for (int k = 0; k < 6; k++) {
        nbep_calendar_entry e;
        assert_true(nbep_slabcal_first(s, &e));
        assert_int_equal(e.item, order[k]);
        nbep_slabcal_remove(s, e.item);
    }
    nbep_slabcal_destroy(&s);
}

/* Within one slab, ties in (time, key) come out by item, as from one calendar, whatever local
 * numbers the items hold: taken from the highest item down, then given back and taken again
 * in another order. */
static void test_ties_in_one_slab_come_out_by_item_not_local_number(void **state)
{
    (void)state;
    nbep_slabcal *s = make(10, 2);
    for (uint32_t i = 9; i >= 5; i--) /* local numbers 0 to 4 for items 9 down to 5 */
        put(s, 1, i, 1.0, 4);
    nbep_slabcal_remove(s, 8);
    nbep_slabcal_remove(s, 6);
    put(s, 1, 2, 1.0, 4); /* the local numbers 8 and 6 gave back, in reverse */
    put(s, 1, 3, 1.0, 4);
    put(s, 0, 4, 1.0, 4); /* and one in the other slab, between them */
    put(s, 1, 1, 1.0, 5); /* a later key: last */
    assert_int_equal(nbep_slabcal_check(s), 0);
    const uint32_t order[7] = {2, 3, 4, 5, 7, 9, 1};
    for (int k = 0; k < 7; k++) {
        nbep_calendar_entry e;
        assert_true(nbep_slabcal_first(s, &e));
        if (e.item != order[k])
            fail_msg("tie %d: item %u came out, not %u", k, e.item, order[k]);
        nbep_slabcal_remove(s, e.item);
    }
    nbep_slabcal_destroy(&s);
}

/* The runners-up (for fetching ahead) are entries held that did not come out first: the next
 * slab's earliest among them, and in one slab its own runner-up; none before a first or when
 * empty. */
static void test_runners_up_name_held_entries_after_the_first(void **state)
{
    (void)state;
    nbep_slabcal *s = make(8, 2);
    uint32_t up[2];
    int m = -1;
    nbep_slabcal_runners_up(s, up, &m);
    assert_int_equal(m, 0);
    put(s, 0, 1, 1.0, 0);
    put(s, 0, 2, 1.5, 0);
    put(s, 1, 5, 2.0, 0);
    nbep_calendar_entry e;
    assert_true(nbep_slabcal_first(s, &e));
    assert_int_equal(e.item, 1);
    nbep_slabcal_runners_up(s, up, &m);
    assert_int_equal(m, 2);
    assert_int_equal(up[0], 2); /* its slab's runner-up */
    assert_int_equal(up[1], 5); /* the other slab's earliest */
    nbep_slabcal_prefetch(s, 5);
    nbep_slabcal_prefetch(s, 7); /* none: harmless */
    nbep_slabcal_remove(s, 1);
    nbep_slabcal_remove(s, 2);
    assert_true(nbep_slabcal_first(s, &e));
    assert_int_equal(e.item, 5);
    nbep_slabcal_runners_up(s, up, &m);
    assert_int_equal(m, 0);
    nbep_slabcal_destroy(&s);
}

/* The slabs of cell columns: in order, each slab's columns a run of widths differing by one
 * at most, every slab holding one when there are as many columns as slabs or more. */
static void test_cell_columns_fall_into_slabs_of_even_widths_in_order(void **state)
{
    (void)state;
    for (size_t columns = 1; columns <= 40; columns++)
        for (int slabs = 2; slabs <= 9; slabs++) {
            size_t width[NBEP_SLABCAL_MAX] = {0};
            int last = 0;
            for (size_t x = 0; x < columns; x++) {
                const int k = nbep_slabcal_slab_of(x, columns, slabs);
                assert_true(k >= last && k < slabs);
                last = k;
                width[k]++;
            }
            size_t lo = columns, hi = 0;
            for (int k = 0; k < slabs; k++) {
                lo = width[k] < lo ? width[k] : lo;
                hi = width[k] > hi ? width[k] : hi;
            }
            if (hi - lo > 1 || (columns >= (size_t)slabs && lo == 0))
                fail_msg("%zu columns on %d slabs: widths %zu to %zu", columns, slabs, lo, hi);
        }
    assert_int_equal(nbep_slabcal_slab_of(0, 0, 4), 0);
}

/* A slab count outside 2 to NBEP_SLABCAL_MAX, or more items than a calendar links, is refused
 * with one line and nothing made. */
static void test_slab_counts_and_sizes_out_of_range_are_refused(void **state)
{
    (void)state;
    const int counts[3] = {1, 0, NBEP_SLABCAL_MAX + 1};
    for (int k = 0; k < 3; k++) {
        nbep_diag d;
        nbep_diag_init(&d);
        nbep_slabcal *s = NULL;
        assert_int_equal(nbep_slabcal_create(10, counts[k], &s, &d), NBEP_EDECK);
        assert_null(s);
        assert_int_equal(d.n_errors, 1);
        assert_non_null(strstr(d.msg[0], "take 2 to 64 slabs"));
        nbep_diag_fini(&d);
    }
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_slabcal *s = NULL;
    assert_int_equal(nbep_slabcal_create(NBEP_CALENDAR_MAX + 1, 2, &s, &d), NBEP_EDECK);
    assert_null(s);
    assert_int_equal(d.n_errors, 1);
    nbep_diag_fini(&d);
    s = make(10, NBEP_SLABCAL_MAX);
    assert_int_equal(nbep_slabcal_slabs(s), NBEP_SLABCAL_MAX);
    put(s, NBEP_SLABCAL_MAX - 1, 9, 1.0, 0);
    assert_int_equal(nbep_slabcal_slab(s, 9), NBEP_SLABCAL_MAX - 1);
    assert_int_equal(nbep_slabcal_check(s), 0);
    nbep_slabcal_destroy(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_merged_first_is_one_calendars_under_random_operations),
        cmocka_unit_test(test_an_entry_set_in_another_slab_moves_there),
        cmocka_unit_test(test_ties_across_slabs_come_out_by_key_then_item),
        cmocka_unit_test(test_ties_in_one_slab_come_out_by_item_not_local_number),
        cmocka_unit_test(test_runners_up_name_held_entries_after_the_first),
        cmocka_unit_test(test_cell_columns_fall_into_slabs_of_even_widths_in_order),
        cmocka_unit_test(test_slab_counts_and_sizes_out_of_range_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
