/* Tests of the spheres' versions and read notes (versions.h): a read takes the latest live
 * version stamped before it, in the calendar's order, whatever order the versions were put in;
 * cancelled ones are passed over; the slabs a put or cancel sends back are those whose reads
 * it may have overtaken (times equal, negative and -0.0 included); a full pool refuses and
 * changes nothing; a window forgets; random operations against a plain model; and a writer
 * against two reader threads at once, where every read that the window's final chains say came
 * too soon must have been answered by a send-back (scripts/tsan.sh runs it under TSan too). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/versions.h"
#include "nbep_test.h"

/* a state of 96 bytes, as the engine's motions are, filled from its sphere and stamp so that a
 * read of a version half written would show */
#define DOUBLES 12
typedef struct {
    double x[DOUBLES];
} state;

static state fill(uint32_t i, nbep_stamp s)
{
    state st;
    for (int k = 0; k < DOUBLES; k++)
        st.x[k] = s.t * (k + 1) + (double)(s.level[0].key % 9973) + 0.5 * i + k;
    return st;
}

static bool whole(const state *st, uint32_t i, nbep_stamp s)
{
    const state want = fill(i, s);
    return memcmp(st, &want, sizeof want) == 0;
}

static nbep_stamp at(double t, uint64_t key)
{
    return nbep_stamp_at(t, key, 0);
}

static nbep_versions *make(size_t n, int slabs, size_t room)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_versions *v = NULL;
    assert_int_equal(nbep_versions_create(n, sizeof(state), slabs, room, &v, &d), NBEP_OK);
    nbep_diag_fini(&d);
    return v;
}

/* a window with spheres 0..n-1 tracked */
static void open_all(nbep_versions *v, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++)
        assert_true(nbep_versions_track(v, i));
    nbep_versions_open(v);
}

/* puts, which must be taken; returns the slabs sent back */
static uint64_t put(nbep_versions *v, int slab, uint32_t i, nbep_stamp s)
{
    const state st = fill(i, s);
    uint64_t roll = ~UINT64_C(0);
    assert_true(nbep_versions_put(v, slab, i, s, &st, &roll));
    return roll;
}

/* the stamp read (t = -1 for none), its state checked whole */
static nbep_stamp get(nbep_versions *v, int reader, uint32_t i, nbep_stamp when)
{
    state st;
    nbep_stamp s;
    if (!nbep_versions_read(v, reader, i, when, &st, &s))
        return at(-1.0, 0);
    assert_true(whole(&st, i, s));
    assert_true(nbep_stamp_before(s, when));
    return s;
}

static void same(nbep_stamp a, nbep_stamp b)
{
    if (!nbep_stamp_same(a, b))
        fail_msg("stamp (%.17g, %llu), wanted (%.17g, %llu)", a.t, (unsigned long long)a.level[0].key,
                 b.t, (unsigned long long)b.level[0].key);
}

