/* The event calendar of the cells engine (evloop.c): at most one entry per item (a sphere),
 * ordered by (time, key, item). The key is the caller's tie breaker (the pair key of an event,
 * the same whoever computes it), so the order of equal times never depends on the order of
 * operations or on the thread count. A calendar queue (buckets of time, the current one a small
 * heap; calendar.c): moving an entry later or removing it costs O(1) plus a heap operation over
 * the current bucket's few entries, independent of n; reading the earliest entry is O(1)
 * amortised. Not thread-safe: one thread owns a calendar. */
#ifndef NBEP_CALENDAR_H
#define NBEP_CALENDAR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

typedef struct nbep_calendar nbep_calendar;

/* An entry of the calendar, as its order sees it. */
typedef struct nbep_calendar_entry {
    double time;
    uint64_t key;
    uint32_t item;
} nbep_calendar_entry;

/* Whether entry a comes out before entry b: the calendar's order (time, then key, then item),
 * for callers that keep a copy of part of it in order (a calendar with tie numbers,
 * nbep_calendar_set_tie, compares those in place of the items). */
static inline bool nbep_calendar_before(nbep_calendar_entry a, nbep_calendar_entry b)
{
    if (a.time != b.time)
        return a.time < b.time;
    if (a.key != b.key)
        return a.key < b.key;
    return a.item < b.item;
}

/* The most items a calendar holds: its lists link items and buckets (n + bucket, with up to
 * 2 n + 16 buckets) by 32-bit numbers, below a reserved one. The cells mode's limit on
 * spheres (the deck check says so). */
#define NBEP_CALENDAR_MAX ((size_t)(UINT32_MAX / 4 - 1))

/* An empty calendar for items 0..n-1: NBEP_EDECK with a message when n > NBEP_CALENDAR_MAX
 * (before allocating anything), NBEP_ENOMEM with a message without memory. */
NBEP_MUST_CHECK nbep_status nbep_calendar_create(size_t n, nbep_calendar **out, nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_calendar_destroy(nbep_calendar **c);

/* Gives item its entry (time, key), inserting it or moving an existing one. time is not NaN. */
void nbep_calendar_set(nbep_calendar *c, uint32_t item, double time, uint64_t key);
/* Removes item's entry, if it has one. */
void nbep_calendar_remove(nbep_calendar *c, uint32_t item);
/* Removes every entry. O(entries). */
void nbep_calendar_clear(nbep_calendar *c);
/* The earliest entry: false when empty, else its item and time. (It may move entries between
 * the calendar's internal buckets, hence not const.) */
bool nbep_calendar_top(nbep_calendar *c, uint32_t *item, double *time);
/* nbep_calendar_top, the whole entry (its key too). */
bool nbep_calendar_first(nbep_calendar *c, nbep_calendar_entry *entry);
/* Sizes the buckets to the entries held, as seen from time t_now (the earliest time that can
 * still come out): a speed setting only, the order entries come out in does not change. Call
 * after filling the calendar; it also retunes itself when its buckets get far too full or far
 * too empty. O(n). */
void nbep_calendar_retune(nbep_calendar *c, double t_now);
/* Up to two items likely to come out after the earliest (the current bucket's runners-up),
 * for a caller that wants to fetch their data ahead; *n of them in items, and their keys in
 * keys unless it is NULL. No effect on the order. */
void nbep_calendar_runners_up(const nbep_calendar *c, uint32_t items[2], uint64_t *keys,
                              int *n);
/* Requests item's entry, to be set or removed soon (no effect on the order). */
void nbep_calendar_prefetch(const nbep_calendar *c, uint32_t item);
/* Requests what setting an entry at `time` will write (no effect on the order): the bucket
 * list it joins when it waits in the ring; with `deep`, the entry at that list's head, which it
 * links to (read from the list's head: call it deep a while after a call without, when the
 * head is in cache). */
void nbep_calendar_prefetch_set(const nbep_calendar *c, double time, bool deep);
/* Entries held. */
size_t nbep_calendar_size(const nbep_calendar *c);
/* The buckets' width in time (nbep_calendar_retune), for tests and diagnostics. */
double nbep_calendar_width(const nbep_calendar *c);
/* Ties in (time, key) broken by tie[item] instead of item, for a caller whose items are local
 * numbers of a wider numbering (slabcal.c: a slab's spheres, ordered by their global numbers):
 * tie[item] of every item with an entry must stay unchanged while it has it, and distinct from
 * every other's. The array stays the caller's; NULL: by item again. Call while empty. */
void nbep_calendar_set_tie(nbep_calendar *c, const uint32_t *tie);
/* Item's entry in *entry (its item field: item), or false when it has none. */
bool nbep_calendar_get(const nbep_calendar *c, uint32_t item, nbep_calendar_entry *entry);
/* True when item has an entry; its time in *time (may be NULL). */
bool nbep_calendar_has(const nbep_calendar *c, uint32_t item, double *time);

/* Invariant check for tests: the heap order holds and every item's position is consistent.
 * Returns the number of violations. */
size_t nbep_calendar_check(const nbep_calendar *c);

/* Bytes a calendar for n items takes. */
size_t nbep_calendar_bytes(size_t n);

#endif
