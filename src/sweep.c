/* `nbep sweep` (sweep.h): the run list, running a share of it, reusing finished runs, the
 * summary table, and the MPI glue. The only file that includes <mpi.h>, and only under
 * NBEP_HAVE_MPI (the Makefile's MPI=1); without it a sweep always runs serially.
 *
 * Invariants:
 * - Every rank builds the same plan from the same deck and command line, so run indices,
 *   overrides and file names agree without communication; the only messages are rank 0's
 *   gather of results and its broadcast of the final status.
 * - A run's file is either complete (its /summary says it completed all its steps, its
 *   overrides are this run's: it is reused), cut short or shorter (resumed from its last
 *   frame), this run complete at more steps (kept: the run fails saying so) or replaced: a
 *   restarted sweep never mixes an old run into a new one, nor throws a longer one away; a
 *   folder holding a run of another deck is refused before any run (runs_of_this_deck).
 * - Runs are independent processes of the simulation library: one run's failure (a deck error
 *   for one combination, a numerical failure) is recorded in its row and the others go on.
 * - MPI calls happen only on the main thread, outside any run's parallel region (the thread
 *   level asked for is MPI_THREAD_FUNNELED).
 * - A rank waiting for the others sleeps between polls (wait_idle): no blocking MPI call, which
 *   would busy-poll a core away from the ranks still running, but MPI_Init and MPI_Finalize
 *   (Open MPI 4 waits in their PMIx fences with usleep; all ranks reach MPI_Finalize at once,
 *   after the last collective). */
#include "nbep/sweep.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include <jansson.h>

#include "build_info.h"
#include "nbep/output_sweep.h"
#include "nbep/output_xdmf.h"
#include "nbep/run.h"
#include "nbep/sim.h"
#include "nbep/summary.h"

#ifdef NBEP_HAVE_MPI
#include <mpi.h>
#endif

/* Run files are named with at least this many digits: run-0007.h5. */
#define RUN_DIGITS_MIN 4

/* The summary's columns in the sweep table: numeric ones (all but algorithm, a text, and
 * status, which has no column: the table's own `status` says how each run ended, runs without
 * a summary too) and, of those, nullable ones (they need a per-row missing flag of their
 * own). */
enum {
    NUMERIC_TEXT = 0, NUMERIC_INT = 1, NUMERIC_UINT = 1, NUMERIC_REAL = 1, NUMERIC_NULLABLE = 1,
    NUMERIC_STATUS = 0, NUMERIC_COUNT = 1,
    NULLABLE_TEXT = 0, NULLABLE_INT = 0, NULLABLE_UINT = 0, NULLABLE_REAL = 0,
    NULLABLE_NULLABLE = 1, NULLABLE_STATUS = 0, NULLABLE_COUNT = 1,
};
#define X_NUMERIC(field, kind) +NUMERIC_##kind
#define X_NULLABLE(field, kind) +NULLABLE_##kind
enum {
    N_SUMMARY_FIELDS = 0 NBEP_SUMMARY_FIELDS(X_NUMERIC),
    N_SUMMARY_NULLABLE = 0 NBEP_SUMMARY_FIELDS(X_NULLABLE),
};
#undef X_NULLABLE
#undef X_NUMERIC
/* The table's own columns besides the axes and the summary's numbers: integers run, replica,
 * seed, rank, exit_code, reused; texts status, file, algorithm (the summary's), error; and the
 * real `seconds`. */
enum { N_FIXED_INT = 6, N_FIXED_TEXT = 4 };

const char *nbep_sweep_outcome_text(nbep_sweep_outcome o)
{
    switch (o) {
#define X_TEXT(name, text)                                                                   \
    case NBEP_SWEEP_##name:                                                                  \
        return text;
        NBEP_SWEEP_OUTCOME_LIST(X_TEXT)
#undef X_TEXT
    }
    return "unknown";
}

/* ---- the plan ---------------------------------------------------------------------------- */

void nbep_sweep_plan_fini(nbep_sweep_plan *p)
{
    if (!p)
        return;
    free(p->deck_path);
    free(p->deck_text);
    for (size_t k = 0; p->base && k < p->n_base; k++) {
        free(p->base[k]);
        free(p->base_origins ? p->base_origins[k] : NULL);
    }
    for (size_t k = 0; p->base_origins && k < p->n_axes; k++)
        free(p->base_origins[p->n_base + k]); /* the axes' labels */
    free(p->base);
    free(p->base_origins);
    for (size_t k = 0; p->axes && k < p->n_axes; k++) {
        free(p->axes[k].key);
        for (size_t v = 0; v < p->axes[k].n_values; v++)
            free(p->axes[k].values[v]);
        free(p->axes[k].values);
    }
    free(p->axes);
    free(p->dir);
    memset(p, 0, sizeof *p);
}

/* "box.h5" -> "box.sweep"; "box.sweep" stays; "box" -> "box.sweep". */
static char *sweep_dir_of(const char *output_file)
{
    size_t len = strlen(output_file);
    while (len > 1 && output_file[len - 1] == '/')
        len--;
    if (len >= 6 && strncmp(output_file + len - 6, ".sweep", 6) == 0)
        return strndup(output_file, len);
    if (len >= 3 && strncmp(output_file + len - 3, ".h5", 3) == 0)
        len -= 3;
    char *dir = malloc(len + sizeof ".sweep");
    if (dir) {
        memcpy(dir, output_file, len);
        memcpy(dir + len, ".sweep", sizeof ".sweep");
    }
    return dir;
}

/* run.steps given as libconfig integer text ("2000", "2000L", "0x7d0"); false if not one. */
static bool parse_steps(const char *text, uint64_t *steps)
{
    char *end;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 0);
    if (end == text || errno || text[0] == '-')
        return false;
    if (*end == 'L')
        end++;
    if (*end != '\0')
        return false;
    *steps = (uint64_t)v;
    return true;
}

/* The plan of scene *scene, loaded from deck_path with the overrides (what was typed for each
 * in origins, may be NULL: nbep_scene_load_from): its axes and deck text move into it (the
 * scene keeps the rest, the caller's to release). */
static nbep_status plan_of_scene(const char *deck_path, const char *const *overrides,
                                 const char *const *origins, size_t n_overrides,
                                 nbep_scene *scene, nbep_sweep_plan *out, nbep_diag *d)
{
    /* "." "..", "/" (or "dir/."): a folder, with no name of its own for OUT.sweep (they
     * made "..sweep", "...sweep" and "/.sweep" until 2026-12-05) */
    const char *out_file = scene->output_file;
    size_t end = strlen(out_file);
    while (end > 0 && out_file[end - 1] == '/')
        end--;
    size_t base = end;
    while (base > 0 && out_file[base - 1] != '/')
        base--;
    if (end == base || (end - base == 1 && out_file[base] == '.') ||
        (end - base == 2 && out_file[base] == '.' && out_file[base + 1] == '.'))
        NBEP_FAIL(d, NBEP_EUSAGE,
                  "nbep: %s: the output %s names a folder, where a study needs a name for its "
                  "own folder NAME.sweep (say -o results, for results.sweep/)",
                  deck_path, out_file);
    nbep_sweep_plan p = {0};
    bool oom = !(p.deck_path = strdup(deck_path)) || !(p.dir = sweep_dir_of(scene->output_file)) ||
               !(p.base = calloc(n_overrides ? n_overrides : 1, sizeof *p.base)) ||
               !(p.base_origins =
                     calloc(n_overrides + scene->sweep_n_axes + 1, sizeof *p.base_origins));
    for (size_t k = 0; !oom && k < n_overrides; k++, p.n_base++)
        oom = !(p.base[k] = strdup(overrides[k])) ||
              (origins && origins[k] && !(p.base_origins[k] = strdup(origins[k])));
    if (oom) {
        nbep_sweep_plan_fini(&p);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory planning the sweep of %s", deck_path);
    }
    p.resumable = scene->out_position && scene->out_velocity;
    /* The scene's axes and deck text move into the plan. */
    p.deck_text = scene->deck_text;
    scene->deck_text = NULL;
    p.axes = scene->sweep_axes;
    p.n_axes = scene->sweep_n_axes;
    scene->sweep_axes = NULL;
    scene->sweep_n_axes = 0;
    /* an axis value a run rejects is named as the deck's axis, not as a --set nobody typed */
    for (size_t k = 0; !oom && k < p.n_axes; k++) {
        const size_t len = strlen(deck_path) + 48;
        char *label = malloc(len);
        if ((oom = !label) == false && p.axes[k].line) /* deck:line:, as every deck error */
            snprintf(label, len, "%s:%u: sweep.vary.[%zu]", deck_path, p.axes[k].line, k);
        else if (label)
            snprintf(label, len, "%s: sweep.vary.[%zu]", deck_path, k);
        p.base_origins[p.n_base + k] = label;
    }
    if (oom) {
        nbep_sweep_plan_fini(&p); /* (the axes and deck text with it) */
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory planning the sweep of %s", deck_path);
    }
    p.replicas = scene->sweep_replicas;
    p.seed = scene->seed;
    p.steps = scene->steps;

    /* at most NBEP_SWEEP_RUNS_MAX runs: the deck check refused more */
    p.n_combos = 1;
    for (size_t k = 0; k < p.n_axes; k++)
        p.n_combos *= p.axes[k].n_values;
    p.n_runs = (size_t)p.replicas * p.n_combos;
    *out = p;
    return NBEP_OK;
}

/* nbep_sweep_plan_create, with what was typed for each override and the signal flag stop
 * (nbep_scene_load_from: a signal while the deck's spheres are placed ends it, NBEP_ESIGINT or
 * NBEP_ESIGTERM without a message). */
static nbep_status plan_create(const char *deck_path, const char *const *overrides,
                               const char *const *origins, size_t n_overrides,
                               const atomic_int *stop, nbep_sweep_plan *out, nbep_diag *d)
{
    nbep_scene sc;
    nbep_status st =
        nbep_scene_load_from(deck_path, overrides, origins, n_overrides, stop, &sc, d);
    if (st != NBEP_OK)
        return st;
    st = plan_of_scene(deck_path, overrides, origins, n_overrides, &sc, out, d);
    nbep_scene_fini(&sc);
    return st;
}

nbep_status nbep_sweep_plan_create(const char *deck_path, const char *const *overrides,
                                   size_t n_overrides, nbep_sweep_plan *out, nbep_diag *d)
{
    return plan_create(deck_path, overrides, NULL, n_overrides, NULL, out, d);
}

uint64_t nbep_sweep_run_replica(const nbep_sweep_plan *p, size_t run)
{
    return run / p->n_combos;
}

uint64_t nbep_sweep_run_seed(const nbep_sweep_plan *p, size_t run)
{
    return p->seed + nbep_sweep_run_replica(p, run);
}

size_t nbep_sweep_run_value(const nbep_sweep_plan *p, size_t run, size_t axis)
{
    /* Row-major: the last axis varies fastest. */
    size_t combo = run % p->n_combos;
    for (size_t k = p->n_axes; k-- > axis + 1;)
        combo /= p->axes[k].n_values;
    return combo % p->axes[axis].n_values;
}

uint64_t nbep_sweep_run_steps(const nbep_sweep_plan *p, size_t run)
{
    uint64_t steps = p->steps;
    for (size_t k = 0; k < p->n_axes; k++)
        if (strcmp(p->axes[k].key, "run.steps") == 0 &&
            !parse_steps(p->axes[k].values[nbep_sweep_run_value(p, run, k)], &steps))
            steps = p->steps; /* checked when planning */
    return steps;
}

void nbep_sweep_overrides_free(char **ov, size_t n)
{
    for (size_t k = 0; ov && k < n; k++)
        free(ov[k]);
    free(ov);
}

