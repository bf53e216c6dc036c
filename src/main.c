/* nbep's entry point: command line -> command (a run goes through run.h); maps a status to an
 * exit code. The only file that prints a status, installs signal handlers or calls exit. */
#include <math.h>
#include <assert.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "build_info.h"
#include "nbep/cli.h"
#include "nbep/nblist.h"
#include "nbep/output.h"
#include "nbep/run.h"
#include "nbep/scene.h"
#include "nbep/sim.h"
#include "nbep/sweep.h"

/* The one mutable global (STYLE 2): the signal that asked the run to stop, 0 if none. The
 * handler only sets it; the run polls it at the end of every step, and the algorithms' loops
 * also within a step (the predictive's every 65536 events or 1024 rounds, naive's and
 * seminaive's every 65536 pair tests or so, abandoning a step too long to wait for:
 * nbep_sim_run). The first signal wins: a
 * SIGINT then a SIGTERM (a job's Ctrl-C, then its time limit) exits as interrupted, 130,
 * whichever the handlers stored last (a review saw 130 or 143 by the race). */
static atomic_int stop_signal;
static_assert(ATOMIC_INT_LOCK_FREE == 2, "the signal flag must be lock-free");

static void on_signal(int sig)
{
    int none = 0;
    atomic_compare_exchange_strong_explicit(&stop_signal, &none, sig, memory_order_relaxed,
                                            memory_order_relaxed);
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

/* `nbep check`: what the scene needs and nothing more, on stdout. */
static void print_check(const nbep_scene *sc, int threads)
{
    uint64_t quad = 0, quart = 0;
    nbep_scene_count_pairs(&sc->state, &quad, &quart);
    printf("deck:            %s\n", sc->deck_path);
    if (strcmp(sc->algorithm, "predictive") == 0) /* run.neighbors and run.order act there */
        printf("algorithm:       predictive (neighbors %s, order %s), %d thread%s\n",
               nbep_scene_neighbors_name(sc), nbep_scene_order_name(sc), threads,
               threads == 1 ? "" : "s");
    else
        printf("algorithm:       %s, %d thread%s\n", sc->algorithm, threads,
               threads == 1 ? "" : "s");
    char use[256];
    nbep_sim_threads_use(sc, threads, use, sizeof use);
    printf("threads:         %s\n", use);
    printf("steps:           %llu of dt = %g (t = 0 .. %g), seed %llu\n",
           (unsigned long long)sc->steps, sc->dt, (double)sc->steps * sc->dt,
           (unsigned long long)sc->seed);
    printf("physics:         restitution %g, gravity [%g, %g, %g]", sc->restitution,
           sc->gravity.x, sc->gravity.y, sc->gravity.z);
    if (sc->restitution < 1.0) /* the TC model and the carry rule act on dissipative scenes */
        printf(", tc %g, carry_drop %g", sc->tc, sc->carry_drop);
    printf("\n");
    if (sc->has_box)
        printf("box:             [%g, %g, %g] .. [%g, %g, %g]\n", sc->box_min.x, sc->box_min.y,
               sc->box_min.z, sc->box_max.x, sc->box_max.y, sc->box_max.z);
    else
        printf("box:             none\n");
    printf("spheres:         %zu\n", sc->state.n);
    int walls = 2 * (!sc->periodic[0] + !sc->periodic[1] + !sc->periodic[2]);
    if (sc->has_box)
        printf("planes:          %zu (%d from the box)\n", sc->state.n_planes, walls);
    else
        printf("planes:          %zu\n", sc->state.n_planes);
    if (sc->periodic[0] || sc->periodic[1] || sc->periodic[2])
        printf("periodic:        %s%s%s\n", sc->periodic[0] ? "x" : "", sc->periodic[1] ? "y" : "",
               sc->periodic[2] ? "z" : "");
    printf("pairs:           %llu need a quadratic (equal accelerations), %llu the quartic\n",
           (unsigned long long)quad, (unsigned long long)quart);
    double pf = nbep_scene_packing_fraction(sc, &sc->state);
    if (isnan(pf))
        printf("packing:         n/a (no box)\n");
    else
        printf("packing:         %.4g of the box volume\n", pf);
    if (nbep_scene_cells_engine(sc)) {
        const double asked = nbep_scene_list_skin(sc, &sc->state);
        const double taken = nbep_scene_list_skin_taken(sc, &sc->state);
        if (taken < asked)
            printf("lists:           skin %.3g of the largest diameter (%.3g by the packing, cut "
                   "down so that three cells fit across the periodic box)\n",
                   taken, asked);
        else
            printf("lists:           skin %.3g of the largest diameter (when nothing "
                   "accelerates, %g at packing %g or below, %g from %g)\n",
                   taken, NBEP_NBLIST_SKIN_DILUTE, NBEP_NBLIST_PHI_DILUTE, NBEP_NBLIST_SKIN,
                   NBEP_NBLIST_PHI_DENSE);
    }
    printf("memory:          about %.3g MB\n", (double)nbep_sim_memory_estimate(sc, threads) / 1e6);
    printf("output:          %s: %llu frames (every %llu steps), about %.3g MB\n",
           sc->output_file, (unsigned long long)nbep_output_frames(sc),
           (unsigned long long)sc->output_every,
           nbep_output_bytes(sc, nbep_sim_keeps_events(sc)) / 1e6);
}

/* How long `nbep check` spends loading a study's runs (each run's spheres placed: a second or
 * so for a million): a login node's minute at most; the runs past it are checked as they run. */
#define CHECK_SWEEP_SECONDS 60.0

static nbep_status cmd_run(const nbep_cli *cli, nbep_diag *d)
{
    const nbep_run_request rq = {.deck_path = cli->path,
                                 .overrides = (const char *const *)cli->overrides,
                                 .override_origins = (const char *const *)cli->origins,
                                 .n_overrides = cli->n_overrides,
                                 .resume = cli->resume,
                                 .summary_path = cli->summary,
                                 .stop_signal = &stop_signal,
                                 .verbose = !cli->quiet};
    nbep_run_result res;
    return nbep_run(&rq, &res, d);
}

static nbep_status cmd_check(const nbep_cli *cli, nbep_diag *d)
{
    nbep_scene sc;
    nbep_status st = nbep_scene_load_from(cli->path, (const char *const *)cli->overrides,
                                          (const char *const *)cli->origins, cli->n_overrides,
                                          &sc, d);
    if (st != NBEP_OK)
        return st;
    st = nbep_run_check_paths(cli->path, sc.output_file, NULL, d); /* as nbep run would */
    if (st != NBEP_OK) {
        nbep_scene_fini(&sc);
        return st;
    }
    /* a study: every run's scene loaded as nbep sweep will load it, before anything is
     * printed (a run it refuses is a deck error: exit 2, as the deck's own) */
    const bool study = sc.sweep_replicas > 1 || sc.sweep_n_axes > 0;
    nbep_sweep_check_report rep;
    if (study)
        st = nbep_sweep_check(cli->path, (const char *const *)cli->overrides,
                              (const char *const *)cli->origins, cli->n_overrides, &sc,
                              CHECK_SWEEP_SECONDS, &rep, d);
    if (st == NBEP_OK)
        print_check(&sc, nbep_sim_resolve_threads(sc.threads));
    if (st == NBEP_OK && study)
        nbep_sweep_check_print(stdout, &rep);
    nbep_scene_fini(&sc);
    return st;
}

int main(int argc, char **argv)
{
    gsl_set_error_handler_off();
    nbep_output_library_init();
    /* Before anything is read or written: a job's SIGTERM at any moment ends the run at the
     * next step's end with every frame so far saved (or within a long step, after the step
     * before; before stepping, with nothing written). */
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
