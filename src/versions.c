/* Versions of sphere states and notes of reads: see versions.h.
 *
 * A tracked sphere's versions form a chain, newest stamp first, threaded through its owner's
 * pool: a put links its version in where its stamp belongs (a message from another slab may
 * come stamped before versions already there), never moving or rewriting one that readers may
 * see; a cancel marks one dead. Within a window a pool's versions are only appended to, so a
 * reader never meets a version being written: it is written whole, then made visible by one
 * atomic store of the link that leads to it.
 *
 * Why no read too soon is missed. A read and a put (or cancel) of one sphere may run at once
 * on two threads. The reader (1) sets its slab's bit in the note's readers and raises the
 * note's time to its own, (2) then walks the chain; the owner (a) makes its version visible (or
 * marks one dead), (b) then reads the note's time and readers. All of these are seq_cst, so
 * they fall in one total order. If the walk missed the new version (or took the one now dead),
 * its load of that link (or mark) came before (a) in that order; then so did (1), and (b),
 * after (a), finds the note at least as late as the read and the reader's bit in it, and sends
 * the reader back. Two orders weaker than that (release on (a), acquire on (2)) would let (b)
 * read an old note while the walk read an old link: tests/test_versions.c races one read
 * against one put or cancel, sphere after sphere, and a release-only (a) fails it on x86. */
#include "nbep/versions.h"

#include <assert.h>
#include <math.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* a sphere without a slot in the open window */
#define NO_SLOT UINT32_MAX

/* A version: its stamp, the link to the next older one (index + 1, 0: none) and whether it was
 * cancelled, then the state. */
typedef struct {
    nbep_stamp s;
    _Atomic uint32_t prev;
    _Atomic uint32_t dead;
} node;
_Static_assert(sizeof(node) % 8 == 0, "a version's state starts 8-byte aligned");

/* A tracked sphere's note (the latest time read, as ordered(); the readers' bits) and its
 * chain's newest version (index + 1) */
typedef struct {
    _Atomic uint64_t read_at;
    _Atomic uint64_t readers;
    _Atomic uint32_t head;
    uint32_t sphere;
} slot;

/* a slab's count of versions put this window, and the slots it touched first this window
 * (a sphere's first version, put by its owner, and this slab's first read of a sphere: close
 * resets only these), on cache lines of its own (its thread's alone in a window) */
typedef struct {
    alignas(64) size_t used;
    uint32_t *touched; /* owned, cap_touched */
    size_t n_touched, cap_touched;
} pool;

struct nbep_versions {
    size_t n, size, stride, room;
    int slabs;
    bool open;
    uint32_t *slot_of; /* owned, n: each sphere's slot, NO_SLOT when not tracked */
    slot *slots;       /* owned, cap: the tracked spheres', tracked of them */
    size_t tracked, cap;
    atomic_bool lost;  /* a touched list could not grow: close resets every slot */
    unsigned char *nodes; /* owned, slabs * room versions of stride bytes: slab k's from k room */
    pool pools[NBEP_VERSIONS_SLABS_MAX];
};

static size_t stride_of(size_t size)
{
    return sizeof(node) + nbep_round8(size);
}

/* Times as unsigned integers in the same order, so that a note's time rises by integer
 * compare-and-swap: a double's bits, the sign's flipped for positives and all flipped for
 * negatives; -0.0 is taken as 0.0 first (equal times must compare equal: a put at one and a
 * read at the other are in either order by key). Not NaN. */
static uint64_t ordered(double t)
{
    t += 0.0; /* -0.0 + 0.0 is +0.0 */
    uint64_t b;
    memcpy(&b, &t, sizeof b);
    return b >> 63 ? ~b : b | (UINT64_C(1) << 63);
}

static node *node_at(const nbep_versions *v, uint32_t link)
{
    return (node *)(v->nodes + (size_t)(link - 1) * v->stride);
}

static slot *slot_for(const nbep_versions *v, uint32_t i)
{
    assert(v->open && i < v->n && v->slot_of[i] != NO_SLOT);
    return &v->slots[v->slot_of[i]];
}

nbep_status nbep_versions_create(size_t n, size_t size, int slabs, size_t room,
                                 nbep_versions **out, nbep_diag *d)
{
    if (slabs < 1 || slabs > NBEP_VERSIONS_SLABS_MAX)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: versions take 1 to %d slabs, not %d",
                  NBEP_VERSIONS_SLABS_MAX, slabs);
    if (size < 1 || size > 4096)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: a version holds 1 to 4096 bytes, not %zu", size);
    /* links are 32-bit, index + 1: every version's below UINT32_MAX, and slots likewise */
    const size_t most = ((size_t)1 << 31) / (size_t)slabs;
    if (room < 1 || room > most || n >= (size_t)1 << 31)
        NBEP_FAIL(d, NBEP_EDECK,
                  "nbep: versions: room for 1 to %zu a slab on %d slabs and fewer than 2^31 "
                  "spheres, not %zu and %zu",
                  most, slabs, room, n);
    nbep_versions *v = calloc(1, sizeof *v);
    if (v) {
        v->n = n;
        v->size = size;
        v->stride = stride_of(size);
        v->room = room;
        v->slabs = slabs;
        v->slot_of = malloc((n ? n : 1) * sizeof *v->slot_of);
        v->nodes = malloc((size_t)slabs * room * v->stride);
    }
    if (!v || !v->slot_of || !v->nodes) {
        nbep_versions_destroy(&v);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the spheres' versions");
    }
    for (size_t i = 0; i < n; i++)
        v->slot_of[i] = NO_SLOT;
    atomic_init(&v->lost, false);
    *out = v;
    return NBEP_OK;
}

