/* One simulation run: the evolving state, the algorithm chosen by the scene, counters, frames
 * and the summary. main.c and the tests drive runs through this interface only. */
#ifndef NBEP_SIM_H
#define NBEP_SIM_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/output.h"
#include "nbep/scene.h"
#include "nbep/state.h"
#include "nbep/status.h"

typedef struct nbep_sim nbep_sim;

/* Called by one thread (never concurrently) for every frame: step 0, every `every` steps and
 * the last step simulated. The state is borrowed for the call only. A non-OK status stops the
 * run with that status. */
typedef nbep_status (*nbep_frame_fn)(void *ctx, int64_t step, const nbep_state *s,
                                     nbep_diag *d);

typedef struct nbep_sim_options {
    int threads;                    /* nbep_sim_resolve_threads' count (resolved again here) */
    nbep_output *out;               /* borrowed, may be NULL: frames and stats go there */
    nbep_frame_fn on_frame;         /* may be NULL: called after `out` got the frame */
    void *on_frame_ctx;
    const atomic_int *stop_signal;  /* borrowed, may be NULL: nonzero = SIGINT/SIGTERM number */
    bool progress;                  /* progress lines on stderr */
    const nbep_resume *resume;      /* borrowed by nbep_sim_create, may be NULL: continue from
                                     * this frame, whose positions, velocities and images
                                     * nbep_resume_apply has put into the scene's state */
    nbep_state *take_state;         /* may be NULL: the scene's own state, whose arrays the
                                     * run takes over instead of copying (nbep_state_take);
                                     * nothing reads them through the scene after */
    double t_begin;                 /* nbep_now() when the run's set-up began (before its deck
                                     * was read: SPEC's setup_seconds counts deck and
                                     * placement); 0: when nbep_sim_create is called */
} nbep_sim_options;

/* A run of sc (borrowed; must outlive the sim) from its initial state, or from opt->resume
 * (its frame's step and, for predictive, event slots; the state is the frame's). Allocates
 * everything the algorithm needs; nothing is allocated inside a step. NBEP_ENOMEM, NBEP_EDECK
 * for an unknown algorithm. The run takes the threads OpenMP gives a region of the resolved
 * count (fewer only inside a caller's parallel region). */
NBEP_MUST_CHECK nbep_status nbep_sim_create(const nbep_scene *sc, const nbep_sim_options *opt,
                                            nbep_sim **out, nbep_diag *d);
void nbep_sim_destroy(nbep_sim **sim);

/* Simulates sc->steps steps (frames and stats as the scene asks). Returns NBEP_OK, the I/O
 * status of a failing write, NBEP_ENUMERIC when a non-finite value appears, NBEP_ENOMEM when a
 * step's memory could not be had (the stats rows of the steps done written all the same), or
 * NBEP_ESIGINT/NBEP_ESIGTERM when *stop_signal was raised: the current step is finished and its
 * frame written first, unless the signal came while the step's events ran in a loop that looks
 * at it (the predictive algorithm's: every 65536 events in cells mode, 1024 rounds in the
 * others), which abandons the step (nbep_sim_abandoned). */
NBEP_MUST_CHECK nbep_status nbep_sim_run(nbep_sim *sim, nbep_diag *d);
/* After nbep_sim_run: whether a signal abandoned a step (the run ends after the step before,
 * nbep_sim_summary's `steps`, with no frame for it unless one was due), and the step of the
 * last frame written, or resumed from, in *frame_step. */
bool nbep_sim_abandoned(const nbep_sim *sim, uint64_t *frame_step);
/* After nbep_sim_run: whether a write to the output failed (a frame's or the stats rows'; the
 * run's status then says how), after which the file got nothing more. An out-of-memory status
 * without it is the algorithm's: the file is sound, its rows up to the last step done. */
bool nbep_sim_output_failed(const nbep_sim *sim);

/* The run's summary so far (valid after create; complete after run), but for `status`, left
 * unknown: how the run ended is the caller's to say (nbep_run: the simulation's status, then
 * the closing file's). */
void nbep_sim_summary(const nbep_sim *sim, nbep_summary *s);
/* A counter's total so far (enum nbep_counter from stats.h). */
uint64_t nbep_sim_counter(const nbep_sim *sim, int counter);
/* The current state (borrowed). */
const nbep_state *nbep_sim_state(const nbep_sim *sim);

/* Bytes a run of sc with `threads` threads needs: state, the run's and the algorithm's
 * workspaces, each counted by a function beside its allocation under the same conditions (a
 * granular scene's contact arrays, none for an elastic fluid's), and one frame's output
 * buffers. An estimate for `nbep check`, without the libraries: cells mode's neighbour lists
 * are counted at what a dense scene's grow to, so a dilute one's estimate is up to a quarter
 * above its peak (README, nbep check). */
size_t nbep_sim_memory_estimate(const nbep_scene *sc, int threads);
/* How a run of sc with `threads` threads shares its work, in a few words for `nbep check`
 * (buf, len bytes, always terminated): which parts run on every thread and which on one (a
 * granular scene's event loop in cells mode), so that a user can choose threads per run
 * against runs per node. */
void nbep_sim_threads_use(const nbep_scene *sc, int threads, char *buf, size_t len);
/* Whether a run of sc keeps every sphere's event slot beside each frame (/checkpoint). */
bool nbep_sim_keeps_events(const nbep_scene *sc);
/* Whether it also keeps its spheres' lasting state for its last two frames
 * (/checkpoint/contacts: a dissipative predictive run's TC clocks, contacts and settling). */
bool nbep_sim_keeps_contacts(const nbep_scene *sc);
/* The same for the run sim, as decided when it was made. */
bool nbep_sim_lasting(const nbep_sim *sim);
/* Whether a run of sc holds a supported sphere still once it has stayed slow for *steps whole
 * steps (the predictive algorithm's settling, e < 1 under an acceleration: README, Held
 * spheres), and then the least and the largest of the spheres' speeds at or below which it
 * does (*lo, *hi; each depends on the sphere's radius and acceleration, and on run.dt).
 * nbep check says it. */
bool nbep_sim_settle_speeds(const nbep_scene *sc, double *lo, double *hi, unsigned *steps);
/* What a stop signal asks of a run (stop may be NULL): NBEP_OK (none yet), NBEP_ESIGINT or
 * NBEP_ESIGTERM. */
nbep_status nbep_sim_stop_status(const atomic_int *stop);

/* The thread count a scene's `threads` setting resolves to, which is what a run uses: n > 0
 * as is; 0 -> OMP_NUM_THREADS if set, else the cores available; at most OMP_THREAD_LIMIT;
 * always 1 in a serial build (make OMP=0). The one place a count is resolved: the run's file,
 * its summary and `nbep check` all show this number. */
int nbep_sim_resolve_threads(int requested);

#endif
