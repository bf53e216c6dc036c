/* The optimistic slab scheme's scheduler: see warp.h.
 *
 * Each slab keeps, besides its undo log (undo.c: its records' stamps are what it has done, in
 * order), the messages it was sent this window: those not acted on yet in a heap by (stamp,
 * sender, number), those acted on in a stack in the order acted on (a rollback pops them back
 * into the heap), a cancelled one marked gone (left in the heap until it comes to the top); and
 * an outbox of messages and cancels that mail.c has not taken yet (a full box), sent in order
 * at the slab's next actions, so that a cancel always follows its message. A slab's numbers for
 * its messages are mail.c's (1, 2, ... each window, in the order posted: the outbox keeps that
 * order, so the number is known when the message is queued, before it is posted). */
#include "nbep/warp.h"

#include <assert.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/mail.h"
#include "nbep/undo.h"

/* A test's copy of this file (tests/test_warp.c) looks at each rollback; a build of nbep has
 * nothing here. */
#ifndef NBEP_WARP_ROLLBACK_HOOK
#define NBEP_WARP_ROLLBACK_HOOK(w, slab, s) ((void)0)
#endif

enum { IN_WAITING, IN_DONE, IN_GONE };

/* A message taken from the box; its data (msg_size bytes) follows it. */
typedef struct {
    nbep_mail_head h;
    uint32_t state;
    bool late; /* come after events stamped after it, which it leaves standing (ops.late) */
} input;

/* A message or cancel not yet taken by mail.c; a message's data follows it. */
typedef struct {
    nbep_undo_sent m;
    bool cancel;
} outgoing;

/* a slab's own (its thread's alone), on cache lines of its own */
typedef struct {
    alignas(64) unsigned char *in; /* inputs, in_stride bytes each, in the order taken */
    size_t n_in, cap_in;
    uint32_t *wait; /* a heap of the inputs not acted on (and gone ones not yet dropped) */
    size_t n_wait, cap_wait;
    uint32_t *done; /* the inputs acted on, in the order acted on */
    size_t n_done, cap_done;
    unsigned char *out; /* outgoing, out_stride bytes each; [out_head, n_out) not yet posted */
    size_t out_head, n_out, cap_out;
    uint64_t queued;  /* messages queued this window: the next one's number is one more */
    nbep_stamp now;   /* the stamp of what the slab is acting on (the levels in use: copied
                       * as deep as they go, nbep_cascade_copy) */
    bool idle;        /* as mail.c has it */
    unsigned spins;   /* idle looks since the last action (nbep_spin_pause's count) */
    nbep_warp_tally tally;
} slab_state;

struct nbep_warp {
    nbep_warp_ops ops;
    void *u;
    int slabs;
    size_t state_size, msg_size, in_stride, out_stride;
    double t_end;
    atomic_bool failed;
    nbep_mail *mail;
    nbep_undo *undo;
    slab_state *s; /* owned, slabs */
};

nbep_status nbep_warp_create(int slabs, size_t state_size, size_t msg_size, size_t room,
                             const nbep_warp_ops *ops, void *u, nbep_warp **out, nbep_diag *d)
{
    if (slabs < 1 || slabs > NBEP_WARP_SLABS_MAX)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: the optimistic scheduler takes 1 to %d slabs, not %d",
                  NBEP_WARP_SLABS_MAX, slabs);
    if (state_size < 1 || state_size > 4096 || msg_size < 1 || msg_size > 4096)
        NBEP_FAIL(d, NBEP_EDECK,
                  "nbep: the optimistic scheduler's states and messages hold 1 to 4096 bytes, "
                  "not %zu and %zu",
                  state_size, msg_size);
    nbep_warp *w = calloc(1, sizeof *w);
    if (!w)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the optimistic scheduler");
    w->ops = *ops;
    w->u = u;
    w->slabs = slabs;
    w->state_size = state_size;
    w->msg_size = msg_size;
    w->in_stride = sizeof(input) + nbep_round8(msg_size);
    w->out_stride = sizeof(outgoing) + nbep_round8(msg_size);
    atomic_init(&w->failed, false);
    nbep_status st = nbep_mail_create(slabs, msg_size, room, &w->mail, d);
    if (st == NBEP_OK)
        st = nbep_undo_create(slabs, state_size, &w->undo, d);
    if (st == NBEP_OK) {
        w->s = nbep_alloc_aligned((size_t)slabs, sizeof *w->s);
        if (!w->s) {
            nbep_warp_destroy(&w);
            NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the optimistic scheduler");
        }
    }
    if (st != NBEP_OK) {
        nbep_warp_destroy(&w);
        return st;
    }
    *out = w;
    return NBEP_OK;
}

