/* `nbep sweep DECK`: a parameter study. The deck's `sweep` group names replicas and axes
 * (scene.h); every run is the deck plus the command line's overrides plus its own: one value
 * of every axis and its own run.seed. Runs are independent, each writing its own nbep-1 file
 * into the sweep directory; a summary table (summary.csv, summary.h5) has one row per run.
 *
 * Order of runs (stable; run indices name the files run-0000.h5, run-0001.h5, ...):
 *   run = replica * n_combinations + combination,
 *   combination = row-major index of the axes' value indices, the first axis varying slowest
 *   and the last fastest (the nested loops of the deck's `vary` order).
 * Replicas are outermost so that raising sweep.replicas later keeps every existing run's
 * index, file and parameters: a restarted sweep reuses them and runs only the new replicas.
 * Replica r runs with run.seed = (the deck's run.seed, after the command line) + r.
 *
 * Under an MPI launcher (mpirun, srun) the runs are dealt statically to the R ranks in rounds
 * of R, alternating direction (nbep_sweep_run_owner): run i goes to rank i mod R when i / R is
 * even and to R - 1 - (i mod R) when it is odd, so that an axis of even length that makes
 * runs slow or fast (an algorithm, a sphere count) is not tied to one rank. Each rank runs its
 * runs one after another with run.threads threads, and rank 0 gathers every run's result and
 * writes the summary. Without MPI, or outside a
 * launcher, this process runs them all. Only sweep.c includes <mpi.h>. */
#ifndef NBEP_SWEEP_H
#define NBEP_SWEEP_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "nbep/cli.h"
#include "nbep/compiler.h"
#include "nbep/output.h"
#include "nbep/scene.h"
#include "nbep/status.h"

/* Longest error text kept per run in the summary (longer texts are cut). */
#define NBEP_SWEEP_ERROR_MAX 512

/* What became of a run. */
/* not_run: not started (the sweep was stopped before it); ok: every step simulated, now or by
 * an earlier sweep; failed: a deck error for this combination, or a run-time error;
 * interrupted: stopped by SIGINT/SIGTERM (run the sweep again to finish it). */
#define NBEP_SWEEP_OUTCOME_LIST(X)                                                           \
    X(NOT_RUN, "not_run") X(OK, "ok") X(FAILED, "failed") X(INTERRUPTED, "interrupted")

typedef enum nbep_sweep_outcome {
#define NBEP_X_ENUM(name, text) NBEP_SWEEP_##name,
    NBEP_SWEEP_OUTCOME_LIST(NBEP_X_ENUM)
#undef NBEP_X_ENUM
} nbep_sweep_outcome;

/* The outcome's name as it appears in the summary's status column; never NULL. */
const char *nbep_sweep_outcome_text(nbep_sweep_outcome o);

/* The run list: everything a rank needs to build any run's overrides, computed identically on
 * every rank from the deck and the command line. */
typedef struct nbep_sweep_plan {
    char *deck_path;              /* owned copy */
    char *deck_text;              /* owned: the deck file's text (for summary.h5) */
    char **base;                  /* owned: the command line's overrides, in order */
    char **base_origins;          /* owned: what was typed for each, NULL for --set (messages,
                                   * nbep_scene_load_from), then NULL for each axis and the
                                   * seed: one entry for every override of a run */
    size_t n_base;
    size_t n_axes;
    nbep_sweep_axis *axes;        /* owned: taken over from the deck's scene */
    uint64_t replicas;            /* >= 1 */
    uint64_t seed;                /* run.seed of replica 0 */
    uint64_t steps;               /* run.steps, unless an axis varies it */
    size_t n_combos, n_runs;      /* n_runs = replicas * n_combos; n_combos = 1 without axes */
    char *dir;                    /* owned: the sweep directory, without a trailing '/' */
    bool resumable;               /* the deck's frames hold positions and velocities
                                   * (output.fields): a run cut short can go on from them */
} nbep_sweep_plan;

/* Loads the deck with the command line's overrides (n_overrides may be 0; each string is
 * copied) once to validate it and read its sweep group, and fills *out. The sweep directory
 * is output.file without a trailing ".h5" plus ".sweep" (kept as is when it already ends in
 * ".sweep"): output.file = "box.h5" or `-o box.sweep` give "box.sweep". NBEP_EDECK (bad deck,
 * an axis that varies run.seed or output.file, a key varied twice), NBEP_EIO, NBEP_ENOMEM;
 * *out is written only on success. Creates no file. */
