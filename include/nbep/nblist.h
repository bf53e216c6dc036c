/* Neighbour lists of the cells engine (evloop.c): for every sphere, the spheres whose list
 * centres were within its cutoff (contact distance plus a skin) when either list was last
 * built. The engine keeps the lists symmetric (j is in i's list exactly when i is in j's),
 * so a sphere that rebuilds its list also enters the lists of its new neighbours and leaves
 * those of its old ones, and no other list has to be rebuilt with it.
 *
 * Storage: one pool of uint32 entries; sphere i's list is pool[off[i] .. off[i] + cnt[i]) with
 * room for cap[i] (nbep_nblist_room_for at a layout). A list that outgrows its room moves to
 * the end of the pool with half as much room again (nbep_nblist_grown); when the pool fills
 * and holds more than a quarter more than a fresh layout would take, it is compacted in place
 * (every list moved, with its room for its count), so memory stays within about 1.6 fresh
 * layouts and proportional to the entries (4 bytes per neighbour, 10 to 11 neighbours in a
 * fluid at phi 0.30 to 0.50) however long the run. The slack is small on purpose: the pool
 * was the largest thing a dense run grew (120 bytes a sphere at N = 256000, phi 0.50, when a
 * list got a quarter more and four, moved with twice its room and the pool was compacted at
 * one and a half fresh layouts; at most 79 now, for 45 of entries); the moves and
 * compactions this costs are rare (two compactions in that run). Not thread-safe for appends
 * and removals (one thread); nbep_nblist_layout and nbep_nblist_fill_own let threads fill
 * disjoint spheres' lists at a full rebuild. */
#ifndef NBEP_NBLIST_H
#define NBEP_NBLIST_H

#include <assert.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

/* The skin of a dense scene (and of any that accelerates or has no box), as a fraction of the
 * largest contact distance: a list holds the spheres whose centres were within contact
 * distance plus the skin, and is rebuilt when its sphere has strayed half the skin from where
 * it was built. A wider skin means longer lists (more pairs tested per re-prediction, as the
 * cube of 1 + skin), a thinner one more rebuilds. Measured (N = 32000 periodic fluid, one time
 * unit from the lattice, medians of 3 interleaved runs, collisions per second on this 2-core
 * machine, before the rebuild's walk lost its branches) with skins 0.3 / 0.4 / 0.5: phi 0.30:
 * 213 / 273 / 241 k; phi 0.43: 362 / 375 / 333 k; phi 0.50: 437 / 434 / 353 k (0.7 and 0.9
 * were slower still at both ends). Smallenburg's EDMD uses 0.5. */
#ifndef NBEP_NBLIST_SKIN /* a -D overrides it, for benchmarks only */
#define NBEP_NBLIST_SKIN 0.4
#endif
/* The skin of a dilute scene that flies free (no acceleration), where a sphere flies farther
 * between collisions and outruns a thin skin's list: at phi = 0.30 a collision had 0.77 list
 * expiries with the skin of 0.4 (0.10 at phi = 0.50). Measured on the melted N = 32000 fluids
 * after the walk lost its branches (8a3d22d; paired resumed runs on an AMD machine, medians
 * of 4 per-run ratios of collisions a second against a skin of 0.4), skins 0.5 / 0.6 / 0.7:
 * phi 0.30: 1.07 / 1.10 / 1.12; phi 0.40: 1.08 / 1.07 / 1.07; phi 0.50: 1.03 / 1.01 / 1.00
 * (0.45: 1.00); and 0.6 / 0.8 at phi 0.10: 1.19 / 1.15, at phi 0.20: 1.09 / 1.15. */
#ifndef NBEP_NBLIST_SKIN_DILUTE
#define NBEP_NBLIST_SKIN_DILUTE 0.6
#endif
/* The skin of a dense scene that flies free (a fluid at phi = 0.45 and above). Thicker than
 * NBEP_NBLIST_SKIN, which a pile keeps: since the rebuild's walk lost its branches (8a3d22d) an
 * expiry costs less than the pairs a thinner skin spares. Counted (cachegrind, the melted
 * N = 32000 fluid at phi = 0.50, instructions a collision) with skins 0.30 / 0.35 / 0.40 /
 * 0.45 / 0.50 / 0.60: 7041 / 6898 / 6747 / 6649 / 6595 / 6552; timed (scripts/ab-pair.sh,
 * 8 paired resumed runs, medians of the per-run ratios of collisions a second), 0.50 against
 * 0.40: 1.025, and 0.60 against 0.50: 0.996, whose lists are a fifth longer again. */
