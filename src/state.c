/* Sphere and plane arrays (struct of arrays) and the invariant checks on them: finiteness and
 * the largest overlap, the latter with a uniform cell grid so that it is O(n), not O(n^2). */
#include "nbep/state.h"

#include "nbep/grid.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

size_t nbep_state_bytes(size_t n, size_t n_planes)
{
    return n * (3 * sizeof(nbep_vec3) + 2 * sizeof(double) + 3 * sizeof(int32_t)) +
           n_planes * (sizeof(nbep_vec3) + sizeof(double));
}

nbep_status nbep_state_init(nbep_state *s, size_t n, size_t n_planes, nbep_diag *d)
{
    memset(s, 0, sizeof *s);
    s->pos = nbep_alloc_aligned(n, sizeof *s->pos);
    s->vel = nbep_alloc_aligned(n, sizeof *s->vel);
    s->acc = nbep_alloc_aligned(n, sizeof *s->acc);
    s->radius = nbep_alloc_aligned(n, sizeof *s->radius);
    s->mass = nbep_alloc_aligned(n, sizeof *s->mass);
    s->image = nbep_alloc_aligned(3 * n, sizeof *s->image);
    s->plane_normal = nbep_alloc_aligned(n_planes, sizeof *s->plane_normal);
    s->plane_offset = nbep_alloc_aligned(n_planes, sizeof *s->plane_offset);
    if (!s->pos || !s->vel || !s->acc || !s->radius || !s->mass || !s->image || !s->plane_normal ||
        !s->plane_offset) {
        nbep_state_fini(s);
        char size[NBEP_BYTES_TEXT_MAX];
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for %zu spheres (%s)", n,
                  nbep_format_bytes((double)nbep_state_bytes(n, n_planes), size));
    }
    memset(s->image, 0, 3 * n * sizeof *s->image);
    s->n = n;
    s->n_planes = n_planes;
    return NBEP_OK;
}

void nbep_state_fini(nbep_state *s)
{
    if (!s)
        return;
    nbep_free_aligned(s->pos);
    nbep_free_aligned(s->vel);
    nbep_free_aligned(s->acc);
    nbep_free_aligned(s->radius);
    nbep_free_aligned(s->mass);
    nbep_free_aligned(s->image);
    nbep_free_aligned(s->plane_normal);
    nbep_free_aligned(s->plane_offset);
    memset(s, 0, sizeof *s);
}

nbep_status nbep_state_copy(nbep_state *dst, const nbep_state *src, nbep_diag *d)
{
    nbep_status st = nbep_state_init(dst, src->n, src->n_planes, d);
    if (st != NBEP_OK)
        return st;
    size_t n = src->n, p = src->n_planes;
    memcpy(dst->pos, src->pos, n * sizeof *dst->pos);
    memcpy(dst->vel, src->vel, n * sizeof *dst->vel);
    memcpy(dst->acc, src->acc, n * sizeof *dst->acc);
    memcpy(dst->radius, src->radius, n * sizeof *dst->radius);
    memcpy(dst->mass, src->mass, n * sizeof *dst->mass);
    memcpy(dst->image, src->image, 3 * n * sizeof *dst->image);
    memcpy(dst->period, src->period, sizeof dst->period);
    memcpy(dst->plane_normal, src->plane_normal, p * sizeof *dst->plane_normal);
    memcpy(dst->plane_offset, src->plane_offset, p * sizeof *dst->plane_offset);
    return NBEP_OK;
}

void nbep_state_take(nbep_state *dst, nbep_state *src)
{
    *dst = *src;
    src->pos = src->vel = src->acc = NULL;
    src->radius = src->mass = NULL;
    src->image = NULL;
    src->plane_normal = NULL;
    src->plane_offset = NULL;
}

bool nbep_state_all_finite(const nbep_state *s)
{
    for (size_t i = 0; i < s->n; i++)
        if (!nbep_vec3_isfinite(s->pos[i]) || !nbep_vec3_isfinite(s->vel[i]) ||
            !nbep_vec3_isfinite(s->acc[i]))
            return false;
    return true;
}

double nbep_state_max_radius(const nbep_state *s)
{
    double rmax = 0.0;
    for (size_t i = 0; i < s->n; i++)
        rmax = fmax(rmax, s->radius[i]);
    return rmax;
}

bool nbep_state_free_flight(const nbep_state *s)
{
    bool flies_free = true;
    for (size_t i = 0; i < s->n; i++)
        flies_free &= s->acc[i].x == 0.0 && s->acc[i].y == 0.0 && s->acc[i].z == 0.0;
    return flies_free;
}

static void consider(double overlap, double rmin, size_t i, size_t j, nbep_overlap *b)
{
    if (overlap > b->max) {
        b->max = overlap;
        b->i = i;
        b->j = j;
    }
    if (overlap > 0.0 && overlap / rmin > b->rel)
        b->rel = overlap / rmin;
}

