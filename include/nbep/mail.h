/* Mail between slabs, one window at a time: the optimistic slab scheme's writes across a face,
 * their cancels, and the meeting that ends a window (docs/optimistic-design.md, step 2,
 * *What crosses a face* (2) and *Windows*).
 *
 * A collision of a sphere of this slab's with one of another's writes both; the event's slab
 * sends the other sphere's new state to its owner, stamped with the event, and the owner puts it
 * in that sphere's versions and predicts it from there. When the event rolls back, its slab
 * sends a cancel naming the message (an anti-message: the owner drops the version, and rolls
 * back itself where that was read). A slab's box takes mail from every other slab; a take hands
 * it over in the order it came, and each sender's in the order it was sent (so a cancel comes
 * after the message it names). Nothing here orders by stamp: the receiver does.
 *
 * The window's end is a meeting that needs more than a barrier: a slab that reached the
 * window's end may still be sent mail that rolls it back. Each slab says when it has nothing
 * left to do (nbep_mail_idle: its events before the window's end handled, its mail taken); a
 * take that hands an idle slab mail makes it busy again. The window's work is done when every
 * slab is idle and no mail is untaken (nbep_mail_quiet), and from then on it stays done: no
 * idle slab sends. One count tells it, the busy slabs plus the untaken mail: a send adds one
 * before its mail can be seen, a take subtracts what it hands over but adds one back when the
 * slab was idle (in one step, so the count never passes through 0 while work is left), an idle
 * subtracts one.
 *
 * A box holds `room` messages (rounded up to a power of two, 2 at least). A send to a full box
 * is refused; the sender takes its own mail (into its own list: taking never waits) and tries
 * again. That cannot deadlock: every slab that waits to send takes its mail meanwhile, and
 * every other slab takes at its next look.
 *
 * Threads: open on one thread while no other call runs (every box empty: the last window's
 * work done); send and cancel from slab `from`'s thread, take and idle on slab `to`'s (each
 * slab one thread at a time); quiet on any thread. A slab's sends are numbered 1, 2, ... each
 * window, its cancels from the same numbers. */
#ifndef NBEP_MAIL_H
#define NBEP_MAIL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/versions.h"

/* The most slabs (a slab's number fits the head's 16 bits many times over). */
#define NBEP_MAIL_SLABS_MAX 1024

/* What a message says besides its data: the event that sent it, the sender's number for it (a
 * cancel: the number of the message it cancels), the receiver's sphere it concerns, its
 * sender, and whether it is a cancel. */
typedef struct {
    nbep_stamp stamp;
    uint64_t id;
    uint32_t sphere;
    uint16_t from;
    uint16_t cancel;
} nbep_mail_head;

typedef struct nbep_mail nbep_mail;

/* Receives one message from a take: its head, and its data (the `size` bytes sent; NULL for a
 * cancel). Both are valid only during the call: copy what is kept. */
typedef void (*nbep_mail_fn)(void *arg, const nbep_mail_head *h, const void *data);

/* Boxes for `slabs` (1 to NBEP_MAIL_SLABS_MAX), each of `room` messages (1 to 2^20, rounded up to
 * a power of two) of `size` bytes (1 to 4096) of data; no window open. NBEP_EDECK with a message
 * for a count out of range, NBEP_ENOMEM with one without memory (nothing left allocated). */
NBEP_MUST_CHECK nbep_status nbep_mail_create(int slabs, size_t size, size_t room, nbep_mail **out,
                                             nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_mail_destroy(nbep_mail **m);
/* The bytes create allocates. */
size_t nbep_mail_bytes(int slabs, size_t size, size_t room);

/* Opens a window: every slab busy, the numbering from 1. Every box must be empty. */
void nbep_mail_open(nbep_mail *m);

/* Slab `from`'s event at stamp s sends slab `to` (another slab) `data` (size bytes) about its
 * sphere `sphere`; *id (may be NULL): the message's number. False when to's box is full: then
 * nothing was sent (take your own mail and try again). `from` must be busy. */
NBEP_MUST_CHECK bool nbep_mail_send(nbep_mail *m, int from, int to, nbep_stamp s, uint32_t sphere,
                                    const void *data, uint64_t *id);
/* Slab `from` cancels its message `id` to `to` (stamp s, sphere `sphere`, as sent). False when
 * to's box is full, as for send. */
NBEP_MUST_CHECK bool nbep_mail_cancel(nbep_mail *m, int from, int to, uint64_t id, nbep_stamp s,
                                      uint32_t sphere);

/* Hands slab `to` its mail, each message to fn, in the order it came; returns how many. An idle
 * slab handed mail is busy again. Never waits: mail still being written stays for the next. */
size_t nbep_mail_take(nbep_mail *m, int to, nbep_mail_fn fn, void *arg);
/* Slab `slab` (busy) has nothing left to do in the window: its events before the window's end
 * handled, its mail taken and acted on. */
void nbep_mail_idle(nbep_mail *m, int slab);
/* Whether the window's work is done: every slab idle, all mail taken. Once true, true until the
 * next open; a thread that sees it sees every slab's work before its idle. */
bool nbep_mail_quiet(const nbep_mail *m);

#endif