void nbep_versions_destroy(nbep_versions **v)
{
    if (!v || !*v)
        return;
    for (int k = 0; k < (*v)->slabs; k++)
        free((*v)->pools[k].touched);
    free((*v)->slot_of);
    free((*v)->slots);
    free((*v)->nodes);
    free(*v);
    *v = NULL;
}

/* The slots' first room; doubled when outgrown */
#define SLOTS0 64

size_t nbep_versions_bytes(size_t n, size_t size, int slabs, size_t room, size_t tracked)
{
    size_t cap = 0;
    while (cap < tracked)
        cap = cap ? 2 * cap : SLOTS0;
    return sizeof(nbep_versions) + (n ? n : 1) * sizeof(uint32_t) +
           (size_t)slabs * room * stride_of(size) + cap * sizeof(slot);
}

static void slot_clear(slot *sl)
{
    atomic_store_explicit(&sl->read_at, 0, memory_order_relaxed); /* below every time */
    atomic_store_explicit(&sl->readers, 0, memory_order_relaxed);
    atomic_store_explicit(&sl->head, 0, memory_order_relaxed);
}

bool nbep_versions_track(nbep_versions *v, uint32_t i)
{
    assert(!v->open && i < v->n);
    if (v->slot_of[i] != NO_SLOT)
        return true;
    if (v->tracked == v->cap) {
        const size_t cap = v->cap ? 2 * v->cap : SLOTS0;
        slot *grown = realloc(v->slots, cap * sizeof *grown);
        if (!grown)
            return false;
        v->slots = grown;
        v->cap = cap;
    }
    slot *sl = &v->slots[v->tracked];
    slot_clear(sl);
    sl->sphere = i;
    v->slot_of[i] = (uint32_t)v->tracked++;
    return true;
}

void nbep_versions_untrack(nbep_versions *v, uint32_t i)
{
    assert(!v->open && i < v->n);
    const uint32_t k = v->slot_of[i];
    if (k == NO_SLOT)
        return;
    const slot *last = &v->slots[--v->tracked];
    /* the last slot into the hole: a closed window's slots are clear, so a plain copy moves it */
    v->slots[k].sphere = last->sphere;
    v->slot_of[last->sphere] = k;
    v->slot_of[i] = NO_SLOT;
}

size_t nbep_versions_count(const nbep_versions *v)
{
    return v->tracked;
}

void nbep_versions_open(nbep_versions *v)
{
    assert(!v->open);
    v->open = true;
}

void nbep_versions_close(nbep_versions *v)
{
    assert(v->open);
    const bool all = atomic_load_explicit(&v->lost, memory_order_relaxed);
    for (int k = 0; k < v->slabs; k++) {
        pool *p = &v->pools[k];
        for (size_t q = 0; q < p->n_touched && !all; q++)
            slot_clear(&v->slots[p->touched[q]]);
        p->n_touched = 0;
        p->used = 0;
    }
    for (size_t k = 0; all && k < v->tracked; k++)
        slot_clear(&v->slots[k]);
    atomic_store_explicit(&v->lost, false, memory_order_relaxed);
    v->open = false;
}

/* Slot k was touched first this window by slab's thread: on its list for close. Where the list
 * cannot grow, close resets every slot instead. */
static void touch(nbep_versions *v, int slab, uint32_t k)
{
    pool *p = &v->pools[slab];
    if (p->n_touched == p->cap_touched) {
        const size_t cap = p->cap_touched ? 2 * p->cap_touched : 256;
        uint32_t *grown = realloc(p->touched, cap * sizeof *grown);
        if (!grown) {
            atomic_store_explicit(&v->lost, true, memory_order_relaxed);
            return;
        }
        p->touched = grown;
        p->cap_touched = cap;
    }
    p->touched[p->n_touched++] = k;
}

bool nbep_versions_tracked(const nbep_versions *v, uint32_t i)
{
    return i < v->n && v->slot_of[i] != NO_SLOT;
}

/* The readers to send back to a version put or cancelled at time t: (b) of *Why no read too
 * soon is missed*. A read at t itself may come after it by key: sent back too. */
