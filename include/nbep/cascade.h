/* Stamps that order events as the cells engine's serial loop hands them out, ties in time
 * included, computed where an entry is made from the event that made it
 * (docs/optimistic-design.md, *Ties in time*).
 *
 * The serial loop takes the earliest calendar entry by (time, key), but an event at time t may
 * make an entry at t itself whose key comes first (a sphere sent into one it touches whose
 * pair's key is smaller: a Newton's cradle struck at its high-numbered end; a pile at e = 0,
 * where 1.3 % of events did so in test_stamp_order's pile). The loop handles that entry next,
 * so (time, key) goes back, while the optimistic scheme's scheduler needs stamps that never
 * go back along the serial order (warp.h: its logs and its stragglers compare stamps). Moving
 * such an entry one ulp later in time would change the physics (a sphere at rest in a V of
 * two planes at t = 0 flew a denormal time under gravity into a plane and counted a collision:
 * tried 2026-12-07, test_granular caught it); a stamp with more parts does not.
 *
 * At one time t the serial loop's entries form a tree. An entry (t, key, item) made by an
 * event that it comes before in the calendar's order (key, then item) is that event's child;
 * one that comes at or after it is a sibling of the event or of one of its ancestors (at the
 * deepest level whose parent it still comes before), and one after the whole path a new root.
 * The loop takes the least entry pending, and the pending entries of deeper levels come before
 * those of shallower ones, so it walks the tree in preorder, children in the calendar's order:
 * the order of the stamps (t, root's (key, item), child's, ...) compared part by part, a stamp
 * before its own extensions. The item matters: a pair's two entries share their time and key,
 * and the loop takes the lower sphere's, then whatever that event made before the pair's key,
 * then the higher sphere's (if still there). An entry made again at the level it holds on the
 * path (a stale slot predicted once more onto the same pair at the same time; a pair sent back
 * into each other by a child's event) comes after its whole subtree: each level counts such
 * makings. So a stamp is the time and the path from the root, made from the maker's stamp
 * alone: a slab can stamp what it makes without knowing what the others did.
 */
#ifndef NBEP_CASCADE_H
#define NBEP_CASCADE_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* The most levels in a stamp: a cascade at one time deeper than this (a cradle of 10 spheres
 * struck at its high-numbered end: 5 gave 4 levels) is past what a stamp holds; its maker is
 * told (nbep_cascade_made). */
#define NBEP_CASCADE_DEPTH 8

/* A level of a stamp: an entry's calendar key and item, and the times it was made again */
typedef struct nbep_cascade_level {
    uint64_t key;
    uint32_t item, again;
} nbep_cascade_level;

/* Only the first `depth` levels are read (nor written, where a stamp is made: a root touches
 * its first 32 bytes). */
typedef struct nbep_cascade {
    double t;
    uint32_t depth; /* levels in use, 1 to NBEP_CASCADE_DEPTH */
    nbep_cascade_level level[NBEP_CASCADE_DEPTH]; /* from the root; each (key, item) before
                                                     the one above it */
} nbep_cascade;

/* *c the stamp of item's entry (t, key) made at an earlier time than t, or by nothing (the
 * setup's predictions): a root. Only its first level written (a whole stamp zeroed and copied
 * cost a made root 17 ns, three times the rest of its work); inline, as the next, which makes
 * one for nearly every entry (out of line, returned whole, it was copied whole: 144 bytes). */
static inline void nbep_cascade_set_root(nbep_cascade *c, double t, uint64_t key, uint32_t item)
{
    c->t = t;
    c->depth = 1;
    c->level[0] = (nbep_cascade_level){key, item, 0};
}

/* The same, returned. */
static inline nbep_cascade nbep_cascade_root(double t, uint64_t key, uint32_t item)
{
    nbep_cascade c;
    nbep_cascade_set_root(&c, t, key, item);
    return c;
}

/* The stamp of item's entry (t, key) made by the event stamped *by (t at or after by's time:
 * an entry is never made behind now), in *out (which may be by). False when it would need more
 * than NBEP_CASCADE_DEPTH levels: *out is then unchanged, and the caller handles what follows
 * another way (the scheduler ends its window there). */
bool nbep_cascade_made(const nbep_cascade *by, double t, uint64_t key, uint32_t item,
                       nbep_cascade *out);

/* *dst = *src, only the levels in use copied (a root, most stamps: 32 of its 144 bytes; a
 * root's level by assignment, not a call of memcpy) */
static inline void nbep_cascade_copy(nbep_cascade *dst, const nbep_cascade *src)
{
    dst->t = src->t;
    dst->depth = src->depth;
    if (src->depth == 1)
        dst->level[0] = src->level[0];
    else
        memcpy(dst->level, src->level, src->depth * sizeof src->level[0]);
}

/* Negative, zero or positive as a comes before, with, or after b in the serial loop's order
 * (inline: the scheduler compares stamps on every input, and a call took copies of both) */
static inline int nbep_cascade_cmp(const nbep_cascade *a, const nbep_cascade *b)
{
    if (a->t != b->t)
        return a->t < b->t ? -1 : 1;
    const uint32_t d = a->depth < b->depth ? a->depth : b->depth;
    for (uint32_t k = 0; k < d; k++) {
        const nbep_cascade_level *x = &a->level[k], *y = &b->level[k];
        if (x->key != y->key)
            return x->key < y->key ? -1 : 1;
        if (x->item != y->item)
            return x->item < y->item ? -1 : 1;
        if (x->again != y->again)
            return x->again < y->again ? -1 : 1;
    }
    /* one is the other's path extended: the maker first */
    return (a->depth > b->depth) - (a->depth < b->depth);
}

#endif
