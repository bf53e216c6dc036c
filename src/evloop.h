/* The cells engine of the predictive algorithm (run.neighbors = "cells", beyond the paper): a
 * step's events processed one at a time in time order from an event calendar (calendar.h),
 * each re-prediction testing only the sphere's neighbour list (nblist.h): the spheres whose
 * centres were within contact distance plus a skin when the list was built. Cell lists of the
 * list centres (cells.h) find the new neighbours when a list is rebuilt, which happens when
 * its sphere has strayed half the skin from where it was built (an expiry event, kind
 * HORIZON), so no pair can touch without being listed. Spheres move lazily (each keeps its own
 * local time). Per event the work is O(log n) for the calendar plus a re-prediction of the one
 * or two spheres involved against their lists (12 to 20 spheres in a dense fluid, against 20
 * to 30 in the 27-cell block the engine scanned before): independent of n.
 *
 * The engine owns the calendar, the cells and the lists, and borrows the algorithm's one-slot
 * event queue (feq.h) and response counts: a sphere's slot holds the earliest of its contacts
 * with the planes and its listed spheres and its list's expiry, and the calendar holds every
 * slot that is not NEVER. The physics (contact times with both spheres brought to the later
 * local time, responses, resting contact) stays with the algorithm, reached through
 * nbep_evloop_ops, so there is one copy of it.
 *
 * Events are handled in the order (time, pair key, sphere): a slot that names a partner whose
 * response count moved on is stale and its sphere is re-predicted; an expiry wraps the sphere into
 * a periodic box if it left it, rebuilds its list around where it is and re-predicts it; any other
 * event reacts and both its spheres (and any other sphere the reaction changed) are re-predicted.
 * nbep_evloop_run handles them on one thread; nbep_evloop_run_lead with nbep_evloop_help on a team
 * of threads (the team loop, below), with the same results bit for bit, so results cannot depend
 * on the thread count. An event is handled in two parts: handle (the motion and slots of its
 * spheres; an expiry's new list found by a walk that reads the cells and lists only) and commit
 * (the new list entered, the cells changed, the calendar entries set). The full rebuild
 * (nbep_evloop_assign, _count, _predict) is per sphere and runs on every thread's own range. */
#ifndef NBEP_EVLOOP_H
#define NBEP_EVLOOP_H

#include <math.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/feq.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

/* What an event may change of one sphere (the team loop keeps it to undo a speculative one). */
typedef struct nbep_evloop_motion {
    nbep_vec3 pos, vel;
    double tau;           /* its local time */
    uint64_t ver;         /* its response count */
    int32_t image[3];
    uint64_t own[2];      /* two words of the caller's own that a reaction may change (the
                           * predictive algorithm's: the TC model's clock, the reaction
                           * count); the engine only keeps them */
} nbep_evloop_motion;

/* The caller's counts and sums as they stood before an event (ops mark, opaque here), which
 * the scheduled loop keeps so that a rollback puts them back (ops back). */
typedef struct nbep_evloop_mark {
    uint64_t word[11];
} nbep_evloop_mark;

