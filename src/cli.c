/* Command-line parsing. Hand-written rather than getopt_long so that every mistake gets one
 * line naming the option, and so that option overrides become deck overrides in order. */
#include "nbep/cli.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene_impl.h" /* nbep__scene_edit_distance */

static const char HELP[] =
    "nbep - N-Body Event Prediction: colliding spheres and static planes\n"
    "\n"
    "usage:\n"
    "  nbep run DECK [options]     run one simulation\n"
    "  nbep check DECK [options]   validate the deck and print what the scene needs\n"
    "  nbep info RUN.h5            print a run's metadata and summary\n"
    "  nbep sweep DECK [options]   parameter study (the deck's sweep group): replicas x\n"
    "                              values; under mpirun the runs are split across ranks\n"
    "  nbep --help [COMMAND] | --help-deck | --version\n"
    "\n"
    "options of run, check and sweep:\n"
    "  -o, --output FILE      output file (overrides output.file)\n"
    "  -a, --algorithm NAME   naive | seminaive | predictive (overrides run.algorithm)\n"
    "  -t, --threads N        threads; 0 = OMP_NUM_THREADS or all cores (run.threads)\n"
    "  -n, --steps N          time steps (run.steps)\n"
    "      --dt X             time step (run.dt)\n"
    "      --set PATH=VALUE   override any deck setting, repeatable, e.g.\n"
    "                         --set physics.restitution=0.9 --set spheres.[0].count=8192\n"
    "      --summary FILE     write the JSON summary there (- = stdout); check: a JSON\n"
    "                         report of what the run needs (memory_bytes, output.bytes)\n"
    "      --resume RUN.h5    (run) continue RUN.h5 from its last complete frame up to\n"
    "                         run.steps, appending to it; frames and summary equal an\n"
    "                         uninterrupted run's bit for bit, but for its own seconds\n"
    "                         (README, Faults)\n"
    "  -q, --quiet            no progress output (check with --summary: no report)\n"
    "  --                     the end of the options: what follows is the deck\n"
    "a short option's value may follow it attached: -n500, -ofile.h5\n"
    "\n"
    "run writes its output file (HDF5: README, Output) and, for RUN.h5, RUN.xmf beside it,\n"
    "an XDMF sidecar that ParaView and VisIt open; scripts/render.py RUN.h5 draws frames.\n"
    "\n"
    "sweep writes OUTPUT.sweep/run-NNNN.h5 (OUTPUT = output.file or -o without .h5) and\n"
    "summary.csv, summary.h5 there; --summary gets the sweep's totals; run again to finish\n"
    "an interrupted sweep (complete runs are reused, runs cut short or shorter go on from\n"
    "their last frames; a run past the steps asked is kept: its run fails).\n"
    "\n"
    "dense and periodic scenes (a hard-sphere fluid or crystal): run.neighbors = \"cells\"\n"
    "(predictive: an event loop over cell lists, the fastest there), box.periodic =\n"
    "[true, true, true] (no walls; /frames/image unwraps), place = \"fcc\" (packings to\n"
    "0.74); see inputs/hard-sphere-fluid.deck and hard-sphere-crystal.deck, and\n"
    "scripts/hard-sphere.py RUN.h5 --from 2 for pressure, collision rate and diffusion\n"
    "beside theory.\n"
    "\n"
    "exit status: 0 done, 1 run-time failure (I/O, numerical; sweep: some runs failed),\n"
    "2 bad usage or deck, 130/143 interrupted by SIGINT/SIGTERM after saving every frame\n"
    "so far (SIGHUP, SIGUSR1 and SIGUSR2 stop a run as SIGTERM does: 143).\n"
    "nbep --help-deck prints every deck setting with its type, default and meaning;\n"
    "README.md describes the output layout and the algorithms.\n";

/* nbep info --help: info takes no options, so the usage's list of them is not its help (until
 * 2026-12-01 it printed that whole usage, options and all, which info then refused). */
static const char HELP_INFO[] =
    "usage: nbep info RUN.h5\n"
    "\n"
    "prints what a run file holds: its format and the build that wrote it, the scene (algorithm,\n"
    "spheres, planes, steps asked, dt, threads, seed, physics, box), the --set overrides it ran\n"
    "with, the frames complete on disk (the last one's step and time), the stats rows, the run's\n"
    "status and its JSON summary. It reads the file only (a run still being written, or cut\n"
    "short, too: what is complete on disk), and takes no options.\n"
    "\n"
    "exit status: 0 done, 1 what it prints could not be written (a full disk), 2 bad usage\n"
    "or a file that is not a readable nbep run.\n"
    "nbep --help gives the other commands and their options.\n";

