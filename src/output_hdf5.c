/* HDF5 helpers shared by the output module's files (output_impl.h): error text, id closing,
 * file access properties, attribute and row readers and writers, and the library's set-up.
 * Errors: HDF5's automatic printing is off (nbep_output_library_init); every negative id or
 * herr_t becomes one line "nbep: PATH: cannot WHAT: REASON", REASON being the innermost entry
 * of HDF5's error stack, captured before any cleanup call clears the stack. */
#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

#include <hdf5.h>

#include "nbep/output_xdmf.h"
#include "output_impl.h"

/* Longest HDF5 error description kept (they are one line; longer ones are cut). */
#define REASON_MAX 512

static herr_t innermost_cb(unsigned n, const H5E_error2_t *err, void *data)
{
    if (n == 0 && err->desc)
        snprintf(data, REASON_MAX, "%s", err->desc);
    return 0;
}

/* HDF5's reason for the failure that just happened: the innermost (most specific) entry of
 * its error stack. File-open failures carry the system's text inside ("..., errno = 2, error
 * message = 'No such file or directory', ..."); that text alone is what a user needs. */
static void hdf5_reason(char *buf)
{
    snprintf(buf, REASON_MAX, "unknown HDF5 error");
    if (H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost_cb, buf) < 0)
        return;
    static const char errno_key[] = "error message = '";
    char *m = strstr(buf, errno_key);
    if (m) {
        m += sizeof errno_key - 1;
        char *end = strchr(m, '\'');
        if (end) {
            memmove(buf, m, (size_t)(end - m));
            buf[end - m] = '\0';
        }
    }
    for (char *c = buf; *c; c++)   /* one line: some descriptions embed newlines */
        if (*c == '\n' || *c == '\r')
            *c = ' ';
}

void nbep__output_hdf5_fail(nbep_diag *d, const char *file, int line, const char *path,
                            const char *what_fmt, ...)
{
    char reason[REASON_MAX], what[256];
    hdf5_reason(reason);
    va_list ap;
    va_start(ap, what_fmt);
    vsnprintf(what, sizeof what, what_fmt, ap);
    va_end(ap);
    nbep_diag_add(d, file, line, "nbep: %s: cannot %s: %s", path, what, reason);
}

void nbep__output_close_id(hid_t *id)
{
    if (*id >= 0)
        H5Idec_ref(*id);
    *id = H5I_INVALID_HID;
}

hid_t nbep__output_utf8_string_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    if (t >= 0 && (H5Tset_size(t, H5T_VARIABLE) < 0 || H5Tset_cset(t, H5T_CSET_UTF8) < 0))
        nbep__output_close_id(&t);
    return t;
}

int nbep__output_write_attr(hid_t loc, const char *path, const char *name, hid_t file_type,
                            hid_t mem_type, hsize_t n, const void *buf, nbep_diag *d)
{
    int rc = -1;
    hid_t space = n ? H5Screate_simple(1, &n, NULL) : H5Screate(H5S_SCALAR);
    hid_t attr = H5I_INVALID_HID;
    if (space < 0) {
        HDF5_FAIL(d, path, "make the dataspace of attribute %s", name);
        goto done;
    }
    attr = H5Acreate2(loc, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT);
    if (attr < 0) {
        HDF5_FAIL(d, path, "create attribute %s", name);
        goto done;
    }
    if (H5Awrite(attr, mem_type, buf) < 0) {
        HDF5_FAIL(d, path, "write attribute %s", name);
        goto done;
    }
    rc = 0;
done:
    nbep__output_close_id(&attr);
    nbep__output_close_id(&space);
    return rc;
}

int nbep__output_write_string_attr(hid_t loc, const char *path, const char *name,
                                   const char *value, nbep_diag *d)
{
    hid_t t = nbep__output_utf8_string_type();
    if (t < 0) {
        HDF5_FAIL(d, path, "make a string type for attribute %s", name);
        return -1;
    }
    const char *v = value ? value : "";
    int rc = nbep__output_write_attr(loc, path, name, t, t, 0, &v, d);
    nbep__output_close_id(&t);
    return rc;
}

hid_t nbep__output_fapl(bool writer)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    if (fapl < 0)
        return fapl;
    if (writer && H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18) < 0)
        nbep__output_close_id(&fapl);
