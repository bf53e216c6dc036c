/* The cells engine's insides, shared by its two loops: the one-thread loop and the engine
 * itself (evloop.c) and the team loop (evloop_team.c, nbep_evloop_run_lead and
 * nbep_evloop_help). Nothing outside the engine includes this. */
#ifndef NBEP_EVLOOP_IMPL_H
#define NBEP_EVLOOP_IMPL_H

#include "evloop.h"

#include <stdalign.h>
#include <stdatomic.h>
#include <stddef.h>

#include "nbep/calendar.h"
#include "nbep/cells.h"
#include "nbep/compiler.h"
#include "nbep/nblist.h"
#include "nbep/periodic.h"
#include "nbep/slabcal.h"

/* The team loop's places in flight at most: enough that a helper finds one to take while the
 * leader commits (a window of 12 to 32 ran within the noise of this one at N = 256000,
 * phi = 0.30, with one helper; more helpers may want more, unmeasured). */
#define WINDOW 16

/* The calendar entries an event's workspace holds for its commit (a pair's two spheres), and
 * the mark of more. */
#define NEXT_MAX 2
#define NEXT_ALL UINT8_MAX

/* One thread's side of an event (handle, then commit): the list a rebuild found and what the
 * event changed, held until its commit; for a speculative event (the team loop's), the
 * motion and slots it may change, kept to undo it. */
typedef struct evl_ws {
    /* the event handled, waiting for its commit, and what the commit reads first, on one
     * cache line (the team's leader waits for it and reads it from another core; a
     * workspace starts a line): in the team loop, the number of the place last handled on it
     * (stored last, with release: what handle wrote is then there to read); the calendar
     * entries to set, the changed spheres' then item's, from the slots handle wrote (n_next
     * of them; NEXT_ALL where there were more than NEXT_MAX: the commit reads them from the
     * slots), each set or, where next_set is false, taken out */
    alignas(NBEP_CACHELINE) _Atomic uint64_t place;
    uint32_t item;
    bool rebuilt;           /* a list expiry: near is item's list, built around `at` */
    bool reacted;
    bool stop;              /* the reaction asked the run to stop after it (ops react) */
    bool oom;               /* out of memory for the walk or the copy of `changed` */
    uint8_t n_next;
    uint32_t next_item[NEXT_MAX];
    bool next_set[NEXT_MAX];
    double next_time[NEXT_MAX];
    uint64_t next_key[NEXT_MAX];
    /* the team loop: the number of the place last handled here once it stood, written by the
     * leader as it commits the place (on the line after the one it reads first, which for a
     * pair's event it reads no more of: it writes without waiting for it), and whether the
     * handler has yet to add that place's counts and sums (its context's) to its own
     * (pending: the handler's alone). The handler reads `stood` before it handles another
     * place here, published after the write, or at the call's end, after quit: so the leader
     * reads none of a helper's counts (settle) */
    uint64_t stood;
    bool pending;
    /* a rebuild of one list (walk): near holds the new list, gain[k] set for the entries i's
     * old list lacked; was holds the old list (n_was entries), kept[k] set for those found
     * again */
    uint32_t *near, *was;   /* owned, room for cap each */
    uint8_t *kept, *gain;   /* owned, room for cap each */
    size_t cap, n_near, n_was;
    nbep_vec3 at;           /* the new list's centre, and its cell (nbep_cells_locate) */
    size_t at_cell;
    uint32_t *changed;      /* owned, room for chg_cap: the spheres the reaction changed */
    size_t n_changed, chg_cap;
    /* a speculative event's undo: the spheres it may change, as they were */
    uint32_t kept_id[2];
    nbep_evloop_motion kept_motion[2];
    nbep_event kept_slot[2];
    int n_kept;
} evl_ws;

/* What an expiry's commit changed besides its workspace's lists (was, near and their flags),
 * for nbep__evloop_unapply to undo it exactly, order included: the building block of expiries
 * run ahead by an optimistic engine (docs/optimistic-design.md, *Lists undone*). */
typedef struct evl_unlist {
    nbep_vec3 at;          /* the list's centre before */
    uint32_t cell, prev;   /* its cell before, and the member before it there */
    uint32_t *drop_q;      /* owned, room cap: where each lost neighbour's list held it, in
                            * the order of was */
    size_t n_drop, cap;
} evl_unlist;