nbep_status nbep_sweep_run_overrides(const nbep_sweep_plan *p, size_t run, char ***out,
                                     size_t *n, nbep_diag *d)
{
    size_t total = p->n_base + p->n_axes + 1, k = 0; /* as many as p->base_origins has */
    char **ov = calloc(total, sizeof *ov);
    bool oom = !ov;
    for (size_t i = 0; !oom && i < p->n_base; i++)
        oom = !(ov[k++] = strdup(p->base[i]));
    for (size_t a = 0; !oom && a < p->n_axes; a++) {
        const char *value = p->axes[a].values[nbep_sweep_run_value(p, run, a)];
        size_t len = strlen(p->axes[a].key) + 1 + strlen(value) + 1;
        if ((oom = !(ov[k] = malloc(len))) == false)
            snprintf(ov[k++], len, "%s=%s", p->axes[a].key, value);
    }
    char seed[64];
    snprintf(seed, sizeof seed, "run.seed=%" PRIu64, nbep_sweep_run_seed(p, run));
    if (!oom)
        oom = !(ov[k++] = strdup(seed));
    if (oom) {
        nbep_sweep_overrides_free(ov, total);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory building the overrides of run %zu", run);
    }
    *out = ov;
    *n = total;
    return NBEP_OK;
}

static int run_digits(const nbep_sweep_plan *p)
{
    int digits = 1;
    for (size_t last = p->n_runs ? p->n_runs - 1 : 0; last >= 10; last /= 10)
        digits++;
    return digits < RUN_DIGITS_MIN ? RUN_DIGITS_MIN : digits;
}

char *nbep_sweep_run_path(const nbep_sweep_plan *p, size_t run)
{
    char num[24], zeros[24] = "00000000000000000000";
    int len = snprintf(num, sizeof num, "%zu", run), pad = run_digits(p) - len;
    zeros[pad > 0 ? pad : 0] = '\0';
    size_t size = strlen(p->dir) + strlen(zeros) + strlen(num) + sizeof "/run-.h5";
    char *path = malloc(size);
    if (path)
        snprintf(path, size, "%s/run-%s%s.h5", p->dir, zeros, num);
    return path;
}

/* An axis value for people: a libconfig string loses its quotes (and its \" and \\ escapes);
 * numbers, vectors and lists stay as written. malloc'd. */
static char *display_value(const char *value)
{
    size_t len = strlen(value);
    if (len < 2 || value[0] != '"' || value[len - 1] != '"')
        return strdup(value);
    char *out = malloc(len);
    if (!out)
        return NULL;
    char *w = out;
    for (size_t i = 1; i + 1 < len; i++) {
        if (value[i] == '\\' && (value[i + 1] == '"' || value[i + 1] == '\\') && i + 2 < len)
            i++;
        *w++ = value[i];
    }
    *w = '\0';
    return out;
}

/* "KEY=VALUE KEY=VALUE seed=S" for messages, cut to fit buf. */
static void describe_run(const nbep_sweep_plan *p, size_t run, char *buf, size_t len)
{
    size_t used = 0;
    buf[0] = '\0';
    for (size_t a = 0; a < p->n_axes && used < len; a++) {
        int k = snprintf(buf + used, len - used, "%s=%s ", p->axes[a].key,
                         p->axes[a].values[nbep_sweep_run_value(p, run, a)]);
        used += k > 0 ? (size_t)k : 0;
    }
    if (used < len)
        snprintf(buf + used, len - used, "seed=%" PRIu64, nbep_sweep_run_seed(p, run));
}

/* Whether run.threads is one of the study's axes. */
static bool varies_threads(const nbep_sweep_plan *p)
{
    for (size_t k = 0; k < p->n_axes; k++)
        if (strcmp(p->axes[k].key, "run.threads") == 0)
            return true;
    return false;
}

/* Why run `run` keeps the file at path, which holds it past the steps the study asks
 * (NBEP_SWEEP_FOUND_LONGER; was its summary): complete at more steps, or cut short by a signal
 * after them. One text for the sweep's failed run and for nbep check, which says it before the
 * job. */
static void kept_text(const nbep_sweep_plan *p, size_t run, const char *path,
                      const nbep_summary *was, char *buf, size_t len)
{
    const uint64_t asked = nbep_sweep_run_steps(p, run), have = was->steps;
    if (nbep_summary_ended(was))
        snprintf(buf, len,
                 "%s holds this run complete at %" PRIu64 " steps, more than the %" PRIu64
                 " asked: kept, not run again (-n %" PRIu64 " reuses it; remove the file to run %"
                 PRIu64 " steps)",
                 path, have, asked, have, asked);
    else
        snprintf(buf, len,
                 "%s holds this run cut short at step %" PRIu64 ", past the %" PRIu64
                 " asked: kept, not run again (a larger -n continues it; remove the file to run %"
                 PRIu64 " steps)",
                 path, have, asked, asked);
}

/* ---- checking a study's runs before it runs (nbep check) --------------------------------- */

nbep_status nbep_sweep_check(const char *deck_path, const char *const *overrides,
                             const char *const *origins, size_t n_overrides, nbep_scene *sc,
                             double budget_s, const atomic_int *stop,
                             nbep_sweep_check_report *rep, nbep_diag *d)
{
    memset(rep, 0, sizeof *rep);
    nbep_sweep_plan p;
    nbep_status st = plan_of_scene(deck_path, overrides, origins, n_overrides, sc, &p, d);
    if (st != NBEP_OK)
        return st;
    rep->n_runs = p.n_runs;
    rep->tables_bytes = nbep_sweep_tables_bytes(&p);
    rep->budget_s = budget_s;
    rep->n_combos = p.n_combos;
    rep->replicas = p.replicas;
    snprintf(rep->dir, sizeof rep->dir, "%s", p.dir);
    const double t0 = nbep_now();
    for (size_t run = 0; st == NBEP_OK && run < p.n_runs; run++) {
        if (run > 0 && !(nbep_now() - t0 < budget_s)) {
            rep->out_of_time = true;
            break;
        }
        if (nbep_sim_stop_status(stop) != NBEP_OK)
            break; /* Ctrl-C: the caller says so (it went on for the whole minute, exit 0) */
        char **ov = NULL;
        size_t n_ov = 0;
        st = nbep_sweep_run_overrides(&p, run, &ov, &n_ov, d);
        if (st != NBEP_OK)
            break;
        /* as the run loads it (nbep_run, sweep_run) */
        nbep_diag dr;
        nbep_diag_init(&dr);
        nbep_scene rs;
        const nbep_status rst = nbep_scene_load_run(p.deck_path, (const char *const *)ov,
                                                     (const char *const *)p.base_origins, n_ov,
                                                     stop, &rs, &dr);
        if (rst == NBEP_ESIGINT || rst == NBEP_ESIGTERM) {
            /* Ctrl-C among its spheres (a second or so a million): the caller says so */
            nbep_diag_fini(&dr);
            nbep_sweep_overrides_free(ov, n_ov);
            break;
        }
        rep->checked++;
        if (rst == NBEP_OK) {
            char *path = nbep_sweep_run_path(&p, run); /* the run's file, which its sidecar names */
            /* what the sweep will do with a file already there (a study run before), the one
             * it would fail on (a run complete at more steps: kept) said now, before the job */
            nbep_summary was = {0};
            const nbep_sweep_found found =
                path ? nbep_sweep_run_found(path, ov, n_ov, nbep_sweep_run_steps(&p, run),
                                            varies_threads(&p), &was, NULL, 0)
                     : NBEP_SWEEP_FOUND_NONE;
            rep->files_complete += found == NBEP_SWEEP_FOUND_COMPLETE;
            rep->files_partial += found == NBEP_SWEEP_FOUND_PARTIAL;
            rep->files_other += found == NBEP_SWEEP_FOUND_OTHER;
            rep->files_kept += found == NBEP_SWEEP_FOUND_LONGER;
            if (found == NBEP_SWEEP_FOUND_LONGER && rep->failed++ < NBEP_SWEEP_CHECK_LISTED) {
                char what[256], kept[4096 + 256];
                describe_run(&p, run, what, sizeof what);
                kept_text(&p, run, path, &was, kept, sizeof kept);
                nbep_diag_add(d, __FILE__, __LINE__, "nbep: sweep run %zu (%s) cannot run: %s",
                              run, what, kept);
            }
            rep->output_bytes +=
                nbep_output_bytes(&rs, nbep_sim_keeps_events(&rs), nbep_sim_keeps_contacts(&rs)) +
                nbep_output_sidecar_bytes(&rs, path ? path : rs.output_file);
            free(path);
            rep->memory_max = fmax(rep->memory_max, (double)nbep_sim_memory_estimate(
                                                        &rs, nbep_sim_resolve_threads(rs.threads)));
            char warn[512];
            if (!rep->tc_warning[0] && nbep_scene_tc_warning(&rs, warn, sizeof warn))
                snprintf(rep->tc_warning, sizeof rep->tc_warning, "%s (sweep run %zu)", warn,
                         run);
            nbep_scene_fini(&rs);
        } else if (rst == NBEP_ENOMEM) {
            st = rst;
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: out of memory checking sweep run %zu",
                          run);
        } else if (rep->failed++ < NBEP_SWEEP_CHECK_LISTED) {
            char what[256];
            describe_run(&p, run, what, sizeof what);
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: sweep run %zu (%s) cannot run: %s", run,
                          what, dr.n_errors ? dr.msg[0] : "its deck is refused");
        }
        nbep_diag_fini(&dr);
        nbep_sweep_overrides_free(ov, n_ov);
    }
    if (st == NBEP_OK && rep->failed > NBEP_SWEEP_CHECK_LISTED)
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %zu more sweep runs cannot run",
                      rep->failed - NBEP_SWEEP_CHECK_LISTED);
    nbep_sweep_plan_fini(&p);
    return st != NBEP_OK ? st : rep->failed ? NBEP_EDECK : NBEP_OK;
}

void nbep_sweep_check_print(FILE *f, const nbep_sweep_check_report *r)
{
    fprintf(f, "sweep:           %zu run%s (%llu replica%s x %zu combination%s) into %s/\n",
            r->n_runs, r->n_runs == 1 ? "" : "s", (unsigned long long)r->replicas,
            r->replicas == 1 ? "" : "s", r->n_combos, r->n_combos == 1 ? "" : "s", r->dir);
    char size[NBEP_BYTES_TEXT_MAX];
    if (r->out_of_time)
        fprintf(f,
                "sweep runs:      the first %zu of %zu loaded and placed in %g s (the others "
                "are checked when they run); the largest needs about %s\n",
                r->checked, r->n_runs, r->budget_s, nbep_format_bytes(r->memory_max, size));
    else
        fprintf(f,
                "sweep runs:      all %zu loaded and placed as nbep sweep will; the largest "
                "needs about %s\n",
                r->checked, nbep_format_bytes(r->memory_max, size));
    /* the files there already, by what the sweep does with them (the kinds it finds) */
    const size_t kinds[4] = {r->files_complete, r->files_partial, r->files_other, r->files_kept};
    static const char *const kind_text[4] = {
        "complete (reused)", "cut short or shorter (go on from their last frames)",
        "replaced (other settings, failed or unreadable)",
        "past the steps asked (kept: those runs fail)"};
    const char *sep = "sweep files:     ";
    for (int k = 0; k < 4; k++)
        if (kinds[k]) {
            fprintf(f, "%s%zu %s", sep, kinds[k], kind_text[k]);
            sep = ", ";
        }
    if (sep[0] == ',')
        fprintf(f, "%s\n", r->out_of_time ? " (of the runs loaded)" : "");
    fprintf(f,
            "sweep output:    about %s in all%s (the runs' files and their sidecars, "
            "summary.csv and summary.h5)\n",
            nbep_format_bytes(r->output_bytes + r->tables_bytes, size),
            r->out_of_time ? " for those" : "");
}

