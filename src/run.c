/* The run pipeline (run.h): deck -> outputs -> simulation -> closed file and summary. */
#define _XOPEN_SOURCE 700 /* realpath() */
#include "nbep/run.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "nbep/output.h"
#include "nbep/output_xdmf.h"
#include "nbep/scene.h"
#include "nbep/sim.h"

/* The summary file is written as "WHERE.partial" (nbep_partial_path) and renamed to WHERE once
 * complete, as the run's file is: an older summary there survives a run refused or killed
 * before its end (a resume refused for a deck that does not match removed it, and a full disk
 * left it empty). */
/* A summary path that names a device or a pipe (/dev/null, /dev/stderr, a FIFO a script reads)
 * is written in place: no temporary file beside it (none can be made in /dev) and nothing to
 * rename, and no older summary to keep (until 2026-11-30 `--summary /dev/null` failed, "cannot
 * write the summary to /dev/null"). */
/* ... and so is one that leads into /proc, its folder resolved or through links: /dev/stdout,
 * /dev/fd/1 or /proc/self/fd/1 with standard output sent to a file (a process's open file, not
 * a name in a folder). Made beside it and renamed, the summary replaced the link /dev/stdout
 * itself where its folder takes files (root, a container's /dev), and the file the shell had
 * opened got nothing (until 2026-12-05). Opened for appending: whatever the run wrote to that
 * file before stays. Not the rest of /dev: /dev/shm is node-local scratch (the first version
 * of this took all of /dev, and a review found a summary there left at NAME.partial). */
static bool in_proc(const char *path, int hops)
{
    char *dir = nbep_path_dir(path);
    char *real = dir ? realpath(dir, NULL) : NULL;
    bool proc = real && strncmp(real, "/proc", 5) == 0 && (real[5] == '\0' || real[5] == '/');
    char target[4096];
    ssize_t k;
    struct stat sb;
    if (!proc && real && hops > 0 && lstat(path, &sb) == 0 && S_ISLNK(sb.st_mode) &&
        (k = readlink(path, target, sizeof target - 1)) > 0) {
        target[k] = '\0';
        if (target[0] == '/') {
            proc = in_proc(target, hops - 1);
        } else { /* relative to the link's folder */
            char *next = malloc(strlen(real) + (size_t)k + 2);
            if (next) {
                sprintf(next, "%s/%s", real, target);
                proc = in_proc(next, hops - 1);
            }
            free(next);
        }
    }
    free(dir);
    free(real);
    return proc;
}

/* 8 links on the way at most (a loop ends there; Linux follows 40) */
static bool leads_into_proc(const char *path)
{
    return in_proc(path, 8);
}

/* The output's fault where it leads into /proc (leads_into_proc) */
#define PROC_OUTPUT_FAULT                                                                      \
    "it leads into /proc, to a process's open file (/dev/stdout), not a name in a folder: an "  \
    "HDF5 file is written by name and renamed"

static bool summary_in_place(const char *where)
{
    struct stat sb;
    return stat(where, &sb) == 0 && !S_ISDIR(sb.st_mode) &&
           (!S_ISREG(sb.st_mode) || leads_into_proc(where));
}

/* Opens the summary's temporary file before anything is simulated, so that an unwritable
 * path fails at once (stdout for "-", NULL when not asked for). An open that a stop signal
 * interrupted (a FIFO waiting for its reader: the handlers do not restart calls) returns that
 * signal's status, with no line: the caller says the run stopped (stop may be NULL). */
static nbep_status open_summary(const char *where, const atomic_int *stop, FILE **out,
                                nbep_diag *d)
{
    *out = NULL;
    if (!where)
        return NBEP_OK;
    if (strcmp(where, "-") == 0) {
        *out = stdout;
        return NBEP_OK;
    }
    /* a directory there (or "dir/"): its ".partial" opens, and only the rename at the run's
     * end failed, exit 1 after every step (README: a path that names a directory is bad
     * usage, found before any step) */
    struct stat sb;
    if (stat(where, &sb) == 0 && S_ISDIR(sb.st_mode))
        NBEP_FAIL(d, nbep_status_of_open(EISDIR), "nbep: cannot write the summary to %s: %s",
                  where, strerror(EISDIR));
    const bool in_place = summary_in_place(where);
    char *tmp = in_place ? NULL : nbep_partial_path(where);
    if (!in_place && !tmp)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the summary's file name");
    /* The temporary file is locked while this run writes it (nbep_lock_take: the lock stands
     * only on the file its name leads to), and put at WHERE before the lock goes: a second run
     * naming the same summary (a job resubmitted with another output) is refused rather than
     * emptying the first's half-written SUMMARY.partial, or having it renamed from under it
     * (until 2026-12-01 both wrote one file). A file system without locks: unguarded. */
    bool busy = false;
    const int fd = in_place ? -1 : nbep_lock_take(tmp, &busy);
    int err = 0;
    if (fd < 0 && !busy)
        *out = fopen(in_place ? where : tmp, in_place ? "a" : "w");
    else if (fd >= 0 && (fcntl(fd, F_GETFL) & O_ACCMODE) == O_RDONLY)
        err = EACCES; /* locked read-only: another user's SUMMARY.partial (nbep_lock_take;
                       * "Invalid argument" from ftruncate, exit 1, until a review) */
    else if (fd >= 0 && ftruncate(fd, 0) == 0)
        *out = fdopen(fd, "w");
    if (!*out) {
        err = err ? err : errno;
        if (fd >= 0)
            close(fd);
    }
    if (!*out && busy) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: cannot write the summary to %s: another nbep run is writing it (it "
                      "holds %s); wait for it to end, or give this run another --summary",
                      where, tmp);
        free(tmp);
        return NBEP_EBUSY;
    }
    free(tmp);
    if (!*out && err == EINTR && nbep_status_of_stop(stop) != NBEP_OK)
        return nbep_status_of_stop(stop); /* until 2026-12-02: "Interrupted system call", 1 */
    if (!*out) /* a missing directory: the user's (exit 2), as for the output file */
        NBEP_FAIL(d, nbep_status_of_open(err), "nbep: cannot write the summary to %s: %s",
                  where, strerror(err));
    return NBEP_OK;
}

