/* Tests of the event calendar: the earliest entry against a brute-force minimum over random
 * sets, moves and removals; the tie order (time, key, item) whatever the order of operations;
 * clearing; and the invariant checker catching nothing on a healthy heap. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "nbep/calendar.h"
#include "nbep_test.h"

static nbep_calendar *make(size_t n)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_calendar *c = NULL;
    assert_int_equal(nbep_calendar_create(n, &c, &d), NBEP_OK);
    nbep_diag_fini(&d);
    return c;
}

static uint64_t lcg(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return *x >> 33;
}

/* The reference: a plain array scanned for the minimum in the same order. */
typedef struct ref {
    bool has;
    double time;
    uint64_t key;
} ref;

static bool ref_before(const ref *r, uint32_t a, uint32_t b)
{
    if (r[a].time != r[b].time)
        return r[a].time < r[b].time;
    if (r[a].key != r[b].key)
        return r[a].key < r[b].key;
    return a < b;
}

static void test_top_is_the_brute_force_minimum_under_random_operations(void **state)
{
    (void)state;
    enum { N = 300, OPS = 20000 };
    nbep_calendar *c = make(N);
    ref r[N];
    memset(r, 0, sizeof r);
    uint64_t x = 12345;
    for (int op = 0; op < OPS; op++) {
        uint32_t i = (uint32_t)(lcg(&x) % N);
        uint64_t what = lcg(&x) % 10;
        if (what < 2) {
            nbep_calendar_remove(c, i);
            r[i].has = false;
        } else if (what == 2 && op % 1000 == 0) {
            nbep_calendar_clear(c);
            memset(r, 0, sizeof r);
        } else {
            /* few distinct times and keys: ties on time and on key are common */
            double t = (double)(lcg(&x) % 50) * 0.125;
            uint64_t key = lcg(&x) % 4;
            nbep_calendar_set(c, i, t, key);
            r[i] = (ref){true, t, key};
        }
        size_t held = 0;
        uint32_t best = UINT32_MAX;
        for (uint32_t k = 0; k < N; k++) {
            if (!r[k].has)
                continue;
            held++;
            if (best == UINT32_MAX || ref_before(r, k, best))
                best = k;
        }
        assert_int_equal(nbep_calendar_size(c), held);
        uint32_t top;
        double t_top;
        bool any = nbep_calendar_top(c, &top, &t_top);
        assert_int_equal(any, held > 0);
        if (any) {
            assert_int_equal(top, best);
            assert_true(t_top == r[best].time);
        }
        double t_has;
        assert_int_equal(nbep_calendar_has(c, i, &t_has), r[i].has);
        if (r[i].has)
            assert_true(t_has == r[i].time);
        if (op % 97 == 0)
            assert_int_equal(nbep_calendar_check(c), 0);
    }
    assert_int_equal(nbep_calendar_check(c), 0);
    nbep_calendar_destroy(&c);
    assert_null(c);
}

/* Draining the calendar gives the entries in (time, key, item) order, the same whatever
 * order they were set in. */
static void test_drain_order_is_time_then_key_then_item_for_any_insert_order(void **state)
{
    (void)state;
    enum { N = 64 };
    uint32_t first[N];
    for (int pass = 0; pass < 2; pass++) {
        nbep_calendar *c = make(N);
        for (uint32_t k = 0; k < N; k++) {
            uint32_t i = pass == 0 ? k : N - 1 - k;
            /* times 0, 1, 2, 3; keys descend with i so that key, not item, decides first */
            nbep_calendar_set(c, i, (double)(i % 4), (uint64_t)(N - i) / 8);
        }
        /* a move to +inf and back must not disturb the order */
        nbep_calendar_set(c, 5, INFINITY, 0);
        nbep_calendar_set(c, 5, (double)(5 % 4), (uint64_t)(N - 5) / 8);
        uint32_t prev = UINT32_MAX;
        double prev_t = -1.0;
        for (uint32_t k = 0; k < N; k++) {
            uint32_t i;
            double t;
            assert_true(nbep_calendar_top(c, &i, &t));
            if (prev != UINT32_MAX) {
                uint64_t kp = (uint64_t)(N - prev) / 8, ki = (uint64_t)(N - i) / 8;
                assert_true(prev_t < t || (prev_t == t && (kp < ki || (kp == ki && prev < i))));
            }
            if (pass == 0)
                first[k] = i;
            else
                assert_int_equal(first[k], i);
            nbep_calendar_remove(c, i);
            prev = i;
            prev_t = t;
        }
        uint32_t i;
        double t;
        assert_false(nbep_calendar_top(c, &i, &t));
        nbep_calendar_destroy(&c);
    }
}

