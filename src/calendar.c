/* Event calendar (see calendar.h): a calendar queue after Brown (1988) and the scheduler of
 * Smallenburg's EDMD, with an indexed binary min-heap for the bucket being drained.
 *
 * Time is cut into buckets of width w from an origin t0; an entry's bucket number is
 * ab = floor((time - t0) / w), which never decreases as time grows, so an entry in an earlier
 * bucket always comes before one in a later bucket. Entries live in one of three places:
 *   heap      every entry with ab <= cur (the bucket being drained), ordered exactly;
 *   ring      entries with cur < ab <= cur + nb, unsorted, in doubly linked lists, one per
 *             ring slot ab mod nb (nb consecutive bucket numbers map to distinct slots);
 *   overflow  entries further ahead (and +inf), one unsorted list.
 * The earliest entry is the heap's top; when the heap empties, cur advances and the next
 * slot's list moves into the heap. Every nb buckets (a lap) the overflow entries that now fall
 * within the ring move into it; no entry can be passed over (each overflow entry is further
 * than the next lap boundary when it is filed). Moving an entry to a later bucket, the common
 * case (a sphere's next event), costs an O(log h) heap removal (h: entries in the current
 * bucket, a handful) and an O(1) list insertion, whatever n is.
 *
 * The width is set by nbep_calendar_retune from the entries' distances ahead of now (the
 * nearer seven eighths of them), so that a bucket holds about BUCKET_ENTRIES entries; a lap
 * that finds the buckets far too full or far too empty retunes on its own. The width only
 * decides where entries wait: the order they come out in is (time, key, item) exactly,
 * whatever the width. */
#include "nbep/calendar.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

#define NIL UINT32_MAX
/* The entries a bucket should hold on average: a small heap to drain, few empty buckets. */
#define BUCKET_ENTRIES 4.0
/* A lap retunes when its non-empty buckets held more than this many times BUCKET_ENTRIES on
 * average, or when fewer than one bucket in EMPTY_LIMIT held anything. */
#define CROWDED_FACTOR 16.0
#define EMPTY_LIMIT 64
/* A retune reads the distances ahead of now of at most this many entries, spread evenly over
 * those held, and leaves out the farthest RETUNE_TRIM of them. */
#define RETUNE_SAMPLE 1024
#define RETUNE_TRIM 0.125

enum { WHERE_NONE = 0, WHERE_HEAP, WHERE_RING, WHERE_OVERFLOW };

typedef struct node {
    double time;
    uint64_t key;
    /* ring and overflow lists: the next item (NIL at the end), and the link that leads here:
     * the item before, or n + s for the head of list s (ring slot s, or nb: the overflow) */
    uint32_t next, prev;
    uint32_t loc;        /* heap index (WHERE_HEAP) or ring slot (WHERE_RING) */
    uint32_t where;
} node;

struct nbep_calendar {
    size_t n;            /* items */
    size_t size;         /* entries held */
    node *node;          /* owned, n */
    uint32_t *heap;      /* owned, n: items of the buckets up to cur, a min-heap */
    size_t heap_len;
    uint32_t *head;      /* owned, nb + 1: first item of each ring slot's list, then of the
                          * overflow list (head[nb], OVERFLOW) */
    size_t nb;           /* ring slots, a power of two */
    size_t ring_len;     /* entries in the ring */
    uint32_t sink;       /* where a link to NIL is written (list_push, list_unlink) */
    int64_t cur;         /* bucket being drained */
    int64_t ovf_min;     /* no overflow entry's bucket is below this */
    double t0, w, inv_w; /* bucket origin, width and 1 / width */
    /* this lap so far: buckets advanced, of which non-empty, and entries they brought */
    size_t lap_steps, lap_full, lap_moved;
    /* look_ahead's walk of the next bucket's list: the item reached, and the bucket */
    uint32_t ahead;
    int64_t ahead_ab;
    /* the heap holds only entries of the last bucket (INT64_MAX: +inf, or 2^62 buckets ahead
     * and more), brought in from the overflow with cur left where it was (advance): a later
     * entry of any other bucket is earlier than them all, and sends them back (file) */
    bool parked;
    /* ties in (time, key) broken by tie[item] rather than item (nbep_calendar_set_tie), or NULL */
    const uint32_t *tie;
};