NBEP_MUST_CHECK nbep_status nbep_sweep_plan_create(const char *deck_path,
                                                   const char *const *overrides,
                                                   size_t n_overrides, nbep_sweep_plan *out,
                                                   nbep_diag *d);
void nbep_sweep_plan_fini(nbep_sweep_plan *p);

/* Run `run`'s replica (0 .. replicas-1), seed, and value index along `axis`. run < n_runs. */
uint64_t nbep_sweep_run_replica(const nbep_sweep_plan *p, size_t run);
uint64_t nbep_sweep_run_seed(const nbep_sweep_plan *p, size_t run);
size_t nbep_sweep_run_value(const nbep_sweep_plan *p, size_t run, size_t axis);
/* run.steps that run `run` asks for (an axis on run.steps, else the plan's). */
uint64_t nbep_sweep_run_steps(const nbep_sweep_plan *p, size_t run);

/* The overrides of run `run`, in the order they are applied: the command line's, then
 * "KEY=VALUE" for every axis in deck order, then "run.seed=SEED". *out is a malloc'd array of
 * *n malloc'd strings; release with nbep_sweep_overrides_free. NBEP_ENOMEM. */
NBEP_MUST_CHECK nbep_status nbep_sweep_run_overrides(const nbep_sweep_plan *p, size_t run,
                                                     char ***out, size_t *n, nbep_diag *d);
void nbep_sweep_overrides_free(char **ov, size_t n);

/* The run's output file, "DIR/run-0007.h5": at least 4 digits, more when the sweep has more
 * than 10^4 runs, so that names sort in run order. malloc'd; NULL when out of memory. */
char *nbep_sweep_run_path(const nbep_sweep_plan *p, size_t run);

/* Whether rank (of n_ranks) runs run: the alternating round-robin above. */
bool nbep_sweep_run_owner(size_t run, int rank, int n_ranks);

/* One run's result, as gathered by rank 0: fixed size and plain data (sent as bytes between
 * ranks of one machine type). */
typedef struct nbep_sweep_result {
    uint64_t run;
    int32_t rank;                 /* that ran or reused it; -1 when not run */
    int32_t outcome;              /* nbep_sweep_outcome */
    int32_t exit_code;            /* what `nbep run` would have exited with; -1 when not run */
    int32_t reused;               /* 1: complete from an earlier sweep, not simulated again */
    int32_t has_summary;          /* 1: `summary` holds the run's summary */
    int32_t pad_;
    double seconds;               /* the whole run as the sweep saw it: deck, file, steps */
    nbep_summary summary;
    char error[NBEP_SWEEP_ERROR_MAX];   /* the run's error lines joined by "; ", or "" */
} nbep_sweep_result;

/* Whether the file at path holds a complete run with these overrides: its /summary json
 * exists and says status "completed" (or no status, as an nbep before 2026-11-30 wrote it)
 * and `steps` steps, and its root `overrides` attribute (one per line, as the scene stores
 * them) lists the same overrides in the same order, ignoring those of run.threads and
 * output.file on both sides (a run's frames do not depend on them). On true, *sum (may be
 * NULL) gets the stored summary. A missing, unreadable, interrupted, failed or different file
 * is simply not complete. Edits to the deck file itself are not detected: start such a study
 * in a fresh directory. */
bool nbep_sweep_run_complete(const char *path, char *const *overrides, size_t n_overrides,
                             uint64_t steps, nbep_summary *sum);

/* What a sweep finds at a run's path (nbep_sweep_run_found): nothing it can use (no file, an
 * unreadable one, other overrides, a failed run), the run complete (reused), the run cut
 * short by a signal or a kill (its summary says interrupted or terminated, or it has none):
 * continued from its last frame, as `nbep run --resume` does, or the run complete at more
 * steps than asked: kept, and the run fails saying so (a study asked again with a smaller -n,
 * or a deck's steps without the -n that ran it, would otherwise throw its longer runs away). */
