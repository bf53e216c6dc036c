/* The optimistic scheduler (src/warp.c) against the serial order, on a model small enough to
 * run both ways and compare: sites on a ring, cut into slabs of consecutive sites. An event of
 * a site reads its two neighbours (another slab's, at a slab's edge: the slab's copy of it),
 * writes itself and its next event's time, and one time in four writes a neighbour too (its
 * value and next time: across a face, a message to the neighbour's owner); each slab sends its
 * edge sites' new values to the slab beside as copies. Run serially on one world (a plain loop
 * over the sites' times), and by the scheduler on 1 to 4 slabs, each with a world of its own,
 * window after window: the owners' sites, the edge copies and the count of events must come out
 * the serial run's bit for bit.
 *
 * On one thread the slabs take turns with budgets drawn at random, one slab held to a single
 * action a turn, so the others run ahead and are sent back: the test wants rollbacks, cancels and
 * inputs acted on again, and each rollback to be to a stamp before what the slab had done; the
 * same turns again with the `late` op (a copy that none of the slab's events since read nor
 * changed acted on without a rollback), which must come out the same and act late. On
 * threads (one a slab, one slab slowed by a spin in each event) the same results, under a
 * progress watchdog (a hang fails). A message and an event of one stamp: the message first,
 * whichever slab runs first. Then bad counts refused with a message. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/undo.h"
#include "nbep/warp.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"
#include "nbep_test_watchdog.h"
#include "warp_ring.h"

/* Each rollback: to a stamp at or before the slab's newest record (what it had done). */
static atomic_ulong bad_rollbacks;
struct nbep_warp;
static void look_at_rollback(struct nbep_warp *w, int slab, nbep_stamp to);
#define NBEP_WARP_ROLLBACK_HOOK(w, slab, s) look_at_rollback(w, slab, s)
#include "../src/warp.c"

static void look_at_rollback(struct nbep_warp *w, int slab, nbep_stamp to)
{
    nbep_stamp last;
    if (!nbep_undo_last(w->undo, slab, &last) || nbep_stamp_before(last, to))
        atomic_fetch_add(&bad_rollbacks, 1);
}

enum { SITES_MAX = 96, SLABS_MAX = 4 };

typedef struct {
    uint64_t val[SITES_MAX];
    double next[SITES_MAX];       /* the owner's: each own site's next event */
    nbep_stamp stamp[SITES_MAX];  /* and its cascade stamp (cascade.h) */
    uint64_t events;              /* events that stand (item SITES_MAX) */
    double touched[SITES_MAX];    /* the time of the newest event of this world that changed
                                   * each site (a rollback leaves it: later than the truth) */
} world;

/* What a keep saves of a site: its value, its next event's time and stamp */
typedef struct {
    ring_state rs;
    nbep_stamp stamp;
} toy_state;

typedef struct {
    int slabs;
    int sites;          /* the ring's, SITES_MAX at most */
    uint64_t most;      /* events handled past which a run has gone round in circles */
    world w[SLABS_MAX];
    nbep_warp *warp; /* NULL: the serial run */
    int slow;        /* the slab whose events spin (threads), -1: none */
    atomic_ulong progress;
    uint64_t ties, back; /* the serial run's events at the time of the one before; and those of
                            them at a lower site (before it in (time, site)) */
} toy;

static int owner(const toy *x, int k)
{
    return (int)((size_t)k * (size_t)x->slabs / (size_t)x->sites);
}


static void keep(toy *x, int slab, uint32_t item)
{
    if (!x->warp)
        return;
    const world *W = &x->w[slab];
    if (item == SITES_MAX) { /* the count written in place, a site copied in: both ways */
        toy_state *room = nbep_warp_keep_room(x->warp, slab, item);
        assert_non_null(room);
        room->rs = (ring_state){W->events, 0.0};
        return;
    }
    const toy_state s = {{W->val[item], W->next[item]}, W->stamp[item]};
    assert_true(nbep_warp_keep(x->warp, slab, item, &s));
}

static void send(toy *x, int slab, int to, uint32_t item, ring_note n)
{
    assert_true(nbep_warp_send(x->warp, slab, to, item, &n));
}

/* Own site k's new value to the other slabs that hold copies of it (its neighbours' owners),
 * but `except` (the writer, who has it already). */
