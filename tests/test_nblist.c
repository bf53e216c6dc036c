/* Tests of the neighbour lists (nblist.h): against a reference adjacency matrix under random
 * symmetric attach and detach operations, with lists growing past their room (moves to the
 * pool's end) and enough of it given up that the pool compacts; a layout from counts and a
 * fill; a list set at once against one cleared and appended to; the invariant checker
 * catching an asymmetric pair, a duplicate and a self entry. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/nblist.h"
#include "nbep_test.h"

static void init(nbep_nblist *l, size_t n)
{
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_nblist_init(l, n, &d), NBEP_OK);
    nbep_diag_fini(&d);
}

static uint64_t lcg(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return *x >> 33;
}

/* Every list holds exactly the reference's row (as a set). */
static void assert_matches(const nbep_nblist *l, const unsigned char *adj, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        size_t m, want = 0;
        const uint32_t *js = nbep_nblist_of(l, (uint32_t)i, &m);
        for (size_t j = 0; j < n; j++)
            want += adj[i * n + j];
        assert_int_equal(m, want);
        for (size_t k = 0; k < m; k++)
            assert_true(adj[i * n + js[k]]);
    }
    assert_int_equal(nbep_nblist_check(l), 0);
}

static void test_random_attach_and_detach_match_a_reference_adjacency(void **state)
{
    (void)state;
    enum { N = 60 };
    nbep_nblist l;
    init(&l, N);
    uint32_t zero[N] = {0};
    assert_true(nbep_nblist_layout(&l, zero)); /* room 4 each: growth comes early */
    unsigned char *adj = calloc(N * N, 1);
    assert_non_null(adj);
    uint64_t x = 7;
    size_t moves = 0, compactions = 0;
    for (int op = 0; op < 20000; op++) {
        const uint32_t i = (uint32_t)(lcg(&x) % N);
        if (lcg(&x) % 4 == 0) { /* a rebuild: i leaves every list, then joins some again */
            nbep_nblist_detach(&l, i);
            for (size_t j = 0; j < N; j++)
                adj[i * N + j] = adj[j * N + i] = 0;
            const size_t want = lcg(&x) % 40; /* up to 2/3 of all: lists outgrow their room */
            for (size_t k = 0; k < want; k++) {
                const uint32_t j = (uint32_t)(lcg(&x) % N);
                if (j == i || adj[i * N + j])
                    continue;
                const size_t len_before = l.pool_len;
                assert_true(nbep_nblist_append(&l, i, j));
                assert_true(nbep_nblist_append(&l, j, i));
                adj[i * N + j] = adj[j * N + i] = 1;
                moves += l.pool_len > len_before;
                compactions += l.pool_len < len_before; /* in place or not */
            }
        }
        if (op % 997 == 0)
            assert_matches(&l, adj, N);
        /* the pool stays within about 1.6 fresh layouts (nblist.h), plus one list's growth
         * and the room of counts that fell since the pool last grew */
        size_t fresh = 0;
        for (size_t k = 0; k < N; k++)
            fresh += nbep_nblist_room_for(l.sp[k].cnt);
        assert_true(l.pool_cap <= fresh * 8 / 5 + 8 * N + 16);
    }
    assert_matches(&l, adj, N);
    assert_true(moves > 0);       /* the test went through the growth path */
    assert_true(compactions > 0); /* and through compaction */
    free(adj);
    nbep_nblist_fini(&l);
}

static void test_layout_gives_each_list_its_count_and_slack_and_fill_appends(void **state)
{
    (void)state;
    nbep_nblist l;
    init(&l, 4);
    const uint32_t counts[4] = {0, 3, 1, 2};
    assert_true(nbep_nblist_layout(&l, counts));
    for (uint32_t i = 0; i < 4; i++) {
        assert_int_equal(l.sp[i].cap, nbep_nblist_room_for(counts[i]));
        assert_true(l.sp[i].cap >= counts[i] + 3); /* slack for drift between rebuilds */
        assert_int_equal(l.sp[i].cnt, 0);
        if (i > 0) /* laid out one after another, no overlap */
            assert_int_equal(l.sp[i].off, l.sp[i - 1].off + l.sp[i - 1].cap);
    }
    /* the complete graph minus 0: 1-2, 1-3, 2-3 ... filled from both sides as a rebuild does */
    nbep_nblist_fill(&l, 1, 2);
    nbep_nblist_fill(&l, 1, 3);
    nbep_nblist_fill(&l, 2, 1);
    nbep_nblist_fill(&l, 3, 1);
    assert_int_equal(nbep_nblist_check(&l), 0);
    size_t m;
    const uint32_t *js = nbep_nblist_of(&l, 1, &m);
    assert_int_equal(m, 2);
    assert_int_equal(js[0], 2);
    assert_int_equal(js[1], 3);
    /* detaching 1 empties its list and removes it from 2's and 3's */
    nbep_nblist_detach(&l, 1);
    for (uint32_t i = 0; i < 4; i++) {
        (void)nbep_nblist_of(&l, i, &m);
        assert_int_equal(m, 0);
    }
    nbep_nblist_fini(&l);
}

