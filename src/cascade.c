/* Stamps in the serial loop's order, ties in time included: see cascade.h. */
#include "nbep/cascade.h"

#include <assert.h>
#include <string.h>

/* Whether (key, item) comes before level l of c in the calendar's order at one time */
static bool before_level(uint64_t key, uint32_t item, const nbep_cascade *c, uint32_t l)
{
    return key != c->level[l].key ? key < c->level[l].key : item < c->level[l].item;
}

bool nbep_cascade_made(const nbep_cascade *by, double t, uint64_t key, uint32_t item,
                       nbep_cascade *out)
{
    assert(by->depth >= 1 && by->depth <= NBEP_CASCADE_DEPTH && !(t < by->t));
    if (t != by->t) {
        nbep_cascade_set_root(out, t, key, item);
        return true;
    }
    uint32_t d = by->depth;
    if (before_level(key, item, by, d - 1)) { /* before its maker: the maker's child, next */
        if (d == NBEP_CASCADE_DEPTH)
            return false;
        if (out != by)
            memcpy(out->level, by->level, d * sizeof *by->level);
        out->t = t;
        out->level[d] = (nbep_cascade_level){key, item, 0};
        out->depth = d + 1;
        return true;
    }
    /* at or after it: at the deepest level whose parent it stays before (the path falls, so
     * every shallower parent is later still), where it is at or after the path's entry */
    while (d > 1 && !before_level(key, item, by, d - 2))
        d--;
    const bool same = key == by->level[d - 1].key && item == by->level[d - 1].item;
    const uint32_t again = same ? by->level[d - 1].again + 1 : 0;
    if (out != by)
        memcpy(out->level, by->level, (d - 1) * sizeof *by->level);
    out->t = t;
    out->level[d - 1] = (nbep_cascade_level){key, item, again};
    out->depth = d;
    return true;
}
