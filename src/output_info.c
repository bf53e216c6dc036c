/* `nbep info RUN.h5` (output.h): a run's metadata and summary, read with the HDF5 helpers of
 * output_hdf5.c; works on interrupted runs and on runs still being written (the writer takes
 * no lock, and only rows its `count` attributes cover are reported as complete). */
#include <inttypes.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <hdf5.h>

#include "nbep/summary.h"
#include "output_impl.h"


/* Everything `nbep info` prints, gathered before printing so that a bad file prints nothing
 * but its one error line. */
typedef struct run_info {
    char *version, *build_flags, *build_commit, *algorithm, *overrides, *summary;
    char *neighbors, *order; /* predictive's (NULL: another algorithm, or an older file) */
    char *resumed; /* NULL: never resumed */
    uint64_t steps, seed;
    int64_t threads;
    double dt, restitution, gravity[3];
    bool has_tc;                           /* predictive at e < 1, since 2026-12-01 */
    double tc, carry_drop;
    int32_t periodic[3];                   /* 0 0 0 for files made before contract 2 */
    bool has_box;                          /* false too for files made before 2026-11-27 */
    double box_min[3], box_max[3];
    hsize_t spheres, planes;
    uint64_t frames, stats_rows;           /* complete rows: the count attributes */
    hsize_t frames_more, stats_more;       /* rows past them, cut off by a crash */
    bool has_stats;
    int64_t last_step;
    double last_time;
} run_info;

static void run_info_fini(run_info *r)
{
    free(r->version);
    free(r->build_flags);
    free(r->build_commit);
    free(r->algorithm);
    free(r->overrides);
    free(r->summary);
    free(r->resumed);
    free(r->neighbors);
    free(r->order);
}

/* Prints a multi-line value with every line after the first indented under the first; the
 * other control characters in a line escaped (nbep_one_line: a file's text is anyone's, and
 * an escape sequence in it reached the terminal raw until 2026-12-05, a review's find). */
static void print_lines(FILE *f, const char *label, const char *text)
{
    fprintf(f, "%-13s%s", label, text[0] ? "" : "\n");
    for (const char *line = text; *line;) {
        size_t len = strcspn(line, "\n");
        char *raw = strndup(line, len), *shown = raw ? nbep_one_line(raw) : NULL;
        fprintf(f, "%s%s\n", line == text ? "" : "             ", shown ? shown : "?");
        free(shown);
        free(raw);
        line += len + (line[len] == '\n');
    }
}

/* *s, a one-line value of the file's, with its control characters escaped (print_lines);
 * false without memory. */
static bool one_line_in_place(char **s)
{
    if (!*s)
        return true;
    char *shown = nbep_one_line(*s);
    if (!shown)
        return false;
    free(*s);
    *s = shown;
    return true;
}

