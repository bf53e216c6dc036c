/* Internals shared by sim.c and the algorithms (algo_*.c): the run object, thread ranges, and
 * the end-of-step hook that thread 0 calls between barriers. */
#ifndef NBEP_SIM_IMPL_H
#define NBEP_SIM_IMPL_H

#include <stdalign.h>
#include <stdatomic.h>
#include <stdint.h>

#include "nbep/barrier.h"
#include "nbep/grid.h"
#include "nbep/sim.h"
#include "nbep/stats.h"
#include "nbep/xsum.h"

/* Spheres are split among threads in whole blocks of this many, so that per-block partial
 * sums (energy) are the same for any thread count: sums never group by thread. Small, so
 * that a scene of a dozen spheres is shared among threads too: at 256 every scene of up to
 * 256 spheres ran on one thread whatever the run's count (the others idle at the barriers),
 * and the tests that compare thread counts on small scenes (a 40-sphere pile, 12-sphere
 * jams) compared one thread with itself. Only the spheres at a share's ends can share a cache
 * line with another thread's; the energy's blocks are n / 8 partial sums a step (32000 at
 * N = 256000: tens of microseconds against a step's tens of milliseconds). */
#define NBEP_BLOCK 8

typedef struct nbep_range {
    size_t lo, hi;
} nbep_range;

/* Thread tid's share of n spheres, in whole blocks: contiguous, in thread order, the same
 * every step. */
nbep_range nbep__range_split(size_t n, int tid, int nt);

/* The calling thread's number inside the run's parallel region (0 in a serial build). */
int nbep__thread_id(void);

/* Per-thread maximum of a step, padded to its own cache line. */
typedef struct nbep_thread_max {
    alignas(NBEP_CACHELINE) double overlap;
    double overlap_rel;
    /* sums of the step (SPEC contract 2): r12 . dp2 over sphere collisions, and per plane the
     * normal momentum it received (wall: this thread's n_planes slots, owned by the sim); exact
     * (xsum.h), so that the step's sums do not depend on which thread added what */
    nbep_xsum virial;
    nbep_xsum *wall;
    /* NULL but while the cells mode's scheduled loop runs (pred_cells.c): where the terms
     * added to these sums are recorded, for a rollback to take them out again (pred_impl.h,
     * nbep__pred_sum_add) */
    struct nbep_sum_journal *jr;
} nbep_thread_max;

typedef struct nbep_algo nbep_algo;

struct nbep_sim {
    const nbep_scene *scene;         /* borrowed */
    nbep_sim_options opt;
    nbep_state st;                   /* owned: the evolving state */
    int nt;                          /* threads */
    uint64_t step_first, step_end;   /* steps to simulate: step_first..step_end (1-based) */
    bool resumed;                    /* continues a file's frame (opt.resume, read in create) */
    double dt;
    const nbep_algo *algo;           /* borrowed: static table entry */
    void *algo_ctx;                  /* owned by the algorithm */
    /* counters double-buffered by step parity: the hook of step k reads and clears
     * [k & 1] while other threads already count step k+1 in the other half */
    nbep_counters *counters[2];      /* owned, nt each */
    nbep_thread_max *tmax[2];        /* owned, nt each */
    double *block_ke, *block_pe;     /* owned, one per NBEP_BLOCK spheres */
    size_t n_blocks;
    double *ev_time;                 /* owned, n each: event slots exported at frames, when */
    uint32_t *ev_partner;            /* the algorithm has them and there is an output */
    uint8_t *ev_kind;
    int32_t *ev_rest;
    bool lasting;                    /* frames also keep the algorithm's lasting state
                                      * (keeps_contacts, decided at create) */
    nbep_grid overlap_grid;          /* owned when the algorithm's overlap is not exact: the
                                      * frame-step overlap check's workspace */
    double overlap_rmax;             /* its largest radius (nbep__sim_frame_overlap) */
    uint64_t overlap_step;           /* the last step whose check the threads shared */
    nbep_step_stats *rows;           /* owned: stats rows not yet written */
    double *wall_rows;               /* owned: their /stats/wall_impulse rows, n_planes each */
    nbep_xsum *wall_buf[2];          /* owned: per parity, nt x n_planes (nbep_thread_max.wall) */
    double virial_total;             /* summary pressure: the virial summed over the steps from
                                      * sums_first on */
    double ke_total;                 /* and the kinetic energy at each step's end, summed */
    uint64_t sums_first;             /* 1, or a resumed run's step_first where its file had no
                                      * totals to go on from (/frames/totals) */
    size_t n_rows, cap_rows;
    /* totals and summary */
    uint64_t totals[NBEP_COUNTER_COUNT];
    uint64_t quiet_steps;
    uint64_t steps_done;
    /* the step of the last frame written (or resumed from); whether a signal abandoned a
     * step in its events (thread 0: nbep_sim_abandoned) */
    uint64_t frame_last;
    bool abandoned;
    /* a write to the output failed (a frame's or the stats rows'): the file gets nothing more
     * (nbep_sim_output_failed) */
    bool out_failed;
    double energy_initial, energy_final;
    double max_overlap, max_overlap_rel;
    double setup_seconds, wall_seconds;
    double t_start, t_last_progress;
    /* the progress line's recent rate: steps done (this session) and the time at its last
     * mark, and the rate between the two marks before (0: none yet); set with t_start
     * (clock_start in sim.c) */
    double t_mark, rate_recent;
    double done_mark;  /* steps done at t_mark: a step's part counts (nbep__sim_progress_within) */
    /* the progress line on a terminal: whether stderr is one (taken once, at the run's start),
     * the widest line shown (a shorter one is padded over it) and whether the last line shown
     * is still open (not ended by a newline) */
    bool tty, line_open;
    int tty_width;
    /* stop request: written by thread 0 in the hook, read by all after the next barrier */
    atomic_int stop;
    nbep_status status;              /* thread 0 only */
    nbep_diag *diag;                 /* borrowed, thread 0 only */
};

