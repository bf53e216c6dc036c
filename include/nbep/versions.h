/* Versions of sphere states and notes of reads, one window at a time: the optimistic slab
 * scheme's reads across a face (docs/optimistic-design.md, step 2, *What crosses a face*).
 *
 * Within a window each slab's thread handles its own events in its own time order, ahead of
 * the others. A sphere near a face (the caller decides which: within SIDE_REACH of its slab's
 * side) is read by other slabs' events, at their own times; so its owner does not overwrite
 * its state but puts each new one here as a version stamped with the event that wrote it, and
 * a reader takes the version valid at its event's stamp. The caller's arrays keep the state
 * at the window's start all window long (no one writes them then): a read that finds no
 * version before its stamp reads them. At the window's end (all threads met) the caller
 * writes each tracked sphere's newest version back and closes the window.
 *
 * A reader leaves a note on each sphere it reads (the latest time any slab read it, and which
 * slabs read it), before it reads. A version put, or cancelled (its event rolled back), at a
 * stamp at or before the note's time may have come too soon for those readers: put and cancel
 * return their slabs, which roll back to the stamp. The note is coarse (one time, a bit a
 * slab): a reader may be sent back when it read in time, never left when it read too soon.
 * That holds for reads running at the same time as the put: see versions.c, *Why no read too
 * soon is missed*.
 *
 * Threads: track, untrack, open and close on one thread while no other call runs; put,
 * cancel and newest for a sphere only on its owner's thread, with the owner's slab (its pool
 * of versions); read on any thread at any time in a window. Stamps order as the serial loop
 * hands events out (cascade stamps: nbep_stamp_before); one event puts one version a sphere,
 * and a re-handled event cancels its old one first.
 *
 * Memory: 4 bytes a sphere, 24 a sphere tracked (room for them doubled as outgrown), and
 * `room` versions a slab of `size` bytes and 24 more (nbep_versions_bytes); and a list a slab
 * of the spheres it touched first in a window (4 bytes each; the window's close resets only
 * those, so its cost is the window's work, not the tracked spheres'). A slab's pool is fixed
 * for the window: a put past it is refused (the caller ends its window there). The tracked set
 * changes only between windows, one sphere at a time (a sphere's list centre, and so whether
 * it lies near a side, changes only at its list's expiry). */
#ifndef NBEP_VERSIONS_H
#define NBEP_VERSIONS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/cascade.h"
#include "nbep/compiler.h"
#include "nbep/status.h"

/* The stamp of an event (of the one that wrote a version, sent a message, or a slab's log
 * records): a cascade stamp (cascade.h), which orders events as the cells engine's serial loop
 * hands them out, ties in time included. One event's stamp on each of its spheres' versions is
 * the same. */
typedef nbep_cascade nbep_stamp;

/* The stamp of item's entry (t, key) that no event at time t made: a root (cascade.h). */
static inline nbep_stamp nbep_stamp_at(double t, uint64_t key, uint32_t item)
{
    return nbep_cascade_root(t, key, item);
}

static inline bool nbep_stamp_before(nbep_stamp a, nbep_stamp b)
{
    return nbep_cascade_cmp(&a, &b) < 0;
}

static inline bool nbep_stamp_same(nbep_stamp a, nbep_stamp b)
{
    return nbep_cascade_cmp(&a, &b) == 0;
}

typedef struct nbep_versions nbep_versions;

/* The most slabs: a note keeps a bit a slab. */
#define NBEP_VERSIONS_SLABS_MAX 64

/* Versions of `size` bytes (1 to 4096) for spheres 0..n-1 (n below 2^31), `room` (at least 1,
 * at most 2^31 / slabs) a slab for each of `slabs` (1 to NBEP_VERSIONS_SLABS_MAX); no window
 * open. NBEP_EDECK with a message for a count out of range, NBEP_ENOMEM with one without
 * memory (nothing left allocated). */
NBEP_MUST_CHECK nbep_status nbep_versions_create(size_t n, size_t size, int slabs, size_t room,
                                                 nbep_versions **out, nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_versions_destroy(nbep_versions **v);
/* The bytes create allocates, and `tracked` spheres' slots add (their room once grown to hold
 * them), beside the lists of spheres touched (a slab's grows with its window's work). */
size_t nbep_versions_bytes(size_t n, size_t size, int slabs, size_t room, size_t tracked);

/* Between windows (none open): tracks sphere i (below n) from the next window on, or stops.
 * track: false when no memory could be had for its slot (then nothing changed). */
NBEP_MUST_CHECK bool nbep_versions_track(nbep_versions *v, uint32_t i);
void nbep_versions_untrack(nbep_versions *v, uint32_t i);
/* Whether sphere i is tracked; the spheres tracked. */
bool nbep_versions_tracked(const nbep_versions *v, uint32_t i);
size_t nbep_versions_count(const nbep_versions *v);

/* Opens a window: no versions, no notes. A window must not be open. */
void nbep_versions_open(nbep_versions *v);
/* Closes it: every version and note forgotten. O(the spheres put or read in it). */
void nbep_versions_close(nbep_versions *v);

/* The owner of tracked sphere i (on slab's thread) puts its state `data` (size bytes) as
 * written at stamp s. False when slab's pool is full: then nothing changed. *roll: the slabs
 * (a bit each) to roll back to s, because they read i at or after s's time (0: none). */
NBEP_MUST_CHECK bool nbep_versions_put(nbep_versions *v, int slab, uint32_t i, nbep_stamp s,
                                       const void *data, uint64_t *roll);
/* The owner of tracked sphere i cancels its live version stamped s (the event that wrote it
 * rolled back). False when i has none: then nothing changed. *roll as for put. */
bool nbep_versions_cancel(nbep_versions *v, uint32_t i, nbep_stamp s, uint64_t *roll);
/* The owner's view of tracked sphere i: its newest live version's state, or NULL when it has
 * none (the caller's arrays hold it). Valid until the window closes. */
const void *nbep_versions_newest(const nbep_versions *v, uint32_t i);

/* Slab `reader`'s event at stamp `at` reads tracked sphere i: copies into out the state of its
 * latest live version stamped before `at`, and its stamp into *found (either may be NULL);
 * false when there is none (the state is the window's start, in the caller's arrays). Leaves
 * the note first. Any thread, at any time in the window. */
bool nbep_versions_read(nbep_versions *v, int reader, uint32_t i, nbep_stamp at, void *out,
                        nbep_stamp *found);

#endif