/* ---- reusing finished runs --------------------------------------------------------------- */

/* Override ov (len bytes) past the blanks before its name, which --set reads past too
 * (`--set ' sweep.replicas=3'` set the replicas, and until 2026-12-02 was not neutral: every
 * finished run was run again). */
static const char *override_name(const char *ov, size_t *len)
{
    while (*len > 0 && (*ov == ' ' || *ov == '\t')) {
        ov++;
        --*len;
    }
    return ov;
}

/* The value of override ov (len bytes, "name = value") if it sets `name`, else NULL. */
static const char *override_value(const char *ov, size_t len, const char *name)
{
    ov = override_name(ov, &len);
    const size_t n = strlen(name);
    if (len <= n || strncmp(ov, name, n) != 0)
        return NULL;
    const char *q = ov + n;
    while (q < ov + len && (*q == ' ' || *q == '\t'))
        q++;
    return q < ov + len && *q == '=' ? q + 1 : NULL;
}

/* Whether an override changes nothing a run computes: the thread count (SPEC: frames are
 * bitwise identical for any thread count; but see same_overrides), the output file (the sweep
 * names its files) and the study's own settings (sweep.*, or the group whole, `--set
 * sweep={...}` for a deck without one: a run's combination and seed are in its other
 * overrides; README's way to add replicas, --set sweep.replicas=N, re-ran every finished run
 * while it counted, and `sweep=` did until 2026-11-30); and the step count, which says how far
 * a run goes, not how (a run's frames up to a step are the same whatever steps it was asked
 * for: resumed, a shorter run becomes the longer one bit for bit), and which its summary's
 * steps judge (nbep_sweep_run_found: until 2026-12-02 another -n ran every run again from step
 * 0, and runs extended by hand with nbep run --resume -n were replaced). */
static bool override_is_neutral(const char *ov, size_t len)
{
    ov = override_name(ov, &len);
    if (len > 6 && strncmp(ov, "sweep.", 6) == 0)
        return true;
    static const char *const neutral[] = {"output.file", "sweep", "run.threads", "run.steps"};
    for (size_t k = 0; k < sizeof neutral / sizeof neutral[0]; k++)
        if (override_value(ov, len, neutral[k]))
            return true;
    return false;
}

/* The thread count an override list (newline-separated) runs with: the value text of its last
 * run.threads override (the axis's comes after the command line's, and wins), "" for none;
 * its length in *len. */
static const char *threads_of(const char *list, size_t *len)
{
    const char *v = "";
    *len = 0;
    for (const char *p = list; *p;) {
        const size_t l = strcspn(p, "\n");
        const char *x = override_value(p, l, "run.threads");
        if (x) {
            while (*x == ' ')
                x++;
            v = x;
            *len = (size_t)(p + l - x);
        }
        p += l + (p[l] != '\0');
    }
    return v;
}

/* Whether two override lists (newline-separated) are equal but for neutral overrides; and,
 * in a study of thread counts (threads_axis: run.threads an axis, whose rows' timings are its
 * results), with the same thread count (until 2026-12-01 a 2-thread run was reused for the
 * row of 4; the count that runs is compared, so that a --set of run.threads, which the axis
 * overrides, changes nothing). */
static bool same_overrides(const char *a, const char *b, bool threads_axis)
{
    if (threads_axis) {
        size_t na, nb;
        const char *ta = threads_of(a, &na), *tb = threads_of(b, &nb);
        if (na != nb || strncmp(ta, tb, na) != 0)
            return false;
    }
    for (;;) {
        size_t la = strcspn(a, "\n"), lb = strcspn(b, "\n");
        if (la && override_is_neutral(a, la)) {
            a += la + (a[la] != '\0');
            continue;
        }
        if (lb && override_is_neutral(b, lb)) {
            b += lb + (b[lb] != '\0');
            continue;
        }
        if (!*a || !*b)
            return !*a && !*b;
        if (la != lb || strncmp(a, b, la) != 0)
            return false;
        a += la + (a[la] != '\0');
        b += lb + (b[lb] != '\0');
    }
}

static char *join_lines(char *const *lines, size_t n)
{
    size_t len = 1;
    for (size_t k = 0; k < n; k++)
        len += strlen(lines[k]) + 1;
    char *out = malloc(len), *w = out;
    if (!out)
        return NULL;
    *w = '\0';
    for (size_t k = 0; k < n; k++)
        w += sprintf(w, "%s%s", k ? "\n" : "", lines[k]);
    return out;
}

/* Whether a run's summary says it completed all `steps`: status "completed", or no status at
 * all (an nbep before 2026-11-30 wrote none, and all the steps done was complete then). Any
 * other status is run again, even with every step done: a signal during the last step (exit
 * 143, its row said interrupted, and reusing it would turn that into ok), or a failure whose
 * summary counts every step (a close that failed after the summary was written). */
static bool says_completed(const nbep_summary *s, uint64_t steps)
{
    return s->steps == steps && nbep_summary_ended(s);
}

nbep_sweep_found nbep_sweep_run_found(const char *path, char *const *overrides,
                                      size_t n_overrides, uint64_t steps, bool threads_axis,
                                      nbep_summary *sum, char *why, size_t why_len)
{
    struct stat sb;
    if (stat(path, &sb) != 0)
        return NBEP_SWEEP_FOUND_NONE; /* the usual case: not run yet; no HDF5 call, no message */
    nbep_diag d;
    nbep_diag_init(&d);
    char *stored = NULL, *json = NULL, *wanted = join_lines(overrides, n_overrides);
    nbep_summary s = {0}; /* set where read: zeroed for the analysers, which cannot see it */
    /* what is said of a file replaced (a new user took a silent replacement of an earlier
     * study's run for a reuse, 2026-12-01) */
    const char *held = "no run nbep can read";
    nbep_sweep_found found = NBEP_SWEEP_FOUND_OTHER;
    char *resumed = NULL;
    if (wanted && nbep_output_sweep_read_run(path, &stored, &json, &resumed, &d) == NBEP_OK) {
        held = "a run of other settings";
        /* a part resumed by hand with other physics or another way (the root's overrides
         * are the first part's: until 2026-12-02 a run of the study's e = 0.95 continued at
         * the deck's e = 1 was reused as the study's) */
        if (resumed && nbep_output_resumed_changed(resumed))
            held = "a run a resume continued with other settings";
        else if (same_overrides(stored, wanted, threads_axis)) {
            /* no summary: killed outright (kill -9, a node lost), its frames up to then kept */
            const bool read = json && nbep_summary_from_json(json, &s);
            held = json && !read ? "a run whose summary cannot be read" : "a run that failed";
            if (read && says_completed(&s, steps))
                found = NBEP_SWEEP_FOUND_COMPLETE;
            else if (!json || (read && (s.status == NBEP_SUMMARY_INTERRUPTED ||
                                        s.status == NBEP_SUMMARY_TERMINATED)))
                /* cut short, past the steps asked: kept as a longer complete run is */
                found = read && s.steps > steps ? NBEP_SWEEP_FOUND_LONGER
                                                : NBEP_SWEEP_FOUND_PARTIAL;
            else if (read && s.status == NBEP_SUMMARY_COMPLETED && s.steps < steps)
                found = NBEP_SWEEP_FOUND_PARTIAL; /* extended: resumed to the steps asked */
            else if (read && s.status == NBEP_SUMMARY_COMPLETED)
                found = NBEP_SWEEP_FOUND_LONGER; /* kept: run_one says so */
        }
    }
    if (found == NBEP_SWEEP_FOUND_OTHER && why)
        snprintf(why, why_len, "%s", held);
    if ((found == NBEP_SWEEP_FOUND_COMPLETE || found == NBEP_SWEEP_FOUND_LONGER) && sum)
        *sum = s;
    free(stored);
    free(json);
    free(resumed);
    free(wanted);
    nbep_diag_fini(&d);
    return found;
}

bool nbep_sweep_run_complete(const char *path, char *const *overrides, size_t n_overrides,
                             uint64_t steps, nbep_summary *sum)
{
    return nbep_sweep_run_found(path, overrides, n_overrides, steps, false, sum, NULL, 0) ==
           NBEP_SWEEP_FOUND_COMPLETE;
}

/* ---- running ----------------------------------------------------------------------------- */

/* The diag's lines joined by "; " into a fixed buffer (len >= 64). Where they do not fit,
 * their start and their end, with " ... " between, each cut between characters: the end holds
 * the reason ("nbep: PATH: cannot ...: REASON"), and a cut inside a character left the tables
 * invalid UTF-8 (until 2026-12-02: the first 511 bytes, which a long path filled). */
static void error_text(const nbep_diag *d, char *buf, size_t len)
{
    static const char gap[] = " ... ";
    size_t total = 0;
    for (size_t k = 0; k < d->n_errors; k++)
        if (d->msg && d->msg[k])
            total += (total ? 2 : 0) + strlen(d->msg[k]);
    char *all = malloc(total + 1);
    if (!all) {
        snprintf(buf, len, "nbep: out of memory for the run's error");
        return;
    }
    size_t used = 0;
    all[0] = '\0';
    for (size_t k = 0; k < d->n_errors; k++)
        if (d->msg && d->msg[k])
            used += (size_t)sprintf(all + used, "%s%s", used ? "; " : "", d->msg[k]);
    if (used < len) {
        memcpy(buf, all, used + 1);
    } else { /* a continuation byte is 10xxxxxx: no character starts there */
        const size_t room = len - 1 - (sizeof gap - 1);
        size_t head = room / 3, from = used - (room - head);
        while (head > 0 && ((unsigned char)all[head] & 0xC0) == 0x80)
            head--; /* the head ends before the character that would not fit */
        while (from < used && ((unsigned char)all[from] & 0xC0) == 0x80)
            from++; /* the tail starts at a character */
        memcpy(buf, all, head);
        memcpy(buf + head, gap, sizeof gap - 1);
        memcpy(buf + head + sizeof gap - 1, all + from, used - from + 1);
    }
    free(all);
}

static nbep_status stop_status(const nbep_sweep_exec *ex)
{
    return nbep_sim_stop_status(ex->stop_signal);
}