/* Whether f, as open_summary opened it at where, writes the summary in place (a device, a
 * pipe, a file through a link into /proc: summary_in_place) rather than into its temporary
 * file, a regular one. Read off the file opened, not the path again: what stands at the path
 * may have changed during the run (a review's find: a device put there since left the
 * temporary file behind, unrenamed); only the links into /proc are looked at again. */
static bool opened_in_place(FILE *f, const char *where)
{
    struct stat sb;
    return fstat(fileno(f), &sb) == 0 && (!S_ISREG(sb.st_mode) || leads_into_proc(where));
}

/* Nothing to write after all: the temporary file goes, an older summary stays. */
static void drop_summary(const char *where, FILE *f)
{
    if (!f || f == stdout)
        return;
    char *tmp = opened_in_place(f, where) ? NULL : nbep_partial_path(where);
    if (tmp) /* while the lock holds: the file is this run's */
        remove(tmp);
    free(tmp);
    fclose(f);
}

/* Writes text to f and closes it (stdout: flushes), then puts it at `where`; NULL f: nothing
 * asked for. On failure the temporary file goes and an older file there stays. */
static nbep_status finish_text(const char *text, const char *where, FILE *f, nbep_diag *d)
{
    if (!f)
        return NBEP_OK;
    errno = 0;
    int bad = !text || fputs(text, f) == EOF || ferror(f);
    int err = text ? errno : ENOMEM;
    if (f == stdout) { /* the write fails as it is flushed (a full disk): its reason too */
        bad |= fflush(f) != 0;
        err = err ? err : errno;
    } else if (opened_in_place(f, where)) {
        bad |= fclose(f) != 0;
        err = err ? err : errno;
    } else { /* the temporary file put in place, or removed, before its lock goes with f */
        bad |= fflush(f) != 0;
        err = err ? err : errno;
        char *tmp = nbep_partial_path(where);
        if (!tmp || bad || rename(tmp, where) != 0) {
            err = err ? err : errno;
            if (tmp)
                remove(tmp);
            bad = 1;
        }
        /* a write that fails only as the file closes (NFS): its text is not whole, and it
         * stands at WHERE already */
        if (fclose(f) != 0 && !bad) {
            err = errno;
            remove(where);
            bad = 1;
        }
        free(tmp);
    }
    if (bad)
        NBEP_FAIL(d, NBEP_EIO, "nbep: cannot write the summary to %s: %s", where,
                  err ? strerror(err) : "write failed");
    return NBEP_OK;
}

static nbep_status write_summary(const nbep_summary *s, const char *where, FILE *f, nbep_diag *d)
{
    if (!f)
        return NBEP_OK;
    char *line = nbep_summary_to_json(s);
    const nbep_status st = finish_text(line, where, f, d);
    free(line);
    return st;
}

nbep_status nbep_run_write_summary_text(const char *where, const char *text, nbep_diag *d)
{
    FILE *f;
    const nbep_status st = open_summary(where, NULL, &f, d);
    return st != NBEP_OK ? st : finish_text(text, where, f, d);
}

nbep_status nbep_run_try_summary(const char *where, nbep_diag *d)
{
    if (where && strcmp(where, "-") != 0 && summary_in_place(where)) {
        if (access(where, W_OK) != 0)
            NBEP_FAIL(d, nbep_status_of_open(errno), "nbep: cannot write the summary to %s: %s",
                      where, strerror(errno));
        return NBEP_OK;
    }
    FILE *f;
    const nbep_status st = open_summary(where, NULL, &f, d);
    drop_summary(where, f); /* (nothing for NULL or stdout) */
    return st;
}

/* x with 3 significant digits, or more where 3 would round a magnitude below 1 up to 1: an
 * energy drift of -0.9998 (a sphere dropped from 5000 radii at e = 0 keeps 2e-4 of its energy)
 * printed as -1 said all of it was gone (a helper's review, 2026-12-03). */
static const char *three_digits(double x, char buf[32])
{
    for (int digits = 3; digits <= 17; digits++) {
        snprintf(buf, 32, "%.*g", digits, x);
        if (!(fabs(x) < 1.0) || fabs(strtod(buf, NULL)) < 1.0)
            break;
    }
    return buf;
}

/* The end line; a resumed run (from its frame at step `from`, else from < 0) counts the steps
 * it ran and names the step reached, which is the summary's `steps`, and says where its
 * collisions, drift and overlap are the whole run's (its file's totals went on: `whole`). */
