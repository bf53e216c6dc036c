/* Status codes, their exit codes and texts (one X-macro list), and nbep_diag, the list of
 * one-line messages a failing call leaves for main.c to print. */
#ifndef NBEP_STATUS_H
#define NBEP_STATUS_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "nbep/compiler.h"

#define NBEP_STATUS_LIST(X)                                                                  \
    X(OK, 0, "success")                                                                      \
    X(EUSAGE, 2, "bad command line")                                                         \
    X(EDECK, 2, "bad deck")                                                                  \
    X(EBUSY, 2, "file held by another run")                                                  \
    X(ENOMEM, 1, "out of memory")                                                            \
    X(EIO, 1, "I/O error")                                                                   \
    X(ENUMERIC, 1, "numerical failure")                                                      \
    X(ESIGINT, 130, "interrupted")                                                           \
    X(ESIGTERM, 143, "terminated")

typedef enum nbep_status {
#define NBEP_X_ENUM(name, code, text) NBEP_##name,
    NBEP_STATUS_LIST(NBEP_X_ENUM)
#undef NBEP_X_ENUM
} nbep_status;

/* The process exit code for a status (0, 1, 2, 130 or 143). */
int nbep_status_exit_code(nbep_status s);
/* The status of a failure (errno err) to open a file that the command line or the deck
 * named: a name that is no file to read or write (no such file, a directory, no permission, a
 * read-only file system) is the user's mistake, NBEP_EUSAGE (exit 2, as a bad deck); anything
 * else (a full disk, a failing device) is an I/O error. */
nbep_status nbep_status_of_open(int err);
/* What the stop flag *stop asks for (main.c's: the signal number its handler stored, 0 for
 * none; stop may be NULL): NBEP_OK, NBEP_ESIGINT for SIGINT, else NBEP_ESIGTERM (SIGTERM, and
 * SIGHUP, SIGUSR1 and SIGUSR2, which ask the same: main.c). A relaxed
 * load, cheap enough for a loop to make every few thousand iterations; any thread may call
 * it. */
nbep_status nbep_status_of_stop(const atomic_int *stop);
/* How a stop status reads in the one line that says so: "interrupted by SIGINT" for
 * NBEP_ESIGINT; for NBEP_ESIGTERM "terminated by SIGTERM", or by the signal the stop flag
 * *stop holds (SIGHUP, SIGUSR1, SIGUSR2; stop may be NULL). */
const char *nbep_status_stop_text(nbep_status st, const atomic_int *stop);
/* A short human text for a status; never NULL. */
const char *nbep_status_text(nbep_status s);

/* Messages for the user, one line each, plus where in our source each was raised (shown only
 * with NBEP_DEBUG set in the environment), and each one's rank for nbep_diag_sort. Not
 * thread-safe: one diag per thread. */
typedef struct nbep_diag {
    size_t n_errors;       /* messages added */
    size_t cap;
    char **msg;            /* owned, n_errors strings */
    char **where;          /* owned, "file:line" of our source */
    uint64_t *rank;        /* owned: where nbep_diag_sort puts each message, smaller first */
} nbep_diag;

/* The rank of a message nbep_diag_add adds: after every message given a smaller one. */
#define NBEP_DIAG_UNRANKED UINT64_MAX

/* A copy of s (to free) with each control character (below the space, and DEL) written as C
 * writes it in a string: \n, \t, \r, else \xNN; NULL where memory runs out. For a user's
 * text (a deck's string, a file's name) in a one-line message: a newline in it broke the line,
 * and an escape sequence reached the terminal (a review, 2026-12-05). */
char *nbep_one_line(const char *s);

void nbep_diag_init(nbep_diag *d);
void nbep_diag_fini(nbep_diag *d);
/* Appends one formatted line (no trailing newline needed), its control characters written as
 * nbep_one_line writes them: a deck's string or a file's name quoted in it cannot break the
 * line. On allocation failure the message is dropped but n_errors still counts it, so callers
 * still fail. */
void nbep_diag_add(nbep_diag *d, const char *file, int line, const char *fmt, ...)
    NBEP_PRINTF(4, 5);
/* nbep_diag_add with the message's rank: its place once nbep_diag_sort orders the list (a
 * module that collects many messages says what its ranks mean; the scene's are the command
 * line's options, then the deck's lines). */
void nbep_diag_add_ranked(nbep_diag *d, uint64_t rank, const char *file, int line,
                          const char *fmt, ...) NBEP_PRINTF(5, 6);
/* Orders the messages from the first'th on by rank, those of one rank in the order they were
 * added (a stable sort); the messages before `first` stay where they are, and those lost to a
 * failed allocation stay counted at the end (nbep_diag_print). */
void nbep_diag_sort(nbep_diag *d, size_t first);
/* Prints every message verbatim, one per line; with NBEP_DEBUG set, each line is followed by
 * the source location that raised it. Messages name their own place ("deck:line: ...") or
 * start with "nbep: ". */
void nbep_diag_print(const nbep_diag *d, FILE *f);
/* Empties the list (keeps the memory). */
void nbep_diag_clear(nbep_diag *d);

#define NBEP_FAIL(diag, code, ...)                                                           \
    do {                                                                                     \
        nbep_diag_add((diag), __FILE__, __LINE__, __VA_ARGS__);                              \
        return (code);                                                                       \
    } while (0)

#endif
