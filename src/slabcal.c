/* Per-slab event calendars merged on one thread: see slabcal.h. */
#include <stdalign.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/compiler.h"

#include "nbep/slabcal.h"
#include "nbep/status.h"

/* an item without an entry */
#define SLAB_NONE UINT8_MAX

_Static_assert(NBEP_SLABCAL_MAX < SLAB_NONE, "a slab number fits a byte beside SLAB_NONE");

/* A slab's local numbers: glob[l] is the item holding l, or FREE with the next free local
 * number in its low bits (LOCAL_NIL: none). Items are below NBEP_CALENDAR_MAX < 2^30, so the
 * bit is never an item's. */
#define FREE ((uint32_t)1 << 31)
#define LOCAL_NIL (FREE - 1)

_Static_assert(NBEP_CALENDAR_MAX < FREE, "an item never has the free bit");

/* A slab's own, on cache lines of its own (the scheduled loop's slabs on threads each change
 * their own slab's alone: evloop_warp.c) */
typedef struct one_slab {
    alignas(NBEP_CACHELINE) nbep_calendar *cal; /* owned: entries by local number, ties by glob
                                                 * (the items' order) */
    uint32_t *glob;     /* owned, cap: each local number's item, or FREE | the next free */
    uint32_t cap;       /* local numbers the calendar and glob have room for */
    uint32_t hi;        /* local numbers handed out (below it: held or free) */
    uint32_t free;      /* the first free local number below hi, or LOCAL_NIL */
    /* its earliest entry as last read, by item (kept.item == NONE_ITEM: empty), and whether
     * its calendar changed since (then it is read again) */
    nbep_calendar_entry kept;
    bool stale;
} one_slab;

struct nbep_slabcal {
    int slabs;
    size_t n;
    one_slab sl[NBEP_SLABCAL_MAX];
    /* owned, n: the slab holding each item's entry and its local number there, side by side
     * (one cache line an item where two arrays would take two) */
    struct {
        uint32_t loc;
        uint8_t slab;
    } *at;
    int best, second; /* the last first's slab, and the slab of the next kept entry (-1) */
};

/* an empty slab's kept entry */
#define NONE_ITEM UINT32_MAX

/* A slab's first room: its even share of the items and a quarter more (a fluid's slabs differ
 * by a few per cent; a room outgrown doubles, slab_grow), and a few for small runs. */
static uint32_t first_cap(size_t n, int slabs)
{
    const size_t share = n / (size_t)slabs;
    const size_t cap = share + share / 4 + 16;
    return (uint32_t)(cap < n ? cap : n);
}

/* Slab k's calendar and local numbers for cap items; false without memory (the slab as it
 * was). */
static bool slab_make(one_slab *k, uint32_t cap)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_calendar *cal = NULL;
    const bool made = nbep_calendar_create(cap, &cal, &d) == NBEP_OK;
    nbep_diag_fini(&d);
    uint32_t *glob = made ? malloc((cap ? cap : 1) * sizeof *glob) : NULL;
    if (!glob) {
        nbep_calendar_destroy(&cal);
        return false;
    }
    nbep_calendar_set_tie(cal, glob);
    *k = (one_slab){.cal = cal, .glob = glob, .cap = cap, .hi = 0, .free = LOCAL_NIL};
    return true;
}

/* Slab k's room doubled (at most n), its entries and local numbers kept: the entries come out
 * in the same order (it is by item), so the kept earliest stays right. False without memory
 * (the slab as it was). */
static bool slab_grow(nbep_slabcal *s, one_slab *k)
{
    const size_t want = 2 * (size_t)k->cap;
    one_slab g;
    if (k->cap >= s->n || !slab_make(&g, (uint32_t)(want < s->n ? want : s->n)))
        return false;
    nbep_calendar_entry c, first;
    const bool any = nbep_calendar_first(k->cal, &first);
    for (uint32_t l = 0; l < k->hi; l++) {
        g.glob[l] = k->glob[l];
        if (nbep_calendar_get(k->cal, l, &c))
            nbep_calendar_set(g.cal, l, c.time, c.key);
    }
    g.hi = k->hi;
    g.free = k->free;
    if (any) /* from its earliest: a speed setting */
        nbep_calendar_retune(g.cal, first.time);
    g.kept = k->kept; /* (its earliest, as kept, and whether to read it again) */
    g.stale = k->stale;
    nbep_calendar_destroy(&k->cal);
    free(k->glob);
    *k = g;
    return true;
}

/* A local number of slab k for item: false when the slab is full and cannot grow. */
static bool local_take(nbep_slabcal *s, one_slab *k, uint32_t item, uint32_t *l)
{
    if (k->free != LOCAL_NIL) {
        *l = k->free;
        k->free = k->glob[*l] & ~FREE;
    } else if (k->hi < k->cap || slab_grow(s, k)) {
        *l = k->hi++;
    } else {
        return false;
    }
    k->glob[*l] = item;
    return true;
}

