/* Helpers of the tests that compile their own copy of the cells engine (src/evloop.c, included
 * before this): the lists and cells copied whole to compare, a workspace copied to keep. */
#ifndef NBEP_TEST_EVLOOP_H
#define NBEP_TEST_EVLOOP_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep_test_scene.h"

/* The lists and cells as they are: each list's length and entries in order, then every cell's
 * members in order (from its head), then every list centre's bits. */
typedef struct {
    uint32_t *w;
    size_t n, cap;
} words;

static inline void put(words *x, uint32_t v)
{
    if (x->n == x->cap) {
        x->cap = x->cap ? 2 * x->cap : 4096;
        x->w = realloc(x->w, x->cap * sizeof *x->w);
        assert_non_null(x->w);
    }
    x->w[x->n++] = v;
}

static inline void copy_of(const nbep_evloop *e, words *x)
{
    x->n = 0;
    for (uint32_t i = 0; i < e->n; i++) {
        size_t m;
        const uint32_t *js = nbep_nblist_of(&e->nl, i, &m);
        put(x, (uint32_t)m);
        for (size_t k = 0; k < m; k++)
            put(x, js[k]);
    }
    const nbep_cells *g = &e->cells;
    for (size_t c = 0; c < g->n_cells; c++) {
        for (uint32_t i = g->head[c]; i != NBEP_CELLS_NONE; i = g->m[i].next) {
            put(x, i);
            put(x, g->m[i].cell);
        }
        put(x, UINT32_MAX);
    }
    for (uint32_t i = 0; i < e->n; i++) {
        uint32_t b[6];
        memcpy(b, &g->m[i].at, sizeof b);
        for (int k = 0; k < 6; k++)
            put(x, b[k]);
        put(x, g->prev[i]);
    }
}

static inline bool same(const words *a, const words *b)
{
    return a->n == b->n && memcmp(a->w, b->w, a->n * sizeof *a->w) == 0;
}

/* What an expiry's apply and undo read of w, into d (the engine's copy: evloop.c) */
static inline void copy_ws(evl_ws *d, const evl_ws *w)
{
    assert_true(nbep__evloop_ws_copy_lists(d, w));
}

/* Whether cells d hold cell c as g do: the same members in the same order, their places bit
 * for bit, their cells and backward links (a slab's own copy of the cells against the run's:
 * ghost.c) */
static inline bool nbep_test_cell_same(const nbep_cells *d, const nbep_cells *g, size_t c)
{
    uint32_t a = d->head[c], b = g->head[c];
    for (; a != NBEP_CELLS_NONE && a == b; a = d->m[a].next, b = g->m[b].next)
        if (memcmp(&d->m[a].at, &g->m[b].at, sizeof d->m[a].at) != 0 ||
            d->m[a].cell != g->m[b].cell || d->prev[a] != g->prev[b])
            return false;
    return a == b;
}

/* The pile the expiry commits' tests run: 64 spheres of unequal masses dropped into a 1 x 1 x 3
 * box under gravity, e = 0.6, in cells mode: they land, lean on one another and settle (a
 * pile's let-go walks its lists in order). */
static inline nbep_scene *nbep_test_evloop_pile(void)
{
    nbep_scene *sc = nbep_test_scene_new(64, 6, "predictive", 400, 1e-3);
    sc->restitution = 0.6;
    sc->neighbors_cells = true;
    nbep_test_set_box_to(sc, (nbep_vec3){1.0, 1.0, 3.0});
    for (size_t i = 0; i < 64; i++) {
        const double x = 0.125 + 0.25 * (double)(i % 4), y = 0.125 + 0.25 * (double)(i / 4 % 4);
        const double z = 0.2 + 0.3 * (double)(i / 16), w = 0.3 * sin(1.7 * (double)i);
        nbep_test_set_sphere(sc, i, (nbep_vec3){x, y, z}, (nbep_vec3){w, -0.5 * w, -0.2 * w},
                             0.1, 1.0 + 0.01 * (double)i, (nbep_vec3){0, 0, -9.81});
    }
    return sc;
}

#endif
