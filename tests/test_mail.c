/* Mail between slabs (src/mail.c): messages come whole, in the order sent; a full box refuses
 * and takes again once emptied, lap after lap; the meeting's count says a window's work is done
 * when, and only when, every slab is idle and all mail taken; bad counts are refused with a
 * message. Then threads: four slabs pass tokens (and cancels) to each other at random through
 * boxes of 4, each taking its own mail while a send waits, window after window, and the test
 * checks that every message came once, whole, in its sender's order, that no window ended
 * before its last token did, and that none hung (a watchdog). */
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

#include "nbep/mail.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"
#include "nbep_test_watchdog.h"

enum { SIZE = 24 }; /* three doubles: a token's number, its hops left, a check */

/* A take's messages, copied. */
typedef struct {
    nbep_mail_head h[64];
    double data[64][3];
    bool has_data[64];
    size_t n;
} got;

static void keep(void *arg, const nbep_mail_head *h, const void *data)
{
    got *g = arg;
    assert_true(g->n < 64);
    g->h[g->n] = *h;
    g->has_data[g->n] = data != NULL;
    if (data)
        memcpy(g->data[g->n], data, SIZE);
    g->n++;
}

static nbep_mail *made(int slabs, size_t room)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_mail *m = NULL;
    assert_int_equal(nbep_mail_create(slabs, SIZE, room, &m, &d), NBEP_OK);
    nbep_diag_fini(&d);
    return m;
}

/* Two slabs send to a third, interleaved, one cancel among them: the third takes them in the
 * order sent, each head and datum as sent, numbered per sender from 1, the cancel without data
 * after the message it names; a second take finds nothing. A new window numbers from 1 again. */
static void test_mail_comes_whole_in_the_order_sent(void **state)
{
    (void)state;
    nbep_mail *m = made(3, 16);
    for (int window = 0; window < 2; window++) {
        nbep_mail_open(m);
        struct {
            int from;
            double t;
            uint32_t sphere;
        } sent[] = {{0, 0.5, 7}, {2, 0.25, 9}, {0, 0.75, 7}, {0, -1.0, 3}, {2, 0.25, 11}};
        uint64_t ids[5];
        for (int k = 0; k < 5; k++) {
            const double data[3] = {k, 10.0 * k + window, -0.5 * k};
            assert_true(nbep_mail_send(m, sent[k].from, 1, nbep_stamp_at(sent[k].t, 100u + k, 0),
                                       sent[k].sphere, data, &ids[k]));
        }
        assert_int_equal(ids[0], 1);
        assert_int_equal(ids[2], 2);
        assert_int_equal(ids[3], 3);
        assert_int_equal(ids[1], 1);
        assert_int_equal(ids[4], 2);
        assert_true(nbep_mail_cancel(m, 0, 1, ids[2], nbep_stamp_at(0.75, 102, 0), 7));
        got g = {.n = 0};
        assert_int_equal(nbep_mail_take(m, 1, keep, &g), 6);
        assert_int_equal(g.n, 6);
        for (int k = 0; k < 5; k++) {
            assert_int_equal(g.h[k].from, sent[k].from);
            assert_int_equal(g.h[k].id, ids[k]);
            assert_int_equal(g.h[k].sphere, sent[k].sphere);
            assert_true(g.h[k].stamp.t == sent[k].t && g.h[k].stamp.level[0].key == 100u + k);
            assert_int_equal(g.h[k].cancel, 0);
            assert_true(g.has_data[k]);
            assert_true(g.data[k][0] == k && g.data[k][1] == 10.0 * k + window &&
                        g.data[k][2] == -0.5 * k);
        }
        assert_int_equal(g.h[5].cancel, 1);
        assert_int_equal(g.h[5].from, 0);
        assert_int_equal(g.h[5].id, ids[2]);
        assert_int_equal(g.h[5].sphere, 7);
        assert_true(g.h[5].stamp.t == 0.75 && g.h[5].stamp.level[0].key == 102);
        assert_false(g.has_data[5]);
        got none = {.n = 0};
        assert_int_equal(nbep_mail_take(m, 1, keep, &none), 0);
        assert_int_equal(nbep_mail_take(m, 0, keep, &none), 0);
        assert_int_equal(nbep_mail_take(m, 2, keep, &none), 0);
        assert_int_equal(none.n, 0);
        for (int k = 0; k < 3; k++)
            nbep_mail_idle(m, k);
        assert_true(nbep_mail_quiet(m));
    }
    nbep_mail_destroy(&m);
    assert_null(m);
    nbep_mail_destroy(&m); /* NULL-safe */
}

