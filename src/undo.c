/* Each slab's log of what its events changed and sent: see undo.h.
 *
 * Four stacks a slab: the records (a stamp's time and first level, and where its states, sends
 * and deeper levels begin in the others), the states kept (a sphere's number and its state,
 * `stride` bytes each), the messages sent, and the levels of stamps past their first. An
 * event's states and sends run from its record's marks to the next record's (or the stacks'
 * tops), so rolling back is popping: no search, no copy. */
#include "nbep/undo.h"

#include <assert.h>
#include <stdalign.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/compiler.h"

/* A record holds its stamp's time and first level; the levels past the first (a stamp made in
 * a cascade at one time: few) sit on the slab's stack of deep levels. 56 bytes where the whole
 * stamp took 160: the records are written once an event, a window's worth of them in a row
 * (about 5500 an event's slab at the bench's window), so their lines are the log's cost
 * (bench_warp on one slab, 2026-12-07: docs/optimistic-design.md, *Ties in time*). */
typedef struct {
    double t;
    uint32_t depth;
    nbep_cascade_level root;
    size_t keep0, sent0, deep0; /* its first state, send and deep level */
} record;

/* a slab's log, on cache lines of its own (its thread's alone) */
typedef struct {
    alignas(64) record *rec;
    size_t n_rec, cap_rec;
    unsigned char *keep; /* states: a uint64_t sphere number, then the state */
    size_t n_keep, cap_keep;
    nbep_undo_sent *sent;
    size_t n_sent, cap_sent;
    nbep_cascade_level *deep; /* the records' levels past the first, in the records' order */
    size_t n_deep, cap_deep;
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
            free((*u)->logs[k].deep);
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

/* Record r's stamp, whole (its levels past depth left unset: never read). */
static nbep_stamp stamp_of(const slab_log *l, const record *r)
{
    nbep_stamp s;
    s.t = r->t;
    s.depth = r->depth;
    s.level[0] = r->root;
    if (r->depth > 1)
        memcpy(&s.level[1], &l->deep[r->deep0], (r->depth - 1) * sizeof *l->deep);
    return s;
}

/* Record r's stamp against s, as nbep_cascade_cmp orders them: by time, read in place (stamps
 * of one time are rare but in cascades), else whole. */
static int rec_cmp(const slab_log *l, const record *r, const nbep_stamp *s)
{
    if (r->t != s->t)
        return r->t < s->t ? -1 : 1;
    const nbep_stamp whole = stamp_of(l, r);
    return nbep_cascade_cmp(&whole, s);
}

static bool begin(nbep_undo *u, int slab, const nbep_stamp *s)
{
    slab_log *l = log_of(u, slab);
    assert(s->depth >= 1 && s->depth <= NBEP_CASCADE_DEPTH);
    if (!nbep_room_for_one((void **)&l->rec, &l->cap_rec, l->n_rec, sizeof *l->rec))
        return false;
    /* room for its depth - 1 deeper levels: one growth at most (the first room, 64, and each
     * doubling exceed the 7 a stamp can add) */
    if (s->depth > 1 && !nbep_room_for_one((void **)&l->deep, &l->cap_deep,
                                           l->n_deep + s->depth - 2, sizeof *l->deep))
        return false;
    l->rec[l->n_rec++] = (record){.t = s->t, .depth = s->depth, .root = s->level[0],
                                  .keep0 = l->n_keep, .sent0 = l->n_sent, .deep0 = l->n_deep};
    for (uint32_t k = 1; k < s->depth; k++)
        l->deep[l->n_deep++] = s->level[k];
    return true;
}

bool nbep_undo_begin(nbep_undo *u, int slab, const nbep_stamp *s)
{
    /* in the slab's time order (one stamp twice: a tie the caller's order breaks) */
    const slab_log *l = log_of(u, slab);
    assert(l->n_rec == 0 || rec_cmp(l, &l->rec[l->n_rec - 1], s) <= 0);
    (void)l;
    return begin(u, slab, s);
}

bool nbep_undo_begin_late(nbep_undo *u, int slab, const nbep_stamp *s)
{
    return begin(u, slab, s);
}

/* Bytes [lo, hi) of a turned so that those of [mid, hi) come first, each run in its order: the
 * top run (a late record's few states: one for a copy) through a buffer on the stack, a piece
 * at a time, the rest moved up by each piece at once (three reversals, byte by byte, were
 * 2.6 % of a run at N = 256000 on 2 slabs, with 117 k late copies). */
static void rotate_bytes(void *base, size_t lo, size_t mid, size_t hi)
{
    unsigned char *a = base, piece[1024];
    while (lo < mid && mid < hi) {
        const size_t c = hi - mid < sizeof piece ? hi - mid : sizeof piece;
        memcpy(piece, a + mid, c);
        memmove(a + lo + c, a + lo, mid - lo);
        memcpy(a + lo, piece, c);
        lo += c;
        mid += c;
    }
}

void nbep_undo_sink(nbep_undo *u, int slab)
{
    slab_log *l = log_of(u, slab);
    assert(l->n_rec > 0);
    const size_t top = l->n_rec - 1;
    record r = l->rec[top];
    const nbep_stamp s = stamp_of(l, &r);
    size_t p = top;
    while (p > 0 && rec_cmp(l, &l->rec[p - 1], &s) >= 0)
        p--;
    if (p == top)
        return;
    /* its states, sends and levels (the stacks' tops) turned in below those of rec[p..top) */
    const record at = l->rec[p];
    const size_t nk = l->n_keep - r.keep0, ns = l->n_sent - r.sent0, nd = l->n_deep - r.deep0;
    rotate_bytes(l->keep, at.keep0 * u->stride, r.keep0 * u->stride, l->n_keep * u->stride);
    rotate_bytes(l->sent, at.sent0 * sizeof *l->sent, r.sent0 * sizeof *l->sent,
                 l->n_sent * sizeof *l->sent);
    rotate_bytes(l->deep, at.deep0 * sizeof *l->deep, r.deep0 * sizeof *l->deep,
                 l->n_deep * sizeof *l->deep);
    memmove(&l->rec[p + 1], &l->rec[p], (top - p) * sizeof *l->rec);
    for (size_t q = p + 1; q <= top; q++) {
        l->rec[q].keep0 += nk;
        l->rec[q].sent0 += ns;
        l->rec[q].deep0 += nd;
    }
    r.keep0 = at.keep0;
    r.sent0 = at.sent0;
    r.deep0 = at.deep0;
    l->rec[p] = r;
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

/* back_to's and back_past's: the records stamped at or after *s (past: after it) undone */
static size_t back(nbep_undo *u, int slab, const nbep_stamp *s, bool past,
                   nbep_undo_restore_fn restore, nbep_undo_cancel_fn cancel, void *arg)
{
    slab_log *l = log_of(u, slab);
    size_t undone = 0;
    while (l->n_rec > 0 && rec_cmp(l, &l->rec[l->n_rec - 1], s) >= (past ? 1 : 0)) {
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
        l->n_deep = r->deep0;
        undone++;
    }
    return undone;
}

size_t nbep_undo_back_to(nbep_undo *u, int slab, const nbep_stamp *s, nbep_undo_restore_fn restore,
                         nbep_undo_cancel_fn cancel, void *arg)
{
    return back(u, slab, s, false, restore, cancel, arg);
}

size_t nbep_undo_back_past(nbep_undo *u, int slab, const nbep_stamp *s,
                           nbep_undo_restore_fn restore, nbep_undo_cancel_fn cancel, void *arg)
{
    return back(u, slab, s, true, restore, cancel, arg);
}

bool nbep_undo_last(const nbep_undo *u, int slab, nbep_stamp *s)
{
    const slab_log *l = log_of(u, slab);
    if (l->n_rec == 0)
        return false;
    *s = stamp_of(l, &l->rec[l->n_rec - 1]);
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
        l->n_rec = l->n_keep = l->n_sent = l->n_deep = 0;
    }
}