static void local_give_back(one_slab *k, uint32_t l)
{
    k->glob[l] = FREE | k->free;
    k->free = l;
}

nbep_status nbep_slabcal_create(size_t n, int slabs, nbep_slabcal **out, nbep_diag *d)
{
    if (slabs < 2 || slabs > NBEP_SLABCAL_MAX)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: per-slab calendars take 2 to %d slabs, not %d",
                  NBEP_SLABCAL_MAX, slabs);
    if (n > NBEP_CALENDAR_MAX)
        NBEP_FAIL(d, NBEP_EDECK,
                  "nbep: per-slab calendars hold at most %zu items (their links are 32-bit), "
                  "not %zu",
                  NBEP_CALENDAR_MAX, n);
    nbep_slabcal *s = nbep_alloc_aligned(1, sizeof *s);
    bool made = s != NULL;
    if (made) {
        memset(s, 0, sizeof *s);
        s->slabs = slabs;
        s->n = n;
        s->best = s->second = -1;
        for (int k = 0; k < slabs && made; k++) {
            made = slab_make(&s->sl[k], first_cap(n, slabs));
            s->sl[k].stale = true;
        }
        s->at = made ? malloc((n ? n : 1) * sizeof *s->at) : NULL;
        made = s->at != NULL;
    }
    if (!made) {
        nbep_slabcal_destroy(&s);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the slabs' event calendars");
    }
    for (size_t i = 0; i < n; i++)
        s->at[i].slab = SLAB_NONE;
    *out = s;
    return NBEP_OK;
}

void nbep_slabcal_destroy(nbep_slabcal **s)
{
    if (!s || !*s)
        return;
    for (int k = 0; k < NBEP_SLABCAL_MAX; k++) { /* (those never made are NULL) */
        nbep_calendar_destroy(&(*s)->sl[k].cal);
        free((*s)->sl[k].glob);
    }
    free((*s)->at);
    nbep_free_aligned(*s);
    *s = NULL;
}

bool nbep_slabcal_set(nbep_slabcal *s, int slab, uint32_t item, double time, uint64_t key)
{
    const int was = s->at[item].slab;
    one_slab *k = &s->sl[slab];
    s->sl[slab].stale = true;
    if (was == slab) {
        nbep_calendar_set(k->cal, s->at[item].loc, time, key);
        return true;
    }
    uint32_t l;
    if (!local_take(s, k, item, &l))
        return false;
    if (was != SLAB_NONE) {
        nbep_calendar_remove(s->sl[was].cal, s->at[item].loc);
        local_give_back(&s->sl[was], s->at[item].loc);
        s->sl[was].stale = true;
    }
    nbep_calendar_set(k->cal, l, time, key);
    s->at[item].slab = (uint8_t)slab;
    s->at[item].loc = l;
    return true;
}

void nbep_slabcal_remove(nbep_slabcal *s, uint32_t item)
{
    const int was = s->at[item].slab;
    if (was == SLAB_NONE)
        return;
    nbep_calendar_remove(s->sl[was].cal, s->at[item].loc);
    local_give_back(&s->sl[was], s->at[item].loc);
    s->at[item].slab = SLAB_NONE;
    s->sl[was].stale = true;
}

void nbep_slabcal_clear(nbep_slabcal *s)
{
    for (int k = 0; k < s->slabs; k++) {
        nbep_calendar_clear(s->sl[k].cal);
        s->sl[k].hi = 0;
        s->sl[k].free = LOCAL_NIL;
        s->sl[k].stale = true;
    }
    for (size_t i = 0; i < s->n; i++)
        s->at[i].slab = SLAB_NONE;
}

void nbep_slabcal_retune(nbep_slabcal *s, double t_now)
{
    for (int k = 0; k < s->slabs; k++) /* (moves no entry in the order: kept stay right) */
        nbep_calendar_retune(s->sl[k].cal, t_now);
}

/* Slab k's kept earliest entry read again if its calendar changed since. */
static inline void refresh(nbep_slabcal *s, int k)
{
    if (!s->sl[k].stale)
        return;
    if (!nbep_calendar_first(s->sl[k].cal, &s->sl[k].kept))
        s->sl[k].kept.item = NONE_ITEM;
    else /* (by item: the merge compares items, as the one calendar does) */
        s->sl[k].kept.item = s->sl[k].glob[s->sl[k].kept.item];
    s->sl[k].stale = false;
}

bool nbep_slabcal_top(nbep_slabcal *s, int slab, nbep_calendar_entry *entry)
{
    refresh(s, slab);
    *entry = s->sl[slab].kept;
    return entry->item != NONE_ITEM;
}

