/* The cells engine of the predictive algorithm (run.neighbors = "cells", beyond the paper): a
 * step's events processed one at a time in time order from an event calendar (calendar.h),
 * each re-prediction testing only the 27-cell block of cell lists kept up to date by cell-exit
 * events (cells.h), spheres moved lazily (each keeps its own local time). Per event the work is
 * O(log n) for the calendar plus a re-prediction of the one or two spheres involved against
 * their block: independent of n.
 *
 * The engine owns the calendar and the cells, and borrows the algorithm's one-slot event queue
 * (feq.h) and response counts: a sphere's slot holds the earliest of its contacts with the
 * planes and the spheres of its block and its cell exit (kind HORIZON), and the calendar holds
 * every slot that is not NEVER. The physics (contact times with both spheres brought to the
 * later local time, responses, resting contact) stays with the algorithm, reached through
 * nbep_evloop_ops, so there is one copy of it.
 *
 * Events are handled in the order (time, pair key, sphere): a slot that names a partner whose
 * response count moved on is stale and its sphere is re-predicted; a cell exit moves the sphere
 * into the cell its centre is in then and re-predicts it; any other event reacts and both its
 * spheres (and any other sphere the reaction changed) are re-predicted. The loop is serial (one thread), so results cannot depend on the
 * thread count; nbep_evloop_assign and nbep_evloop_predict are per sphere and run on every
 * thread's own range. */
#ifndef NBEP_EVLOOP_H
#define NBEP_EVLOOP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/feq.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

/* The algorithm's side. u is the caller's context, passed through. */
typedef struct nbep_evloop_ops {
    /* the earliest contact of sphere i with a plane, kind NONE when none */
    nbep_event (*planes)(void *u, uint32_t i);
    /* lowers *best (kind NONE: nothing yet) to the earliest contact of sphere i with the m
     * spheres js (none of them i), each taken at its position plus shift (a copy of the box
     * across periodic faces; zero otherwise); called with the block's members a batch at a
     * time */
    void (*pairs)(void *u, uint32_t i, const uint32_t *js, size_t m, nbep_vec3 shift,
                  nbep_event *best);
    /* true while the event in i's slot is still valid (no response since it was predicted) */
    bool (*fresh)(void *u, uint32_t i, const nbep_event *ev);
    /* reacts to the event in i's slot (a sphere or plane contact), at its time; returns the
     * number of spheres whose motion it changed and points *changed at them (the event's own
     * and any that resting or held contact moved; the loop re-predicts each) */
    size_t (*react)(void *u, uint32_t i, const nbep_event *ev, const uint32_t **changed);
    /* sphere i's centre, velocity and acceleration at absolute time t (not stored) */
    void (*flight)(void *u, uint32_t i, double t, nbep_vec3 *p, nbep_vec3 *v, nbep_vec3 *a);
    /* periodic boxes only (may be NULL otherwise): sphere i, leaving its cell at absolute time
     * t, is brought to t and wrapped into the box (periodic.h), its image count kept */
    void (*wrap)(void *u, uint32_t i, double t);
} nbep_evloop_ops;

typedef struct nbep_evloop nbep_evloop;

/* An engine for n spheres in the box [lo, hi] whose contacts happen within `reach` (the
 * largest diameter), with the slots q and response counts ver (both borrowed, n each).
 * periodic (NULL: none) names the axes along which the box repeats: the cells wrap around
 * (cells.h), partners across a periodic face are tested at their image, and a sphere that
 * leaves the box is wrapped (ops->wrap) when it changes cell. */
NBEP_MUST_CHECK nbep_status nbep_evloop_create(size_t n, nbep_vec3 lo, nbep_vec3 hi,
                                               double reach, const bool *periodic,
                                               nbep_feq *q, const uint64_t *ver,
                                               nbep_evloop **out, nbep_diag *d);
void nbep_evloop_destroy(nbep_evloop **e);

/* A full rebuild, from spheres that all sit at one time t: (1) every thread assigns its range
 * to cells, (2) one thread links the lists, (3) every thread predicts its range (writes those
 * slots), (4) one thread schedules every slot. Barriers between the parts are the caller's. */
void nbep_evloop_assign(nbep_evloop *e, const nbep_vec3 *pos, size_t lo, size_t hi);
void nbep_evloop_link(nbep_evloop *e);
void nbep_evloop_predict(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, size_t lo,
                         size_t hi, double t);
void nbep_evloop_schedule(nbep_evloop *e);

/* What one call of nbep_evloop_run did. */
typedef struct nbep_evloop_tally {
    uint64_t events;     /* calendar entries handled (stale, exits and reactions) */
    uint64_t reactions;
    uint64_t exits;      /* cell exits */
} nbep_evloop_tally;

/* Handles every event before t_end, in order. One thread. Returns false, with the time of
 * the stuck event in *t_stuck, when `stall_events` events in a row did not advance time by
 * more than stall_dt (a cascade of zero-time events the model cannot resolve). */
bool nbep_evloop_run(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, double t_end,
                     uint64_t stall_events, double stall_dt, nbep_evloop_tally *tally,
                     double *t_stuck);

/* Calls visit(u, j) for every sphere j (i included) in the 27-cell block of i's cell: every
 * sphere that can touch i. Read-only; a react callback may call it. */
void nbep_evloop_visit_block(const nbep_evloop *e, uint32_t i,
                             void (*visit)(void *u, uint32_t j), void *u);

/* Bytes the engine itself takes for n spheres (calendar and cells). */
size_t nbep_evloop_bytes(size_t n);

#endif
