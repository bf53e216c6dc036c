/* Indexed binary min-heap (see calendar.h). Entries live in the heap array itself, so a
 * comparison touches one cache line per side; where[item] is the item's slot in the heap.
 *
 * Why a heap and not EDMD's or DynamO's calendar (a sorted block for the near future plus
 * unsorted lists for later blocks): the engine keeps one entry per sphere, whose times spread
 * over less than a step ahead of the current event, so the heap is shallow (log2 n ~ 15 at
 * n = 32000) and every operation is a handful of predictable compares; the bucket scheme's
 * O(1) pays off once re-predictions are cheaper than a heap walk, which they are not yet here
 * (a re-prediction tests some 30 partners). The interface hides the structure, so a bucket
 * queue can replace it without touching the engine. */
#include "nbep/calendar.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

#define NOWHERE UINT32_MAX

typedef struct entry {
    double time;
    uint64_t key;
    uint32_t item;
} entry;

struct nbep_calendar {
    size_t n;         /* items */
    size_t size;      /* entries held */
    entry *heap;      /* owned, n */
    uint32_t *where;  /* owned, n: heap index of an item's entry, or NOWHERE */
};

nbep_status nbep_calendar_create(size_t n, nbep_calendar **out, nbep_diag *d)
{
    nbep_calendar *c = calloc(1, sizeof *c);
    if (c && n < UINT32_MAX) {
        c->n = n;
        c->heap = nbep_alloc_aligned(n ? n : 1, sizeof *c->heap);
        c->where = nbep_alloc_aligned(n ? n : 1, sizeof *c->where);
    }
    if (!c || !c->heap || !c->where) {
        nbep_calendar_destroy(&c);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for an event calendar of %zu items", n);
    }
    for (size_t i = 0; i < n; i++)
        c->where[i] = NOWHERE;
    *out = c;
    return NBEP_OK;
}

void nbep_calendar_destroy(nbep_calendar **c)
{
    if (!c || !*c)
        return;
    nbep_free_aligned((*c)->heap);
    nbep_free_aligned((*c)->where);
    free(*c);
    *c = NULL;
}

size_t nbep_calendar_bytes(size_t n)
{
    return sizeof(nbep_calendar) + n * (sizeof(entry) + sizeof(uint32_t));
}

/* The strict order: time, then key, then item (items are unique, so no two entries tie). */
static bool before(const entry *a, const entry *b)
{
    if (a->time != b->time)
        return a->time < b->time;
    if (a->key != b->key)
        return a->key < b->key;
    return a->item < b->item;
}

static void place(nbep_calendar *c, size_t k, entry e)
{
    c->heap[k] = e;
    c->where[e.item] = (uint32_t)k;
}

static void sift_up(nbep_calendar *c, size_t k, entry e)
{
    while (k > 0) {
        size_t parent = (k - 1) / 2;
        if (!before(&e, &c->heap[parent]))
            break;
        place(c, k, c->heap[parent]);
        k = parent;
    }
    place(c, k, e);
}

static void sift_down(nbep_calendar *c, size_t k, entry e)
{
    for (;;) {
        size_t child = 2 * k + 1;
        if (child >= c->size)
            break;
        if (child + 1 < c->size && before(&c->heap[child + 1], &c->heap[child]))
            child++;
        if (!before(&c->heap[child], &e))
            break;
        place(c, k, c->heap[child]);
        k = child;
    }
    place(c, k, e);
}

void nbep_calendar_set(nbep_calendar *c, uint32_t item, double time, uint64_t key)
{
    assert(item < c->n && !isnan(time));
    entry e = {time, key, item};
    uint32_t k = c->where[item];
    if (k == NOWHERE) {
        sift_up(c, c->size++, e);
        return;
    }
    if (before(&e, &c->heap[k]))
        sift_up(c, k, e);
    else
        sift_down(c, k, e);
}

void nbep_calendar_remove(nbep_calendar *c, uint32_t item)
{
    assert(item < c->n);
    uint32_t k = c->where[item];
    if (k == NOWHERE)
        return;
    c->where[item] = NOWHERE;
    entry last = c->heap[--c->size];
    if (k == c->size)
        return; /* it was the last entry */
    /* the last entry fills the hole and moves whichever way the order asks */
    if (k > 0 && before(&last, &c->heap[(k - 1) / 2]))
        sift_up(c, k, last);
    else
        sift_down(c, k, last);
}

void nbep_calendar_clear(nbep_calendar *c)
{
    for (size_t k = 0; k < c->size; k++)
        c->where[c->heap[k].item] = NOWHERE;
    c->size = 0;
}

bool nbep_calendar_top(const nbep_calendar *c, uint32_t *item, double *time)
{
    if (c->size == 0)
        return false;
    *item = c->heap[0].item;
    *time = c->heap[0].time;
    return true;
}

size_t nbep_calendar_size(const nbep_calendar *c)
{
    return c->size;
}

bool nbep_calendar_has(const nbep_calendar *c, uint32_t item, double *time)
{
    if (item >= c->n || c->where[item] == NOWHERE)
        return false;
    if (time)
        *time = c->heap[c->where[item]].time;
    return true;
}

size_t nbep_calendar_check(const nbep_calendar *c)
{
    size_t bad = 0, held = 0;
    for (size_t k = 0; k < c->size; k++) {
        const entry *e = &c->heap[k];
        if (e->item >= c->n || c->where[e->item] != k)
            bad++;
        if (k > 0 && before(e, &c->heap[(k - 1) / 2]))
            bad++;
    }
    for (size_t i = 0; i < c->n; i++)
        held += c->where[i] != NOWHERE;
    return bad + (held != c->size);
}