void nbep_cli_print_help(FILE *f, nbep_command of)
{
    fputs(of == NBEP_CMD_INFO ? HELP_INFO : HELP, f);
}

void nbep_cli_fini(nbep_cli *cli)
{
    for (size_t i = 0; i < cli->n_overrides; i++) {
        free(cli->overrides[i]);
        free(cli->origins[i]);
    }
    free(cli->overrides);
    free(cli->origins);
    cli->overrides = cli->origins = NULL;
    cli->n_overrides = 0;
}

/* Appends override s with its origin (both taken; s NULL: out of memory; origin NULL for
 * --set). */
static nbep_status push_override(nbep_cli *cli, char *s, char *origin, nbep_diag *d)
{
    char **o = s ? realloc(cli->overrides, (cli->n_overrides + 1) * sizeof *o) : NULL;
    if (o)
        cli->overrides = o;
    char **g = o ? realloc(cli->origins, (cli->n_overrides + 1) * sizeof *g) : NULL;
    if (g)
        cli->origins = g;
    if (!g) {
        free(s);
        free(origin);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: out of memory reading the command line");
    }
    cli->overrides[cli->n_overrides] = s;
    cli->origins[cli->n_overrides++] = origin;
    return NBEP_OK;
}

/* The override of an option that sets a deck path: "path=value", value quoted as a libconfig
 * string where quote. Its origin, for messages, is what was typed: opt ("--steps=abc"), or opt
 * and its value apart ("-n abc") where apart. */
static nbep_status add_override(nbep_cli *cli, const char *path, const char *value, bool quote,
                                const char *opt, bool apart, nbep_diag *d)
{
    size_t len = strlen(path) + 1 + 2 * strlen(value) + 3;
    char *s = malloc(len);
    char *origin = malloc(strlen(opt) + (apart ? 1 + strlen(value) : 0) + 1);
    if (!s || !origin) { /* push_override reports it */
        free(s);
        return push_override(cli, NULL, origin, d);
    }
    if (apart)
        sprintf(origin, "%s %s", opt, value);
    else
        strcpy(origin, opt);
    char *w = s + sprintf(s, "%s=", path);
    if (quote) { /* a libconfig string: escape quotes and backslashes */
        *w++ = '"';
        for (const char *r = value; *r; r++) {
            if (*r == '"' || *r == '\\')
                *w++ = '\\';
            *w++ = *r;
        }
        *w++ = '"';
        *w = '\0';
    } else {
        strcpy(w, value);
    }
    return push_override(cli, s, origin, d);
}

static nbep_status parse_command(const char *word, nbep_command *cmd, nbep_diag *d)
{
    static const struct {
        const char *name;
        nbep_command cmd;
    } table[] = {{"run", NBEP_CMD_RUN},     {"check", NBEP_CMD_CHECK},
                 {"info", NBEP_CMD_INFO},   {"sweep", NBEP_CMD_SWEEP},
                 {"--help", NBEP_CMD_HELP}, {"-h", NBEP_CMD_HELP},
                 {"help", NBEP_CMD_HELP},   {"--version", NBEP_CMD_VERSION},
                 {"--help-deck", NBEP_CMD_HELP_DECK}};
    for (size_t i = 0; i < sizeof table / sizeof table[0]; i++)
        if (strcmp(word, table[i].name) == 0) {
            *cmd = table[i].cmd;
            return NBEP_OK;
        }
    NBEP_FAIL(d, NBEP_EUSAGE, "nbep: unknown command '%s' (try nbep --help)", word);
}

/* The command's one operand: the deck (run, check, sweep) or the run file (info). */
static nbep_status take_operand(nbep_cli *cli, const char *a, nbep_diag *d)
{
    if (cli->path)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: unexpected argument '%s' (one %s only)", a,
                  cli->cmd == NBEP_CMD_INFO ? "run file" : "deck");
    cli->path = a;
    return NBEP_OK;
}