static void test_remove_of_an_absent_item_and_an_empty_calendar_are_harmless(void **state)
{
    (void)state;
    nbep_calendar *c = make(3);
    nbep_calendar_remove(c, 1);
    assert_int_equal(nbep_calendar_size(c), 0);
    assert_false(nbep_calendar_has(c, 1, NULL));
    assert_false(nbep_calendar_has(c, 7, NULL)); /* out of range */
    nbep_calendar_set(c, 2, 1.0, 0);
    nbep_calendar_remove(c, 2);
    nbep_calendar_remove(c, 2);
    assert_int_equal(nbep_calendar_size(c), 0);
    assert_int_equal(nbep_calendar_check(c), 0);
    nbep_calendar_destroy(&c);
    nbep_calendar_destroy(&c); /* NULL-safe */
}

/* The brute-force minimum of the reference, or UINT32_MAX when it holds nothing. */
static uint32_t ref_min(const ref *r, uint32_t n)
{
    uint32_t best = UINT32_MAX;
    for (uint32_t k = 0; k < n; k++)
        if (r[k].has && (best == UINT32_MAX || ref_before(r, k, best)))
            best = k;
    return best;
}

/* Used as an event loop uses it, over many laps of the ring of buckets: the earliest entry is
 * moved later each time (mostly a little, sometimes far past the ring, sometimes to +inf),
 * others are moved or removed at random, and the pace changes by factors of 1000 both ways
 * so that the buckets retune themselves; every top is the brute-force minimum. */
static void test_top_is_the_minimum_over_many_laps_with_far_entries_and_changing_pace(void **st)
{
    (void)st;
    enum { N = 200, OPS = 60000 };
    nbep_calendar *c = make(N);
    ref r[N];
    memset(r, 0, sizeof r);
    uint64_t x = 777;
    for (uint32_t i = 0; i < N; i++) {
        r[i] = (ref){true, (double)(lcg(&x) % 1000) / 1000.0, lcg(&x) % 3};
        nbep_calendar_set(c, i, r[i].time, r[i].key);
    }
    nbep_calendar_retune(c, 0.0);
    assert_int_equal(nbep_calendar_check(c), 0);
    double pace = 1.0;
    int with_next = 0; /* tops with runners-up: the current bucket held more than one */
    for (int op = 0; op < OPS; op++) {
        if (op == OPS / 3)
            pace = 1000.0; /* far too many empty buckets for the old width */
        if (op == 2 * OPS / 3)
            pace = 1e-3;   /* far too full buckets */
        uint32_t best = ref_min(r, N), top;
        double t;
        bool any = nbep_calendar_top(c, &top, &t);
        assert_int_equal(any, best != UINT32_MAX);
        if (!any) { /* everything was removed: refill from where time stands */
            for (uint32_t i = 0; i < N; i++) {
                r[i] = (ref){true, (double)(lcg(&x) % 1000) * pace, 0};
                nbep_calendar_set(c, i, r[i].time, 0);
            }
            continue;
        }
        assert_int_equal(top, best);
        assert_true(t == r[best].time);
        /* the whole earliest entry, and the order a caller compares entries by (the team
         * loop's) agrees with the calendar's against another entry */
        nbep_calendar_entry first;
        assert_true(nbep_calendar_first(c, &first));
        assert_int_equal(first.item, best);
        assert_int_equal(first.key, r[best].key);
        assert_true(first.time == t);
        /* the runners-up a caller fetches ahead: held entries other than the top, distinct,
         * each with its own key */
        uint32_t next[2];
        uint64_t next_key[2];
        int n_next = -1;
        nbep_calendar_runners_up(c, next, next_key, &n_next);
        assert_true(n_next >= 0 && n_next <= 2);
        for (int k = 0; k < n_next; k++) {
            assert_true(next[k] < N && r[next[k]].has && next[k] != best);
            assert_int_equal(next_key[k], r[next[k]].key);
        }
        assert_true(n_next < 2 || next[0] != next[1]);
        with_next += n_next > 0;
        const uint32_t o = (uint32_t)(lcg(&x) % N);
        if (r[o].has && o != best) {
            const nbep_calendar_entry other = {r[o].time, r[o].key, o};
            assert_true(nbep_calendar_before(first, other));
            assert_false(nbep_calendar_before(other, first));
        }
        uint64_t what = lcg(&x) % 100;
        double later = t + pace * (double)(lcg(&x) % 4096) / 2048.0;
        if (what < 30) { /* often past the ring, due laps later */
            later = t + pace * (double)(lcg(&x) % 4096) / 64.0;
        } else if (what < 31) {
            later = lcg(&x) % 2 ? INFINITY : t + pace * 1e6;
        } else if (what < 34) {
            nbep_calendar_remove(c, top);
            r[top].has = false;
        }
        if (what >= 34 || what < 31) {
            uint64_t key = lcg(&x) % 3;
            nbep_calendar_set(c, top, later, key);
            r[top] = (ref){true, later, key};
        }
        /* another item moves to a time not before the top's, or goes */
        uint32_t other = (uint32_t)(lcg(&x) % N);
        if (lcg(&x) % 4 == 0) {
            nbep_calendar_remove(c, other);
            r[other].has = false;
        } else {
            double when = t + pace * (double)(lcg(&x) % 4096) / 1024.0;
            nbep_calendar_set(c, other, when, 1);
            r[other] = (ref){true, when, 1};
        }
        assert_int_equal(nbep_calendar_check(c), 0);
    }
    assert_true(with_next > 0);
    /* only +inf entries left: they still come out, in (key, item) order */
    for (uint32_t i = 0; i < N; i++) {
        nbep_calendar_remove(c, i);
        r[i].has = false;
    }
    for (uint32_t i = 10; i > 0; i--) {
        nbep_calendar_set(c, i, INFINITY, i % 3);
        r[i] = (ref){true, INFINITY, i % 3};
    }
    for (uint32_t k = 0; k < 10; k++) {
        uint32_t top, best = ref_min(r, N);
        double t;
        assert_true(nbep_calendar_top(c, &top, &t));
        assert_int_equal(top, best);
        assert_true(isinf(t));
        nbep_calendar_remove(c, top);
        r[top].has = false;
        assert_int_equal(nbep_calendar_check(c), 0);
    }
    nbep_calendar_destroy(&c);
}