#ifndef NBEP_NBLIST_SKIN_DENSE
#define NBEP_NBLIST_SKIN_DENSE 0.5
#endif
/* The packing fractions at and below which a free-flying scene takes the dilute skin, and at
 * and above which the dense one (NBEP_NBLIST_SKIN_DENSE); in between, the skin goes linearly
 * from one to the other. The dense end keeps the lists of a dense fluid shorter (a list is
 * 4 bytes a neighbour, and a fluid at phi = 0.50 would list a fifth more with the dilute
 * skin, for no gain). */
#define NBEP_NBLIST_PHI_DILUTE 0.35
#define NBEP_NBLIST_PHI_DENSE 0.45

/* The skin of a sparse elastic scene (packing fraction NBEP_NBLIST_PHI_SPARSE or below in its
 * box, restitution 1, accelerating or not): there a list holds well under one sphere at the
 * skins above, and its expiries, not collisions, are most of the events (the paper's box, 4096
 * spheres under gravity at phi = 0.0021: 3300 predictions a step for 2 collisions). Measured
 * (one thread, this 2-core machine, ms a step, the paper's box in cells mode, 4096 spheres
 * over 500 steps and 16384 over 200, and the 4096 without gravity) with skins 0.4 (0.6
 * without gravity) / 1.0 / 1.5 / 2.0 / 3.0 / 4.0: 0.176 / 0.092 / 0.072 / 0.063 / 0.058 /
 * 0.053; 0.537 / 0.309 / 0.263 / 0.235 / 0.219 / 0.197; 0.071 / 0.043 / 0.036 / 0.033 /
 * 0.029 / 0.028. Only where nothing dissipates: the skin is fixed at the start, and a sparse
 * start that loses its energy crowds somewhere later, where the wide skin lists 8 phi (1 +
 * skin)^3 spheres (95 where they pack at 0.6, against 13): the paper's box poured at e = 0.3
 * into a column 20 times taller than wide (phi = 0.013) ran past 3 times the thin skin's 72 s.
 * An elastic scene keeps its energy and its spread. Held at 2.0, not the 4.0 that ran fastest:
 * a list reaches 3 contact distances. A resumed run takes the skin from the same deck: the same
 * lists' reach, the same bits. */
#ifndef NBEP_NBLIST_SKIN_SPARSE
#define NBEP_NBLIST_SKIN_SPARSE 2.0
#endif
/* At and below NBEP_NBLIST_PHI_SPARSE the sparse skin; at and above NBEP_NBLIST_PHI_SPARSE_END
 * the rules above; in between, the skin goes linearly from one to the other. */
#define NBEP_NBLIST_PHI_SPARSE 0.01
#define NBEP_NBLIST_PHI_SPARSE_END 0.05

/* The skin on the straight line from s0 at packing phi0 to s1 at phi1. */
static inline double nbep_nblist_skin_between(double phi, double phi0, double s0, double phi1,
                                              double s1)
{
    return s0 + (phi - phi0) / (phi1 - phi0) * (s1 - s0);
}

/* Whether a scene packing the fraction phi of its box, elastic or not, takes the sparse skin
 * or a skin between it and the denser rules (NAN, no box: not). */
static inline bool nbep_nblist_sparse(double phi, bool elastic)
{
    return elastic && phi < NBEP_NBLIST_PHI_SPARSE_END;
}

/* The skin (a fraction of the largest contact distance) for a scene whose spheres fill the
 * fraction phi of its box, fly free (flies_free: no acceleration anywhere) or not, and collide
 * elastically (restitution 1) or not. NBEP_NBLIST_SKIN when phi is not a number (no box), or
 * when the scene accelerates and is not sparse and elastic: a pile's spheres are crowded at the
 * bottom of a box that is mostly empty, so the box's fraction says nothing of it. */