static void run_one(const nbep_sweep_plan *p, size_t run, const nbep_sweep_exec *ex,
                    nbep_sweep_result *res)
{
    const double t0 = nbep_now();
    nbep_diag d;
    nbep_diag_init(&d);
    char **ov = NULL, *path = NULL;
    size_t n_ov = 0;
    bool has_summary = false, reused = false;
    int64_t resumed_from = -1;
    char refused[320] = ""; /* why the file left cut short could not be resumed */
    nbep_status st = nbep_sweep_run_overrides(p, run, &ov, &n_ov, &d);
    if (st == NBEP_OK && !(path = nbep_sweep_run_path(p, run))) {
        nbep_diag_add(&d, __FILE__, __LINE__, "nbep: out of memory naming run %zu", run);
        st = NBEP_ENOMEM;
    }
    char replaced[64] = ""; /* what the file there held, when this run replaces it */
    const nbep_sweep_found found =
        st == NBEP_OK ? nbep_sweep_run_found(path, ov, n_ov, nbep_sweep_run_steps(p, run),
                                             varies_threads(p), &res->summary, replaced,
                                             sizeof replaced)
                      : NBEP_SWEEP_FOUND_NONE; /* replaced: "" unless OTHER */
    if (found == NBEP_SWEEP_FOUND_COMPLETE) {
        has_summary = reused = true;
    } else if (found == NBEP_SWEEP_FOUND_LONGER) {
        /* the same run taken further (complete, or cut short past the steps asked): its
         * steps are the study's work, which a run of fewer would replace (until 2026-12-05 it
         * did, from step 0: a study asked again without the -n it ran with lost every run).
         * Kept; the user says which they want. */
        char kept[4096 + 256];
        kept_text(p, run, path, &res->summary, kept, sizeof kept);
        nbep_diag_add(&d, __FILE__, __LINE__, "nbep: %s", kept);
        memset(&res->summary, 0, sizeof res->summary); /* not this run's: no summary */
        st = NBEP_EUSAGE;
    } else if (st == NBEP_OK) {
        /* as `nbep run` does it, but quiet and into the sweep's file; the command line's
         * overrides named as typed. A run an earlier sweep left cut short (a signal, a job's
         * time limit, a kill) goes on from its last frame, as `nbep run --resume` (its summary
         * the whole run's: /frames/totals); where its file cannot be resumed (damaged, or cut
         * before any step, say), it runs afresh, as every such run did until 2026-11-30. */
        nbep_run_request rq = {.deck_path = p->deck_path,
                               .overrides = (const char *const *)ov,
                               .override_origins = (const char *const *)p->base_origins,
                               .n_overrides = n_ov,
                               .output_path = path,
                               .resume = found == NBEP_SWEEP_FOUND_PARTIAL ? path : NULL,
                               .stop_signal = ex->stop_signal,
                               .sweep_run = true};
        nbep_run_result rr;
        st = nbep_run(&rq, &rr, &d);
        resumed_from = rq.resume && rr.simulated ? rr.resumed_from : -1;
        /* a run file another process holds (an `nbep run --resume` of it, a second sweep
         * of the study's folder on another node) is neither run afresh nor removed: it is
         * that process's (until 2026-12-01 the refused resume ran afresh, was refused again,
         * and the file was removed from under its writer) */
        /* A file the user may not write (chmod 444 to keep it, another user's) is no damage:
         * the run fails, naming why, and the file stays (until 2026-12-05 it was replaced,
         * from step 0, as the folder allowed). */
        if (rq.resume && !rr.simulated && st != NBEP_ESIGINT && st != NBEP_ESIGTERM &&
            st != NBEP_EBUSY && access(path, W_OK) == 0) {
            /* said on its line below, so that a user paying for the run again knows why (a
             * file whose frames lack the velocities, say: until 2026-12-01 nothing said it) */
            error_text(&d, refused, sizeof refused);
            nbep_diag_fini(&d); /* the refusal is no failure of the run: it runs afresh */
            nbep_diag_init(&d);
            rq.resume = NULL;
            st = nbep_run(&rq, &rr, &d);
        }
        has_summary = rr.simulated;
        res->summary = rr.summary;
        /* a stale file of an earlier sweep must not pass for this run (a run cut short that a
         * signal kept from resuming stays for the next sweep: a refused resume changes
         * nothing) */
        if (!has_summary && !rq.resume && st != NBEP_EBUSY) {
            remove(path);
            char *xmf = nbep_xdmf_path(path);
            if (xmf)
                remove(xmf);
            free(xmf);
        }
    }
    res->rank = ex->rank;
    res->reused = reused;
    res->has_summary = has_summary;
    res->exit_code = nbep_status_exit_code(st);
    res->outcome = st == NBEP_OK                                  ? NBEP_SWEEP_OK
                   : st == NBEP_ESIGINT || st == NBEP_ESIGTERM ? NBEP_SWEEP_INTERRUPTED
                                                                  : NBEP_SWEEP_FAILED;
    error_text(&d, res->error, sizeof res->error);
    res->seconds = nbep_now() - t0;

    char what[256];
    describe_run(p, run, what, sizeof what);
    /* the run's own words without their "nbep: " (a deck error has none): the line has it
     * (until 2026-12-01 an I/O error read "failed: nbep: PATH: ...") */
    const char *why = strncmp(res->error, "nbep: ", 6) == 0 ? res->error + 6 : res->error;
    if (res->outcome == NBEP_SWEEP_FAILED)
        fprintf(stderr, "nbep: sweep run %zu (%s) failed: %s\n", run, what, why);
    else if (!ex->quiet && reused)
        fprintf(stderr, "nbep sweep: rank %d: run %zu (of %zu; %s): complete already, reused\n",
                ex->rank, run, p->n_runs, what);
    else if (!ex->quiet) {
        char from[400] = "";
        if (resumed_from >= 0)
            snprintf(from, sizeof from, ", resumed from step %lld", (long long)resumed_from);
        else if (refused[0])
            snprintf(from, sizeof from, ", from step 0: its file could not be resumed (%s)",
                     refused);
        else if (replaced[0])
            snprintf(from, sizeof from, ", from step 0: its file, %s, replaced", replaced);
        fprintf(stderr,
                "nbep sweep: rank %d: run %zu (of %zu; %s): %s in %.3g s (%" PRIu64
                " steps%s, %.4g steps/s)\n",
                ex->rank, run, p->n_runs, what, nbep_sweep_outcome_text(res->outcome),
                res->seconds, res->summary.steps, from, res->summary.steps_per_second);
    }
    nbep_sweep_overrides_free(ov, n_ov);
    free(path);
    nbep_diag_fini(&d);
}

bool nbep_sweep_run_owner(size_t run, int rank, int n_ranks)
{
    const size_t size = n_ranks > 0 ? (size_t)n_ranks : 1, round = run / size, j = run % size;
    return (round % 2 == 0 ? j : size - 1 - j) == (size_t)rank;
}

nbep_status nbep_sweep_execute(const nbep_sweep_plan *p, const nbep_sweep_exec *ex,
                               nbep_sweep_result *results)
{
    for (size_t run = 0; run < p->n_runs; run++) {
        memset(&results[run], 0, sizeof results[run]);
        results[run].run = run;
        results[run].rank = -1;
        results[run].outcome = NBEP_SWEEP_NOT_RUN;
        results[run].exit_code = -1;
    }
    for (size_t run = 0; run < p->n_runs; run++) {
        if (!nbep_sweep_run_owner(run, ex->rank, ex->n_ranks))
            continue;
        nbep_status st = stop_status(ex);
        if (st == NBEP_OK && ex->peer_stop && (st = ex->peer_stop(ex->u)) != NBEP_OK)
            return st; /* another's signal: no new run here either */
        if (st == NBEP_OK) {
            run_one(p, run, ex, &results[run]);
            if (results[run].outcome == NBEP_SWEEP_INTERRUPTED)
                st = stop_status(ex) != NBEP_OK ? stop_status(ex) : NBEP_ESIGTERM;
        }
        if (st != NBEP_OK) {
            if (ex->announce_stop)
                ex->announce_stop(ex->u, st);
            return st;
        }
    }
    const nbep_status st = stop_status(ex);
    if (st != NBEP_OK && ex->announce_stop)
        ex->announce_stop(ex->u, st);
    return st;
}

/* ---- the summary table ------------------------------------------------------------------- */

/* One CSV field (RFC 4180): quoted when it holds a comma, quote or line break. */
static void csv_text(FILE *f, const char *s)
{
    if (!strpbrk(s, ",\"\r\n")) {
        fputs(s, f);
        return;
    }
    fputc('"', f);
    for (; *s; s++) {
        if (*s == '"')
            fputc('"', f);
        fputc(*s, f);
    }
    fputc('"', f);
}

static nbep_status write_csv(const char *path, const nbep_table *t, nbep_diag *d)
{
    char *tmp = nbep_partial_path(path);
    if (!tmp)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: %s: out of memory", path);
    FILE *f = fopen(tmp, "w");
    if (!f) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot write: %s", tmp, strerror(errno));
        free(tmp);
        return NBEP_EIO;
    }
    char real[NBEP_REAL_TEXT_MAX];
    for (size_t k = 0; k < t->n_cols; k++) {
        fputs(k ? "," : "", f);
        csv_text(f, t->cols[k].name);
    }
    fputc('\n', f);
    for (size_t row = 0; row < t->n_rows; row++) {
        for (size_t k = 0; k < t->n_cols; k++) {
            const nbep_table_column *c = &t->cols[k];
            fputs(k ? "," : "", f);
            if (c->missing && c->missing[row])
                continue;
            if (c->kind == NBEP_TABLE_INT)
                fprintf(f, "%" PRId64, c->i[row]);
            else if (c->kind == NBEP_TABLE_REAL)
                fputs(nbep_format_real(c->r[row], false, real), f);
            else
                csv_text(f, c->s[row] ? c->s[row] : "");
        }
        fputc('\n', f);
    }
    int bad = ferror(f);
    bad |= fclose(f) != 0;
    if (bad || rename(tmp, path) != 0) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot write: %s", path,
                      strerror(errno ? errno : EIO));
        remove(tmp);
        free(tmp);
        return NBEP_EIO;
    }
    free(tmp);
    return NBEP_OK;
}

/* The bytes csv_text writes for s. */
static double csv_text_bytes(const char *s)
{
    if (!strpbrk(s, ",\"\r\n"))
        return (double)strlen(s);
    double n = 2.0; /* the quotes around it */
    for (; *s; s++)
        n += *s == '"' ? 2.0 : 1.0;
    return n;
}

/* What a study's tables take, about (nbep_sweep_tables_bytes); measured 2026-11-30 on tables of
 * 2 to 1000 runs of 8 spheres and of 16 runs of 512 (inputs/sweep-restitution.deck), all ok.
 * summary.csv: the header but for the axes' keys is 341 bytes; a row but for its axis values
 * and file name 226 bytes for 8 spheres, 270 for 512 (its seconds and energies at up to 17
 * digits, its counts: 240 taken for all). summary.h5: 3.7 kB of HDF5's headers and the root
 * attributes but for the deck's text; a row's record, 8 bytes a number and 16 a string; each
 * string in HDF5's global heap, 16 bytes and its text rounded up to 8, in collections of 4 kB
 * (20 runs took 14432 bytes, as counted so; 200 runs 8 % more, 1000 runs 1 % more). */
#define TABLE_CSV_HEADER_BYTES 341.0
#define TABLE_CSV_ROW_BYTES 240.0
#define TABLE_H5_BYTES 3.7e3
#define TABLE_H5_HEAP_COLLECTION 4096.0

/* A string's room in summary.h5's global heap. */
static double heap_bytes(double len)
{
    return 16.0 + 8.0 * ceil(len / 8.0);
}

double nbep_sweep_tables_bytes(const nbep_sweep_plan *p)
{
    const double runs = (double)p->n_runs;
    const double numbers = N_FIXED_INT + 1 + N_SUMMARY_FIELDS, texts = N_FIXED_TEXT + p->n_axes;
    char *path = p->n_runs ? nbep_sweep_run_path(p, p->n_runs - 1) : NULL;
    /* every run's name has as many digits as the last run's */
    const double file = path ? csv_text_bytes(path + strlen(p->dir) + 1) : 0.0;
    free(path);
    double csv_row = TABLE_CSV_ROW_BYTES + file;
    /* a row's strings: status "ok", its file, its algorithm ("predictive", the default), no
     * error; then its axis values */
    double heap_row = heap_bytes(2.0) + heap_bytes(file) + heap_bytes(10.0) + heap_bytes(0.0);
    double csv = TABLE_CSV_HEADER_BYTES;
    for (size_t a = 0; a < p->n_axes; a++) {
        const nbep_sweep_axis *x = &p->axes[a];
        csv += 1.0 + csv_text_bytes(x->key);
        double shown_csv = 0.0, shown_heap = 0.0; /* each value takes an equal share of runs */
        for (size_t v = 0; v < x->n_values; v++) {
            char *shown = display_value(x->values[v]);
            const double len = shown ? (double)strlen(shown) : (double)strlen(x->values[v]);
            shown_csv += 1.0 + (shown ? csv_text_bytes(shown) : len);
            shown_heap += heap_bytes(len);
            free(shown);
        }
        if (x->n_values) {
            csv_row += shown_csv / (double)x->n_values;
            heap_row += shown_heap / (double)x->n_values;
        }
    }
    const double heap = TABLE_H5_HEAP_COLLECTION * ceil(runs * heap_row / TABLE_H5_HEAP_COLLECTION);
    const double h5 = TABLE_H5_BYTES + (p->deck_text ? (double)strlen(p->deck_text) : 0.0) +
                      runs * (8.0 * numbers + 16.0 * texts) + fmax(heap, TABLE_H5_HEAP_COLLECTION);
    return csv + runs * csv_row + h5;
}