/* Entries of the last bucket (+inf, or a finite time 2^62 buckets ahead and more) that the top
 * has brought into the heap, with the bucket being drained left where it was, and then an
 * entry of an earlier bucket set: it comes out first (a review found the parked entries
 * returned before it: 93888 wrong tops in 100000 operations of a fuzz mixing +inf and far
 * entries, the check seeing nothing). Against the brute-force minimum, with the check at each
 * step. */
static void test_an_entry_set_after_the_last_buckets_are_drawn_comes_first(void **state)
{
    (void)state;
    enum { N = 64, OPS = 20000 };
    nbep_calendar *c = make(N);
    /* the review's two cases: +inf, then 5; a time 1e30 bucket widths ahead, then 2 */
    uint32_t top;
    double t;
    nbep_calendar_set(c, 0, INFINITY, 0);
    assert_true(nbep_calendar_top(c, &top, &t) && top == 0 && isinf(t));
    nbep_calendar_set(c, 1, 5.0, 0);
    assert_true(nbep_calendar_top(c, &top, &t) && top == 1 && t == 5.0);
    assert_int_equal(nbep_calendar_check(c), 0);
    nbep_calendar_set(c, 2, 1e6, 0);
    nbep_calendar_remove(c, 1);
    assert_true(nbep_calendar_top(c, &top, &t) && top == 2 && t == 1e6);
    /* the jump past the ring took 1e6's bucket for the earliest, not the last (+inf) one: 1e6
     * is drawn on its own, and 0 waits in the overflow */
    assert_int_equal(nbep_calendar_check(c), 0);
    nbep_calendar_clear(c);
    nbep_calendar_retune(c, 0.0);
    nbep_calendar_set(c, 3, 1e30, 0);
    assert_true(nbep_calendar_top(c, &top, &t) && top == 3 && t == 1e30);
    nbep_calendar_set(c, 4, 2.0, 0);
    assert_true(nbep_calendar_top(c, &top, &t) && top == 4 && t == 2.0);
    assert_int_equal(nbep_calendar_check(c), 0);
    nbep_calendar_clear(c);
    /* and at random: +inf, far and near entries, the near ones now and then all removed */
    ref r[N];
    memset(r, 0, sizeof r);
    uint64_t x = 4242;
    double now = 0.0;
    for (int op = 0; op < OPS; op++) {
        const uint32_t i = (uint32_t)(lcg(&x) % N);
        const uint64_t what = lcg(&x) % 100;
        if (what < 10) {
            nbep_calendar_remove(c, i);
            r[i].has = false;
        } else if (what < 12) { /* every near entry goes */
            for (uint32_t k = 0; k < N; k++)
                if (r[k].has && r[k].time < 1e20) {
                    nbep_calendar_remove(c, k);
                    r[k].has = false;
                }
        } else {
            const uint64_t key = lcg(&x) % 3;
            const double when = what < 40   ? INFINITY
                                : what < 60 ? now + 1e25 * (double)(1 + lcg(&x) % 8)
                                            : now + (double)(lcg(&x) % 1000) / 100.0;
            nbep_calendar_set(c, i, when, key);
            r[i] = (ref){true, when, key};
        }
        const uint32_t best = ref_min(r, N);
        const bool any = nbep_calendar_top(c, &top, &t);
        assert_int_equal(any, best != UINT32_MAX);
        if (any) {
            assert_int_equal(top, best);
            assert_true(t == r[best].time || (isinf(t) && isinf(r[best].time)));
            if (t < 1e20)
                now = t;
        }
        assert_int_equal(nbep_calendar_check(c), 0);
    }
    nbep_calendar_destroy(&c);
}

