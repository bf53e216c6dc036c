/* The optimistic slab scheme's scheduler, one window at a time (docs/optimistic-design.md,
 * step 2, *The scheduler*): each slab's thread handles its own events in its own time order,
 * ahead of the others, and rolls back when it learns it went too far. The model (the cells
 * engine, or a test's) says what an event is; this says when it runs and what to undo.
 *
 * A slab keeps a world of its own (the model's: its own items and copies of the others' that
 * its events read) and changes it only by its own events and by messages. An event may send a
 * message to another slab about one of that slab's items or copies (a write across a face, or
 * a copy's new state), stamped with the event (nbep_stamp, a cascade stamp: cascade.h). A slab
 * acts on its events and messages in stamp order, a message before an event of the same stamp;
 * a message that comes stamped at or before what the slab has already done (a straggler) sends
 * the slab back:
 * it undoes everything it did from that stamp on, newest first (its items restored from the
 * states kept before each change, its messages cancelled, the messages it had acted on put back
 * to act on again), then goes on. A cancel of a message not yet acted on drops it; of one acted
 * on, sends the slab back to it first. So whatever the threads' timing, each slab ends the
 * window having acted on exactly the events and messages of the serial order, in that order:
 * the serial run's results, bit for bit, if the model's handlers depend only on the world they
 * are given (Jefferson's Time Warp, with the window's meeting as its global virtual time).
 *
 * Built on mail.h (the boxes and the meeting) and undo.h (the logs). A message waiting for a
 * full box stays in its sender's outbox (the sender busy) and goes at its next action, so no
 * handler ever waits: slabs may run on threads, one each, or take turns on one thread
 * (nbep_warp_run's budget: a test holds one slab back that way, so that rollbacks happen).
 *
 * Threads: create, open, destroy on one thread while no other call runs; run, keep, send on
 * the slab's own thread (keep and send only inside the model's handle and apply); failed and
 * tally on any, between windows. */
#ifndef NBEP_WARP_H
#define NBEP_WARP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/versions.h"

typedef struct nbep_warp nbep_warp;

/* The model's side; u is the model's context. Items are numbered by the model (below
 * UINT32_MAX); each slab's world holds its own state of every item it touches. */
typedef struct nbep_warp_ops {
    /* slab's earliest own event, its stamp in *s; false when it has none */
    bool (*next)(void *u, int slab, nbep_stamp *s);
    /* handles that event (next's, stamped *s: valid until it returns): before changing an
     * item, nbep_warp_keep its state; messages through nbep_warp_send */
    void (*handle)(void *u, int slab, const nbep_stamp *s);
    /* acts on a message to slab from slab `from`: `data` (msg_size bytes) about `item`, from
     * the event stamped *s (as handle's); keeps before it changes, as handle (and may send) */
    void (*apply)(void *u, int slab, int from, const nbep_stamp *s, uint32_t item,
                  const void *data);
    /* puts item back to `state` (state_size bytes, as kept) in slab's world; the model's own
     * calendar of events goes back with it */
    void (*restore)(void *u, int slab, uint32_t item, const void *state);
    /* may be NULL: true where the event next has just given (before the window's end) is to
     * wait for the meeting: the slab then acts only on messages stamped before it, and is idle
     * once it has none (the model does it between windows, after nbep_warp_cut to it) */
    bool (*held)(void *u, int slab);
    /* may be NULL: true where a message stamped *s about `item` (its `data`), come after slab
     * handled events stamped at or after it, may be acted on without undoing them, because
     * none of them read or changed what it changes and it changes nothing they kept (the
     * model's own test, which must be sure: a true taken wrongly makes the results differ from
     * the serial order's). It is then acted on at once, its record sunk to its stamp's place
     * (nbep_undo_sink), as if it had come in order; NULL or false: the slab rolls back to it.
     * Called on the slab's thread before the message is acted on. */
    bool (*late)(void *u, int slab, const nbep_stamp *s, uint32_t item, const void *data);
} nbep_warp_ops;

/* What a slab did, in all windows since create: events handled (again after a rollback too),
 * messages acted on, events and messages undone, rollbacks, messages sent, cancels sent, and
 * messages come late but acted on without a rollback (ops.late). */