/* Every array the table's columns point into, owned here. */
typedef struct table_data {
    size_t n_cols;
    nbep_table_column *cols;
    int64_t *ints;        /* n_int_cols x n_rows */
    double *reals;
    const char **texts;   /* n_text_cols x n_rows; entries in `owned` or borrowed */
    char **owned;         /* strings made for the table, n_owned */
    size_t n_owned, cap_owned;
    bool *no_summary;     /* per row: the summary's columns are missing */
} table_data;

static void table_data_fini(table_data *t)
{
    for (size_t k = 0; k < t->n_owned; k++)
        free(t->owned[k]);
    free(t->owned);
    free(t->cols);
    free(t->ints);
    free(t->reals);
    free(t->texts);
    free(t->no_summary);
}

/* Keeps s (malloc'd, may be NULL) for the table's lifetime; false when out of memory. */
static bool keep(table_data *t, char *s, const char **slot)
{
    if (!s)
        return false;
    t->owned[t->n_owned++] = s;
    *slot = s;
    return true;
}

nbep_status nbep_sweep_write_summary(const nbep_sweep_plan *p, const nbep_sweep_result *results,
                                     int n_ranks, double wall_seconds, bool *csv_written,
                                     nbep_diag *d)
{
    bool csv_ok = false;
    const size_t n = p->n_runs;
    const size_t n_int = N_FIXED_INT + N_SUMMARY_FIELDS, n_text = N_FIXED_TEXT + p->n_axes;
    /* per row and nullable summary column: no summary, or null in it */
    bool *null_cells = calloc(N_SUMMARY_NULLABLE * n + 1, sizeof *null_cells);
    table_data t = {0};
    t.n_cols = n_int + n_text + 1;   /* + seconds */
    t.cap_owned = n * (p->n_axes + 1);
    t.cols = calloc(t.n_cols, sizeof *t.cols);
    t.ints = calloc(n_int * n + 1, sizeof *t.ints);
    t.reals = calloc((N_SUMMARY_FIELDS + 1) * n + 1, sizeof *t.reals);
    t.texts = calloc(n_text * n + 1, sizeof *t.texts);
    t.owned = calloc(t.cap_owned + 1, sizeof *t.owned);
    t.no_summary = calloc(n + 1, sizeof *t.no_summary);
    char *csv = malloc(strlen(p->dir) + 32), *h5 = malloc(strlen(p->dir) + 32);
    char *base = join_lines(p->base, p->n_base), *keys = NULL;
    nbep_status st = NBEP_ENOMEM;
    if (!t.cols || !t.ints || !t.reals || !t.texts || !t.owned || !t.no_summary || !csv || !h5 ||
        !base || !null_cells)
        goto oom;
    char **key_list = calloc(p->n_axes + 1, sizeof *key_list);
    if (!key_list)
        goto oom;
    for (size_t a = 0; a < p->n_axes; a++)
        key_list[a] = p->axes[a].key;
    keys = join_lines(key_list, p->n_axes);
    free(key_list);
    if (!keys)
        goto oom;

    /* Column by column, in the documented order; ic, rc, tc: next int, real, text array. */
    size_t col = 0, ic = 0, rc = 0, tc = 0;
#define INT_COL(label, expr, miss)                                                           \
    do {                                                                                     \
        int64_t *v = t.ints + n * ic++;                                                      \
        for (size_t r = 0; r < n; r++) {                                                     \
            const nbep_sweep_result *res = &results[r];                                      \
            (void)res;                                                                       \
            v[r] = (int64_t)(expr);                                                          \
        }                                                                                    \
        t.cols[col++] = (nbep_table_column){.name = (label), .kind = NBEP_TABLE_INT,         \
                                            .i = v, .missing = (miss)};                      \
    } while (0)
#define REAL_COL(label, expr, miss)                                                          \
    do {                                                                                     \
        double *v = t.reals + n * rc++;                                                      \
        for (size_t r = 0; r < n; r++) {                                                     \
            const nbep_sweep_result *res = &results[r];                                      \
            v[r] = (double)(expr);                                                           \
        }                                                                                    \
        t.cols[col++] = (nbep_table_column){.name = (label), .kind = NBEP_TABLE_REAL,        \
                                            .r = v, .missing = (miss)};                      \
    } while (0)
#define TEXT_COL(label, expr, miss)                                                          \
    do {                                                                                     \
        const char **v = t.texts + n * tc++;                                                 \
        for (size_t r = 0; r < n; r++) {                                                     \
            const nbep_sweep_result *res = &results[r];                                      \
            (void)res;                                                                       \
            v[r] = (expr);                                                                   \
        }                                                                                    \
        t.cols[col++] = (nbep_table_column){.name = (label), .kind = NBEP_TABLE_TEXT,        \
                                            .s = v, .missing = (miss)};                      \
    } while (0)

    for (size_t r = 0; r < n; r++)
        t.no_summary[r] = !results[r].has_summary;
    INT_COL("run", r, NULL);
    INT_COL("replica", nbep_sweep_run_replica(p, r), NULL);
    INT_COL("seed", nbep_sweep_run_seed(p, r), NULL);
    INT_COL("rank", res->rank, NULL);
    for (size_t a = 0; a < p->n_axes; a++) {
        const char **v = t.texts + n * tc++;
        for (size_t r = 0; r < n; r++)
            if (!keep(&t, display_value(p->axes[a].values[nbep_sweep_run_value(p, r, a)]),
                      &v[r]))
                goto oom;
        t.cols[col++] = (nbep_table_column){.name = p->axes[a].key, .kind = NBEP_TABLE_TEXT,
                                            .s = v};
    }
    TEXT_COL("status", nbep_sweep_outcome_text((nbep_sweep_outcome)res->outcome), NULL);
    INT_COL("exit_code", res->exit_code, NULL);
    INT_COL("reused", res->reused, NULL);
    REAL_COL("seconds", res->seconds, NULL);
    {
        const char **v = t.texts + n * tc++;
        for (size_t r = 0; r < n; r++) {
            char *path = nbep_sweep_run_path(p, r);
            char *name = path ? strdup(path + strlen(p->dir) + 1) : NULL;
            free(path);
            if (!keep(&t, name, &v[r]))
                goto oom;
        }
        t.cols[col++] = (nbep_table_column){.name = "file", .kind = NBEP_TABLE_TEXT, .s = v,
                                            .missing = t.no_summary};
    }
    bool *null_col = null_cells;
#define X_COL_TEXT(field) TEXT_COL(#field, res->summary.field, t.no_summary)
#define X_COL_INT(field) INT_COL(#field, res->summary.field, t.no_summary)
#define X_COL_UINT(field) X_COL_INT(field)
#define X_COL_REAL(field) REAL_COL(#field, res->summary.field, t.no_summary)
#define X_COL_NULLABLE(field)                                                                \
    do {                                                                                     \
        for (size_t r = 0; r < n; r++)                                                       \
            null_col[r] = !results[r].has_summary || !results[r].summary.field.known;        \
        REAL_COL(#field, res->summary.field.known ? res->summary.field.value : NAN,          \
                 null_col);                                                                  \
        null_col += n;                                                                       \
    } while (0)
#define X_COL_COUNT(field)                                                                   \
    do {                                                                                     \
        for (size_t r = 0; r < n; r++)                                                       \
            null_col[r] = !results[r].has_summary || !results[r].summary.field.known;        \
        INT_COL(#field, res->summary.field.value, null_col);                                 \
        null_col += n;                                                                       \
    } while (0)
#define X_COL_STATUS(field) (void)0 /* the table's `status` column, above */
#define X_COL(field, kind) X_COL_##kind(field);
    NBEP_SUMMARY_FIELDS(X_COL)
#undef X_COL
#undef X_COL_STATUS
#undef X_COL_COUNT
#undef X_COL_NULLABLE
#undef X_COL_REAL
#undef X_COL_UINT
#undef X_COL_INT
#undef X_COL_TEXT
    TEXT_COL("error", res->error, NULL);
#undef TEXT_COL
#undef REAL_COL
#undef INT_COL

    const nbep_table table = {.n_rows = n, .n_cols = col, .cols = t.cols};
    sprintf(csv, "%s/summary.csv", p->dir);
    sprintf(h5, "%s/summary.h5", p->dir);
    const nbep_table_attr attrs[] = {
        {.name = "deck_path", .kind = NBEP_TABLE_TEXT, .s = p->deck_path},
        {.name = "deck", .kind = NBEP_TABLE_TEXT, .s = p->deck_text},
        {.name = "overrides", .kind = NBEP_TABLE_TEXT, .s = base},
        {.name = "axes", .kind = NBEP_TABLE_TEXT, .s = keys},
        {.name = "replicas", .kind = NBEP_TABLE_INT, .i = (int64_t)p->replicas},
        {.name = "runs", .kind = NBEP_TABLE_INT, .i = (int64_t)n},
        {.name = "ranks", .kind = NBEP_TABLE_INT, .i = n_ranks},
        {.name = "wall_seconds", .kind = NBEP_TABLE_REAL, .r = wall_seconds},
        {.name = "build_flags", .kind = NBEP_TABLE_TEXT, .s = NBEP_BUILD_FLAGS},
    };
    st = write_csv(csv, &table, d);
    csv_ok = st == NBEP_OK;
    nbep_status hst = nbep_output_sweep_write(h5, &table, attrs, sizeof attrs / sizeof *attrs, d);
    if (st == NBEP_OK)
        st = hst;
    goto done;
oom:
    nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: out of memory writing the sweep summary",
                  p->dir);
    st = NBEP_ENOMEM;
done:
    if (csv_written)
        *csv_written = csv_ok;
    table_data_fini(&t);
    free(null_cells);
    free(csv);
    free(h5);
    free(base);
    free(keys);
    return st;
}

/* ---- the command ------------------------------------------------------------------------- */

/* What mkdir(p) would do, without making it, for a check (`nbep check` of a study): -1 and
 * errno EEXIST where something is at p, the error of a parent that cannot be written in,
 * else 0; `below` (a folder above p would be made): 0, for the folders below one made are. */
static int mkdir_looked(const char *p, bool below)
{
    if (below)
        return 0;
    struct stat sb;
    /* lstat, as mkdir looks: a link there, even one to nothing, is something at p (mkdir
     * fails with EEXIST and make_dir's stat then says what) */
    if (lstat(p, &sb) == 0) {
        errno = EEXIST;
        return -1;
    }
    if (errno != ENOENT)
        return -1;
    char *parent = nbep_path_dir(p);
    if (!parent) {
        errno = ENOMEM;
        return -1;
    }
    /* mkdir fails as a file made there would (in /proc, ENOENT for root too) */
    const int err = nbep_dir_takes_files(parent);
    free(parent);
    errno = err;
    return err ? -1 : 0;
}

