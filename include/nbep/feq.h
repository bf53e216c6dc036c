/* The N-Body Future Event Queue (paper Sections 3.2 and 4.4): one slot per sphere holding its
 * earliest known event (partner sphere or plane, absolute time, and the response counts of
 * both objects when it was predicted, so that a stale event can be recognised). No locks: the
 * slot of sphere i is written only by the thread owning i, and read by others only after a
 * barrier. No OpenMP in here; callers pass their index range. */
#ifndef NBEP_FEQ_H
#define NBEP_FEQ_H

#include <assert.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

typedef enum nbep_event_kind {
    NBEP_EVENT_NONE = 0,    /* invalid slot: nothing known, the sphere must be re-predicted */
    NBEP_EVENT_SPHERE = 1,  /* partner is a sphere index */
    NBEP_EVENT_PLANE = 2,   /* partner is a plane index */
    NBEP_EVENT_NEVER = 3,   /* valid: nothing ahead on the current course (time +inf); stays
                             * true until the sphere's own course changes, because a partner
                             * whose course changes re-predicts the pair itself */
    NBEP_EVENT_HORIZON = 4, /* valid: nothing known before `time`, when the sphere must be
                             * re-predicted (predictions that looked only nearby) */
} nbep_event_kind;

typedef struct nbep_event {
    double time;            /* absolute simulation time of contact; +inf: never */
    uint32_t partner;       /* sphere or plane index, by kind */
    uint32_t kind;          /* nbep_event_kind */
    uint64_t ver_self;      /* response count of the slot's sphere at prediction */
    uint64_t ver_partner;   /* response count of the partner sphere (0 for planes) */
} nbep_event;

/* The slots, visible so that the accessors below inline into the event loops; only feq.c and
 * those accessors touch them. */
typedef struct nbep_feq {
    size_t n;            /* spheres, one slot each */
    nbep_event *slot;    /* owned, length n, cache-line aligned */
} nbep_feq;

/* A queue of n invalid slots. NBEP_ENOMEM with a message on failure. */
NBEP_MUST_CHECK nbep_status nbep_feq_create(size_t n, nbep_feq **out, nbep_diag *d);
/* Bytes nbep_feq_create(n) allocates, for memory estimates. */
size_t nbep_feq_bytes(size_t n);
/* NULL-safe; NULLs the pointer. */
void nbep_feq_destroy(nbep_feq **q);

/* Paper Procedure 10: stores e in sphere i's slot when the slot is invalid or e is earlier
 * (supersedes). Equal times keep the event with the smaller (kind, partner), so that the
 * result does not depend on the order of inserts. Returns true when e was stored. */
bool nbep_feq_insert(nbep_feq *q, size_t i, nbep_event e);
/* True when event a is kept over b by insert: earlier time; at equal times the smaller
 * (kind, partner), then the newer prediction. A strict order, so a minimum over any partition
 * of the predictions equals the minimum of them all (threads may each find a partial best). */
bool nbep_feq_event_before(const nbep_event *a, const nbep_event *b);
/* Marks sphere i's slot valid with nothing ahead (kind NBEP_EVENT_NEVER) as of response count
 * ver_self. */
void nbep_feq_set_never(nbep_feq *q, size_t i, uint64_t ver_self);
/* Paper Procedure 11: marks sphere i's slot invalid. */
void nbep_feq_remove(nbep_feq *q, size_t i);
/* The slot of sphere i (kind NBEP_EVENT_NONE when invalid). */
static inline const nbep_event *nbep_feq_slot(const nbep_feq *q, size_t i)
{
    return &q->slot[i];
}
/* An event time predicted at t_now, kept at t_now or after. A sphere is predicted from its own
 * local time, or a pair from the later of the two (not from now: moving them there would
 * round their flights once more), and a root between that time and now is one the
 * predictions made before had not found: a pair left touching by a response (e = 0, the
 * normal speed 7e-12 m/s, the gap 3e-17 m) whose gap rounds to +3e-17 from one local time
 * and -2e-17 from another, its contact predicted 4e-6 s ahead and then at zero time from a
 * clock 3e-7 s behind now. Placed behind now, the event sent its spheres off on a course
 * that began before events already handled, and the pairs behind it overlapped by 1e-10
 * (max_overlap_rel 2.5e-8 in a tilted pile at dt = 0.05, both loops: the rounds went back in
 * time). At now, the pair meets as it is: overlapping by round-off. */
static inline double nbep_feq_not_before(double time, double t_now)
{
    return time < t_now ? t_now : time;
}

/* Stores e in sphere i's slot whatever was there: a fresh prediction from scratch (kind
 * SPHERE, PLANE or HORIZON with a finite time, or NEVER), or a slot put back as it was (the
 * team loop's undo). An event at +inf of a kind that names a partner would reach the frames'
 * /checkpoint/event_time as inf (a mutant of the cells mode's pair loop that kept a miss
 * showed it): asserted, one compare an event. */
static inline void nbep_feq_put(nbep_feq *q, size_t i, nbep_event e)
{
    assert(isfinite(e.time) || e.kind == NBEP_EVENT_NEVER || e.kind == NBEP_EVENT_NONE);
    q->slot[i] = e;
}

/* Paper Procedure 13, for one thread's spheres [lo, hi): writes to out (room for hi - lo ids)
 * the spheres whose valid event happens before t_end, in increasing index, and returns their
 * count. The paper's `== current_time` becomes `< t_end`: events fall anywhere inside a step. */
size_t nbep_feq_find(const nbep_feq *q, size_t lo, size_t hi, double t_end, uint32_t *out);
/* Paper Procedure 12, for [lo, hi): writes the spheres with an invalid slot, returns count. */
size_t nbep_feq_find_invalid(const nbep_feq *q, size_t lo, size_t hi, uint32_t *out);

/* Invariant check for tests: every valid slot has a finite time >= t_now, a partner within
 * range (n spheres, n_planes planes) and not itself. Returns the number of bad slots and
 * describes the first in *d. */
size_t nbep_feq_check(const nbep_feq *q, double t_now, size_t n_planes, nbep_diag *d);

#endif
