/* Per-slab event calendars: step 1 of the optimistic event loop over slabs
 * (docs/optimistic-design.md). The cells' region is cut into `slabs` slabs across x, on cell
 * boundaries, and each slab keeps its spheres' entries in a calendar of its own (calendar.h),
 * as each slab's thread will in the optimistic loop; the entry of a sphere lives in the
 * calendar of the slab its caller names (the engine: the slab of the cell holding the
 * sphere's list centre, which changes only at the sphere's list expiry). Here one thread merges
 * the slabs' earliest entries in the calendar's order (time, key, item), so the entries come
 * out exactly as from one calendar holding them all: a run is the same bit for bit for any
 * number of slabs, and what the merge costs is measured (README, Threads on dense scenes).
 *
 * The merge keeps each slab's earliest entry, read again only from a slab whose calendar
 * changed since (a set or a removal there), and compares the slabs' kept entries: O(slabs) an
 * event beside the calendar's own work. Not thread-safe: one thread owns it.
 *
 * Memory: each slab numbers the items it holds locally (a number taken as an item's entry
 * comes in, given back as it leaves), so its calendar is of its own items, not of all n: room
 * for its even share and a quarter more at first, doubled (at most n) when outgrown. Its
 * calendar breaks ties in (time, key) by the items' own numbers (nbep_calendar_set_tie), not
 * the local ones, which keeps the one calendar's order: a pair's two entries share time and
 * key, and the lower sphere's comes out first. Beside the calendars, 8 bytes an item. */
#ifndef NBEP_SLABCAL_H
#define NBEP_SLABCAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/calendar.h"
#include "nbep/compiler.h"
#include "nbep/status.h"

typedef struct nbep_slabcal nbep_slabcal;

/* The most slabs: a sphere's slab is a byte, and 64 already passes the 16 threads the design
 * aims at. */
#define NBEP_SLABCAL_MAX 64

/* The slab of cell column x of `columns` across x, for `slabs` slabs: slab s holds the columns
 * from s * columns / slabs on (the slabs' widths differ by a column at most; with more slabs
 * than columns some hold none). */
static inline int nbep_slabcal_slab_of(size_t x, size_t columns, int slabs)
{
    return columns ? (int)((x * (size_t)slabs) / columns) : 0;
}

/* Calendars for items 0..n-1 on `slabs` slabs (2 to NBEP_SLABCAL_MAX): NBEP_EDECK with a
 * message for a count out of that range or n past NBEP_CALENDAR_MAX, NBEP_ENOMEM with a
 * message without memory (nothing left allocated). */
NBEP_MUST_CHECK nbep_status nbep_slabcal_create(size_t n, int slabs, nbep_slabcal **out,
                                                nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_slabcal_destroy(nbep_slabcal **s);

/* Gives item its entry (time, key) in slab's calendar, moving it out of another slab's if it
 * was there. time is not NaN. False when slab's room is full and no memory could be had to
 * grow it: then nothing changed. */
NBEP_MUST_CHECK bool nbep_slabcal_set(nbep_slabcal *s, int slab, uint32_t item, double time,
                                      uint64_t key);
/* Removes item's entry, if it has one. */
void nbep_slabcal_remove(nbep_slabcal *s, uint32_t item);
/* Removes every entry. O(entries). */
void nbep_slabcal_clear(nbep_slabcal *s);
/* Sizes each slab's buckets to its entries (nbep_calendar_retune): a speed setting only. */
void nbep_slabcal_retune(nbep_slabcal *s, double t_now);
/* The earliest entry of all slabs, in the calendar's order: false when all are empty. */
bool nbep_slabcal_first(nbep_slabcal *s, nbep_calendar_entry *entry);
/* Slab's own earliest entry (by item, as nbep_slabcal_first gives it), in *entry: false when
 * its calendar is empty. For a slab's own loop (the scheduled loop on slabs: evloop_warp.c);
 * leaves what nbep_slabcal_runners_up reports as it was. */
bool nbep_slabcal_top(nbep_slabcal *s, int slab, nbep_calendar_entry *entry);
/* Up to two items likely to come out after the last nbep_slabcal_first's (the runner-up of its
 * slab's current bucket, nbep_calendar_runners_up, and the next slab's earliest as kept then),
 * for a caller that wants to fetch their data ahead; *n of them. No effect on the order. */
void nbep_slabcal_runners_up(const nbep_slabcal *s, uint32_t items[2], int *n);
/* The same for slab's own calendar alone (up to two of its items likely to come out after its
 * earliest): for a slab's own loop, which reads no other slab's. */
void nbep_slabcal_runners_up_of(const nbep_slabcal *s, int slab, uint32_t items[2], int *n);
/* Requests item's entry, to be set or removed soon (no effect on the order). */
void nbep_slabcal_prefetch(const nbep_slabcal *s, uint32_t item);
/* The slab holding item's entry, or -1 when it has none. */
int nbep_slabcal_slab(const nbep_slabcal *s, uint32_t item);
/* Entries held, all slabs. */
size_t nbep_slabcal_size(const nbep_slabcal *s);
/* Entries held by one slab. */
size_t nbep_slabcal_size_of(const nbep_slabcal *s, int slab);
/* The items slab has room for now (its entries' local numbers). */
size_t nbep_slabcal_room_of(const nbep_slabcal *s, int slab);
/* The slabs. */
int nbep_slabcal_slabs(const nbep_slabcal *s);

/* Invariant check for tests: each item with an entry holds a local number of its slab that
 * names it back and has the entry, every other local number handed out is on the slab's free
 * list with no entry, each calendar's own check passes, and each kept earliest entry is its
 * slab's. Returns the number of violations. */
size_t nbep_slabcal_check(nbep_slabcal *s);

/* Bytes nbep_slabcal_create(n, slabs) allocates (a slab outgrowing its first room later
 * takes more). */
size_t nbep_slabcal_bytes(size_t n, int slabs);

#endif
