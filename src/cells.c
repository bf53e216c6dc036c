/* Cell lists (see cells.h). */
#include "nbep/cells.h"

#include <assert.h>
#include <math.h>
#include <string.h>

size_t nbep_cells_bytes(size_t n)
{
    /* lay_out's cells: at most 2 n + 8, or a periodic box's least, 3^3 (nbep_cells_init: the
     * heads, a member and a link per sphere, one at least) */
    const size_t p = NBEP_CELLS_PERIODIC_MIN, least = p * p * p;
    const size_t cells = 2 * n + 8 > least ? 2 * n + 8 : least, m = n ? n : 1;
    return cells * sizeof(uint32_t) + m * (sizeof(nbep_cells_member) + sizeof(uint32_t));
}

/* The cells' layout over [lo, hi] (sides, counts): see nbep_cells_init. */
static void lay_out(nbep_cells *g, nbep_vec3 lo, nbep_vec3 hi, double reach)
{
    g->lo = lo;
    g->hi = hi;
    const double ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    const double cap = 2.0 * (double)g->n + 8.0;
    /* no contacts possible (no spheres: reach 0): one cell per axis */
    const double base =
        reach > 0.0 && isfinite(reach) ? reach : fmax(ext[0], fmax(ext[1], ext[2])) + 1.0;
    double side[3] = {base, base, base};
    double least[3];
    for (int k = 0; k < 3; k++)
        least[k] = g->periodic[k] ? NBEP_CELLS_PERIODIC_MIN : 1.0;
    /* too many cells: the side of the axis with the most doubles until they fit (at least
     * halving the count each pass), or until no axis can take fewer (a periodic box's least:
     * the cells are then at most 2 n + 8 or that, nbep_cells_bytes). Axis by axis, not all at
     * once: a region stretched along one axis (a scene without a box, one sphere flown far
     * off) keeps cells of the reach across the others, so the rest of its spheres do not all
     * share a few coarse cells. */
    double count[3];
    for (;;) {
        double cells = 1.0, most = 0.0;
        int widest = -1;
        for (int k = 0; k < 3; k++) {
            count[k] = fmax(least[k], floor(ext[k] / side[k]));
            cells *= count[k];
            if (count[k] > least[k] && count[k] > most) {
                most = count[k];
                widest = k;
            }
        }
        if (cells <= cap || widest < 0)
            break;
        side[widest] *= 2.0;
    }
    g->n_cells = 1;
    for (int k = 0; k < 3; k++) {
        g->dim[k] = (size_t)count[k];
        g->h[k] = ext[k] / count[k];
        g->n_cells *= g->dim[k];
    }
}

nbep_status nbep_cells_init(nbep_cells *g, nbep_vec3 lo, nbep_vec3 hi, double reach, size_t n,
                            const bool *periodic, nbep_diag *d)
{
    memset(g, 0, sizeof *g);
    for (int k = 0; k < 3; k++)
        g->periodic[k] = periodic && periodic[k];
    g->n = n;
    lay_out(g, lo, hi, reach);
    g->cap_cells = g->n_cells;
    g->head = nbep_alloc_aligned(g->n_cells, sizeof *g->head);
    g->m = nbep_alloc_aligned(n ? n : 1, sizeof *g->m);
    g->prev = nbep_alloc_aligned(n ? n : 1, sizeof *g->prev);
    if (!g->head || !g->m || !g->prev) {
        nbep_cells_fini(g);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for cell lists of %zu spheres", n);
    }
    return NBEP_OK;
}

nbep_status nbep_cells_refit(nbep_cells *g, nbep_vec3 lo, nbep_vec3 hi, double reach,
                             nbep_diag *d)
{
    assert(!g->periodic[0] && !g->periodic[1] && !g->periodic[2]);
    lay_out(g, lo, hi, reach);
    if (g->n_cells > g->cap_cells) {
        nbep_free_aligned(g->head);
        g->head = nbep_alloc_aligned(g->n_cells, sizeof *g->head);
        g->cap_cells = g->head ? g->n_cells : 0;
        if (!g->head)
            NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for %zu cells", g->n_cells);
    }
    return NBEP_OK;
}

void nbep_cells_fini(nbep_cells *g)
{
    if (!g)
        return;
    nbep_free_aligned(g->head);
    nbep_free_aligned(g->m);
    nbep_free_aligned(g->prev);
    memset(g, 0, sizeof *g);
}

static size_t axis_cell(double x, double lo, double h, size_t dim)
{
    double c = floor((x - lo) / h);
    if (!(c > 0.0)) /* also NaN */
        return 0;
    return c >= (double)dim ? dim - 1 : (size_t)c;
}