static void reads_by_stamp(void **state_)
{
    (void)state_;
    nbep_versions *v = make(5, 2, 16);
    assert_true(nbep_versions_track(v, 3));
    assert_true(nbep_versions_track(v, 1));
    assert_true(nbep_versions_track(v, 3)); /* once is enough */
    assert_int_equal(nbep_versions_count(v), 2);
    nbep_versions_open(v);
    assert_true(nbep_versions_tracked(v, 1));
    assert_true(nbep_versions_tracked(v, 3));
    assert_false(nbep_versions_tracked(v, 0));
    assert_false(nbep_versions_tracked(v, 7)); /* past n */
    /* nothing put: the window's start, in the caller's arrays (a read before every put
     * below, so none sends it back) */
    same(get(v, 1, 3, at(0.5, 0)), at(-1.0, 0));
    assert_null(nbep_versions_newest(v, 3));
    /* put out of order: 3, 1, 2, and a tie in time broken by key */
    assert_int_equal(put(v, 0, 3, at(3.0, 7)), 0);
    assert_int_equal(put(v, 0, 3, at(1.0, 7)), 0);
    assert_int_equal(put(v, 0, 3, at(2.0, 9)), 0);
    assert_int_equal(put(v, 0, 3, at(2.0, 4)), 0);
    same(get(v, 1, 3, at(0.5, 0)), at(-1.0, 0));
    same(get(v, 1, 3, at(1.0, 7)), at(-1.0, 0)); /* strictly before: not its own stamp */
    same(get(v, 1, 3, at(1.0, 8)), at(1.0, 7));
    same(get(v, 1, 3, at(2.0, 4)), at(1.0, 7));
    same(get(v, 1, 3, at(2.0, 5)), at(2.0, 4));
    same(get(v, 1, 3, at(2.0, 9)), at(2.0, 4));
    same(get(v, 1, 3, at(2.0, 10)), at(2.0, 9));
    same(get(v, 1, 3, at(3.0, 7)), at(2.0, 9));
    same(get(v, 1, 3, at(9.0, 0)), at(3.0, 7));
    /* another sphere's chain is its own */
    same(get(v, 1, 1, at(9.0, 0)), at(-1.0, 0));
    const state *nw = nbep_versions_newest(v, 3);
    assert_non_null(nw);
    assert_true(whole(nw, 3, at(3.0, 7)));
    /* the window closed forgets them; the next tracks what it is told to */
    nbep_versions_close(v);
    assert_true(nbep_versions_tracked(v, 3));
    nbep_versions_untrack(v, 3);
    nbep_versions_untrack(v, 3); /* once is enough */
    assert_true(nbep_versions_track(v, 0));
    assert_int_equal(nbep_versions_count(v), 2);
    nbep_versions_open(v);
    assert_false(nbep_versions_tracked(v, 3));
    assert_true(nbep_versions_tracked(v, 1));
    same(get(v, 1, 0, at(9.0, 0)), at(-1.0, 0));
    same(get(v, 1, 1, at(9.0, 0)), at(-1.0, 0));
    nbep_versions_close(v);
    assert_true(nbep_versions_track(v, 3));
    nbep_versions_open(v);
    same(get(v, 1, 3, at(9.0, 0)), at(-1.0, 0));
    assert_null(nbep_versions_newest(v, 3));
    nbep_versions_close(v);
    nbep_versions_destroy(&v);
    assert_null(v);
    nbep_versions_destroy(&v); /* NULL-safe */
}

/* Spheres tracked and untracked in any order, window after window: each keeps its own slot
 * (its versions and notes), and a window forgets what the last put and read, a sphere only put
 * and a sphere only read alike. */
static void tracking(void **state_)
{
    (void)state_;
    enum { N = 200 };
    nbep_versions *v = make(N, 3, 4 * N);
    bool on[N] = {false};
    uint64_t x = 5;
    for (int w = 0; w < 30; w++) {
        for (int k = 0; k < 60; k++) { /* untrack the middle of the slots, track new ones */
            const uint32_t i = (uint32_t)((x = x * 6364136223846793005ULL + 1) >> 33) % N;
            if (on[i])
                nbep_versions_untrack(v, i);
            else
                assert_true(nbep_versions_track(v, i));
            on[i] = !on[i];
        }
        size_t count = 0;
        for (uint32_t i = 0; i < N; i++) {
            assert_int_equal(nbep_versions_tracked(v, i), on[i]);
            count += on[i];
        }
        assert_int_equal(nbep_versions_count(v), count);
        nbep_versions_open(v);
        for (uint32_t i = 0; i < N; i++) {
            if (!on[i])
                continue;
            /* nothing from the last window, where each sphere was either only put or only
             * read: no version, and (a put before the last window's read) no note */
            assert_null(nbep_versions_newest(v, i));
            if ((i + (uint32_t)w) % 2 == 0) {
                assert_int_equal(put(v, (int)(i % 3), i, at(1.0, i)), 0);
                assert_non_null(nbep_versions_newest(v, i));
            } else {
                same(get(v, (int)((i + 1) % 3), i, at(2.0, 0)), at(-1.0, 0));
            }
        }
        nbep_versions_close(v);
    }
    /* and within a window: a put sends back the slabs that read, a read finds the put */
    open_all(v, N);
    for (uint32_t i = 0; i < N; i++) {
        assert_int_equal(put(v, (int)(i % 3), i, at(1.0, i)), 0);
        if (i % 2)
            get(v, (int)((i + 1) % 3), i, at(2.0, 0));
    }
    for (uint32_t i = 0; i < N; i++) {
        same(get(v, 0, i, at(5.0, 0)), at(1.0, i));
        assert_int_equal(put(v, (int)(i % 3), i, at(3.0, i)),
                         i % 2 ? (1u | (1u << ((i + 1) % 3))) : 1u);
    }
    nbep_versions_close(v);
    nbep_versions_destroy(&v);
}