#if H5_VERSION_GE(1, 12, 1) || (H5_VERS_MAJOR == 1 && H5_VERS_MINOR == 10 && H5_VERS_RELEASE >= 7)
    /* ignore_when_disabled: a reader still works where the file system has no locks. */
    if (fapl >= 0 && H5Pset_file_locking(fapl, !writer, true) < 0)
        nbep__output_close_id(&fapl);
#endif
    /* Older HDF5 cannot switch the lock off per file: HDF5_USE_FILE_LOCKING=FALSE in the
     * environment does it there. */
    return fapl;
}

int nbep__output_fields_missing(hid_t file, const char *path, const char *name, hid_t want,
                                char missing[NBEP_FIELD_NAME_MAX], nbep_diag *d)
{
    missing[0] = '\0';
    hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
    hid_t type = ds < 0 ? H5I_INVALID_HID : H5Dget_type(ds);
    nbep__output_close_id(&ds);
    if (type < 0) {
        HDF5_FAIL(d, path, "read the type of %s", name);
        return -1;
    }
    const bool compound = H5Tget_class(type) == H5T_COMPOUND;
    const int n = H5Tget_nmembers(want);
    for (int k = 0; k < n && !missing[0]; k++) {
        char *field = H5Tget_member_name(want, (unsigned)k);
        const int i = field && compound ? H5Tget_member_index(type, field) : -1;
        if (!field || i < 0 ||
            H5Tget_member_class(type, (unsigned)i) != H5Tget_member_class(want, (unsigned)k))
            snprintf(missing, NBEP_FIELD_NAME_MAX, "%s", field ? field : "?");
        H5free_memory(field);
    }
    nbep__output_close_id(&type);
    return 0;
}

int nbep__output_summary_json(hid_t file, const char *path, char **json, nbep_diag *d)
{
    *json = NULL;
    const htri_t group = H5Lexists(file, "/summary", H5P_DEFAULT);
    const htri_t has = group > 0 ? H5Aexists_by_name(file, "/summary", "json", H5P_DEFAULT) : 0;
    if (group < 0 || has < 0) {
        HDF5_FAIL(d, path, "look for the /summary json attribute");
        return -1;
    }
    if (!has)
        return 0;
    hid_t g = H5Gopen2(file, "/summary", H5P_DEFAULT);
    if (g < 0) {
        HDF5_FAIL(d, path, "open /summary");
        return -1;
    }
    const int rc = nbep__output_read_string_attr(g, path, "json", json, d);
    nbep__output_close_id(&g);
    return rc < 0 ? -1 : 0;
}

/* Variable-length strings live in the file's global heap, and HDF5 (1.10) trusts the sizes
 * written there: a damaged object size makes H5Aread copy past its buffer (SIGSEGV, found
 * 2026-12-05 with one flipped byte). So before such a read nbep walks the heap collection
 * the attribute points into, as HDF5 will, and refuses a collection whose objects do not
 * tile it or whose object is not the string's length. The pointer (length, collection
 * address, object index: the attribute's raw 4 + sizeof_addr + 4 bytes) is what HDF5 hands a
 * conversion function, so a soft conversion from variable-length strings to an opaque type
 * of that size reads it without touching the heap. */
#define HEAP_ID_TAG "nbep global heap id"
#define HEAP_ID_MAX 24 /* 4 + the widest address (16) + 4 */

static herr_t heap_id_conv(hid_t src, hid_t dst, H5T_cdata_t *cdata, size_t n, size_t stride,
                           size_t bkg_stride, void *buf, void *bkg, hid_t dxpl)
{
    (void)n, (void)stride, (void)bkg_stride, (void)buf, (void)bkg, (void)dxpl;
    if (cdata->command == H5T_CONV_INIT) {
        char *tag = H5Tget_class(dst) == H5T_OPAQUE ? H5Tget_tag(dst) : NULL;
        const bool ours = tag && strcmp(tag, HEAP_ID_TAG) == 0 &&
                          H5Tis_variable_str(src) > 0;
        H5free_memory(tag);
        return ours ? 0 : -1;
    }
    return 0; /* the raw bytes are already the answer: nothing to convert */
}