void nbep_warp_destroy(nbep_warp **w)
{
    if (!w || !*w)
        return;
    if ((*w)->s)
        for (int k = 0; k < (*w)->slabs; k++) {
            free((*w)->s[k].in);
            free((*w)->s[k].wait);
            free((*w)->s[k].done);
            free((*w)->s[k].out);
        }
    nbep_free_aligned((*w)->s);
    nbep_mail_destroy(&(*w)->mail);
    nbep_undo_destroy(&(*w)->undo);
    free(*w);
    *w = NULL;
}

void nbep_warp_open(nbep_warp *w, double t_end)
{
    for (int k = 0; k < w->slabs; k++) {
        slab_state *s = &w->s[k];
        s->n_in = s->n_wait = s->n_done = s->out_head = s->n_out = 0;
        s->queued = 0;
        s->idle = false;
        s->spins = 0;
    }
    nbep_undo_clear(w->undo);
    nbep_mail_open(w->mail);
    w->t_end = t_end;
}

static input *in_at(const nbep_warp *w, const slab_state *s, size_t k)
{
    return (input *)(s->in + k * w->in_stride);
}

static outgoing *out_at(const nbep_warp *w, const slab_state *s, size_t k)
{
    return (outgoing *)(s->out + k * w->out_stride);
}

/* The order inputs are acted on in: by stamp, then sender, then the sender's number (a tie
 * of stamps across senders is the model's to make impossible or harmless; this makes it the
 * same in every run). */
static bool in_before(const input *a, const input *b)
{
    if (nbep_stamp_before(a->h.stamp, b->h.stamp))
        return true;
    if (nbep_stamp_before(b->h.stamp, a->h.stamp))
        return false;
    return a->h.from != b->h.from ? a->h.from < b->h.from : a->h.id < b->h.id;
}

static bool wait_push(nbep_warp *w, slab_state *s, uint32_t k)
{
    if (!nbep_room_for_one((void **)&s->wait, &s->cap_wait, s->n_wait, sizeof *s->wait))
        return false;
    size_t c = s->n_wait++;
    while (c > 0) {
        const size_t p = (c - 1) / 2;
        if (!in_before(in_at(w, s, k), in_at(w, s, s->wait[p])))
            break;
        s->wait[c] = s->wait[p];
        c = p;
    }
    s->wait[c] = k;
    return true;
}

static void wait_pop(nbep_warp *w, slab_state *s)
{
    const uint32_t last = s->wait[--s->n_wait];
    size_t c = 0;
    for (;;) {
        size_t m = 2 * c + 1;
        if (m >= s->n_wait)
            break;
        if (m + 1 < s->n_wait && in_before(in_at(w, s, s->wait[m + 1]), in_at(w, s, s->wait[m])))
            m++;
        if (!in_before(in_at(w, s, s->wait[m]), in_at(w, s, last)))
            break;
        s->wait[c] = s->wait[m];
        c = m;
    }
    if (s->n_wait > 0)
        s->wait[c] = last;
}

