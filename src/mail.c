/* Mail between slabs: see mail.h.
 *
 * A box is a ring of cells that many slabs send into and one takes from. Each cell carries a
 * sequence number that says whose turn it is: cell c of a ring of R is free for the send that
 * reserves position p (p mod R = c) when its number is p, and holds that send's message, written
 * whole, when it is p + 1; the take of position p sets it to p + R, freeing it for the next lap.
 * A send reserves its position by compare-and-swap on the ring's tail, writes its message, then
 * publishes it with a release store of the cell's number; the take reads the number with
 * acquire, so it reads the message whole, and releases the cell with a release store, so the
 * next lap's send (acquire) writes only after the take read. A sender that finds its cell's
 * number behind its position finds the ring full. (The bounded queue of D. Vyukov, with one
 * taker.) Per sender, positions rise with its sends, so its mail is taken in the order sent.
 *
 * The meeting's count (mail.h): `work`, the busy slabs plus the mail sent and not taken. A send
 * adds one (relaxed: the message's own release and acquire order it before the take that
 * subtracts it, and read-modify-writes of one variable never go back in its order); take and
 * idle subtract with release, quiet loads with acquire, so a thread that reads 0 sees every
 * slab's work before its idle (the release sequence of the subtractions). */
#include "nbep/mail.h"

#include "nbep/compiler.h"

#include <assert.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* a cell: its sequence number, the message's head, then its data */
typedef struct {
    _Atomic uint64_t seq;
    nbep_mail_head h;
} cell;
_Static_assert(sizeof(cell) % 8 == 0, "a cell's data starts 8-byte aligned");

/* a slab's box (tail: its senders'; head and idle: its own thread's) and its own sends' count */
typedef struct {
    alignas(64) _Atomic uint64_t tail;
    alignas(64) uint64_t head;
    bool idle;
    uint64_t sent; /* this slab's sends this window: the last message's number */
    unsigned char *cells; /* within nbep_mail's block: room cells of stride bytes */
} box;

struct nbep_mail {
    alignas(64) _Atomic int64_t work;
    size_t size, stride, room;
    int slabs;
    box *boxes;           /* owned, slabs */
    unsigned char *block; /* owned, slabs * room * stride */
};

static size_t stride_of(size_t size)
{
    return sizeof(cell) + nbep_round8(size);
}

/* A ring's cells: a power of two, at least 2 (with one, a cell's "holds the message of p"
 * would read as "free for p + 1"). */
static size_t room_of(size_t room)
{
    size_t r = 2;
    while (r < room)
        r *= 2;
    return r;
}

static cell *cell_at(const nbep_mail *m, const box *b, uint64_t pos)
{
    return (cell *)(b->cells + (size_t)(pos & (m->room - 1)) * m->stride);
}

#define ROOM_MAX ((size_t)1 << 20)

nbep_status nbep_mail_create(int slabs, size_t size, size_t room, nbep_mail **out, nbep_diag *d)
{
    if (slabs < 1 || slabs > NBEP_MAIL_SLABS_MAX)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: mail takes 1 to %d slabs, not %d", NBEP_MAIL_SLABS_MAX,
                  slabs);
    if (size < 1 || size > 4096)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: a message holds 1 to 4096 bytes, not %zu", size);
    if (room < 1 || room > ROOM_MAX)
        NBEP_FAIL(d, NBEP_EDECK, "nbep: a box holds 1 to %zu messages, not %zu", ROOM_MAX, room);
    nbep_mail *m = nbep_alloc_aligned(1, sizeof *m);
    if (m) {
        m->size = size;
        m->stride = stride_of(size);
        m->room = room_of(room);
        m->slabs = slabs;
        m->boxes = nbep_alloc_aligned((size_t)slabs, sizeof *m->boxes);
        m->block = malloc((size_t)slabs * m->room * m->stride);
    }
    if (!m || !m->boxes || !m->block) {
        nbep_mail_destroy(&m);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the slabs' mail");
    }
    for (int k = 0; k < slabs; k++) {
        box *b = &m->boxes[k];
        atomic_init(&b->tail, 0);
        b->cells = m->block + (size_t)k * m->room * m->stride;
        for (uint64_t p = 0; p < m->room; p++)
            atomic_init(&cell_at(m, b, p)->seq, p);
    }
    atomic_init(&m->work, 0); /* quiet: no window open */
    *out = m;
    return NBEP_OK;
}

void nbep_mail_destroy(nbep_mail **m)
{
    if (!m || !*m)
        return;
    nbep_free_aligned((*m)->boxes);
    free((*m)->block);
    nbep_free_aligned(*m);
    *m = NULL;
}

size_t nbep_mail_bytes(int slabs, size_t size, size_t room)
{
    return sizeof(nbep_mail) + (size_t)slabs * sizeof(box) +
           (size_t)slabs * room_of(room) * stride_of(size);
}