static void print_human_summary(const nbep_summary *s, const char *file, nbep_status st,
                                int64_t from, bool whole)
{
    const uint64_t ran = from >= 0 && s->steps >= (uint64_t)from ? s->steps - (uint64_t)from
                                                                  : s->steps;
    char reached[48] = "";
    if (from >= 0)
        snprintf(reached, sizeof reached, " (to step %llu)", (unsigned long long)s->steps);
    fprintf(stderr,
            "nbep: %s %llu step%s%s of %llu sphere%s (%s, %d thread%s) in %.3g s (%.4g steps/s); "
            "%s%llu collision%s; energy drift %s; max overlap / r %.3g; %s\n",
            st == NBEP_OK ? "ran" : "stopped after", (unsigned long long)ran, ran == 1 ? "" : "s",
            reached, (unsigned long long)s->spheres, s->spheres == 1 ? "" : "s",
            s->algorithm, s->threads, s->threads == 1 ? "" : "s", s->wall_seconds,
            s->steps_per_second, from >= 0 && whole ? "since step 0: " : "",
            (unsigned long long)s->collisions,
            s->collisions == 1 ? "" : "s", three_digits(s->energy_rel_drift, (char[32]){0}),
            s->max_overlap_rel, file);
}

/* Steps sim, closes out (with the summary unless writing already failed) and reports. */
static nbep_status step_and_close(const nbep_run_request *rq, const char *file, nbep_sim *sim,
                                  int64_t from, bool whole, nbep_output **out,
                                  nbep_run_result *res, nbep_diag *d)
{
    nbep_status st = nbep_sim_run(sim, d);
    nbep_sim_summary(sim, &res->summary);
    /* the file's /summary says how the simulation ended; a close that then fails makes the
     * run's status, and the --summary file's, failed (below) */
    res->summary.status = nbep_summary_status_of(st);
    res->simulated = true;
    res->resumed_from = from;
    /* after a write failure closing fails the same way: keep only the first error (a step out
     * of memory with no write failed is the algorithm's: the file is sound and gets its
     * /summary, which says the run failed, as after a numerical failure; until 2026-12-07 it
     * was taken for a write's and the file had none) */
    nbep_diag quiet;
    nbep_diag_init(&quiet);
    bool io_failed = st == NBEP_EIO || nbep_sim_output_failed(sim);
    nbep_status cst = nbep_output_close(out, io_failed ? NULL : &res->summary,
                                        io_failed ? &quiet : d);
    nbep_diag_fini(&quiet);
    if (st == NBEP_OK || st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
        st = cst == NBEP_OK ? st : cst;
    res->summary.status = nbep_summary_status_of(st);
    if (rq->verbose)
        print_human_summary(&res->summary, file, st, from, whole);
    uint64_t frame_step;
    const bool abandoned = nbep_sim_abandoned(sim, &frame_step);
    const char *how = nbep_status_stop_text(st, rq->stop_signal);
    if ((st == NBEP_ESIGINT || st == NBEP_ESIGTERM) && abandoned)
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s during step %llu, which is abandoned; the run ends "
                      "after step %llu, and its frames up to step %llu are in %s",
                      how, (unsigned long long)res->summary.steps + 1,
                      (unsigned long long)res->summary.steps, (unsigned long long)frame_step,
                      file);
    else if (st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s after step %llu; every frame up to it is in %s", how,
                      (unsigned long long)res->summary.steps, file);
    return st;
}

/* The exact algorithm (predictive, run.order = "time") places every contact by prediction,
 * so its overlaps are round-off: 1e-14 to 5e-11 of a radius (README, Checking a run; 3.7e-12 at
 * most over the accuracy study's 494 runs). One of a millionth of a radius is five orders past
 * the largest seen, and still far below anything a user would see: such a run went wrong
 * (spheres passed into each other, as cells mode did in a periodic box until a7bf0a0, or the
 * file it resumed was changed), though every check of the state passed. naive and seminaive
 * find contacts after the overlap, and the paper's step order may shadow events: they
 * overlap by design (README, Accuracy), and get no warning. */
#define EXACT_OVERLAP_WARN 1e-6
/* Far from the origin, round-off is the coordinates': a position rounds to 2^-53 of its size,
 * span * 2^-53 of a radius at the deck's farthest coordinate (scene.h span; up to 2^-13 at
 * NBEP_DECK_SPAN_MAX), and a contact there is placed to a few of those, its flights to the
 * contact, response and slot each rounding it once, and a sphere that flies many steps to it
 * in all-pairs and grid mode carries half of one a step (README, The deck: the span). A floor
 * at 1e11 radii overlapped by 1 to 4 of them in every predictive mode, and got this warning
 * until 2026-12-03; 64 leave room for those, and the warning is for overlaps beyond what the
 * coordinates can hold (0.24 of a radius at 5e11 radii after 1.1e4 steps of flight). */
#define EXACT_OVERLAP_ULPS 64.0
/* The others' overlaps grow with run.dt (speed dt / r: README, Accuracy), by design; one of
 * more than the smaller radius means spheres went halfway through each other within a step,
 * and those that went all the way through were never found: the collisions are the step's
 * artefact, whatever the user's trade of accuracy for speed meant to keep. */
#define DETECT_OVERLAP_WARN 1.0

/* A warning, also with --quiet (it says the results are wrong), when a run ended with overlaps
 * past what its algorithm allows: round-off for the exact one, the smaller radius for those
 * that find contacts after they overlap; the run's status and exit stay those of a run that
 * completed. */
