/* libFuzzer harness for the deck parser, nbep_scene_load(_from): every input is a deck, written to a
 * scratch file (the loader takes a path) and loaded; a load must either succeed and give a
 * scene that nbep_scene_fini releases, or fail with one of its documented statuses and at
 * least one message. Anything else (a crash, a sanitizer report, a leak, a status outside
 * the contract) is a finding.
 *
 * An input may carry --set overrides too: the lines after a line "#@set" (a comment to
 * libconfig, so the deck above stays a deck) are passed as overrides, one per line, so the
 * fuzzer also explores scene_override.c. Every other override comes with an origin (what a
 * user typed for an option, nbep_scene_load_from): the override's own text behind "-x ", so
 * that messages name labels of any length and content too.
 *
 * Built and run by scripts/fuzz.sh (clang -fsanitize=fuzzer,address,undefined); not part of
 * `make`. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "nbep/scene.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The separator between the deck and its overrides. */
#define SET_MARK "#@set\n"
/* Overrides per input at most: more add nothing that a few do not. */
#define MAX_OVERRIDES 16

/* The scratch folder and deck of this process (libFuzzer's -fork and -jobs run several
 * processes, each with its own). */
static char deck_dir[256], deck_path[300];

static void remove_deck(void)
{
    unlink(deck_path);
    rmdir(deck_dir);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    const char *tmp = getenv("NBEP_FUZZ_TMP");
    snprintf(deck_dir, sizeof deck_dir, "%s/nbep-fuzz-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(deck_dir)) {
        perror("fuzz_scene: mkdtemp");
        abort();
    }
    snprintf(deck_path, sizeof deck_path, "%s/fuzz.deck", deck_dir);
    atexit(remove_deck);
    return 0;
}

static void write_deck(const uint8_t *data, size_t size)
{
    FILE *f = fopen(deck_path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) {
        perror("fuzz_scene: writing the scratch deck");
        abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* split off the overrides: copies, NUL-terminated, one per line */
    size_t deck_len = size;
    const uint8_t *mark = NULL;
    const size_t mark_len = sizeof SET_MARK - 1;
    for (size_t i = 0; i + mark_len <= size && !mark; i++)
        if ((i == 0 || data[i - 1] == '\n') && memcmp(data + i, SET_MARK, mark_len) == 0)
            mark = data + i;
    char *ov_text = NULL;
    const char *ov[MAX_OVERRIDES], *origins[MAX_OVERRIDES];
    char *labels[MAX_OVERRIDES] = {0};
    size_t n_ov = 0;
    if (mark) {
        deck_len = (size_t)(mark - data);
        size_t rest = size - deck_len - mark_len;
        ov_text = malloc(rest + 1);
        if (!ov_text)
            return 0;
        memcpy(ov_text, mark + mark_len, rest);
        ov_text[rest] = '\0';
        for (char *line = ov_text; line && n_ov < MAX_OVERRIDES;) {
            char *nl = strchr(line, '\n');
            if (nl)
                *nl = '\0';
            if (*line) {
                if (n_ov % 2 && (labels[n_ov] = malloc(strlen(line) + 4)))
                    sprintf(labels[n_ov], "-x %s", line);
                origins[n_ov] = labels[n_ov]; /* NULL: "--set PATH=VALUE" */
                ov[n_ov++] = line;
            }
            line = nl ? nl + 1 : NULL;
        }
    }
    write_deck(data, deck_len);

    nbep_diag d;
    nbep_diag_init(&d);
    nbep_scene sc;
    memset(&sc, 0xA5, sizeof sc); /* *out must be written only on success */
    nbep_status st = nbep_scene_load_from(deck_path, ov, origins, n_ov, NULL, &sc, &d);
    switch (st) {
    case NBEP_OK:
        if (d.n_errors != 0)
            abort(); /* success with messages: outside the contract */
        nbep_scene_fini(&sc);
        break;
    case NBEP_EDECK:
    case NBEP_ENOMEM:
    case NBEP_EIO:
        if (d.n_errors == 0)
            abort(); /* a failure must say why */
        break;
    default:
        abort(); /* a status nbep_scene_load does not return */
    }
    nbep_diag_fini(&d);
    for (size_t k = 0; k < n_ov; k++)
        free(labels[k]);
    free(ov_text);
    return 0;
}
