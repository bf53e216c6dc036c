/* The slabs' undo logs (src/undo.c): rolling back to a stamp undoes the events stamped at or
 * after it, newest first, each one's messages cancelled in the order sent and its spheres put
 * back in the reverse order kept (a sphere kept twice ends in its first state); then random
 * events and rollbacks on three slabs against a plain model of the world, stamped as the cells
 * engine's cascades stamp them (most deeper than a root: the log keeps their levels apart):
 * after every rollback each sphere is as it was before the first event undone, the cancels are
 * exactly the undone events' messages, and the log's last stamp is the model's, whole; a late
 * message's record sunk to its place; bad counts refused with their message. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/undo.h"
#include "nbep_test.h"
#include "nbep_test_stamp.h"

enum { SIZE = 16 }; /* two doubles a state */

/* What a rollback did, in order: restores (sphere, state) and cancels (message numbers). */
typedef struct {
    double *world; /* the spheres' states, SIZE bytes each */
    uint32_t restored[256];
    double restored_to[256][2];
    size_t n_restored;
    uint64_t cancelled[256];
    size_t n_cancelled;
} seen;

static void restore(void *arg, uint32_t i, const void *state)
{
    seen *w = arg;
    assert_true(w->n_restored < 256);
    w->restored[w->n_restored] = i;
    memcpy(w->restored_to[w->n_restored], state, SIZE);
    w->n_restored++;
    if (w->world)
        memcpy(&w->world[2 * i], state, SIZE);
}

static void cancel(void *arg, const nbep_undo_sent *m)
{
    seen *w = arg;
    assert_true(w->n_cancelled < 256);
    w->cancelled[w->n_cancelled++] = m->id;
}

static nbep_undo *made(int slabs)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_undo *u = NULL;
    assert_int_equal(nbep_undo_create(slabs, SIZE, &u, &d), NBEP_OK);
    nbep_diag_fini(&d);
    return u;
}

static void keep2(nbep_undo *u, int slab, uint32_t i, double a, double b)
{
    const double st[2] = {a, b};
    assert_true(nbep_undo_keep(u, slab, i, st));
}

static void sent(nbep_undo *u, int slab, uint64_t id, int to)
{
    const nbep_undo_sent m = {.stamp = {0.0, 0}, .id = id, .sphere = 0, .to = to};
    assert_true(nbep_undo_sent_one(u, slab, &m));
}

/* Three events on slab 1 (at 1, 2 and 3; the second keeps sphere 3 twice and sends two
 * messages); slab 0's one event untouched by slab 1's rollbacks. Back to (2, 5): the third and
 * the second undone, the third first; its spheres back in the reverse order kept (sphere 3 to
 * its first state); its messages cancelled in the order sent. Back to (1, 8), after (1, 7): none.
 * Back to (1, 7): the first, stamped there. */