static uint64_t le_bytes(const unsigned char *p, size_t n)
{
    uint64_t v = 0;
    for (size_t k = n; k-- > 0;)
        v = v << 8 | p[k];
    return v;
}

/* 0 when the attribute (a variable-length string) points at an object of its own length
 * inside a well-formed heap collection, or when the file is not one nbep can read raw (not
 * the sec2 driver): HDF5 then reads it as before; -2 after a line saying the file is
 * damaged (exit 2, as for any file no run wrote), -1 when the check itself failed. */
static int heap_object_ok(hid_t attr, const char *path, const char *name, nbep_diag *d)
{
    static bool registered;
    hid_t file = H5Iget_file_id(attr), fcpl = H5I_INVALID_HID, fapl = H5I_INVALID_HID;
    hid_t opaque = H5I_INVALID_HID;
    unsigned char *heap = NULL;
    int rc = -1;
    size_t sizeof_addr = 0, sizeof_size = 0;
    hsize_t base = 0;
    if (file < 0 || (fcpl = H5Fget_create_plist(file)) < 0 ||
        (fapl = H5Fget_access_plist(file)) < 0 ||
        H5Pget_sizes(fcpl, &sizeof_addr, &sizeof_size) < 0 ||
        H5Pget_userblock(fcpl, &base) < 0) {
        HDF5_FAIL(d, path, "read the layout of the file for attribute %s", name);
        goto done;
    }
    if (H5Pget_driver(fapl) != H5FD_SEC2) {
        rc = 0;
        goto done;
    }
    const size_t id_size = 8 + sizeof_addr; /* on disk; H5Tget_size says a pointer's */
    if (id_size > HEAP_ID_MAX || sizeof_size > 8) {
        rc = 0; /* a layout nbep never writes: left to HDF5 */
        goto done;
    }
    unsigned char id[HEAP_ID_MAX];
    opaque = H5Tcreate(H5T_OPAQUE, id_size);
    if (opaque >= 0 && H5Tset_tag(opaque, HEAP_ID_TAG) >= 0 && !registered) {
        hid_t vs = nbep__output_utf8_string_type();
        registered = vs >= 0 &&
                     H5Tregister(H5T_PERS_SOFT, "nbep heap id", vs, opaque, heap_id_conv) >= 0;
        nbep__output_close_id(&vs);
    }
    if (!registered || H5Aread(attr, opaque, id) < 0) {
        HDF5_FAIL(d, path, "read where attribute %s is stored", name);
        goto done;
    }
    const uint64_t length = le_bytes(id, 4), index = le_bytes(id + 4 + sizeof_addr, 4);
    const uint64_t at = le_bytes(id + 4, sizeof_addr);
    void *handle = NULL;
    struct stat st;
    if (H5Fget_vfd_handle(file, fapl, &handle) < 0 || !handle ||
        fstat(*(int *)handle, &st) != 0) {
        HDF5_FAIL(d, path, "read where attribute %s is stored", name);
        goto done;
    }
    const int fd = *(int *)handle;
    const uint64_t eof = (uint64_t)st.st_size;
    /* a collection: "GCOL", version 1, 3 reserved bytes, its size (sizeof_size bytes), then
     * objects of a 2-byte index, 2-byte reference count, 4 reserved bytes and a size, their
     * data padded to 8 bytes; index 0 is the free space, its size counting its header */
    const size_t head = 8 + sizeof_size, obj_head = 8 + sizeof_size;
    unsigned char top[16];
    uint64_t size = 0;
    bool ok = base <= eof && at <= eof - base && eof - base - at >= head &&
              pread(fd, top, head, (off_t)(base + at)) == (ssize_t)head &&
              memcmp(top, "GCOL", 4) == 0 && top[4] == 1 &&
              (size = le_bytes(top + 8, sizeof_size)) >= head && size <= eof - base - at;
    if (ok && !(heap = malloc(size))) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory to read attribute %s", path,
                      name);
        goto done;
    }
    ok = ok && pread(fd, heap, size, (off_t)(base + at)) == (ssize_t)size;
    bool found = false;
    for (uint64_t p = head; ok && p + obj_head <= size;) {
        const uint64_t k = le_bytes(heap + p, 2), n = le_bytes(heap + p + 8, sizeof_size);
        const uint64_t need = n > size ? 0 : k ? obj_head + ((n + 7) & ~(uint64_t)7) : n;
        ok = need >= obj_head && need <= size - p;
        found = found || (ok && k == index && k && n == length);
        p += need;
    }
    if (!ok || !found) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: attribute %s points into a damaged part of the file (its "
                      "global heap): the file is damaged, or no run wrote it",
                      path, name);
        rc = -2;
        goto done;
    }
    rc = 0;
