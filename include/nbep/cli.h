/* The command line: `nbep run|check|sweep DECK [options]`, `nbep info RUN.h5`, --help,
 * --version. Options that override deck settings become "PATH=VALUE" overrides in the order
 * given, exactly as --set takes them, so the deck code has one way to apply them. */
#ifndef NBEP_CLI_H
#define NBEP_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

typedef enum nbep_command {
    NBEP_CMD_RUN,
    NBEP_CMD_CHECK,
    NBEP_CMD_INFO,
    NBEP_CMD_SWEEP,
    NBEP_CMD_HELP,
    NBEP_CMD_VERSION,
    NBEP_CMD_HELP_DECK,
} nbep_command;

typedef struct nbep_cli {
    nbep_command cmd;
    const char *path;         /* borrowed from argv: the deck, or the run file for info */
    char **overrides;         /* owned: "PATH=VALUE" strings */
    char **origins;           /* owned, n_overrides: what was typed for each ("-n abc",
                               * "--steps=abc"), NULL for --set PATH=VALUE (its own text) */
    size_t n_overrides;
    const char *summary;      /* borrowed: --summary FILE, "-" = stdout, NULL = none */
    const char *resume;       /* borrowed: --resume RUN.h5, NULL = none */
    bool quiet;
    nbep_command help_of;     /* cmd NBEP_CMD_HELP: the command it was asked of (nbep run
                               * --help), else NBEP_CMD_HELP (nbep --help) */
} nbep_cli;

/* Parses argv into *cli (zeroed on entry). NBEP_EUSAGE with one line naming the problem. */
NBEP_MUST_CHECK nbep_status nbep_cli_parse(int argc, char **argv, nbep_cli *cli, nbep_diag *d);
void nbep_cli_fini(nbep_cli *cli);
/* The --help text asked of command `of` (cli.help_of): info's own (it takes no options), else
 * the whole usage. */
void nbep_cli_print_help(FILE *f, nbep_command of);

#endif