/* 0 when read (a run file: nbep__output_run_openable said so); -1 after a message. */
static int gather_info(hid_t file, const char *path, run_info *r, nbep_diag *d)
{
    if (nbep__output_read_string_attr(file, path, "version", &r->version, d) < 0 ||
        nbep__output_read_string_attr(file, path, "build_flags", &r->build_flags, d) < 0 ||
        nbep__output_read_string_attr(file, path, "build_commit", &r->build_commit, d) < 0 ||
        nbep__output_read_string_attr(file, path, "algorithm", &r->algorithm, d) < 0 ||
        nbep__output_read_string_attr(file, path, "overrides", &r->overrides, d) < 0 ||
        nbep__output_read_attr(file, path, "steps", H5T_NATIVE_UINT64, &r->steps, d) < 0 ||
        nbep__output_read_attr(file, path, "dt", H5T_NATIVE_DOUBLE, &r->dt, d) < 0 ||
        nbep__output_read_attr(file, path, "threads", H5T_NATIVE_INT64, &r->threads, d) < 0 ||
        nbep__output_read_attr(file, path, "seed", H5T_NATIVE_UINT64, &r->seed, d) < 0 ||
        nbep__output_read_attr(file, path, "restitution", H5T_NATIVE_DOUBLE, &r->restitution,
                               d) < 0 ||
        nbep__output_read_attr(file, path, "gravity", H5T_NATIVE_DOUBLE, r->gravity, d) < 0 ||
        (H5Aexists(file, "periodic") > 0 &&
         nbep__output_read_attr(file, path, "periodic", H5T_NATIVE_INT32, r->periodic, d) < 0) ||
        ((r->has_box = H5Aexists(file, "box_min") > 0) &&
         (nbep__output_read_attr(file, path, "box_min", H5T_NATIVE_DOUBLE, r->box_min, d) < 0 ||
          nbep__output_read_attr(file, path, "box_max", H5T_NATIVE_DOUBLE, r->box_max, d) <
              0)) ||
        (H5Aexists(file, "resumed") > 0 &&
         nbep__output_read_string_attr(file, path, "resumed", &r->resumed, d) < 0) ||
        (H5Aexists(file, "neighbors") > 0 &&
         nbep__output_read_string_attr(file, path, "neighbors", &r->neighbors, d) < 0) ||
        (H5Aexists(file, "order") > 0 &&
         nbep__output_read_string_attr(file, path, "order", &r->order, d) < 0) ||
        ((r->has_tc = H5Aexists(file, "tc") > 0) &&
         (nbep__output_read_attr(file, path, "tc", H5T_NATIVE_DOUBLE, &r->tc, d) < 0 ||
          nbep__output_read_attr(file, path, "carry_drop", H5T_NATIVE_DOUBLE, &r->carry_drop,
                                 d) < 0)) ||
        nbep__output_dataset_rows(file, path, "/spheres/radius", &r->spheres, d) < 0 ||
        nbep__output_dataset_rows(file, path, "/planes/offset", &r->planes, d) < 0 ||
        nbep__output_complete_rows(file, path, "/frames", "/frames/step", &r->frames,
                                   &r->frames_more, d) < 0)
        return -1;
    if (r->frames > 0 &&
        (nbep__output_read_row(file, path, "/frames/step", r->frames - 1, 1, H5T_NATIVE_INT64,
                               &r->last_step, d) < 0 ||
         nbep__output_read_row(file, path, "/frames/time", r->frames - 1, 1, H5T_NATIVE_DOUBLE,
                               &r->last_time, d) < 0))
        return -1;
    htri_t stats = H5Lexists(file, "/stats", H5P_DEFAULT);
    if (stats < 0) {
        HDF5_FAIL(d, path, "look for /stats");
        return -1;
    }
    r->has_stats = stats > 0;
    if (r->has_stats &&
        nbep__output_complete_rows(file, path, "/stats", "/stats/step", &r->stats_rows,
                                   &r->stats_more, d) < 0)
        return -1;
    if (nbep__output_summary_json(file, path, &r->summary, d) < 0)
        return -1;
    return 0;
}

/* How the run ended, by its summary's `status`, and the step it reached of those it was to
 * reach ("interrupted (SIGINT): step 37 of 100"; the summary does not say which of the
 * signals that terminate a run did); unknown where the summary has no status (an
 * nbep before 2026-11-30) or there is no summary. */
static void print_status(FILE *f, const run_info *r)
{
    nbep_summary s;
    if (!r->summary || !nbep_summary_from_json(r->summary, &s)) {
        fprintf(f, "%-13sunknown (%s)\n", "status:",
                r->summary ? "the summary cannot be read"
                           : "no summary: the run was killed, stopped by a write error, or is "
                             "still running");
        return;
    }
    const char *how = s.status == NBEP_SUMMARY_INTERRUPTED  ? " (SIGINT)"
                      : s.status == NBEP_SUMMARY_TERMINATED
                          ? " (SIGTERM, SIGHUP, SIGUSR1 or SIGUSR2)"
                      : s.status == NBEP_SUMMARY_UNKNOWN
                          ? " (the summary is older than its status key)"
                          : "";
    const char *text = nbep_summary_status_text(s.status);
    fprintf(f, "%-13s%s%s: step %" PRIu64 " of %" PRIu64 "\n", "status:", text ? text : "unknown",
            how, s.steps, s.steps_requested.known ? s.steps_requested.value : r->steps);
}

