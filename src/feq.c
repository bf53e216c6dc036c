/* The N-Body Future Event Queue (paper Sections 3.2 and 4.4, Procedures 10-13): an array of
 * one-element priority queues, one slot per sphere, each holding the earliest event known for
 * that sphere. Inserting a later event into a filled slot stores nothing, an earlier one
 * replaces (supersedes) the old one, so the queue never grows and every operation on a slot is
 * O(1); find and find_invalid are linear scans over one thread's index range.
 *
 * Invariants: an invalid slot has kind NBEP_EVENT_NONE; a valid slot has kind SPHERE or PLANE
 * and a finite time (+inf and NaN are never inserted), or kind NEVER and time +inf (set only by
 * nbep_feq_set_never: "nothing ahead", which find never reports). nbep_feq_check adds what the queue cannot
 * know by itself: times not in the past, partners within range and not the sphere itself.
 *
 * Why no locks, atomics or OpenMP: sphere i's slot is written only by the thread that owns i
 * (a fixed index range per thread, the same every step), and other threads read it only in a
 * later sub-phase, after a barrier (nbep_barrier_wait: acquire/release) that orders the
 * owner's writes before their reads. Within a sub-phase no slot is read by one thread while
 * another writes it, so plain loads and stores are race-free. Neighbouring ranges can share a
 * cache line at their boundary (two slots per line); that costs at most one line per thread.
 *
 * Departures from the paper: Procedure 13 compares `time == current_time`; we report events
 * with time < t_end, since contacts fall anywhere inside a step. Procedure 10 keeps whichever
 * of two equal-time events came first; we order equal times by (kind, partner), then prefer
 * the newer prediction, so the stored event does not depend on the order of inserts (and so
 * not on the thread count). */
#include "nbep/feq.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>

/* Two slots per cache line, and the slot array stays a plain array the scans walk. */
static_assert(sizeof(nbep_event) == 32, "nbep_event must stay 32 bytes");
static_assert(NBEP_CACHELINE % sizeof(nbep_event) == 0, "slots must not straddle cache lines");

/* What an invalid slot holds: kind NONE, and a time of +inf so that a reader that forgets to
 * test the kind still sees "never". */
static nbep_event empty_event(void)
{
    return (nbep_event){.time = INFINITY, .partner = 0, .kind = NBEP_EVENT_NONE};
}

size_t nbep_feq_bytes(size_t n)
{
    return sizeof(nbep_feq) + n * sizeof(nbep_event);
}

nbep_status nbep_feq_create(size_t n, nbep_feq **out, nbep_diag *d)
{
    /* find writes sphere ids as uint32_t (STYLE 2: sphere ids are uint32_t). */
    if (n > UINT32_MAX)
        NBEP_FAIL(d, NBEP_ENOMEM,
                  "nbep: an event queue of %zu spheres is too large (at most %lu sphere ids)", n,
                  (unsigned long)UINT32_MAX);
    nbep_feq *q = calloc(1, sizeof *q);
    if (!q || !(q->slot = nbep_alloc_aligned(n, sizeof *q->slot))) {
        nbep_feq_destroy(&q); /* frees whatever was made */
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for an event queue of %zu spheres", n);
    }
    q->n = n;
    for (size_t i = 0; i < n; i++)
        q->slot[i] = empty_event();
    *out = q;
    return NBEP_OK;
}

void nbep_feq_destroy(nbep_feq **qp)
{
    if (!qp || !*qp)
        return;
    nbep_free_aligned((*qp)->slot);
    free(*qp);
    *qp = NULL;
}

/* True when a should be kept over b: earlier time; at equal times the smaller (kind, partner);
 * for the same time and partner the newer prediction (larger response counts), which is the
 * one made from the later state. A strict total order on everything but identical events, so
 * the winner of several inserts does not depend on their order. */
bool nbep_feq_event_before(const nbep_event *a, const nbep_event *b)
{
    if (a->time != b->time)
        return a->time < b->time;
    if (a->kind != b->kind)
        return a->kind < b->kind;
    if (a->partner != b->partner)
        return a->partner < b->partner;
    if (a->ver_self != b->ver_self)
        return a->ver_self > b->ver_self;
    return a->ver_partner > b->ver_partner;
}