/* The algorithm's side. u is the caller's context, passed through. */
typedef struct nbep_evloop_ops {
    /* the earliest contact of sphere i with a plane, kind NONE when none */
    nbep_event (*planes)(void *u, uint32_t i);
    /* lowers *best (kind NONE: nothing yet) to the earliest contact of sphere i with the m
     * spheres js (none of them i); in a periodic box each at its image nearest to i, which
     * is the sphere itself for all of them when images is false (i is far from every
     * periodic face: the engine knows, see near_face) */
    void (*pairs)(void *u, uint32_t i, const uint32_t *js, size_t m, bool images,
                  nbep_event *best);
    /* true while the event in i's slot is still valid (no response since it was predicted) */
    bool (*fresh)(void *u, uint32_t i, const nbep_event *ev);
    /* reacts to the event in i's slot (a sphere or plane contact), at its time; returns the
     * number of spheres whose motion it changed and points *changed at them (the event's own
     * and any that resting or held contact moved; the loop re-predicts each). Setting *stop
     * (false on entry) ends the run after this event: nbep_evloop_run returns false with its
     * time in *t_stuck (the caller knows why it asked); the team loop does the same once the
     * event stands, so a speculative event's stop that is undone stops nothing */
    size_t (*react)(void *u, uint32_t i, const nbep_event *ev, const uint32_t **changed,
                    bool *stop);
    /* sphere i's centre, velocity and acceleration at absolute time t (not stored) */
    void (*flight)(void *u, uint32_t i, double t, nbep_vec3 *p, nbep_vec3 *v, nbep_vec3 *a);
    /* periodic boxes only (may be NULL otherwise): flight's answer for sphere i, leaving its
     * cell at absolute time t, after it is brought to t and wrapped into the box (periodic.h),
     * its image count kept, where its centre is then outside the box (an expiry takes its new
     * list's centre from it: one flight, not a flight to test and another to take) */
    void (*wrap)(void *u, uint32_t i, double t, nbep_vec3 *p, nbep_vec3 *v, nbep_vec3 *a);
    /* the team and scheduled loops only (may be NULL otherwise): sphere i's motion kept and
     * put back */
    void (*save)(void *u, uint32_t i, nbep_evloop_motion *m);
    void (*restore)(void *u, uint32_t i, const nbep_evloop_motion *m);
    /* the team loop only: context uh's counts and sums from zero, before it handles one
     * event (on the thread that handles it: the lines stay on that core until the merge) */
    void (*clear)(void *uh);
    /* the team loop only: context uh has handled one event that stands; its counts and sums
     * (kept apart, from zero) go into u, the context of the thread that handled it, on that
     * thread; every sum is exact, so the total over the threads is the one thread's bit for
     * bit (an undone event's are never merged) */
    void (*merge)(void *u, const void *uh);
    /* the team and scheduled loops only (may be NULL): requests sphere i's motion, which a
     * handle is about to read and write (no effect on results) */
    void (*prefetch)(const void *u, uint32_t i);
    /* the scheduled loop only (the three set together, or all NULL: a rollback then leaves the
     * counts as they are, each event undone counted again): mark, before each event, context
     * u's counts and sums as they stand into *m (false: the record of the sums' terms that
     * back needs ran out of memory; *m is whole all the same); back, at a rollback, puts them
     * as they were at *m, the terms added to the sums since then taken out again (exactly: the
     * sums are exact, xsum.h); settle, at a window's end, when every event so far stands: the
     * record of terms emptied */
    bool (*mark)(const void *u, struct nbep_evloop_mark *m);
    void (*back)(void *u, const struct nbep_evloop_mark *m);
    void (*settle)(void *u);
} nbep_evloop_ops;

typedef struct nbep_evloop nbep_evloop;

/* An engine for n spheres in the box [lo, hi] whose contacts happen within `reach` (the
 * largest diameter), with lists of the skin skin_frac * reach (nbep_scene_list_skin's; cut
 * down in a small periodic box: nbep_evloop_skin_in), with the slots q and response counts ver (both borrowed, n each).
 * periodic (NULL: none) names the axes along which the box repeats: the cells wrap around
 * (cells.h), partners across a periodic face are tested at their image, and a sphere that
 * leaves the box is wrapped (ops->wrap) when it changes cell. team (1 to
 * NBEP_EVLOOP_TEAM_MAX): the threads that may run the team loop together. */
NBEP_MUST_CHECK nbep_status nbep_evloop_create(size_t n, nbep_vec3 lo, nbep_vec3 hi,
                                               double reach, double skin_frac,
                                               const bool *periodic, int team, nbep_feq *q,
                                               const uint64_t *ver,
                                               nbep_evloop **out, nbep_diag *d);