/* Whose lists an expiry's commit changes, by slab across x (docs/optimistic-design.md, *Lists
 * by message*): for each entry of its workspace's new list (near) and old list (was), the slab
 * of that neighbour (its list centre's cell column's: nbep__evloop_slab_in) when the commit
 * was made (nbep__listmsg_split). The commit's own slab changes its sphere's own list, centre
 * and cell and the lists of its own neighbours (nbep__evloop_apply_part); each other slab
 * changes those of its own from a message (nbep__listmsg_make, nbep__listmsg_apply). */
typedef struct evl_split {
    uint8_t *near, *was;   /* owned, room cap_near and cap_was */
    size_t cap_near, cap_was;
} evl_split;

/* A list message: what an expiry's commit changes in one slab's lists. Sphere `item` enters
 * the lists of id[0 .. n_gain) and leaves those of id[n_gain .. n_gain + n_lose), in the
 * order the whole commit makes those changes (apply_rec in evloop.c); q holds where each lost
 * one's list held it once applied, for the undo. A list has at most one change of a commit,
 * so the message's changes and the sender's commute: applied in stamp order with every other
 * change of those lists, they leave each list as the whole commit does, its order too. */
typedef struct evl_listmsg {
    uint32_t item;
    size_t n_gain, n_lose;
    uint32_t *id, *q;      /* owned, room cap_id and cap_q */
    size_t cap_id, cap_q;
} evl_listmsg;

/* A cell message (ghost.c): sphere `item`'s list centre placed at `at`, in cell `cell`, by
 * an expiry's commit in another slab; what it replaced in the receiver's cells (old_at,
 * old_cell, old_prev) once applied, for the undo. */
typedef struct evl_cellmsg {
    nbep_vec3 at, old_at;
    uint32_t item, cell;
    uint32_t old_cell, old_prev;
} evl_cellmsg;

/* A place of the team loop's window, as every thread reads it: its sphere, the other sphere
 * its slot names and whether it was the calendar's earliest (nbep_evloop's batch). One record
 * of a place on one line: a taker meets one line that the leader wrote, not one per field. */
typedef struct evl_place {
    uint32_t item;
    uint32_t other;
    uint32_t first;
    uint32_t pad_; /* to 16 bytes: four records a line, none across two */
} evl_place;
_Static_assert(sizeof(evl_place) == 16, "a place's record divides a cache line");