typedef struct {
    uint64_t handled, applied, undone, rollbacks, sent, cancels, late;
} nbep_warp_tally;

/* The most slabs (the mail's and the logs' bound). */
#define NBEP_WARP_SLABS_MAX 1024

/* A scheduler for `slabs` (1 to NBEP_WARP_SLABS_MAX) slabs whose items' states are state_size
 * bytes and messages msg_size (1 to 4096 each), with boxes of `room` messages (mail.h); ops
 * and u kept. No window open. NBEP_EDECK with a message for a count out of range, NBEP_ENOMEM
 * with one without memory (nothing left allocated). */
NBEP_MUST_CHECK nbep_status nbep_warp_create(int slabs, size_t state_size, size_t msg_size,
                                             size_t room, const nbep_warp_ops *ops, void *u,
                                             nbep_warp **out, nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_warp_destroy(nbep_warp **w);

/* Opens a window that ends at time t_end: the slabs act on what is stamped before it. The last
 * window's work must be done (every slab's run returned true). */
void nbep_warp_open(nbep_warp *w, double t_end);
/* Slab's thread: up to `budget` actions (taking mail, acting on one event or message, a look
 * whether the window's work is done); true once it is done (every slab's and all mail: then
 * every slab's world holds the serial run's results up to t_end). SIZE_MAX: until then. */
bool nbep_warp_run(nbep_warp *w, int slab, size_t budget);

/* Inside handle or apply on slab: item, now in `state` (state_size bytes), is about to change.
 * False when no memory could be had (the window fails: nbep_warp_failed). */
bool nbep_warp_keep(nbep_warp *w, int slab, uint32_t item, const void *state);
/* The same, the state written by the model in place (one copy fewer): the room for it
 * (state_size bytes, 8-byte aligned, to be filled before the next keep), or NULL as keep's
 * false. */
void *nbep_warp_keep_room(nbep_warp *w, int slab, uint32_t item);
/* Inside handle or apply on slab: sends slab `to` (another) `data` (msg_size bytes) about its
 * item, stamped with the event (or message) acted on. False as for keep. */
bool nbep_warp_send(nbep_warp *w, int slab, int to, uint32_t item, const void *data);

/* Between slab's runs (on its thread, not inside handle or apply): slab undoes what it did at
 * or after *to, as a straggler stamped *to would make it (its events' and messages' changes
 * restored, newest first, their messages cancelled), and acts on them again as its next and
 * its mail give them: for tests of a model's restore, which one slab otherwise never calls.
 * False, nothing done, where slab has nothing to undo there or is idle (its window's work
 * looked done: a rollback then would need the meeting's count raised again). */
bool nbep_warp_roll_back(nbep_warp *w, int slab, const nbep_stamp *to);

/* After a window's work is done (every slab's run returned true), on one thread: every slab
 * undoes what it did at or after *to (past: after it; its events' and messages' changes
 * restored, newest first), and nothing is sent: each message stamped there or later was sent by an event that
 * its sender undoes and acted on by a slab that undoes that too, so every world then holds the
 * serial run's results up to *to (a window cut short where the model finds it must do
 * something between the slabs' worlds at *to, at the meeting). The next call is open's. */
void nbep_warp_cut(nbep_warp *w, const nbep_stamp *to, bool past);

/* The stamp of the newest event or message slab has done in this window and not undone, in *s;
 * false when it has none. */
bool nbep_warp_last(const nbep_warp *w, int slab, nbep_stamp *s);

/* Whether a window ran out of memory (its worlds are then not the serial run's). */
bool nbep_warp_failed(const nbep_warp *w);
nbep_warp_tally nbep_warp_tally_of(const nbep_warp *w, int slab);
/* *to += t, count by count (a sum over slabs or runs). */
static inline void nbep_warp_tally_add(nbep_warp_tally *to, nbep_warp_tally t)
{
    to->handled += t.handled;
    to->applied += t.applied;
    to->undone += t.undone;
    to->rollbacks += t.rollbacks;
    to->sent += t.sent;
    to->cancels += t.cancels;
    to->late += t.late;
}

#endif