typedef enum nbep_sweep_found {
    NBEP_SWEEP_FOUND_NONE,
    NBEP_SWEEP_FOUND_COMPLETE,
    NBEP_SWEEP_FOUND_PARTIAL,
    NBEP_SWEEP_FOUND_OTHER, /* a file of no use: the run replaces it (NONE: no file at all) */
    NBEP_SWEEP_FOUND_LONGER, /* the same run past the steps asked (complete at more, or cut
                              * short by a signal after them): kept, never replaced */
} nbep_sweep_found;
/* nbep_sweep_run_complete's look, telling a run cut short from one of no use; threads_axis:
 * run.threads is one of the study's axes, so a run with another thread count is of no use
 * (nbep_sweep_run_complete passes false). For NBEP_SWEEP_FOUND_OTHER, why (when not NULL, of
 * why_len bytes) says what the file held, in a few words. *sum (may be NULL) gets the stored
 * summary for NBEP_SWEEP_FOUND_COMPLETE and NBEP_SWEEP_FOUND_LONGER (its steps). */
nbep_sweep_found nbep_sweep_run_found(const char *path, char *const *overrides,
                                      size_t n_overrides, uint64_t steps, bool threads_axis,
                                      nbep_summary *sum, char *why, size_t why_len);

/* How a process runs its share of a sweep. */
typedef struct nbep_sweep_exec {
    int rank, n_ranks;               /* this process runs the runs nbep_sweep_run_owner gives */
    const atomic_int *stop_signal;   /* borrowed, may be NULL: nonzero stops the sweep */
    bool quiet;                      /* no per-run progress lines (errors are still printed) */
    /* Several processes (NULL: one): peer_stop, asked before each run, says whether another
     * process has stopped on its signal (its status) or NBEP_OK; announce_stop tells the
     * others that this one has. A signal that reaches one rank alone (a kill, the OOM killer's
     * SIGTERM) then stops the new runs of all, as a signal to all of them does. u: theirs. */
    nbep_status (*peer_stop)(void *u);
    void (*announce_stop)(void *u, nbep_status st);
    void *u;
} nbep_sweep_exec;

/* Runs this process's share of the plan, one run after another, writing each run's file into
 * the plan's directory (which must exist). A run already complete (nbep_sweep_run_complete)
 * is reused, not run again; any other file at its path is replaced. results has n_runs
 * entries: this process's runs are filled in, the others are left as NOT_RUN. A failing run
 * prints one line on stderr ("nbep: sweep run 3 (KEY=VALUE ...): error") and the others go
 * on. On a stop signal the current run stops after its step, no further run starts, and the
 * status is NBEP_ESIGINT/NBEP_ESIGTERM (a peer's stop: its status, the current run finished);
 * otherwise NBEP_OK, whatever the runs' outcomes. */
NBEP_MUST_CHECK nbep_status nbep_sweep_execute(const nbep_sweep_plan *p,
                                               const nbep_sweep_exec *ex,
                                               nbep_sweep_result *results);

/* Writes DIR/summary.csv and DIR/summary.h5 from the results of every run (n_runs entries),
 * each replaced atomically (written aside, then renamed). Columns, in order: run, replica,
 * seed, rank, one per axis (its key; the value as deck text, strings without quotes), status,
 * exit_code, reused, seconds, file, the JSON summary's fields in order (but its `status`: the
 * column `status` says how each run ended in the table's words), error. n_ranks
 * and wall_seconds go into summary.h5's root attributes. NBEP_EIO, NBEP_ENOMEM; *csv_written
 * (may be NULL): whether summary.csv was written, which it may be when summary.h5 is not (a
 * disk that filled up between them). */
NBEP_MUST_CHECK nbep_status nbep_sweep_write_summary(const nbep_sweep_plan *p,
                                                     const nbep_sweep_result *results,
                                                     int n_ranks, double wall_seconds,
                                                     bool *csv_written, nbep_diag *d);

/* The bytes of DIR/summary.csv and DIR/summary.h5 that nbep_sweep_write_summary writes for
 * the plan's runs, all ok, about (within some 15 %: a run's figures are not known before it
 * runs): the header, the axes' values and files' names as they will be, the rest measured. */
double nbep_sweep_tables_bytes(const nbep_sweep_plan *p);