/* A box of 5 holds 8 (rounded up to a power of two): the ninth send and a cancel are refused,
 * changing nothing (the next send that passes is numbered 9); a take empties it, and so on for
 * 50 laps, every message in its place; a box half full wraps round too. */
static void test_a_full_box_refuses_and_takes_again_once_emptied(void **state)
{
    (void)state;
    nbep_mail *m = made(2, 5);
    nbep_mail_open(m);
    uint64_t next = 1;
    for (int lap = 0; lap < 50; lap++) {
        const int fill = lap % 3 == 2 ? 5 : 8;
        for (int k = 0; k < fill; k++) {
            const double data[3] = {lap, k, 0.0};
            uint64_t id = 0;
            assert_true(nbep_mail_send(m, 0, 1, nbep_stamp_at(lap, (uint64_t)k, 0), 1, data, &id));
            assert_int_equal(id, next++);
        }
        if (fill == 8) {
            const double data[3] = {-1.0, -1.0, -1.0};
            uint64_t id = 77;
            assert_false(nbep_mail_send(m, 0, 1, nbep_stamp_at(lap, 99, 0), 1, data, &id));
            assert_int_equal(id, 77);
            assert_false(nbep_mail_cancel(m, 0, 1, next - 1, nbep_stamp_at(lap, 7, 0), 1));
        }
        got g = {.n = 0};
        assert_int_equal(nbep_mail_take(m, 1, keep, &g), (size_t)fill);
        for (int k = 0; k < fill; k++) {
            assert_int_equal(g.h[k].id, next - (uint64_t)fill + (uint64_t)k);
            assert_true(g.data[k][0] == lap && g.data[k][1] == k);
        }
    }
    nbep_mail_idle(m, 0);
    nbep_mail_idle(m, 1);
    assert_true(nbep_mail_quiet(m));
    nbep_mail_destroy(&m);
    /* a box of 1 holds two (a ring needs two cells) */
    m = made(2, 1);
    nbep_mail_open(m);
    const double data[3] = {0};
    got g = {.n = 0};
    for (int lap = 0; lap < 3; lap++) {
        assert_true(nbep_mail_send(m, 1, 0, nbep_stamp_at(lap, 0, 0), 0, data, NULL));
        assert_true(nbep_mail_send(m, 1, 0, nbep_stamp_at(lap, 1, 0), 0, data, NULL));
        assert_false(nbep_mail_send(m, 1, 0, nbep_stamp_at(lap, 2, 0), 0, data, NULL));
        assert_int_equal(nbep_mail_take(m, 0, keep, &g), 2);
    }
    assert_int_equal(g.n, 6);
    for (size_t k = 0; k < g.n; k++)
        assert_int_equal(g.h[k].id, k + 1);
    nbep_mail_destroy(&m);
}

/* The meeting: a window's work is done only when every slab is idle and all mail is taken.
 * Mail to an idle slab keeps the window open until that slab takes it and is idle again; mail
 * taken by a busy slab leaves it busy; a take of nothing leaves an idle slab idle. */
