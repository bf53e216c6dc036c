/* Stamps in the serial loop's order, ties in time included: see cascade.h. */
#include "nbep/cascade.h"

#include <assert.h>
#include <string.h>

nbep_cascade nbep_cascade_root(double t, uint64_t key, uint32_t item)
{
    nbep_cascade c = {.t = t, .depth = 1};
    c.key[0] = key;
    c.item[0] = item;
    return c;
}

/* Whether (key, item) comes before level l of c in the calendar's order at one time */
static bool before_level(uint64_t key, uint32_t item, const nbep_cascade *c, uint32_t l)
{
    return key != c->key[l] ? key < c->key[l] : item < c->item[l];
}

bool nbep_cascade_made(const nbep_cascade *by, double t, uint64_t key, uint32_t item,
                       nbep_cascade *out)
{
    assert(by->depth >= 1 && by->depth <= NBEP_CASCADE_DEPTH && !(t < by->t));
    if (t != by->t) {
        *out = nbep_cascade_root(t, key, item);
        return true;
    }
    uint32_t d = by->depth;
    if (before_level(key, item, by, d - 1)) { /* before its maker: the maker's child, next */
        if (d == NBEP_CASCADE_DEPTH)
            return false;
        if (out != by)
            *out = *by;
        out->key[d] = key;
        out->item[d] = item;
        out->again[d] = 0;
        out->depth = d + 1;
        return true;
    }
    /* at or after it: at the deepest level whose parent it stays before (the path falls, so
     * every shallower parent is later still), where it is at or after the path's entry */
    while (d > 1 && !before_level(key, item, by, d - 2))
        d--;
    const bool same = key == by->key[d - 1] && item == by->item[d - 1];
    const uint32_t again = same ? by->again[d - 1] + 1 : 0;
    if (out != by) {
        memcpy(out->key, by->key, (d - 1) * sizeof *by->key);
        memcpy(out->item, by->item, (d - 1) * sizeof *by->item);
        memcpy(out->again, by->again, (d - 1) * sizeof *by->again);
    }
    out->t = t;
    out->key[d - 1] = key;
    out->item[d - 1] = item;
    out->again[d - 1] = again;
    out->depth = d;
    return true;
}

int nbep_cascade_cmp(const nbep_cascade *a, const nbep_cascade *b)
{
    if (a->t != b->t)
        return a->t < b->t ? -1 : 1;
    const uint32_t d = a->depth < b->depth ? a->depth : b->depth;
    for (uint32_t k = 0; k < d; k++) {
        if (a->key[k] != b->key[k])
            return a->key[k] < b->key[k] ? -1 : 1;
        if (a->item[k] != b->item[k])
            return a->item[k] < b->item[k] ? -1 : 1;
        if (a->again[k] != b->again[k])
            return a->again[k] < b->again[k] ? -1 : 1;
    }
    /* one is the other's path extended: the maker first */
    return (a->depth > b->depth) - (a->depth < b->depth);
}