static inline double nbep_nblist_skin_for(double phi, bool flies_free, bool elastic)
{
    if (!(phi >= 0.0))
        return NBEP_NBLIST_SKIN;
    double skin = NBEP_NBLIST_SKIN;
    if (flies_free && phi <= NBEP_NBLIST_PHI_DILUTE)
        skin = NBEP_NBLIST_SKIN_DILUTE;
    else if (flies_free && phi < NBEP_NBLIST_PHI_DENSE)
        skin = nbep_nblist_skin_between(phi, NBEP_NBLIST_PHI_DILUTE, NBEP_NBLIST_SKIN_DILUTE,
                                        NBEP_NBLIST_PHI_DENSE, NBEP_NBLIST_SKIN_DENSE);
    else if (flies_free)
        skin = NBEP_NBLIST_SKIN_DENSE;
    if (!nbep_nblist_sparse(phi, elastic))
        return skin;
    if (phi <= NBEP_NBLIST_PHI_SPARSE)
        return NBEP_NBLIST_SKIN_SPARSE;
    return nbep_nblist_skin_between(phi, NBEP_NBLIST_PHI_SPARSE, NBEP_NBLIST_SKIN_SPARSE,
                                    NBEP_NBLIST_PHI_SPARSE_END, skin);
}
/* A list rebuilt at its expiry is centred this many strays (half skins) ahead of its sphere
 * along a straight flight (evloop.c, list_centre), so that the sphere flies 1 + LEAD strays
 * before the list expires again if nothing deflects it. Measured (N = 32000 periodic fluid
 * from the lattice, 5 time units, the two binaries at once on the two cores, medians of 8
 * per-run ratios): events 2.01 / 1.79 / 1.74 million with leads 0 / 0.5 / 0.75 at phi 0.30,
 * time 0.90 and 0.89 of lead 0's; at phi 0.50, where a list outlives many collisions,
 * events and time unchanged (1.01). */
#ifndef NBEP_NBLIST_LEAD /* a -D overrides it, for benchmarks only */
#define NBEP_NBLIST_LEAD 0.5
#endif
/* A centre a whole stray or more ahead puts the rebuilt list's sphere at its expiry at once:
 * the next expiry comes at the same time, and so on (with 1.0, the loop stalled). */
_Static_assert((int)NBEP_NBLIST_LEAD == 0, "a list's centre is less than one stray ahead");
/* In a small periodic box the skin is cut down so that three cells of width contact distance
 * plus skin fit across, but never below this (the deck check asks for that much room). */
#define NBEP_NBLIST_SKIN_MIN 0.125

/* Sphere i's list: pool[off .. off + cnt), room for cap; the three in one record, so that a
 * list is found with one cache line. */
typedef struct nbep_nblist_span {
    uint32_t off, cnt, cap;
} nbep_nblist_span;

typedef struct nbep_nblist {
    size_t n;
    nbep_nblist_span *sp;      /* owned, n */
    uint32_t *pool;            /* owned, pool_cap entries */
    size_t pool_len;           /* entries handed out (live lists and given-up room) */
    size_t pool_cap;
    size_t room;               /* sum of cap[]: the room in use */
    uint32_t cap_max;          /* no list has more room than this */
    bool arena;                /* a view of one arena (nbep_nblist_arena): its moves go into
                                * [pool_len, pool_cap) of the pool it shares, never past */
} nbep_nblist;

/* Empty lists for n spheres (n < UINT32_MAX). NBEP_ENOMEM with a message. */
NBEP_MUST_CHECK nbep_status nbep_nblist_init(nbep_nblist *l, size_t n, nbep_diag *d);
/* Frees; safe on a zeroed value. */
void nbep_nblist_fini(nbep_nblist *l);

/* A full rebuild: given how many entries each sphere's list will get (counts, n), lays the
 * lists out one after another, each with a little slack, all empty. False when out of memory
 * (the lists are then all empty with no room; appends fail). One thread. */
bool nbep_nblist_layout(nbep_nblist *l, const uint32_t *counts);
/* Appends j to i's list after nbep_nblist_layout; i's room must not be full. Threads may fill
 * disjoint spheres' lists at once. */
static inline void nbep_nblist_fill(nbep_nblist *l, uint32_t i, uint32_t j)
{
    l->pool[l->sp[i].off + l->sp[i].cnt++] = j;
}

/* Appends j to i's list, growing its room if needed. False when out of memory (nothing
 * changed). One thread. */
bool nbep_nblist_append(nbep_nblist *l, uint32_t i, uint32_t j);
/* Makes i's list js[0..m) (i's own list rebuilt): copied in place when its room holds m, else
 * as nbep_nblist_clear and m appends (the same moves and rooms). False when out of memory
 * (then as an append that failed: i's list holds a part). One thread. */
NBEP_MUST_CHECK bool nbep_nblist_set(nbep_nblist *l, uint32_t i, const uint32_t *js, size_t m);
/* Removes j from i's list, if it is there (the last entry takes its place): where it was, or
 * UINT32_MAX where it was not. One thread. */
uint32_t nbep_nblist_drop(nbep_nblist *l, uint32_t i, uint32_t j);
/* Undoes the nbep_nblist_drop(l, i, j) that returned q < UINT32_MAX, the last change of i's list
 * since: j at q again, the entry that took its place last again, so the list is as it was, its
 * order too (an optimistic engine's undo of a list rebuilt ahead: evloop.c). False when out of
 * memory (as an append that failed). One thread. */
