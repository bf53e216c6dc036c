/* The HDF5 side of `nbep sweep` (output_sweep.h): the summary table and the reading back of a
 * run's overrides and summary. A separate file from output.c so that the run format's writer
 * stays one owner's; it follows the module's rules (output_hdf5.c): HDF5's printing is off,
 * every negative id or herr_t becomes NBEP_EIO with HDF5's innermost reason, every id is
 * released on every path.
 *
 * The table is one compound dataset rather than a group of column datasets because that is
 * what table readers expect (h5py structured arrays, pandas, PyTables, HDFView's table view),
 * and a sweep's table is small (one row per run). */
#include "nbep/output_sweep.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <hdf5.h>

#include "build_info.h"
#include "output_impl.h"

/* Every member of a row takes one slot wide enough for any of the three kinds, so that member
 * k sits at k * sizeof(slot) in memory. */
typedef union slot {
    int64_t i;
    double r;
    const char *s;
} slot;


/* A scalar attribute of one of the table's kinds. */
static int write_attr(hid_t loc, const char *path, const nbep_table_attr *a, nbep_diag *d)
{
    int rc = -1;
    const char *text = a->s ? a->s : "";
    hid_t type = a->kind == NBEP_TABLE_TEXT ? nbep__output_utf8_string_type() : H5I_INVALID_HID;
    hid_t file_type = a->kind == NBEP_TABLE_INT    ? H5T_STD_I64LE
                      : a->kind == NBEP_TABLE_REAL ? H5T_IEEE_F64LE
                                                   : type;
    hid_t mem_type = a->kind == NBEP_TABLE_INT    ? H5T_NATIVE_INT64
                     : a->kind == NBEP_TABLE_REAL ? H5T_NATIVE_DOUBLE
                                                  : type;
    const void *buf = a->kind == NBEP_TABLE_INT    ? (const void *)&a->i
                      : a->kind == NBEP_TABLE_REAL ? (const void *)&a->r
                                                   : (const void *)&text;
    hid_t space = H5Screate(H5S_SCALAR);
    hid_t attr = H5I_INVALID_HID;
    if (file_type < 0 || space < 0 ||
        (attr = H5Acreate2(loc, a->name, file_type, space, H5P_DEFAULT, H5P_DEFAULT)) < 0 ||
        H5Awrite(attr, mem_type, buf) < 0) {
        char what[128];
        snprintf(what, sizeof what, "write attribute %s", a->name);
        HDF5_FAIL(d, path, "%s", what);
    } else {
        rc = 0;
    }
    nbep__output_close_id(&attr);
    nbep__output_close_id(&space);
    nbep__output_close_id(&type);
    return rc;
}

/* The memory and file compound types of a row: members in column order, each in its slot in
 * memory; packed, little-endian in the file. */
static int make_row_types(const nbep_table *t, hid_t str, hid_t *mem, hid_t *file)
{
    size_t file_size = 0;
    for (size_t k = 0; k < t->n_cols; k++)
        file_size += t->cols[k].kind == NBEP_TABLE_TEXT ? H5Tget_size(str) : 8;
    *mem = H5Tcreate(H5T_COMPOUND, (t->n_cols ? t->n_cols : 1) * sizeof(slot));
    *file = H5Tcreate(H5T_COMPOUND, file_size ? file_size : 8);
    if (*mem < 0 || *file < 0)
        return -1;
    size_t file_off = 0;
    for (size_t k = 0; k < t->n_cols; k++) {
        const nbep_table_column *c = &t->cols[k];
        hid_t mt = c->kind == NBEP_TABLE_INT    ? H5T_NATIVE_INT64
                   : c->kind == NBEP_TABLE_REAL ? H5T_NATIVE_DOUBLE
                                                : str;
        hid_t ft = c->kind == NBEP_TABLE_INT    ? H5T_STD_I64LE
                   : c->kind == NBEP_TABLE_REAL ? H5T_IEEE_F64LE
                                                : str;
        if (H5Tinsert(*mem, c->name, k * sizeof(slot), mt) < 0 ||
            H5Tinsert(*file, c->name, file_off, ft) < 0)
            return -1;
        file_off += H5Tget_size(ft);
    }
    return 0;
}

/* The rows in memory layout; text points into the caller's strings (borrowed). */
static slot *make_rows(const nbep_table *t)
{
    size_t n = t->n_rows * t->n_cols;
    if (t->n_cols && n / t->n_cols != t->n_rows)
        return NULL;
    slot *rows = calloc(n ? n : 1, sizeof *rows);
    if (!rows)
        return NULL;
    for (size_t row = 0; row < t->n_rows; row++)
        for (size_t k = 0; k < t->n_cols; k++) {
            const nbep_table_column *c = &t->cols[k];
            slot *v = &rows[row * t->n_cols + k];
            bool missing = c->missing && c->missing[row];
            switch (c->kind) {
            case NBEP_TABLE_INT:
                v->i = missing ? 0 : c->i[row];
                break;
            case NBEP_TABLE_REAL:
                v->r = missing ? NAN : c->r[row];
                break;
            case NBEP_TABLE_TEXT:
                v->s = missing || !c->s[row] ? "" : c->s[row];
                break;
            }
        }
    return rows;
}

