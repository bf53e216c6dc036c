/* The HDF5 side of `nbep sweep`: the summary table summary.h5, and what a sweep reads back from
 * an earlier run's file to decide whether it can be reused. Part of the output module (it
 * includes hdf5.h); called by sweep.c from one thread, outside parallel regions.
 *
 * summary.h5 (format "nbep-sweep-1"):
 *   /runs                 compound dataset, one row per run, one member per column, in the
 *                         table's column order: integers as i64, reals as f64, text as
 *                         variable-length UTF-8 strings (h5py: f["runs"][:] is a structured
 *                         array; pandas.DataFrame(f["runs"][:]) a table)
 *   / attributes          format, version, and the caller's text attributes (deck, overrides,
 *                         axes, ...) */
#ifndef NBEP_OUTPUT_SWEEP_H
#define NBEP_OUTPUT_SWEEP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

typedef enum nbep_table_kind {
    NBEP_TABLE_INT,     /* i64 */
    NBEP_TABLE_REAL,    /* f64 */
    NBEP_TABLE_TEXT,    /* string */
} nbep_table_kind;

/* One column of n_rows values; only the array of its kind is read (borrowed). A row whose
 * missing[row] is true (missing may be NULL: none) is written as 0, NaN or "" in HDF5 and left
 * empty in CSV. */
typedef struct nbep_table_column {
    const char *name;
    nbep_table_kind kind;
    const int64_t *i;
    const double *r;
    const char *const *s;   /* NULL entries are written as "" */
    const bool *missing;
} nbep_table_column;

typedef struct nbep_table {
    size_t n_rows, n_cols;
    const nbep_table_column *cols;   /* borrowed; names must differ */
} nbep_table;

/* An attribute of the root group: a scalar of the given kind (only the matching field is
 * read). */
typedef struct nbep_table_attr {
    const char *name;
    nbep_table_kind kind;
    int64_t i;
    double r;
    const char *s;
} nbep_table_attr;

/* Writes the table as the compound dataset /runs of a new file at path, with root attributes
 * format = "nbep-sweep-1", version, and attrs (n_attrs may be 0; i64, f64 or string). Built as
 * "PATH.partial" and renamed to path when complete, so that readers never see half a table.
 * NBEP_EIO with HDF5's reason ("nbep: PATH: cannot WHAT: REASON"), NBEP_ENOMEM. */
NBEP_MUST_CHECK nbep_status nbep_output_sweep_write(const char *path, const nbep_table *t,
                                                    const nbep_table_attr *attrs,
                                                    size_t n_attrs, nbep_diag *d);

/* Reads from an nbep-1 run file the root attribute `deck` (the deck's text it was made from)
 * into *deck, malloc'd. NBEP_EIO when the file cannot be opened or lacks it. */
NBEP_MUST_CHECK nbep_status nbep_output_sweep_read_deck(const char *path, char **deck,
                                                        nbep_diag *d);

/* Reads from an nbep-1 run file the root attribute `overrides` and, when present, the /summary
 * json attribute and the root attribute `resumed`. *overrides, *summary_json and *resumed are
 * malloc'd (the caller frees them); *summary_json is NULL when the run wrote no summary
 * (killed, or still running), *resumed when no part was resumed. NBEP_EIO when the file
 * cannot be opened or lacks the overrides; nothing is then written out. */
NBEP_MUST_CHECK nbep_status nbep_output_sweep_read_run(const char *path, char **overrides,
                                                       char **summary_json, char **resumed,
                                                       nbep_diag *d);

#endif