bool nbep_slabcal_first(nbep_slabcal *s, nbep_calendar_entry *entry)
{
    int best = -1, second = -1;
    for (int k = 0; k < s->slabs; k++) {
        refresh(s, k);
        if (s->sl[k].kept.item == NONE_ITEM)
            continue;
        if (best < 0 || nbep_calendar_before(s->sl[k].kept, s->sl[best].kept)) {
            second = best;
            best = k;
        } else if (second < 0 || nbep_calendar_before(s->sl[k].kept, s->sl[second].kept)) {
            second = k;
        }
    }
    s->best = best;
    s->second = second;
    if (best < 0)
        return false;
    *entry = s->sl[best].kept;
    return true;
}

void nbep_slabcal_runners_up(const nbep_slabcal *s, uint32_t items[2], int *n)
{
    *n = 0;
    if (s->best < 0)
        return;
    nbep_slabcal_runners_up_of(s, s->best, items, n);
    if (s->second >= 0) { /* (first keeps only non-empty slabs' as best and second) */
        *n = *n > 0 ? 1 : 0;
        items[(*n)++] = s->sl[s->second].kept.item;
    }
}

void nbep_slabcal_runners_up_of(const nbep_slabcal *s, int slab, uint32_t items[2], int *n)
{
    const one_slab *k = &s->sl[slab];
    uint32_t up[2];
    nbep_calendar_runners_up(k->cal, up, NULL, n);
    for (int m = 0; m < *n; m++)
        items[m] = k->glob[up[m]];
}

void nbep_slabcal_prefetch(const nbep_slabcal *s, uint32_t item)
{
    const int k = s->at[item].slab;
    if (k != SLAB_NONE)
        nbep_calendar_prefetch(s->sl[k].cal, s->at[item].loc);
}

int nbep_slabcal_slab(const nbep_slabcal *s, uint32_t item)
{
    return s->at[item].slab == SLAB_NONE ? -1 : s->at[item].slab;
}

size_t nbep_slabcal_size(const nbep_slabcal *s)
{
    size_t m = 0;
    for (int k = 0; k < s->slabs; k++)
        m += nbep_calendar_size(s->sl[k].cal);
    return m;
}

size_t nbep_slabcal_size_of(const nbep_slabcal *s, int slab)
{
    return nbep_calendar_size(s->sl[slab].cal);
}

size_t nbep_slabcal_room_of(const nbep_slabcal *s, int slab)
{
    return s->sl[slab].cap;
}

int nbep_slabcal_slabs(const nbep_slabcal *s)
{
    return s->slabs;
}

size_t nbep_slabcal_check(nbep_slabcal *s)
{
    size_t bad = 0;
    size_t held[NBEP_SLABCAL_MAX] = {0};
    for (size_t i = 0; i < s->n; i++) { /* an item's entry at its local number, which names it */
        const int k = s->at[i].slab;
        if (k == SLAB_NONE)
            continue;
        if (k >= s->slabs || s->at[i].loc >= s->sl[k].hi || s->sl[k].glob[s->at[i].loc] != i ||
            !nbep_calendar_has(s->sl[k].cal, s->at[i].loc, NULL)) {
            bad++;
            continue;
        }
        held[k]++;
    }
    for (int k = 0; k < s->slabs; k++) {
        const one_slab *sl = &s->sl[k];
        /* below hi: each local number an item's (counted above) or free, with no entry */
        size_t free_ones = 0;
        for (uint32_t l = sl->free; l != LOCAL_NIL && free_ones <= sl->hi;
             l = sl->glob[l] & ~FREE, free_ones++)
            bad += l >= sl->hi || !(sl->glob[l] & FREE) || nbep_calendar_has(sl->cal, l, NULL);
        bad += sl->hi > sl->cap || free_ones + held[k] != sl->hi;
        bad += nbep_calendar_check(sl->cal);
        bad += held[k] != nbep_calendar_size(sl->cal);
        nbep_calendar_entry c;
        const bool any = nbep_calendar_first(sl->cal, &c);
        if (!s->sl[k].stale) /* a kept entry is the slab's earliest */
            bad += any ? s->sl[k].kept.item != sl->glob[c.item] || s->sl[k].kept.time != c.time ||
                             s->sl[k].kept.key != c.key
                       : s->sl[k].kept.item != NONE_ITEM;
    }
    return bad;
}

size_t nbep_slabcal_bytes(size_t n, int slabs)
{
    const size_t cap = first_cap(n, slabs);
    return sizeof(nbep_slabcal) + (n ? n : 1) * sizeof(((nbep_slabcal *)0)->at[0]) +
           (size_t)slabs * (nbep_calendar_bytes(cap) + (cap ? cap : 1) * sizeof(uint32_t));
}