bool nbep_feq_insert(nbep_feq *q, size_t i, nbep_event e)
{
    assert(q && i < q->n);
    assert(e.kind == NBEP_EVENT_SPHERE || e.kind == NBEP_EVENT_PLANE ||
           e.kind == NBEP_EVENT_HORIZON);
    /* "Never" carries no information: leave the slot as it is (invalid slots get re-predicted,
     * which is what a sphere with no known event needs). Also refuses NaN, which would
     * otherwise compare neither earlier nor later than anything. */
    if (!(e.time < INFINITY))
        return false;
    nbep_event *s = &q->slot[i];
    if (s->kind != NBEP_EVENT_NONE && !nbep_feq_event_before(&e, s))
        return false;
    *s = e;
    return true;
}

void nbep_feq_set_never(nbep_feq *q, size_t i, uint64_t ver_self)
{
    assert(q && i < q->n);
    q->slot[i] = (nbep_event){.time = INFINITY, .kind = NBEP_EVENT_NEVER, .ver_self = ver_self};
}

void nbep_feq_remove(nbep_feq *q, size_t i)
{
    assert(q && i < q->n);
    q->slot[i] = empty_event();
}

size_t nbep_feq_find(const nbep_feq *q, size_t lo, size_t hi, double t_end, uint32_t *out)
{
    assert(q && lo <= hi && hi <= q->n);
    size_t count = 0;
    for (size_t i = lo; i < hi; i++) {
        const nbep_event *s = &q->slot[i];
        /* Strict: an event exactly at t_end belongs to the next step. */
        if (s->kind != NBEP_EVENT_NONE && s->time < t_end)
            out[count++] = (uint32_t)i;
    }
    return count;
}

size_t nbep_feq_find_invalid(const nbep_feq *q, size_t lo, size_t hi, uint32_t *out)
{
    assert(q && lo <= hi && hi <= q->n);
    size_t count = 0;
    for (size_t i = lo; i < hi; i++)
        if (q->slot[i].kind == NBEP_EVENT_NONE)
            out[count++] = (uint32_t)i;
    return count;
}

/* The reason slot i (valid) breaks an invariant, or NULL when it is sound. */
static const char *slot_problem(const nbep_event *s, size_t i, double t_now, size_t n,
                                size_t n_planes)
{
    if (s->kind == NBEP_EVENT_NEVER)
        return s->time == INFINITY ? NULL : "a 'never' slot with a finite time";
    if (s->kind == NBEP_EVENT_HORIZON)
        return isfinite(s->time) && s->time >= t_now ? NULL : "a horizon not in the future";
    if (s->kind != NBEP_EVENT_SPHERE && s->kind != NBEP_EVENT_PLANE)
        return "unknown event kind";
    if (!isfinite(s->time))
        return "time is not finite";
    if (s->time < t_now)
        return "time is before the current time";
    if (s->kind == NBEP_EVENT_SPHERE && s->partner >= n)
        return "partner sphere out of range";
    if (s->kind == NBEP_EVENT_SPHERE && s->partner == i)
        return "partner is the sphere itself";
    if (s->kind == NBEP_EVENT_PLANE && s->partner >= n_planes)
        return "partner plane out of range";
    return NULL;
}

/* d may be NULL when only the count is wanted. */
size_t nbep_feq_check(const nbep_feq *q, double t_now, size_t n_planes, nbep_diag *d)
{
    assert(q);
    size_t bad = 0;
    for (size_t i = 0; i < q->n; i++) {
        const nbep_event *s = &q->slot[i];
        if (s->kind == NBEP_EVENT_NONE)
            continue;
        const char *why = slot_problem(s, i, t_now, q->n, n_planes);
        if (!why)
            continue;
        if (bad == 0 && d)
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: event slot of sphere %zu: %s (kind %u, partner %u, time %.17g, "
                          "now %.17g, %zu spheres, %zu planes)",
                          i, why, (unsigned)s->kind, (unsigned)s->partner, s->time, t_now, q->n,
                          n_planes);
        bad++;
    }
    return bad;
}