/* The earliest input waiting to be acted on (gone ones dropped on the way), or NULL. */
static input *wait_top(nbep_warp *w, slab_state *s)
{
    while (s->n_wait > 0) {
        input *in = in_at(w, s, s->wait[0]);
        if (in->state != IN_GONE)
            return in;
        wait_pop(w, s);
    }
    return NULL;
}

static void give_up(nbep_warp *w)
{
    /* a stop signal only: the window's worlds are not the serial run's from here on, and the
     * caller reads the flag after the meeting (whose acquire orders it) */
    atomic_store_explicit(&w->failed, true, memory_order_relaxed);
}

bool nbep_warp_failed(const nbep_warp *w)
{
    return atomic_load_explicit(&w->failed, memory_order_relaxed);
}

nbep_warp_tally nbep_warp_tally_of(const nbep_warp *w, int slab)
{
    return w->s[slab].tally;
}

typedef struct {
    nbep_warp *w;
    int slab;
} slab_arg;

static void restore_one(void *arg, uint32_t i, const void *state)
{
    const slab_arg *a = arg;
    a->w->ops.restore(a->w->u, a->slab, i, state);
}

static void cancel_one(void *arg, const nbep_undo_sent *m)
{
    const slab_arg *a = arg;
    slab_state *s = &a->w->s[a->slab];
    if (!nbep_room_for_one((void **)&s->out, &s->cap_out, s->n_out, a->w->out_stride)) {
        give_up(a->w);
        return;
    }
    *out_at(a->w, s, s->n_out++) = (outgoing){.m = *m, .cancel = true};
    s->tally.cancels++;
}

/* Slab undoes what it did at or after stamp `to`: its events' and inputs' changes restored and
 * their messages cancelled (undo.c), the inputs put back to act on again. */
static void roll_back(nbep_warp *w, int slab, nbep_stamp to)
{
    slab_state *s = &w->s[slab];
    NBEP_WARP_ROLLBACK_HOOK(w, slab, to);
    slab_arg a = {w, slab};
    s->tally.undone += nbep_undo_back_to(w->undo, slab, &to, restore_one, cancel_one, &a);
    s->tally.rollbacks++;
    while (s->n_done > 0) {
        const uint32_t k = s->done[s->n_done - 1];
        input *in = in_at(w, s, k);
        if (nbep_stamp_before(in->h.stamp, to))
            break;
        s->n_done--;
        in->state = IN_WAITING;
        if (!wait_push(w, s, k))
            give_up(w);
    }
}

bool nbep_warp_roll_back(nbep_warp *w, int slab, const nbep_stamp *to)
{
    assert(slab >= 0 && slab < w->slabs);
    nbep_stamp last;
    if (w->s[slab].idle || !nbep_undo_last(w->undo, slab, &last) || nbep_stamp_before(last, *to))
        return false;
    roll_back(w, slab, *to);
    return true;
}

/* a cut's: nothing is sent (every receiver undoes its own) */
static void cancel_none(void *arg, const nbep_undo_sent *m)
{
    (void)arg, (void)m;
}

void nbep_warp_cut(nbep_warp *w, const nbep_stamp *to, bool past)
{
    for (int k = 0; k < w->slabs; k++) {
        slab_state *s = &w->s[k];
        assert(s->idle && s->out_head == s->n_out);
        slab_arg a = {w, k};
        const size_t undone =
            past ? nbep_undo_back_past(w->undo, k, to, restore_one, cancel_none, &a)
                 : nbep_undo_back_to(w->undo, k, to, restore_one, cancel_none, &a);
        s->tally.undone += undone;
        s->tally.rollbacks += undone > 0;
    }
}

bool nbep_warp_last(const nbep_warp *w, int slab, nbep_stamp *s)
{
    assert(slab >= 0 && slab < w->slabs);
    return nbep_undo_last(w->undo, slab, s);
}