static void cancels(void **state_)
{
    (void)state_;
    nbep_versions *v = make(2, 2, 16);
    open_all(v, 2);
    put(v, 0, 0, at(1.0, 1));
    put(v, 0, 0, at(2.0, 1));
    put(v, 0, 0, at(3.0, 1));
    uint64_t roll = 99;
    assert_true(nbep_versions_cancel(v, 0, at(2.0, 1), &roll));
    assert_int_equal(roll, 0);
    same(get(v, 1, 0, at(2.5, 0)), at(1.0, 1));
    same(get(v, 1, 0, at(9.0, 0)), at(3.0, 1));
    /* once only; an unknown stamp, or one of another sphere, is none of its */
    roll = 99;
    assert_false(nbep_versions_cancel(v, 0, at(2.0, 1), &roll));
    assert_int_equal(roll, 0);
    assert_false(nbep_versions_cancel(v, 0, at(2.0, 2), &roll));
    assert_false(nbep_versions_cancel(v, 1, at(1.0, 1), &roll));
    /* the event handled again puts its version anew */
    put(v, 0, 0, at(2.0, 1));
    same(get(v, 1, 0, at(2.5, 0)), at(2.0, 1));
    assert_true(nbep_versions_cancel(v, 0, at(2.0, 1), &roll));
    same(get(v, 1, 0, at(2.5, 0)), at(1.0, 1));
    /* the newest passes over the dead */
    assert_true(nbep_versions_cancel(v, 0, at(3.0, 1), &roll));
    assert_true(whole(nbep_versions_newest(v, 0), 0, at(1.0, 1)));
    assert_true(nbep_versions_cancel(v, 0, at(1.0, 1), &roll));
    assert_null(nbep_versions_newest(v, 0));
    same(get(v, 1, 0, at(9.0, 0)), at(-1.0, 0));
    nbep_versions_close(v);
    nbep_versions_destroy(&v);
}

static void sends_back(void **state_)
{
    (void)state_;
    nbep_versions *v = make(3, 4, 16);
    open_all(v, 3);
    /* slab 1 reads sphere 0 at 5: a put at 6 is after, at 4 before it, at 5 with a lower key
     * is before it too and with a higher one after (the note keeps the time only: sent back) */
    get(v, 1, 0, at(5.0, 10));
    assert_int_equal(put(v, 0, 0, at(6.0, 0)), 0);
    assert_int_equal(put(v, 0, 0, at(4.0, 0)), 1u << 1);
    assert_int_equal(put(v, 0, 0, at(5.0, 3)), 1u << 1);
    assert_int_equal(put(v, 0, 0, at(5.0, 30)), 1u << 1);
    /* another sphere's note is its own */
    assert_int_equal(put(v, 0, 1, at(1.0, 0)), 0);
    /* slabs 2 and 3 read it later and earlier; the note keeps the latest time and all three */
    get(v, 3, 0, at(7.0, 0));
    get(v, 2, 0, at(2.0, 0));
    assert_int_equal(put(v, 0, 0, at(6.5, 1)), (1u << 1) | (1u << 2) | (1u << 3));
    assert_int_equal(put(v, 0, 0, at(7.5, 1)), 0);
    uint64_t roll = 0;
    assert_true(nbep_versions_cancel(v, 0, at(6.0, 0), &roll));
    assert_int_equal(roll, (1u << 1) | (1u << 2) | (1u << 3));
    assert_true(nbep_versions_cancel(v, 0, at(7.5, 1), &roll));
    assert_int_equal(roll, 0);
    /* a read with no copy wanted still notes */
    assert_true(nbep_versions_read(v, 0, 1, at(3.0, 0), NULL, NULL));
    assert_int_equal(put(v, 0, 1, at(2.0, 0)), 1u);
    nbep_versions_close(v);
    /* a new window's notes start empty */
    open_all(v, 3);
    assert_int_equal(put(v, 0, 0, at(0.0, 0)), 0);
    nbep_versions_close(v);
    nbep_versions_destroy(&v);
}