static void test_a_rollback_undoes_from_its_stamp_newest_first(void **state)
{
    (void)state;
    nbep_undo *u = made(2);
    assert_true(nbep_undo_begin(u, 0, STAMP_AT(0.5, 1, 0)));
    keep2(u, 0, 9, 9.0, 9.5);
    assert_true(nbep_undo_begin(u, 1, STAMP_AT(1.0, 7, 0)));
    keep2(u, 1, 4, 40.0, 41.0);
    sent(u, 1, 1, 0);
    assert_true(nbep_undo_begin(u, 1, STAMP_AT(2.0, 5, 0)));
    keep2(u, 1, 3, 30.0, 31.0);
    keep2(u, 1, 5, 50.0, 51.0);
    keep2(u, 1, 3, 32.0, 33.0);
    sent(u, 1, 2, 0);
    sent(u, 1, 3, 0);
    assert_true(nbep_undo_begin(u, 1, STAMP_AT(3.0, 1, 0)));
    keep2(u, 1, 5, 52.0, 53.0);
    assert_int_equal(nbep_undo_count(u, 1), 3);

    seen w = {.world = NULL};
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(2.0, 5, 0), restore, cancel, &w), 2);
    assert_int_equal(nbep_undo_count(u, 1), 1);
    assert_int_equal(nbep_undo_count(u, 0), 1);
    const uint32_t order[4] = {5, 3, 5, 3};
    const double to[4][2] = {{52.0, 53.0}, {32.0, 33.0}, {50.0, 51.0}, {30.0, 31.0}};
    assert_int_equal(w.n_restored, 4);
    for (int k = 0; k < 4; k++) {
        assert_int_equal(w.restored[k], order[k]);
        assert_true(w.restored_to[k][0] == to[k][0] && w.restored_to[k][1] == to[k][1]);
    }
    assert_int_equal(w.n_cancelled, 2);
    assert_int_equal(w.cancelled[0], 2);
    assert_int_equal(w.cancelled[1], 3);

    seen none = {.world = NULL};
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(1.0, 8, 0), restore, cancel, &none), 0);
    assert_int_equal(none.n_restored + none.n_cancelled, 0);
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(1.0, 7, 0), restore, cancel, &none), 1);
    assert_int_equal(none.n_restored, 1);
    assert_int_equal(none.restored[0], 4);
    assert_int_equal(none.n_cancelled, 1);
    assert_int_equal(none.cancelled[0], 1);
    assert_int_equal(nbep_undo_count(u, 1), 0);
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(-1.0, 0, 0), restore, cancel, &none), 0);

    /* the window's end forgets slab 0's too; the log takes new events after */
    nbep_undo_clear(u);
    assert_int_equal(nbep_undo_count(u, 0), 0);
    assert_true(nbep_undo_begin(u, 0, STAMP_AT(0.1, 0, 0)));
    keep2(u, 0, 2, 1.0, 2.0);
    seen after = {.world = NULL};
    assert_int_equal(nbep_undo_back_to(u, 0, STAMP_AT(0.0, 0, 0), restore, cancel, &after), 1);
    assert_int_equal(after.n_restored, 1);
    assert_int_equal(after.restored[0], 2);
    nbep_undo_destroy(&u);
    assert_null(u);
    nbep_undo_destroy(&u); /* NULL-safe */
}

/* Whether the slab's last stamp is *want, whole */
static void last_is(const nbep_undo *u, int slab, const nbep_stamp *want)
{
    nbep_stamp s;
    assert_true(nbep_undo_last(u, slab, &s));
    assert_int_equal(nbep_cascade_cmp(&s, want), 0);
}

/* A late message's record (warp.h's late: acted on after events stamped after it, which it
 * leaves standing) sinks to its stamp's place with its states, sends and deeper levels: events
 * at 1, 2 (a cascade's stamp, two levels) and 3 on slab 1, then one at 1.5 (two levels too)
 * begun late, keeping sphere 4 twice and sending one message. The last stamp stays the one at
 * 3; back to 2.5 undoes that alone; back to 1.2 undoes the one at 2, then the late one (its
 * sphere to its first state), their messages cancelled in that order, and leaves the one at 1,
 * whose stamp is then the last. A late record stamped after the newest stays where it is; one
 * stamped before every record sinks to the bottom; slab 0's record is never moved. */