static void send_copies(toy *x, int slab, int k, int except)
{
    if (!x->warp)
        return;
    const int nb[2] = {(k + x->sites - 1) % x->sites, (k + 1) % x->sites};
    int sent = -1;
    for (int q = 0; q < 2; q++) {
        const int to = owner(x, nb[q]);
        if (to != slab && to != except && to != sent) {
            send(x, slab, to, (uint32_t)k, (ring_note){x->w[slab].val[k], 0.0, RING_COPY});
            sent = to;
        }
    }
}

/* Site q's entry at time `next`, made by the event stamped *now: its stamp */
static nbep_stamp made_by(const nbep_stamp *now, double next, int q)
{
    nbep_stamp c;
    assert_true(nbep_cascade_made(now, next, (uint64_t)q, (uint32_t)q, &c));
    return c;
}

/* Site k's event, stamped *now (its time now->t), on slab's world (the serial run: slab 0 of
 * one). One write across in two is a tie: the site written has its next event at once, at the
 * same time (before the writer's in (time, site) where it is the lower site: the serial loop
 * takes it next, and its stamp is the writer's child), while the cascade stays within the
 * stamps' depth (the same in every run: the serial run stamps its events too). */
static void site_event(toy *x, int slab, int k, const nbep_stamp *now)
{
    world *W = &x->w[slab];
    const double t = now->t;
    const int km = (k + x->sites - 1) % x->sites, kp = (k + 1) % x->sites;
    const uint64_t v = ring_mix(W->val[km], W->val[k], W->val[kp], t);
    keep(x, slab, SITES_MAX);
    W->events++;
    keep(x, slab, (uint32_t)k);
    W->touched[k] = t;
    W->val[k] = v;
    W->next[k] = t + ring_gap(v);
    W->stamp[k] = made_by(now, W->next[k], k);
    send_copies(x, slab, k, -1);
    if ((v & 3) != 0)
        return;
    const int q = (v & 4) ? kp : km; /* a write across, where q is another slab's */
    const uint64_t vq = ring_mix(v, W->val[q], RING_SALT, t);
    keep(x, slab, (uint32_t)q);
    W->touched[q] = t;
    W->val[q] = vq;
    const bool tie = (vq & 8) && now->depth < NBEP_CASCADE_DEPTH; /* made: one level deeper */
    W->next[q] = tie ? t : t + ring_gap(vq);
    W->stamp[q] = made_by(now, W->next[q], q);
    if (owner(x, q) == slab)
        send_copies(x, slab, q, -1);
    else
        send(x, slab, owner(x, q), (uint32_t)q, (ring_note){vq, W->next[q], RING_WRITE});
}

/* The earliest own site's event of slab's world by its stamp (the scheduler's order): in *s */
static bool earliest(const toy *x, int slab, nbep_stamp *s)
{
    const world *W = &x->w[slab];
    bool any = false;
    for (int k = 0; k < x->sites; k++) {
        if (owner(x, k) != slab)
            continue;
        if (!any || nbep_stamp_before(W->stamp[k], *s)) {
            *s = W->stamp[k];
            any = true;
        }
    }
    return any;
}

static bool toy_next(void *u, int slab, nbep_stamp *s)
{
    return earliest(u, slab, s);
}

static void toy_handle(void *u, int slab, const nbep_stamp *s)
{
    toy *x = u;
    if (slab == x->slow) /* held back a little each event: the others run ahead */
        for (volatile int spin = 0; spin < 2000; spin++)
            ;
    site_event(x, slab, (int)s->level[s->depth - 1].item, s);
    if (atomic_fetch_add_explicit(&x->progress, 1, memory_order_relaxed) > x->most) {
        fputs("test_warp: the slabs handled far more events than the serial run: going round in "
              "circles\n", stderr);
        _exit(1); /* (a thread's: cmocka fails only on its main thread) */
    }
}

static void toy_apply(void *u, int slab, int from, const nbep_stamp *s, uint32_t item,
                      const void *data)
{
    toy *x = u;
    ring_note n;
    memcpy(&n, data, sizeof n);
    world *W = &x->w[slab];
    keep(x, slab, item);
    W->val[item] = n.val;
    if (n.kind == RING_WRITE) { /* its own site, written across the face */
        assert_int_equal(owner(x, (int)item), slab);
        W->next[item] = n.next;
        W->stamp[item] = made_by(s, n.next, (int)item); /* made by the writer's event */
        send_copies(x, slab, (int)item, from);
    } else {
        assert_int_not_equal(owner(x, (int)item), slab);
    }
}

