/* Neighbour lists: see nblist.h. */
#include "nbep/nblist.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/compiler.h"

nbep_status nbep_nblist_init(nbep_nblist *l, size_t n, nbep_diag *d)
{
    memset(l, 0, sizeof *l);
    if (n < UINT32_MAX) {
        l->n = n;
        l->sp = nbep_alloc_aligned(n ? n : 1, sizeof *l->sp);
    }
    if (!l->sp) {
        nbep_nblist_fini(l);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the neighbour lists of %zu spheres", n);
    }
    return NBEP_OK;
}

void nbep_nblist_fini(nbep_nblist *l)
{
    nbep_free_aligned(l->sp);
    free(l->pool);
    memset(l, 0, sizeof *l);
}

/* Makes the pool hold at least `need` entries, keeping its contents; when it must grow, it
 * grows to need + need / spare_div (room for later moves). */
static bool reserve(nbep_nblist *l, size_t need, size_t spare_div)
{
    if (need <= l->pool_cap)
        return true;
    size_t cap = need + need / spare_div;
    uint32_t *p = realloc(l->pool, cap * sizeof *p);
    if (!p)
        return false;
    nbep_huge_pages(p, cap * sizeof *p); /* read at random, as the spheres' arrays are */
    l->pool = p;
    l->pool_cap = cap;
    return true;
}

bool nbep_nblist_layout(nbep_nblist *l, const uint32_t *counts)
{
    size_t total = 0;
    for (size_t i = 0; i < l->n; i++)
        total += nbep_nblist_room_for(counts[i]);
    bool ok = reserve(l, total, 8u); /* an eighth spare: lists that outgrow their room move */
    size_t at = 0;
    l->cap_max = 0;
    for (size_t i = 0; i < l->n; i++) {
        l->sp[i].off = (uint32_t)(ok ? at : 0);
        l->sp[i].cap = ok ? nbep_nblist_room_for(counts[i]) : 0;
        l->sp[i].cnt = 0;
        at += l->sp[i].cap;
        if (l->sp[i].cap > l->cap_max)
            l->cap_max = l->sp[i].cap;
    }
    l->pool_len = l->room = at;
    return ok;
}