/* One message or cancel taken from slab's box (mail.c's take). */
static void on_mail(void *arg, const nbep_mail_head *h, const void *data)
{
    const slab_arg *a = arg;
    nbep_warp *w = a->w;
    slab_state *s = &w->s[a->slab];
    if (nbep_warp_failed(w))
        return;
    if (h->cancel) { /* its message came before it (one sender's mail comes in order) */
        size_t k = s->n_in;
        while (k-- > 0) {
            const input *in = in_at(w, s, k);
            if (in->h.from == h->from && in->h.id == h->id)
                break;
        }
        assert(k < s->n_in);
        input *in = in_at(w, s, k);
        if (in->state == IN_DONE) /* acted on: undone first (and so waiting again) */
            roll_back(w, a->slab, in->h.stamp);
        in->state = IN_GONE;
        return;
    }
    /* a straggler: the slab went past it. It rolls back to it, unless the model finds that
     * nothing the slab did since read or changed what it changes: then it is acted on late,
     * next (it is the earliest: act), and the events after it stand */
    nbep_stamp last;
    bool late = false;
    if (nbep_undo_last(w->undo, a->slab, &last) && !nbep_stamp_before(last, h->stamp)) {
        late = w->ops.late && w->ops.late(w->u, a->slab, &h->stamp, h->sphere, data);
        if (!late)
            roll_back(w, a->slab, h->stamp);
    }
    if (!nbep_room_for_one((void **)&s->in, &s->cap_in, s->n_in, w->in_stride)) {
        give_up(w);
        return;
    }
    const uint32_t k = (uint32_t)s->n_in++;
    input *in = in_at(w, s, k);
    *in = (input){.h = *h, .state = IN_WAITING, .late = late};
    memcpy(in + 1, data, w->msg_size);
    if (!wait_push(w, s, k))
        give_up(w);
}

/* Posts slab's outbox in order, up to the first box that is full. */
static void post(nbep_warp *w, int slab)
{
    slab_state *s = &w->s[slab];
    if (s->out_head == s->n_out) /* (most calls: a look that costs nearly nothing) */
        return;
    if (nbep_warp_failed(w))
        s->out_head = s->n_out; /* nothing more is worth sending */
    for (; s->out_head < s->n_out; s->out_head++) {
        const outgoing *o = out_at(w, s, s->out_head);
        if (o->cancel) {
            if (!nbep_mail_cancel(w->mail, slab, o->m.to, o->m.id, o->m.stamp, o->m.sphere))
                return;
            continue;
        }
        uint64_t id;
        if (!nbep_mail_send(w->mail, slab, o->m.to, o->m.stamp, o->m.sphere, o + 1, &id))
            return;
        assert(id == o->m.id);
        (void)id;
    }
    s->out_head = s->n_out = 0;
}

/* The input acted on last moved down the slab's done inputs to its stamp's place, as its
 * record in the log (nbep_undo_sink), so that a rollback finds the inputs to act on again at
 * the top, as it finds the records. */
static void sink_done(nbep_warp *w, slab_state *s)
{
    size_t p = s->n_done - 1;
    const uint32_t k = s->done[p];
    const nbep_stamp *st = &in_at(w, s, k)->h.stamp;
    for (; p > 0 && !nbep_stamp_before(in_at(w, s, s->done[p - 1])->h.stamp, *st); p--)
        s->done[p] = s->done[p - 1];
    s->done[p] = k;
}

/* Slab acts on its earliest input or event before the window's end (an input first on a tie);
 * false when it has none. */