static void toy_restore(void *u, int slab, uint32_t item, const void *state)
{
    toy *x = u;
    toy_state s;
    memcpy(&s, state, sizeof s);
    world *W = &x->w[slab];
    if (item == SITES_MAX) {
        W->events = s.rs.val;
        return;
    }
    W->val[item] = s.rs.val;
    W->next[item] = s.rs.next;
    W->stamp[item] = s.stamp;
}

static const nbep_warp_ops toy_ops = {toy_next, toy_handle, toy_apply, toy_restore, NULL, NULL};

/* warp.h's late: a copy of site j come after events of this slab is acted on without a
 * rollback where none of them read j (the events of its neighbours, j - 1 and j + 1, read it)
 * nor changed it (a write across): none of the three changed at or after its time */
static bool toy_late(void *u, int slab, const nbep_stamp *s, uint32_t item, const void *data)
{
    const toy *x = u;
    ring_note n;
    memcpy(&n, data, sizeof n);
    const world *W = &x->w[slab];
    const int j = (int)item, jm = (j + x->sites - 1) % x->sites, jp = (j + 1) % x->sites;
    return n.kind == RING_COPY && W->touched[j] < s->t && W->touched[jm] < s->t &&
           W->touched[jp] < s->t;
}

static const nbep_warp_ops toy_ops_late = {toy_next,    toy_handle, toy_apply,
                                           toy_restore, NULL,       toy_late};
static bool with_late; /* made() gives the scheduler toy_late */

static void start(toy *x, int slabs, int sites, uint64_t seed)
{
    memset(x, 0, sizeof *x);
    x->slabs = slabs;
    x->sites = sites;
    x->slow = -1;
    x->most = UINT64_MAX;
    for (int k = 0; k < sites; k++) {
        x->w[0].touched[k] = -1.0; /* (before every event) */
        x->w[0].val[k] = ring_mix64(seed * SITES_MAX + (uint64_t)k);
        x->w[0].next[k] = ring_gap(x->w[0].val[k]);
        x->w[0].stamp[k] = nbep_stamp_at(x->w[0].next[k], (uint64_t)k, (uint32_t)k);
    }
    for (int s = 1; s < slabs; s++)
        x->w[s] = x->w[0];
}

/* The serial run to t_end: one world, the earliest event first by (time, site), as a calendar
 * takes them (its stamps made all the same, for the ties' depth; and checked: they rise). */
static void serial(toy *x, double t_end)
{
    assert_int_equal(x->slabs, 1);
    world *W = &x->w[0];
    nbep_stamp last = nbep_stamp_at(0.0, 0, 0);
    for (uint64_t taken = 0;; taken++) {
        int k = 0;
        for (int j = 1; j < x->sites; j++)
            if (W->next[j] < W->next[k])
                k = j;
        if (!(W->next[k] < t_end))
            return;
        const nbep_stamp now = W->stamp[k]; /* its time W->next[k] */
        if (taken > 0) {
            const int k_last = (int)last.level[last.depth - 1].item;
            x->ties += now.t == last.t;
            x->back += now.t == last.t && k < k_last;
            if (!nbep_stamp_before(last, now))
                fail_msg("the serial run's event at site %d (t %.17g) is stamped at or before "
                         "the one before it (site %d)", k, now.t, k_last);
        }
        last = now;
        site_event(x, 0, k, &now);
    }
}

/* The slabs' worlds against the serial one: each site as its owner has it, each copy a slab
 * keeps of a site beside its own, and the events. */
static void same_as_serial(const toy *x, const toy *ref)
{
    uint64_t events = 0;
    for (int s = 0; s < x->slabs; s++)
        events += x->w[s].events;
    assert_int_equal(events, ref->w[0].events);
    for (int k = 0; k < x->sites; k++) {
        const world *W = &x->w[owner(x, k)];
        if (W->val[k] != ref->w[0].val[k] || W->next[k] != ref->w[0].next[k])
            fail_msg("site %d: value %llx next %.17g on slab %d, serial %llx %.17g", k,
                     (unsigned long long)W->val[k], W->next[k], owner(x, k),
                     (unsigned long long)ref->w[0].val[k], ref->w[0].next[k]);
        const int nb[2] = {(k + x->sites - 1) % x->sites, (k + 1) % x->sites};
        for (int q = 0; q < 2; q++) {
            const int s = owner(x, nb[q]);
            if (s != owner(x, k) && x->w[s].val[k] != ref->w[0].val[k])
                fail_msg("slab %d's copy of site %d: %llx, serial %llx", s, k,
                         (unsigned long long)x->w[s].val[k],
                         (unsigned long long)ref->w[0].val[k]);
        }
    }
}