/* mkdir -p: every missing directory on the way. */
/* Makes dir and the folders above it that are missing; *made: how many of its trailing
 * components it made (unmake_dir takes them away again). `look`: makes nothing and says what
 * making it would (*made: how many it would make), a folder already there that cannot be
 * written in failing as its files would. */
static nbep_status make_dir(const char *dir, bool look, int *made, nbep_diag *d)
{
    *made = 0;
    char *p = strdup(dir);
    if (!p)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory");
    nbep_status st = NBEP_OK;
    for (char *s = p + 1;; s++) {
        if (*s != '/' && *s != '\0')
            continue;
        char c = *s;
        *s = '\0';
        struct stat sb;
        const int r = look ? mkdir_looked(p, *made > 0) : mkdir(p, 0777);
        *made += r == 0; /* once one is made, every one below it is */
        if (r != 0 && (errno != EEXIST || stat(p, &sb) != 0 || !S_ISDIR(sb.st_mode))) {
            const int err = errno;
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: cannot make the sweep directory %s: %s",
                          p, err == EEXIST ? "a file is in the way" : strerror(err));
            /* a file in the way, a path not allowed: the command line's (exit 2), as for a
             * run's output path */
            st = err == EEXIST ? NBEP_EUSAGE : nbep_status_of_open(err);
            break;
        }
        *s = c;
        if (c == '\0')
            break;
    }
    int err;
    if (st == NBEP_OK && look && *made == 0 && (err = nbep_dir_takes_files(dir)) != 0) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: cannot write in the sweep directory %s: %s",
                      dir, strerror(err));
        st = nbep_status_of_open(err);
    }
    free(p);
    return st;
}

nbep_status nbep_sweep_check_dir(const char *dir, nbep_diag *d)
{
    int would_make;
    return make_dir(dir, true, &would_make, d);
}

/* Takes away the last `made` components of dir that make_dir made (empty: nothing in them). */
static void unmake_dir(const char *dir, int made)
{
    char *p = strdup(dir);
    for (int k = 0; p && k < made; k++) {
        if (rmdir(p) != 0)
            break;
        char *slash = strrchr(p, '/');
        if (!slash || slash == p)
            break;
        *slash = '\0';
    }
    free(p);
}

/* One study at a time in a folder: a second `nbep sweep` into it (a job resubmitted while the
 * first still runs) resumed the runs the first was writing and rewrote its tables, both ending
 * with exit 0 and "ok" for files of neither (a user's find: /stats rows of zeros, a checkpoint
 * of another run's; the run files are written without HDF5's own locks, so that readers may
 * look while they grow). Rank 0 holds a write lock on DIR/.lock (fcntl, which NFS passes on;
 * the kernel lets it go however the process ends) for the study's life, in *fd. Held by
 * another: NBEP_EUSAGE (exit 2), a line naming it. A lock that cannot be had for another
 * reason (a file system without locks, a folder that takes no new file: the study's own
 * writes fail there anyway) leaves *fd at -1 and the study runs, unguarded. */
static nbep_status lock_dir(const char *dir, int *fd, nbep_diag *d)
{
    *fd = -1;
    const size_t len = strlen(dir) + sizeof "/.lock";
    char *path = malloc(len);
    if (!path)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory");
    snprintf(path, len, "%s/.lock", dir);
    bool busy;
    const int f = nbep_lock_take(path, &busy);
    nbep_status st = NBEP_OK;
    if (busy) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: another nbep sweep is running in this folder (it holds %s); "
                      "wait for it to end, or give this study another output",
                      dir, path);
        st = NBEP_EUSAGE;
    }
    free(path);
    *fd = f;
    return st;
}

/* A --summary that is one of the study's own files (its tables or a run's file) would replace
 * it: the table, or a run the next sweep then runs again (a review's find). NBEP_EUSAGE. Called
 * once the study's folder is there: the two names are compared with their folders resolved
 * (nbep_run_same_path), and a folder not yet made resolves to nothing, so that
 * ./S.sweep/summary.csv or an absolute path passed a fresh study's check and the JSON took the
 * table's place (until 2026-12-01). A run's sidecar and the study's lock are refused before
 * this by their names alone (nbep_run_check_paths: any summary ending in .xmf or .lock; until
 * 2026-12-02 asked here again, where no test could tell, a mutant found). */
static nbep_status summary_not_in_study(const nbep_sweep_plan *p, const char *summary,
                                        nbep_diag *d)
{
    if (!summary || strcmp(summary, "-") == 0)
        return NBEP_OK;
    const char *slash = strrchr(summary, '/');
    const char *base = slash ? slash + 1 : summary;
    const size_t len = strlen(base);
    const bool run_file = strncmp(base, "run-", 4) == 0 && nbep_ends_with(base, ".h5");
    if (!(strcmp(base, "summary.csv") == 0 || strcmp(base, "summary.h5") == 0 || run_file))
        return NBEP_OK;
    /* a study file's name: is it that file of this study? */
    char *own = malloc(strlen(p->dir) + 1 + len + 1);
    if (!own)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory");
    sprintf(own, "%s/%s", p->dir, base);
    const bool ours = nbep_run_same_path(summary, own);
    free(own);
    if (ours)
        NBEP_FAIL(d, NBEP_EUSAGE,
                  "nbep: the summary file %s is one of the study's own files in %s/; choose "
                  "another",
                  summary, p->dir);
    return NBEP_OK;
}

/* Rank 0, before any run: the last sweep's summary.csv and summary.h5 go, so that a sweep
 * killed outright (kill -9, a node lost, mpirun's SIGKILL) leaves no table that the run files
 * contradict: the same command again reuses the finished runs and writes it. */
static nbep_status remove_tables(const nbep_sweep_plan *p, nbep_diag *d)
{
    const char *const tables[] = {"summary.csv", "summary.h5"};
    for (size_t k = 0; k < 2; k++) {
        char *path = malloc(strlen(p->dir) + strlen(tables[k]) + 2);
        if (!path)
            NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory");
        sprintf(path, "%s/%s", p->dir, tables[k]);
        /* a folder by the table's name is the user's: not removed (remove() took an empty one,
         * and a full one gave "Directory not empty", exit 1, until 2026-12-05) */
        struct stat sb;
        if (lstat(path, &sb) == 0 && S_ISDIR(sb.st_mode)) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s is a folder, where the sweep writes its table: move it, or "
                          "give the study another -o",
                          path);
            free(path);
            return NBEP_EUSAGE;
        }
        const int gone = remove(path) == 0 || errno == ENOENT;
        const int err = errno;
        free(path);
        if (!gone) /* a read-only file system, no permission: the user's path (exit 2) */
            NBEP_FAIL(d, nbep_status_of_open(err), "nbep: cannot remove the last sweep's %s/%s: %s",
                      p->dir, tables[k], strerror(err));
    }
    return NBEP_OK;
}

/* Rank 0, before any run: a run file in the study's folder made from another deck (its root
 * attribute `deck` unlike this deck's, nbep_scene_decks_alike: the run.steps, run.threads,
 * output.file and sweep settings aside, which the reuse judges apart) refuses the sweep, exit
 * 2, nothing removed. Until 2026-12-03 only the overrides were compared: two decks sharing an
 * output.file (a copied template) or a deck edited between two jobs took the other's finished
 * runs as their own, the table labelled with the new deck and its rows from the old (an HPC
 * user's review). A file that cannot be read is left to the run, which replaces it. */
static nbep_status runs_of_this_deck(const nbep_sweep_plan *p, nbep_diag *d)
{
    for (size_t run = 0; run < p->n_runs; run++) {
        char *path = nbep_sweep_run_path(p, run), *deck = NULL;
        if (!path)
            NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory naming run %zu", run);
        struct stat sb;
        nbep_diag quiet;
        nbep_diag_init(&quiet);
        const bool other = stat(path, &sb) == 0 &&
                           nbep_output_sweep_read_deck(path, &deck, &quiet) == NBEP_OK &&
                           !nbep_scene_decks_alike(deck, p->deck_text);
        nbep_diag_fini(&quiet);
        free(deck);
        if (other) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s holds a run of another deck (its root attribute `deck` "
                          "differs from %s's beyond run.steps, run.threads, output.file and "
                          "the sweep group): this study would take it as its own; give this "
                          "study a folder of its own (output.file or -o), or remove %s/",
                          path, p->deck_path, p->dir);
            free(path);
            return NBEP_EUSAGE;
        }
        free(path);
    }
    return NBEP_OK;
}

/* A rank other than 0, once rank 0 has made the study's folder: whether it sees the folder.
 * Ranks on nodes that do not share it (a node-local TMPDIR, a relative -o from another
 * working directory) failed each of their runs with "cannot create the output file: No such
 * file or directory" until 2026-12-03 (an HPC user's review); now the sweep stops before any
 * run, this rank saying why in d (its own: each rank prints its messages). */
static nbep_status sees_dir(const nbep_sweep_plan *p, int rank, nbep_diag *d)
{
    struct stat sb;
    if (stat(p->dir, &sb) == 0 && S_ISDIR(sb.st_mode))
        return NBEP_OK;
    const int err = errno;
    char host[256] = "";
    if (gethostname(host, sizeof host) != 0)
        snprintf(host, sizeof host, "?");
    host[sizeof host - 1] = '\0';
    NBEP_FAIL(d, NBEP_EUSAGE,
              "nbep: sweep: rank %d (on %s) cannot see the study's folder %s, which rank 0 made "
              "(%s): every rank must see it, on a file system all the nodes share (output.file "
              "or -o, an absolute path)",
              rank, host, p->dir, S_ISDIR(sb.st_mode) || err ? strerror(err) : "not a folder");
}

/* An integer from the environment, or -1. */
static long env_long(const char *name)
{
    const char *v = getenv(name);
    char *end;
    if (!v || !*v)
        return -1;
    long x = strtol(v, &end, 10);
    return *end == '\0' ? x : -1;
}

/* Whether an MPI launcher started this process, by the variables mpirun (Open MPI), srun
 * (PMI-2, PMIx) and MPICH's Hydra set; NBEP_MPI=0/1 overrides. *many: certainly more than one
 * process. MPI_Init is called only then, so that a plain `nbep sweep` (and the test suite)
 * never starts MPI's runtime. */
static bool launched_by_mpi(bool *many)
{
    long size = env_long("OMPI_COMM_WORLD_SIZE");
    if (size < 0)
        size = env_long("PMI_SIZE");
    long rank = env_long("OMPI_COMM_WORLD_RANK");
    if (rank < 0)
        rank = env_long("PMIX_RANK");
    if (rank < 0)
        rank = env_long("PMI_RANK");
    *many = size > 1 || rank > 0;
    /* srun without a PMI plugin (--mpi=none, a cluster's default): no MPI variables, but each
     * task has its SLURM_PROCID, and the step's task count (a batch script's own shell has no
     * SLURM_STEP_ID); each task would run the whole study into the same files */
    if (env_long("SLURM_PROCID") > 0 ||
        (getenv("SLURM_STEP_ID") && env_long("SLURM_STEP_NUM_TASKS") > 1))
        *many = true;
    long forced = env_long("NBEP_MPI");
    if (forced == 0) /* one study per process, as asked (a task farm: srun -n 4 running a
                      * study of its own in each task) */
        *many = false;
    if (forced == 0 || forced == 1)
        return forced == 1;
    return size >= 0 || rank >= 0;
}

typedef struct sweep_totals {
    size_t ok, failed, interrupted, not_run, reused;
    size_t ended;         /* the runs that ran to their end now: ok and not reused, or failed
                           * after they began to simulate (a run that failed before, a deck
                           * error or a longer run kept, took no time: until 2026-12-05 it
                           * counted, and a study asked again with a smaller -n, each run
                           * failing in a millisecond, claimed 12949 runs a minute) */
    double sim_seconds;   /* setup + stepping of the runs simulated now */
} sweep_totals;