/* The width a retune picks puts about BUCKET_ENTRIES (4) entries in a bucket near now: 2000
 * entries spread evenly over [0, 1) ahead take a width of 2 mean 4 / 2000 = 0.002, as the
 * mean of their distances gave it before 2026-11-30, within a tenth (the retune reads every
 * second entry here); and still so with one entry 1e12 ahead among them, which took the
 * mean's width to 2e6, one bucket for all (a sphere 1e-12 as fast as the others: a gas of
 * 100000 such ran 1.24 times as fast once the width left it out). */
static void test_a_retune_is_not_led_by_one_far_entry(void **state)
{
    (void)state;
    enum { N = 2001 };
    nbep_calendar *c = make(N);
    for (uint32_t i = 0; i < N - 1; i++)
        nbep_calendar_set(c, i, ((double)i + 0.5) / (double)(N - 1), 0);
    nbep_calendar_retune(c, 0.0);
    assert_close(nbep_calendar_width(c), 0.002, 0.1, 0.0);
    nbep_calendar_set(c, N - 1, 1e12, 0);
    nbep_calendar_retune(c, 0.0);
    assert_close(nbep_calendar_width(c), 0.002, 0.1, 0.0);
    assert_int_equal(nbep_calendar_check(c), 0);
    nbep_calendar_destroy(&c);
}

/* Run as an event loop runs it, `ops` times: the earliest entry, at t, moved to t + pace u
 * (u uniform in [0, 2)). Returns the time of the last top. */
static double run_at_pace(nbep_calendar *c, double pace, int ops, uint64_t *x)
{
    double t = 0.0;
    for (int op = 0; op < ops; op++) {
        uint32_t top;
        assert_true(nbep_calendar_top(c, &top, &t));
        nbep_calendar_set(c, top, t + pace * (double)(lcg(x) % 4096) / 2048.0, lcg(x) % 3);
    }
    return t;
}

/* A pace that changes is followed by the calendar's own laps: once every entry moves 1000
 * times as far (nearly every bucket empty: fewer than one in 64 holds anything) or 32 times as
 * near (a bucket holds far more than 16 times the 4 entries it was sized for), laps retune,
 * and the width is then within 4 times of the width a retune from that moment gives (it was
 * 1000 or 32 times off), measured from where time stands after a long run at the first pace
 * (not from the origin of the width before: t = 0). */
static void test_a_lap_retunes_the_width_to_a_changed_pace(void **state)
{
    (void)state;
    enum { N = 256 };
    const double paces[2] = {1000.0, 1.0 / 32.0};
    const int ops[2] = {20000, 200000}; /* laps of 256 buckets: some 30 and 6 */
    for (int k = 0; k < 2; k++) {
        nbep_calendar *c = make(N);
        uint64_t x = 99 + (uint64_t)k;
        for (uint32_t i = 0; i < N; i++)
            nbep_calendar_set(c, i, (double)(lcg(&x) % 4096) / 2048.0, 0);
        nbep_calendar_retune(c, 0.0);
        /* a long run at the pace it was tuned for: time moves far from the origin */
        const double t_far = run_at_pace(c, 1.0, 100000, &x);
        assert_true(t_far > 100.0);
        const double w_before = nbep_calendar_width(c);
        const double t_now = run_at_pace(c, paces[k], ops[k], &x);
        const double w_lap = nbep_calendar_width(c);
        assert_int_equal(nbep_calendar_check(c), 0);
        nbep_calendar_retune(c, t_now);
        const double w_fresh = nbep_calendar_width(c);
        if (!(w_lap > w_fresh / 4.0 && w_lap < 4.0 * w_fresh))
            fail_msg("pace %g: width %g after the laps, %g from a retune now (%g before)",
                     paces[k], w_lap, w_fresh, w_before);
        nbep_calendar_destroy(&c);
    }
}