static void warn_overlap(const nbep_scene *sc, const nbep_summary *s, const char *file,
                         bool other_algorithm)
{
    const bool exact = strcmp(sc->algorithm, "predictive") == 0 && !sc->order_step;
    const double coords = EXACT_OVERLAP_ULPS * sc->span * 0x1p-53; /* of a radius */
    if (exact && s->max_overlap_rel > fmax(EXACT_OVERLAP_WARN, coords)) {
        char far[96] = "";
        if (coords > 1e-9)
            snprintf(far, sizeof far, "; with coordinates this far from the origin, below %.2g",
                     coords);
        /* a summary from step 0 counts the earlier parts too: one run by naive, say, left
         * overlaps that the predictive part carries on from (a review's, 2026-12-04: the
         * warning blamed the predictive algorithm for them) */
        fprintf(stderr,
                "nbep: warning: spheres overlapped by up to %.3g of the smaller radius "
                "(max_overlap_rel) in %s, where the predictive algorithm's overlaps are "
                "round-off (below 1e-9%s)%s: its collisions are not to be trusted (README, "
                "Checking a run)\n",
                s->max_overlap_rel, file, far,
                other_algorithm ? "; an earlier part of the run ran another algorithm, whose "
                                  "overlaps this part starts from"
                                : "");
    }
    /* the cure named for what the run is: step order is the predictive algorithm already,
     * whose exact order is run.order = "time" (until 2026-12-05 it was sent to "the
     * predictive algorithm"); planes named only where the scene has some (a periodic box
     * has none) */
    else if (!exact && s->max_overlap_rel > DETECT_OVERLAP_WARN) {
        char how[128];
        if (sc->order_step)
            snprintf(how, sizeof how, "run.order = \"step\" reacts to a step's events at once, "
                                      "some shadowed by others");
        else
            snprintf(how, sizeof how, "%s finds contacts after they overlap", sc->algorithm);
        fprintf(stderr,
                "nbep: warning: spheres overlapped by up to %.3g of the smaller radius "
                "(max_overlap_rel) in %s: %s, and at this run.dt spheres passed into and "
                "through each other%s (collisions missed); a smaller run.dt, or %s, avoids it "
                "(README, Accuracy)\n",
                s->max_overlap_rel, file, how, s->planes > 0 ? " or the planes" : "",
                sc->order_step ? "run.order = \"time\" (exact)" : "the predictive algorithm");
    }
}

/* path with its directory resolved (realpath) and its last name kept, malloc'd: two names of
 * one file compare equal even before the file exists. NULL when the directory does not exist
 * or without memory. */
static char *canonical(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    char *dir = nbep_path_dir(path);
    if (!dir)
        return NULL;
    char *real = realpath(dir, NULL);
    free(dir);
    if (!real)
        return NULL;
    char *c = malloc(strlen(real) + strlen(base) + 2);
    if (c)
        sprintf(c, "%s/%s", real, base);
    free(real);
    return c;
}

bool nbep_run_same_path(const char *a, const char *b)
{
    if (strcmp(a, b) == 0 || nbep_output_same_file(a, b))
        return true;
    char *ca = canonical(a), *cb = canonical(b);
    const bool same = ca && cb && strcmp(ca, cb) == 0;
    free(ca);
    free(cb);
    return same;
}

/* Whether the name path's file is written under, `path` with `suffix` (".partial": a new
 * run file, a summary), fits its folder's file system: 0, else ENAMETOOLONG (a name of 248
 * to 255 characters passed `nbep check` and failed the run, until 2026-12-01). */
static int staged_name_fits(const char *path, const char *suffix)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    char *dir = nbep_path_dir(path);
    long max = dir ? pathconf(dir, _PC_NAME_MAX) : -1;
    free(dir);
    if (max <= 0)
        max = 255; /* the common limit, where the folder does not say */
    return strlen(base) + strlen(suffix) > (size_t)max ? ENAMETOOLONG : 0;
}

/* Whether the file at path begins with HDF5's signature. */
static bool is_hdf5_file(const char *path)
{
    char head[NBEP_HDF5_SIGNATURE_LEN];
    FILE *f = fopen(path, "rb");
    const bool hdf5 = f && fread(head, 1, sizeof head, f) == sizeof head &&
                      memcmp(head, NBEP_HDF5_SIGNATURE, sizeof head) == 0;
    if (f)
        fclose(f);
    return hdf5;
}

/* What stands at a sidecar's path xmf when it is not a regular file holding XDMF
 * (nbep_xdmf_run_of: an earlier run's sidecar, which a run may replace), in words; NULL when
 * nothing stands there or a sidecar does. */
static const char *sidecar_misfit(const char *xmf)
{
    char name[8];
    struct stat sb;
    const char *what = NULL;
    if (stat(xmf, &sb) == 0) {
        if (S_ISDIR(sb.st_mode))
            what = "a folder";
        else if (!S_ISREG(sb.st_mode))
            what = "no regular file (a device, a pipe or a socket)";
        else if (!nbep_xdmf_run_of(xmf, name, sizeof name))
            what = "a file that is not XDMF (one of yours?)";
    }
    return what;
}

/* The place of output's XDMF sidecar, which a run writes by rename: not the deck (it replaced
 * the deck, until 2026-12-01); not the sidecar of another run beside it (`-o x` and `-o x.h5`
 * have one sidecar, x.xmf: the second run replaced the first's, until 2026-12-02); and holding
 * nothing, or an earlier run's sidecar, which the run replaces (or, writing no positions,
 * removes): a user's file there was replaced or removed without a word, and a folder there
 * failed the run after its set-up and first frame (until 2026-12-04, a review). NBEP_EUSAGE
 * with one line otherwise. */