static inline NBEP_ALWAYS_INLINE bool act(nbep_warp *w, int slab)
{
    slab_state *s = &w->s[slab];
    if (nbep_warp_failed(w))
        return false;
    input *in = wait_top(w, s);
    nbep_stamp ev;
    const bool has_ev = w->ops.next(w->u, slab, &ev) && ev.t < w->t_end;
    if (!in && !has_ev)
        return false;
    if (in && (!has_ev || !nbep_stamp_before(ev, in->h.stamp))) {
        const uint32_t k = s->wait[0];
        wait_pop(w, s);
        /* (still late: a rollback since it came may have put it in order) */
        nbep_stamp last;
        const bool late = in->late && nbep_undo_last(w->undo, slab, &last) &&
                          !nbep_stamp_before(last, in->h.stamp);
        if (!nbep_room_for_one((void **)&s->done, &s->cap_done, s->n_done, sizeof *s->done) ||
            !(late ? nbep_undo_begin_late(w->undo, slab, &in->h.stamp)
                   : nbep_undo_begin(w->undo, slab, &in->h.stamp))) {
            give_up(w);
            return false;
        }
        s->done[s->n_done++] = k;
        in->state = IN_DONE;
        in->late = false;
        nbep_cascade_copy(&s->now, &in->h.stamp);
        s->tally.applied++;
        w->ops.apply(w->u, slab, in->h.from, &s->now, in->h.sphere, in + 1);
        if (late) {
            s->tally.late++;
            nbep_undo_sink(w->undo, slab);
            sink_done(w, s);
        }
        return true;
    }
    if (w->ops.held && w->ops.held(w->u, slab)) /* (its event waits for the meeting) */
        return false;
    if (!nbep_undo_begin(w->undo, slab, &ev)) {
        give_up(w);
        return false;
    }
    nbep_cascade_copy(&s->now, &ev);
    s->tally.handled++;
    w->ops.handle(w->u, slab, &s->now);
    return true;
}

bool nbep_warp_run(nbep_warp *w, int slab, size_t budget)
{
    assert(slab >= 0 && slab < w->slabs);
    slab_state *s = &w->s[slab];
    slab_arg a = {w, slab};
    for (size_t b = 0; b < budget; b++) {
        if (s->idle && nbep_mail_quiet(w->mail))
            return true;
        if (nbep_mail_take(w->mail, slab, on_mail, &a) > 0)
            s->idle = false; /* as mail.c made it: busy again */
        if (!s->idle) {
            post(w, slab); /* the outbox, a rollback's cancels with it */
            /* No further ahead while mail waits for room: a slab that ran on would pile up
             * messages its receiver cannot take yet, and the cancels its rollbacks send would
             * wait behind them while the receivers act on what they cancel (a ping-pong of two
             * slabs, one held to an action a turn, went back and forth for a million turns
             * without passing the 20th event: test_memory_plan). Waiting, it takes its own
             * mail, as mail.c asks. */
            const bool waits = s->out_head < s->n_out;
            if (!waits && act(w, slab)) {
                s->spins = 0;
                continue;
            }
            if (!waits) {
                nbep_mail_idle(w->mail, slab);
                s->idle = true;
                continue;
            }
        }
        nbep_spin_pause(++s->spins);
    }
    return false;
}

void *nbep_warp_keep_room(nbep_warp *w, int slab, uint32_t item)
{
    void *room = nbep_undo_keep_room(w->undo, slab, item);
    if (!room)
        give_up(w);
    return room;
}

bool nbep_warp_keep(nbep_warp *w, int slab, uint32_t item, const void *state)
{
    void *room = nbep_warp_keep_room(w, slab, item);
    if (room)
        memcpy(room, state, w->state_size);
    return room != NULL;
}

bool nbep_warp_send(nbep_warp *w, int slab, int to, uint32_t item, const void *data)
{
    slab_state *s = &w->s[slab];
    assert(to >= 0 && to < w->slabs && to != slab);
    const nbep_undo_sent m = {.stamp = s->now, .id = s->queued + 1, .sphere = item, .to = to};
    if (!nbep_room_for_one((void **)&s->out, &s->cap_out, s->n_out, w->out_stride) ||
        !nbep_undo_sent_one(w->undo, slab, &m)) {
        give_up(w);
        return false;
    }
    outgoing *o = out_at(w, s, s->n_out++);
    *o = (outgoing){.m = m, .cancel = false};
    memcpy(o + 1, data, w->msg_size);
    s->queued++;
    s->tally.sent++;
    return true;
}
