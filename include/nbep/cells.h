/* Cell lists for the cells engine (evloop.c): the box is cut into cells at least `reach` wide
 * (the largest distance at which the caller looks for partners), and each sphere is a member
 * of exactly one cell, the one its place lies in. A place is the point the caller last
 * assigned or placed the sphere at (the engine: the centre of its neighbour list, which stays
 * put between the list's rebuilds); the cells never move a member by themselves. Two places
 * within reach of each other therefore lie in the same or adjacent cells (the 27-cell block
 * around either), so a search for a place's partners tests only that block. That holds up to
 * the rounding of locating a place (a few units in the last place of its cell coordinate,
 * nbep_cells_gap2): a caller that must find every pair within d lays the cells out for a reach
 * a hair above d (the engine's cutoff carries CUT_SLACK). Places past an outer face of an
 * axis that is not periodic (a list centre that leads its sphere past a wall, a sphere past
 * the extent the cells were fitted to) are clamped into the edge cells, which keeps the
 * adjacency.
 *
 * Periodic axes (box.periodic): the cells wrap around, so the first and last cells of such an
 * axis are neighbours. There are at least three cells along a periodic axis, so that a
 * neighbouring cell is one copy of the box only: a block names each neighbour cell with the
 * period it lies in (-1, 0, +1), and the sphere a search tests is at its place plus that many
 * box lengths. The caller wraps a place into the box along periodic axes before assigning or
 * placing it (periodic.h), as clamping would break the adjacency across the wrapped faces.
 *
 * Lists are doubly linked through per-sphere arrays (no allocation after init). A member's
 * place, its link to the next member and its cell share one 32-byte record, so that walking a
 * cell and testing its members' places touches one cache line half per member. Building is
 * split so that the heavy part runs in parallel: nbep_cells_assign is pure per sphere (any
 * index range on any thread), nbep_cells_link one O(n + cells) pass. Memory: 36 bytes per
 * sphere plus 4 per cell, cells at most 2n + 8. */
#ifndef NBEP_CELLS_H
#define NBEP_CELLS_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

#define NBEP_CELLS_NONE UINT32_MAX

typedef struct nbep_cells_member {
    nbep_vec3 at;          /* the member's place: where it was assigned or last placed */
    uint32_t next;         /* the next member of its cell, or NBEP_CELLS_NONE */
    uint32_t cell;         /* its cell */
} nbep_cells_member;

typedef struct nbep_cells {
    nbep_vec3 lo, hi;      /* the box */
    double h[3];           /* cell side per axis */
    size_t dim[3];         /* cells per axis */
    size_t n_cells, n;
    size_t cap_cells;      /* the cells head has room for */
    bool periodic[3];      /* the cells wrap around along that axis */
    uint32_t *head;        /* owned, n_cells: first member, or NBEP_CELLS_NONE */
    nbep_cells_member *m;  /* owned, n: each sphere's place, forward link and cell */
    uint32_t *prev;        /* owned, n: the backward links */
} nbep_cells;

/* Cells over the box [lo, hi] (hi > lo) for n spheres whose partners lie within `reach` of
 * each other (reach <= 0, as with no spheres: one cell): as many as fit with sides of at least
 * reach, at most 2n + 8 in all but never fewer than three along a periodic axis (periodic:
 * NULL for none; such an axis must be at least 3 reach long, which the deck check ensures).
 * NBEP_ENOMEM with a message. */
NBEP_MUST_CHECK nbep_status nbep_cells_init(nbep_cells *g, nbep_vec3 lo, nbep_vec3 hi,
                                            double reach, size_t n, const bool *periodic,
                                            nbep_diag *d);
/* The same cells laid out afresh over [lo, hi] (no periodic axis), for a scene without a box
 * whose spheres' extent changes: every member must be assigned and linked again. The head
 * array grows when the new layout has more cells than it holds (at most 2n + 8); NBEP_ENOMEM
 * with a message, the cells then unusable. */
NBEP_MUST_CHECK nbep_status nbep_cells_refit(nbep_cells *g, nbep_vec3 lo, nbep_vec3 hi,
                                             double reach, nbep_diag *d);