static void test_a_window_is_done_when_every_slab_is_idle_and_all_mail_taken(void **state)
{
    (void)state;
    nbep_mail *m = made(3, 4);
    assert_true(nbep_mail_quiet(m)); /* no window open */
    const double data[3] = {0};
    got g = {.n = 0};
    nbep_mail_open(m);
    assert_false(nbep_mail_quiet(m));
    nbep_mail_idle(m, 0);
    nbep_mail_idle(m, 2);
    assert_false(nbep_mail_quiet(m)); /* slab 1 busy */
    assert_true(nbep_mail_send(m, 1, 0, nbep_stamp_at(1.0, 0, 0), 4, data, NULL));
    assert_true(nbep_mail_send(m, 1, 0, nbep_stamp_at(1.5, 0, 0), 4, data, NULL));
    nbep_mail_idle(m, 1);
    assert_false(nbep_mail_quiet(m)); /* mail for slab 0 untaken */
    assert_int_equal(nbep_mail_take(m, 2, keep, &g), 0);
    assert_false(nbep_mail_quiet(m));
    assert_int_equal(nbep_mail_take(m, 0, keep, &g), 2);
    assert_false(nbep_mail_quiet(m)); /* slab 0 busy again with it */
    assert_true(nbep_mail_send(m, 0, 2, nbep_stamp_at(2.0, 0, 0), 5, data, NULL));
    nbep_mail_idle(m, 0);
    assert_false(nbep_mail_quiet(m)); /* slab 2's mail */
    assert_int_equal(nbep_mail_take(m, 2, keep, &g), 1);
    assert_false(nbep_mail_quiet(m));
    nbep_mail_idle(m, 2);
    assert_true(nbep_mail_quiet(m));
    assert_int_equal(nbep_mail_take(m, 1, keep, &g), 0);
    assert_true(nbep_mail_quiet(m)); /* done stays done */

    /* a busy slab's take: it stays busy, and its idle ends the window */
    nbep_mail_open(m);
    assert_false(nbep_mail_quiet(m));
    assert_true(nbep_mail_send(m, 0, 1, nbep_stamp_at(0.0, 0, 0), 1, data, NULL));
    assert_true(nbep_mail_send(m, 2, 1, nbep_stamp_at(0.0, 1, 0), 1, data, NULL));
    assert_true(nbep_mail_send(m, 2, 1, nbep_stamp_at(0.0, 2, 0), 1, data, NULL));
    nbep_mail_idle(m, 0);
    nbep_mail_idle(m, 2);
    assert_int_equal(nbep_mail_take(m, 1, keep, &g), 3);
    assert_false(nbep_mail_quiet(m));
    nbep_mail_idle(m, 1);
    assert_true(nbep_mail_quiet(m));
    assert_int_equal(g.n, 6);
    nbep_mail_destroy(&m);

    /* one slab alone: its idle is the window's end */
    m = made(1, 1);
    nbep_mail_open(m);
    assert_false(nbep_mail_quiet(m));
    assert_int_equal(nbep_mail_take(m, 0, keep, &g), 0);
    nbep_mail_idle(m, 0);
    assert_true(nbep_mail_quiet(m));
    nbep_mail_destroy(&m);
}