NBEP_MUST_CHECK bool nbep_nblist_undrop(nbep_nblist *l, uint32_t i, uint32_t j, uint32_t q);
/* Undoes nbep_nblist_append(l, i, j), the last change of i's list since (j is its last entry):
 * j taken off; the room stays. */
static inline void nbep_nblist_unappend(nbep_nblist *l, uint32_t i, uint32_t j)
{
    assert(l->sp[i].cnt > 0 && l->pool[l->sp[i].off + l->sp[i].cnt - 1] == j);
    (void)j;
    l->sp[i].cnt--;
}
/* Empties i's list; its room stays. */
static inline void nbep_nblist_clear(nbep_nblist *l, uint32_t i)
{
    l->sp[i].cnt = 0;
}
/* Removes i from the list of every sphere in i's list, then empties i's list. One thread. */
void nbep_nblist_detach(nbep_nblist *l, uint32_t i);

/* i's list: *m entries. */
static inline const uint32_t *nbep_nblist_of(const nbep_nblist *l, uint32_t i, size_t *m)
{
    *m = l->sp[i].cnt;
    return l->pool + l->sp[i].off;
}

/* Entries the pool can still hand out before it must grow or be compacted: appends that
 * move lists needing no more than this in all leave the pool where it is (a reader of other
 * lists may go on reading them meanwhile). */
static inline size_t nbep_nblist_spare(const nbep_nblist *l)
{
    return l->pool_cap - l->pool_len;
}
/* The room a list of c entries gets at a layout or compaction: an eighth more and three (a
 * sphere's neighbour count drifts by a few between rebuilds of a dense fluid; a list that
 * outgrows its room moves). Two instead of three gave the same peak and looked slower at
 * phi 0.30 (1.07 in one paired run, 1.01 in the next); four gave 3 % more peak. */
static inline uint32_t nbep_nblist_room_for(uint32_t c)
{
    return c + c / 8u + 3u;
}
/* The room a full list of room cap moves to. */
static inline uint32_t nbep_nblist_grown(uint32_t cap)
{
    return cap + cap / 2u + 4u;
}
/* The most a list of m entries built from scratch, and n_gain other lists gaining one entry
 * each, can take of the spare. A gaining list moves at most once, to at most
 * nbep_nblist_grown(cap_max). The list built from scratch moves through rooms r_1 < ... <
 * r_k: r_k = r_(k-1) * 3/2 + 4 < 3 m / 2 + 4, as it moved from r_(k-1) < m, and each earlier
 * room is under 2/3 of the next, so together they are under 3 m: 9 m / 2 + 4 in all. */
static inline size_t nbep_nblist_need(const nbep_nblist *l, size_t m, size_t n_gain)
{
    return n_gain * (size_t)nbep_nblist_grown(l->cap_max) + 5u * m + 8u;
}
/* Arenas, for threads that change disjoint spheres' lists at once (the scheduled loop's slabs
 * on threads: evloop_warp.c): the pool's spare cut into pieces, one a thread, each reached
 * through a view of the lists whose moves go into its piece alone. A view shares the pool and
 * the spans (sp) with l and every other view; a thread changes only its own spheres' lists
 * through its own view, and moves only within its piece: an append that would move a list
 * past the piece fails (nothing changed) where the list proper would grow the pool, so a
 * caller first asks nbep_nblist_need of the view's nbep_nblist_spare. One thread, while no
 * view is in use: nbep_nblist_make_spare, nbep_nblist_arena, nbep_nblist_arena_back. */

/* Makes the pool's spare at least `spare` entries, compacting or growing it (the lists' offsets
 * may change; their contents and order do not). False without memory (nothing changed). */
NBEP_MUST_CHECK bool nbep_nblist_make_spare(nbep_nblist *l, size_t spare);
/* *a: a view of l whose moves go into pool entries [lo, hi) (within l's spare, past
 * l->pool_len; the caller hands each view its own piece and then marks them all handed out,
 * l->pool_len = the last hi). */
void nbep_nblist_arena(const nbep_nblist *l, size_t lo, size_t hi, nbep_nblist *a);
/* What view a changed of l's counts (its room's and cap_max, from `room0`, l's room when the
 * view was made) added into l; the view is done with (its piece's spare given up). */
void nbep_nblist_arena_back(nbep_nblist *l, const nbep_nblist *a, size_t room0);

/* Invariant check for tests: every list within its room and the pool, no sphere listing
 * itself or a sphere twice, and symmetry. Returns the number of violations. */
size_t nbep_nblist_check(const nbep_nblist *l);

/* Bytes for n spheres with `entries` neighbours in all, as laid out (pool slack included). */
size_t nbep_nblist_bytes(size_t n, size_t entries);

#endif