nbep_status nbep_calendar_create(size_t n, nbep_calendar **out, nbep_diag *d)
{
    if (n > NBEP_CALENDAR_MAX)
        NBEP_FAIL(d, NBEP_EDECK,
                  "nbep: an event calendar holds at most %zu items (its links are 32-bit), not "
                  "%zu",
                  NBEP_CALENDAR_MAX, n);
    nbep_calendar *c = calloc(1, sizeof *c);
    if (c) { /* (room for the links n + s, s <= nb < 2 n + 16: NBEP_CALENDAR_MAX) */
        c->n = n;
        c->nb = 16;
        while (c->nb < n)
            c->nb *= 2;
        c->node = nbep_alloc_aligned(n ? n : 1, sizeof *c->node);
        c->heap = nbep_alloc_aligned(n ? n : 1, sizeof *c->heap);
        c->head = nbep_alloc_aligned(c->nb + 1, sizeof *c->head);
    }
    if (!c || !c->node || !c->heap || !c->head) {
        nbep_calendar_destroy(&c);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for an event calendar of %zu items", n);
    }
    for (size_t i = 0; i < n; i++)
        c->node[i].where = WHERE_NONE;
    for (size_t s = 0; s <= c->nb; s++)
        c->head[s] = NIL;
    c->w = c->inv_w = 1.0;
    c->ovf_min = INT64_MAX;
    c->ahead = NIL;
    c->ahead_ab = -1;
    *out = c;
    return NBEP_OK;
}

void nbep_calendar_destroy(nbep_calendar **c)
{
    if (!c || !*c)
        return;
    nbep_free_aligned((*c)->node);
    nbep_free_aligned((*c)->heap);
    nbep_free_aligned((*c)->head);
    free(*c);
    *c = NULL;
}

size_t nbep_calendar_bytes(size_t n)
{
    size_t nb = 16;
    while (nb < n)
        nb *= 2;
    return sizeof(nbep_calendar) + n * (sizeof(node) + sizeof(uint32_t)) +
           (nb + 1) * sizeof(uint32_t);
}

/* ---- the strict order and the heap of the current bucket ---------------------------------- */

/* The strict order: time, then key, then item, or the item's tie number where the caller gave
 * them (items and tie numbers are unique, so no two entries tie). */
static inline bool before(const nbep_calendar *c, uint32_t a, uint32_t b)
{
    const node *x = &c->node[a], *y = &c->node[b];
    if (x->time != y->time)
        return x->time < y->time;
    if (x->key != y->key)
        return x->key < y->key;
    return c->tie ? c->tie[a] < c->tie[b] : a < b;
}

static inline void heap_place(nbep_calendar *c, size_t k, uint32_t item)
{
    c->heap[k] = item;
    c->node[item].loc = (uint32_t)k;
}

static void sift_up(nbep_calendar *c, size_t k, uint32_t item)
{
    while (k > 0) {
        size_t parent = (k - 1) / 2;
        if (!before(c, item, c->heap[parent]))
            break;
        heap_place(c, k, c->heap[parent]);
        k = parent;
    }
    heap_place(c, k, item);
}

static void sift_down(nbep_calendar *c, size_t k, uint32_t item)
{
    for (;;) {
        size_t child = 2 * k + 1;
        if (child >= c->heap_len)
            break;
        if (child + 1 < c->heap_len && before(c, c->heap[child + 1], c->heap[child]))
            child++;
        if (!before(c, c->heap[child], item))
            break;
        heap_place(c, k, c->heap[child]);
        k = child;
    }
    heap_place(c, k, item);
}

static void heap_push(nbep_calendar *c, uint32_t item)
{
    c->node[item].where = WHERE_HEAP;
    sift_up(c, c->heap_len++, item);
}

