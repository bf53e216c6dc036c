/* The run pipeline (run.h): deck -> outputs -> simulation -> closed file and summary. */
#include "nbep/run.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/output.h"
#include "nbep/output_xdmf.h"
#include "nbep/scene.h"
#include "nbep/sim.h"

/* Opens the summary file before anything is simulated, so that an unwritable path fails at
 * once (stdout for "-", NULL when not asked for). */
static nbep_status open_summary(const char *where, FILE **out, nbep_diag *d)
{
    *out = NULL;
    if (!where)
        return NBEP_OK;
    *out = strcmp(where, "-") == 0 ? stdout : fopen(where, "w");
    if (!*out) /* a missing directory: the user's (exit 2), as for the output file */
        NBEP_FAIL(d, nbep_status_of_open(errno), "nbep: cannot write the summary to %s: %s",
                  where, strerror(errno));
    return NBEP_OK;
}

/* Writes and closes (stdout: flushes) f; NULL f: nothing asked for. */
static nbep_status write_summary(const nbep_summary *s, const char *where, FILE *f, nbep_diag *d)
{
    if (!f)
        return NBEP_OK;
    int bad = nbep_summary_write_json(s, f) < 0;
    bad |= f == stdout ? fflush(f) != 0 : fclose(f) != 0;
    if (bad)
        NBEP_FAIL(d, NBEP_EIO, "nbep: cannot write the summary to %s", where);
    return NBEP_OK;
}

/* A new output file that nothing was simulated into goes, with its XDMF sidecar. */
static void remove_output(const char *path)
{
    remove(path);
    char *xmf = nbep_xdmf_path(path);
    if (xmf)
        remove(xmf);
    free(xmf);
}

/* The end line; a resumed run (from its frame at step `from`, else from < 0) counts the steps
 * it ran and names the step reached, which is the summary's `steps`. */
static void print_human_summary(const nbep_summary *s, const char *file, nbep_status st,
                                int64_t from)
{
    const uint64_t ran = from >= 0 && s->steps >= (uint64_t)from ? s->steps - (uint64_t)from
                                                                  : s->steps;
    char reached[48] = "";
    if (from >= 0)
        snprintf(reached, sizeof reached, " (to step %llu)", (unsigned long long)s->steps);
    fprintf(stderr,
            "nbep: %s %llu step%s%s of %llu sphere%s (%s, %d thread%s) in %.3g s (%.4g steps/s); "
            "%llu collision%s; energy drift %.3g; max overlap %.3g; %s\n",
            st == NBEP_OK ? "ran" : "stopped after", (unsigned long long)ran, ran == 1 ? "" : "s",
            reached, (unsigned long long)s->spheres, s->spheres == 1 ? "" : "s",
            s->algorithm, s->threads, s->threads == 1 ? "" : "s", s->wall_seconds,
            s->steps_per_second, (unsigned long long)s->collisions,
            s->collisions == 1 ? "" : "s", s->energy_rel_drift, s->max_overlap_rel, file);
}

/* Steps sim, closes out (with the summary unless writing already failed) and reports. */
static nbep_status step_and_close(const nbep_run_request *rq, const char *file, nbep_sim *sim,
                                  int64_t from, nbep_output **out, nbep_run_result *res,
                                  nbep_diag *d)
{
    nbep_status st = nbep_sim_run(sim, d);
    nbep_sim_summary(sim, &res->summary);
    res->simulated = true;
    /* after a write failure closing fails the same way: keep only the first error */
    nbep_diag quiet;
    nbep_diag_init(&quiet);
    bool io_failed = st == NBEP_EIO || st == NBEP_ENOMEM;
    nbep_status cst = nbep_output_close(out, io_failed ? NULL : &res->summary,
                                        io_failed ? &quiet : d);
    nbep_diag_fini(&quiet);
    if (st == NBEP_OK || st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
        st = cst == NBEP_OK ? st : cst;
    if (rq->verbose)
        print_human_summary(&res->summary, file, st, from);
    if (st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s by SIG%s after step %llu; every frame up to it is in %s",
                      st == NBEP_ESIGINT ? "interrupted" : "terminated",
                      st == NBEP_ESIGINT ? "INT" : "TERM",
                      (unsigned long long)res->summary.steps, file);
    return st;
}

nbep_status nbep_run_check_paths(const char *deck, const char *output, const char *summary,
                                 nbep_diag *d)
{
    /* -o DECK replaced the deck with the run's file, --summary DECK with the JSON; --summary
     * RUN.h5 emptied the run file (its fopen comes first) and, a resume then failing,
     * removed it */
    const char *over = nbep_output_same_file(output, deck)    ? output
                       : nbep_output_same_file(summary, deck) ? summary
                                                              : NULL;
    if (over)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: the %s file %s is the deck %s itself; choose another",
                  over == output ? "output" : "summary", over, deck);
    if (summary && output &&
        (strcmp(summary, output) == 0 || nbep_output_same_file(summary, output)))
        NBEP_FAIL(d, NBEP_EUSAGE,
                  "nbep: the summary file %s is the run's file itself; choose another", summary);
    return NBEP_OK;
}

