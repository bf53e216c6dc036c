/* nbep's entry point: command line -> scene -> run -> output; maps a status to an exit code.
 * The only file that prints a status, installs signal handlers or calls exit. */
#include <math.h>
#include <assert.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <errno.h>
#include <string.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "build_info.h"
#include "nbep/cli.h"
#include "nbep/output.h"
#include "nbep/scene.h"
#include "nbep/sim.h"
#include "nbep/sweep.h"

/* The one mutable global (STYLE 2): the signal that asked the run to stop, 0 if none. The
 * handler only stores to it; the run polls it at the end of every step. */
static atomic_int stop_signal;
static_assert(ATOMIC_INT_LOCK_FREE == 2, "the signal flag must be lock-free");

static void on_signal(int sig)
{
    atomic_store_explicit(&stop_signal, sig, memory_order_relaxed);
}

static void install_signal_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

static double packing_fraction(const nbep_scene *sc)
{
    if (!sc->has_box)
        return NAN;
    double vol = 1.0, spheres = 0.0;
    vol *= sc->box_max.x - sc->box_min.x;
    vol *= sc->box_max.y - sc->box_min.y;
    vol *= sc->box_max.z - sc->box_min.z;
    for (size_t i = 0; i < sc->state.n; i++)
        spheres += 4.0 / 3.0 * 3.14159265358979323846 * pow(sc->state.radius[i], 3.0);
    return spheres / vol;
}

/* `nbep check`: what the scene needs and nothing more, on stdout. */
static void print_check(const nbep_scene *sc, int threads)
{
    uint64_t quad = 0, quart = 0;
    nbep_scene_count_pairs(&sc->state, &quad, &quart);
    printf("deck:            %s\n", sc->deck_path);
    printf("algorithm:       %s, %d thread%s\n", sc->algorithm, threads, threads == 1 ? "" : "s");
    printf("steps:           %llu of dt = %g (t = 0 .. %g)\n", (unsigned long long)sc->steps,
           sc->dt, (double)sc->steps * sc->dt);
    printf("spheres:         %zu\n", sc->state.n);
    printf("planes:          %zu%s\n", sc->state.n_planes, sc->has_box ? " (6 from the box)" : "");
    printf("pairs:           %llu need a quadratic (equal accelerations), %llu the quartic\n",
           (unsigned long long)quad, (unsigned long long)quart);
    double pf = packing_fraction(sc);
    if (isnan(pf))
        printf("packing:         n/a (no box)\n");
    else
        printf("packing:         %.4g of the box volume\n", pf);
    printf("memory:          about %.3g MB\n", (double)nbep_sim_memory_estimate(sc, threads) / 1e6);
    unsigned long long frames = sc->steps / sc->output_every + 1 +
                                (sc->steps % sc->output_every ? 1 : 0);
    double frame_bytes = (double)sc->state.n * 24.0 * (sc->out_position + sc->out_velocity);
    printf("output:          %s: %llu frames, about %.3g MB\n", sc->output_file, frames,
           (double)frames * frame_bytes / 1e6);
}

static void print_human_summary(const nbep_summary *s, const char *file, nbep_status st)
{
    fprintf(stderr,
            "nbep: %s %llu steps of %llu spheres (%s, %d thread%s) in %.3g s (%.4g steps/s); "
            "%llu collisions; energy drift %.3g; max overlap %.3g; %s\n",
            st == NBEP_OK ? "ran" : "stopped after", (unsigned long long)s->steps,
            (unsigned long long)s->spheres, s->algorithm, s->threads, s->threads == 1 ? "" : "s",
            s->wall_seconds, s->steps_per_second, (unsigned long long)s->collisions,
            s->energy_rel_drift, s->max_overlap_rel, file);
}

/* Opens --summary FILE before anything is simulated, so that an unwritable path fails at once
 * (stdout for "-", NULL when not asked for). */
static nbep_status open_summary(const char *where, FILE **out, nbep_diag *d)
{
    *out = NULL;
    if (!where)
        return NBEP_OK;
    *out = strcmp(where, "-") == 0 ? stdout : fopen(where, "w");
    if (!*out)
        NBEP_FAIL(d, NBEP_EIO, "nbep: cannot write the summary to %s: %s", where,
                  strerror(errno));
    return NBEP_OK;
}

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

