/* Status texts and exit codes from the one X-macro list, and the diag message list. */
#include "nbep/status.h"

#include <errno.h>
#include <signal.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

int nbep_status_exit_code(nbep_status s)
{
    switch (s) {
#define NBEP_X_CODE(name, code, text) \
    case NBEP_##name:                  \
        return code;
        NBEP_STATUS_LIST(NBEP_X_CODE)
#undef NBEP_X_CODE
    }
    return 1;
}

nbep_status nbep_status_of_open(int err)
{
    /* EROFS: a path on a read-only file system is as unwritable as one without permission
     * (README promises exit 2 for either; until 2026-12-01 it gave 1, a user's find); EPERM
     * too, a place that allows no new file (a sweep's folder under /sys gave 1 until
     * 2026-12-04, a review) */
    return err == ENOENT || err == ENOTDIR || err == EISDIR || err == EACCES || err == EPERM ||
                   err == EROFS || err == ENAMETOOLONG || err == ELOOP
               ? NBEP_EUSAGE
               : NBEP_EIO;
}

nbep_status nbep_status_of_stop(const atomic_int *stop)
{
    /* relaxed: the handler stores the signal with no other data to pass */
    const int sig = stop ? atomic_load_explicit(stop, memory_order_relaxed) : 0;
    return !sig ? NBEP_OK : sig == SIGINT ? NBEP_ESIGINT : NBEP_ESIGTERM;
}

const char *nbep_status_stop_text(nbep_status st, const atomic_int *stop)
{
    if (st != NBEP_ESIGTERM)
        return "interrupted by SIGINT";
    /* the signal that asked for it, where this process took it (in an MPI sweep another
     * rank's may have: then SIGTERM's words, which every stop signal but SIGINT's share) */
    const int sig = stop ? atomic_load_explicit(stop, memory_order_relaxed) : 0;
    return sig == SIGHUP    ? "terminated by SIGHUP"
           : sig == SIGUSR1 ? "terminated by SIGUSR1"
           : sig == SIGUSR2 ? "terminated by SIGUSR2"
                            : "terminated by SIGTERM";
}

const char *nbep_status_text(nbep_status s)
{
    switch (s) {
#define NBEP_X_TEXT(name, code, text) \
    case NBEP_##name:                  \
        return text;
        NBEP_STATUS_LIST(NBEP_X_TEXT)
#undef NBEP_X_TEXT
    }
    return "unknown status";
}

void nbep_diag_init(nbep_diag *d)
{
    memset(d, 0, sizeof *d);
}

void nbep_diag_clear(nbep_diag *d)
{
    size_t stored = d->n_errors < d->cap ? d->n_errors : d->cap;
    for (size_t i = 0; i < stored; i++) {
        free(d->msg[i]);
        free(d->where[i]);
        d->msg[i] = d->where[i] = NULL;
    }
    d->n_errors = 0;
}

void nbep_diag_fini(nbep_diag *d)
{
    if (!d)
        return;
    nbep_diag_clear(d);
    free(d->msg);
    free(d->where);
    free(d->rank);
    memset(d, 0, sizeof *d);
}

static char *vformat(const char *fmt, va_list ap)
{
    va_list ap2;
    va_copy(ap2, ap);
    int len = vsnprintf(NULL, 0, fmt, ap2);
    va_end(ap2);
    if (len < 0)
        return NULL;
    char *s = malloc((size_t)len + 1);
    if (s)
        vsnprintf(s, (size_t)len + 1, fmt, ap);
    return s;
}

static char *format(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *s = vformat(fmt, ap);
    va_end(ap);
    return s;
}