done:
    free(heap);
    nbep__output_close_id(&opaque);
    nbep__output_close_id(&fapl);
    nbep__output_close_id(&fcpl);
    nbep__output_close_id(&file);
    return rc;
}

int nbep__output_read_string_attr(hid_t loc, const char *path, const char *name, char **out,
                                  nbep_diag *d)
{
    int rc = -1;
    hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
    hid_t ftype = H5I_INVALID_HID, mtype = H5I_INVALID_HID;
    char *value = NULL;
    if (attr < 0 || (ftype = H5Aget_type(attr)) < 0) {
        HDF5_FAIL(d, path, "read attribute %s", name);
        goto done;
    }
    if (H5Tget_class(ftype) != H5T_STRING) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: attribute %s is not a string", path,
                      name);
        goto done;
    }
    htri_t variable = H5Tis_variable_str(ftype);
    size_t size = H5Tget_size(ftype);
    mtype = H5Tcopy(H5T_C_S1);
    if (variable < 0 || size == 0 || mtype < 0 ||
        H5Tset_size(mtype, variable ? H5T_VARIABLE : size + 1) < 0 ||
        H5Tset_cset(mtype, H5Tget_cset(ftype)) < 0) {
        HDF5_FAIL(d, path, "make a string type to read attribute %s", name);
        goto done;
    }
    if (variable) {
        char *v = NULL;
        if ((rc = heap_object_ok(attr, path, name, d)) < 0)
            goto done;
        rc = -1;
        if (H5Aread(attr, mtype, &v) < 0) {
            HDF5_FAIL(d, path, "read attribute %s", name);
            goto done;
        }
        value = strdup(v ? v : "");
        H5free_memory(v);
    } else if ((value = calloc(size + 1, 1)) && H5Aread(attr, mtype, value) < 0) {
        HDF5_FAIL(d, path, "read attribute %s", name);
        free(value);
        value = NULL;
        goto done;
    }
    if (!value) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for attribute %s", path,
                      name);
        goto done;
    }
    *out = value;
    rc = 0;
done:
    nbep__output_close_id(&mtype);
    nbep__output_close_id(&ftype);
    nbep__output_close_id(&attr);
    return rc;
}

int nbep__output_read_attr(hid_t loc, const char *path, const char *name, hid_t mem_type,
                           void *buf, nbep_diag *d)
{
    hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
    if (attr < 0 || H5Aread(attr, mem_type, buf) < 0) {
        HDF5_FAIL(d, path, "read attribute %s", name);
        nbep__output_close_id(&attr);
        return -1;
    }
    nbep__output_close_id(&attr);
    return 0;
}

int nbep__output_dataset_rows(hid_t file, const char *path, const char *name, hsize_t *rows,
                              nbep_diag *d)
{
    hsize_t dims[H5S_MAX_RANK];
    hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
    hid_t space = ds < 0 ? H5I_INVALID_HID : H5Dget_space(ds);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_dims(space, dims, NULL);
    if (rank < 1) {
        HDF5_FAIL(d, path, "read the shape of %s", name);
        rank = -1;
    } else {
        *rows = dims[0];
    }
    nbep__output_close_id(&space);
    nbep__output_close_id(&ds);
    return rank < 0 ? -1 : 0;
}