static nbep_status sidecar_place(const char *deck, const char *output, nbep_diag *d)
{
    char *xmf = nbep_xdmf_path(output), *owner = NULL;
    const char *not_side = NULL;
    nbep_status st = NBEP_EUSAGE;
    if (!xmf) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: out of memory");
        st = NBEP_ENOMEM;
    } else if (deck && nbep_output_same_file(xmf, deck))
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: the output file %s's XDMF sidecar is the deck %s itself; choose "
                      "another output",
                      output, deck);
    else if ((owner = nbep_xdmf_other_run(output)))
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: the output file %s's XDMF sidecar would replace that of the run %s "
                      "beside it; choose another output",
                      output, owner);
    else if ((not_side = sidecar_misfit(xmf)))
        /* worded as the output's other faults, which nbep_run_blame_deck_output puts at the
         * deck's output.file line */
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: cannot create the output file: its XDMF sidecar's place %s "
                      "holds %s, which the run would replace; move it away or choose another "
                      "output",
                      output, xmf, not_side);
    else
        st = NBEP_OK;
    free(owner);
    free(xmf);
    return st;
}

nbep_status nbep_run_check_paths(const char *deck, const char *output, const char *summary,
                                 nbep_diag *d)
{
    if (summary && !*summary)
        NBEP_FAIL(d, NBEP_EUSAGE,
                  "nbep: --summary names no file (an empty path); name one, or - for standard "
                  "output");
    if (summary && strcmp(summary, "-") != 0 && !summary_in_place(summary) &&
        staged_name_fits(summary, ".partial") != 0)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: cannot write the summary to %s: %s (its .partial, "
                  "written first, is longer than the folder allows)", summary,
                  strerror(ENAMETOOLONG));
    nbep_status st = output ? sidecar_place(deck, output, d) : NBEP_OK;
    if (st != NBEP_OK)
        return st;
    /* -o DECK replaced the deck with the run's file, --summary DECK with the JSON; --summary
     * RUN.h5 emptied the run file (its fopen comes first) and, a resume then failing,
     * removed it */
    const char *over = nbep_output_same_file(output, deck)    ? output
                       : nbep_output_same_file(summary, deck) ? summary
                                                              : NULL;
    if (over)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: the %s file %s is the deck %s itself; choose another",
                  over == output ? "output" : "summary", over, deck);
    /* a run's lock is OUT.lock beside its file (nbep_lock_path): an output there would be
     * renamed over another run's lock, which that run then removes with it at its end. A new
     * file is made as OUT.partial (nbep_partial_path) under OUT's lock: an output there was
     * emptied by a run into OUT, under another lock, and renamed from under its writer (until
     * 2026-12-01) */
    if (output && nbep_ends_with(output, ".lock"))
        NBEP_FAIL(d, NBEP_EUSAGE,
                  "nbep: the output file %s ends in .lock, the name of a run's lock beside its "
                  "file; choose another",
                  output);
    if (output && nbep_ends_with(output, ".partial"))
        NBEP_FAIL(d, NBEP_EUSAGE,
                  "nbep: the output file %s ends in .partial, the name a run's file is made "
                  "under until it is whole; choose another",
                  output);
    if (summary && output && strcmp(summary, "-") != 0) {
        /* the run's file and its sidecar are written by rename: a summary at either name
         * would be replaced, or would replace it; at its lock's, it would take the lock
         * file's place and another run would lock that one */
        char *xmf = nbep_xdmf_path(output), *lock = nbep_lock_path(output);
        /* and the name a new run's file is built under, OUT.partial, which a run that fails
         * before its file is whole removes, a summary there with it (a review, 2026-12-05) */
        char *staged = nbep_partial_path(output);
        const bool run = nbep_run_same_path(summary, output);
        const bool side = xmf && nbep_run_same_path(summary, xmf);
        const bool held = lock && nbep_run_same_path(summary, lock);
        const bool built = staged && nbep_run_same_path(summary, staged);
        free(xmf);
        free(lock);
        free(staged);
        if (run || side || held || built)
            NBEP_FAIL(d, NBEP_EUSAGE, "nbep: the summary file %s is the run's %s; choose another",
                      summary,
                      run    ? "file itself"
                      : side ? "XDMF sidecar"
                      : held ? "lock file"
                             : "file as it is built (OUT.partial, renamed to OUT once whole)");
    }
    /* ... nor another run's: a summary replaced an HDF5 file at its path (another run's file,
     * which went on writing a file no longer there and ended with exit 0), and at a name
     * ending in .lock or .xmf it took another run's lock (a third run then wrote into the
     * file it guarded) or sidecar (until 2026-12-02, a review) */
    if (summary && strcmp(summary, "-") != 0 && !summary_in_place(summary)) {
        const char *name = nbep_ends_with(summary, ".lock")  ? "lock"
                           : nbep_ends_with(summary, ".xmf") ? "XDMF sidecar"
                                                             : NULL;
        if (name)
            NBEP_FAIL(d, NBEP_EUSAGE,
                      "nbep: the summary file %s has the name of a run's %s, which the summary "
                      "would replace; choose another",
                      summary, name);
        if (is_hdf5_file(summary))
            NBEP_FAIL(d, NBEP_EUSAGE,
                      "nbep: the summary file %s is an HDF5 file (a run's?), which the summary "
                      "would replace; choose another",
                      summary);
    }
    return NBEP_OK;
}