static sweep_totals count(const nbep_sweep_plan *p, const nbep_sweep_result *results)
{
    sweep_totals s = {0};
    for (size_t r = 0; r < p->n_runs; r++) {
        const nbep_sweep_result *x = &results[r];
        s.ok += x->outcome == NBEP_SWEEP_OK;
        s.failed += x->outcome == NBEP_SWEEP_FAILED;
        s.interrupted += x->outcome == NBEP_SWEEP_INTERRUPTED;
        s.not_run += x->outcome == NBEP_SWEEP_NOT_RUN;
        s.reused += x->reused != 0;
        s.ended += (x->outcome == NBEP_SWEEP_OK && !x->reused) ||
                   (x->outcome == NBEP_SWEEP_FAILED && x->has_summary);
        if (x->has_summary && !x->reused)
            s.sim_seconds += x->summary.setup_seconds + x->summary.wall_seconds;
    }
    return s;
}

/* The sweep's pace, in the closing line and the JSON: the runs that ran to their end in this
 * sweep, per minute of its wall time. A reused run did not run, a run cut short by a signal did
 * not end, and one never started did neither: until 2026-11-30 every run of the study counted,
 * so an interrupted sweep (or one continued, its finished runs reused) claimed a pace it never
 * had, runs that never ran included. */
static double runs_per_minute(const sweep_totals *s, double wall)
{
    return wall > 0.0 ? 60.0 * (double)s->ended / wall : 0.0;
}

/* The --summary JSON of the whole sweep. */
static nbep_status write_sweep_json(const char *where, const nbep_sweep_plan *p,
                                    const sweep_totals *s, int n_ranks, double wall,
                                    nbep_diag *d)
{
    /* jansson escapes the folder's name whatever it holds (a quote or a newline made the
     * hand-written text no JSON until 2026-11-30), and the line is written as a run's summary
     * is, whole or not at all (an older file at `where` stays when writing fails) */
    const double n = (double)p->n_runs;
    json_t *o = json_pack(
        "{s:s, s:s, s:o, s:I, s:I, s:I, s:I, s:I, s:I, s:i, s:f, s:f, s:f, s:f}", "format",
        "nbep-sweep-summary-1", "version", NBEP_VERSION, "dir", nbep_summary_json_text(p->dir),
        "runs",
        (json_int_t)p->n_runs, "ok", (json_int_t)s->ok, "failed", (json_int_t)s->failed,
        "interrupted", (json_int_t)s->interrupted, "not_run", (json_int_t)s->not_run, "reused",
        (json_int_t)s->reused, "ranks", n_ranks, "wall_seconds", wall, "runs_per_minute",
        runs_per_minute(s, wall), "sim_seconds", s->sim_seconds, "overhead_seconds_per_run",
        n > 0.0 ? ((double)n_ranks * wall - s->sim_seconds) / n : 0.0);
    char *line = o ? nbep_summary_dump_line(o) : NULL;
    json_decref(o);
    const nbep_status st = nbep_run_write_summary_text(where, line, d);
    free(line);
    return st;
}

/* Rank 0's closing: the summary files, one line about the sweep, the status of the whole. */
static nbep_status finish(const nbep_sweep_plan *p, const nbep_sweep_result *results,
                          nbep_status run_st, const atomic_int *stop_signal, const nbep_cli *cli,
                          int n_ranks, double t0, nbep_diag *d)
{
    bool csv_written;
    nbep_status st = nbep_sweep_write_summary(p, results, n_ranks, nbep_now() - t0,
                                              &csv_written, d);
    const double wall = nbep_now() - t0;
    sweep_totals s = count(p, results);
    /* where the table is: the CSV, which a disk that filled up may have had room for when
     * summary.h5 had none */
    const char *table = !csv_written   ? ""
                        : st == NBEP_OK ? "/summary.csv"
                                        : "/summary.csv (summary.h5 could not be written)";
    if (!cli->quiet) {
        /* three figures, a whole number from 1000 up (8160 runs/min, not 8.16e+03) */
        const double pace = runs_per_minute(&s, wall);
        char pace_text[32];
        snprintf(pace_text, sizeof pace_text, pace >= 999.5 ? "%.0f" : "%.3g", pace);
        fprintf(stderr,
                "nbep sweep: %zu run%s on %d rank%s in %.3g s (%zu ran to %s end: %s "
                "runs/min): %zu ok (%zu reused), %zu failed, %zu interrupted, %zu not run; "
                "%s%s\n",
                p->n_runs, p->n_runs == 1 ? "" : "s", n_ranks, n_ranks == 1 ? "" : "s", wall,
                s.ended,
                s.ended == 1 ? "its" : "their", pace_text, s.ok, s.reused, s.failed,
                s.interrupted, s.not_run, csv_written ? p->dir : "no summary table could be written",
                table);
    }
    if (cli->summary) {
        nbep_status jst = write_sweep_json(cli->summary, p, &s, n_ranks, wall, d);
        if (st == NBEP_OK)
            st = jst;
    }
    char list[256];
    list[0] = '\0';
    if (s.failed) {
        size_t used = 0, shown = 0;
        for (size_t r = 0; r < p->n_runs && used < sizeof list - 8; r++)
            if (results[r].outcome == NBEP_SWEEP_FAILED) {
                int k = snprintf(list + used, sizeof list - used, "%s%zu", shown++ ? ", " : "", r);
                used += k > 0 ? (size_t)k : 0;
            }
        if (shown < s.failed)
            snprintf(list + used, sizeof list - used, ", ...");
    }
    /* One line (SPEC: every error one line): the runs complete, those failed and where their
     * errors are (the table, if it was written; a full disk: only the lines said as each run
     * failed have them), and after a signal what the same command does again. Until 2026-12-01
     * a failure said "the others are complete" whatever the others were (runs interrupted or
     * never run, or none at all), and a signal added a second line. */
    const bool stopped = run_st == NBEP_ESIGINT || run_st == NBEP_ESIGTERM;
    char failed[400] = "";
    if (s.failed)
        snprintf(failed, sizeof failed, "%s%zu failed (run %s; errors %s%s%s)",
                 stopped ? ", " : "", s.failed, list,
                 csv_written ? "in " : "above: no summary table could be written",
                 csv_written ? p->dir : "", csv_written ? "/summary.csv" : "");
    if (stopped) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: sweep %s: %zu of %zu runs complete%s; the same command "
                      "again runs the others, those cut short %s",
                      nbep_status_stop_text(run_st, stop_signal), s.ok, p->n_runs, failed,
                      p->resumable ? "from their last frames"
                                   : "from step 0 (their frames, without positions or "
                                     "velocities, output.fields, cannot be resumed)");
        return run_st;
    }
    if (s.failed)
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: sweep: %zu of %zu runs complete, %s",
                      s.ok, p->n_runs, failed);
    if (st != NBEP_OK)
        return st;
    /* Some runs failed: exit status 1 (status.h has no code of its own for it). */
    return s.failed ? NBEP_EIO : NBEP_OK;
}

#ifdef NBEP_HAVE_MPI
/* Every wait of a rank for the others (the collectives, the stop messages) goes through here, never
 * through a blocking MPI call: Open MPI's blocking calls busy-poll (its one knob,
 * mpi_yield_when_idle, on where mpirun sees a node oversubscribed, only adds sched_yield to the
 * loop: the rank still takes every cycle it is given), so a rank done with its share of the runs
 * burnt a core for as long as the slowest rank ran, one that the busy ranks' OpenMP threads on the
 * node could use. MPI_Testall drives Open MPI's progress (libnbc's schedules included) once per
 * call; between calls the rank sleeps, 20 us at first (collectives that all ranks reach at once end
 * within a few polls), doubling up to 1 ms. 1 ms keeps a waiting rank at 1 to 4 % of a core
 * (measured on a 2-core machine, tests/test_sweep_mpi.sh: a poll with its wake-up costs some tens
 * of microseconds; a blocking collective took 89 %; on a guest that charges each sleep the idle
 * balancing it sets off, 27 to 31 %, where a bare loop of 1 ms nanosleeps took 30 %), and adds
 * at most about 1 ms to a collective per stage of its schedule that waits on a sleeping rank: a
 * sweep makes seven collectives, once, against runs of tenths of a second and more. Longer naps
 * would save little more CPU; shorter ones would cost it for latency nobody sees. */
enum { WAIT_SLEEP_MIN_NS = 20000, WAIT_SLEEP_MAX_NS = 1000000 };

/* wait_idle, calling look(u) (when not NULL) before each nap. */
static void wait_idle_looking(int n, MPI_Request *req, void (*look)(void *), void *u)
{
    long ns = WAIT_SLEEP_MIN_NS;
    for (;;) {
        int done = 0;
        MPI_Testall(n, req, &done, MPI_STATUSES_IGNORE);
        if (done)
            return;
        if (look)
            look(u);
        /* a signal cuts the sleep short (EINTR): the loop only polls sooner */
        const struct timespec nap = {.tv_sec = 0, .tv_nsec = ns};
        nanosleep(&nap, NULL);
        ns = ns * 2 < WAIT_SLEEP_MAX_NS ? ns * 2 : WAIT_SLEEP_MAX_NS;
    }
}

static void wait_idle(int n, MPI_Request *req)
{
    wait_idle_looking(n, req, NULL, NULL);
}

/* MPI_Allreduce of one int over MPI_COMM_WORLD, waited for with wait_idle. */
static int allreduce_int(int mine, MPI_Op op)
{
    int all = 0;
    MPI_Request req;
    MPI_Iallreduce(&mine, &all, 1, MPI_INT, op, MPI_COMM_WORLD, &req);
    wait_idle(1, &req);
    return all;
}

/* Rank 0 receives every rank's results (each rank's runs in its own order) and puts each at
 * its run's index. Byte copies, a result a unit (MPI's counts are ints: counted in bytes, a
 * study of more than 2.9 million runs, which the deck allows, failed here after every run had
 * finished): the ranks of one job run one build on one kind of machine. */
static nbep_status gather(const nbep_sweep_plan *p, int rank, int size,
                          nbep_sweep_result *results, nbep_diag *d)
{
    const size_t rec = sizeof *results;
    nbep_status st = NBEP_OK;
    _Static_assert(NBEP_SWEEP_RUNS_MAX <= INT32_MAX, "a study's runs count in an int");
    MPI_Datatype one = MPI_DATATYPE_NULL;
    if (MPI_Type_contiguous((int)rec, MPI_BYTE, &one) != MPI_SUCCESS ||
        MPI_Type_commit(&one) != MPI_SUCCESS) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: sweep: cannot describe a result to MPI");
        st = NBEP_ENOMEM;
    }
    size_t mine = 0;
    for (size_t r = 0; r < p->n_runs; r++)
        mine += nbep_sweep_run_owner(r, rank, size);
    nbep_sweep_result *send = calloc(mine + 1, rec), *recv = NULL;
    int *counts = NULL, *displs = NULL;
    if (rank == 0) {
        recv = calloc(p->n_runs + 1, rec);
        counts = calloc((size_t)size, sizeof *counts);
        displs = calloc((size_t)size, sizeof *displs);
    }
    int ok = st == NBEP_OK && send && (rank != 0 || (recv && counts && displs));
    if (!allreduce_int(ok, MPI_MIN)) {
        if (st == NBEP_OK)
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: out of memory gathering the sweep");
        st = st == NBEP_OK ? NBEP_ENOMEM : st;
        goto done;
    }
    size_t k = 0;
    for (size_t r = 0; r < p->n_runs; r++)
        if (nbep_sweep_run_owner(r, rank, size))
            send[k++] = results[r];
    if (rank == 0) {
        size_t off = 0;
        for (int q = 0; q < size; q++) {
            size_t n_q = 0;
            for (size_t r = 0; r < p->n_runs; r++)
                n_q += nbep_sweep_run_owner(r, q, size);
            counts[q] = (int)n_q;
            displs[q] = (int)off;
            off += n_q;
        }
    }
    MPI_Request req;
    MPI_Igatherv(send, (int)mine, one, recv, counts, displs, one, 0, MPI_COMM_WORLD, &req);
    wait_idle(1, &req);
    if (rank == 0)
        for (size_t i = 0; i < p->n_runs; i++)
            results[recv[i].run] = recv[i];