static void test_a_late_record_sinks_to_its_stamps_place(void **state)
{
    (void)state;
    nbep_undo *u = made(2);
    assert_true(nbep_undo_begin(u, 0, STAMP_AT(0.5, 1, 0)));
    keep2(u, 0, 9, 9.0, 9.5);
    const nbep_stamp two = {.t = 2.0, .depth = 2, .level = {{5, 2, 0}, {6, 7, 0}}};
    const nbep_stamp late = {.t = 1.5, .depth = 2, .level = {{3, 1, 0}, {8, 4, 0}}};
    assert_true(nbep_undo_begin(u, 1, STAMP_AT(1.0, 7, 0)));
    keep2(u, 1, 1, 10.0, 11.0);
    sent(u, 1, 1, 0);
    assert_true(nbep_undo_begin(u, 1, &two));
    keep2(u, 1, 2, 20.0, 21.0);
    sent(u, 1, 2, 0);
    assert_true(nbep_undo_begin(u, 1, STAMP_AT(3.0, 1, 0)));
    keep2(u, 1, 3, 30.0, 31.0);
    sent(u, 1, 3, 0);
    assert_true(nbep_undo_begin_late(u, 1, &late));
    keep2(u, 1, 4, 40.0, 41.0);
    keep2(u, 1, 4, 42.0, 43.0);
    sent(u, 1, 4, 0);
    nbep_undo_sink(u, 1);
    assert_int_equal(nbep_undo_count(u, 1), 4);
    last_is(u, 1, STAMP_AT(3.0, 1, 0));

    seen w = {.world = NULL};
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(2.5, 0, 0), restore, cancel, &w), 1);
    assert_int_equal(w.n_restored, 1);
    assert_int_equal(w.restored[0], 3);
    assert_int_equal(w.n_cancelled, 1);
    assert_int_equal(w.cancelled[0], 3);
    last_is(u, 1, &two);

    seen v = {.world = NULL};
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(1.2, 0, 0), restore, cancel, &v), 2);
    const uint32_t order[3] = {2, 4, 4};
    const double to[3][2] = {{20.0, 21.0}, {42.0, 43.0}, {40.0, 41.0}};
    assert_int_equal(v.n_restored, 3);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(v.restored[k], order[k]);
        assert_true(v.restored_to[k][0] == to[k][0] && v.restored_to[k][1] == to[k][1]);
    }
    assert_int_equal(v.n_cancelled, 2);
    assert_int_equal(v.cancelled[0], 2);
    assert_int_equal(v.cancelled[1], 4);
    last_is(u, 1, STAMP_AT(1.0, 7, 0));

    /* after the newest: in place; before every record: to the bottom */
    assert_true(nbep_undo_begin_late(u, 1, STAMP_AT(4.0, 0, 0)));
    keep2(u, 1, 5, 50.0, 51.0);
    nbep_undo_sink(u, 1);
    last_is(u, 1, STAMP_AT(4.0, 0, 0));
    assert_true(nbep_undo_begin_late(u, 1, &late));
    nbep_undo_sink(u, 1); /* (one with nothing kept) */
    assert_true(nbep_undo_begin_late(u, 1, STAMP_AT(0.25, 0, 0)));
    keep2(u, 1, 6, 60.0, 61.0);
    nbep_undo_sink(u, 1);
    last_is(u, 1, STAMP_AT(4.0, 0, 0));
    seen x = {.world = NULL};
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(0.3, 0, 0), restore, cancel, &x), 3);
    const uint32_t order2[2] = {5, 1};
    assert_int_equal(x.n_restored, 2);
    for (int k = 0; k < 2; k++)
        assert_int_equal(x.restored[k], order2[k]);
    last_is(u, 1, STAMP_AT(0.25, 0, 0));
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(0.0, 0, 0), restore, cancel, &x), 1);
    assert_int_equal(x.restored[2], 6);
    assert_true(x.restored_to[2][0] == 60.0);
    assert_int_equal(nbep_undo_count(u, 1), 0);
    assert_int_equal(nbep_undo_count(u, 0), 1);
    last_is(u, 0, STAMP_AT(0.5, 1, 0));

    /* a late record with more states than undo.c's buffer holds (60 of 24 bytes: turned a
     * piece at a time) sinks below one event, whose states stay its own */
    assert_true(nbep_undo_begin(u, 1, STAMP_AT(2.0, 0, 0)));
    keep2(u, 1, 7, 70.0, 71.0);
    assert_true(nbep_undo_begin_late(u, 1, STAMP_AT(1.0, 0, 0)));
    for (uint32_t k = 0; k < 60; k++)
        keep2(u, 1, 100 + k, k, -(double)k);
    nbep_undo_sink(u, 1);
    last_is(u, 1, STAMP_AT(2.0, 0, 0));
    seen y = {.world = NULL};
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(1.5, 0, 0), restore, cancel, &y), 1);
    assert_int_equal(y.n_restored, 1);
    assert_int_equal(y.restored[0], 7);
    assert_true(y.restored_to[0][0] == 70.0 && y.restored_to[0][1] == 71.0);
    assert_int_equal(nbep_undo_back_to(u, 1, STAMP_AT(0.0, 0, 0), restore, cancel, &y), 1);
    assert_int_equal(y.n_restored, 61);
    for (uint32_t k = 0; k < 60; k++) { /* (newest first) */
        assert_int_equal(y.restored[1 + k], 159 - k);
        assert_true(y.restored_to[1 + k][0] == 59.0 - k && y.restored_to[1 + k][1] == k - 59.0);
    }
    nbep_undo_destroy(&u);
}

/* ---- random events and rollbacks against a plain model ------------------------------------ */

enum { SLABS = 3, SPHERES = 40, EVENTS_MAX = 400, STEPS = 20000 };

typedef struct {
    nbep_stamp s;              /* its stamp: a cascade's (deeper than one level) or a root */
    double before[SPHERES][2]; /* the slab's spheres before it */
    uint64_t sent_from, sent_to; /* its messages' numbers: [from, to) */
} model_event;