int nbep__output_read_row(hid_t file, const char *path, const char *name, hsize_t row,
                          hsize_t per_row, hid_t mem_type, void *buf, nbep_diag *d)
{
    /* dims of any rank a file may hold (a row is read from ranks 1 to 3 only) */
    hsize_t dims[H5S_MAX_RANK] = {0}, start[3] = {row, 0, 0}, count[3] = {1, 0, 0};
    int rc = -1;
    hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
    hid_t space = ds < 0 ? H5I_INVALID_HID : H5Dget_space(ds);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_dims(space, dims, NULL);
    hsize_t values = 1;
    for (int k = 1; k < rank && k < 3; k++)
        values *= (count[k] = dims[k]);
    /* the memory space of the row's own shape: a flat one made HDF5 map each element to
     * its chunk apart */
    hid_t mem = rank >= 1 && rank <= 3 ? H5Screate_simple(rank, count, NULL) : H5I_INVALID_HID;
    if (rank < 1 || rank > 3 || mem < 0) {
        HDF5_FAIL(d, path, "read the shape of %s", name);
        goto done;
    }
    if (values != per_row || row >= dims[0]) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: %s has no row %llu of %llu value%s (wrong shape for this deck)",
                      path, name, (unsigned long long)row, (unsigned long long)per_row,
                      per_row == 1 ? "" : "s");
        goto done;
    }
    if (per_row > 0 &&
        (H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL) < 0 ||
         H5Dread(ds, mem_type, mem, space, H5P_DEFAULT, buf) < 0)) {
        HDF5_FAIL(d, path, "read row %llu of %s", (unsigned long long)row, name);
        goto done;
    }
    rc = 0;
done:
    nbep__output_close_id(&mem);
    nbep__output_close_id(&space);
    nbep__output_close_id(&ds);
    return rc;
}

int nbep__output_complete_rows(hid_t file, const char *path, const char *group,
                               const char *dataset, uint64_t *complete, hsize_t *more,
                               nbep_diag *d)
{
    hsize_t rows;
    if (nbep__output_dataset_rows(file, path, dataset, &rows, d) < 0)
        return -1;
    htri_t has = H5Aexists_by_name(file, group, "count", H5P_DEFAULT);
    hid_t g = has > 0 ? H5Gopen2(file, group, H5P_DEFAULT) : H5I_INVALID_HID;
    if (has < 0 || (has > 0 && g < 0)) {
        HDF5_FAIL(d, path, "look for the count attribute of %s", group);
        return -1;
    }
    uint64_t count = rows;
    int rc = has > 0 ? nbep__output_read_attr(g, path, "count", H5T_NATIVE_UINT64, &count, d) : 0;
    nbep__output_close_id(&g);
    if (rc < 0)
        return -1;
    if (count > rows) { /* no run writes it so: a file damaged or edited (-2: exit 2) */
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: %s counts %" PRIu64 " rows but %s has %llu: the file is "
                      "damaged, or no run wrote it",
                      path, group, count, dataset, (unsigned long long)rows);
        return -2;
    }
    *complete = count;
    *more = rows - count;
    return 0;
}

void nbep_output_library_init(void)
{
    /* No clean-up at exit: after a write failure (disk full) a dataset can refuse to close,
     * and HDF5's exit handler then crashes closing it again. The process is ending anyway. */
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

/* 1 when the open file's root attribute `format` is the string FORMAT_NAME, 0 (after a line
 * saying what it is instead) when it is another, missing or no string, -2 when it cannot be
 * read (the file damaged), -1 after another failure. */
static int is_run(hid_t file, const char *path, nbep_diag *d)
{
    /* HDF5 opened the file, so a root it cannot read is the file's fault (a damaged object
     * header: "incorrect metadata checksum"), exit 2 as for any part of it (until 2026-12-05
     * exit 1, while the same damage one object further on said 2) */
    const htri_t has = H5Aexists(file, "format");
    if (has < 0) {
        HDF5_FAIL(d, path, "read the root attributes");
        return -2;
    }
    char *format = NULL;
    const char *what = "missing";
    int run;
    if (has) {
        hid_t attr = H5Aopen(file, "format", H5P_DEFAULT), type = H5I_INVALID_HID;
        const H5T_class_t cls = attr < 0 || (type = H5Aget_type(attr)) < 0
                                    ? H5T_NO_CLASS
                                    : H5Tget_class(type);
        if (cls == H5T_NO_CLASS) /* HDF5's reason, before a close clears it */
            HDF5_FAIL(d, path, "read attribute format");
        nbep__output_close_id(&type);
        nbep__output_close_id(&attr);
        if (cls == H5T_NO_CLASS)
            return -2;
        if (cls != H5T_STRING)
            what = "not a string";
        else if ((run = nbep__output_read_string_attr(file, path, "format", &format, d)) < 0)
            return run;
    }
    run = format && strcmp(format, FORMAT_NAME) == 0;
    /* a sweep's table, the file most often taken for a run */
    const bool table = format && strcmp(format, SWEEP_FORMAT_NAME) == 0;
    if (!run)
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: not an %s file (root attribute format is %s%s%s)%s", path,
                      FORMAT_NAME, format ? "\"" : what, format ? format : "",
                      format ? "\"" : "",
                      table ? ": a sweep's summary table; read summary.csv beside it, or pass "
                              "one of its run-NNNN.h5"
                            : "");
    free(format);
    return run;
}