/* Frees; safe on a zeroed grid. */
void nbep_cells_fini(nbep_cells *g);

/* The cell holding point p (clamped into the box; NaN goes to cell 0). */
size_t nbep_cells_locate(const nbep_cells *g, nbep_vec3 p);
/* Assigns spheres [lo, hi) to the cells of their centres pos[] (their places); touches nothing
 * shared, so threads may assign disjoint ranges at once. */
void nbep_cells_assign(nbep_cells *g, const nbep_vec3 *pos, size_t lo, size_t hi);
/* Links every sphere into its assigned cell's list (ascending ids within a cell). One thread. */
void nbep_cells_link(nbep_cells *g);
/* Gives sphere i the place p, whose cell c = nbep_cells_locate(g, p) the caller has found (the
 * cells engine locates a rebuilt list's centre for its walk, then places it at the commit),
 * moving it into c if that is another. O(1). */
void nbep_cells_place(nbep_cells *g, uint32_t i, nbep_vec3 p, size_t c);
/* Undoes an nbep_cells_place of sphere i, the last change of its cells since: its place p
 * again, and where the place moved it, its cell c again after the member `prev` that was before
 * it there (g->prev[i] before the place; NBEP_CELLS_NONE: first), so that every cell's order is
 * as it was (an optimistic engine's undo of a list rebuilt ahead: evloop.c). O(1). */
void nbep_cells_put_back(nbep_cells *g, uint32_t i, nbep_vec3 p, size_t c, uint32_t prev);

/* The block around cell c: per axis k, cnt[k] (1 to 3) cell coordinates idx[k][] (c's and its
 * neighbours', clamped at walls, wrapped on periodic axes) and the period each lies in,
 * per[k][] (-1 below the box, +1 above, else 0). Every cell of the block is
 * (idx[0][a], idx[1][b], idx[2][c]) and lies per[0][a], per[1][b], per[2][c] periods away. */
typedef struct nbep_cells_block {
    size_t idx[3][3];
    int per[3][3];
    int cnt[3];
} nbep_cells_block;
void nbep_cells_block_of(const nbep_cells *g, size_t c, nbep_cells_block *b);

/* The square of how far coordinate x (along axis k) lies from the slab of the cells with
 * coordinate idx along k, the slab grown by a 64th of a side at each face and open past an
 * outer face of an axis that is not periodic (places there are clamped into the edge cell):
 * no member's place in those cells is nearer x along k. (nbep_cells_locate puts a place in
 * the cell its coordinates fall in to within a few roundings, which the 64th covers many times
 * over, so a search that skips cells by this bound skips no place it would have found.) */
static inline double nbep_cells_gap2(const nbep_cells *g, int k, size_t idx, double x)
{
    const double o = k == 0 ? g->lo.x : k == 1 ? g->lo.y : g->lo.z, s = g->h[k] / 64.0;
    const double lo = idx > 0 || g->periodic[k] ? o + (double)idx * g->h[k] - s : -INFINITY;
    const double hi =
        idx + 1 < g->dim[k] || g->periodic[k] ? o + (double)(idx + 1) * g->h[k] + s : INFINITY;
    const double d = x < lo ? lo - x : x > hi ? x - hi : 0.0;
    return d * d;
}

/* Index of cell (x, y, z). */
static inline size_t nbep_cells_index(const nbep_cells *g, size_t x, size_t y, size_t z)
{
    return (z * g->dim[1] + y) * g->dim[0] + x;
}

/* Invariant check for tests: each sphere is listed once, in the cell it is assigned to, and
 * that cell is the one its place lies in (nbep_cells_locate). Returns the number of
 * violations. */
size_t nbep_cells_check(const nbep_cells *g);

/* The fewest cells along a periodic axis, so that a neighbour is one image only. */
#define NBEP_CELLS_PERIODIC_MIN 3

/* Bytes nbep_cells_init takes at most for n spheres. */
size_t nbep_cells_bytes(size_t n);

#endif