/* Times below zero and -0.0 order as times do: the note's integer order is the doubles'. */
static void signed_times(void **state_)
{
    (void)state_;
    nbep_versions *v = make(1, 2, 32);
    open_all(v, 1);
    get(v, 1, 0, at(-2.0, 5));
    assert_int_equal(put(v, 0, 0, at(-3.0, 0)), 2u);
    assert_int_equal(put(v, 0, 0, at(-1.0, 0)), 0);
    assert_int_equal(put(v, 0, 0, at(-2.5, 0)), 2u);
    assert_int_equal(put(v, 0, 0, at(-1e-300, 0)), 0);
    get(v, 1, 0, at(-1e-300, 9));
    assert_int_equal(put(v, 0, 0, at(-1e-299, 1)), 2u);
    nbep_versions_close(v);
    /* a read at -0.0 and a put at +0.0 with a lower key: the put comes first, so the read was
     * too soon; and the other way round */
    open_all(v, 1);
    get(v, 1, 0, at(-0.0, 5));
    assert_int_equal(put(v, 0, 0, at(0.0, 1)), 2u);
    nbep_versions_close(v);
    open_all(v, 1);
    get(v, 1, 0, at(0.0, 5));
    assert_int_equal(put(v, 0, 0, at(-0.0, 1)), 2u);
    assert_int_equal(put(v, 0, 0, at(1e-300, 1)), 0);
    same(get(v, 1, 0, at(0.0, 2)), at(-0.0, 1));
    nbep_versions_close(v);
    nbep_versions_destroy(&v);
}

static void full_pool(void **state_)
{
    (void)state_;
    nbep_versions *v = make(2, 2, 3);
    open_all(v, 2);
    put(v, 0, 0, at(1.0, 0));
    put(v, 0, 1, at(2.0, 0));
    put(v, 0, 0, at(3.0, 0));
    get(v, 1, 0, at(9.0, 0));
    const state st = fill(0, at(0.5, 0));
    uint64_t roll = 77;
    assert_false(nbep_versions_put(v, 0, 0, at(0.5, 0), &st, &roll));
    assert_int_equal(roll, 77); /* nothing changed, not even that */
    same(get(v, 1, 0, at(0.9, 0)), at(-1.0, 0));
    same(get(v, 1, 0, at(9.0, 0)), at(3.0, 0));
    /* the other slab's pool is its own; a cancel frees no room (versions stay till the end) */
    put(v, 1, 1, at(0.5, 0));
    assert_true(nbep_versions_cancel(v, 0, at(3.0, 0), &roll));
    assert_false(nbep_versions_put(v, 0, 0, at(0.5, 0), &st, &roll));
    nbep_versions_close(v);
    open_all(v, 2);
    put(v, 0, 0, at(0.5, 0));
    nbep_versions_close(v);
    nbep_versions_destroy(&v);
}