nbep_status nbep_run(const nbep_run_request *rq, nbep_run_result *res, nbep_diag *d)
{
    memset(res, 0, sizeof *res);
    const double t_begin = nbep_now(); /* setup_seconds counts the deck and placement (SPEC) */
    nbep_peak_rss_reset(); /* peak_rss_bytes: this run's, not an earlier run's of a sweep */
    nbep_scene sc;
    nbep_status st = nbep_scene_load_from(rq->deck_path, rq->overrides, rq->override_origins,
                                          rq->n_overrides, &sc, d);
    if (st != NBEP_OK)
        return st;
    /* a signal while the deck was read and the spheres placed (seconds for millions): stop
     * now, with nothing written (the step loop would only see it after its first step, and a
     * run of 0 steps never) */
    const nbep_status sig = nbep_sim_stop_status(rq->stop_signal);
    if (sig != NBEP_OK) {
        nbep_scene_fini(&sc);
        NBEP_FAIL(d, sig, "nbep: %s by SIG%s before the run began; nothing written",
                  sig == NBEP_ESIGTERM ? "terminated" : "interrupted",
                  sig == NBEP_ESIGTERM ? "TERM" : "INT");
    }
    const int threads = nbep_sim_resolve_threads(sc.threads);
    nbep_output *out = NULL;
    nbep_sim *sim = NULL;
    nbep_resume resume = {0};
    int64_t from = -1; /* the resumed frame's step */
    FILE *summary = NULL;
    /* A resumed run appends to the file it continues; output.file does not apply. */
    const char *file = rq->resume        ? rq->resume
                       : rq->output_path ? rq->output_path
                                         : sc.output_file;
    st = nbep_run_check_paths(rq->deck_path, file, rq->summary_path, d);
    if (st != NBEP_OK) {
        nbep_scene_fini(&sc);
        return st;
    }
    st = open_summary(rq->summary_path, &summary, d);
    if (st == NBEP_OK)
        st = rq->resume ? nbep_output_open_resume(file, &sc, &out, &resume, d)
                        : nbep_output_create(file, &sc, threads, &out, d);
    if (st == NBEP_OK) {
        if (rq->resume)
            nbep_resume_apply(&resume, &sc.state);
        nbep_sim_options opt = {.threads = threads, .out = out,
                                .stop_signal = rq->stop_signal, .progress = rq->verbose,
                                .resume = rq->resume ? &resume : NULL,
                                .take_state = &sc.state, /* nothing reads the scene's again */
                                .t_begin = t_begin};
        st = nbep_sim_create(&sc, &opt, &sim, d);
        if (st == NBEP_OK && rq->resume) /* only now is the file changed */
            st = nbep_output_resume_begin(out, &sc, threads, d);
        if (st == NBEP_OK && rq->resume && rq->verbose && resume.last_step != resume.step)
            fprintf(stderr,
                    "nbep: %s continues from its frame at step %lld, the last at a multiple of "
                    "output.every (run.neighbors = \"cells\" continues bit for bit from those "
                    "only); the frames after it, to step %lld, are dropped\n",
                    file, (long long)resume.step, (long long)resume.last_step);
        from = rq->resume ? resume.step : -1;
        nbep_resume_fini(&resume); /* the run has its event slots now */
        if (st != NBEP_OK) {
            nbep_status ignored = nbep_output_close(&out, NULL, d);
            (void)ignored;
            if (!rq->resume) /* nothing was simulated: leave nothing behind */
                remove_output(file);
        }
    }
    if (st == NBEP_OK) {
        st = step_and_close(rq, file, sim, from, &out, res, d);
        nbep_status sst = write_summary(&res->summary, rq->summary_path, summary, d);
        summary = NULL;
        if (st == NBEP_OK)
            st = sst;
    }
    if (summary && summary != stdout) { /* never simulated: no summary file either */
        fclose(summary);
        remove(rq->summary_path);
    }
    nbep_sim_destroy(&sim);
    nbep_resume_fini(&resume);
    nbep_scene_fini(&sc);
    return st;
}