struct nbep_evloop {
    size_t n;
    nbep_calendar *cal;   /* owned; NULL with slabs */
    nbep_slabcal *slabcal; /* owned, NULL but with slabs (nbep_evloop_set_slabs): the
                            * entries in per-slab calendars instead of cal, merged on one
                            * thread (the one-thread loop only) */
    nbep_cells cells;     /* owned: cells of the list centres, at least `cut` wide; a
                           * member's place (cells.m[i].at) is where i's list was built */
    nbep_nblist nl;       /* owned */
    uint32_t *count;      /* owned, n: list lengths, at a full rebuild */
    /* one per ring slot of the team loop and thread, the leader's [0] and helper t's [t]
     * (t < team): a place's workspace is its taker's, written by it alone, so that its lines
     * pass to another core only where the leader reads what a helper handled (one thread:
     * ws[0][0]) */
    evl_ws ws[NBEP_EVLOOP_TEAM_MAX][NBEP_EVLOOP_RING];
    int team;             /* the threads that may run the loop together (create) */
    int crew;             /* the leader's alone: the threads of this call (run_lead) */
    nbep_periodic pb;     /* the box's periodic geometry */
    double cut;           /* the list cutoff: contact distance plus skin, plus slack */
    double stray;         /* half the skin: how far a sphere goes before its list expires */
    const double *rad;    /* borrowed, n: the radii where each pair's own cutoff is taken
                           * (nbep_evloop_set_radii); NULL: every pair's is `cut` */
    double reach;         /* twice the largest radius (create) */
    double skin;          /* the skin, twice stray: a pair's cutoff is its contact distance
                           * plus the skin, plus slack (pair_cut) */
    double face_reach;    /* cut + stray, and a margin: see near_face */
    double face_lo[3], face_hi[3]; /* near_face's faces: a periodic axis's low and high
                                    * sides, -inf and +inf on any other */
    bool failed;          /* out of memory for a list: the run stops */
    struct evl_sched *sched; /* owned, NULL but with nbep_evloop_set_scheduled */
    int own_slab;         /* the scheduled loop on slabs: the slab whose world the engine acts
                           * in, which predicts and enters only its own spheres (another's
                           * sphere that an event changes is its owner's to predict:
                           * evloop_warp.c); -1 (every other loop): every sphere its own */
    nbep_feq *q;          /* borrowed */
    const uint64_t *ver;  /* borrowed */
    /* the team loop's window: the places handled ahead and not yet committed, numbered in
     * order (place s lives in ring slot s % NBEP_EVLOOP_RING). Written by the leader and read
     * by both threads: each one's sphere, the other sphere its slot names (a pair's partner,
     * fresh or stale; NO_SPHERE for a plane or an expiry), and whether it was the calendar's
     * earliest when the window was empty (it stands, and is neither kept nor checked) */
    alignas(NBEP_CACHELINE) evl_place batch[NBEP_EVLOOP_RING];
    /* the leader's alone (a line that another core reads makes each write to it wait): the
     * list centres of the window's spheres as floats (place p's own at 2 (p % WINDOW), its
     * other's next; +inf for none), for the places that join (place_apart); whether each
     * place is a list expiry (its handle walks the cells around its sphere and its commit
     * changes them) and then the cell coordinates of its list centre; each place's calendar
     * entry, taken out while it is in flight, and the window's last (cur); the window, places
     * head .. tail - 1, more looked for once head reaches fill_at */
    alignas(NBEP_CACHELINE) float taken_x[2 * WINDOW];
    alignas(NBEP_CACHELINE) float taken_y[2 * WINDOW];
    alignas(NBEP_CACHELINE) float taken_z[2 * WINDOW];
    float near2;          /* the square of the distance beyond which two events touch nothing
                           * in common, for those float centres (set_near2) */
    float len_f[3], half_f[3]; /* the periodic sides and their halves (+inf: not periodic) */
    double shore;         /* how far a centre is taken past a side that is not periodic */
    bool batch_walks[NBEP_EVLOOP_RING];
    size_t batch_cell[NBEP_EVLOOP_RING][3];
    nbep_calendar_entry batch_entry[NBEP_EVLOOP_RING], cur;
    uint64_t head, tail, fill_at;
    uint64_t lead_seen;   /* the leader's last reading of avail (take_one) */
    /* the hand-over: the leader publishes places up to avail; any thread of the team takes
     * the next place to handle from `next` and marks it handled (its number, in its
     * workspace's `place`); the leader posts the end of a call in quit (the call's number),
     * helper t answers it in done[t].word */
    alignas(NBEP_CACHELINE) _Atomic uint64_t avail;
    alignas(NBEP_CACHELINE) _Atomic uint64_t next;
    alignas(NBEP_CACHELINE) _Atomic uint64_t quit;
    struct {
        alignas(NBEP_CACHELINE) _Atomic uint64_t word;
    } done[NBEP_EVLOOP_TEAM_MAX];
};

_Static_assert(offsetof(evl_ws, next_key) + sizeof((evl_ws *)0)->next_key <= NBEP_CACHELINE,
               "what a commit reads first is on one cache line");

/* ---- shared by both loops (evloop.c) ------------------------------------------------------- */

/* Handles the event of sphere i (its slot ev, at absolute time t) on workspace w: reacts if
 * the slot is fresh and predicts the spheres it changed, writing their motion and slots only;
 * a list expiry walks the cells for the new list. What the calendar, the lists and the cells
 * need is left on w for nbep__evloop_commit. `commits`: this thread commits it next (the one
 * thread's loop), so an expiry requests the lists its commit changes while it predicts (a
 * team's handler leaves that to the leader, which commits on its own core). */
void nbep__evloop_handle(nbep_evloop *e, evl_ws *w, const nbep_evloop_ops *ops, void *u,
                         uint32_t i, const nbep_event *ev, double t, bool commits);
/* What nbep__evloop_handle left waiting on w: the new list entered, the changed spheres'
 * calendar entries set. */
void nbep__evloop_commit(nbep_evloop *e, const evl_ws *w);
/* nbep__evloop_commit's part for an expiry, recording in *u what undoes it (the workspace w
 * must be kept as it is until then): nbep__evloop_unapply(e, w, u), while nothing else changed
 * the lists and cells since, leaves them as they were, bit for bit (one thread). Out of memory:
 * the engine fails (nbep_evloop_failed), as at a commit. */