/* Every option, once: the short and long names, and for those that set a deck value the path
 * they override (NULL: none; quote: the value is a string). is_option, the parse and the
 * "did you mean" of an unknown option all read it. */
static const struct cli_option {
    const char *shrt, *lng, *path;
    bool quote;
} OPTIONS[] = {
    {"-o", "--output", "output.file", true},   {"-a", "--algorithm", "run.algorithm", true},
    {"-t", "--threads", "run.threads", false}, {"-n", "--steps", "run.steps", false},
    {NULL, "--dt", "run.dt", false},           {NULL, "--summary", NULL, false},
    {NULL, "--resume", NULL, false},           {NULL, "--set", NULL, false},
    {"-q", "--quiet", NULL, false},            {"-h", "--help", NULL, false},
};
#define N_OPTIONS (sizeof OPTIONS / sizeof OPTIONS[0])

/* Whether a is one of the options (as typed apart, or --name=value): the value an option
 * takes from the next argument is never one. `-n -o x.h5` took -o as the count and was said
 * as "unexpected argument 'x.h5'" (until 2026-12-04, a review). */
static bool is_option(const char *a)
{
    for (size_t i = 0; i < N_OPTIONS; i++) {
        const size_t n = strlen(OPTIONS[i].lng);
        if ((OPTIONS[i].shrt && strcmp(a, OPTIONS[i].shrt) == 0) ||
            (strncmp(a, OPTIONS[i].lng, n) == 0 && (a[n] == '\0' || a[n] == '=')))
            return true;
    }
    return false;
}

/* The value of option name from the argument after it (argv[*k + 1]), *k moved past it: NULL
 * after a line where there is none, or the next argument is another option. */
static const char *value_after(int argc, char **argv, int *k, const char *name, nbep_diag *d)
{
    if (*k + 1 >= argc) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: option %s needs a value", name);
        return NULL;
    }
    if (is_option(argv[*k + 1])) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: option %s needs a value (got the option %s)",
                      name, argv[*k + 1]);
        return NULL;
    }
    return argv[++*k];
}