void nbep_evloop_destroy(nbep_evloop **e);
/* Each list to hold only the partners within its pair's own cutoff, the pair's contact
 * distance r_i + r_j plus the skin (radius: n, borrowed, unchanged while the engine lives; no
 * radius above half the reach): in a mixture a small sphere's list then holds its own kind's
 * neighbours, not every sphere within the largest pair's reach. Before the first rebuild;
 * NULL (as created): one cutoff, the largest pair's, for every pair. */
void nbep_evloop_set_radii(nbep_evloop *e, const double *radius);
/* The calendar cut into `slabs` per-slab calendars across x, merged on one thread
 * (slabcal.h; step 1 of docs/optimistic-design.md): the events come out in the same order, so
 * the run is the same bit for bit; what changes is the cost of finding the earliest. Fewer
 * than 2: one calendar (as created). Only on an engine created for a team of one (the team
 * loop keeps one calendar), before the first schedule. NBEP_ENOMEM, NBEP_EDECK past
 * NBEP_SLABCAL_MAX, with a message. */
NBEP_MUST_CHECK nbep_status nbep_evloop_set_slabs(nbep_evloop *e, int slabs, nbep_diag *d);
/* The one-thread loop run through the optimistic scheduler (warp.h) on one slab (or, on an
 * engine with slabs, on each of them: nbep_evloop_set_worlds; nbep_evloop_run_lead with
 * nbep_evloop_help runs the slabs on the crew's threads, thread t slabs t, t + crew, ...,
 * each thread its own in turns), for measuring what its bookkeeping costs the real engine (NBEP_SCHEDULED; docs/optimistic-
 * design.md, *The engine on the scheduler*): each event handled as the scheduler's model
 * handles it, what it changes kept in the slab's log (its spheres' motion and slots, an
 * expiry's list record), in windows of a 64th of the call's span. The same events in the same
 * order: the results are the same bit for bit. For free flight (the motion kept is a free
 * flight's). Entries made at the time of the event that made them (a cascade's tie at one
 * time) are stamped as made (cascade.h); a cascade deeper than a stamp holds
 * (NBEP_CASCADE_DEPTH) stops the run at its time (nbep_evloop_run false, and
 * nbep_evloop_too_deep true). Only on an engine for one thread, after nbep_evloop_set_slabs if
 * any, before the first run. NBEP_ENOMEM with a message. */
NBEP_MUST_CHECK nbep_status nbep_evloop_set_scheduled(nbep_evloop *e, nbep_diag *d);
/* The scheduled loop on slabs (nbep_evloop_set_scheduled on an engine with slabs, on one
 * thread or a crew's): each slab acts in a world of its own, wu[s] (the callbacks' context
 * whose motion arrays are slab s's) with response counts wver[s] (both borrowed, set before
 * each call): the call copies the context's motion into each at its start, each slab's own
 * spheres (nbep_slabcal's) back at its end, and merges their counts (ops clear, merge), so that
 * every op is needed (save, restore, clear, merge, mark, back, settle). */
void nbep_evloop_set_worlds(nbep_evloop *e, void *const *wu, const uint64_t *const *wver);
/* True where the scheduled loop (nbep_evloop_set_scheduled) stopped its last call at a cascade
 * at one time deeper than its stamps hold; false otherwise (and without the setting). */
bool nbep_evloop_too_deep(const nbep_evloop *e);
/* The lists' skin that the engine takes when asked for skin_frac of `reach`: cut
 * down in a small periodic box (its sides hi - lo along the axes that periodic names; NULL:
 * none) so that three cells, sides of the cutoff, fit across. Below NBEP_NBLIST_SKIN_MIN the
 * engine refuses the box (the deck check first: nbep_evloop_min_periodic_side). */
double nbep_evloop_skin_in(double skin_frac, double reach, const bool *periodic, nbep_vec3 lo,
                           nbep_vec3 hi);
/* The shortest periodic side the engine takes for contacts within `reach`: three cells of
 * the list cutoff with the thinnest skin (NBEP_NBLIST_SKIN_MIN); a shorter one is refused. */
double nbep_evloop_min_periodic_side(double reach);

