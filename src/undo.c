/* Each slab's log of what its events changed and sent: see undo.h.
 *
 * Three stacks a slab: the records (a stamp, and where its states and sends begin in the
 * others), the states kept (a sphere's number and its state, `stride` bytes each) and the
 * messages sent. An event's states and sends run from its record's marks to the next record's
 * (or the stacks' tops), so rolling back is popping: no search, no copy. */
#include "nbep/undo.h"

#include <assert.h>
#include <stdalign.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/compiler.h"

typedef struct {
    nbep_stamp s;
    size_t keep0, sent0; /* its first state and send */
} record;

/* a slab's log, on cache lines of its own (its thread's alone) */
typedef struct {
    alignas(64) record *rec;
    size_t n_rec, cap_rec;
    unsigned char *keep; /* states: a uint64_t sphere number, then the state */
    size_t n_keep, cap_keep;
    nbep_undo_sent *sent;
    size_t n_sent, cap_sent;
} slab_log;

struct nbep_undo {
    size_t size, stride;
    int slabs;
    slab_log *logs; /* owned, slabs */
};

nbep_status nbep_undo_create(int slabs, size_t size, nbep_undo **out, nbep_diag *d)
{
    if (slabs < 1 || slabs > NBEP_UNDO_SLABS_MAX)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: undo logs take 1 to %d slabs, not %d", NBEP_UNDO_SLABS_MAX,
                  slabs);
    if (size < 1 || size > 4096)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: an undo log's state holds 1 to 4096 bytes, not %zu",
                  size);
    nbep_undo *u = calloc(1, sizeof *u);
    if (u) {
        u->size = size;
        u->stride = sizeof(uint64_t) + nbep_round8(size);
        u->slabs = slabs;
        u->logs = nbep_alloc_aligned((size_t)slabs, sizeof *u->logs);
    }
    if (!u || !u->logs) {
        nbep_undo_destroy(&u);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the slabs' undo logs");
    }
    *out = u;
    return NBEP_OK;
}

void nbep_undo_destroy(nbep_undo **u)
{
    if (!u || !*u)
        return;
    if ((*u)->logs)
        for (int k = 0; k < (*u)->slabs; k++) {
            free((*u)->logs[k].rec);
            free((*u)->logs[k].keep);
            free((*u)->logs[k].sent);
        }
    nbep_free_aligned((*u)->logs);
    free(*u);
    *u = NULL;
}

static slab_log *log_of(const nbep_undo *u, int slab)
{
    assert(slab >= 0 && slab < u->slabs);
    return &u->logs[slab];
}

bool nbep_undo_begin(nbep_undo *u, int slab, nbep_stamp s)
{
    slab_log *l = log_of(u, slab);
    /* in the slab's time order (one stamp twice: a tie the caller's order breaks) */
    assert(l->n_rec == 0 || !nbep_stamp_before(s, l->rec[l->n_rec - 1].s));
    if (!nbep_room_for_one((void **)&l->rec, &l->cap_rec, l->n_rec, sizeof *l->rec))
        return false;
    l->rec[l->n_rec++] = (record){.s = s, .keep0 = l->n_keep, .sent0 = l->n_sent};
    return true;
}

void *nbep_undo_keep_room(nbep_undo *u, int slab, uint32_t i)
{
    slab_log *l = log_of(u, slab);
    assert(l->n_rec > 0);
    if (!nbep_room_for_one((void **)&l->keep, &l->cap_keep, l->n_keep, u->stride))
        return NULL;
    unsigned char *k = l->keep + l->n_keep++ * u->stride;
    const uint64_t sphere = i;
    memcpy(k, &sphere, sizeof sphere);
    return k + sizeof sphere;
}

bool nbep_undo_keep(nbep_undo *u, int slab, uint32_t i, const void *state)
{
    void *room = nbep_undo_keep_room(u, slab, i);
    if (!room)
        return false;
    memcpy(room, state, u->size);
    return true;
}

bool nbep_undo_sent_one(nbep_undo *u, int slab, const nbep_undo_sent *m)
{
    slab_log *l = log_of(u, slab);
    assert(l->n_rec > 0);
    if (!nbep_room_for_one((void **)&l->sent, &l->cap_sent, l->n_sent, sizeof *l->sent))
        return false;
    l->sent[l->n_sent++] = *m;
    return true;
}

size_t nbep_undo_back_to(nbep_undo *u, int slab, nbep_stamp s, nbep_undo_restore_fn restore,
                         nbep_undo_cancel_fn cancel, void *arg)
{
    slab_log *l = log_of(u, slab);
    size_t undone = 0;
    while (l->n_rec > 0 && !nbep_stamp_before(l->rec[l->n_rec - 1].s, s)) {
        const record *r = &l->rec[--l->n_rec];
        for (size_t q = r->sent0; q < l->n_sent; q++)
            cancel(arg, &l->sent[q]);
        for (size_t q = l->n_keep; q-- > r->keep0;) {
            const unsigned char *k = l->keep + q * u->stride;
            uint64_t sphere;
            memcpy(&sphere, k, sizeof sphere);
            restore(arg, (uint32_t)sphere, k + sizeof sphere);
        }
        l->n_keep = r->keep0;
        l->n_sent = r->sent0;
        undone++;
    }
    return undone;
}

bool nbep_undo_last(const nbep_undo *u, int slab, nbep_stamp *s)
{
    const slab_log *l = log_of(u, slab);
    if (l->n_rec == 0)
        return false;
    *s = l->rec[l->n_rec - 1].s;
    return true;
}

size_t nbep_undo_count(const nbep_undo *u, int slab)
{
    return log_of(u, slab)->n_rec;
}

void nbep_undo_clear(nbep_undo *u)
{
    for (int k = 0; k < u->slabs; k++) {
        slab_log *l = &u->logs[k];
        l->n_rec = l->n_keep = l->n_sent = 0;
    }
}