static uint64_t readers_after(slot *sl, double t)
{
    if (atomic_load_explicit(&sl->read_at, memory_order_seq_cst) < ordered(t))
        return 0;
    return atomic_load_explicit(&sl->readers, memory_order_seq_cst);
}

bool nbep_versions_put(nbep_versions *v, int slab, uint32_t i, nbep_stamp s, const void *data,
                       uint64_t *roll)
{
    assert(slab >= 0 && slab < v->slabs && !isnan(s.t));
    slot *sl = slot_for(v, i);
    pool *p = &v->pools[slab];
    if (p->used == v->room)
        return false;
    const uint32_t link = (uint32_t)((size_t)slab * v->room + p->used + 1);
    node *nd = node_at(v, link);
    nd->s = s;
    memcpy(nd + 1, data, v->size);
    atomic_store_explicit(&nd->dead, 0, memory_order_relaxed);
    /* after the versions stamped after s, before the rest (a version of an equal stamp, dead:
     * the re-handled event's, is passed over by readers) */
    _Atomic uint32_t *at = &sl->head;
    uint32_t next = atomic_load_explicit(at, memory_order_relaxed); /* the owner's own */
    while (next && nbep_stamp_before(s, node_at(v, next)->s)) {
        at = &node_at(v, next)->prev;
        next = atomic_load_explicit(at, memory_order_relaxed);
    }
    atomic_store_explicit(&nd->prev, next, memory_order_relaxed);
    p->used++;
    if (!atomic_load_explicit(&sl->head, memory_order_relaxed))
        touch(v, slab, v->slot_of[i]); /* its first version this window */
    /* (a): the version whole before it is visible (a seq_cst store releases) */
    atomic_store_explicit(at, link, memory_order_seq_cst);
    *roll = readers_after(sl, s.t);
    return true;
}

bool nbep_versions_cancel(nbep_versions *v, uint32_t i, nbep_stamp s, uint64_t *roll)
{
    slot *sl = slot_for(v, i);
    for (uint32_t k = atomic_load_explicit(&sl->head, memory_order_relaxed); k;
         k = atomic_load_explicit(&node_at(v, k)->prev, memory_order_relaxed)) {
        node *nd = node_at(v, k);
        if (nbep_stamp_same(nd->s, s) &&
            !atomic_load_explicit(&nd->dead, memory_order_relaxed)) {
            atomic_store_explicit(&nd->dead, 1, memory_order_seq_cst); /* (a) */
            *roll = readers_after(sl, s.t);
            return true;
        }
    }
    *roll = 0;
    return false;
}

const void *nbep_versions_newest(const nbep_versions *v, uint32_t i)
{
    slot *sl = slot_for(v, i);
    for (uint32_t k = atomic_load_explicit(&sl->head, memory_order_relaxed); k;
         k = atomic_load_explicit(&node_at(v, k)->prev, memory_order_relaxed)) {
        const node *nd = node_at(v, k);
        if (!atomic_load_explicit(&nd->dead, memory_order_relaxed))
            return nd + 1;
    }
    return NULL;
}

bool nbep_versions_read(nbep_versions *v, int reader, uint32_t i, nbep_stamp at, void *out,
                        nbep_stamp *found)
{
    assert(reader >= 0 && reader < v->slabs && !isnan(at.t));
    slot *sl = slot_for(v, i);
    /* (1): the bit (set already by this slab's earlier read in the window, if it reads so: bits
     * are never cleared in a window, so that read's set came before), then the time raised. A
     * slab's first read of the sphere puts it on the slab's list for close (each reader's: a
     * slot on two lists is cleared twice; asking whether any slab read it first would take the
     * old bits back, a loop of compare-and-swap where a plain locked or does) */
    const uint64_t bit = UINT64_C(1) << reader;
    if (!(atomic_load_explicit(&sl->readers, memory_order_seq_cst) & bit)) {
        atomic_fetch_or_explicit(&sl->readers, bit, memory_order_seq_cst);
        touch(v, reader, v->slot_of[i]);
    }
    const uint64_t mine = ordered(at.t);
    uint64_t was = atomic_load_explicit(&sl->read_at, memory_order_seq_cst);
    while (was < mine && !atomic_compare_exchange_weak_explicit(&sl->read_at, &was, mine,
                                                                 memory_order_seq_cst,
                                                                 memory_order_seq_cst)) {
    }
    /* (2) */
    for (uint32_t k = atomic_load_explicit(&sl->head, memory_order_seq_cst); k;
         k = atomic_load_explicit(&node_at(v, k)->prev, memory_order_seq_cst)) {
        const node *nd = node_at(v, k);
        if (nbep_stamp_before(nd->s, at) &&
            !atomic_load_explicit(&nd->dead, memory_order_seq_cst)) {
            if (out)
                memcpy(out, nd + 1, v->size);
            if (found)
                *found = nd->s;
            return true;
        }
    }
    return false;
}
