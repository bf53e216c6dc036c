/* Ghost cells (docs/optimistic-design.md, *Ghost cells*): a slab's own copy of the cells of
 * the list centres, which its expiries' walks read instead of the run's, so that no slab
 * reads cells another slab's thread writes. The copy is exact on the slab's own cell columns
 * across x and on the columns beside them (the columns a walk from a centre in the slab's
 * columns reads), and only there: the slab's own commits place its spheres in it
 * (nbep_cells_place), and every commit of another slab that moves a centre from or to a cell
 * the slab keeps so sends it a cell message, which it makes in its copy in stamp order among
 * its own changes and undoes, newest first, on a rollback. A cell's order is its history of
 * places (each puts its sphere first in its new cell), so the same places in the same order
 * give the same members in the same order. Tested against the run's cells at every commit of
 * a fluid and a pile, singly and in runs undone as a rollback does (tests/test_listmsg.c), and
 * read by the slabs' loop (evloop_warp.c: each slab's view has its own copy; the slabs' test
 * compares each copy with the run's cells at window openings). */
#include "evloop_impl.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

bool nbep__ghost_keeps(const nbep_cells *g, int slabs, int slab, size_t c)
{
    const size_t column = c % g->dim[0];
    for (int dc = -1; dc <= 1; dc++)
        if (nbep__column_slab(g->dim[0], g->periodic[0], slabs, column, dc) == slab)
            return true;
    return false;
}

uint64_t nbep__ghost_receivers(const nbep_cells *g, int slabs, int from, size_t was, size_t now)
{
    assert(slabs >= 1 && slabs <= NBEP_SLABCAL_MAX);
    uint64_t to = 0;
    for (int s = 0; s < slabs; s++)
        if (s != from &&
            (nbep__ghost_keeps(g, slabs, s, was) || nbep__ghost_keeps(g, slabs, s, now)))
            to |= UINT64_C(1) << s;
    return to;
}

void nbep__ghost_apply(nbep_cells *g, evl_cellmsg *m)
{
    m->old_at = g->m[m->item].at;
    m->old_cell = g->m[m->item].cell;
    m->old_prev = g->prev[m->item];
    nbep_cells_place(g, m->item, m->at, m->cell);
}

void nbep__ghost_unapply(nbep_cells *g, const evl_cellmsg *m)
{
    nbep_cells_put_back(g, m->item, m->old_at, m->old_cell, m->old_prev);
}

bool nbep__ghost_copy(nbep_cells *d, const nbep_cells *g)
{
    if (!d->m || d->n != g->n || d->cap_cells < g->n_cells) { /* (made anew: another layout) */
        nbep_cells_fini(d);
        d->head = nbep_alloc_aligned(g->cap_cells, sizeof *d->head);
        d->m = nbep_alloc_aligned(g->n, sizeof *d->m);
        d->prev = nbep_alloc_aligned(g->n, sizeof *d->prev);
        if (!d->head || !d->m || !d->prev) {
            nbep_cells_fini(d);
            return false;
        }
        d->cap_cells = g->cap_cells;
    }
    uint32_t *head = d->head;
    nbep_cells_member *m = d->m;
    uint32_t *prev = d->prev;
    const size_t cap_cells = d->cap_cells;
    *d = *g; /* (the layout) */
    d->head = head;
    d->m = m;
    d->prev = prev;
    d->cap_cells = cap_cells;
    memcpy(d->head, g->head, g->n_cells * sizeof *d->head);
    memcpy(d->m, g->m, g->n * sizeof *d->m);
    memcpy(d->prev, g->prev, g->n * sizeof *d->prev);
    return true;
}