void nbep_mail_open(nbep_mail *m)
{
    for (int k = 0; k < m->slabs; k++) {
        box *b = &m->boxes[k];
        assert(atomic_load_explicit(&b->tail, memory_order_relaxed) == b->head);
        b->idle = false;
        b->sent = 0;
    }
    atomic_store_explicit(&m->work, m->slabs, memory_order_relaxed);
}

/* Reserves a cell in to's box and writes the head and data; false when the box is full. */
static bool post(nbep_mail *m, int from, int to, const nbep_mail_head *h, const void *data)
{
    assert(from >= 0 && from < m->slabs && to >= 0 && to < m->slabs && from != to);
    assert(!m->boxes[from].idle);
    box *b = &m->boxes[to];
    uint64_t pos = atomic_load_explicit(&b->tail, memory_order_relaxed);
    cell *c;
    for (;;) {
        c = cell_at(m, b, pos);
        const uint64_t seq = atomic_load_explicit(&c->seq, memory_order_acquire);
        const int64_t lag = (int64_t)(seq - pos);
        if (lag == 0) { /* free for this position: take it, or learn the tail that passed it */
            if (atomic_compare_exchange_weak_explicit(&b->tail, &pos, pos + 1,
                                                      memory_order_relaxed, memory_order_relaxed))
                break;
        } else if (lag < 0) { /* still holds the message a lap before, untaken: full */
            return false;
        } else { /* another send took this position: look again */
            pos = atomic_load_explicit(&b->tail, memory_order_relaxed);
        }
    }
    atomic_fetch_add_explicit(&m->work, 1, memory_order_relaxed);
    c->h = *h;
    if (data)
        memcpy(c + 1, data, m->size);
    atomic_store_explicit(&c->seq, pos + 1, memory_order_release);
    return true;
}

bool nbep_mail_send(nbep_mail *m, int from, int to, nbep_stamp s, uint32_t sphere,
                    const void *data, uint64_t *id)
{
    const nbep_mail_head h = {.stamp = s, .id = m->boxes[from].sent + 1, .sphere = sphere,
                              .from = (uint16_t)from, .cancel = 0};
    if (!post(m, from, to, &h, data))
        return false;
    m->boxes[from].sent++;
    if (id)
        *id = h.id;
    return true;
}

bool nbep_mail_cancel(nbep_mail *m, int from, int to, uint64_t id, nbep_stamp s, uint32_t sphere)
{
    assert(id >= 1 && id <= m->boxes[from].sent);
    const nbep_mail_head h = {.stamp = s, .id = id, .sphere = sphere, .from = (uint16_t)from,
                              .cancel = 1};
    return post(m, from, to, &h, NULL);
}

/* nbep_mail_take past its first look: box b's messages from the one at its head, which is
 * there. Out of line, so that the take of an empty box (nearly every take: the scheduler takes
 * its mail before each action) saves no registers and calls nothing (it cost 41 instructions
 * an action when the loop was the whole call). */
static NBEP_NOINLINE size_t take_from(nbep_mail *m, box *b, nbep_mail_fn fn, void *arg)
{
    size_t n = 0;
    for (;;) {
        cell *c = cell_at(m, b, b->head);
        if (atomic_load_explicit(&c->seq, memory_order_acquire) != b->head + 1)
            break; /* empty, or the next message still being written */
        fn(arg, &c->h, c->h.cancel ? NULL : (const void *)(c + 1));
        atomic_store_explicit(&c->seq, b->head + m->room, memory_order_release);
        b->head++;
        n++;
    }
    if (n > 0) {
        /* an idle slab handed mail is busy again: one back for it, in the same step */
        const int64_t back = b->idle ? 1 : 0;
        b->idle = false;
        atomic_fetch_sub_explicit(&m->work, (int64_t)n - back, memory_order_release);
    }
    return n;
}

size_t nbep_mail_take(nbep_mail *m, int to, nbep_mail_fn fn, void *arg)
{
    assert(to >= 0 && to < m->slabs);
    box *b = &m->boxes[to];
    /* the loop's own first look (the same load, acquire: what it finds it reads) */
    if (atomic_load_explicit(&cell_at(m, b, b->head)->seq, memory_order_acquire) != b->head + 1)
        return 0;
    return take_from(m, b, fn, arg);
}

void nbep_mail_idle(nbep_mail *m, int slab)
{
    assert(slab >= 0 && slab < m->slabs && !m->boxes[slab].idle);
    m->boxes[slab].idle = true;
    atomic_fetch_sub_explicit(&m->work, 1, memory_order_release);
}

bool nbep_mail_quiet(const nbep_mail *m)
{
    return atomic_load_explicit(&m->work, memory_order_acquire) == 0;
}