static void heap_delete(nbep_calendar *c, uint32_t item)
{
    size_t k = c->node[item].loc;
    uint32_t last = c->heap[--c->heap_len];
    if (k == c->heap_len)
        return; /* it was the last entry */
    /* the last entry fills the hole and moves whichever way the order asks */
    if (k > 0 && before(c, last, c->heap[(k - 1) / 2]))
        sift_up(c, k, last);
    else
        sift_down(c, k, last);
}

/* ---- the ring and the overflow ------------------------------------------------------------- */

/* The bucket number of a time; +inf and anything beyond 2^62 buckets ahead: INT64_MAX. */
static inline int64_t bucket_of(const nbep_calendar *c, double time)
{
    double q = floor((time - c->t0) * c->inv_w);
    if (!(q < 0x1p62))
        return INT64_MAX;
    return q < -0x1p62 ? -INT64_MAX : (int64_t)q;
}

/* Whether bucket ab waits in the ring (after the current one, at most nb ahead), and its list
 * there. */
static inline bool in_ring(const nbep_calendar *c, int64_t ab)
{
    return ab > c->cur && ab - c->cur <= (int64_t)c->nb;
}
static inline uint32_t ring_loc(const nbep_calendar *c, int64_t ab)
{
    return (uint32_t)((uint64_t)ab & (c->nb - 1));
}

/* The overflow list's head, after the ring slots'. */
#define OVERFLOW(c) ((c)->head[(c)->nb])

/* The link that list_push and list_unlink write: the next field of the item before (prev
 * below n), or the head it leads from (n + s); the back link of the item after, or the sink
 * when there is none. Chosen by selects, not branches: whether an item heads its list, or
 * ends it, is a coin toss in a calendar's lists (cachegrind's branch model: five
 * mispredicted branches a collision in unfile at phi = 0.50). */
static inline uint32_t *link_to(nbep_calendar *c, uint32_t prev)
{
    return prev < c->n ? &c->node[prev].next : &c->head[prev - c->n];
}
static inline uint32_t *link_back(nbep_calendar *c, uint32_t next)
{
    return next != NIL ? &c->node[next].prev : &c->sink;
}

/* Item to the front of list s (a ring slot, or nb: the overflow). */
static void list_push(nbep_calendar *c, size_t s, uint32_t item)
{
    node *x = &c->node[item];
    x->prev = (uint32_t)(c->n + s);
    x->next = c->head[s];
    *link_back(c, x->next) = item;
    c->head[s] = item;
}

static void list_unlink(nbep_calendar *c, uint32_t item)
{
    const node *x = &c->node[item];
    *link_to(c, x->prev) = x->next;
    *link_back(c, x->next) = x->prev;
}

/* Files an entry (its node's time and key set) where its bucket says. */
static void file(nbep_calendar *c, uint32_t item)
{
    node *x = &c->node[item];
    int64_t ab = bucket_of(c, x->time);
    if (c->parked && ab < INT64_MAX) { /* the last bucket's entries go back to the overflow */
        for (size_t k = 0; k < c->heap_len; k++) {
            c->node[c->heap[k]].where = WHERE_OVERFLOW;
            list_push(c, c->nb, c->heap[k]);
        }
        c->heap_len = 0;
        c->parked = false;
    }
    if (ab <= c->cur || c->parked) {
        heap_push(c, item);
    } else if (in_ring(c, ab)) {
        x->where = WHERE_RING;
        x->loc = ring_loc(c, ab);
        list_push(c, x->loc, item);
        c->ring_len++;
    } else {
        x->where = WHERE_OVERFLOW;
        list_push(c, c->nb, item);
        if (ab < c->ovf_min)
            c->ovf_min = ab;
    }
}

/* Takes an entry out of wherever it is. */
static void unfile(nbep_calendar *c, uint32_t item)
{
    node *x = &c->node[item];
    if (x->where == WHERE_HEAP) {
        heap_delete(c, item);
    } else {
        list_unlink(c, item);
        c->ring_len -= x->where == WHERE_RING;
    }
    x->where = WHERE_NONE;
}