/* The algorithm table entry. create: allocate per-run workspaces (before any parallel region);
 * run: the one parallel region over all steps, calling nbep__sim_end_step on thread 0 after
 * each step's state is final (all spheres at the step's end time); destroy: free. */
struct nbep_algo {
    const char *name;
    /* true when the algorithm's detection examines every overlapping pair each step and fills
     * tmax exactly; otherwise the hook measures overlaps with a cell grid at frame steps */
    bool exact_overlap;
    nbep_status (*create)(nbep_sim *sim, void **ctx, nbep_diag *d);
    void (*run)(nbep_sim *sim, void *ctx);
    void (*destroy)(void *ctx);
    /* the bytes create allocates for a run of sc on nt threads, by the same conditions (kept
     * beside create, so that nbep check's memory estimate counts what a run makes) */
    size_t (*bytes)(const nbep_scene *sc, int nt);
    /* how a run of sc on nt >= 2 threads shares its work, by the same plan as create's, in a
     * few words for nbep check (buf, len bytes, always terminated) */
    void (*threads_use)(const nbep_scene *sc, int nt, char *buf, size_t len);
    /* optional (NULL): the state beyond positions and velocities that a resumed run needs to
     * continue bit for bit: export at a frame (thread 0, slots stable), import at create */
    void (*export_events)(const void *ctx, const nbep_state *s, double *time,
                          uint32_t *partner, uint8_t *kind, int32_t *rest);
    void (*import_events)(void *ctx, const nbep_resume *r);
    /* optional (NULL), with export_events: whether a run of sc with the spheres st keeps
     * lasting state beside its slots (nbep_contact_rec; st: the run takes the scene's state
     * over), and spheres [lo, hi)'s at a frame (as export_events) */
    bool (*keeps_contacts)(const nbep_scene *sc, const nbep_state *st);
    void (*export_contacts)(const void *ctx, size_t lo, size_t hi, nbep_contact_rec *out);
    /* optional (NULL): whether a run of sc holds slow spheres still (settling), and then the
     * least and the largest speed at or below which it does, and for how many whole steps */
    bool (*settle_speeds)(const nbep_scene *sc, double *lo, double *hi, unsigned *steps);
};

extern const nbep_algo nbep__algo_naive;
extern const nbep_algo nbep__algo_seminaive;
extern const nbep_algo nbep__algo_predictive;

/* Kinetic and potential energy of the spheres of thread's range, per block, into the block
 * arrays (call for the own range only; ranges are whole blocks). */
void nbep__sim_block_energy(nbep_sim *sim, nbep_range own);

/* Whether the end of step `step` writes a frame on the run's schedule (every output.every
 * steps, and the last); a stop signal adds a frame at the step it comes. */
bool nbep__sim_frame_due(const nbep_sim *sim, uint64_t step);
/* Thread 0, once the first predictions are made: they belong to the set-up time (SPEC), and
 * the stepping loop's clock and the progress line's start now. */
void nbep__sim_setup_done(nbep_sim *sim);

/* Every thread, all spheres at the end of step `step`, before nbep__sim_end_step: at a frame
 * at a multiple of output.every of an algorithm whose overlap is not exact, the frame's overlap
 * check shared (thread 0 sorts the centres between two waits on bar, then each thread checks
 * its own spheres into its step's maxima), which end_step then does not repeat. */
void nbep__sim_frame_overlap(nbep_sim *sim, uint64_t step, int tid, nbep_range own,
                             nbep_barrier *bar);

/* Thread 0, between barriers, all spheres at the end of step `step` (1-based): merges the
 * step's counters, sums block energies, records the stats row, writes a frame when due,
 * prints progress, and sets sim->stop when the run must end (signal, error, last step).
 * Returns the value of stop. */
int nbep__sim_end_step(nbep_sim *sim, uint64_t step);
/* Thread 0, at an event at absolute time t within step `step`: the progress line, when one is
 * due (a step of minutes otherwise showed none until its end; SPEC: a line about every 10 s in
 * a log, a live one on a terminal). */
void nbep__sim_progress_within(nbep_sim *sim, uint64_t step, double t);
/* The same, with the part of step `step`'s work done (0 to 1), for an algorithm whose step is
 * a pass over its pairs rather than a sequence of events in time (naive, seminaive). */
void nbep__sim_progress_part(nbep_sim *sim, uint64_t step, double part);
/* Thread 0, during the first predictions (all-pairs mode's n^2/2 pair tests: 25 s for 32000
 * spheres), the part of them made (0 to 1): the progress line, when one is due. */
void nbep__sim_progress_setup(nbep_sim *sim, double part);
/* Thread 0, when a look within step `step`'s events found the stop signal: the run ends with
 * the signal's status after the step before, the step abandoned (nbep_sim_abandoned). */
void nbep__sim_abandon(nbep_sim *sim);

#endif
