/* The event calendar of the cells engine (evloop.c): an indexed binary min-heap holding at most
 * one entry per item (a sphere), ordered by (time, key, item). The key is the caller's tie
 * breaker (the pair key of an event, the same whoever computes it), so the order of equal
 * times never depends on the order of operations or on the thread count. Setting, moving and
 * removing an item's entry cost O(log n); the earliest entry is read in O(1). Not thread-safe:
 * one thread owns a calendar. */
#ifndef NBEP_CALENDAR_H
#define NBEP_CALENDAR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

typedef struct nbep_calendar nbep_calendar;

/* An empty calendar for items 0..n-1 (n < UINT32_MAX). NBEP_ENOMEM with a message. */
NBEP_MUST_CHECK nbep_status nbep_calendar_create(size_t n, nbep_calendar **out, nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_calendar_destroy(nbep_calendar **c);

/* Gives item its entry (time, key), inserting it or moving an existing one. time is not NaN. */
void nbep_calendar_set(nbep_calendar *c, uint32_t item, double time, uint64_t key);
/* Removes item's entry, if it has one. */
void nbep_calendar_remove(nbep_calendar *c, uint32_t item);
/* Removes every entry. O(entries). */
void nbep_calendar_clear(nbep_calendar *c);
/* The earliest entry: false when empty, else its item and time. */
bool nbep_calendar_top(const nbep_calendar *c, uint32_t *item, double *time);
/* Entries held. */
size_t nbep_calendar_size(const nbep_calendar *c);
/* True when item has an entry; its time in *time (may be NULL). */
bool nbep_calendar_has(const nbep_calendar *c, uint32_t item, double *time);

/* Invariant check for tests: the heap order holds and every item's position is consistent.
 * Returns the number of violations. */
size_t nbep_calendar_check(const nbep_calendar *c);

/* Bytes a calendar for n items takes. */
size_t nbep_calendar_bytes(size_t n);

#endif