/* Entries at +inf (spheres with nothing ahead) are no distance ahead a bucket can be sized
 * for: a retune of 2000 entries spread over [0, 1) and 2000 at +inf gives the width of the
 * 2000 alone (0.002, as above), not the width it had (1, a new calendar's). */
static void test_a_retune_leaves_out_entries_at_infinity(void **state)
{
    (void)state;
    enum { N = 4000 };
    nbep_calendar *c = make(N);
    assert_true(nbep_calendar_width(c) == 1.0);
    for (uint32_t i = 0; i < N; i++)
        nbep_calendar_set(c, i, i % 2 ? INFINITY : ((double)(i / 2) + 0.5) / (double)(N / 2), 0);
    nbep_calendar_retune(c, 0.0);
    assert_close(nbep_calendar_width(c), 0.002, 0.1, 0.0);
    assert_int_equal(nbep_calendar_check(c), 0);
    nbep_calendar_destroy(&c);
}

/* A retune keeps its width finite and not huge: entries so far ahead that the width they ask
 * for is past 1e300 (one 1e300 ahead: 8e300) or overflows (0.5, 3 and 1e308: +inf) leave the
 * width as it was (1), and the calendar drains in time order either way. No deck's events lie
 * that far ahead (scene.h's window of magnitudes); the guard is the calendar's own promise
 * (nbep_calendar_width), which the eleventh draw's `&&` as `||` broke unseen. */
static void test_a_retune_never_takes_an_infinite_or_huge_width(void **state)
{
    (void)state;
    const double far[2][3] = {{1e300, NAN, NAN}, {0.5, 3.0, 1e308}};
    const int count[2] = {1, 3};
    for (int k = 0; k < 2; k++) {
        nbep_calendar *c = make(4);
        for (int i = 0; i < count[k]; i++)
            nbep_calendar_set(c, (uint32_t)i, far[k][i], 0);
        nbep_calendar_retune(c, 0.0);
        if (!(nbep_calendar_width(c) == 1.0))
            fail_msg("case %d: the retune took width %g", k, nbep_calendar_width(c));
        assert_int_equal(nbep_calendar_check(c), 0);
        double last = -1.0;
        uint32_t i;
        double t;
        int drained = 0;
        while (nbep_calendar_top(c, &i, &t)) {
            assert_true(t >= last);
            last = t;
            nbep_calendar_remove(c, i);
            drained++;
        }
        assert_int_equal(drained, count[k]);
        nbep_calendar_destroy(&c);
    }
}

/* More items than the 32-bit links hold: refused with a message of its own (not blamed on
 * memory), before anything is allocated (the request would be for gigabytes). */
static void test_more_items_than_the_links_hold_is_refused(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_calendar *c = NULL;
    assert_int_equal(nbep_calendar_create(NBEP_CALENDAR_MAX + 1, &c, &d), NBEP_EDECK);
    assert_null(c);
    assert_int_equal(d.n_errors, 1);
    assert_non_null(strstr(d.msg[0], "holds at most 1073741822 items"));
    nbep_diag_fini(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_top_is_the_brute_force_minimum_under_random_operations),
        cmocka_unit_test(test_an_entry_set_after_the_last_buckets_are_drawn_comes_first),
        cmocka_unit_test(test_a_retune_is_not_led_by_one_far_entry),
        cmocka_unit_test(test_a_retune_leaves_out_entries_at_infinity),
        cmocka_unit_test(test_a_retune_never_takes_an_infinite_or_huge_width),
        cmocka_unit_test(test_a_lap_retunes_the_width_to_a_changed_pace),
        cmocka_unit_test(test_more_items_than_the_links_hold_is_refused),
        cmocka_unit_test(test_drain_order_is_time_then_key_then_item_for_any_insert_order),
        cmocka_unit_test(test_remove_of_an_absent_item_and_an_empty_calendar_are_harmless),
        cmocka_unit_test(test_top_is_the_minimum_over_many_laps_with_far_entries_and_changing_pace),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