static void refusals(void **state_)
{
    (void)state_;
    struct {
        size_t n, size, room;
        int slabs;
        const char *says;
    } bad[] = {
        {4, 96, 8, 0, "versions take 1 to 64 slabs, not 0"},
        {4, 96, 8, 65, "versions take 1 to 64 slabs, not 65"},
        {4, 0, 8, 2, "a version holds 1 to 4096 bytes, not 0"},
        {4, 4097, 8, 2, "a version holds 1 to 4096 bytes, not 4097"},
        {4, 96, 0, 2, "room for 1 to 1073741824 a slab on 2 slabs"},
        {4, 96, ((size_t)1 << 30) + 1, 2, "not 1073741825 and 4"},
        {(size_t)1 << 31, 96, 8, 2, "fewer than 2^31 spheres, not 8 and 2147483648"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        nbep_diag d;
        nbep_diag_init(&d);
        nbep_versions *v = NULL;
        assert_int_equal(nbep_versions_create(bad[k].n, bad[k].size, bad[k].slabs, bad[k].room,
                                              &v, &d),
                         NBEP_EDECK);
        assert_null(v);
        assert_int_equal(d.n_errors, 1);
        if (!strstr(d.msg[0], bad[k].says))
            fail_msg("case %zu said \"%s\", wanted \"%s\"", k, d.msg[0], bad[k].says);
        nbep_diag_fini(&d);
    }
    /* what create allocates, and the tracked spheres' slots (room for 64, doubled); one byte
     * of state takes 8 */
    const size_t base = nbep_versions_bytes(10, 1, 2, 4, 0);
    assert_true(nbep_versions_bytes(10, 1, 2, 4, 3) == base + 64 * 24);
    assert_true(nbep_versions_bytes(10, 1, 2, 4, 64) == base + 64 * 24);
    assert_true(nbep_versions_bytes(10, 1, 2, 4, 65) == base + 128 * 24);
    assert_true(nbep_versions_bytes(10, 8, 2, 4, 0) == nbep_versions_bytes(10, 1, 2, 4, 0));
    assert_true(nbep_versions_bytes(10, 9, 2, 4, 0) == nbep_versions_bytes(10, 1, 2, 4, 0) + 64);
}

static uint64_t lcg(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return *x >> 33;
}

/* Random puts, cancels and reads on a few spheres and slabs against a plain model: each
 * sphere's versions as a list, its note as the latest time read and the readers; times on a
 * coarse grid, so that ties in time are common. */
#define MS 4    /* spheres */
#define MV 64   /* versions a sphere a window, at most */
static void against_model(void **state_)
{
    (void)state_;
    const int slabs = 3;
    nbep_versions *v = make(MS, slabs, MS * MV);
    uint64_t x = 11;
    for (int w = 0; w < 40; w++) {
        struct {
            nbep_stamp s[MV];
            bool live[MV];
            int n;
            double read_t;
            bool read;
            uint64_t readers;
        } m[MS] = {0};
        open_all(v, MS);
        for (int op = 0; op < 400; op++) {
            const uint32_t i = (uint32_t)(lcg(&x) % MS);
            const nbep_stamp s = at((double)(lcg(&x) % 16) / 4.0 - 1.0, lcg(&x) % 4);
            const int kind = (int)(lcg(&x) % 3);
            if (kind == 0 && m[i].n < MV) {
                bool dup = false; /* one live version a stamp: a re-handled event cancels first */
                for (int k = 0; k < m[i].n; k++)
                    dup |= m[i].live[k] && nbep_stamp_same(m[i].s[k], s);
                if (dup)
                    continue;
                const uint64_t want = m[i].read && m[i].read_t >= s.t ? m[i].readers : 0;
                assert_int_equal(put(v, 0, i, s), want);
                m[i].s[m[i].n] = s;
                m[i].live[m[i].n++] = true;
            } else if (kind == 1 && m[i].n > 0) {
                /* a stamp put before, whose version may be dead, or put again since */
                const nbep_stamp c = m[i].s[lcg(&x) % (uint64_t)m[i].n];
                int had = -1;
                for (int k = 0; k < m[i].n; k++)
                    if (m[i].live[k] && nbep_stamp_same(m[i].s[k], c))
                        had = k;
                uint64_t roll = 0;
                assert_int_equal(nbep_versions_cancel(v, i, c, &roll), had >= 0);
                if (had >= 0) {
                    assert_int_equal(roll, m[i].read && m[i].read_t >= c.t ? m[i].readers : 0);
                    m[i].live[had] = false;
                }
            } else {
                const int r = (int)(lcg(&x) % (uint64_t)slabs);
                int best = -1;
                for (int k = 0; k < m[i].n; k++)
                    if (m[i].live[k] && nbep_stamp_before(m[i].s[k], s) &&
                        (best < 0 || nbep_stamp_before(m[i].s[best], m[i].s[k])))
                        best = k;
                same(get(v, r, i, s), best < 0 ? at(-1.0, 0) : m[i].s[best]);
                m[i].read_t = m[i].read ? (s.t > m[i].read_t ? s.t : m[i].read_t) : s.t;
                m[i].read = true;
                m[i].readers |= UINT64_C(1) << r;
            }
        }
        for (uint32_t i = 0; i < MS; i++) {
            int best = -1;
            for (int k = 0; k < m[i].n; k++)
                if (m[i].live[k] && (best < 0 || nbep_stamp_before(m[i].s[best], m[i].s[k])))
                    best = k;
            const state *nw = nbep_versions_newest(v, i);
            if (best < 0)
                assert_null(nw);
            else
                assert_true(nw && whole(nw, i, m[i].s[best]));
        }
        nbep_versions_close(v);
    }
    nbep_versions_destroy(&v);
}

/* A writer against readers on threads of their own, window after window. The writer (slab 0)
 * puts versions of a few spheres at random stamps, out of order, and cancels some; each reader
 * (slabs 1 and 2) reads them at random stamps while the writer runs. After each window, with
 * the final chains known: every version read was put, whole, and stamped before the read; a
 * read that took a version since cancelled was sent back by that cancel, and one that missed
 * the version the final chain says it should have read, by that version's put. (These notes
 * soon hold late times and both readers, so the send-backs here would pass with a lost note;
 * the races below are the notes' test. This one is the chains': links changed under readers,
 * in the middle of a chain and at its head, and marks of the dead.) */
#define TS 6        /* spheres */
#define TP 300      /* puts a window */
#define TREADS 3000 /* reads a reader a window, at most */

typedef struct {
    uint32_t i;
    nbep_stamp s;
    uint64_t roll;        /* what the put sent back */
    bool cancelled;
    uint64_t cancel_roll; /* and the cancel */
} put_op;

typedef struct {
    uint32_t i;
    nbep_stamp at, found;
    bool got, torn;
} read_op;

typedef struct {
    nbep_versions *v;
    put_op puts[TP];
    int n_puts;
    read_op reads[2][TREADS];
    int n_reads[2];
    atomic_int started, done;
    atomic_long ticks;       /* reads done, both readers */
    atomic_int readers_left; /* readers still reading */
    uint64_t seed;
} stress;

typedef struct {
    stress *z;
    int reader; /* 0 or 1: slab 1 or 2 */
} reader_arg;

/* a grid of 64 times, so that ties in time are common; the writer's k'th put's key is k
 * modulo TP (so a stamp names one put), a reader's any */
static nbep_stamp random_stamp(uint64_t *x, int k)
{
    const double t = (double)(lcg(x) % 64) / 64.0;
    const uint64_t high = lcg(x) % 1000u * TP;
    return at(t, high + (uint64_t)(k < 0 ? (int)(lcg(x) % TP) : k));
}

static void *writer_main(void *arg)
{
    stress *z = arg;
    uint64_t x = z->seed;
    atomic_store_explicit(&z->started, 1, memory_order_relaxed);
    for (int k = 0; k < TP; k++) {
        put_op *p = &z->puts[k];
        p->i = (uint32_t)(lcg(&x) % TS);
        p->s = random_stamp(&x, k);
        p->cancelled = false;
        const state st = fill(p->i, p->s);
        if (!nbep_versions_put(z->v, 0, p->i, p->s, &st, &p->roll))
            p->roll = ~UINT64_C(0); /* cannot be: room for TP */
        z->n_puts = k + 1;
        /* the readers read between puts (a few reads each, unless they have stopped), so
         * that reads meet puts on every link of the chains */
        const long seen = atomic_load_explicit(&z->ticks, memory_order_relaxed);
        while (atomic_load_explicit(&z->ticks, memory_order_relaxed) < seen + 4 &&
               atomic_load_explicit(&z->readers_left, memory_order_relaxed) > 0)
            sched_yield();
        if (lcg(&x) % 4 == 0) { /* cancel an earlier put of the window */
            put_op *c = &z->puts[lcg(&x) % (uint64_t)(k + 1)];
            if (!c->cancelled)
                c->cancelled = nbep_versions_cancel(z->v, c->i, c->s, &c->cancel_roll);
        }
    }
    atomic_store_explicit(&z->done, 1, memory_order_release);
    return NULL;
}

static void *reader_main(void *arg)
{
    const reader_arg *a = arg;
    stress *z = a->z;
    uint64_t x = z->seed ^ (0x9e3779b97f4a7c15ULL * (uint64_t)(a->reader + 1));
    int n = 0;
    while (!atomic_load_explicit(&z->started, memory_order_relaxed))
        sched_yield(); /* a single CPU (valgrind's) runs the writer */
    while (n < TREADS && !atomic_load_explicit(&z->done, memory_order_acquire)) {
        read_op *r = &z->reads[a->reader][n++];
        r->i = (uint32_t)(lcg(&x) % TS);
        r->at = random_stamp(&x, -1);
        state st;
        r->got = nbep_versions_read(z->v, a->reader + 1, r->i, r->at, &st, &r->found);
        r->torn = r->got && !whole(&st, r->i, r->found);
        atomic_fetch_add_explicit(&z->ticks, 1, memory_order_relaxed);
    }
    z->n_reads[a->reader] = n;
    atomic_fetch_sub_explicit(&z->readers_left, 1, memory_order_relaxed);
    return NULL;
}

static const put_op *put_of(const stress *z, uint32_t i, nbep_stamp s)
{
    for (int k = 0; k < z->n_puts; k++)
        if (z->puts[k].i == i && nbep_stamp_same(z->puts[k].s, s))
            return &z->puts[k];
    return NULL;
}

/* The window's reads checked against its final chains: failures, described into why */
static int check_window(const stress *z, char *why, size_t len, long *too_soon)
{
    int bad = 0;
    for (int r = 0; r < 2; r++) {
        const uint64_t bit = UINT64_C(1) << (r + 1);
        for (int k = 0; k < z->n_reads[r]; k++) {
            const read_op *q = &z->reads[r][k];
            const put_op *want = NULL; /* the latest live put before the read, finally */
            for (int p = 0; p < z->n_puts; p++) {
                const put_op *c = &z->puts[p];
                if (c->i == q->i && !c->cancelled && nbep_stamp_before(c->s, q->at) &&
                    (!want || nbep_stamp_before(want->s, c->s)))
                    want = c;
            }
            const put_op *took = q->got ? put_of(z, q->i, q->found) : NULL;
            const char *wrong = NULL;
            if (q->torn || (q->got && !took))
                wrong = "a version not put, or half written";
            else if (took && !nbep_stamp_before(took->s, q->at))
                wrong = "a version not before the read";
            else if (took && took->cancelled) {
                ++*too_soon;
                if (!(took->cancel_roll & bit))
                    wrong = "a version since cancelled, and the cancel did not send it back";
            } else if (want && took != want) {
                ++*too_soon;
                if (!(want->roll & bit))
                    wrong = "too soon for a later put, which did not send it back";
            }
            if (wrong && bad++ == 0)
                snprintf(why, len, "reader %d, read %d of sphere %u at (%.17g, %llu): %s", r,
                         k, q->i, q->at.t, (unsigned long long)q->at.level[0].key, wrong);
        }
    }
    return bad;
}

static void threads(void **state_)
{
    (void)state_;
    const char *scale = getenv("NBEP_TEST_SCALE");
    const int windows = scale && strcmp(scale, "small") == 0 ? 10 : 60;
    stress *z = calloc(1, sizeof *z);
    assert_non_null(z);
    z->v = make(TS, 3, TP);
    long too_soon = 0, reads = 0;
    char why[256] = "";
    int bad = 0;
    for (int w = 0; w < windows && !bad; w++) {
        open_all(z->v, TS);
        z->n_puts = 0;
        z->seed = 1000u + (uint64_t)w;
        atomic_store_explicit(&z->started, 0, memory_order_relaxed);
        atomic_store_explicit(&z->ticks, 0, memory_order_relaxed);
        atomic_store_explicit(&z->readers_left, 2, memory_order_relaxed);
        atomic_store_explicit(&z->done, 0, memory_order_relaxed);
        pthread_t tw, tr[2];
        reader_arg ra[2] = {{z, 0}, {z, 1}};
        for (int r = 0; r < 2; r++)
            assert_int_equal(pthread_create(&tr[r], NULL, reader_main, &ra[r]), 0);
        assert_int_equal(pthread_create(&tw, NULL, writer_main, z), 0);
        pthread_join(tw, NULL);
        for (int r = 0; r < 2; r++)
            pthread_join(tr[r], NULL);
        for (int k = 0; k < z->n_puts; k++)
            if (z->puts[k].roll == ~UINT64_C(0))
                fail_msg("window %d: put %d refused", w, k);
        bad = check_window(z, why, sizeof why, &too_soon);
        reads += z->n_reads[0] + z->n_reads[1];
        nbep_versions_close(z->v);
    }
    if (bad)
        fail_msg("%d reads too soon not sent back; the first: %s", bad, why);
    print_message("%ld reads, %ld of them overtaken by the window's later puts or cancels, all "
                  "sent back\n",
                  reads, too_soon);
    nbep_versions_destroy(&z->v);
    free(z);
}

/* One read against one put (or cancel) of the same sphere, started at the same moment on two
 * threads, sphere after sphere: the read is at 1, the put at 0.5, so either the read finds the
 * version or the put finds the read's note and sends the reader back; a cancel of a version at
 * 0.5 put before, either the read passes over it or the cancel sends the reader back. The
 * random writer above cannot show a lost note (its readers' notes soon hold late times and
 * both slabs, and then every put sends both back); here each sphere's note is the one read's.
 * A read that noted after its walk, or a put that read the note before its version was
 * visible, fails this within a few windows on two CPUs. */
#define RS 4096 /* spheres */

typedef struct {
    nbep_versions *v;
    bool cancel;           /* the window's race: put or cancel */
    _Atomic int meet[RS];  /* both threads at sphere i: 2 */
    bool got[RS];          /* what the read found */
    uint64_t roll[RS];     /* what the put or cancel sent back */
} race;

static void meet(_Atomic int *m)
{
    atomic_fetch_add_explicit(m, 1, memory_order_relaxed);
    for (int spin = 0; atomic_load_explicit(m, memory_order_relaxed) < 2; spin++)
        if (spin > 1000)
            sched_yield(); /* on one CPU (valgrind's) the other thread must run */
}

static void *race_writer(void *arg)
{
    race *z = arg;
    for (uint32_t i = 0; i < RS; i++) {
        meet(&z->meet[i]);
        if (z->cancel) {
            if (!nbep_versions_cancel(z->v, i, at(0.5, 0), &z->roll[i]))
                z->roll[i] = 0; /* cannot be: put before */
        } else {
            const state st = fill(i, at(0.5, 0));
            if (!nbep_versions_put(z->v, 0, i, at(0.5, 0), &st, &z->roll[i]))
                z->roll[i] = 0;
        }
    }
    return NULL;
}

static void *race_reader(void *arg)
{
    race *z = arg;
    for (uint32_t i = 0; i < RS; i++) {
        meet(&z->meet[i]);
        z->got[i] = nbep_versions_read(z->v, 1, i, at(1.0, 0), NULL, NULL);
    }
    return NULL;
}

static void races(void **state_)
{
    (void)state_;
    const char *scale = getenv("NBEP_TEST_SCALE");
    const int windows = scale && strcmp(scale, "small") == 0 ? 2 : 40;
    race *z = calloc(1, sizeof *z);
    assert_non_null(z);
    z->v = make(RS, 2, RS);
    long both = 0, found_only = 0, sent_only = 0;
    for (int w = 0; w < windows; w++) {
        open_all(z->v, RS);
        z->cancel = w % 2 == 1;
        for (uint32_t i = 0; i < RS; i++) {
            atomic_init(&z->meet[i], 0);
            if (z->cancel) /* the version to cancel, before any read */
                assert_int_equal(put(z->v, 0, i, at(0.5, 0)), 0);
        }
        pthread_t tw, tr;
        assert_int_equal(pthread_create(&tr, NULL, race_reader, z), 0);
        assert_int_equal(pthread_create(&tw, NULL, race_writer, z), 0);
        pthread_join(tw, NULL);
        pthread_join(tr, NULL);
        for (uint32_t i = 0; i < RS; i++) {
            const bool sent = z->roll[i] == 2u, seen = z->got[i] != z->cancel;
            if (!sent && !seen)
                fail_msg("window %d (%s), sphere %u: the read %s the version, and the %s did "
                         "not send it back",
                         w, z->cancel ? "cancels" : "puts", i, z->cancel ? "took" : "missed",
                         z->cancel ? "cancel" : "put");
            both += sent && seen;
            found_only += seen && !sent;
            sent_only += sent && !seen;
        }
        nbep_versions_close(z->v);
    }
    print_message("%ld races: read in time and not sent back %ld, sent back %ld (of which "
                  "read in time %ld)\n",
                  (long)windows * RS, found_only, sent_only + both, both);
    nbep_versions_destroy(&z->v);
    free(z);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(reads_by_stamp), cmocka_unit_test(tracking),
        cmocka_unit_test(cancels),
        cmocka_unit_test(sends_back),     cmocka_unit_test(signed_times),
        cmocka_unit_test(full_pool),      cmocka_unit_test(refusals),
        cmocka_unit_test(against_model),  cmocka_unit_test(threads),
        cmocka_unit_test(races),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