/* For a file that is not HDF5: where it is an XDMF sidecar, ": " and what to pass instead into
 * buf (nbep_xdmf_run_of); else "". */
static void sidecar_hint(const char *path, char *buf, size_t len)
{
    char run[1024];
    buf[0] = '\0';
    if (!nbep_xdmf_run_of(path, run, sizeof run))
        return;
    if (run[0])
        snprintf(buf, len, ": the XDMF sidecar of %s, beside it; pass that file", run);
    else
        snprintf(buf, len, ": an XDMF sidecar; pass the run file beside it (RUN.h5 for RUN.xmf)");
}

nbep_status nbep__output_run_openable(const char *path, int mode, const char *what,
                                      hid_t *file_out, nbep_diag *d)
{
    struct stat sb;
    int err = access(path, mode) != 0 ? errno : stat(path, &sb) != 0 ? errno : 0;
    if (!err && !S_ISREG(sb.st_mode))
        err = S_ISDIR(sb.st_mode) ? EISDIR : EINVAL; /* a device, a pipe: no run file */
    if (err) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot %s: %s", path, what,
                      err == EINVAL ? "not a regular file" : strerror(err));
        return err == EINVAL ? NBEP_EUSAGE : nbep_status_of_open(err);
    }
    /* the signature; < 0 (cannot tell) leaves the verdict to the open */
#if H5_VERSION_GE(1, 12, 0)
    const htri_t hdf5 = H5Fis_accessible(path, H5P_DEFAULT);
#else
    const htri_t hdf5 = H5Fis_hdf5(path);
#endif
    if (hdf5 == 0) {
        char hint[1200];
        sidecar_hint(path, hint, sizeof hint);
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot %s: not an HDF5 file%s", path,
                      what, hint);
        return NBEP_EUSAGE;
    }
    hid_t fapl = nbep__output_fapl(false);
    hid_t file = H5I_INVALID_HID;
    /* A run being written is flushed in pieces (its superblock's end of file, then the data): a
     * reader that comes in between sees a file cut short, 13 opens in 30 of a run writing 300
     * frames a second. It is tried again, 20 times 50 ms apart, before it counts as cut short:
     * a truly broken file costs a second. The last try's reason stays on HDF5's error stack
     * for the message (the TRY only keeps a test's HDF5 from printing it). */
    for (int tries = 0; fapl >= 0 && tries < 20; tries++) {
        if (tries > 0)
            nanosleep(&(struct timespec){.tv_nsec = 50 * 1000 * 1000}, NULL);
        H5E_BEGIN_TRY { file = H5Fopen(path, H5F_ACC_RDONLY, fapl); } H5E_END_TRY;
        if (file >= 0)
            break;
    }
    if (file < 0) { /* HDF5's reason first: closing the fapl would clear it */
        HDF5_FAIL(d, path, "%s", what);
        nbep__output_close_id(&fapl);
        /* HDF5's signature, but no file it can open (cut short by a copy, or locked by the
         * run that writes it): not a file this command can take, as a file of another kind */
        return NBEP_EUSAGE;
    }
    nbep__output_close_id(&fapl);
    const int run = is_run(file, path, d);
    if (run > 0 && file_out)
        *file_out = file;
    else
        nbep__output_close_id(&file);
    return run > 0 ? NBEP_OK : run == 0 || run == -2 ? NBEP_EUSAGE : NBEP_EIO;
}