/* Why no new run file can be made at `output` by the name it is made under and renamed from,
 * in the words of "nbep: OUTPUT: cannot create the output file: REASON", or NULL: something
 * other than a file, a link or a folder there (a FIFO, a device: /dev/null, as root, was
 * replaced by the run's file until 2026-12-01; a link is replaced itself), or OUTPUT.partial
 * longer than the folder allows (a name of 248 to 255 characters passed `nbep check` and failed
 * the run). Shared by run (a new file; a resume makes no .partial) and check. */
static const char *new_output_fault(const char *output)
{
    struct stat sb;
    if (leads_into_proc(output)) /* as root the run's rename replaced /dev/stdout, the link */
        return PROC_OUTPUT_FAULT;
    if (lstat(output, &sb) == 0 && S_ISDIR(sb.st_mode))
        return strerror(EISDIR); /* before anything is made: a folder given as "results/"
                                  * made results/.partial and failed its rename, "Not a
                                  * directory", until 2026-12-03 (an HPC user's review) */
    if (lstat(output, &sb) == 0 && !S_ISREG(sb.st_mode) && !S_ISLNK(sb.st_mode))
        return "not a regular file (a device, a pipe or a socket)";
    if (staged_name_fits(output, ".partial") != 0)
        return "File name too long (its .partial, made first, is longer than the folder allows)";
    return NULL;
}

/* Why `nbep run` could not create its output file at `output` (its reason's words), or NULL;
 * *err_out the errno behind it (0: none, or the reason is new_output_fault's). */
static const char *output_dir_fault(const char *output, const char *dir, int *err_out)
{
    struct stat sb;
    int err = 0;
    if (leads_into_proc(output)) /* before its folder's ENOENT (/proc) or none (root) */
        return PROC_OUTPUT_FAULT;
    /* lstat: the run's rename replaces a symbolic link at `output`, to a directory too */
    if (lstat(output, &sb) == 0 && S_ISDIR(sb.st_mode))
        err = EISDIR; /* the run's rename onto it fails */
    else if (stat(dir, &sb) != 0)
        err = errno; /* ENOENT, or ENOTDIR for a file on the way */
    else if (!S_ISDIR(sb.st_mode))
        err = ENOTDIR;
    else
        err = nbep_dir_takes_files(dir); /* EACCES, EROFS: the user's path (exit 2), as the
                                          * run's own */
    *err_out = err;
    return err ? strerror(err) : new_output_fault(output);
}

const char *nbep_run_output_fault(const char *output)
{
    char *dir = nbep_path_dir(output);
    int err = 0;
    const char *fault = dir ? output_dir_fault(output, dir, &err) : strerror(ENOMEM);
    free(dir);
    return fault;
}

nbep_status nbep_run_check_output_dir(const char *output, nbep_diag *d)
{
    char *dir = nbep_path_dir(output);
    if (!dir)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory");
    int err = 0;
    const char *fault = output_dir_fault(output, dir, &err);
    free(dir);
    if (fault) /* the words of the run's own failure (output.c, nbep_run) */
        NBEP_FAIL(d, err ? nbep_status_of_open(err) : NBEP_EUSAGE,
                  "nbep: %s: cannot create the output file: %s", output, fault);
    return NBEP_OK;
}

void nbep_run_blame_deck_output(const nbep_scene *sc, const char *deck, const char *output,
                                nbep_diag *d, size_t first)
{
    if (!sc->output_file_line || !output || strcmp(output, sc->output_file) != 0)
        return;
    static const char tail[] = ": cannot create the output file";
    const size_t n = strlen(output), stored = d->n_errors < d->cap ? d->n_errors : d->cap;
    for (size_t i = first; i < stored; i++) {
        const char *m = d->msg[i]; /* "nbep: OUTPUT: cannot create the output file..." */
        if (!m || strncmp(m, "nbep: ", 6) != 0 || strncmp(m + 6, output, n) != 0 ||
            strncmp(m + 6 + n, tail, sizeof tail - 1) != 0)
            continue;
        const int len = snprintf(NULL, 0, "%s:%u: output.file: %s", deck, sc->output_file_line,
                                 m + 6);
        char *b = len > 0 ? malloc((size_t)len + 1) : NULL;
        if (!b)
            continue; /* without memory the message stays as it was */
        snprintf(b, (size_t)len + 1, "%s:%u: output.file: %s", deck, sc->output_file_line, m + 6);
        free(d->msg[i]);
        d->msg[i] = b;
    }
}

/* The pair tests before the first step from which a run of the paper's all-pairs mode says, as
 * it begins, that the cells mode exists: 2^30, from 46342 spheres, whose first predictions alone
 * take a minute or more of one core (65536 spheres: minutes, README). A new user ran 400000
 * spheres so (2026-12-02) and waited 10 minutes for a first step that took hours. */
#define ALL_PAIRS_NOTE_PAIRS 1073741824.0

/* The line of a run stopped by signal st before its first frame, with nothing written. */
static nbep_status not_begun(nbep_status st, const nbep_run_request *rq, nbep_diag *d)
{
    NBEP_FAIL(d, st, "nbep: %s before the run began; nothing written",
              nbep_status_stop_text(st, rq->stop_signal));
}