/* Counts out of range are refused with one line that names them, nothing made. */
static void test_bad_counts_are_refused_with_a_message(void **state)
{
    (void)state;
    const struct {
        int slabs;
        size_t size, room;
        const char *says;
    } bad[] = {
        {0, SIZE, 4, "1 to 1024 slabs, not 0"},
        {NBEP_MAIL_SLABS_MAX + 1, SIZE, 4, "1 to 1024 slabs, not 1025"},
        {2, 0, 4, "1 to 4096 bytes, not 0"},
        {2, 4097, 4, "1 to 4096 bytes, not 4097"},
        {2, SIZE, 0, "1 to 1048576 messages, not 0"},
        {2, SIZE, ((size_t)1 << 20) + 1, "1 to 1048576 messages, not 1048577"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        nbep_diag d;
        nbep_diag_init(&d);
        nbep_mail *m = NULL;
        assert_int_equal(nbep_mail_create(bad[k].slabs, bad[k].size, bad[k].room, &m, &d),
                         NBEP_EDECK);
        assert_null(m);
        assert_int_equal(d.n_errors, 1);
        if (!strstr(d.msg[0], bad[k].says))
            fail_msg("case %zu: \"%s\" does not say \"%s\"", k, d.msg[0], bad[k].says);
        nbep_diag_fini(&d);
    }
    /* the largest are taken */
    nbep_mail *m = made(NBEP_MAIL_SLABS_MAX, 1);
    nbep_mail_destroy(&m);
}

/* ---- threads ------------------------------------------------------------------------------- */

enum { SLABS = 4, TOKENS = 64, HOPS_MAX = 12, WINDOWS = 30 };

typedef struct slab_run {
    nbep_mail *m;
    int slab;
    uint64_t rng;
    /* tokens to pass on: number, hops left */
    double *work;
    size_t n_work, cap_work;
    /* per sender: the last message's number taken, and whether each was cancelled */
    uint64_t last_id[SLABS];
    uint64_t taken, ended, cancels_taken;
    uint64_t bad; /* what this slab found wrong */
    uint64_t acted;      /* `taken` when it last went idle: its work before its idle */
    uint64_t seen_taken; /* at the window's end, every slab's `acted` as this slab saw it */
    struct slab_run *all; /* every slab's */
} slab_run;

static _Atomic int quiet_seen;     /* a thread saw this window's work done */
static atomic_ulong taken_after;   /* mail handed over after that */
static atomic_ulong progress;      /* the watchdog's: messages sent and taken (not retries) */
static atomic_ulong sent_all, cancelled_all;

static uint64_t next_rand(uint64_t *x)
{
    *x ^= *x << 13;
    *x ^= *x >> 7;
    *x ^= *x << 17;
    return *x;
}

static void push_work(slab_run *r, double token, double hops)
{
    if (r->n_work == r->cap_work) {
        r->cap_work = r->cap_work ? 2 * r->cap_work : 64;
        r->work = realloc(r->work, r->cap_work * 2 * sizeof *r->work);
        assert_non_null(r->work);
    }
    r->work[2 * r->n_work] = token;
    r->work[2 * r->n_work + 1] = hops;
    r->n_work++;
}

static void take_token(void *arg, const nbep_mail_head *h, const void *data)
{
    slab_run *r = arg;
    atomic_fetch_add_explicit(&progress, 1, memory_order_relaxed);
    if (atomic_load_explicit(&quiet_seen, memory_order_relaxed))
        atomic_fetch_add_explicit(&taken_after, 1, memory_order_relaxed);
    r->taken++;
    if (h->from >= SLABS || h->from == r->slab) {
        r->bad++;
        return;
    }
    if (h->cancel) { /* names a message already taken from its sender (it came first) */
        r->cancels_taken++;
        if (data || h->id == 0 || h->id > r->last_id[h->from])
            r->bad++;
        return;
    }
    if (!data || h->id <= r->last_id[h->from]) /* each sender's in order (its numbers rise) */
        r->bad++;
    r->last_id[h->from] = h->id;
    double v[3];
    memcpy(v, data, sizeof v);
    if (v[2] != v[0] * 3.0 + v[1] || h->sphere != (uint32_t)v[0] || h->stamp.t != v[1])
        r->bad++; /* torn */
    if (v[1] > 0.0)
        push_work(r, v[0], v[1] - 1.0);
    else
        r->ended++;
}

/* Sends one token on to a random other slab, taking its own mail while the box is full; now
 * and then cancels what it just sent (the receiver only checks the cancel's order). */
static void pass_on(slab_run *r, double token, double hops)
{
    int to = (int)(next_rand(&r->rng) % (SLABS - 1));
    to += to >= r->slab;
    const double data[3] = {token, hops, token * 3.0 + hops};
    uint64_t id;
    while (!nbep_mail_send(r->m, r->slab, to, nbep_stamp_at(hops, (uint64_t)token, 0),
                           (uint32_t)token, data, &id)) {
        (void)nbep_mail_take(r->m, r->slab, take_token, r);
        sched_yield();
    }
    atomic_fetch_add_explicit(&sent_all, 1, memory_order_relaxed);
    if (next_rand(&r->rng) % 8 == 0) {
        while (!nbep_mail_cancel(r->m, r->slab, to, id, nbep_stamp_at(hops, (uint64_t)token, 0),
                                 (uint32_t)token))
            (void)nbep_mail_take(r->m, r->slab, take_token, r);
        atomic_fetch_add_explicit(&cancelled_all, 1, memory_order_relaxed);
    }
}

static void *slab_main(void *arg)
{
    slab_run *r = arg;
    for (;;) {
        (void)nbep_mail_take(r->m, r->slab, take_token, r);
        if (r->n_work > 0) {
            r->n_work--;
            pass_on(r, r->work[2 * r->n_work], r->work[2 * r->n_work + 1]);
            atomic_fetch_add_explicit(&progress, 1, memory_order_relaxed);
            continue;
        }
        r->acted = r->taken;
        nbep_mail_idle(r->m, r->slab);
        for (;;) { /* idle: wait for mail or the window's end */
            if (nbep_mail_quiet(r->m)) {
                atomic_store_explicit(&quiet_seen, 1, memory_order_relaxed);
                /* a slab that sees the window done sees every slab's work before its idle
                 * (plain fields: ThreadSanitizer reports it if it does not) */
                r->seen_taken = 0;
                for (int k = 0; k < SLABS; k++)
                    r->seen_taken += r->all[k].acted;
                return NULL;
            }
            if (nbep_mail_take(r->m, r->slab, take_token, r) > 0)
                break; /* busy again */
            sched_yield(); /* (more threads than cores) */
        }
    }
}

static void test_threads_pass_mail_until_the_window_is_done(void **state)
{
    (void)state;
    nbep_mail *m = made(SLABS, 4);
    nbep_test_watchdog_arm_progress(10, "test_mail: threads made no progress for 10 s: a hang\n",
                                    &progress);
    slab_run run[SLABS];
    memset(run, 0, sizeof run);
    uint64_t tokens = 0, taken = 0, ended = 0, cancels = 0;
    /* under valgrind (for the memory alone) a few short windows: its one thread at a time spends
     * each waiting thread's turn spinning */
    const int windows = (int)nbep_test_scaled(WINDOWS, 4);
    const uint64_t most_tokens = nbep_test_scaled(TOKENS, 8);
    const uint64_t most_hops = nbep_test_scaled(HOPS_MAX, 3);
    for (int w = 0; w < windows; w++) {
        const uint64_t before = tokens;
        nbep_mail_open(m);
        atomic_store(&quiet_seen, 0);
        atomic_store(&sent_all, 0);
        atomic_store(&cancelled_all, 0);
        for (int k = 0; k < SLABS; k++) {
            slab_run *r = &run[k];
            r->m = m;
            r->slab = k;
            r->all = run;
            r->rng = 0x9E3779B97F4A7C15ull * (uint64_t)(w * SLABS + k + 1);
            r->n_work = 0;
            memset(r->last_id, 0, sizeof r->last_id);
            r->taken = r->ended = r->cancels_taken = r->acted = 0;
            const int n = 1 + (int)(next_rand(&r->rng) % most_tokens);
            for (int q = 0; q < n; q++) {
                const double token = (double)(tokens++ % 1000000);
                push_work(r, token, (double)(1 + next_rand(&r->rng) % most_hops));
            }
        }
        pthread_t th[SLABS];
        for (int k = 0; k < SLABS; k++)
            assert_int_equal(pthread_create(&th[k], NULL, slab_main, &run[k]), 0);
        for (int k = 0; k < SLABS; k++)
            pthread_join(th[k], NULL);
        uint64_t w_taken = 0, w_ended = 0, w_cancels = 0, bad = 0;
        for (int k = 0; k < SLABS; k++) {
            w_taken += run[k].taken;
            w_ended += run[k].ended;
            w_cancels += run[k].cancels_taken;
            bad += run[k].bad;
            assert_int_equal(run[k].n_work, 0);
        }
        for (int k = 0; k < SLABS; k++) {
            assert_int_equal(run[k].seen_taken, w_taken);
            got none = {.n = 0};
            assert_int_equal(nbep_mail_take(m, k, keep, &none), 0); /* nothing left */
        }
        if (bad || atomic_load(&taken_after) || w_ended != tokens - before ||
            w_taken != atomic_load(&sent_all) + atomic_load(&cancelled_all) ||
            w_cancels != atomic_load(&cancelled_all))
            fail_msg("window %d: %llu wrong, %llu taken after the window was done, %llu of %llu "
                     "tokens ended, %llu taken of %llu sent and %llu cancelled",
                     w, (unsigned long long)bad, (unsigned long long)atomic_load(&taken_after),
                     (unsigned long long)w_ended, (unsigned long long)(tokens - before),
                     (unsigned long long)w_taken, (unsigned long long)atomic_load(&sent_all),
                     (unsigned long long)atomic_load(&cancelled_all));
        taken += w_taken;
        ended += w_ended;
        cancels += w_cancels;
    }
    nbep_test_watchdog_disarm();
    fprintf(stderr, "%d windows: %llu messages taken, %llu cancels, %llu tokens ended\n", windows,
            (unsigned long long)taken, (unsigned long long)cancels, (unsigned long long)ended);
    for (int k = 0; k < SLABS; k++)
        free(run[k].work);
    nbep_mail_destroy(&m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mail_comes_whole_in_the_order_sent),
        cmocka_unit_test(test_a_full_box_refuses_and_takes_again_once_emptied),
        cmocka_unit_test(test_a_window_is_done_when_every_slab_is_idle_and_all_mail_taken),
        cmocka_unit_test(test_bad_counts_are_refused_with_a_message),
        cmocka_unit_test(test_threads_pass_mail_until_the_window_is_done),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