static uint64_t rng_next(uint64_t *r)
{
    *r = ring_mix64(*r);
    return *r;
}

enum { WINDOWS = 40 };
/* The rings: slabs of 24 sites and more, and of one or two (so that a site's neighbours are two
 * other slabs', and a write across a face is copied on by the slab written to). */
static const int RINGS[2] = {SITES_MAX, 5};
static const double T_END = 12.0; /* about a thousand events */

static nbep_warp *made(toy *x, size_t room)
{
    nbep_warp *w = NULL;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_warp_create(x->slabs, sizeof(toy_state), sizeof(ring_note), room,
                                      with_late ? &toy_ops_late : &toy_ops, x, &w, &d),
                     NBEP_OK);
    nbep_diag_fini(&d);
    x->warp = w;
    return w;
}

/* One thread: the slabs take turns in an order drawn each round, with budgets of 1 to 24
 * actions, slab 0 held to 1; a window ends when every slab has said its work is done. With
 * late, copies that no event since read are acted on late, and the results are the same. */
static void turns_give_the_serial_results(bool late)
{
    with_late = late;
    nbep_warp_tally all = {0};
    uint64_t ties = 0, back = 0;
    /* under valgrind (for the memory alone) a seed's two rings */
    const uint64_t runs = nbep_test_scaled(12, 2);
    for (uint64_t run = 0; run < runs; run++) {
        const uint64_t seed = 1 + run / 2;
        const int sites = RINGS[run % 2];
        toy ref;
        start(&ref, 1, sites, seed);
        serial(&ref, T_END);
        ties += ref.ties;
        back += ref.back;
        for (int slabs = 1; slabs <= SLABS_MAX; slabs++) {
            toy *x = malloc(sizeof *x);
            assert_non_null(x);
            start(x, slabs, sites, seed);
            x->most = 50 * ref.w[0].events + 1000;
            nbep_warp *w = made(x, 4);
            uint64_t r = run * 977 + (uint64_t)slabs;
            for (int win = 1; win <= WINDOWS; win++) {
                nbep_warp_open(w, T_END * win / WINDOWS);
                bool done[SLABS_MAX] = {false};
                int n_done = 0;
                for (long round = 0; n_done < slabs; round++) {
                    assert_true(round < 1000000); /* a hang: no window needs this many */
                    const int first = (int)(rng_next(&r) % (uint64_t)slabs);
                    for (int q = 0; q < slabs; q++) {
                        const int s = (first + q) % slabs;
                        const size_t budget = s == 0 ? 1 : 1 + rng_next(&r) % 24;
                        if (!done[s] && nbep_warp_run(w, s, budget)) {
                            done[s] = true;
                            n_done++;
                        }
                    }
                }
            }
            assert_false(nbep_warp_failed(w));
            same_as_serial(x, &ref);
            for (int s = 0; s < slabs; s++) {
                const nbep_warp_tally t = nbep_warp_tally_of(w, s);
                nbep_warp_tally_add(&all, t);
                if (slabs == 1)
                    assert_int_equal(t.rollbacks + t.sent + t.applied, 0);
            }
            nbep_warp_destroy(&w);
            free(x);
        }
    }
    fprintf(stderr,
            "turns%s: %llu events handled, %llu messages sent, %llu acted on (%llu late), %llu "
            "rollbacks undoing %llu, %llu cancels; the serial runs' events at the time of the "
            "one before %llu, %llu of them at a lower site\n",
            late ? " with late copies" : "", (unsigned long long)all.handled,
            (unsigned long long)all.sent, (unsigned long long)all.applied,
            (unsigned long long)all.late, (unsigned long long)all.rollbacks,
            (unsigned long long)all.undone, (unsigned long long)all.cancels,
            (unsigned long long)ties, (unsigned long long)back);
    /* the serial order went back in (time, site), where only cascade stamps order it */
    assert_true(back > 0);
    /* the held-back slab made the others run ahead: every kind of going back happened */
    assert_true(all.rollbacks > 0);
    assert_true(all.undone > all.rollbacks);
    assert_true(all.cancels > 0);
    assert_true(all.applied > all.sent / 2);
    assert_int_equal(atomic_load(&bad_rollbacks), 0);
    if (late) /* (copies came late that nothing had read, and were kept late) */
        assert_true(all.late > 10);
    else
        assert_int_equal(all.late, 0);
}

