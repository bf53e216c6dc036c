/* Lists by message (docs/optimistic-design.md, *Lists by message*): an expiry's commit cut by
 * slab, so that a slab changes only its own spheres' lists and tells each other slab what to
 * change in its own. The sender makes its part (nbep__evloop_apply_part: its sphere's own list,
 * centre and cell, and its own neighbours' lists) and one message a slab; each receiver makes
 * the message's changes among its other changes in stamp order and undoes them, newest first,
 * on a rollback. Each list has at most one change of a commit (the sphere enters it or leaves
 * it), so cutting the commit this way changes no list's contents or order: tested against the
 * whole commit on a fluid and a pile, singly and in runs undone as a rollback does
 * (tests/test_listmsg.c). Not yet used by a run. Both sides assume what the loop's rules give:
 * a neighbour's slab is the same at a commit's undo as at its making (a move waits for the
 * meeting), and a message whose apply failed (no memory: the run fails) is never undone. */
#include "evloop_impl.h"

#include <assert.h>
#include <stdlib.h>

#include "nbep/compiler.h"

/* Room for need elements of elem bytes in *p (room *cap); false without memory (as it was). */
static bool room(void **p, size_t *cap, size_t need, size_t elem)
{
    while (*cap < need)
        if (!nbep_room_grow(p, cap, *cap, elem))
            return false;
    return true;
}

bool nbep__listmsg_split(const nbep_evloop *e, const evl_ws *w, int slabs, evl_split *sp)
{
    assert(slabs >= 1 && slabs <= NBEP_SLABCAL_MAX);
    if (!room((void **)&sp->near, &sp->cap_near, w->n_near, 1) ||
        !room((void **)&sp->was, &sp->cap_was, w->n_was, 1))
        return false;
    for (size_t k = 0; k < w->n_near; k++)
        sp->near[k] = (uint8_t)nbep__evloop_slab_in(e, w->near[k], slabs);
    for (size_t k = 0; k < w->n_was; k++)
        sp->was[k] = (uint8_t)nbep__evloop_slab_in(e, w->was[k], slabs);
    return true;
}

void nbep__listmsg_split_fini(evl_split *sp)
{
    free(sp->near);
    free(sp->was);
    *sp = (evl_split){0};
}

bool nbep__listmsg_make(const evl_ws *w, const evl_split *sp, int slab, evl_listmsg *m)
{
    m->item = w->item;
    m->n_gain = m->n_lose = 0;
    if (!room((void **)&m->id, &m->cap_id, w->n_near + w->n_was, sizeof *m->id) ||
        !room((void **)&m->q, &m->cap_q, w->n_was, sizeof *m->q)) /* (the losses' places) */
        return false;
    for (size_t k = 0; k < w->n_near; k++)
        if (w->gain[k] && sp->near[k] == slab)
            m->id[m->n_gain++] = w->near[k];
    for (size_t k = 0; k < w->n_was; k++)
        if (!w->kept[k] && sp->was[k] == slab)
            m->id[m->n_gain + m->n_lose++] = w->was[k];
    return true;
}

bool nbep__listmsg_apply(nbep_nblist *l, evl_listmsg *m)
{
    for (size_t k = 0; k < m->n_gain; k++)
        if (!nbep_nblist_append(l, m->id[k], m->item))
            return false;
    for (size_t k = 0; k < m->n_lose; k++)
        m->q[k] = nbep_nblist_drop(l, m->id[m->n_gain + k], m->item);
    return true;
}

bool nbep__listmsg_unapply(nbep_nblist *l, const evl_listmsg *m)
{
    for (size_t k = m->n_lose; k-- > 0;)
        if (m->q[k] != UINT32_MAX &&
            !nbep_nblist_undrop(l, m->id[m->n_gain + k], m->item, m->q[k]))
            return false;
    for (size_t k = m->n_gain; k-- > 0;)
        nbep_nblist_unappend(l, m->id[k], m->item);
    return true;
}

void nbep__listmsg_fini(evl_listmsg *m)
{
    free(m->id);
    free(m->q);
    *m = (evl_listmsg){0};
}
