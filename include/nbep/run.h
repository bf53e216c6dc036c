/* One run of a deck, from its path to a closed output file: load the scene, open the outputs
 * (HDF5 file, or the run to resume; the JSON summary file), create the simulation, run it,
 * close and write the summary. `nbep run` (main.c) and every run of `nbep sweep` (sweep.c)
 * go through nbep_run, so that they fail, clean up and report errors the same way. */
#ifndef NBEP_RUN_H
#define NBEP_RUN_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/summary.h"

typedef struct nbep_run_request {
    const char *deck_path;
    const char *const *overrides;  /* n_overrides "key = value" texts, as --set gives them */
    const char *const *override_origins; /* NULL, or what was typed for each (NULL: --set),
                                          * for messages (nbep_scene_load_from) */
    size_t n_overrides;
    const char *output_path;       /* NULL: the deck's output.file */
    const char *resume;            /* NULL, or a run to continue (then output_path is unused) */
    const char *summary_path;      /* NULL, "-" (stdout) or a file for the JSON summary */
    const atomic_int *stop_signal; /* borrowed, may be NULL: nonzero = SIGINT/SIGTERM number */
    bool verbose;                  /* progress lines and a one-line human summary on stderr */
    bool sweep_run;                /* one run of a sweep, whose plan checked its axes' values
                                    * (nbep_scene_load_run) */
} nbep_run_request;

typedef struct nbep_run_result {
    bool simulated;                /* stepping began: `summary` says what was done */
    int64_t resumed_from;          /* when simulated: the step of the frame a resume went on
                                    * from, -1 for a run from its start */
    nbep_summary summary;          /* its `status` is the returned status's
                                    * (nbep_summary_status_of), close included */
} nbep_run_result;

/* For `nbep check`: whether `nbep run` could create its output file at `output`, looked at
 * without writing anything: its directory exists, is one and may be written, and `output` is
 * not a directory. NBEP_EUSAGE (NBEP_EIO for a read-only file system), one line in the words
 * of the run's own failure, "nbep: OUTPUT: cannot create the output file: REASON". */
NBEP_MUST_CHECK nbep_status nbep_run_check_output_dir(const char *output, nbep_diag *d);

/* The same look, its reason alone ("No such file or directory"), or NULL where `nbep run`
 * could create the file: for a study's deck, whose `nbep sweep` makes its own folder, so that
 * `nbep check` says what `nbep run` of it would meet (a new user's review: check passed a
 * study whose output.file's folder was missing, and nbep run of the deck then failed). The
 * text is strerror's or static: valid until the next strerror. */
const char *nbep_run_output_fault(const char *output);
/* Where the run file `output` that cannot be made is sc's output.file as the deck set it (not
 * -o or a --set, whose messages name the path typed), rewords the messages from d's message
 * `first` on that say so ("nbep: OUTPUT: cannot create the output file: REASON") to name the
 * deck's line: "DECK:LINE: output.file: OUTPUT: cannot create the output file: REASON". */
void nbep_run_blame_deck_output(const nbep_scene *sc, const char *deck, const char *output,
                                nbep_diag *d, size_t first);

/* Writes text (a JSON line) as the summary file `where` is written: "-" is stdout; a file is
 * written as WHERE.partial and renamed to WHERE once complete, so an older file there stays
 * when anything fails. NBEP_EUSAGE for a missing directory, NBEP_EIO for a write error, each
 * one line "nbep: cannot write the summary to WHERE: ...". A NULL text (out of memory) fails. */
NBEP_MUST_CHECK nbep_status nbep_run_write_summary_text(const char *where, const char *text,
                                                        nbep_diag *d);
/* Whether the summary file `where` can be written as nbep_run_write_summary_text will write it,
 * tried before any run (a typo in a job script's path found at once), leaving nothing behind:
 * a file's WHERE.partial is made (and its lock taken) and removed, WHERE untouched; a device
 * or a pipe is only asked whether it may be written (opened and closed, a FIFO's reader would
 * take that for its end). The errors of nbep_run_write_summary_text's opening. */
NBEP_MUST_CHECK nbep_status nbep_run_try_summary(const char *where, nbep_diag *d);

/* The files a command writes, against the deck and each other: an output file (the run's, or
 * the one resumed) or a summary file that is the deck would replace it, and a summary file
 * that is the run's file would empty it before the run opens it. NBEP_EUSAGE with one line
 * naming both; NBEP_OK otherwise. output and summary may be NULL. */
NBEP_MUST_CHECK nbep_status nbep_run_check_paths(const char *deck, const char *output,
                                                 const char *summary, nbep_diag *d);
/* Whether paths a and b name one file, which may not exist yet (their directories resolved:
 * "./x" and "x" are one; so are two names of a file that exists). */
bool nbep_run_same_path(const char *a, const char *b);

/* Runs rq. Deck errors come before anything is written; outputs are opened before any
 * simulating, so that an unwritable path fails at once; a run that never stepped leaves no
 * output behind (a new file and its XDMF sidecar are removed, a resumed file is left as it
 * was; no summary file). After a write failure the file gets nothing more and d holds that
 * one error. A stop by signal returns NBEP_ESIGINT/NBEP_ESIGTERM with a line saying after
 * which step and where the frames are. *res is always filled. */
NBEP_MUST_CHECK nbep_status nbep_run(const nbep_run_request *rq, nbep_run_result *res,
                                     nbep_diag *d);

#endif