void nbep__evloop_apply_undoable(nbep_evloop *e, const evl_ws *w, evl_unlist *u);
void nbep__evloop_unapply(nbep_evloop *e, const evl_ws *w, const evl_unlist *u);
void nbep__evloop_unlist_fini(evl_unlist *u);
/* nbep__evloop_apply_undoable's part for slab `slab` of the split sp: the sphere's own list,
 * centre and cell, and the lists of the neighbours sp gives that slab; with the messages of
 * nbep__listmsg_make for every other slab applied, the lists and cells are as the whole
 * commit leaves them. Undone by nbep__evloop_unapply_part with the same sp and slab, once
 * every later change of those lists is undone (the messages' included). */
void nbep__evloop_apply_part(nbep_evloop *e, const evl_ws *w, evl_unlist *u,
                             const evl_split *sp, int slab);
void nbep__evloop_unapply_part(nbep_evloop *e, const evl_ws *w, const evl_unlist *u,
                               const evl_split *sp, int slab);
/* The lists' messages (listmsg.c). Into sp, the slab (of `slabs`) of each neighbour that the
 * expiry walked on w gains or loses; false without memory. */
bool nbep__listmsg_split(const nbep_evloop *e, const evl_ws *w, int slabs, evl_split *sp);
void nbep__listmsg_split_fini(evl_split *sp);
/* Into m, what the commit of w changes in the lists of slab `slab` of the split sp (none:
 * n_gain + n_lose == 0); false without memory. */
bool nbep__listmsg_make(const evl_ws *w, const evl_split *sp, int slab, evl_listmsg *m);
/* m's changes made to the lists l, each lost one's place kept in m; false without memory (a
 * list that could not grow: the run fails, as a commit's append that fails). */
bool nbep__listmsg_apply(nbep_nblist *l, evl_listmsg *m);
/* m's changes undone, newest first, while nothing since changed those lists (or what did is
 * undone); false without memory. */
bool nbep__listmsg_unapply(nbep_nblist *l, const evl_listmsg *m);
void nbep__listmsg_fini(evl_listmsg *m);
/* Ghost cells (ghost.c): each slab's own copy of the cells, exact on its columns and on the
 * columns beside them (what its expiries' walks read), kept so by its own commits and by the
 * cell messages of the others' commits. Whether slab `slab` of `slabs` keeps cell c so. */
bool nbep__ghost_keeps(const nbep_cells *g, int slabs, int slab, size_t c);
/* The slabs (a bit each, slab s bit s; NBEP_SLABCAL_MAX of them at most) other than `from`
 * (-1: none, every slab that keeps one: the meeting's) that a commit moving a centre from cell
 * `was` to cell `now` must tell (nbep__ghost_keeps either cell). */
uint64_t nbep__ghost_receivers(const nbep_cells *g, int slabs, int from, size_t was, size_t now);
/* m made in the slab's cells g (what it replaces kept in m), and undone (while nothing since
 * changed those cells, or what did is undone). */
void nbep__ghost_apply(nbep_cells *g, evl_cellmsg *m);
void nbep__ghost_unapply(nbep_cells *g, const evl_cellmsg *m);
/* d (zeroed, or made so before: its arrays made again where g's layout outgrew them) a copy
 * of g: its layout, members, places and links; false without memory (d then freed:
 * nbep_cells_fini). */
bool nbep__ghost_copy(nbep_cells *d, const nbep_cells *g);
/* Into d (zeroed, or a copy made so before; its arrays its own): what an expiry's apply and
 * its undo read of workspace w (its sphere, new centre and cell, the lists and their flags),
 * for an undo after the engine's workspace has gone on to other events. False without memory
 * (d's arrays then as they were, or grown). */
bool nbep__evloop_ws_copy_lists(evl_ws *d, const evl_ws *w);
/* Frees such a copy's arrays; zeroed again. */
void nbep__evloop_ws_copy_fini(evl_ws *d);
/* nbep__evloop_commit, an expiry's list entered with its record in *rec (as
 * nbep__evloop_apply_undoable) */
void nbep__evloop_commit_undoable(nbep_evloop *e, const evl_ws *w, evl_unlist *rec);
/* nbep_evloop_run through the optimistic scheduler, on one slab or, with slabs, on each
 * (evloop_warp.c) */