static void test_turns_give_the_serial_results(void **state)
{
    (void)state;
    turns_give_the_serial_results(false);
}

static void test_late_copies_give_the_serial_results(void **state)
{
    (void)state;
    turns_give_the_serial_results(true);
}

/* (the late op off again after a failure too, and its bad rollbacks forgotten, for the tests
 * that follow) */
static int late_off(void **state)
{
    (void)state;
    with_late = false;
    atomic_store(&bad_rollbacks, 0);
    return 0;
}

typedef struct {
    toy *x;
    int slab;
    pthread_barrier_t *bar;
} slab_thread;

static void *slab_main(void *arg)
{
    slab_thread *t = arg;
    nbep_warp *w = t->x->warp;
    for (int win = 1; win <= WINDOWS; win++) {
        if (t->slab == 0)
            nbep_warp_open(w, T_END * win / WINDOWS);
        pthread_barrier_wait(t->bar);
        while (!nbep_warp_run(w, t->slab, 64))
            ;
        pthread_barrier_wait(t->bar); /* every slab done before the next open */
    }
    return NULL;
}

/* Threads, one a slab, slab 0 slowed: the same results whatever the timing. */
static void test_threads_give_the_serial_results(void **state)
{
    (void)state;
    /* under valgrind (for the memory alone: it runs one thread at a time, and each waiting
     * slab spins through its turn) the small ring on 2 slabs only */
    const uint64_t runs = nbep_test_scaled(8, 1);
    const int most_slabs = (int)nbep_test_scaled(SLABS_MAX, 2);
    uint64_t rollbacks = 0;
    for (uint64_t run = 0; run < runs; run++) {
        const uint64_t seed = 1 + run / 2;
        const int sites = RINGS[(run + 1) % 2];
        toy ref;
        start(&ref, 1, sites, seed);
        serial(&ref, T_END);
        for (int slabs = 2; slabs <= most_slabs; slabs++) {
            toy *x = malloc(sizeof *x);
            assert_non_null(x);
            start(x, slabs, sites, seed);
            x->most = 50 * ref.w[0].events + 1000;
            x->slow = 0;
            nbep_warp *w = made(x, 2);
            nbep_test_watchdog_arm_progress(
                10, "test_warp: the slabs' threads made no progress for 10 s: a hang\n",
                &x->progress);
            pthread_barrier_t bar;
            pthread_barrier_init(&bar, NULL, (unsigned)slabs);
            slab_thread th[SLABS_MAX];
            pthread_t id[SLABS_MAX];
            for (int s = 0; s < slabs; s++) {
                th[s] = (slab_thread){x, s, &bar};
                assert_int_equal(pthread_create(&id[s], NULL, slab_main, &th[s]), 0);
            }
            for (int s = 0; s < slabs; s++)
                pthread_join(id[s], NULL);
            nbep_test_watchdog_disarm();
            pthread_barrier_destroy(&bar);
            assert_false(nbep_warp_failed(w));
            same_as_serial(x, &ref);
            for (int s = 0; s < slabs; s++)
                rollbacks += nbep_warp_tally_of(w, s).rollbacks;
            nbep_warp_destroy(&w);
            free(x);
        }
    }
    fprintf(stderr, "threads: %llu rollbacks\n", (unsigned long long)rollbacks);
    assert_int_equal(atomic_load(&bad_rollbacks), 0);
}

static void refused(int slabs, size_t state, size_t msg, const char *says)
{
    nbep_warp *w = NULL;
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_warp_create(slabs, state, msg, 4, &toy_ops, NULL, &w, &d), NBEP_EDECK);
    assert_null(w);
    assert_int_equal(d.n_errors, 1);
    if (!strstr(d.msg[0], says))
        fail_msg("\"%s\" does not say \"%s\"", d.msg[0], says);
    nbep_diag_fini(&d);
}

/* A message and an event of one stamp in one slab (warp.h: the message first). A model of two
 * slabs, each with one event at the same stamp: slab 0's sends slab 1 a message; slab 1 logs
 * its event (E) and the message (M) in the order it acts on them, and puts the log back on a
 * rollback. Slab 0 first: slab 1 holds both at once and must take the message first; slab 1
 * first: it has done its event when the message comes, stamped as that event, which makes the
 * message a straggler (at or before what it did): the event is undone and done again after. */
