/* The JSON summary (SPEC "JSON summary"): one table of its keys, NBEP_SUMMARY_FIELDS, makes
 * the struct, the writer and the parser here, and the sweep's table columns (sweep.c). A key
 * is added in one place, and the sweep's reuse check reads back exactly what was written. */
#ifndef NBEP_SUMMARY_H
#define NBEP_SUMMARY_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "nbep/scene.h"
#include "nbep/status.h"

/* The value of a key that may be JSON null. */
typedef struct nbep_summary_nullable {
    bool known;          /* false: written as null */
    double value;        /* finite when known */
} nbep_summary_nullable;

/* A count that may be unknown: JSON null, or a key that an older nbep did not write. */
typedef struct nbep_summary_count {
    bool known;          /* false: written as null */
    uint64_t value;
} nbep_summary_count;

/* How a run ended, the key "status": X(NAME, text). UNKNOWN is JSON null, and what a summary
 * written before the key was added (2026-11-30) reads as. The others follow the run's exit
 * status (nbep_summary_status_of): completed, 0; interrupted (SIGINT), 130; terminated
 * (SIGTERM), 143; failed, 1 (a write error, memory, a non-finite state, a jam, a stall of the
 * event loop). */
#define NBEP_SUMMARY_STATUS_LIST(X)                                                          \
    X(UNKNOWN, NULL)                                                                         \
    X(COMPLETED, "completed")                                                                \
    X(INTERRUPTED, "interrupted")                                                            \
    X(TERMINATED, "terminated")                                                              \
    X(FAILED, "failed")

typedef enum nbep_summary_status {
#define NBEP_X_ENUM(name, text) NBEP_SUMMARY_##name,
    NBEP_SUMMARY_STATUS_LIST(NBEP_X_ENUM)
#undef NBEP_X_ENUM
} nbep_summary_status;

/* Every key after "format" and "version", in SPEC order: X(field, KIND), field being both the
 * struct member and the JSON key. KIND: TEXT (char[NBEP_ALGO_NAME_MAX]), INT (int), UINT
 * (uint64_t), REAL (finite double), NULLABLE (nbep_summary_nullable), STATUS
 * (nbep_summary_status: a text, or null when unknown), COUNT (nbep_summary_count: an integer,
 * or null when unknown). Keys are only ever added (the format stays "nbep-summary-1"); the
 * reader requires every key of the kinds before STATUS and COUNT, and takes a missing STATUS
 * or COUNT key, which summaries written before it lack, as unknown. */
#define NBEP_SUMMARY_FIELDS(X)                                                               \
    X(algorithm, TEXT)                                                                       \
    X(threads, INT)                                                                          \
    X(spheres, UINT)                                                                         \
    X(planes, UINT)                                                                          \
    X(steps, UINT)           /* steps simulated (fewer than asked when interrupted) */       \
    X(dt, REAL)                                                                              \
    X(setup_seconds, REAL)                                                                   \
    X(wall_seconds, REAL)                                                                    \
    X(steps_per_second, REAL)                                                                \
    X(checks, UINT)                                                                          \
    X(predictions, UINT)                                                                     \
    X(collisions, UINT)                                                                      \
    X(sphere_collisions, UINT)                                                               \
    X(plane_collisions, UINT)                                                                \
    X(quiet_steps, UINT)                                                                     \
    X(energy_initial, REAL)                                                                  \
    X(energy_final, REAL)                                                                    \
    X(energy_rel_drift, REAL)                                                                \
    X(max_overlap, REAL)                                                                     \
    X(max_overlap_rel, REAL)                                                                 \
    X(peak_rss_bytes, UINT)                                                                  \
    X(pressure, NULLABLE)    /* contract 2: fully periodic boxes only, null otherwise */     \
    X(status, STATUS)        /* how the run ended (added 2026-11-30) */                      \
    X(steps_requested, COUNT) /* run.steps: the step it was to reach (added 2026-11-30) */