static uint64_t next_rand(uint64_t *x)
{
    *x ^= *x << 13;
    *x ^= *x >> 7;
    *x ^= *x << 17;
    return *x;
}

/* The stamp just after s in the serial order: its least extension (or, at the depth bound,
 * its last level made once more), before every later stamp that is not one of its own. */
static nbep_stamp just_after(nbep_stamp s)
{
    if (s.depth < NBEP_CASCADE_DEPTH)
        s.level[s.depth++] = (nbep_cascade_level){0, 0, 0};
    else
        s.level[s.depth - 1].again++;
    return s;
}

/* Each slab owns spheres k, k + SLABS, ...; its events change one to three of them (one maybe
 * twice) and send none to two messages. Most events come at the time of the slab's last one,
 * stamped as the cells engine's cascades make them (cascade.h: children, siblings, makings
 * again, up to the depth bound), so most records hold stamps deeper than their first level,
 * which the log keeps apart; the rest at a later time, as roots. Now and then a slab rolls
 * back to a random stamp between its records (a record's own, or just after it), before all or
 * after all; and at random the window ends (clear). After each event and rollback the log's
 * last stamp is the model's, whole; after each rollback the slab's spheres are as before the
 * first event undone, and the cancels are the undone events' messages, newest event first,
 * each event's in the order sent. */
static void test_random_events_and_rollbacks_match_a_plain_model(void **state)
{
    (void)state;
    nbep_undo *u = made(SLABS);
    static double world[SPHERES * 2];
    static model_event ev[SLABS][EVENTS_MAX];
    size_t n_ev[SLABS] = {0};
    double clock[SLABS] = {0};
    uint64_t next_id[SLABS] = {0};
    uint64_t rng = 12345;
    for (int i = 0; i < SPHERES; i++)
        world[2 * i] = world[2 * i + 1] = i;
    size_t rollbacks = 0, undone_all = 0, deep = 0, deepest = 0;
    /* not scaled down under valgrind (a few hundred milliseconds there): 2000 steps' cascades
     * stopped at 6 levels */
    const int steps = STEPS;
    for (int step = 0; step < steps; step++) {
        const int sl = (int)(next_rand(&rng) % SLABS);
        const uint64_t r = next_rand(&rng) % 100;
        if (r < 70 && n_ev[sl] < EVENTS_MAX) { /* an event */
            const size_t n = n_ev[sl];
            model_event *e = &ev[sl][n];
            const uint64_t key = next_rand(&rng) % 16;
            const uint32_t item = (uint32_t)(next_rand(&rng) % 4);
            if (n == 0 || next_rand(&rng) % 8 == 0 ||
                !nbep_cascade_made(&ev[sl][n - 1].s, clock[sl], key, item, &e->s)) {
                clock[sl] += 0.25;
                e->s = nbep_stamp_at(clock[sl], key, item);
            }
            n_ev[sl]++;
            deep += e->s.depth > 1;
            deepest = e->s.depth > deepest ? e->s.depth : deepest;
            memcpy(e->before, world, sizeof e->before);
            assert_true(nbep_undo_begin(u, sl, &e->s));
            const int changes = 1 + (int)(next_rand(&rng) % 3);
            for (int c = 0; c < changes; c++) {
                const uint32_t i =
                    (uint32_t)(sl + SLABS * (int)(next_rand(&rng) % (SPHERES / SLABS)));
                assert_true(nbep_undo_keep(u, sl, i, &world[2 * i]));
                world[2 * i] += 1.0 + (double)step;
                world[2 * i + 1] = -(double)step;
            }
            e->sent_from = next_id[sl];
            const int sends = (int)(next_rand(&rng) % 3);
            for (int c = 0; c < sends; c++) {
                const nbep_undo_sent m = {.stamp = e->s, .id = next_id[sl]++,
                                          .sphere = (uint32_t)c, .to = (sl + 1) % SLABS};
                assert_true(nbep_undo_sent_one(u, sl, &m));
            }
            e->sent_to = next_id[sl];
        } else if (r < 97) { /* a rollback to a stamp among the records, or past either end */
            const size_t n = n_ev[sl];
            const size_t at = n ? (size_t)(next_rand(&rng) % (n + 2)) : 0;
            nbep_stamp to;
            if (at == 0 || n == 0)
                to = nbep_stamp_at(-1.0, 0, 0);
            else if (at > n)
                to = nbep_stamp_at(clock[sl] + 1.0, 0, 0);
            else if (next_rand(&rng) % 2)
                to = ev[sl][at - 1].s;
            else
                to = just_after(ev[sl][at - 1].s);
            /* the model: the first record at or after `to` */
            size_t first = n;
            while (first > 0 && !nbep_stamp_before(ev[sl][first - 1].s, to))
                first--;
            seen w = {.world = world};
            const size_t undone = nbep_undo_back_to(u, sl, &to, restore, cancel, &w);
            assert_int_equal(undone, n - first);
            assert_int_equal(nbep_undo_count(u, sl), first);
            if (undone) {
                /* this slab's spheres as before the first undone; the others' untouched */
                for (int i = sl; i < SPHERES; i += SLABS)
                    assert_memory_equal(&world[2 * i], ev[sl][first].before[i], SIZE);
                size_t q = 0;
                for (size_t k = n; k-- > first;)
                    for (uint64_t id = ev[sl][k].sent_from; id < ev[sl][k].sent_to; id++) {
                        assert_true(q < w.n_cancelled);
                        assert_int_equal(w.cancelled[q++], id);
                    }
                assert_int_equal(q, w.n_cancelled);
                next_id[sl] = ev[sl][first].sent_from; /* numbers used again, as a slab would */
                clock[sl] = ev[sl][first].s.t;
            } else {
                assert_int_equal(w.n_restored + w.n_cancelled, 0);
            }
            n_ev[sl] = first;
            rollbacks++;
            undone_all += undone;
        } else { /* the window's end: every slab's events final */
            nbep_undo_clear(u);
            for (int k = 0; k < SLABS; k++) {
                n_ev[k] = 0;
                assert_int_equal(nbep_undo_count(u, k), 0);
            }
        }
        /* the log's last stamp, whole: its time, depth and every level */
        nbep_stamp last;
        assert_int_equal(nbep_undo_last(u, sl, &last), n_ev[sl] > 0);
        if (n_ev[sl] > 0) {
            const nbep_stamp *m = &ev[sl][n_ev[sl] - 1].s;
            assert_true(last.t == m->t);
            assert_int_equal(last.depth, m->depth);
            assert_memory_equal(last.level, m->level, m->depth * sizeof m->level[0]);
        }
    }
    fprintf(stderr, "%d steps: %zu rollbacks, %zu events undone, %zu stamps deeper than a "
                    "root (deepest %zu levels)\n",
            steps, rollbacks, undone_all, deep, deepest);
    assert_true(undone_all > 0);
    assert_true(deep > 0 && deepest == NBEP_CASCADE_DEPTH); /* the model reaches the bound */
    nbep_undo_destroy(&u);
}

