/* The event calendar's self-check (nbep_calendar_check, which test_calendar calls after its
 * operations) against calendars broken from inside: this file compiles its own copy of
 * src/calendar.c, so that it can reach an entry's links. Each invariant the check names is
 * broken alone, on an entry of the heap, of the ring and of the overflow, and each must be
 * found; put back, the calendar passes again (a check that looked at fewer of them, or only
 * when several broke at once, would pass a calendar that hands out events out of order). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "../src/calendar.c"

#include "nbep_test.h"

#define N 256

/* A calendar of N items: after a retune at 0, items at times over [0, 400) and some far
 * beyond (the overflow), its first bucket drained into the heap by a look at the top. */
static nbep_calendar *filled(void)
{
    nbep_calendar *c = NULL;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_calendar_create(N, &c, &d), NBEP_OK);
    nbep_diag_fini(&d);
    for (uint32_t i = 0; i < N; i++)
        nbep_calendar_set(c, i, (double)((i * 37u) % 400u) + 0.25, i);
    nbep_calendar_retune(c, 0.0);
    for (uint32_t i = 0; i < N; i += 16) /* far ahead: past the ring's lap */
        nbep_calendar_set(c, i, 1.0e9 + (double)i, i);
    uint32_t top;
    double t;
    assert_true(nbep_calendar_top(c, &top, &t));
    assert_int_equal(nbep_calendar_check(c), 0);
    return c;
}

/* The first item found where `where` says (WHERE_HEAP: a heap entry past the root, so that
 * it has a parent). */
static uint32_t one_in(const nbep_calendar *c, uint32_t where)
{
    for (uint32_t i = 0; i < N; i++)
        if (c->node[i].where == where && (where != WHERE_HEAP || c->node[i].loc > 0))
            return i;
    fail_msg("no entry in part %u of the calendar", (unsigned)where);
    return NIL;
}

/* The check finds what break did to c, counting a few violations (a count, not a figure
 * wrapped past zero: a subtraction among its terms would give SIZE_MAX for one, and cancel
 * another to nothing), and passes again once it is put back (the node and the calendar's own
 * record restored whole). */
#define FOUND(c, item, what, broken)                                                        \
    do {                                                                                    \
        const node saved_ = (c)->node[item];                                                \
        const nbep_calendar cal_ = *(c);                                                    \
        const uint32_t heap0_ = (c)->heap[0];                                               \
        broken;                                                                             \
        const size_t bad_ = nbep_calendar_check(c);                                         \
        if (bad_ == 0 || bad_ > 4 * (size_t)N)                                              \
            fail_msg("%s: %zu violations counted", what, bad_);                             \
        (c)->node[item] = saved_;                                                           \
        *(c) = cal_;                                                                        \
        (c)->heap[0] = heap0_;                                                              \
        assert_int_equal(nbep_calendar_check(c), 0);                                        \
    } while (0)

static void test_each_broken_invariant_is_found(void **state)
{
    (void)state;
    nbep_calendar *c = filled();
    const uint32_t h = one_in(c, WHERE_HEAP), r = one_in(c, WHERE_RING),
                   o = one_in(c, WHERE_OVERFLOW);
    /* the heap: an item out of range, one marked elsewhere, its index wrong, before its
     * parent, of a later bucket */
    FOUND(c, h, "a heap slot holding no item", c->heap[0] = (uint32_t)N);
    FOUND(c, h, "a heap entry marked in the ring", c->node[h].where = WHERE_RING);
    FOUND(c, h, "a heap entry with another index", c->node[h].loc ^= 1u);
    FOUND(c, h, "a heap entry before its parent", c->node[h].time = -1.0);
    FOUND(c, h, "a heap entry of a later bucket", c->node[h].time = 300.0);
    /* the ring: marked elsewhere, in another slot, linked from another, of a drained bucket,
     * of a bucket past the lap, in the slot of another bucket */
    FOUND(c, r, "a ring entry marked in the overflow", c->node[r].where = WHERE_OVERFLOW);
    FOUND(c, r, "a ring entry with another slot", c->node[r].loc ^= 1u);
    FOUND(c, r, "a ring entry's back link wrong", c->node[r].prev ^= 1u);
    FOUND(c, r, "a ring entry of a drained bucket", c->node[r].time = -1.0);
    FOUND(c, r, "a ring entry past the lap", c->node[r].time = 1.0e8);
    FOUND(c, r, "a ring entry in another bucket's slot",
          c->node[r].time += c->w * (double)(c->nb / 2));
    /* the overflow: marked elsewhere, its back link wrong, below the overflow's least bucket */
    FOUND(c, o, "an overflow entry marked in the ring", c->node[o].where = WHERE_RING);
    FOUND(c, o, "an overflow entry's back link wrong", c->node[o].prev ^= 1u);
    FOUND(c, o, "an overflow entry below its least bucket", c->node[o].time = -1.0);
    /* the counts: entries held, in the heap, in the ring */
    FOUND(c, h, "the entries held miscounted", c->size++);
    FOUND(c, h, "the heap's entries miscounted", c->heap_len--);
    FOUND(c, h, "the ring's entries miscounted", c->ring_len++);
    /* two at once (what one slip could do: an entry moved to the overflow with the ring's
     * count and its mark left): still found */
    FOUND(c, h, "the ring's and the heap's entries miscounted", (c->ring_len++, c->heap_len--));
    FOUND(c, o, "an overflow entry marked in the ring, the ring miscounted",
          (c->ring_len++, c->node[o].where = WHERE_RING));
    nbep_calendar_destroy(&c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_each_broken_invariant_is_found),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