static nbep_status cmd_run(const nbep_cli *cli, nbep_diag *d)
{
    nbep_scene sc;
    nbep_status st = nbep_scene_load(cli->path, (const char *const *)cli->overrides,
                                     cli->n_overrides, &sc, d);
    if (st != NBEP_OK)
        return st;
    int threads = nbep_sim_resolve_threads(sc.threads);
    nbep_output *out = NULL;
    nbep_sim *sim = NULL;
    nbep_resume res = {0};
    FILE *summary = NULL;
    /* --resume appends to the run it continues; output.file does not apply. */
    const char *file = cli->resume ? cli->resume : sc.output_file;
    /* Outputs are opened before any simulating: an unwritable path fails at once. */
    st = open_summary(cli->summary, &summary, d);
    if (st == NBEP_OK)
        st = cli->resume ? nbep_output_open_resume(file, &sc, &out, &res, d)
                         : nbep_output_create(file, &sc, threads, &out, d);
    if (st == NBEP_OK) {
        nbep_sim_options opt = {.threads = threads, .out = out, .stop_signal = &stop_signal,
                                .progress = !cli->quiet, .resume = cli->resume ? &res : NULL};
        st = nbep_sim_create(&sc, &opt, &sim, d);
        if (st != NBEP_OK) {
            nbep_status ignored = nbep_output_close(&out, NULL, d);
            (void)ignored;
            if (!cli->resume) /* nothing was simulated: leave nothing behind */
                remove(file);
        }
    }
    if (st == NBEP_OK) {
        st = nbep_sim_run(sim, d);
        nbep_summary sum;
        nbep_sim_summary(sim, &sum);
        /* after a write failure closing fails the same way: keep only the first error */
        nbep_diag quiet;
        nbep_diag_init(&quiet);
        bool io_failed = st == NBEP_EIO || st == NBEP_ENOMEM;
        nbep_status cst = nbep_output_close(&out, io_failed ? NULL : &sum, io_failed ? &quiet : d);
        nbep_diag_fini(&quiet);
        if (st == NBEP_OK || st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
            st = cst == NBEP_OK ? st : cst;
        if (!cli->quiet)
            print_human_summary(&sum, file, st);
        if (st == NBEP_ESIGINT || st == NBEP_ESIGTERM)
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s by SIG%s after step %llu; every frame up to it is in %s",
                          st == NBEP_ESIGINT ? "interrupted" : "terminated",
                          st == NBEP_ESIGINT ? "INT" : "TERM", (unsigned long long)sum.steps,
                          file);
        nbep_status sst = write_summary(&sum, cli->summary, summary, d);
        summary = NULL;
        if (st == NBEP_OK)
            st = sst;
    }
    if (summary && summary != stdout) { /* never simulated: no summary file either */
        fclose(summary);
        remove(cli->summary);
    }
    nbep_sim_destroy(&sim);
    nbep_resume_fini(&res);
    nbep_scene_fini(&sc);
    return st;
}

static nbep_status cmd_check(const nbep_cli *cli, nbep_diag *d)
{
    nbep_scene sc;
    nbep_status st = nbep_scene_load(cli->path, (const char *const *)cli->overrides,
                                     cli->n_overrides, &sc, d);
    if (st != NBEP_OK)
        return st;
    print_check(&sc, nbep_sim_resolve_threads(sc.threads));
    nbep_scene_fini(&sc);
    return NBEP_OK;
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    nbep_output_library_init();
    /* Before anything is read or written: a job's SIGTERM at any moment ends the run at the
     * next step's end with every frame so far saved (or, before stepping, with nothing). */
    install_signal_handlers();
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_cli cli;
    nbep_status st = nbep_cli_parse(argc, argv, &cli, &d);
    if (st == NBEP_OK) {
        switch (cli.cmd) {
        case NBEP_CMD_HELP:
            nbep_cli_print_help(stdout);
            break;
        case NBEP_CMD_HELP_DECK:
            nbep_scene_print_reference(stdout);
            break;
        case NBEP_CMD_VERSION:
            printf("nbep %s (%s, commit %s)\n", NBEP_VERSION, NBEP_BUILD_FLAGS,
                   NBEP_BUILD_COMMIT);
            break;
        case NBEP_CMD_RUN:
            st = cmd_run(&cli, &d);
            break;
        case NBEP_CMD_CHECK:
            st = cmd_check(&cli, &d);
            break;
        case NBEP_CMD_INFO:
            st = nbep_output_info(cli.path, stdout, &d);
            break;
        case NBEP_CMD_SWEEP:
            st = nbep_sweep_main(&cli, &stop_signal, &d);
            break;
        }
    }
    nbep_diag_print(&d, stderr);
    nbep_diag_fini(&d);
    nbep_cli_fini(&cli);
    return nbep_status_exit_code(st);
}