/* nbep_nblist_need bounds what a rebuild takes of the pool's spare: the rebuilt list moving
 * from its room up to m entries, and each of its m new neighbours' lists, full, gaining one
 * entry (while the spare covers it, the pool stays where it is, which the team loop's helper
 * relies on as it reads other lists meanwhile). */
static void test_need_bounds_what_a_rebuild_takes_of_the_spare(void **state)
{
    (void)state;
    enum { N = 1200 };
    uint32_t *counts = calloc(N, sizeof *counts);
    assert_non_null(counts);
    size_t tight = 0;
    for (uint32_t c0 = 0; c0 < 40; c0 += 3)
        for (uint32_t m = 0; m < N - 1; m = m * 3 / 2 + 1) {
            nbep_nblist l;
            init(&l, N);
            for (uint32_t j = 0; j < N; j++) /* one room for all: each gain takes the most */
                counts[j] = c0;
            assert_true(nbep_nblist_layout(&l, counts));
            for (uint32_t j = 1; j < N; j++) /* every other list full */
                for (uint32_t k = 0; k < l.sp[j].cap; k++)
                    nbep_nblist_fill(&l, j, (j + 1 + k) % N);
            const size_t need = nbep_nblist_need(&l, m, m), len0 = l.pool_len;
            for (uint32_t k = 1; k <= m; k++) {
                assert_true(nbep_nblist_append(&l, 0, k));
                assert_true(nbep_nblist_append(&l, k, 0));
                assert_true(l.pool_len >= len0); /* grown, never compacted here */
            }
            assert_true(l.pool_len - len0 <= need);
            tight += 10 * (l.pool_len - len0) > 9 * need; /* the bound is near what it takes */
            nbep_nblist_fini(&l);
        }
    assert_true(tight > 0);
    free(counts);
}

/* A view of an arena (nbep_nblist_arena, the scheduled loop's slabs on threads) moves lists
 * within its piece of the spare alone: a move past it fails with nothing changed (the pool
 * neither grown nor compacted under the other views' reads), one within it lands there, in the
 * spans every view shares; arena_back adds the moves' room and largest room into the lists. */
static void test_an_arena_moves_lists_within_its_piece_alone(void **state)
{
    (void)state;
    enum { N = 64 };
    nbep_nblist l;
    init(&l, N);
    uint32_t counts[N];
    for (uint32_t j = 0; j < N; j++)
        counts[j] = 4;
    assert_true(nbep_nblist_layout(&l, counts));
    for (uint32_t j = 0; j < N; j++) /* every list full */
        for (uint32_t k = 0; k < l.sp[j].cap; k++)
            nbep_nblist_fill(&l, j, (j + 1 + k) % N);
    const uint32_t cap0 = l.sp[0].cap, g = nbep_nblist_grown(cap0);
    assert_true(nbep_nblist_make_spare(&l, 2 * (size_t)g));
    assert_true(nbep_nblist_spare(&l) >= 2 * (size_t)g);
    const size_t lo = l.pool_len, room0 = l.room, pool_cap = l.pool_cap;
    const uint32_t *pool = l.pool;
    nbep_nblist a, b;
    nbep_nblist_arena(&l, lo, lo + g, &a);
    nbep_nblist_arena(&l, lo + g, lo + g + 1, &b); /* too small for any move */
    l.pool_len = lo + g + 1;
    const nbep_nblist_span sp1 = l.sp[1];
    assert_false(nbep_nblist_append(&b, 1, 40));
    assert_memory_equal(&l.sp[1], &sp1, sizeof sp1);
    assert_int_equal(b.pool_len, lo + g);
    assert_true(nbep_nblist_append(&a, 0, 40));
    assert_int_equal(l.sp[0].off, lo);
    assert_int_equal(l.sp[0].cap, g);
    assert_int_equal(l.sp[0].cnt, cap0 + 1);
    assert_int_equal(l.pool[lo + cap0], 40);
    assert_int_equal(a.pool_len, lo + g);
    assert_false(nbep_nblist_append(&a, 2, 41)); /* its piece used up */
    assert_ptr_equal(l.pool, pool);
    assert_ptr_equal(a.pool, pool);
    assert_int_equal(l.pool_cap, pool_cap);
    nbep_nblist_arena_back(&l, &a, room0);
    nbep_nblist_arena_back(&l, &b, room0);
    assert_int_equal(l.room, room0 + g - cap0);
    assert_int_equal(l.cap_max, g);
    nbep_nblist_fini(&l);
}