/* The offsets of sphere i's copies whose reach can meet a centre in the grid g's extent: none
 * (0) always, and on a periodic axis (period > 0) the period either way where the copy's reach
 * still meets the extent (near a face: centres are only wrapped into the box at times, so the
 * extent may be a little wider than the box). Returns how many, into off[axis][k]. */
static void copy_offsets(const nbep_state *s, const nbep_grid *g, nbep_vec3 p, double reach,
                         double off[3][3], int cnt[3])
{
    const double x[3] = {p.x, p.y, p.z}, lo[3] = {g->lo.x, g->lo.y, g->lo.z};
    for (int a = 0; a < 3; a++) {
        const double hi = lo[a] + (double)g->dim[a] * g->h, per = s->period[a];
        cnt[a] = 0;
        off[a][cnt[a]++] = 0.0;
        if (per > 0.0 && x[a] + per - reach <= hi)
            off[a][cnt[a]++] = per;
        if (per > 0.0 && x[a] - per + reach >= lo[a])
            off[a][cnt[a]++] = -per;
    }
}

double nbep_state_overlap_grid(const nbep_state *s, nbep_grid *g)
{
    /* Cells at least a diameter wide: overlapping pairs sit in neighbouring cells, or in a
     * periodic box in cells next to a sphere's copy across a face (the nearest way round: a
     * periodic side is over two diameters, so one copy of a partner is within reach at
     * most). */
    const double rmax = nbep_state_max_radius(s);
    if (s->n > 1)
        nbep_grid_build(g, s->pos, s->n, 2.0 * rmax);
    return rmax;
}

void nbep_state_overlap_part(const nbep_state *s, const nbep_grid *g, double rmax, size_t lo,
                             size_t hi, nbep_overlap *best)
{
    const size_t n = s->n;
    for (size_t i = lo; i < hi; i++)
        for (size_t p = 0; p < s->n_planes; p++) {
            double gap = nbep_vec3_dot(s->plane_normal[p], s->pos[i]) - s->plane_offset[p] -
                         s->radius[i];
            consider(-gap, s->radius[i], i, n + p, best);
        }
    if (n < 2)
        return;
    for (size_t i = lo; i < hi; i++) {
        const double reach = s->radius[i] + rmax;
        double off[3][3];
        int cnt[3];
        copy_offsets(s, g, s->pos[i], reach, off, cnt);
        for (int u = 0; u < cnt[0] * cnt[1] * cnt[2]; u++) {
            /* copy u of i: a pair is met once from i (j > i) unmoved, from either sphere
             * across a face (the largest overlap is the same) */
            const nbep_vec3 shift =
                nbep_vec3_make(off[0][u % cnt[0]], off[1][u / cnt[0] % cnt[1]],
                               off[2][u / (cnt[0] * cnt[1])]);
            const bool moved = u > 0;
            size_t blo[3], bhi[3];
            nbep_grid_block(g, nbep_vec3_add(s->pos[i], shift), reach, blo, bhi);
            for (size_t z = blo[2]; z <= bhi[2]; z++)
                for (size_t y = blo[1]; y <= bhi[1]; y++)
                    for (size_t x = blo[0]; x <= bhi[0]; x++) {
                        size_t c = nbep_grid_index(g, x, y, z);
                        for (size_t k = g->start[c]; k < g->start[c + 1]; k++) {
                            size_t j = g->item[k];
                            if (moved ? j == i : j <= i)
                                continue;
                            /* as the engine takes an image: the centres' difference, less
                             * whole periods */
                            const nbep_vec3 dv =
                                nbep_vec3_sub(nbep_vec3_sub(s->pos[j], s->pos[i]), shift);
                            const double sum = s->radius[i] + s->radius[j];
                            const double d2 = nbep_vec3_norm2(dv);
                            /* most pairs are apart by far: no root for them (a margin of
                             * 1e-12 over the rounding of the squares, so that every pair the
                             * root could find overlapping is taken) */
                            if (d2 > sum * sum * (1.0 + 1e-12))
                                continue;
                            consider(sum - sqrt(d2), fmin(s->radius[i], s->radius[j]), i, j,
                                     best);
                        }
                    }
        }
    }
}

nbep_status nbep_state_max_overlap(const nbep_state *s, nbep_grid *ws, double *max_out,
                                   double *rel_out, size_t *i_out, size_t *j_out, nbep_diag *d)
{
    nbep_overlap best = NBEP_OVERLAP_NONE;
    nbep_grid own = {0}, *g = ws;
    if (!g && s->n > 1) {
        nbep_status st = nbep_grid_init(&own, s->n, d);
        if (st != NBEP_OK)
            return st;
        g = &own;
    }
    const double rmax = nbep_state_overlap_grid(s, g);
    nbep_state_overlap_part(s, g, rmax, 0, s->n, &best);
    nbep_grid_fini(&own); /* safe on the zeroed grid when ws was given */
    *max_out = best.max;
    if (rel_out)
        *rel_out = best.rel;
    if (i_out)
        *i_out = best.i;
    if (j_out)
        *j_out = best.j;
    return NBEP_OK;
}