nbep_status nbep_run(const nbep_run_request *rq, nbep_run_result *res, nbep_diag *d)
{
    memset(res, 0, sizeof *res);
    const double t_begin = nbep_now(); /* setup_seconds counts the deck and placement (SPEC) */
    nbep_peak_rss_reset(); /* peak_rss_bytes: this run's, not an earlier run's of a sweep */
    nbep_scene sc;
    nbep_status st = (rq->sweep_run ? nbep_scene_load_run : nbep_scene_load_from)(
        rq->deck_path, rq->overrides, rq->override_origins, rq->n_overrides, rq->stop_signal,
        &sc, d);
    /* a signal while the deck was read and the spheres placed (seconds for millions, which
     * look at it every few thousand spheres and stop there: until 2026-11-30 only once all
     * were placed and checked): stop now, with nothing written (the step loop would only see
     * it after its first step, and a run of 0 steps never) */
    if (st == NBEP_OK && (st = nbep_sim_stop_status(rq->stop_signal)) != NBEP_OK)
        nbep_scene_fini(&sc);
    if (st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
        return not_begun(st, rq, d);
    if (st != NBEP_OK)
        return st;
    char warn[512];
    const char *tc_warning = nbep_scene_tc_warning(&sc, warn, sizeof warn);
    /* --quiet too, as the overlap warning: the results change; a sweep's run, never (its
     * check said it once) */
    if (tc_warning && !rq->sweep_run)
        fprintf(stderr, "%s\n", tc_warning);
    /* a user who meant the study (a new user ran `nbep run` on a study's deck and took its
     * one run for the study, 2026-12-01) */
    if (rq->verbose && !rq->sweep_run && (sc.sweep_n_axes > 0 || sc.sweep_replicas > 1))
        fprintf(stderr,
                "nbep: note: %s has a sweep group, which nbep run leaves aside: this is one run "
                "of the deck's own values (`nbep sweep %s` runs the study)\n",
                rq->deck_path, rq->deck_path);
    /* a neighbour mode asked of naive or seminaive, which find pairs their own way (a new
     * user's review: left aside without a word); a sweep's run, never (its check said it) */
    if (rq->verbose && !rq->sweep_run && nbep_scene_neighbors_aside(&sc))
        fprintf(stderr,
                "nbep: note: run.neighbors = \"%s\" is the predictive algorithm's, which %s "
                "leaves aside (it finds pairs its own way)\n",
                nbep_scene_neighbors_name(&sc), sc.algorithm);
    const double pairs = 0.5 * (double)sc.state.n * ((double)sc.state.n - 1.0);
    if (rq->verbose && !rq->sweep_run && nbep_scene_all_pairs(&sc) &&
        pairs >= ALL_PAIRS_NOTE_PAIRS)
        fprintf(stderr,
                "nbep: note: %s: run.neighbors = \"all\" (the paper's mode, the default) tests "
                "each of its %zu spheres against every other: %.3g pair tests before the first "
                "step, and %zu at each collision; run.neighbors = \"cells\" tests neighbours "
                "only, the fast mode for crowded scenes\n",
                rq->deck_path, sc.state.n, pairs, sc.state.n - 1);
    const int threads = nbep_sim_resolve_threads(sc.threads);
    nbep_output *out = NULL;
    nbep_sim *sim = NULL;
    nbep_resume resume = {0};
    int64_t from = -1; /* the resumed frame's step */
    bool whole = true;  /* the summary counts from step 0 (a resume's file had the totals) */
    bool other_algorithm = false; /* a resume after a part of another algorithm */
    FILE *summary = NULL;
    /* A resumed run appends to the file it continues; output.file does not apply, and one
     * given on the command line (-o, --set) that names another file is refused (until
     * 2026-11-30 it was ignored, exit 0, nothing written where it said) */
    const char *file = rq->resume        ? rq->resume
                       : rq->output_path ? rq->output_path
                                         : sc.output_file;
    /* the file the command line named (a sweep's run names its own: output_path, the file
     * it resumes) */
    const char *named = rq->output_path ? rq->output_path : sc.output_file;
    const char *other = rq->resume && sc.output_file_origin &&
                                !nbep_run_same_path(named, rq->resume)
                            ? sc.output_file_origin
                            : NULL;
    const size_t first_error = d->n_errors;
    st = other ? NBEP_EUSAGE : nbep_run_check_paths(rq->deck_path, file, rq->summary_path, d);
    /* a resume writes the file in place and makes no FILE.partial (a resume of a name of 248
     * to 250 characters was refused for one, for a day) */
    const char *fault = st == NBEP_OK && !rq->resume ? new_output_fault(file) : NULL;
    if (fault) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot create the output file: %s",
                      file, fault);
        st = NBEP_EUSAGE;
    }
    if (other)
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s does not go with --resume: a resumed run appends to %s (drop "
                      "it, or name that file)",
                      other, rq->resume);
    if (st != NBEP_OK) {
        nbep_run_blame_deck_output(&sc, rq->deck_path, file, d, first_error);
        nbep_scene_fini(&sc);
        return st;
    }
    /* the output first: it takes the file's lock, and a run refused there (another writes the
     * file) must not open the summary, whose SUMMARY.partial is the other run's when both
     * name one (a resubmitted job: fopen emptied it, the refusal removed it, and the first
     * run failed at its end, until 2026-12-01) */
    st = rq->resume ? nbep_output_open_resume(file, &sc, &out, &resume, d)
                    : nbep_output_create_staged(file, &sc, threads, &out, d);
    if (st == NBEP_OK &&
        (st = open_summary(rq->summary_path, rq->stop_signal, &summary, d)) != NBEP_OK) {
        nbep_status ignored = nbep_output_close(&out, NULL, d); /* nothing written yet */
        (void)ignored;
        if (st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
            st = not_begun(st, rq, d);
    }
    if (st == NBEP_OK) {
        if (rq->resume)
            nbep_resume_apply(&resume, &sc.state);
        nbep_sim_options opt = {.threads = threads, .out = out,
                                .stop_signal = rq->stop_signal, .progress = rq->verbose,
                                .resume = rq->resume ? &resume : NULL,
                                .take_state = &sc.state, /* nothing reads the scene's again */
                                .t_begin = t_begin};
        st = nbep_sim_create(&sc, &opt, &sim, d);
        /* a signal while the run's memory was made (up to a second for millions of spheres):
         * as during the load, the file not changed yet (it was taken after frame 0) */
        if (st == NBEP_OK && (st = nbep_sim_stop_status(rq->stop_signal)) != NBEP_OK)
            st = not_begun(st, rq, d);
        /* only now is the file changed: a resumed one appended to, a new one put at its path
         * (an older file there survives a deck that sim_create refuses) */
        if (st == NBEP_OK)
            st = rq->resume ? nbep_output_resume_begin(out, &sc, threads, d)
                            : nbep_output_publish(out, d);
        /* --quiet too: a user who looks for the sidecar should learn why there is none (a
         * sweep's runs, never: its check's report gives their sidecars as null); once the
         * file is there (a refused run says only why) */
        if (st == NBEP_OK && !rq->sweep_run && nbep_output_sidecar_unnamed(out)) {
            char *shown = nbep_one_line(file); /* a newline in the name: still one line */
            fprintf(stderr,
                    "nbep: warning: %s: its name is not UTF-8 text free of control characters, "
                    "which the XDMF sidecar (XML) must name it in: no sidecar is written "
                    "(ParaView and VisIt read the run through one; give the output such a name "
                    "for it)\n",
                    shown ? shown : file);
            free(shown);
        }
        if (st == NBEP_OK && rq->resume && rq->verbose && resume.last_step != resume.step)
            fprintf(stderr,
                    "nbep: %s continues from its frame at step %lld, the last at a multiple of "
                    "output.every (run.neighbors = \"cells\" continues bit for bit from those "
                    "only); the frames after it, to step %lld, are dropped\n",
                    file, (long long)resume.step, (long long)resume.last_step);
        else if (st == NBEP_OK && rq->resume && rq->verbose && resume.kept_step != resume.step)
            fprintf(stderr,
                    "nbep: %s continues from its frame at step %lld, which is off output.every's "
                    "grid (a stop's own frame): the next frame written takes its place, and the "
                    "file keeps the frames the uninterrupted run writes\n",
                    file, (long long)resume.step);
        /* a part with another restitution, algorithm, neighbour mode or order than the file's
         * first part: said at the time, not only in the file's `resumed` (a sweep replaces
         * such a file; a hand resume may mean it, as a cooling gas resumed from its melt) */
        const char *changes = st == NBEP_OK && rq->resume ? nbep_output_resume_changes(out) : NULL;
        other_algorithm = st == NBEP_OK && rq->resume && nbep_output_resume_other_algorithm(out);
        if (changes && rq->verbose)
            fprintf(stderr,
                    "nbep: %s continues from step %lld with %s, which its first part did not "
                    "run with (the root attribute `resumed` keeps it: nbep info)\n",
                    file, (long long)resume.step, changes);
        /* (a file made before 2026-11-30, or the frame of a part that kept no such state) */
        if (st == NBEP_OK && rq->resume && resume.step > 0 && !resume.contacts &&
            resume.restitution_kept && nbep_sim_lasting(sim))
            fprintf(stderr,
                    "nbep: warning: %s continues as a predictive run at e < 1 from step %lld, "
                    "whose TC clocks, held spheres and lasting contacts no frame keeps: they "
                    "start afresh, and the frames after it follow the same physics but not the "
                    "uninterrupted run's bits\n",
                    file, (long long)resume.step);
        from = rq->resume ? resume.step : -1;
        whole = !rq->resume || resume.has_totals;
        nbep_resume_fini(&resume); /* the run has its event slots now */
        if (st != NBEP_OK) { /* nothing was simulated: a new file, never published, goes */
            nbep_status ignored = nbep_output_close(&out, NULL, d);
            (void)ignored;
        }
    }
    if (st == NBEP_OK) {
        st = step_and_close(rq, file, sim, from, whole, &out, res, d);
        warn_overlap(&sc, &res->summary, file, other_algorithm);
        nbep_status sst = write_summary(&res->summary, rq->summary_path, summary, d);
        summary = NULL;
        if (st == NBEP_OK)
            st = sst;
    }
    drop_summary(rq->summary_path, summary); /* never simulated: no summary file either */
    if (st != NBEP_OK) /* the file made, or published, as the deck named it */
        nbep_run_blame_deck_output(&sc, rq->deck_path, file, d, first_error);
    nbep_sim_destroy(&sim);
    nbep_resume_fini(&resume);
    nbep_scene_fini(&sc);
    return st;
}