nbep_status nbep_output_info(const char *path, FILE *f, nbep_diag *d)
{
    hid_t file = H5I_INVALID_HID;
    const nbep_status open_st = nbep__output_run_openable(path, R_OK, "open it", &file, d);
    if (open_st != NBEP_OK)
        return open_st;
    run_info r = {0};
    int rc = gather_info(file, path, &r, d);
    /* a file of format nbep-1 without a part every run writes (its attributes, /spheres, the
     * frames' datasets) is no readable nbep run, as a foreign file is: exit 2, as --help says
     * (until 2026-12-01 exit 1, as for a failed write) */
    nbep_status fail = NBEP_EUSAGE;
    if (rc == 0 && !(one_line_in_place(&r.version) && one_line_in_place(&r.build_flags) &&
                     one_line_in_place(&r.build_commit) && one_line_in_place(&r.algorithm) &&
                     one_line_in_place(&r.neighbors) && one_line_in_place(&r.order))) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory to show it", path);
        rc = -1;
        fail = NBEP_ENOMEM;
    }
    if (H5Fclose(file) < 0 && rc == 0) {
        HDF5_FAIL(d, path, "close the file");
        rc = -1;
        fail = NBEP_EIO;
    }
    if (rc == 0) {
        fprintf(f, "%-13s%s\n", "file:", path);
        fprintf(f, "%-13s%s\n", "format:", FORMAT_NAME);
        fprintf(f, "%-13s%s (%s, commit %s)\n", "version:", r.version, r.build_flags,
                r.build_commit);
        if (r.neighbors && r.order)
            fprintf(f, "%-13s%s (neighbors %s, order %s)\n", "algorithm:", r.algorithm,
                    r.neighbors, r.order);
        else
            fprintf(f, "%-13s%s\n", "algorithm:", r.algorithm);
        fprintf(f, "%-13s%llu\n", "spheres:", (unsigned long long)r.spheres);
        fprintf(f, "%-13s%llu\n", "planes:", (unsigned long long)r.planes);
        fprintf(f, "%-13s%" PRIu64 "\n", "steps asked:", r.steps);
        char b0[NBEP_REAL_TEXT_MAX], b1[NBEP_REAL_TEXT_MAX], b2[NBEP_REAL_TEXT_MAX];
        fprintf(f, "%-13s%s\n", "dt:", nbep_format_real(r.dt, false, b0));
        fprintf(f, "%-13s%" PRId64 "\n", "threads:", r.threads);
        fprintf(f, "%-13s%" PRIu64 "\n", "seed:", r.seed);
        fprintf(f, "%-13s%s\n", "restitution:", nbep_format_real(r.restitution, false, b0));
        if (r.has_tc)
            fprintf(f, "%-13stc %s, carry_drop %s\n", "contacts:",
                    nbep_format_real(r.tc, false, b0),
                    nbep_format_real(r.carry_drop, false, b1));
        fprintf(f, "%-13s[%s, %s, %s]\n", "gravity:",
                nbep_format_real(r.gravity[0], false, b0),
                nbep_format_real(r.gravity[1], false, b1),
                nbep_format_real(r.gravity[2], false, b2));
        if (r.has_box) {
            char c0[NBEP_REAL_TEXT_MAX], c1[NBEP_REAL_TEXT_MAX], c2[NBEP_REAL_TEXT_MAX];
            fprintf(f, "%-13s[%s, %s, %s] to [%s, %s, %s]\n", "box:",
                    nbep_format_real(r.box_min[0], false, b0),
                    nbep_format_real(r.box_min[1], false, b1),
                    nbep_format_real(r.box_min[2], false, b2),
                    nbep_format_real(r.box_max[0], false, c0),
                    nbep_format_real(r.box_max[1], false, c1),
                    nbep_format_real(r.box_max[2], false, c2));
        }
        if (r.periodic[0] || r.periodic[1] || r.periodic[2])
            fprintf(f, "%-13s%s%s%s\n", "periodic:", r.periodic[0] ? "x" : "",
                    r.periodic[1] ? "y" : "", r.periodic[2] ? "z" : "");
        if (r.overrides[0])
            print_lines(f, "overrides:", r.overrides);
        if (r.resumed)
            print_lines(f, "resumed:", r.resumed);
        fprintf(f, "%-13s%" PRIu64, "frames:", r.frames);
        if (r.frames > 0)
            fprintf(f, " (last: step %" PRId64 ", time %s)", r.last_step,
                    nbep_format_real(r.last_time, false, b0));
        if (r.frames_more)
            fprintf(f, ", and %llu incomplete (being written, or its write was cut short: a kill, or "
                    "a full disk)",
                    (unsigned long long)r.frames_more);
        fprintf(f, "\n");
        if (r.has_stats)
            fprintf(f, "%-13s%" PRIu64 "%s\n", "stats rows:", r.stats_rows,
                    r.stats_more ? ", and incomplete ones after them" : "");
        else
            fprintf(f, "%-13snone (not recorded)\n", "stats rows:");
        print_status(f, &r);
        if (r.summary)
            print_lines(f, "summary:", r.summary);
        else
            fprintf(f, "%-13snone (run killed, stopped by a write error, or still running)\n",
                    "summary:");
    }
    run_info_fini(&r);
    return rc == 0 ? NBEP_OK : fail;
}

