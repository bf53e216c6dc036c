/* Each slab's log of what its events changed and sent within a window, so that it can roll
 * back: the optimistic slab scheme's rollback (docs/optimistic-design.md, step 2, *Rollback*).
 *
 * A slab handles its own events in its own time order, ahead of the others. When it learns that
 * one of them came too soon (a version put before a note it left: versions.h; a message stamped
 * before events it handled that read the sphere: mail.h), it undoes its events from that stamp
 * on, newest first: each sphere an event changed goes back to the state it kept before (the
 * caller's: motion, slot, response count, what it needs), and each message the event sent is
 * cancelled. The caller then handles them again. At the window's end every event is final and
 * the log is emptied.
 *
 * An event's record: its stamp, the spheres it changed with their state before (`size` bytes
 * each, kept in the order given: they are restored in the reverse order, so a sphere kept twice
 * ends in its first state), and the messages it sent (to whom, the message's number, the sphere
 * and stamp it named: what a cancel names, mail.h). Records are kept in the slab's time order:
 * each begins stamped after the last (asserted), but for a late message, which sinks to its
 * place (nbep_undo_sink).
 *
 * Threads: each slab's log is its own thread's; clear between windows. Memory: each slab's
 * records, states and sends grow by doubling as a window needs them; a growth refused is false
 * and changes nothing (the caller ends its window there, as for a full pool of versions). */
#ifndef NBEP_UNDO_H
#define NBEP_UNDO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/versions.h"

typedef struct nbep_undo nbep_undo;

/* A message an event sent, as its cancel names it. */
typedef struct {
    nbep_stamp stamp;
    uint64_t id;
    uint32_t sphere;
    int32_t to;
} nbep_undo_sent;

/* Puts sphere i back to `state` (size bytes, as kept). */
typedef void (*nbep_undo_restore_fn)(void *arg, uint32_t i, const void *state);
/* Cancels message m (sent by the event undone). */
typedef void (*nbep_undo_cancel_fn)(void *arg, const nbep_undo_sent *m);

/* The most slabs. */
#define NBEP_UNDO_SLABS_MAX 1024

/* Logs for `slabs` (1 to NBEP_UNDO_SLABS_MAX) slabs of states of `size` bytes (1 to 4096), empty. NBEP_EDECK
 * with a message for a count out of range, NBEP_ENOMEM with one without memory. */
NBEP_MUST_CHECK nbep_status nbep_undo_create(int slabs, size_t size, nbep_undo **out,
                                             nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_undo_destroy(nbep_undo **u);

/* Slab `slab` begins its event stamped *s (after its last record's stamp). False when no memory
 * could be had: then nothing changed. */
NBEP_MUST_CHECK bool nbep_undo_begin(nbep_undo *u, int slab, const nbep_stamp *s);
/* The same for a message stamped before records the slab already has, acted on without
 * undoing them (the caller found that none of them read what it changes: warp.h's `late`):
 * begun on top, and put in its stamp's place by nbep_undo_sink once its spheres are kept. */
NBEP_MUST_CHECK bool nbep_undo_begin_late(nbep_undo *u, int slab, const nbep_stamp *s);
/* The slab's newest record moved down to its stamp's place, below every record stamped at or
 * after it, its kept states, sends and levels with it: the log is in time order again, as if
 * it had come in order (a rollback to a stamp after it leaves it; one to it or before undoes
 * it after the records above it, which changed none of its spheres). Nothing where it is in
 * place already (one comparison). */
void nbep_undo_sink(nbep_undo *u, int slab);
/* Its current event is about to change sphere i, now in `state`: kept. False as for begin. */
NBEP_MUST_CHECK bool nbep_undo_keep(nbep_undo *u, int slab, uint32_t i, const void *state);
/* The same, the state written by the caller in place: the room for it (size bytes, 8-byte
 * aligned, valid until the slab's next keep), or NULL as keep's false. */
void *nbep_undo_keep_room(nbep_undo *u, int slab, uint32_t i);
/* Its current event sent message m. False as for begin. */
NBEP_MUST_CHECK bool nbep_undo_sent_one(nbep_undo *u, int slab, const nbep_undo_sent *m);

/* Undoes slab's events stamped at or after *s, newest first: for each, its messages cancelled
 * (cancel, in the order sent), then its spheres restored (restore, in the reverse order kept);
 * the records dropped. Returns how many events were undone. */
size_t nbep_undo_back_to(nbep_undo *u, int slab, const nbep_stamp *s, nbep_undo_restore_fn restore,
                         nbep_undo_cancel_fn cancel, void *arg);
/* The same for the events stamped after *s (the one stamped *s, if any, stays). */
size_t nbep_undo_back_past(nbep_undo *u, int slab, const nbep_stamp *s,
                           nbep_undo_restore_fn restore, nbep_undo_cancel_fn cancel, void *arg);
/* The stamp of slab's newest record in *s; false when it has none this window. */
bool nbep_undo_last(const nbep_undo *u, int slab, nbep_stamp *s);
/* The events slab has recorded this window. */
size_t nbep_undo_count(const nbep_undo *u, int slab);
/* Between windows: every slab's records forgotten (their memory kept for the next). */
void nbep_undo_clear(nbep_undo *u);

#endif
