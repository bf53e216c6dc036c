/* nbep's entry point: command line -> command (a run goes through run.h); maps a status to an
 * exit code. The only file that prints a status, installs signal handlers or calls exit. */
#include <assert.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <gsl/gsl_errno.h>

#include "build_info.h"
#include "nbep/check.h"
#include "nbep/cli.h"
#include "nbep/output.h"
#include "nbep/run.h"
#include "nbep/scene.h"
#include "nbep/sim.h"
#include "nbep/sweep.h"

/* The one mutable global (STYLE 2): the signal that asked the run to stop, 0 if none. The
 * handler only sets it; the run polls it at the end of every step, and the algorithms' loops
 * also within a step (the predictive's every 65536 events or 1024 rounds, naive's and
 * seminaive's every 65536 pair tests or so, cells mode's rebuilds every 16384 predictions,
 * abandoning a step too long to wait for: nbep_sim_run), and the deck's placement and overlap
 * check every 4096 spheres (nbep_scene_load_from, nothing written). The first signal wins: a
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

/* The signals that stop a run at a step's end with its frames saved. SIGINT (Ctrl-C) and
 * SIGTERM (a job's time limit: SPEC), and three that by default would kill it outright with
 * the step's work lost: SIGHUP (its terminal closed) and SIGUSR1 and SIGUSR2 (the warning a
 * batch system sends before its time limit where so set: Slurm's --signal, LSF's job
 * warning action). Those three are taken as SIGTERM (exit 143, status terminated; the line
 * names the signal: nbep_status_stop_text). */
static const int stop_signals[] = {SIGINT, SIGTERM, SIGHUP, SIGUSR1, SIGUSR2};
#define N_STOP_SIGNALS (sizeof stop_signals / sizeof stop_signals[0])