typedef struct {
    uint32_t done, n_log;
} tie_world;
typedef struct {
    tie_world s[2];
    char log[8];
    nbep_warp *w;
} tie_model;
static const nbep_stamp TIE_STAMP = {.t = 1.0, .depth = 1, .level = {{5, 7, 0}}};

static bool tie_next(void *u, int slab, nbep_stamp *s)
{
    const tie_model *x = u;
    if (x->s[slab].done)
        return false;
    *s = TIE_STAMP;
    return true;
}

static void tie_handle(void *u, int slab, const nbep_stamp *s)
{
    tie_model *x = u;
    assert_true(nbep_cascade_cmp(s, &TIE_STAMP) == 0);
    assert_true(nbep_warp_keep(x->w, slab, 0, &x->s[slab]));
    x->s[slab].done = 1;
    const uint64_t note = 42;
    if (slab == 0)
        assert_true(nbep_warp_send(x->w, 0, 1, 0, &note));
    else
        x->log[x->s[1].n_log++] = 'E';
}

static void tie_apply(void *u, int slab, int from, const nbep_stamp *s, uint32_t item,
                      const void *data)
{
    tie_model *x = u;
    uint64_t note;
    memcpy(&note, data, sizeof note);
    assert_true(slab == 1 && from == 0 && item == 0 && note == 42);
    assert_true(nbep_cascade_cmp(s, &TIE_STAMP) == 0);
    assert_true(nbep_warp_keep(x->w, slab, 0, &x->s[1]));
    x->log[x->s[1].n_log++] = 'M';
}

static void tie_restore(void *u, int slab, uint32_t item, const void *state)
{
    tie_model *x = u;
    assert_int_equal(item, 0);
    memcpy(&x->s[slab], state, sizeof x->s[slab]);
}

static void test_a_message_comes_before_an_event_of_its_stamp(void **state)
{
    (void)state;
    static const nbep_warp_ops ops = {tie_next, tie_handle, tie_apply, tie_restore, NULL, NULL};
    for (int first = 0; first < 2; first++) {
        tie_model x = {0};
        nbep_diag d;
        nbep_diag_init(&d);
        assert_int_equal(nbep_warp_create(2, sizeof(tie_world), sizeof(uint64_t), 4, &ops, &x,
                                          &x.w, &d),
                         NBEP_OK);
        nbep_diag_fini(&d);
        nbep_warp_open(x.w, 2.0);
        /* the first slab alone until it has acted on its event, then turns of a few actions */
        while (!x.s[first].done)
            (void)nbep_warp_run(x.w, first, 1);
        bool done[2] = {false, false};
        for (int turn = 0; !(done[0] && done[1]); turn++) {
            assert_true(turn < 1000); /* a hang */
            for (int q = 0; q < 2; q++)
                if (!done[q])
                    done[q] = nbep_warp_run(x.w, q, 3);
        }
        assert_false(nbep_warp_failed(x.w));
        assert_int_equal(x.s[1].n_log, 2);
        assert_true(x.log[0] == 'M' && x.log[1] == 'E');
        const nbep_warp_tally t = nbep_warp_tally_of(x.w, 1);
        assert_int_equal(t.applied, 1);
        /* slab 1 first: its event undone for the message and done again */
        assert_int_equal(t.rollbacks, first == 1 ? 1 : 0);
        assert_int_equal(t.handled, first == 1 ? 2 : 1);
        nbep_warp_destroy(&x.w);
    }
}

static void test_bad_counts_are_refused(void **state)
{
    (void)state;
    refused(0, 16, 24, "takes 1 to 1024 slabs, not 0");
    refused(NBEP_WARP_SLABS_MAX + 1, 16, 24, "not 1025");
    refused(2, 0, 24, "hold 1 to 4096 bytes, not 0 and 24");
    refused(2, 16, 4097, "not 16 and 4097");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_turns_give_the_serial_results),
        cmocka_unit_test_teardown(test_late_copies_give_the_serial_results, late_off),
        cmocka_unit_test(test_threads_give_the_serial_results),
        cmocka_unit_test(test_a_message_comes_before_an_event_of_its_stamp),
        cmocka_unit_test(test_bad_counts_are_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