nbep_status nbep_output_sweep_write(const char *path, const nbep_table *t,
                                    const nbep_table_attr *attrs, size_t n_attrs, nbep_diag *d)
{
    nbep_status st = NBEP_EIO;
    char *tmp = nbep_partial_path(path);
    slot *rows = make_rows(t);
    hid_t fapl = H5I_INVALID_HID, file = H5I_INVALID_HID, str = H5I_INVALID_HID;
    hid_t mem = H5I_INVALID_HID, ftype = H5I_INVALID_HID, space = H5I_INVALID_HID;
    hid_t ds = H5I_INVALID_HID;
    bool made = false;
    if (!tmp || !rows) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the summary table", path);
        st = NBEP_ENOMEM;
        goto done;
    }
    /* The 1.8 format, as for run files (output.c): no "open for write" mark that would make
     * HDF5 tools refuse a file whose writer was killed. */
    if ((fapl = H5Pcreate(H5P_FILE_ACCESS)) < 0 ||
        H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18) < 0) {
        HDF5_FAIL(d, path, "set up file access");
        goto done;
    }
    /* a create that fails may leave the file made, empty (a full disk): it goes too */
    made = true;
    if ((file = H5Fcreate(tmp, H5F_ACC_TRUNC, H5P_DEFAULT, fapl)) < 0) {
        HDF5_FAIL(d, tmp, "create the file");
        goto done;
    }
    const nbep_table_attr format = {.name = "format", .kind = NBEP_TABLE_TEXT,
                                    .s = SWEEP_FORMAT_NAME};
    const nbep_table_attr version = {.name = "version", .kind = NBEP_TABLE_TEXT,
                                     .s = NBEP_VERSION};
    if (write_attr(file, tmp, &format, d) < 0 || write_attr(file, tmp, &version, d) < 0)
        goto done;
    for (size_t k = 0; k < n_attrs; k++)
        if (write_attr(file, tmp, &attrs[k], d) < 0)
            goto done;
    hsize_t n = t->n_rows;
    if ((str = nbep__output_utf8_string_type()) < 0 || make_row_types(t, str, &mem, &ftype) < 0) {
        HDF5_FAIL(d, tmp, "make the row type of /runs");
        goto done;
    }
    if ((space = H5Screate_simple(1, &n, NULL)) < 0 ||
        (ds = H5Dcreate2(file, "/runs", ftype, space, H5P_DEFAULT, H5P_DEFAULT,
                         H5P_DEFAULT)) < 0 ||
        (n && H5Dwrite(ds, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) < 0)) {
        HDF5_FAIL(d, tmp, "write /runs");
        goto done;
    }
    nbep__output_close_id(&ds);
    if (H5Fclose(file) < 0) {
        file = H5I_INVALID_HID;
        HDF5_FAIL(d, tmp, "close the file");
        goto done;
    }
    file = H5I_INVALID_HID;
    if (rename(tmp, path) != 0) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot rename to %s", tmp, path);
        goto done;
    }
    made = false;
    st = NBEP_OK;
done:
    nbep__output_close_id(&ds);
    nbep__output_close_id(&space);
    nbep__output_close_id(&ftype);
    nbep__output_close_id(&mem);
    nbep__output_close_id(&str);
    nbep__output_close_id(&file);
    nbep__output_close_id(&fapl);
    if (made)
        remove(tmp);
    free(rows);
    free(tmp);
    return st;
}

/* Opens a run file to read, without HDF5's lock (the look must work on file systems without
 * locks, and takes one look); *fapl and the file's id to close; < 0 (a message in d) when it
 * cannot. */
static hid_t open_run(const char *path, hid_t *fapl, nbep_diag *d)
{
    hid_t file = H5I_INVALID_HID;
    *fapl = H5Pcreate(H5P_FILE_ACCESS);
#if H5_VERSION_GE(1, 12, 1) || (H5_VERS_MAJOR == 1 && H5_VERS_MINOR == 10 && H5_VERS_RELEASE >= 7)
    if (*fapl >= 0 && H5Pset_file_locking(*fapl, false, true) < 0)
        nbep__output_close_id(fapl);
#endif
    if (*fapl < 0 || (file = H5Fopen(path, H5F_ACC_RDONLY, *fapl)) < 0)
        HDF5_FAIL(d, path, "open the file");
    return file;
}

nbep_status nbep_output_sweep_read_deck(const char *path, char **deck, nbep_diag *d)
{
    hid_t fapl, file = open_run(path, &fapl, d);
    const nbep_status st =
        file >= 0 && nbep__output_read_string_attr(file, path, "deck", deck, d) >= 0 ? NBEP_OK
                                                                                     : NBEP_EIO;
    nbep__output_close_id(&file);
    nbep__output_close_id(&fapl);
    return st;
}

nbep_status nbep_output_sweep_read_run(const char *path, char **overrides, char **summary_json,
                                       char **resumed, nbep_diag *d)
{
    char *ov = NULL, *json = NULL, *res = NULL;
    nbep_status st = NBEP_EIO;
    hid_t fapl, file = open_run(path, &fapl, d);
    if (file < 0)
        goto done;
    if (nbep__output_read_string_attr(file, path, "overrides", &ov, d) < 0)
        goto done;
    if (nbep__output_summary_json(file, path, &json, d) < 0)
        goto done;
    const htri_t has = H5Aexists(file, "resumed");
    if (has < 0 || (has > 0 && nbep__output_read_string_attr(file, path, "resumed", &res, d) < 0))
        goto done;
    *overrides = ov;
    *summary_json = json;
    *resumed = res;
    ov = json = res = NULL;
    st = NBEP_OK;
done:
    free(ov);
    free(json);
    free(res);
    nbep__output_close_id(&file);
    nbep__output_close_id(&fapl);
    return st;
}