bool nbep__evloop_run_scheduled(nbep_evloop *e, const nbep_evloop_ops *ops, void *u,
                                int crew, uint64_t call, double t_end, nbep_evloop_stall *stall,
                                nbep_evloop_tally *tally, double *t_stuck);
/* With slabs on crew threads (nbep_evloop_run_lead's): thread t's part of call `call` (as
 * nbep_evloop_help's), its slabs run each window; returns when the lead's call does. */
void nbep__evloop_sched_help(nbep_evloop *e, int t, uint64_t call);
void nbep__evloop_sched_destroy(struct evl_sched **s);
/* A workspace of one's own (zeroed before: its arrays made; false without memory, the part made
 * freed by fini), and its arrays freed. */
bool nbep__evloop_ws_init(evl_ws *w);
void nbep__evloop_ws_fini(evl_ws *w);
/* The calendar entry of sphere i from its slot. */
void nbep__evloop_schedule_one(nbep_evloop *e, uint32_t i);
/* The cell columns that the expiry of sphere i at time t (in context u) would read or write,
 * from lo to hi (offsets across x from its list centre's column now, -1 or less and 1 or
 * more): its walk reads the columns beside its new centre's, its commit writes the lists of its
 * old and new members, in the columns beside its old and new centres', and the cells of
 * both. */
void nbep__evloop_expiry_span(const nbep_evloop *e, const nbep_evloop_ops *ops, void *u,
                              uint32_t i, double t, int *lo, int *hi);
/* Whether sphere i is the engine's to predict and enter: always, but on the scheduled loop's
 * slabs, where only the slab its engine acts in (own_slab) owns it. */
bool nbep__evloop_owned(const nbep_evloop *e, uint32_t i);
/* With slabs: the slab of sphere i (its list centre's cell column's). */
int nbep__evloop_sphere_slab(const nbep_evloop *e, uint32_t i);
/* Sphere i's slot predicted afresh at time t from its list, in context u (its calendar entry
 * not set: nbep__evloop_schedule_one). */
void nbep__evloop_predict_own(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                              double t);

/* The slab of sphere i among `slabs` across x: that of its list centre's cell column (the
 * cells are the centres', and a centre moves only at its list's expiry). */
static inline int nbep__evloop_slab_in(const nbep_evloop *e, uint32_t i, int slabs)
{
    const size_t columns = e->cells.dim[0];
    return nbep_slabcal_slab_of(e->cells.m[i].cell % columns, columns, slabs);
}

/* The slab of cell column c + dc across x (|dc| at most the columns) among `slabs` over
 * `columns`, around x where it wraps; -1 past a side that does not. nbep__evloop_column_slab:
 * the engine's, with slabs. */
static inline int nbep__column_slab(size_t columns, bool wraps, int slabs, size_t c, int dc)
{
    const long k = (long)c + dc;
    long m = k;
    if (k < 0 || k >= (long)columns) {
        if (!wraps)
            return -1;
        m = (k + (long)columns) % (long)columns;
    }
    return nbep_slabcal_slab_of((size_t)m, columns, slabs);
}
static inline int nbep__evloop_column_slab(const nbep_evloop *e, size_t c, int dc)
{
    return nbep__column_slab(e->cells.dim[0], e->pb.axis[0], nbep_slabcal_slabs(e->slabcal), c,
                             dc);
}

/* The calendar's tie key: the pair (lower sphere high, higher low), the same in both spheres'
 * slots; a plane contact (UINT32_MAX - 1 - plane low) or a list expiry (UINT32_MAX low) ranks
 * after every pair of its sphere. (Until 2026-11-30 plane p's was UINT32_MAX - p, so plane 0's
 * was an expiry's and the team loop held such contacts to the expiries' rule; spheres number
 * fewer than NBEP_CALENDAR_MAX, so either way the order is the same.) */
static inline uint64_t nbep__evloop_slot_key(uint32_t i, const nbep_event *ev)
{
    uint32_t a = i, b = UINT32_MAX;
    if (ev->kind == NBEP_EVENT_SPHERE) {
        a = i < ev->partner ? i : ev->partner;
        b = i < ev->partner ? ev->partner : i;
    } else if (ev->kind == NBEP_EVENT_PLANE) {
        b = UINT32_MAX - 1 - ev->partner;
    }
    return (uint64_t)a << 32 | b;
}

/* What the key says back (nbep__evloop_slot_key(i, ev)): the other sphere of a pair (an index
 * at or past n for a plane or an expiry: UINT32_MAX - 1 - plane or UINT32_MAX), and whether it
 * is an expiry. */