char *nbep_one_line(const char *s)
{
    size_t len = 0;
    for (const unsigned char *r = (const unsigned char *)s; *r; r++)
        len += *r < 0x20 || *r == 0x7f ? 4 : 1; /* \xNN at most */
    char *out = malloc(len + 1), *w = out;
    if (!out)
        return NULL;
    for (const unsigned char *r = (const unsigned char *)s; *r; r++) {
        if (*r >= 0x20 && *r != 0x7f)
            *w++ = (char)*r;
        else if (*r == '\n' || *r == '\t' || *r == '\r') {
            *w++ = '\\';
            *w++ = *r == '\n' ? 'n' : *r == '\t' ? 't' : 'r';
        } else
            w += sprintf(w, "\\x%02x", *r);
    }
    *w = '\0';
    return out;
}

static void diag_vadd(nbep_diag *d, uint64_t rank, const char *file, int line, const char *fmt,
                      va_list ap)
{
    size_t i = d->n_errors++;
    /* Messages are stored densely: once an allocation failed, later ones are only counted. */
    if (i > d->cap)
        return;
    if (i == d->cap) {
        size_t cap = d->cap ? 2 * d->cap : 8;
        char **m = realloc(d->msg, cap * sizeof *m);
        if (!m)
            return;
        d->msg = m;
        char **w = realloc(d->where, cap * sizeof *w);
        if (!w)
            return;
        d->where = w;
        uint64_t *r = realloc(d->rank, cap * sizeof *r);
        if (!r)
            return;
        d->rank = r;
        for (size_t k = d->cap; k < cap; k++)
            d->msg[k] = d->where[k] = NULL;
        d->cap = cap;
    }
    char *m = vformat(fmt, ap);
    d->msg[i] = m ? nbep_one_line(m) : NULL;
    free(m);
    d->where[i] = format("%s:%d", file, line);
    d->rank[i] = rank;
}

void nbep_diag_add(nbep_diag *d, const char *file, int line, const char *fmt, ...)
{
    if (!d)
        return;
    va_list ap;
    va_start(ap, fmt);
    diag_vadd(d, NBEP_DIAG_UNRANKED, file, line, fmt, ap);
    va_end(ap);
}

void nbep_diag_add_ranked(nbep_diag *d, uint64_t rank, const char *file, int line,
                          const char *fmt, ...)
{
    if (!d)
        return;
    va_list ap;
    va_start(ap, fmt);
    diag_vadd(d, rank, file, line, fmt, ap);
    va_end(ap);
}

void nbep_diag_sort(nbep_diag *d, size_t first)
{
    /* Insertion in place: stable (a message passes only those ranked strictly after it), no
     * memory to fail, and quadratic only in how far messages stand out of place: a load's
     * come in blocks, check by check, each already in the order of the deck's lines. (Until
     * 2026-11-30 a qsort of a copy, with this as its fallback without memory: two ways for one
     * order.) */
    const size_t stored = d->n_errors < d->cap ? d->n_errors : d->cap;
    for (size_t i = first + 1; i < stored; i++) {
        const uint64_t r = d->rank[i];
        char *m = d->msg[i], *w = d->where[i];
        size_t j = i;
        for (; j > first && d->rank[j - 1] > r; j--) {
            d->rank[j] = d->rank[j - 1];
            d->msg[j] = d->msg[j - 1];
            d->where[j] = d->where[j - 1];
        }
        d->rank[j] = r;
        d->msg[j] = m;
        d->where[j] = w;
    }
}

void nbep_diag_print(const nbep_diag *d, FILE *f)
{
    size_t stored = d->n_errors < d->cap ? d->n_errors : d->cap;
    int debug = getenv("NBEP_DEBUG") != NULL;
    for (size_t i = 0; i < stored; i++) {
        fprintf(f, "%s\n", d->msg[i] ? d->msg[i] : "nbep: (message lost: out of memory)");
        if (debug && d->where[i])
            fprintf(f, "    raised at %s\n", d->where[i]);
    }
    if (d->n_errors > stored)
        fprintf(f, "nbep: %zu more messages lost (out of memory)\n", d->n_errors - stored);
}