/* A scene without a box: the cells laid out afresh over [lo, hi], the extent of the spheres'
 * centres now (with a margin), before a full rebuild (one thread, before part 1). Between
 * rebuilds spheres may leave it: they are clamped into its edge cells (cells.h), so contacts are
 * still found, at the cost of fuller cells there. No periodic axis. Out of memory:
 * NBEP_ENOMEM with a message. */
NBEP_MUST_CHECK nbep_status nbep_evloop_refit(nbep_evloop *e, nbep_vec3 lo, nbep_vec3 hi,
                                              nbep_diag *d);
/* A full rebuild, from spheres that all sit at one time t: (1) every thread assigns its range
 * to cells, (2) one thread links the cell lists, (3) every thread counts its range's
 * neighbours, (4) one thread lays the neighbour lists out, (5) every thread fills its range's
 * lists and predicts its range (writes those slots), (6) one thread schedules every slot.
 * Barriers between the parts are the caller's. Out of memory for the lists: nothing is
 * predicted and nbep_evloop_failed says so. */
void nbep_evloop_assign(nbep_evloop *e, const nbep_vec3 *pos, size_t lo, size_t hi);
void nbep_evloop_link(nbep_evloop *e);
void nbep_evloop_count(nbep_evloop *e, size_t lo, size_t hi);
void nbep_evloop_layout(nbep_evloop *e);
void nbep_evloop_predict(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, size_t lo,
                         size_t hi, double t);
void nbep_evloop_schedule(nbep_evloop *e, double t);
/* True once a neighbour list, or a slab's calendar growing (nbep_evloop_set_slabs), could not
 * get memory (at a rebuild or in nbep_evloop_run, which then returns false): the run must
 * stop. */
bool nbep_evloop_failed(const nbep_evloop *e);

/* What one call of nbep_evloop_run did. */
typedef struct nbep_evloop_tally {
    uint64_t events;     /* calendar entries handled (stale, expiries and reactions) */
    uint64_t reactions;
    uint64_t exits;      /* list expiries (rebuilds of one list) */
    uint64_t ahead;      /* team loop: events handled ahead (not a window's first) that stood */
    uint64_t undone;     /* team loop: events handled ahead and undone */
} nbep_evloop_tally;

/* The stall check: every `events` events time must have advanced by more than dt. `since`
 * and `t_mark` (0 and -INFINITY at a step's start, NBEP_EVLOOP_STALL) carry the count from one
 * call to the next, so that a step whose events run in two calls (the first part of the step
 * on other threads) checks them as one call would. With it, every NBEP_EVLOOP_STOP_EVERY
 * events, a look at the run's stop signal (`stop`, may be NULL): a signal ends the call as a
 * stall does, with `stopped` set, so that a step far longer than a job's grace after its
 * SIGTERM is abandoned instead of killed (README, Faults); else `on_look` (may be NULL) is
 * called with the event's time, for the run's progress within a long step. */
typedef struct nbep_evloop_stall {
    uint64_t events;
    double dt;
    uint64_t since;  /* events since t_mark */
    double t_mark;
    const atomic_int *stop; /* borrowed, may be NULL: nonzero = SIGINT/SIGTERM number */
    uint64_t looks;         /* events since the last look at stop */
    bool stopped;           /* the call ended at a look that found a signal */
    void (*on_look)(void *ctx, double t);
    void *look_ctx;
} nbep_evloop_stall;
#define NBEP_EVLOOP_STALL(events, dt, stop, on_look, look_ctx)                                    \
    ((nbep_evloop_stall){(events), (dt), 0, -INFINITY, (stop), 0, false, (on_look), (look_ctx)})
/* A look at the stop signal every this many events: a relaxed load, a few tenths of a
 * nanosecond an event, and at about a million events a second on one core a signal is seen
 * within a tenth of a second. */
#define NBEP_EVLOOP_STOP_EVERY 65536u