size_t nbep_cells_locate(const nbep_cells *g, nbep_vec3 p)
{
    return nbep_cells_index(g, axis_cell(p.x, g->lo.x, g->h[0], g->dim[0]),
                            axis_cell(p.y, g->lo.y, g->h[1], g->dim[1]),
                            axis_cell(p.z, g->lo.z, g->h[2], g->dim[2]));
}

void nbep_cells_assign(nbep_cells *g, const nbep_vec3 *pos, size_t lo, size_t hi)
{
    for (size_t i = lo; i < hi; i++) {
        g->m[i].at = pos[i];
        g->m[i].cell = (uint32_t)nbep_cells_locate(g, pos[i]);
    }
}

static void link_in(nbep_cells *g, uint32_t i, size_t c)
{
    g->m[i].cell = (uint32_t)c;
    g->prev[i] = NBEP_CELLS_NONE;
    g->m[i].next = g->head[c];
    if (g->head[c] != NBEP_CELLS_NONE)
        g->prev[g->head[c]] = i;
    g->head[c] = i;
}

void nbep_cells_link(nbep_cells *g)
{
    for (size_t c = 0; c < g->n_cells; c++)
        g->head[c] = NBEP_CELLS_NONE;
    for (size_t i = g->n; i-- > 0;) /* head insertion, downwards: ids ascend in a list */
        link_in(g, (uint32_t)i, g->m[i].cell);
}

/* Takes sphere i out of its cell's list. O(1). */
static void unlink_member(nbep_cells *g, uint32_t i)
{
    const uint32_t nx = g->m[i].next;
    if (g->prev[i] != NBEP_CELLS_NONE)
        g->m[g->prev[i]].next = nx;
    else
        g->head[g->m[i].cell] = nx;
    if (nx != NBEP_CELLS_NONE)
        g->prev[nx] = g->prev[i];
}

/* Moves sphere i into cell c (its place unchanged). O(1). */
static void move_member(nbep_cells *g, uint32_t i, size_t c)
{
    unlink_member(g, i);
    link_in(g, i, c);
}

void nbep_cells_place(nbep_cells *g, uint32_t i, nbep_vec3 p, size_t c)
{
    assert(c < g->n_cells);
    g->m[i].at = p;
    if (c != g->m[i].cell)
        move_member(g, i, c);
}

void nbep_cells_put_back(nbep_cells *g, uint32_t i, nbep_vec3 p, size_t c, uint32_t prev)
{
    assert(c < g->n_cells);
    g->m[i].at = p;
    if (c == g->m[i].cell) /* the place left it in its cell (and in its order there) */
        return;
    unlink_member(g, i);
    assert(prev == NBEP_CELLS_NONE || g->m[prev].cell == c);
    const uint32_t nx = prev == NBEP_CELLS_NONE ? g->head[c] : g->m[prev].next;
    g->m[i].cell = (uint32_t)c;
    g->prev[i] = prev;
    g->m[i].next = nx;
    if (nx != NBEP_CELLS_NONE)
        g->prev[nx] = i;
    if (prev == NBEP_CELLS_NONE)
        g->head[c] = i;
    else
        g->m[prev].next = i;
}

static void cell_coords(const nbep_cells *g, size_t c, size_t xyz[3])
{
    xyz[0] = c % g->dim[0];
    xyz[1] = c / g->dim[0] % g->dim[1];
    xyz[2] = c / (g->dim[0] * g->dim[1]);
}

void nbep_cells_block_of(const nbep_cells *g, size_t c, nbep_cells_block *b)
{
    size_t xyz[3];
    cell_coords(g, c, xyz);
    for (int k = 0; k < 3; k++) {
        int m = 0;
        if (xyz[k] > 0) {
            b->idx[k][m] = xyz[k] - 1;
            b->per[k][m++] = 0;
        } else if (g->periodic[k]) {
            b->idx[k][m] = g->dim[k] - 1;
            b->per[k][m++] = -1;
        }
        b->idx[k][m] = xyz[k];
        b->per[k][m++] = 0;
        if (xyz[k] + 1 < g->dim[k]) {
            b->idx[k][m] = xyz[k] + 1;
            b->per[k][m++] = 0;
        } else if (g->periodic[k]) {
            b->idx[k][m] = 0;
            b->per[k][m++] = 1;
        }
        b->cnt[k] = m;
    }
}

size_t nbep_cells_check(const nbep_cells *g)
{
    size_t bad = 0, listed = 0;
    for (size_t c = 0; c < g->n_cells; c++) {
        uint32_t before = NBEP_CELLS_NONE;
        for (uint32_t i = g->head[c]; i != NBEP_CELLS_NONE; i = g->m[i].next) {
            if (i >= g->n || g->m[i].cell != c || g->prev[i] != before || ++listed > g->n)
                return bad + 1; /* a broken list: stop before looping forever */
            before = i;
            bad += nbep_cells_locate(g, g->m[i].at) != c;
        }
    }
    return bad + (listed != g->n);
}