/* nbep_nblist_set is a clear and appends, copied in place where the room holds the list: two
 * pools, one set and one cleared and appended to, step for step through lists shorter and
 * longer than their rooms (moves, and the compactions a full pool brings), hold the same lists
 * at the same places with the same rooms. */
static void test_set_is_clear_and_appends(void **state)
{
    (void)state;
    enum { N = 40 };
    nbep_nblist a, b;
    init(&a, N);
    init(&b, N);
    uint32_t zero[N] = {0};
    assert_true(nbep_nblist_layout(&a, zero));
    assert_true(nbep_nblist_layout(&b, zero));
    uint64_t x = 11;
    uint32_t js[3 * N];
    size_t in_place = 0, moved = 0;
    for (int op = 0; op < 4000; op++) {
        const uint32_t i = (uint32_t)(lcg(&x) % N);
        const size_t m = lcg(&x) % (op % 3 == 0 ? 3 * N : 8); /* mostly short, at times long */
        for (size_t k = 0; k < m; k++)
            js[k] = (uint32_t)(lcg(&x) % N);
        const size_t len0 = a.pool_len;
        const uint32_t off0 = a.sp[i].off;
        assert_true(nbep_nblist_set(&a, i, js, m));
        nbep_nblist_clear(&b, i);
        for (size_t k = 0; k < m; k++)
            assert_true(nbep_nblist_append(&b, i, js[k]));
        in_place += a.pool_len == len0 && a.sp[i].off == off0;
        moved += a.sp[i].off != off0;
        assert_int_equal(a.pool_len, b.pool_len);
        assert_int_equal(a.cap_max, b.cap_max);
        assert_int_equal(a.room, b.room);
        for (uint32_t k = 0; k < N; k++) {
            assert_int_equal(a.sp[k].off, b.sp[k].off);
            assert_int_equal(a.sp[k].cnt, b.sp[k].cnt);
            assert_int_equal(a.sp[k].cap, b.sp[k].cap);
            assert_memory_equal(a.pool + a.sp[k].off, b.pool + b.sp[k].off,
                                a.sp[k].cnt * sizeof *a.pool);
        }
        size_t got;
        const uint32_t *have = nbep_nblist_of(&a, i, &got);
        assert_int_equal(got, m);
        if (m > 0)
            assert_memory_equal(have, js, m * sizeof *js);
    }
    assert_true(in_place > 0 && moved > 0); /* both ways were taken */
    nbep_nblist_fini(&a);
    nbep_nblist_fini(&b);
}

static void test_check_catches_asymmetry_duplicates_and_self_entries(void **state)
{
    (void)state;
    nbep_nblist l;
    init(&l, 3);
    const uint32_t counts[3] = {2, 2, 2};
    assert_true(nbep_nblist_layout(&l, counts));
    nbep_nblist_fill(&l, 0, 1); /* 1 does not list 0 */
    assert_int_equal(nbep_nblist_check(&l), 1);
    nbep_nblist_fill(&l, 1, 0);
    assert_int_equal(nbep_nblist_check(&l), 0);
    nbep_nblist_fill(&l, 2, 2); /* itself */
    assert_int_equal(nbep_nblist_check(&l), 1);
    l.sp[2].cnt = 0;
    nbep_nblist_fill(&l, 0, 1); /* twice */
    assert_true(nbep_nblist_check(&l) >= 1);
    nbep_nblist_fini(&l);
}

/* The skin by packing fraction: the dense one at and above NBEP_NBLIST_PHI_DENSE, without a
 * box (NAN) and whenever the scene accelerates; the dilute one at and below
 * NBEP_NBLIST_PHI_DILUTE; a straight line between, so no fraction jumps from one to the
 * other. */
/* The skin falls steadily from `from` at packing phi0 to `to` at phi1: never up, no step past
 * a fiftieth of the fall, and ends at `to`. */
static void assert_falls_steadily(double phi0, double from, double phi1, double to,
                                  bool free_flight)
{
    double last = from;
    for (int k = 0; k <= 100; k++) {
        const double phi = phi0 + (phi1 - phi0) * k / 100.0;
        const double skin = nbep_nblist_skin_for(phi, free_flight, true);
        assert_true(skin <= last && last - skin < 0.02 * (from - to) + 1e-12);
        last = skin;
    }
    assert_close(last, to, 1e-12, 0.0);
}