/* What `nbep check` found of a study's runs (nbep_sweep_check). */
typedef struct nbep_sweep_check_report {
    size_t n_runs, n_combos;
    uint64_t replicas;
    char dir[4096];               /* the sweep directory, as nbep sweep makes it */
    size_t checked;               /* runs whose scene was loaded (first runs first) */
    size_t failed;                /* of those, runs whose scene a deck error refused, or whose
                                   * file holds the run complete at more steps (kept) */
    double output_bytes;          /* the files of the checked runs that load, in all: each run's
                                   * and its XDMF sidecar */
    double tables_bytes;          /* the sweep's own summary.csv and summary.h5, of all runs */
    double memory_max;            /* the most memory one of them needs (nbep_sim_memory_estimate) */
    bool out_of_time;             /* stopped after budget_s: the runs past `checked` unchecked */
    double budget_s;              /* the time it was given */
    /* the files already at the checked runs' paths, as nbep sweep will find them
     * (nbep_sweep_run_found): reused, resumed, replaced, and kept (each such run is also one
     * of `failed`, its line in the diag: the sweep would fail it) */
    size_t files_complete, files_partial, files_other, files_kept;
    char tc_warning[640];         /* the first checked run's nbep_scene_tc_warning, naming the
                                   * run ("" for none): a run's e or dt may differ from the
                                   * deck's */
} nbep_sweep_check_report;

/* The most runs' deck errors nbep_sweep_check lists (one line each); the rest are counted. */
#define NBEP_SWEEP_CHECK_LISTED 10

/* `nbep check` of a deck with a sweep group: sc is the deck's scene as nbep_scene_load_from
 * loaded it from deck_path with the overrides (origins as there, may be NULL); its axes and
 * deck text move out of it (the caller releases it). Loads every run's scene as `nbep sweep`
 * would (its overrides, its spheres placed and checked for overlaps), in run order, until
 * budget_s seconds have passed (at least one run): the axes' combinations and each replica's
 * placement, which a check of each value alone does not see, fail here instead of in the job.
 * A run refused is named in d, "nbep: sweep run K (KEY=VALUE ... seed=S) cannot run: " and its
 * first error, the first NBEP_SWEEP_CHECK_LISTED of them, then how many more; the result is
 * then NBEP_EDECK. NBEP_ENOMEM. A nonzero *stop (main.c's signal flag, borrowed, may be NULL)
 * ends the loading before the next run, as the time does, or within a run's placement
 * (nbep_scene_load_run), that run not counted: the caller looks at it. */
NBEP_MUST_CHECK nbep_status nbep_sweep_check(const char *deck_path, const char *const *overrides,
                                             const char *const *origins, size_t n_overrides,
                                             nbep_scene *sc, double budget_s,
                                             const atomic_int *stop,
                                             nbep_sweep_check_report *rep, nbep_diag *d);

/* For `nbep check` of a study: whether `nbep sweep` could make its folder dir (as
 * nbep_sweep_check_report's dir) and write in it, looked at without making anything: the
 * sweep's own line where it could not ("nbep: cannot make the sweep directory D: REASON", a
 * file in the way: NBEP_EUSAGE; a folder that cannot be written in: nbep_status_of_open's). */
NBEP_MUST_CHECK nbep_status nbep_sweep_check_dir(const char *dir, nbep_diag *d);

/* nbep check's lines about a study (after the deck's own): its runs and folder, what was
 * checked of them and the most memory one needs, its output in all: the runs' files and
 * sidecars, and the summary tables (README, Parameter studies). */
void nbep_sweep_check_print(FILE *f, const nbep_sweep_check_report *r);

/* `nbep sweep DECK [options]`: plans the sweep from cli (path, overrides, summary, quiet),
 * creates the sweep directory, runs every run (split over the ranks when started by an MPI
 * launcher: mpirun, or srun with PMI/PMIx; NBEP_MPI=0 in the environment forces a serial
 * sweep, NBEP_MPI=1 forces MPI_Init), gathers and writes the summary on rank 0, and with
 * cli->summary writes a JSON object about the whole sweep there. MPI_Init and MPI_Finalize
 * happen inside. stop_signal (borrowed, may be NULL) is main.c's signal flag.
 * Returns, identically on every rank: NBEP_OK when every run succeeded; NBEP_EUSAGE/NBEP_EDECK
 * for a bad command line or deck before any run; NBEP_ESIGINT/NBEP_ESIGTERM when interrupted;
 * NBEP_EIO when some runs failed (d says which) or the summary could not be written, so that
 * the exit status is 1. d gets messages on rank 0 only. */
NBEP_MUST_CHECK nbep_status nbep_sweep_main(const nbep_cli *cli, const atomic_int *stop_signal,
                                            nbep_diag *d);

#endif