#define NBEP_SUMMARY_CTYPE_TEXT(field) char field[NBEP_ALGO_NAME_MAX]
#define NBEP_SUMMARY_CTYPE_INT(field) int field
#define NBEP_SUMMARY_CTYPE_UINT(field) uint64_t field
#define NBEP_SUMMARY_CTYPE_REAL(field) double field
#define NBEP_SUMMARY_CTYPE_NULLABLE(field) nbep_summary_nullable field
#define NBEP_SUMMARY_CTYPE_STATUS(field) nbep_summary_status field
#define NBEP_SUMMARY_CTYPE_COUNT(field) nbep_summary_count field

/* Everything the JSON summary holds. */
typedef struct nbep_summary {
#define NBEP_X_MEMBER(field, kind) NBEP_SUMMARY_CTYPE_##kind(field);
    NBEP_SUMMARY_FIELDS(NBEP_X_MEMBER)
#undef NBEP_X_MEMBER
} nbep_summary;

/* The status of a run that ended with st: NBEP_OK completed, NBEP_ESIGINT interrupted,
 * NBEP_ESIGTERM terminated, any other failed. */
nbep_summary_status nbep_summary_status_of(nbep_status st);
/* Whether s says its run ended as completed, or says nothing of how it ended (a summary before
 * the status key, taken as completed: a sweep reuses such a run, a resume finds nothing to
 * do). */
bool nbep_summary_ended(const nbep_summary *s);
/* The status's JSON text ("completed", ...); NULL for NBEP_SUMMARY_UNKNOWN (JSON null). */
const char *nbep_summary_status_text(nbep_summary_status s);

/* The text of v in the fewest significant digits (at most 17) that read back as v exactly
 * ("0.05", not "0.050000000000000003"; two different values never print alike), with %g's
 * exponent but none for a whole number below 10^15 ("48000", not "4.8e+04"), and where
 * mark_real, a decimal point or an exponent ("48000.0": a real stays a real in JSON). Into
 * buf; returns it. Every real nbep writes as text (JSON summaries, summary.csv, nbep info). */
#define NBEP_REAL_TEXT_MAX 32
const char *nbep_format_real(double v, bool mark_real, char buf[NBEP_REAL_TEXT_MAX]);

/* Writes the summary as one JSON object ("format": "nbep-summary-1", "version", then the
 * table's keys in order, reals as nbep_format_real writes them) followed by a newline.
 * Returns bytes written or -1 on a stream error. */
int nbep_summary_write_json(const nbep_summary *s, FILE *f);
/* The same into a malloc'd string (caller frees); NULL on allocation failure. */
char *nbep_summary_to_json(const nbep_summary *s);
/* Any jansson value as one line of text as the summary's is written (SPEC's separators, keys
 * in insertion order, reals as nbep_format_real writes them) and a newline, malloc'd; NULL
 * when out of memory (check.c's report; the value stays the caller's). */
struct json_t;
char *nbep_summary_dump_line(struct json_t *o);
/* A path (or any text) as a JSON string, a new reference: JSON text is UTF-8, and jansson
 * refuses a string that is not, so each byte of s that is not part of a valid UTF-8 sequence
 * becomes U+FFFD (a file name of Latin-1 bytes, "r\xe9sultats"); NULL only when out of
 * memory. (Until 2026-11-30 such a deck or folder name made nbep check's and the sweep's JSON
 * fail as "Cannot allocate memory", exit 1, after the sweep's runs.) */
struct json_t *nbep_summary_json_text(const char *s);
/* Whether s is valid UTF-8 throughout (RFC 3629, as nbep_summary_json_text reads it). */
bool nbep_utf8_valid(const char *s);
/* Parses a summary as nbep_summary_write_json writes it (format "nbep-summary-1", any
 * version) into *sum. false when the text is not such a summary, a key of the table is of the
 * wrong type (a status none of the texts above), or a required key is missing; *sum is then
 * unchanged. A STATUS or COUNT key that is missing (an older nbep's summary) reads as
 * unknown. */
bool nbep_summary_from_json(const char *json, nbep_summary *sum);

#endif