/* Re-files the overflow entries, which brings those now within the ring into it. */
static void redistribute(nbep_calendar *c)
{
    uint32_t item = OVERFLOW(c);
    OVERFLOW(c) = NIL;
    c->ovf_min = INT64_MAX;
    while (item != NIL) {
        uint32_t next = c->node[item].next;
        file(c, item);
        item = next;
    }
}

/* Re-files every entry with the origin at t_now and the width w (> 0). */
static void refile_all(nbep_calendar *c, double t_now, double w)
{
    /* gather every entry into one list, the overflow (the heap's items first) */
    for (size_t k = 0; k < c->heap_len; k++)
        list_push(c, c->nb, c->heap[k]);
    for (size_t s = 0; s < c->nb && c->ring_len > 0; s++) {
        uint32_t item = c->head[s];
        c->head[s] = NIL;
        while (item != NIL) {
            uint32_t next = c->node[item].next;
            list_push(c, c->nb, item);
            c->ring_len--;
            item = next;
        }
    }
    c->heap_len = 0;
    c->parked = false;
    c->t0 = t_now;
    c->w = w;
    c->inv_w = 1.0 / w;
    c->cur = 0;
    c->lap_steps = c->lap_full = c->lap_moved = 0;
    redistribute(c);
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Whether x holds an entry at a finite time after t_now (what a retune sizes buckets for). */
static bool held_ahead(const node *x, double t_now)
{
    return x->where != WHERE_NONE && x->time > t_now && x->time < INFINITY;
}

void nbep_calendar_retune(nbep_calendar *c, double t_now)
{
    size_t ahead = 0;
    for (size_t i = 0; i < c->n; i++)
        ahead += held_ahead(&c->node[i], t_now);
    /* The width that puts BUCKET_ENTRIES entries in a bucket where they are spread evenly over
     * twice their mean distance ahead, taken over the nearer seven eighths of them (of a
     * sample): the next buckets hold the nearer entries. Until 2026-11-30 it was taken over
     * all of them, and one entry far ahead pulled the mean with it (a sphere 1e-12 as fast as
     * the others among 20000 made the width 5999 for 4.9e-5, the calendar one heap of all,
     * 3.2 times the time an operation in a review's model of a loop); a fluid's widths moved
     * by 0.73 and 1.1 times (phi = 0.50, 0.30) with no change of speed. */
    double d[RETUNE_SAMPLE];
    size_t m = 0;
    const size_t stride = ahead / RETUNE_SAMPLE + 1;
    for (size_t i = 0, k = 0; i < c->n && m < RETUNE_SAMPLE; i++)
        if (held_ahead(&c->node[i], t_now) && k++ % stride == 0)
            d[m++] = c->node[i].time - t_now;
    double w = 0.0;
    if (m > 0) {
        qsort(d, m, sizeof *d, cmp_double);
        const size_t k = m - (size_t)(RETUNE_TRIM * (double)m); /* at least one */
        double sum = 0.0;
        for (size_t j = 0; j < k; j++)
            sum += d[j];
        /* the nearer entries, a fraction k / m of those ahead, spread over twice their mean */
        w = 2.0 * (sum / (double)k) * BUCKET_ENTRIES / ((double)k / (double)m * (double)ahead);
    }
    /* finite, positive and not subnormal, or unchanged */
    if (!(w > 1e-300 && w < 1e300 && 1.0 / w < 1e300))
        w = c->w;
    refile_all(c, t_now, w);
}

/* The heap is empty and entries are held: brings the next non-empty bucket into the heap. */
static void advance(nbep_calendar *c)
{
    while (c->heap_len == 0) {
        if (c->ring_len == 0) {
            /* everything waits in the overflow: jump to its earliest bucket, which re-filing
             * brings into the heap (the lap rule holds from any bucket: what stays in the
             * overflow is further than the next lap boundary) */
            int64_t m = INT64_MAX;
            for (uint32_t item = OVERFLOW(c); item != NIL; item = c->node[item].next) {
                int64_t ab = bucket_of(c, c->node[item].time);
                m = ab < m ? ab : m;
            }
            if (m == INT64_MAX) { /* only the last bucket's: they come out in order from the heap */
                uint32_t item = OVERFLOW(c);
                OVERFLOW(c) = NIL;
                while (item != NIL) {
                    uint32_t next = c->node[item].next;
                    heap_push(c, item);
                    item = next;
                }
                c->parked = true;
                return;
            }
            c->cur = m;
            redistribute(c);
            continue;
        }
        c->cur++;
        const uint32_t slot = (uint32_t)((uint64_t)c->cur & (c->nb - 1));
        uint32_t item = c->head[slot];
        c->head[slot] = NIL;
        c->lap_steps++;
        c->lap_full += item != NIL;
        while (item != NIL) {
            uint32_t next = c->node[item].next;
            c->ring_len--;
            c->lap_moved++;
            heap_push(c, item);
            item = next;
        }
        if ((c->cur & (int64_t)(c->nb - 1)) == 0) { /* a lap: the overflow's turn */
            if (c->ovf_min <= c->cur + (int64_t)c->nb)
                redistribute(c);
            /* far too full or far too empty buckets: a new width from where things are now */
            if (c->lap_full > 0 &&
                ((double)c->lap_moved > CROWDED_FACTOR * BUCKET_ENTRIES * (double)c->lap_full ||
                 c->lap_full * EMPTY_LIMIT < c->lap_steps))
                nbep_calendar_retune(c, c->t0 + (double)c->cur * c->w);
            c->lap_steps = c->lap_full = c->lap_moved = 0;
        }
    }
}

/* ---- the interface ------------------------------------------------------------------------- */

void nbep_calendar_set(nbep_calendar *c, uint32_t item, double time, uint64_t key)
{
    assert(item < c->n && !isnan(time));
    node *x = &c->node[item];
    if (x->where != WHERE_NONE)
        unfile(c, item);
    else
        c->size++;
    x->time = time;
    x->key = key;
    file(c, item);
}

void nbep_calendar_remove(nbep_calendar *c, uint32_t item)
{
    assert(item < c->n);
    if (c->node[item].where == WHERE_NONE)
        return;
    unfile(c, item);
    c->size--;
}

void nbep_calendar_clear(nbep_calendar *c)
{
    for (size_t i = 0; i < c->n; i++)
        c->node[i].where = WHERE_NONE;
    for (size_t s = 0; s <= c->nb; s++)
        c->head[s] = NIL;
    c->ovf_min = INT64_MAX;
    c->heap_len = c->ring_len = c->size = 0;
    c->parked = false;
}

/* One step of a walk down the next bucket's list, requesting each node a step before it is
 * read (no effect on the order): draining a bucket into the heap follows its list node by
 * node, each a miss that waits for the one before (a tenth of a dense fluid's time, with the
 * list's nodes scattered over n); walked a node per call, the list is in cache when its turn
 * comes. The list may change between steps: the walk then strays down another list, or stops,
 * and only its requests are wasted (every item it reaches is a valid index). */
static void look_ahead(nbep_calendar *c)
{
    if (c->ahead_ab != c->cur + 1) {
        c->ahead_ab = c->cur + 1;
        c->ahead = c->head[(uint64_t)c->ahead_ab & (c->nb - 1)];
    } else if (c->ahead != NIL) {
        c->ahead = c->node[c->ahead].next;
    }
    if (c->ahead != NIL)
        NBEP_PREFETCH(&c->node[c->ahead]);
}

bool nbep_calendar_top(nbep_calendar *c, uint32_t *item, double *time)
{
    if (c->size == 0)
        return false;
    if (c->heap_len == 0)
        advance(c);
    look_ahead(c);
    *item = c->heap[0];
    *time = c->node[*item].time;
    return true;
}

bool nbep_calendar_first(nbep_calendar *c, nbep_calendar_entry *entry)
{
    if (!nbep_calendar_top(c, &entry->item, &entry->time))
        return false;
    entry->key = c->node[entry->item].key;
    return true;
}

void nbep_calendar_prefetch(const nbep_calendar *c, uint32_t item)
{
    NBEP_PREFETCH(&c->node[item]);
}

void nbep_calendar_prefetch_set(const nbep_calendar *c, double time, bool deep)
{
    const int64_t ab = bucket_of(c, time);
    if (!in_ring(c, ab)) /* the heap's or the overflow's */
        return;
    const uint32_t *head = &c->head[ring_loc(c, ab)];
    if (!deep)
        NBEP_PREFETCH_W(head);
    else if (*head != NIL)
        NBEP_PREFETCH_W(&c->node[*head]);
}

void nbep_calendar_runners_up(const nbep_calendar *c, uint32_t items[2], uint64_t *keys,
                              int *n)
{
    *n = 0;
    for (size_t k = 1; k < 3 && k < c->heap_len; k++) {
        if (keys)
            keys[*n] = c->node[c->heap[k]].key;
        items[(*n)++] = c->heap[k];
    }
}

size_t nbep_calendar_size(const nbep_calendar *c)
{
    return c->size;
}

double nbep_calendar_width(const nbep_calendar *c)
{
    return c->w;
}

void nbep_calendar_set_tie(nbep_calendar *c, const uint32_t *tie)
{
    assert(c->size == 0);
    c->tie = tie;
}

bool nbep_calendar_get(const nbep_calendar *c, uint32_t item, nbep_calendar_entry *entry)
{
    if (item >= c->n || c->node[item].where == WHERE_NONE)
        return false;
    *entry = (nbep_calendar_entry){c->node[item].time, c->node[item].key, item};
    return true;
}

bool nbep_calendar_has(const nbep_calendar *c, uint32_t item, double *time)
{
    if (item >= c->n || c->node[item].where == WHERE_NONE)
        return false;
    if (time)
        *time = c->node[item].time;
    return true;
}

size_t nbep_calendar_check(const nbep_calendar *c)
{
    size_t bad = 0, held = 0, in_heap = 0, in_ring = 0;
    for (size_t k = 0; k < c->heap_len; k++) {
        const uint32_t item = c->heap[k], parent = k > 0 ? c->heap[(k - 1) / 2] : NIL;
        if (item >= c->n || c->node[item].where != WHERE_HEAP || c->node[item].loc != k)
            bad++;
        else if (parent < c->n && before(c, item, parent)) /* (a bad parent: at its slot) */
            bad++;
        else if (!c->parked && bucket_of(c, c->node[item].time) > c->cur)
            bad++; /* a later bucket's entry in the heap (parked: only the last bucket's) */
        else if (c->parked && bucket_of(c, c->node[item].time) != INT64_MAX)
            bad++;
    }
    for (size_t s = 0; s < c->nb; s++)
        for (uint32_t item = c->head[s], prev = (uint32_t)(c->n + s); item != NIL;
             prev = item, item = c->node[item].next) {
            const node *x = &c->node[item];
            int64_t ab = bucket_of(c, x->time);
            in_ring++;
            if (x->where != WHERE_RING || x->loc != s || x->prev != prev || ab <= c->cur ||
                ab - c->cur > (int64_t)c->nb || (uint64_t)ab % c->nb != s)
                bad++;
            if (in_ring > c->n)
                return bad + 1; /* a cycle */
        }
    size_t in_ovf = 0;
    for (uint32_t item = OVERFLOW(c), prev = (uint32_t)(c->n + c->nb); item != NIL;
         prev = item, item = c->node[item].next) {
        const node *x = &c->node[item];
        in_ovf++;
        if (x->where != WHERE_OVERFLOW || x->prev != prev || bucket_of(c, x->time) < c->ovf_min)
            bad++;
        if (in_ovf > c->n)
            return bad + 1;
    }
    for (size_t i = 0; i < c->n; i++) {
        held += c->node[i].where != WHERE_NONE;
        in_heap += c->node[i].where == WHERE_HEAP;
    }
    return bad + (held != c->size) + (in_heap != c->heap_len) + (in_ring != c->ring_len) +
           (in_heap + in_ring + in_ovf != c->size);
}