static void install_signal_handlers(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    /* each stop signal blocked while the handler runs: a second one taken by the same thread
     * waits until the first is stored, so it cannot nest in it and store first */
    sigemptyset(&sa.sa_mask);
    for (size_t k = 0; k < N_STOP_SIGNALS; k++)
        sigaddset(&sa.sa_mask, stop_signals[k]);
    for (size_t k = 0; k < N_STOP_SIGNALS; k++) {
        /* a signal the run was started ignoring stays ignored: `nohup nbep run` must outlive
         * its terminal (SIGINT and SIGTERM are taken whatever, as always) */
        struct sigaction was;
        if (stop_signals[k] != SIGINT && stop_signals[k] != SIGTERM &&
            sigaction(stop_signals[k], NULL, &was) == 0 && was.sa_handler == SIG_IGN)
            continue;
        sigaction(stop_signals[k], &sa, NULL);
    }
    /* SIGPIPE, whose default kills a run that could go on: stderr a pipe whose reader has
     * gone (`nbep run ... 2>&1 | head`). Ignored, the progress line's write fails alone, and
     * a --summary - into it fails the run with its line, exit 1 (until 2026-12-02 the run
     * ended at once, exit 141, no summary, its lock left). SIGXFSZ (a file-size limit) keeps
     * its default: the writer keeps within the limit itself (nbep__output_reserve), and a
     * write past it ends the run before HDF5 records a file end beyond what it could write. */
    struct sigaction ign;
    memset(&ign, 0, sizeof ign);
    ign.sa_handler = SIG_IGN;
    sigemptyset(&ign.sa_mask);
    sigaction(SIGPIPE, &ign, NULL);
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

/* The line of a check stopped by signal st, which writes no report. */
static nbep_status check_stopped(nbep_status st, nbep_diag *d)
{
    NBEP_FAIL(d, st, "nbep: check %s; nothing written", nbep_status_stop_text(st, &stop_signal));
}

static nbep_status cmd_check(const nbep_cli *cli, nbep_diag *d)
{
    nbep_scene sc;
    nbep_status st = nbep_scene_load_from(cli->path, (const char *const *)cli->overrides,
                                          (const char *const *)cli->origins, cli->n_overrides,
                                          &stop_signal, &sc, d);
    if (st == NBEP_ESIGINT || st == NBEP_ESIGTERM) /* one in the placement ends it there */
        return check_stopped(st, d);
    if (st != NBEP_OK)
        return st;
    /* as nbep run would: the run's file, and the report's, against the deck and each other,
     * and (for a single run; a study's goes into a folder of its own) where the run's file
     * goes: nbep run fails at once there (exit 2), and check passed it until 2026-11-30. A
     * study's runs write no output.file (their files are DIR/run-NNNN.h5): its report against
     * the deck alone, as nbep sweep takes its --summary (until 2026-11-30 a report named as
     * output.file was refused as "the run's file itself", which nbep sweep takes) */
    const bool study = sc.sweep_replicas > 1 || sc.sweep_n_axes > 0;
    const size_t first_error = d->n_errors;
    st = nbep_run_check_paths(cli->path, study ? NULL : sc.output_file, cli->summary, d);
    if (st == NBEP_OK && !study)
        st = nbep_run_check_output_dir(sc.output_file, d);
    if (st != NBEP_OK) {
        nbep_run_blame_deck_output(&sc, cli->path, study ? NULL : sc.output_file, d,
                                   first_error);
        nbep_scene_fini(&sc);
        return st;
    }
    /* a study: every run's scene loaded as nbep sweep will load it, before anything is
     * printed (a run it refuses is a deck error: exit 2, as the deck's own) */
    nbep_sweep_check_report rep;
    if (study)
        st = nbep_sweep_check(cli->path, (const char *const *)cli->overrides,
                              (const char *const *)cli->origins, cli->n_overrides, &sc,
                              CHECK_SWEEP_SECONDS, &stop_signal, &rep, d);
    if (st == NBEP_OK && study) /* where its runs go: nbep sweep makes the folder */
        st = nbep_sweep_check_dir(rep.dir, d);
    /* Ctrl-C or a SIGTERM while the deck was read and the spheres placed, or between a study's
     * runs: no report, as a run stopped before its first step writes nothing (until
     * 2026-11-30 the check went on, for a study up to its minute, and exited 0) */
    const nbep_status sig = nbep_sim_stop_status(&stop_signal);
    if (sig != NBEP_OK) {
        nbep_scene_fini(&sc);
        return check_stopped(sig, d);
    }
    if (st == NBEP_OK) {
        nbep_check_facts facts;
        nbep_check_gather(&sc, &facts);
        /* --summary -: stdout is the JSON's alone, and the human report goes to stderr, as a
         * run's end lines do; --quiet leaves the human report out where a JSON is written */
        const bool json_out = cli->summary && strcmp(cli->summary, "-") == 0;
        FILE *human = cli->summary && cli->quiet ? NULL : json_out ? stderr : stdout;
        if (cli->summary) { /* first: a report it cannot write is the check's failure */
            char *line = nbep_check_to_json(&sc, &facts, study ? &rep : NULL);
            st = nbep_run_write_summary_text(cli->summary, line, d);
            free(line);
        }
        if (st == NBEP_OK && human) {
            nbep_check_print(human, &sc, &facts);
            if (study)
                nbep_sweep_check_print(human, &rep);
        }
        if (st == NBEP_OK) {
            /* the deck's own, or a study's first run's (its e or dt may be an axis's); with
             * --quiet too, as the run's overlap warning: it says the results change */
            char warn[512];
            const char *tc_warning = nbep_scene_tc_warning(&sc, warn, sizeof warn);
            if (!tc_warning && study && rep.tc_warning[0])
                tc_warning = rep.tc_warning;
            if (tc_warning)
                fprintf(stderr, "%s\n", tc_warning);
        }
    }
    nbep_scene_fini(&sc);
    return st;
}

/* Standard input, output and error opened on /dev/null where the caller closed them (`2>&-`):
 * the first file nbep opened took descriptor 2, its run's lock, and the progress lines went
 * into it, which later runs then kept as a file of the user's (until 2026-12-04, a review); a
 * data file there would take the error messages. */
static void standard_streams_open(void)
{
    for (int fd = 0; fd <= 2; fd++)
        if (fcntl(fd, F_GETFD) < 0 && errno == EBADF) {
            const int got = open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
            if (got >= 0 && got != fd) /* a lower one was closed too and took it first */
                close(got);
        }
}

int main(int argc, char **argv)
{
    standard_streams_open();
    gsl_set_error_handler_off();
    nbep_memory_init();
    nbep_output_library_init();
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_cli cli;
    nbep_status st = nbep_cli_parse(argc, argv, &cli, &d);
    /* Before the deck or any file is read: a job's SIGTERM at any moment ends the run at the
     * next step's end with every frame so far saved (or within a long step, after the step
     * before; before stepping, with nothing written). Only the commands that look at the flag:
     * --help, --version and info keep the signals' defaults, so a signal ends them at once
     * (until 2026-12-02 taken, it was ignored, or failed a write waiting on a full pipe:
     * "Interrupted system call", exit 1) */
    if (st == NBEP_OK &&
        (cli.cmd == NBEP_CMD_RUN || cli.cmd == NBEP_CMD_CHECK || cli.cmd == NBEP_CMD_SWEEP))
        install_signal_handlers();
    if (st == NBEP_OK) {
        switch (cli.cmd) {
        case NBEP_CMD_HELP:
            nbep_cli_print_help(stdout, cli.help_of);
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
    /* a report that never reached its reader (stdout a full disk, a closed file) is a failure
     * (exit 1): until 2026-12-01 check, info and --help said 0 with their report lost */
    errno = 0;
    if ((fflush(stdout) != 0 || ferror(stdout)) && st == NBEP_OK) {
        nbep_diag_add(&d, __FILE__, __LINE__, "nbep: cannot write to standard output: %s",
                      errno ? strerror(errno) : "write failed");
        st = NBEP_EIO;
    }
    nbep_diag_print(&d, stderr);
    nbep_diag_fini(&d);
    nbep_cli_fini(&cli);
    return nbep_status_exit_code(st);
}