done:
    if (one != MPI_DATATYPE_NULL)
        MPI_Type_free(&one);
    free(send);
    free(recv);
    free(counts);
    free(displs);
    return st;
}
#endif

#ifdef NBEP_HAVE_MPI
/* A rank's stop, told to the others (nbep_sweep_exec's peer_stop and announce_stop): one int,
 * the status, to every other rank; each takes what was sent to it before it ends (drain). */
enum { TAG_STOP = 7 };
typedef struct peers {
    int rank, size;
    bool announced;
    int received;              /* stop messages taken so far */
    nbep_status seen;          /* the first peer's status taken */
    MPI_Request *req;          /* the announcement's sends, size entries */
} peers;

static nbep_status peers_stop(void *u)
{
    peers *q = u;
    int flag = 0;
    MPI_Status s;
    /* a few looks: one Iprobe may give MPI's progress engine too little to find a message
     * that has arrived (Open MPI 4 over shared memory missed one sent seconds before) */
    for (int k = 0; k < 64 && !flag; k++)
        MPI_Iprobe(MPI_ANY_SOURCE, TAG_STOP, MPI_COMM_WORLD, &flag, &s);
    if (flag) {
        int v;
        MPI_Recv(&v, 1, MPI_INT, s.MPI_SOURCE, TAG_STOP, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (q->received++ == 0)
            q->seen = (nbep_status)v;
    }
    return q->received ? q->seen : NBEP_OK;
}

static void peers_announce(void *u, nbep_status st)
{
    peers *q = u;
    static int value; /* the sends read it until drained */
    if (q->announced || !q->req)
        return;
    q->announced = true;
    value = (int)st;
    for (int r = 0; r < q->size; r++)
        q->req[r] = MPI_REQUEST_NULL;
    for (int r = 0; r < q->size; r++)
        if (r != q->rank)
            MPI_Isend(&value, 1, MPI_INT, r, TAG_STOP, MPI_COMM_WORLD, &q->req[r]);
}

/* A rank done with its runs, waiting for the others' (peers_drain): a stop signal that
 * reaches it is told to them as one during its runs is, so that they start no other run. */
typedef struct waiting {
    peers *q;
    const atomic_int *stop_signal; /* may be NULL */
    nbep_status st;                /* the signal's status once seen, else NBEP_OK */
} waiting;

static void look_for_signal(void *u)
{
    waiting *w = u;
    if (w->st != NBEP_OK || (w->st = nbep_sim_stop_status(w->stop_signal)) == NBEP_OK)
        return;
    peers_announce(w->q, w->st);
}

/* Every rank, after its runs: waits until every rank has ended its own (a barrier), telling
 * the others of a stop signal that reaches it meanwhile (until 2026-11-29 such a rank ignored
 * it: the others started every run left, and the sweep exited 0); then takes the stop messages
 * still on their way to it (each announcer sent one to every other rank, the late ones before
 * the barrier ended) and completes its own sends. Returns the status of a signal seen while
 * waiting (NBEP_OK: none). */
static nbep_status peers_drain(peers *q, const atomic_int *stop_signal)
{
    waiting w = {.q = q, .stop_signal = stop_signal, .st = NBEP_OK};
    MPI_Request done;
    MPI_Ibarrier(MPI_COMM_WORLD, &done);
    wait_idle_looking(1, &done, look_for_signal, &w);
    const int mine = q->announced, all = allreduce_int(mine, MPI_SUM);
    for (int k = q->received; k < all - mine; k++) {
        int v;
        MPI_Request req;
        MPI_Irecv(&v, 1, MPI_INT, MPI_ANY_SOURCE, TAG_STOP, MPI_COMM_WORLD, &req);
        wait_idle(1, &req);
    }
    if (q->announced && q->req)
        wait_idle(q->size, q->req);
    return w.st;
}
#endif

/* The most serious of the ranks' statuses, agreed by all (identity without MPI). */
static nbep_status agree(nbep_status st, bool mpi)
{
#ifdef NBEP_HAVE_MPI
    if (mpi)
        return (nbep_status)allreduce_int((int)st, MPI_MAX);
#endif
    (void)mpi;
    return st;
}

nbep_status nbep_sweep_main(const nbep_cli *cli, const atomic_int *stop_signal, nbep_diag *d)
{
    double t0 = nbep_now();
    bool many = false;
    const bool mpi = launched_by_mpi(&many);
    int rank = 0, size = 1;
#ifdef NBEP_HAVE_MPI
    if (mpi) {
        int provided;
        MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided);
        MPI_Comm_rank(MPI_COMM_WORLD, &rank);
        MPI_Comm_size(MPI_COMM_WORLD, &size);
        /* The sweep's time starts once MPI's runtime is up (about 0.3 s on a laptop): what
         * it then measures is the sweep's own work, comparable across rank counts. */
        t0 = nbep_now();
    }
#else
    if (many)
        NBEP_FAIL(d, NBEP_EUSAGE,
                  "nbep: this nbep was built without MPI (MPI=0) but was started as one of "
                  "several MPI processes: each would run the whole sweep; rebuild with MPI=1 "
                  "or run `nbep sweep` once");
#endif
    /* Messages of the ranks other than 0 would repeat rank 0's; they keep theirs apart. */
    nbep_diag quiet_diag;
    nbep_diag_init(&quiet_diag);
    nbep_diag *dd = rank == 0 ? d : &quiet_diag;
    nbep_sweep_plan p = {0};
    nbep_sweep_result *results = NULL;
    nbep_status st = plan_create(cli->path, (const char *const *)cli->overrides,
                                 (const char *const *)cli->origins, cli->n_overrides,
                                 stop_signal, &p, dd);
    /* a signal while the deck's spheres were placed for the plan (seconds for millions: until
     * 2026-11-30 it was taken once they were, and the sweep's folder and tables made, before
     * its first run): nothing is made */
    if (st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
        nbep_diag_add(dd, __FILE__, __LINE__,
                      "nbep: sweep %s before its first run; nothing written",
                      nbep_status_stop_text(st, stop_signal));
    if (st == NBEP_OK) /* its JSON would replace the deck, as for nbep run */
        st = nbep_run_check_paths(cli->path, NULL, cli->summary, dd);
    if (st == NBEP_OK && many && size == 1) {
        nbep_diag_add(dd, __FILE__, __LINE__,
                      "nbep: started as one of several processes but MPI sees one: launch "
                      "with mpirun, or srun --mpi=pmix (or pmi2); NBEP_MPI=0 if each process "
                      "runs a study of its own");
        st = NBEP_EUSAGE;
    }
    if (st == NBEP_OK && !(results = calloc(p.n_runs + 1, sizeof *results))) {
        nbep_diag_add(dd, __FILE__, __LINE__, "nbep: out of memory for %zu runs' results",
                      p.n_runs);
        st = NBEP_ENOMEM;
    }
    int made = 0;
    if (st == NBEP_OK && rank == 0)
        st = make_dir(p.dir, false, &made, dd);
    /* after the sweep's folder, which may hold it (-o res/a --summary res/a.sweep/t.json); a
     * path it cannot take leaves nothing made */
    if (st == NBEP_OK && rank == 0 &&
        ((st = summary_not_in_study(&p, cli->summary, dd)) != NBEP_OK ||
         (st = nbep_run_try_summary(cli->summary, dd)) != NBEP_OK))
        unmake_dir(p.dir, made);
    int lock = -1;
    if (st == NBEP_OK && rank == 0)
        st = lock_dir(p.dir, &lock, dd);
    if (st == NBEP_OK && rank == 0)
        st = runs_of_this_deck(&p, dd);
    st = agree(st, mpi); /* the folder made, or not: every rank goes on, or none */
    if (st == NBEP_OK && rank != 0)
        st = sees_dir(&p, rank, d);
    const nbep_status own = st;
    st = agree(st, mpi);
    if (rank == 0 && own == NBEP_OK && st != NBEP_OK) { /* what rank 0 made goes */
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: sweep: another rank cannot run the study (its line says why); "
                      "nothing run");
        if (made) {
            char *at = malloc(strlen(p.dir) + sizeof "/.lock");
            if (at)
                sprintf(at, "%s/.lock", p.dir);
            nbep_lock_drop(lock, at);
            lock = -1;
            free(at);
            unmake_dir(p.dir, made);
        }
    }
    if (st == NBEP_OK && rank == 0)
        st = remove_tables(&p, dd);
    st = agree(st, mpi); /* every rank stops here, or none: the collectives below need all */
    if (st == NBEP_OK) {
        /* a job chain's time limit would start such runs again for ever (also with --quiet,
         * as the run's warnings) */
        if (rank == 0 && !p.resumable)
            fprintf(stderr, "nbep: warning: %s: output.fields lacks \"position\" or "
                            "\"velocity\": a run cut short (a signal, a job's time limit) cannot "
                            "go on from its last frame, and the same command again runs it from "
                            "step 0\n",
                    p.deck_path);
        if (rank == 0 && !cli->quiet)
            fprintf(stderr, "nbep sweep: %s: %zu run%s (%" PRIu64 " replica%s x %zu "
                            "combination%s) on %d rank%s into %s/\n",
                    p.deck_path, p.n_runs, p.n_runs == 1 ? "" : "s", p.replicas,
                    p.replicas == 1 ? "" : "s", p.n_combos,
                    p.n_combos == 1 ? "" : "s", size, size == 1 ? "" : "s", p.dir);
        nbep_sweep_exec ex = {.rank = rank, .n_ranks = size, .stop_signal = stop_signal,
                              .quiet = cli->quiet};
#ifdef NBEP_HAVE_MPI
        peers q = {.rank = rank, .size = size, .seen = NBEP_OK};
        if (mpi && size > 1) {
            q.req = calloc((size_t)size, sizeof *q.req); /* NULL: no announcing, as before */
            ex.peer_stop = peers_stop;
            ex.announce_stop = peers_announce;
            ex.u = &q;
        }
#endif
        nbep_status run_st = nbep_sweep_execute(&p, &ex, results);
#ifdef NBEP_HAVE_MPI
        if (mpi && size > 1) {
            const nbep_status late = peers_drain(&q, stop_signal);
            run_st = run_st == NBEP_OK ? late : run_st;
            free(q.req);
        }
#endif
        run_st = agree(run_st, mpi);
#ifdef NBEP_HAVE_MPI
        if (mpi)
            st = agree(gather(&p, rank, size, results, dd), mpi);
#endif
        if (st == NBEP_OK && rank == 0)
            st = finish(&p, results, run_st, stop_signal, cli, size, t0, dd);
        st = agree(st, mpi);
    }
    nbep_lock_drop(lock, NULL); /* the study is over: another may take the folder */
    free(results);
    nbep_sweep_plan_fini(&p);
    nbep_diag_fini(&quiet_diag);
#ifdef NBEP_HAVE_MPI
    if (mpi)
        MPI_Finalize();
#endif
    return st;
}
