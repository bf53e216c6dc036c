/* A uniform cell grid over sphere centres, rebuilt from scratch by a counting sort: the
 * neighbour search of the overlap check and of the predictive algorithm's "grid" mode. About
 * one cell per sphere at most, so memory stays O(n) whatever the layout. */
#ifndef NBEP_GRID_H
#define NBEP_GRID_H

#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

typedef struct nbep_grid {
    nbep_vec3 lo;          /* corner of cell (0,0,0) */
    double h, inv_h;       /* cell side */
    size_t dim[3];         /* cells per axis */
    size_t n;              /* spheres in the last build */
    uint32_t *start;       /* owned, cap_cells + 1: items of cell c are item[start[c]..start[c+1]) */
    uint32_t *item;        /* owned, cap_n: sphere ids by cell, ascending within a cell */
    uint32_t *cell;        /* owned, cap_n: each sphere's cell */
    uint32_t *fill;        /* owned, cap_cells: per-cell cursors of a build */
    size_t cap_n, cap_cells;
} nbep_grid;

/* Room for builds of up to n_max spheres (cells at most 2 n_max + 8). NBEP_ENOMEM. */
NBEP_MUST_CHECK nbep_status nbep_grid_init(nbep_grid *g, size_t n_max, nbep_diag *d);
/* Bytes nbep_grid_init(n_max) allocates, for memory estimates. */
size_t nbep_grid_bytes(size_t n_max);
/* Frees; safe on a zeroed grid. */
void nbep_grid_fini(nbep_grid *g);

/* Sorts the n centres pos into cells of side at least h_min (and large enough that the cells
 * over the centres' bounding box fit the room). Allocates nothing; O(n + cells). Not
 * thread-safe; queries afterwards may run in parallel. */
void nbep_grid_build(nbep_grid *g, const nbep_vec3 *pos, size_t n, double h_min);

/* The same build in parts, for threads that share it (grid mode builds its grid every step).
 * Every thread owns a range of spheres [lo_i, hi_i) and a range of cells [c_lo, c_hi) (of
 * nbep_grid_cells(g)); barriers between the steps:
 * 1. every thread: nbep_grid_bounds over its spheres, into its own lo/hi;
 * 2. one thread: nbep_grid_size from the union of the bounds;
 * 3. every thread: nbep_grid_assign over its spheres (their cells: the arithmetic);
 * 4. every thread: nbep_grid_count over its cells, returning the spheres in them; the totals
 *    of the threads before it, in thread order, are its offset;
 * 5. every thread: nbep_grid_place over its cells from that offset.
 * Counting and placing read every sphere's cell (one pass over 4 bytes a sphere each) and
 * write only the thread's own cells, in ascending sphere order: no atomics, and the result is
 * bit for bit nbep_grid_build's whatever the split into threads. */
void nbep_grid_bounds(const nbep_vec3 *pos, size_t lo_i, size_t hi_i, nbep_vec3 *lo,
                      nbep_vec3 *hi);
void nbep_grid_size(nbep_grid *g, nbep_vec3 lo, nbep_vec3 hi, size_t n, double h_min);
size_t nbep_grid_cells(const nbep_grid *g);
void nbep_grid_assign(nbep_grid *g, const nbep_vec3 *pos, size_t lo_i, size_t hi_i);
size_t nbep_grid_count(nbep_grid *g, size_t c_lo, size_t c_hi);
void nbep_grid_place(nbep_grid *g, size_t c_lo, size_t c_hi, size_t offset);

/* The block of cells [lo, hi] (inclusive, per axis) holding every centre within `reach` of p
 * (clamped to the grid). */
void nbep_grid_block(const nbep_grid *g, nbep_vec3 p, double reach, size_t lo[3],
                     size_t hi[3]);

/* Index of cell (x, y, z). */
static inline size_t nbep_grid_index(const nbep_grid *g, size_t x, size_t y, size_t z)
{
    return (z * g->dim[1] + y) * g->dim[0] + x;
}

#endif