/* Counts out of range are refused with one line that names them, nothing made. */
static void test_bad_counts_are_refused_with_a_message(void **state)
{
    (void)state;
    const struct {
        int slabs;
        size_t size;
        const char *says;
    } bad[] = {
        {0, SIZE, "1 to 1024 slabs, not 0"},
        {NBEP_UNDO_SLABS_MAX + 1, SIZE, "1 to 1024 slabs, not 1025"},
        {2, 0, "1 to 4096 bytes, not 0"},
        {2, 4097, "1 to 4096 bytes, not 4097"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        nbep_diag d;
        nbep_diag_init(&d);
        nbep_undo *u = NULL;
        assert_int_equal(nbep_undo_create(bad[k].slabs, bad[k].size, &u, &d), NBEP_EDECK);
        assert_null(u);
        assert_int_equal(d.n_errors, 1);
        if (!strstr(d.msg[0], bad[k].says))
            fail_msg("case %zu: \"%s\" does not say \"%s\"", k, d.msg[0], bad[k].says);
        nbep_diag_fini(&d);
    }
    nbep_undo *u = made(NBEP_UNDO_SLABS_MAX);
    nbep_undo_destroy(&u);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_rollback_undoes_from_its_stamp_newest_first),
        cmocka_unit_test(test_a_late_record_sinks_to_its_stamps_place),
        cmocka_unit_test(test_random_events_and_rollbacks_match_a_plain_model),
        cmocka_unit_test(test_bad_counts_are_refused_with_a_message),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
