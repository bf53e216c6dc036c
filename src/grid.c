/* Uniform cell grid by counting sort (see grid.h). */
#include "nbep/grid.h"

#include <math.h>
#include <string.h>

/* At most this many cells for n_max spheres: about one per sphere or fewer, so memory stays
 * O(n) whatever the layout. */
static size_t cap_cells(size_t n_max)
{
    return 2 * n_max + 8;
}

size_t nbep_grid_bytes(size_t n_max)
{
    const nbep_grid *g = NULL; /* for the element sizes only (sizeof does not evaluate) */
    const size_t cells = cap_cells(n_max);
    return (cells + 1) * sizeof *g->start + cells * sizeof *g->fill +
           n_max * (sizeof *g->item + sizeof *g->cell);
}

nbep_status nbep_grid_init(nbep_grid *g, size_t n_max, nbep_diag *d)
{
    memset(g, 0, sizeof *g);
    g->cap_n = n_max;
    g->cap_cells = cap_cells(n_max);
    g->start = nbep_alloc_aligned(g->cap_cells + 1, sizeof *g->start);
    g->item = nbep_alloc_aligned(n_max, sizeof *g->item);
    g->cell = nbep_alloc_aligned(n_max, sizeof *g->cell);
    g->fill = nbep_alloc_aligned(g->cap_cells, sizeof *g->fill);
    if (!g->start || !g->item || !g->cell || !g->fill) {
        nbep_grid_fini(g);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for a cell grid of %zu spheres", n_max);
    }
    return NBEP_OK;
}

void nbep_grid_fini(nbep_grid *g)
{
    if (!g)
        return;
    nbep_free_aligned(g->start);
    nbep_free_aligned(g->item);
    nbep_free_aligned(g->cell);
    nbep_free_aligned(g->fill);
    memset(g, 0, sizeof *g);
}

static size_t axis_cell(double x, double lo, double inv_h, size_t dim)
{
    double c = floor((x - lo) * inv_h);
    if (!(c > 0.0)) /* also NaN: a grid never crashes on bad input */
        return 0;
    return c >= (double)dim ? dim - 1 : (size_t)c;
}

void nbep_grid_bounds(const nbep_vec3 *pos, size_t lo_i, size_t hi_i, nbep_vec3 *lo,
                      nbep_vec3 *hi)
{
    /* compares, not fmin/fmax (libm calls): a NaN centre is left out of the bounds, and
     * axis_cell puts it in cell 0 */
    nbep_vec3 l = {INFINITY, INFINITY, INFINITY}, h = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = lo_i; i < hi_i; i++) {
        const nbep_vec3 p = pos[i];
        l.x = p.x < l.x ? p.x : l.x, h.x = p.x > h.x ? p.x : h.x;
        l.y = p.y < l.y ? p.y : l.y, h.y = p.y > h.y ? p.y : h.y;
        l.z = p.z < l.z ? p.z : l.z, h.z = p.z > h.z ? p.z : h.z;
    }
    *lo = l;
    *hi = h;
}

void nbep_grid_size(nbep_grid *g, nbep_vec3 lo, nbep_vec3 hi, size_t n, double h_min)
{
    g->n = n;
    if (!(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z)) /* no centre: one cell at 0 */
        lo = hi = (nbep_vec3){0, 0, 0};
    double ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    double h = h_min > 0.0 && isfinite(h_min) ? h_min : 1.0;
    /* Grow h until the cells over the box fit the room (at most about 2n + 8): each pass at
     * least doubles the cell volume, so this ends quickly. */
    for (;;) {
        double cells = 1.0;
        for (int k = 0; k < 3; k++)
            cells *= floor(ext[k] / h) + 1.0;
        if (cells <= (double)g->cap_cells && isfinite(cells))
            break;
        h = fmax(2.0 * h, cbrt(ext[0] * ext[1] * ext[2] / (double)(g->cap_cells / 2 + 1)));
        if (!isfinite(h)) {
            h = INFINITY;
            break;
        }
    }
    g->lo = lo;
    g->h = h;
    g->inv_h = isfinite(h) ? 1.0 / h : 0.0;
    for (int k = 0; k < 3; k++)
        g->dim[k] = isfinite(h) ? (size_t)(floor(ext[k] / h) + 1.0) : 1;
}

size_t nbep_grid_cells(const nbep_grid *g)
{
    return g->dim[0] * g->dim[1] * g->dim[2];
}

void nbep_grid_assign(nbep_grid *g, const nbep_vec3 *pos, size_t lo_i, size_t hi_i)
{
    for (size_t i = lo_i; i < hi_i; i++)
        g->cell[i] = (uint32_t)nbep_grid_index(
            g, axis_cell(pos[i].x, g->lo.x, g->inv_h, g->dim[0]),
            axis_cell(pos[i].y, g->lo.y, g->inv_h, g->dim[1]),
            axis_cell(pos[i].z, g->lo.z, g->inv_h, g->dim[2]));
}

size_t nbep_grid_count(nbep_grid *g, size_t c_lo, size_t c_hi)
{
    for (size_t c = c_lo; c < c_hi; c++)
        g->fill[c] = 0;
    for (size_t i = 0; i < g->n; i++) {
        const size_t c = g->cell[i];
        if (c >= c_lo && c < c_hi)
            g->fill[c]++;
    }
    size_t sum = 0;
    for (size_t c = c_lo; c < c_hi; c++)
        sum += g->fill[c];
    return sum;
}

void nbep_grid_place(nbep_grid *g, size_t c_lo, size_t c_hi, size_t offset)
{
    /* start[c]: the spheres before cell c; fill[c] becomes cell c's cursor */
    for (size_t c = c_lo; c < c_hi; c++) {
        const uint32_t k = g->fill[c];
        g->start[c] = g->fill[c] = (uint32_t)offset;
        offset += k;
    }
    if (c_hi == nbep_grid_cells(g))
        g->start[c_hi] = (uint32_t)offset;
    /* ascending ids within a cell, so every walk is the same for any thread count */
    for (size_t i = 0; i < g->n; i++) {
        const size_t c = g->cell[i];
        if (c >= c_lo && c < c_hi)
            g->item[g->fill[c]++] = (uint32_t)i;
    }
}

void nbep_grid_build(nbep_grid *g, const nbep_vec3 *pos, size_t n, double h_min)
{
    nbep_vec3 lo, hi;
    nbep_grid_bounds(pos, 0, n, &lo, &hi);
    nbep_grid_size(g, lo, hi, n, h_min);
    nbep_grid_assign(g, pos, 0, n);
    const size_t cells = nbep_grid_cells(g);
    (void)nbep_grid_count(g, 0, cells);
    nbep_grid_place(g, 0, cells, 0);
}

void nbep_grid_block(const nbep_grid *g, nbep_vec3 p, double reach, size_t lo[3],
                     size_t hi[3])
{
    const double x[3] = {p.x, p.y, p.z}, o[3] = {g->lo.x, g->lo.y, g->lo.z};
    for (int k = 0; k < 3; k++) {
        lo[k] = axis_cell(x[k] - reach, o[k], g->inv_h, g->dim[k]);
        hi[k] = axis_cell(x[k] + reach, o[k], g->inv_h, g->dim[k]);
    }
}