static void test_the_skin_follows_the_packing_fraction_of_a_free_scene(void **state)
{
    (void)state;
    const double dense = NBEP_NBLIST_SKIN_DENSE, dilute = NBEP_NBLIST_SKIN_DILUTE;
    assert_true(dilute > dense && dense > NBEP_NBLIST_SKIN);
    assert_true(nbep_nblist_skin_for(0.50, true, true) == dense);
    assert_true(nbep_nblist_skin_for(0.64, true, false) == dense); /* a cooling gas too */
    assert_true(nbep_nblist_skin_for(NBEP_NBLIST_PHI_DENSE, true, true) == dense);
    assert_true(nbep_nblist_skin_for(NBEP_NBLIST_PHI_DILUTE, true, true) == dilute);
    assert_true(nbep_nblist_skin_for(0.30, true, true) == dilute);
    /* what accelerates, or has no box to take a packing from: NBEP_NBLIST_SKIN, the pile's */
    assert_true(nbep_nblist_skin_for(NAN, true, true) == NBEP_NBLIST_SKIN);
    assert_true(nbep_nblist_skin_for(0.30, false, true) == NBEP_NBLIST_SKIN);
    assert_true(nbep_nblist_skin_for(0.50, false, true) == NBEP_NBLIST_SKIN);
    const double mid = 0.5 * (NBEP_NBLIST_PHI_DILUTE + NBEP_NBLIST_PHI_DENSE);
    assert_close(nbep_nblist_skin_for(mid, true, true), 0.5 * (dense + dilute), 1e-12, 0.0);
    assert_falls_steadily(NBEP_NBLIST_PHI_DILUTE, dilute, NBEP_NBLIST_PHI_DENSE, dense, true);
}

/* A sparse elastic scene takes the sparse skin whether or not it accelerates: at and below
 * NBEP_NBLIST_PHI_SPARSE, and a straight line from there to the rule of denser scenes at
 * NBEP_NBLIST_PHI_SPARSE_END (the dilute skin in free flight, the dense one otherwise), so no
 * fraction jumps; without a box (NAN) the dense one, as before; a dissipative one (e < 1),
 * which may crowd later, the rules of denser scenes at any packing. */
static void test_a_sparse_scene_takes_the_sparse_skin_and_no_fraction_jumps(void **state)
{
    (void)state;
    const double sparse = NBEP_NBLIST_SKIN_SPARSE;
    assert_true(sparse > NBEP_NBLIST_SKIN_DILUTE);
    for (int free_flight = 0; free_flight < 2; free_flight++) {
        const double denser = free_flight ? NBEP_NBLIST_SKIN_DILUTE : NBEP_NBLIST_SKIN;
        assert_true(nbep_nblist_skin_for(0.0, free_flight, true) == sparse);
        assert_true(nbep_nblist_skin_for(0.002, free_flight, true) == sparse);
        assert_true(nbep_nblist_skin_for(NBEP_NBLIST_PHI_SPARSE, free_flight, true) == sparse);
        assert_true(nbep_nblist_skin_for(NBEP_NBLIST_PHI_SPARSE_END, free_flight, true) ==
                    denser);
        /* pile.deck's pour packs 0.19: never sparse */
        assert_true(nbep_nblist_skin_for(0.19, free_flight, true) == denser);
        assert_true(nbep_nblist_skin_for(NAN, free_flight, true) == NBEP_NBLIST_SKIN);
        const double mid = 0.5 * (NBEP_NBLIST_PHI_SPARSE + NBEP_NBLIST_PHI_SPARSE_END);
        assert_close(nbep_nblist_skin_for(mid, free_flight, true), 0.5 * (sparse + denser),
                     1e-12, 0.0);
        assert_falls_steadily(NBEP_NBLIST_PHI_SPARSE, sparse, NBEP_NBLIST_PHI_SPARSE_END, denser,
                              free_flight);
        assert_true(nbep_nblist_skin_for(0.0, free_flight, false) == denser);
        assert_true(nbep_nblist_skin_for(0.002, free_flight, false) == denser);
        assert_true(nbep_nblist_skin_for(mid, free_flight, false) == denser);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_attach_and_detach_match_a_reference_adjacency),
        cmocka_unit_test(test_layout_gives_each_list_its_count_and_slack_and_fill_appends),
        cmocka_unit_test(test_need_bounds_what_a_rebuild_takes_of_the_spare),
        cmocka_unit_test(test_an_arena_moves_lists_within_its_piece_alone),
        cmocka_unit_test(test_set_is_clear_and_appends),
        cmocka_unit_test(test_check_catches_asymmetry_duplicates_and_self_entries),
        cmocka_unit_test(test_the_skin_follows_the_packing_fraction_of_a_free_scene),
        cmocka_unit_test(test_a_sparse_scene_takes_the_sparse_skin_and_no_fraction_jumps),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
