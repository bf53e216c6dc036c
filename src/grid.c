/* Uniform cell grid by counting sort (see grid.h). */
#include "nbep/grid.h"

#include <math.h>
#include <string.h>

nbep_status nbep_grid_init(nbep_grid *g, size_t n_max, nbep_diag *d)
{
    memset(g, 0, sizeof *g);
    g->cap_n = n_max;
    g->cap_cells = 2 * n_max + 8;
    g->start = nbep_alloc_aligned(g->cap_cells + 1, sizeof *g->start);
    g->item = nbep_alloc_aligned(n_max, sizeof *g->item);
    g->cell = nbep_alloc_aligned(n_max, sizeof *g->cell);
    if (!g->start || !g->item || !g->cell) {
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
    memset(g, 0, sizeof *g);
}

static size_t axis_cell(double x, double lo, double inv_h, size_t dim)
{
    double c = floor((x - lo) * inv_h);
    if (!(c > 0.0)) /* also NaN: a grid never crashes on bad input */
        return 0;
    return c >= (double)dim ? dim - 1 : (size_t)c;
}

void nbep_grid_build(nbep_grid *g, const nbep_vec3 *pos, size_t n, double h_min)
{
    g->n = n;
    nbep_vec3 lo = n ? pos[0] : (nbep_vec3){0, 0, 0}, hi = lo;
    for (size_t i = 1; i < n; i++) {
        lo.x = fmin(lo.x, pos[i].x), hi.x = fmax(hi.x, pos[i].x);
        lo.y = fmin(lo.y, pos[i].y), hi.y = fmax(hi.y, pos[i].y);
        lo.z = fmin(lo.z, pos[i].z), hi.z = fmax(hi.z, pos[i].z);
    }
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
    size_t cells = g->dim[0] * g->dim[1] * g->dim[2];
    memset(g->start, 0, (cells + 1) * sizeof *g->start);
    for (size_t i = 0; i < n; i++) {
        size_t c = nbep_grid_index(g, axis_cell(pos[i].x, lo.x, g->inv_h, g->dim[0]),
                                   axis_cell(pos[i].y, lo.y, g->inv_h, g->dim[1]),
                                   axis_cell(pos[i].z, lo.z, g->inv_h, g->dim[2]));
        g->cell[i] = (uint32_t)c;
        g->start[c + 1]++;
    }
    for (size_t c = 0; c < cells; c++)
        g->start[c + 1] += g->start[c];
    /* stable: ids ascend within a cell, so every walk is the same for any thread count */
    for (size_t i = 0; i < n; i++)
        g->item[g->start[g->cell[i]]++] = (uint32_t)i;
    for (size_t c = cells; c > 0; c--)
        g->start[c] = g->start[c - 1];
    g->start[0] = 0;
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
