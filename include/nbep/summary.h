/* The JSON summary (SPEC "JSON summary"): one table of its keys, NBEP_SUMMARY_FIELDS, makes
 * the struct, the writer and the parser here, and the sweep's table columns (sweep.c). A key
 * is added in one place, and the sweep's reuse check reads back exactly what was written. */
#ifndef NBEP_SUMMARY_H
#define NBEP_SUMMARY_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "nbep/scene.h"

/* The value of a key that may be JSON null. */
typedef struct nbep_summary_nullable {
    bool known;          /* false: written as null */
    double value;        /* finite when known */
} nbep_summary_nullable;

/* Every key after "format" and "version", in SPEC order: X(field, KIND), field being both the
 * struct member and the JSON key. KIND: TEXT (char[NBEP_ALGO_NAME_MAX]), INT (int), UINT
 * (uint64_t), REAL (finite double), NULLABLE (nbep_summary_nullable). Keys are only ever
 * added (the format stays "nbep-summary-1"). */
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
    X(pressure, NULLABLE)    /* contract 2: fully periodic boxes only, null otherwise */

#define NBEP_SUMMARY_CTYPE_TEXT(field) char field[NBEP_ALGO_NAME_MAX]
#define NBEP_SUMMARY_CTYPE_INT(field) int field
#define NBEP_SUMMARY_CTYPE_UINT(field) uint64_t field
#define NBEP_SUMMARY_CTYPE_REAL(field) double field
#define NBEP_SUMMARY_CTYPE_NULLABLE(field) nbep_summary_nullable field

/* Everything the JSON summary holds. */
typedef struct nbep_summary {
#define NBEP_X_MEMBER(field, kind) NBEP_SUMMARY_CTYPE_##kind(field);
    NBEP_SUMMARY_FIELDS(NBEP_X_MEMBER)
#undef NBEP_X_MEMBER
} nbep_summary;

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
/* Parses a summary as nbep_summary_write_json writes it (format "nbep-summary-1", any
 * version) into *sum. false when the text is not such a summary or a key of the table is
 * missing or of the wrong type; *sum is then unchanged. */
bool nbep_summary_from_json(const char *json, nbep_summary *sum);

#endif
