/* Per-slab event calendars merged on one thread: see slabcal.h. */
#include <stdlib.h>
#include <string.h>

#include "nbep/slabcal.h"
#include "nbep/status.h"

/* an item without an entry */
#define SLAB_NONE UINT8_MAX

_Static_assert(NBEP_SLABCAL_MAX < SLAB_NONE, "a slab number fits a byte beside SLAB_NONE");

struct nbep_slabcal {
    int slabs;
    size_t n;
    nbep_calendar *cal[NBEP_SLABCAL_MAX]; /* owned, one a slab */
    uint8_t *slab;                        /* owned, n: the slab holding each item's entry */
    /* each slab's earliest entry as last read (kept[s].item == NONE_ITEM: empty), and whether
     * its calendar changed since (then it is read again) */
    nbep_calendar_entry kept[NBEP_SLABCAL_MAX];
    bool stale[NBEP_SLABCAL_MAX];
    int best, second; /* the last first's slab, and the slab of the next kept entry (-1) */
};

/* an empty slab's kept entry */
#define NONE_ITEM UINT32_MAX

nbep_status nbep_slabcal_create(size_t n, int slabs, nbep_slabcal **out, nbep_diag *d)
{
    if (slabs < 2 || slabs > NBEP_SLABCAL_MAX)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: per-slab calendars take 2 to %d slabs, not %d",
                  NBEP_SLABCAL_MAX, slabs);
    nbep_slabcal *s = calloc(1, sizeof *s);
    if (!s)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the slabs' event calendars");
    s->slabs = slabs;
    s->n = n;
    s->best = s->second = -1;
    /* the calendars first: the first refuses more items than its links hold, before anything
     * of that size is asked for */
    for (int k = 0; k < slabs; k++) {
        const nbep_status st = nbep_calendar_create(n, &s->cal[k], d);
        if (st != NBEP_OK) {
            nbep_slabcal_destroy(&s);
            return st;
        }
        s->stale[k] = true;
    }
    s->slab = malloc(n ? n : 1);
    if (!s->slab) {
        nbep_slabcal_destroy(&s);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the slabs' event calendars");
    }
    memset(s->slab, SLAB_NONE, n);
    *out = s;
    return NBEP_OK;
}

void nbep_slabcal_destroy(nbep_slabcal **s)
{
    if (!s || !*s)
        return;
    for (int k = 0; k < NBEP_SLABCAL_MAX; k++) /* (those never made are NULL) */
        nbep_calendar_destroy(&(*s)->cal[k]);
    free((*s)->slab);
    free(*s);
    *s = NULL;
}

void nbep_slabcal_set(nbep_slabcal *s, int slab, uint32_t item, double time, uint64_t key)
{
    const int was = s->slab[item];
    if (was != SLAB_NONE && was != slab) {
        nbep_calendar_remove(s->cal[was], item);
        s->stale[was] = true;
    }
    nbep_calendar_set(s->cal[slab], item, time, key);
    s->slab[item] = (uint8_t)slab;
    s->stale[slab] = true;
}

void nbep_slabcal_remove(nbep_slabcal *s, uint32_t item)
{
    const int was = s->slab[item];
    if (was == SLAB_NONE)
        return;
    nbep_calendar_remove(s->cal[was], item);
    s->slab[item] = SLAB_NONE;
    s->stale[was] = true;
}

void nbep_slabcal_clear(nbep_slabcal *s)
{
    for (int k = 0; k < s->slabs; k++) {
        nbep_calendar_clear(s->cal[k]);
        s->stale[k] = true;
    }
    memset(s->slab, SLAB_NONE, s->n);
}

void nbep_slabcal_retune(nbep_slabcal *s, double t_now)
{
    for (int k = 0; k < s->slabs; k++) /* (moves no entry in the order: kept stay right) */
        nbep_calendar_retune(s->cal[k], t_now);
}

bool nbep_slabcal_first(nbep_slabcal *s, nbep_calendar_entry *entry)
{
    int best = -1, second = -1;
    for (int k = 0; k < s->slabs; k++) {
        if (s->stale[k]) {
            if (!nbep_calendar_first(s->cal[k], &s->kept[k]))
                s->kept[k].item = NONE_ITEM;
            s->stale[k] = false;
        }
        if (s->kept[k].item == NONE_ITEM)
            continue;
        if (best < 0 || nbep_calendar_before(s->kept[k], s->kept[best])) {
            second = best;
            best = k;
        } else if (second < 0 || nbep_calendar_before(s->kept[k], s->kept[second])) {
            second = k;
        }
    }
    s->best = best;
    s->second = second;
    if (best < 0)
        return false;
    *entry = s->kept[best];
    return true;
}

void nbep_slabcal_runners_up(const nbep_slabcal *s, uint32_t items[2], int *n)
{
    *n = 0;
    if (s->best < 0)
        return;
    uint32_t up[2];
    int m;
    nbep_calendar_runners_up(s->cal[s->best], up, NULL, &m);
    if (m > 0)
        items[(*n)++] = up[0];
    if (s->second >= 0) /* (first keeps only non-empty slabs' as best and second) */
        items[(*n)++] = s->kept[s->second].item;
    else if (m > 1)
        items[(*n)++] = up[1];
}

void nbep_slabcal_prefetch(const nbep_slabcal *s, uint32_t item)
{
    const int k = s->slab[item];
    if (k != SLAB_NONE)
        nbep_calendar_prefetch(s->cal[k], item);
}

int nbep_slabcal_slab(const nbep_slabcal *s, uint32_t item)
{
    return s->slab[item] == SLAB_NONE ? -1 : s->slab[item];
}

size_t nbep_slabcal_size(const nbep_slabcal *s)
{
    size_t m = 0;
    for (int k = 0; k < s->slabs; k++)
        m += nbep_calendar_size(s->cal[k]);
    return m;
}

size_t nbep_slabcal_size_of(const nbep_slabcal *s, int slab)
{
    return nbep_calendar_size(s->cal[slab]);
}

int nbep_slabcal_slabs(const nbep_slabcal *s)
{
    return s->slabs;
}

size_t nbep_slabcal_check(nbep_slabcal *s)
{
    size_t bad = 0;
    size_t held[NBEP_SLABCAL_MAX] = {0};
    for (size_t i = 0; i < s->n; i++) {
        const int k = s->slab[i];
        for (int j = 0; j < s->slabs; j++) /* in its slab's calendar, and no other */
            bad += nbep_calendar_has(s->cal[j], (uint32_t)i, NULL) != (j == k);
        if (k != SLAB_NONE && k >= s->slabs)
            bad++;
        else if (k != SLAB_NONE)
            held[k]++;
    }
    for (int k = 0; k < s->slabs; k++) {
        bad += nbep_calendar_check(s->cal[k]);
        bad += held[k] != nbep_calendar_size(s->cal[k]);
        nbep_calendar_entry c;
        const bool any = nbep_calendar_first(s->cal[k], &c);
        if (!s->stale[k]) /* a kept entry is the slab's earliest */
            bad += any ? s->kept[k].item != c.item || s->kept[k].time != c.time ||
                             s->kept[k].key != c.key
                       : s->kept[k].item != NONE_ITEM;
    }
    return bad;
}

size_t nbep_slabcal_bytes(size_t n, int slabs)
{
    return sizeof(nbep_slabcal) + (n ? n : 1) + (size_t)slabs * nbep_calendar_bytes(n);
}