static int by_key(const void *a, const void *b)
{
    const uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Lays every list out again in place with its room for its count (`fresh` rooms in all, the
 * sum the caller counted), then `extra` entries and an eighth of the whole spare: the room
 * given up by lists that moved is reclaimed. In place, so that the pool is never held twice
 * (a copy into a fresh pool doubled the peak memory of a fluid whose lists grow as it melts
 * from a lattice): the lists in order of their places are first packed down with no room to
 * spare (each lands no later than it was), then spread out from the last down to their rooms
 * (each lands no earlier than it was packed). */
static bool compact(nbep_nblist *l, size_t fresh, size_t extra)
{
    const size_t total = fresh + extra;
    const size_t cap = total + total / 8u;
    uint64_t *ord = malloc((l->n ? l->n : 1) * sizeof *ord);
    if (!ord || !reserve(l, cap, 1u << 30)) { /* room for cap (next to no spare) */
        free(ord);
        return false;
    }
    for (size_t i = 0; i < l->n; i++)
        ord[i] = (uint64_t)l->sp[i].off << 32 | (uint64_t)i;
    qsort(ord, l->n, sizeof *ord, by_key);
    size_t at = 0;
    for (size_t k = 0; k < l->n; k++) { /* packed: at <= off, as every cnt <= its cap */
        nbep_nblist_span *sp = &l->sp[(uint32_t)ord[k]];
        memmove(l->pool + at, l->pool + sp->off, sp->cnt * sizeof *l->pool);
        sp->off = (uint32_t)at;
        at += sp->cnt;
    }
    size_t end = fresh;
    l->cap_max = 0;
    for (size_t k = l->n; k-- > 0;) { /* spread: each list's new place is past its packed one */
        nbep_nblist_span *sp = &l->sp[(uint32_t)ord[k]];
        sp->cap = nbep_nblist_room_for(sp->cnt);
        end -= sp->cap;
        memmove(l->pool + end, l->pool + sp->off, sp->cnt * sizeof *l->pool);
        sp->off = (uint32_t)end;
        if (sp->cap > l->cap_max)
            l->cap_max = sp->cap;
    }
    free(ord);
    l->pool_len = l->room = fresh;
    if (l->pool_cap > cap) { /* give back what a long melt grew */
        uint32_t *p = realloc(l->pool, cap * sizeof *p);
        if (p) {
            l->pool = p;
            l->pool_cap = cap;
        }
    }
    return true;
}

/* A full pool compacted, with `extra` entries of spare after, where it holds more than a quarter
 * more than a fresh layout of the lists as they are would take (room given up by moves, and
 * rooms grown for counts that have since fallen); else left to grow. False without memory. */
static bool compact_if_loose(nbep_nblist *l, size_t extra)
{
    size_t fresh = 0;
    for (size_t k = 0; k < l->n; k++)
        fresh += nbep_nblist_room_for(l->sp[k].cnt);
    return 4u * l->pool_len <= 5u * fresh || compact(l, fresh, extra);
}

bool nbep_nblist_append(nbep_nblist *l, uint32_t i, uint32_t j)
{
    if (l->sp[i].cnt == l->sp[i].cap) { /* full: move to the end with more room */
        const uint32_t grown = nbep_nblist_grown(l->sp[i].cap);
        /* The pool is full: compact it if it holds more than a quarter more than a fresh
         * layout of the lists as they are would take (room given up by moves, and rooms grown
         * for counts that have since fallen), else let it grow by a quarter. Either way the
         * pool stays within about 1.6 fresh layouts (5/4 of 5/4), and the O(n) count is paid
         * only when it fills. */
        if (l->pool_len + grown > l->pool_cap) {
            if (l->arena) /* (a view moves within its piece alone: nblist.h) */
                return false;
            if (!compact_if_loose(l, grown))
                return false;
        }
        if (l->sp[i].cnt == l->sp[i].cap) { /* compaction may have made room already */
            if (l->pool_len + grown > UINT32_MAX || !reserve(l, l->pool_len + grown, 4u))
                return false;
            memcpy(l->pool + l->pool_len, l->pool + l->sp[i].off, l->sp[i].cnt * sizeof *l->pool);
            l->sp[i].off = (uint32_t)l->pool_len;
            l->room += grown - l->sp[i].cap;
            l->sp[i].cap = grown;
            l->pool_len += grown;
            if (grown > l->cap_max)
                l->cap_max = grown;
        }
    }
    l->pool[l->sp[i].off + l->sp[i].cnt++] = j;
    return true;
}

bool nbep_nblist_set(nbep_nblist *l, uint32_t i, const uint32_t *js, size_t m)
{
    nbep_nblist_clear(l, i);
    if (m <= l->sp[i].cap) { /* the common case: a rebuilt list keeps about its length */
        memcpy(l->pool + l->sp[i].off, js, m * sizeof *js);
        l->sp[i].cnt = (uint32_t)m;
        return true;
    }
    for (size_t k = 0; k < m; k++)
        if (!nbep_nblist_append(l, i, js[k]))
            return false;
    return true;
}

uint32_t nbep_nblist_drop(nbep_nblist *l, uint32_t i, uint32_t j)
{
    uint32_t *theirs = l->pool + l->sp[i].off;
    for (uint32_t q = 0; q < l->sp[i].cnt; q++)
        if (theirs[q] == j) { /* order does not matter: swap the last in */
            theirs[q] = theirs[--l->sp[i].cnt];
            return q;
        }
    return UINT32_MAX;
}

bool nbep_nblist_undrop(nbep_nblist *l, uint32_t i, uint32_t j, uint32_t q)
{
    assert(q <= l->sp[i].cnt);
    if (!nbep_nblist_append(l, i, j)) /* (it may move the list: its offset read after) */
        return false;
    uint32_t *theirs = l->pool + l->sp[i].off;
    theirs[l->sp[i].cnt - 1] = theirs[q];
    theirs[q] = j;
    return true;
}

void nbep_nblist_detach(nbep_nblist *l, uint32_t i)
{
    const uint32_t *mine = l->pool + l->sp[i].off;
    for (uint32_t k = 0; k < l->sp[i].cnt; k++)
        nbep_nblist_drop(l, mine[k], i);
    nbep_nblist_clear(l, i);
}

bool nbep_nblist_make_spare(nbep_nblist *l, size_t spare)
{
    assert(!l->arena);
    if (l->pool_cap - l->pool_len >= spare)
        return true;
    /* (as an append that fills the pool) */
    if (!compact_if_loose(l, spare))
        return false;
    return l->pool_len + spare <= UINT32_MAX && reserve(l, l->pool_len + spare, 4u);
}

void nbep_nblist_arena(const nbep_nblist *l, size_t lo, size_t hi, nbep_nblist *a)
{
    assert(lo >= l->pool_len && lo <= hi && hi <= l->pool_cap);
    *a = *l;
    a->pool_len = lo;
    a->pool_cap = hi;
    a->arena = true;
}

void nbep_nblist_arena_back(nbep_nblist *l, const nbep_nblist *a, size_t room0)
{
    assert(a->pool == l->pool && a->sp == l->sp);
    l->room += a->room - room0;
    if (a->cap_max > l->cap_max)
        l->cap_max = a->cap_max;
}

/* Is j in i's list? */
static bool listed(const nbep_nblist *l, uint32_t i, uint32_t j)
{
    for (uint32_t k = 0; k < l->sp[i].cnt; k++)
        if (l->pool[l->sp[i].off + k] == j)
            return true;
    return false;
}

size_t nbep_nblist_check(const nbep_nblist *l)
{
    size_t bad = 0;
    for (size_t i = 0; i < l->n; i++) {
        if (l->sp[i].cnt > l->sp[i].cap || (size_t)l->sp[i].off + l->sp[i].cap > l->pool_len) {
            bad++;
            continue;
        }
        const uint32_t *a = l->pool + l->sp[i].off;
        for (uint32_t k = 0; k < l->sp[i].cnt; k++) {
            bad += a[k] >= l->n || a[k] == i;
            for (uint32_t q = k + 1; q < l->sp[i].cnt; q++)
                bad += a[q] == a[k];
            bad += a[k] < l->n && !listed(l, a[k], (uint32_t)i);
        }
    }
    return bad;
}

size_t nbep_nblist_bytes(size_t n, size_t entries)
{
    /* the rooms of a fresh layout (nbep_nblist_room_for), and the pool's bound of 5/4 of 5/4 */
    return n * sizeof(nbep_nblist_span) +
           (entries + entries / 8u + 3u * n) * 25 / 16 * sizeof(uint32_t);
}