/* Handles every event before t_end, in order. One thread. Returns false, with the time of
 * the stuck event in *t_stuck, when the stall check fails (a cascade of zero-time events the
 * model cannot resolve), when memory could not be had (nbep_evloop_failed), or
 * after an event whose reaction set *stop (ops react). */
bool nbep_evloop_run(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, double t_end,
                     nbep_evloop_stall *stall, nbep_evloop_tally *tally, double *t_stuck);

/* The team loop's ring of places (a power of 2, more than the places it keeps in flight):
 * the contexts a caller passes it (us, below), one per ring slot. */
#define NBEP_EVLOOP_RING 32
/* The most threads that run the team loop together (the leader and its helpers). */
#define NBEP_EVLOOP_TEAM_MAX 16

/* nbep_evloop_run on `crew` threads (2 to the engine's team), with the same results bit for bit.
 * The leader (thread 0) keeps a window of places in flight: the calendar's earliest events, taken
 * out of it in order while each is apart from every place in flight (both spheres of each, the one
 * whose entry it is and the other its slot names, list centres twice (cutoff + (1 +
 * NBEP_NBLIST_LEAD) strays) apart, and cells 4 apart along an axis when both are list expiries:
 * none reads what another writes, and lists, cells and calendar are written only at commits), the
 * entries of the other spheres of its pairs taken out with them. The leader and the helpers
 * (threads 1 to crew - 1, in nbep_evloop_help at the same time, each with its number t) take the
 * places one at a time and handle them, each but a window's first speculatively (what it may change
 * kept: ops save). The leader commits them in order, and adds places behind them as they free the
 * window: a place stands if no entry left in the calendar comes before it (the one thread would
 * handle it next, from the same state), else it and the places after it are undone (ops restore),
 * their entries put back, and handled again. The event at place m is handled with context us[m %
 * NBEP_EVLOOP_RING] of the thread that takes it (each thread passes its own array: one context per
 * ring slot, the place's counts and sums kept apart), and added (ops merge) to u, the context of
 * the thread that handled it (the leader's, or the helper's own passed to nbep_evloop_help),
 * once it stands: by that thread, before it reuses the slot's context or as the call ends, so
 * no thread reads another's counts; the sums are exact and the counts integers, so the caller's
 * total over the threads' u is the one thread's. For scenes whose reactions change only
 * the event's own spheres (the caller's choice: an elastic scene where nothing accelerates).
 * `call` (> 0) names the call, the same on the leader and its helpers and unlike every earlier
 * call's (one per part of a step: a thread may sit out calls of fewer threads, and must not
 * take an earlier call's end for this one's). Returns as nbep_evloop_run; the helpers return
 * when it does. */
bool nbep_evloop_run_lead(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                          int crew, uint64_t call, double t_end, nbep_evloop_stall *stall,
                          nbep_evloop_tally *tally, double *t_stuck);
void nbep_evloop_help(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, void *const *us,
                      int t, uint64_t call);
/* The leader's way out of call `call` without running it (a failure before it: the scheduled
 * loop's worlds without memory), so that helpers already waiting in nbep_evloop_help return:
 * for the scheduled loop on slabs, whose helpers wait for the call's windows (the team loop's
 * run_lead always ends its call). */
void nbep_evloop_release(nbep_evloop *e, uint64_t call);

/* Calls visit(u, j) for sphere i and every sphere j of its neighbour list: every sphere that
 * can touch i. Read-only; a react callback may call it. */
void nbep_evloop_visit_block(const nbep_evloop *e, uint32_t i,
                             void (*visit)(void *u, uint32_t j), void *u);

/* Bytes nbep_evloop_create(n, ..., team, ...) allocates and its lists grow to with `neighbours`
 * listed per sphere on average (its own record, calendar, cells, lists, counts, and the team's
 * workspaces: one per thread per ring slot, at their first room), with nbep_evloop_set_slabs'
 * calendars for `slabs` of 2 or more, for memory estimates. */
size_t nbep_evloop_bytes(size_t n, double neighbours, int team, int slabs);

#endif