nbep_status nbep_cli_parse(int argc, char **argv, nbep_cli *cli, nbep_diag *d)
{
    memset(cli, 0, sizeof *cli);
    cli->help_of = NBEP_CMD_HELP;
    if (argc < 2)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: no command given (try nbep --help)");
    nbep_status st = parse_command(argv[1], &cli->cmd, d);
    if (st != NBEP_OK)
        return st;
    /* --version and --help-deck take nothing more (until 2026-11-30 the rest was ignored);
     * --help takes a command's name (below) */
    if ((cli->cmd == NBEP_CMD_VERSION || cli->cmd == NBEP_CMD_HELP_DECK) && argc > 2)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: %s takes no arguments (got '%s')", argv[1], argv[2]);
    /* nbep --help CMD (nbep help run) is CMD's help, as nbep CMD --help; another word, or
     * more, is refused (until 2026-12-05 ignored: `nbep --help extra` printed the usage,
     * exit 0) */
    if (cli->cmd == NBEP_CMD_HELP && argc > 2) {
        nbep_command of = NBEP_CMD_HELP;
        const bool command = argc == 3 && parse_command(argv[2], &of, NULL) == NBEP_OK &&
                             of != NBEP_CMD_HELP && of != NBEP_CMD_VERSION &&
                             of != NBEP_CMD_HELP_DECK;
        if (!command)
            NBEP_FAIL(d, NBEP_EUSAGE,
                      "nbep: %s takes one command (run, check, info or sweep) or nothing (got "
                      "'%s')",
                      argv[1], argv[argc == 3 ? 2 : 3]);
        cli->help_of = of;
        return st;
    }
    if (cli->cmd == NBEP_CMD_HELP || cli->cmd == NBEP_CMD_VERSION ||
        cli->cmd == NBEP_CMD_HELP_DECK)
        return st;
    bool operands = false; /* after `--`: every argument is the deck (run file), as getopt
                            * takes it (a deck named -x.deck: nbep run -- -x.deck) */
    for (int k = 2; k < argc; k++) {
        const char *a = argv[k];
        if (!operands && strcmp(a, "--") == 0) {
            operands = true;
            continue;
        }
        if (operands) {
            st = take_operand(cli, a, d);
            if (st != NBEP_OK)
                return st;
            continue;
        }
        if (strcmp(a, "--quiet") == 0 || strcmp(a, "-q") == 0) {
            cli->quiet = true;
            continue;
        }
        if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
            cli->help_of = cli->cmd;
            cli->cmd = NBEP_CMD_HELP;
            return NBEP_OK;
        }
        const char *name = a, *value = NULL;
        char longname[32];
        /* -n5, -t2, -ofile.h5: a short option with its value attached (getopt's way) */
        for (size_t i = 0; i < N_OPTIONS && !value; i++)
            if (OPTIONS[i].path && OPTIONS[i].shrt && strncmp(a, OPTIONS[i].shrt, 2) == 0 &&
                a[2] != '\0') {
                name = OPTIONS[i].shrt;
                value = a + 2;
            }
        /* --name=value form */
        const char *eq = strncmp(a, "--", 2) == 0 ? strchr(a, '=') : NULL;
        if (eq && (size_t)(eq - a) < sizeof longname) {
            memcpy(longname, a, (size_t)(eq - a));
            longname[eq - a] = '\0';
            name = longname;
            value = eq + 1;
        }
        bool known = false;
        for (size_t i = 0; i < N_OPTIONS && !known; i++) {
            if (OPTIONS[i].path && ((OPTIONS[i].shrt && strcmp(name, OPTIONS[i].shrt) == 0) ||
                                    strcmp(name, OPTIONS[i].lng) == 0)) {
                known = true;
                const bool apart = !value;
                if (!value && !(value = value_after(argc, argv, &k, name, d)))
                    return NBEP_EUSAGE;
                st = add_override(cli, OPTIONS[i].path, value, OPTIONS[i].quote, a, apart, d);
                if (st != NBEP_OK)
                    return st;
            }
        }
        if (known)
            continue;
        const char **slot = strcmp(name, "--summary") == 0  ? &cli->summary
                            : strcmp(name, "--resume") == 0 ? &cli->resume
                            : strcmp(name, "--set") == 0    ? &value
                                                            : NULL;
        if (slot) {
            if (!value && !(value = value_after(argc, argv, &k, name, d)))
                return NBEP_EUSAGE;
            if (strcmp(name, "--set") == 0) {
                const char *e2 = strchr(value, '=');
                if (!e2 || e2 == value)
                    NBEP_FAIL(d, NBEP_EUSAGE,
                              "nbep: --set takes PATH=VALUE, e.g. --set physics.restitution=0.9 "
                              "(got '%s')",
                              value);
                st = push_override(cli, strdup(value), NULL, d);
                if (st != NBEP_OK)
                    return st;
            } else {
                *slot = value;
            }
            continue;
        }
        if (a[0] == '-' && a[1] != '\0') {
            /* the nearest long option, for a slip of a letter or two (--stpes: a new user's,
             * 2026-12-01), as the deck's keys get */
            const char *near = NULL;
            size_t best = 3; /* at most 2 edits, and fewer than the name's own length */
            for (size_t i = 0; i < N_OPTIONS; i++) {
                const size_t dist = nbep__scene_edit_distance(name, OPTIONS[i].lng);
                if (dist < best && dist < strlen(name) - 2) {
                    best = dist;
                    near = OPTIONS[i].lng;
                }
            }
            if (near)
                NBEP_FAIL(d, NBEP_EUSAGE, "nbep: unknown option '%s' (did you mean %s? nbep "
                          "--help lists them)", a, near);
            NBEP_FAIL(d, NBEP_EUSAGE, "nbep: unknown option '%s' (try nbep --help)", a);
        }
        st = take_operand(cli, a, d);
        if (st != NBEP_OK)
            return st;
    }
    if (!cli->path)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: %s needs a %s (try nbep --help)", argv[1],
                  cli->cmd == NBEP_CMD_INFO ? "run file (RUN.h5)" : "deck file");
    /* --quiet too: info prints only what was asked for, and README says it takes no options
     * (it was taken and did nothing until 2026-12-04, where -t 3 was refused) */
    if (cli->cmd == NBEP_CMD_INFO &&
        (cli->n_overrides || cli->summary || cli->resume || cli->quiet))
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: info takes only a run file");
    if (cli->resume && cli->cmd != NBEP_CMD_RUN)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: --resume goes with run only");
    return NBEP_OK;
}