static inline uint32_t nbep__evloop_key_other(uint64_t key, uint32_t i)
{
    const uint32_t a = (uint32_t)(key >> 32), b = (uint32_t)key;
    return a == i ? b : a;
}
static inline bool nbep__evloop_key_expiry(uint64_t key, uint32_t i)
{
    return key == ((uint64_t)i << 32 | UINT32_MAX);
}

/* Whether the commit of the event handled on w set sphere j's calendar entry. */
static inline bool nbep__evloop_commit_sets(const evl_ws *w, uint32_t j)
{
    bool set = j == w->item;
    if (w->n_next != NEXT_ALL)
        for (size_t k = 0; k < w->n_next; k++)
            set |= w->next_item[k] == j;
    else
        for (size_t k = 0; k < w->n_changed; k++)
            set |= w->changed[k] == j;
    return set;
}

/* A look at the stall check before each event (tests/test_team_faults.c compiles its own copy
 * of the engine whose hook makes the check fail from a time on, so that the loops' way out of a
 * stall is tested; a build of nbep has nothing here). */
#ifndef NBEP_EVLOOP_STALL_HOOK
#define NBEP_EVLOOP_STALL_HOOK(st, t) ((void)0)
#endif

/* Counts one event at time t towards the stall check: false when st->events events in a row
 * have not advanced time by more than st->dt, or at a look at the stop signal that finds one
 * (st->stopped set; a look that finds none calls st->on_look). The look is relaxed: the
 * signal's handler stores it with no other data to pass. */
static inline bool nbep__evloop_advances(nbep_evloop_stall *st, double t)
{
    NBEP_EVLOOP_STALL_HOOK(st, t);
    if (++st->since >= st->events) {
        if (!(t - st->t_mark > st->dt))
            return false;
        st->t_mark = t;
        st->since = 0;
    }
    if (++st->looks >= NBEP_EVLOOP_STOP_EVERY) {
        st->looks = 0;
        if (st->stop && atomic_load_explicit(st->stop, memory_order_relaxed) != 0) {
            st->stopped = true;
            return false;
        }
        if (st->on_look)
            st->on_look(st->look_ctx, t);
    }
    return true;
}

/* Requests what the event of sphere i (slot ev) and the next ones will read (no effect on
 * results): the first line of its list (from the list's record, which the event before
 * requested with the runners-up), its place, its partner's list record and place, and the
 * runners-up' slots, places and list records. */
static inline NBEP_ALWAYS_INLINE void nbep__evloop_prefetch_event(const nbep_evloop *e,
                                                                uint32_t i, const nbep_event *ev)
{
    NBEP_PREFETCH(&e->nl.pool[e->nl.sp[i].off]);
    NBEP_PREFETCH(&e->cells.m[i]);
    if (ev->kind == NBEP_EVENT_SPHERE) {
        NBEP_PREFETCH(&e->nl.sp[ev->partner]);
        NBEP_PREFETCH(&e->cells.m[ev->partner]);
        if (!e->slabcal) /* moved at the commit if it is fresh */
            nbep_calendar_prefetch(e->cal, ev->partner);
        else if (e->own_slab < 0 || /* (another slab's entry is its own to read) */
                 nbep_slabcal_slab(e->slabcal, ev->partner) == e->own_slab)
            nbep_slabcal_prefetch(e->slabcal, ev->partner);
    }
    uint32_t next[2];
    int n_next;
    if (e->slabcal && e->own_slab >= 0) /* (a slab's own loop: its calendar's alone) */
        nbep_slabcal_runners_up_of(e->slabcal, e->own_slab, next, &n_next);
    else if (e->slabcal)
        nbep_slabcal_runners_up(e->slabcal, next, &n_next);
    else
        nbep_calendar_runners_up(e->cal, next, NULL, &n_next);
    for (int k = 0; k < n_next; k++) {
        NBEP_PREFETCH(nbep_feq_slot(e->q, next[k]));
        NBEP_PREFETCH(&e->cells.m[next[k]]);
        NBEP_PREFETCH(&e->nl.sp[next[k]]);
    }
}

static inline void nbep__evloop_count_handled(nbep_evloop_tally *tally, const evl_ws *w)
{
    tally->exits += w->rebuilt;
    tally->reactions += w->reacted;
}

#endif
