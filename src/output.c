/* HDF5 output in layout "nbep-1" (SPEC "HDF5 output"); the JSON summary is summary.c's. The only file that includes hdf5.h; one writing thread (thread 0 between barriers).
 *
 * Invariants of an open nbep_output:
 * - every id field is a valid HDF5 id or H5I_INVALID_HID, so one release path closes them all;
 * - n_frames rows of each /frames dataset and n_stats rows of each /stats dataset are
 *   written; /frames@count = n_frames on disk once nbep_output_frame returned NBEP_OK.
 *
 * Crash safety (SPEC: a run killed at any moment leaves a file HDF5 tools open, holding every
 * frame written so far). Checked by the tests (kill -9 and _exit between frames) and, for
 * kills at random moments, by hand: 400 kills of a writer of back-to-back frames, 0 losses.
 * - The file uses format bounds (1.8, 1.8), not the 1.10 format. HDF5 >= 1.10 marks a file in
 *   the 1.10 format (superblock v3) "open for write" in its superblock and clears the mark only
 *   on close, so after a crash h5dump, h5py and H5Fopen refuse the file until someone runs
 *   `h5clear -s` on it; SWMR write mode leaves the same mark (only SWMR readers get past it).
 *   The 1.8 format has no such mark; it still has checksummed object headers and dense
 *   storage for large attributes.
 * - The file is built as PATH.partial and renamed once its layout is flushed: a kill during
 *   create leaves nothing at PATH.
 * - Each frame ends with a global H5Fflush: data, metadata, chunk index and the superblock's
 *   end of file, so the file on disk then holds every frame written so far, and later chunks
 *   go past that end of file. A second flush then bumps the `count` attributes (see commit):
 *   a kill inside the first can leave a half-written last row, never a counted one.
 * - A chunk-index node that splits in a flush cut short can take old frames with it; K is
 *   raised so that the index does not split for the planned frames (CHUNK_INDEX_K_MIN).
 * - The writer takes no file lock, so `nbep info` and HDF5 tools can look at a run while it
 *   runs (they see the last flushed frame), and runs work on parallel file systems without
 *   flock support. The price: nothing stops two runs from writing one file.
 *
 * Errors: HDF5's automatic printing is off (nbep_output_library_init); every negative id or
 * herr_t becomes NBEP_EIO with one line "nbep: PATH: cannot WHAT: REASON", REASON being the
 * innermost entry of HDF5's error stack, captured before any cleanup call clears the stack. */
#include "nbep/output.h"

#include "nbep/output_xdmf.h"

#include <assert.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <hdf5.h>

#include "build_info.h"
#include "output_impl.h"

/* Frames are written straight from nbep_vec3 arrays as n x 3 doubles. */
static_assert(sizeof(nbep_vec3) == 3 * sizeof(double), "nbep_vec3 must be 3 packed doubles");

#define FORMAT_NAME "nbep-1"

/* One frame per chunk, so that a reader asking for frame f reads one chunk; but a chunk is
 * capped near 4 MiB (by splitting the spheres) because HDF5 reads and writes whole chunks: a
 * reader wanting some spheres of a 10^7-sphere frame should not have to read 240 MB. */
#define FRAME_CHUNK_BYTES ((size_t)4 << 20)
/* /frames/step and /frames/time: 512 rows = 4 KiB per chunk, one file-system block, rewritten
 * in place by each frame's flush; their chunk index grows by one entry per 512 frames. */
#define SERIES_CHUNK_ROWS 512
/* /stats datasets: one row per step, appended in batches; 4096 rows = 32 KiB per chunk keeps
 * the chunk index short for runs of 10^6 steps. */
#define STATS_CHUNK_ROWS 4096
/* The chunk index of the 1.8 format is a v1 B-tree. When a node overflows it splits: half its
 * entries move to a new node written past the end of file, and the old node is rewritten in
 * place. HDF5 orders nothing within a flush, so a kill in the middle of the flush that splits
 * can leave the old node on disk without the new one (or without the superblock's new end of
 * file): frames committed long before become unreadable. A node holds 2K entries and never
 * splits before, so K is raised to cover every planned frame. The price: the node, about 48
 * bytes per entry, is rewritten with each frame, so its size is capped at the size of one
 * frame of one field (24 bytes per sphere); runs with many frames of few spheres keep some
 * risk (one split in K frames). HDF5 allows K up to 2^15 - 1; its default is 32. */
#define CHUNK_INDEX_K_MIN 32u
#define CHUNK_INDEX_K_MAX 32767u
#define CHUNK_INDEX_ENTRY_BYTES 48u
/* Longest HDF5 error description kept (they are one line; longer ones are cut). */
#define REASON_MAX 512

/* The /stats columns: dataset name = field of nbep_step_stats, and its type. Written straight
 * from the caller's array of rows, one strided column at a time, so every field must be 8
 * bytes at a multiple of 8 (checked below). */
#define STATS_COLUMN_LIST(X)                                                                 \
    X(step, I64)                                                                             \
    X(checks, U64)                                                                           \
    X(predictions, U64)                                                                      \
    X(collisions, U64)                                                                       \
    X(kinetic_energy, F64)                                                                   \
    X(potential_energy, F64)                                                                 \
    X(max_overlap, F64)

enum column_type { COL_I64, COL_U64, COL_F64 };

enum {
#define X_ENUM(field, type) STATS_COL_##field,
    STATS_COLUMN_LIST(X_ENUM)
#undef X_ENUM
    STATS_N_COLUMNS
};

static const struct stats_column {
    const char *name;       /* "/stats/<field>" */
    size_t word;            /* offset of the field in 8-byte words */
    enum column_type type;
} stats_columns[STATS_N_COLUMNS] = {
#define X_COLUMN(field, type) {"/stats/" #field, offsetof(nbep_step_stats, field) / 8, COL_##type},
    STATS_COLUMN_LIST(X_COLUMN)
#undef X_COLUMN
};

#define X_CHECK(field, type)                                                                 \
    static_assert(sizeof(((nbep_step_stats *)0)->field) == 8 &&                              \
                      offsetof(nbep_step_stats, field) % 8 == 0,                             \
                  "stats column " #field " must be an aligned 8-byte field");
STATS_COLUMN_LIST(X_CHECK)
#undef X_CHECK
static_assert(sizeof(nbep_step_stats) == 8 * STATS_N_COLUMNS,
              "every field of nbep_step_stats must be a /stats column (and no padding)");

struct nbep_output {
    char *path;                    /* owned copy, for messages */
    size_t n_spheres;
    hid_t file;
    hid_t summary;                 /* the /summary group; its json attribute comes at close */
    hid_t frame_step, frame_time;  /* /frames/step, /frames/time */
    hid_t frame_pos, frame_vel;    /* H5I_INVALID_HID when the deck did not ask for them */
    hid_t stats[STATS_N_COLUMNS];  /* all H5I_INVALID_HID when the deck did not ask for them */
    hid_t frames_count;            /* the `count` attribute of /frames */
    hid_t stats_count;             /* the `count` attribute of /stats, if any */
    hsize_t n_frames, n_stats;     /* rows written */
    hid_t ck[4];                   /* /checkpoint series (predictive runs), else invalid */
    /* the XDMF sidecar (RUN.xmf) that lets ParaView and VisIt open the run: rewritten as
     * frames come (nbep_xdmf_due) and at close; needs positions */
    bool xmf;
    int64_t *xmf_step;             /* owned, xmf_cap: every frame's step and time so far */
    double *xmf_time;
    size_t xmf_cap;
    double xmf_last;               /* monotonic seconds of the last rewrite */
};

/* Room for frame row f in the sidecar's lists; false when memory runs out. */
static bool xmf_room(nbep_output *o, size_t f)
{
    if (f < o->xmf_cap)
        return true;
    size_t cap = o->xmf_cap ? 2 * o->xmf_cap : 64;
    while (cap <= f)
        cap *= 2;
    int64_t *s = realloc(o->xmf_step, cap * sizeof *s);
    if (s)
        o->xmf_step = s;
    double *t = realloc(o->xmf_time, cap * sizeof *t);
    if (t)
        o->xmf_time = t;
    if (!s || !t)
        return false;
    o->xmf_cap = cap;
    return true;
}

static nbep_status xmf_write(nbep_output *o, nbep_diag *d)
{
    o->xmf_last = nbep_now();
    return nbep_xdmf_write(o->path, o->n_spheres, (size_t)o->n_frames, o->xmf_step, o->xmf_time,
                           o->frame_vel >= 0, d);
}

/* The per-frame columns a predictive run keeps for --resume, in nbep_events_view's order. */
static const struct ck_column {
    const char *name;
    hid_t *file_type, *mem_type;   /* HDF5's type ids are variables, not constants */
} ck_columns[4] = {
    {"/checkpoint/event_time", &H5T_IEEE_F64LE_g, &H5T_NATIVE_DOUBLE_g},
    {"/checkpoint/event_partner", &H5T_STD_U32LE_g, &H5T_NATIVE_UINT32_g},
    {"/checkpoint/event_kind", &H5T_STD_U8LE_g, &H5T_NATIVE_UINT8_g},
    {"/checkpoint/rest", &H5T_STD_I32LE_g, &H5T_NATIVE_INT32_g},
};

/* ---- errors ------------------------------------------------------------------------------ */

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

/* ---- writing helpers ----------------------------------------------------------------------- */

hid_t nbep__output_utf8_string_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    if (t >= 0 && (H5Tset_size(t, H5T_VARIABLE) < 0 || H5Tset_cset(t, H5T_CSET_UTF8) < 0))
        nbep__output_close_id(&t);
    return t;
}

/* Writes attribute name on loc: n values (a scalar when n == 0) of mem_type as file_type. */
static int write_attr(hid_t loc, const char *path, const char *name, hid_t file_type,
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

/* A UTF-8 string attribute, variable length so that h5dump prints it as text; NULL is "". */
static int write_string_attr(hid_t loc, const char *path, const char *name, const char *value,
                             nbep_diag *d)
{
    hid_t t = nbep__output_utf8_string_type();
    if (t < 0) {
        HDF5_FAIL(d, path, "make a string type for attribute %s", name);
        return -1;
    }
    const char *v = value ? value : "";
    int rc = write_attr(loc, path, name, t, t, 0, &v, d);
    nbep__output_close_id(&t);
    return rc;
}

static int make_group(nbep_output *o, const char *name, hid_t *out, nbep_diag *d)
{
    hid_t g = H5Gcreate2(o->file, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (g < 0) {
        HDF5_FAIL(d, o->path, "create group %s", name);
        return -1;
    }
    if (out)
        *out = g;
    else
        nbep__output_close_id(&g);
    return 0;
}

/* Group name with its `count` attribute (u64, 0 for now), which stays open in *count. */
static int make_group_with_count(nbep_output *o, const char *name, hid_t *count, nbep_diag *d)
{
    hid_t g = H5I_INVALID_HID, space = H5I_INVALID_HID;
    uint64_t zero = 0;
    int rc = -1;
    if (make_group(o, name, &g, d) < 0)
        return -1;
    space = H5Screate(H5S_SCALAR);
    if (space < 0 ||
        (*count = H5Acreate2(g, "count", H5T_STD_U64LE, space, H5P_DEFAULT, H5P_DEFAULT)) < 0 ||
        H5Awrite(*count, H5T_NATIVE_UINT64, &zero) < 0) {
        HDF5_FAIL(d, o->path, "create attribute count of %s", name);
        goto done;
    }
    rc = 0;
done:
    nbep__output_close_id(&space);
    nbep__output_close_id(&g);
    return rc;
}

/* A fixed-size contiguous dataset holding buf (dims[0] * ... values of mem_type). */
static int write_fixed(nbep_output *o, const char *name, hid_t file_type, hid_t mem_type,
                       int rank, const hsize_t *dims, const void *buf, nbep_diag *d)
{
    int rc = -1;
    hid_t ds = H5I_INVALID_HID, space = H5Screate_simple(rank, dims, NULL);
    if (space < 0) {
        HDF5_FAIL(d, o->path, "make the dataspace of %s", name);
        goto done;
    }
    ds = H5Dcreate2(o->file, name, file_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (ds < 0) {
        HDF5_FAIL(d, o->path, "create %s", name);
        goto done;
    }
    if (H5Sget_simple_extent_npoints(space) > 0 &&
        H5Dwrite(ds, mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
        HDF5_FAIL(d, o->path, "write %s", name);
        goto done;
    }
    rc = 0;
done:
    nbep__output_close_id(&ds);
    nbep__output_close_id(&space);
    return rc;
}

/* An empty chunked dataset whose first dimension grows without limit; tail holds the other
 * rank - 1 dimensions (fixed), chunk the chunk shape. */
static int create_series(nbep_output *o, const char *name, hid_t file_type, int rank,
                         const hsize_t *tail, const hsize_t *chunk, hid_t *out, nbep_diag *d)
{
    int rc = -1;
    hsize_t dims[3] = {0}, maxdims[3] = {H5S_UNLIMITED};
    assert(rank >= 1 && rank <= 3);
    for (int k = 1; k < rank; k++)
        dims[k] = maxdims[k] = tail[k - 1];
    hid_t space = H5Screate_simple(rank, dims, maxdims);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (space < 0 || dcpl < 0 || H5Pset_chunk(dcpl, rank, chunk) < 0) {
        HDF5_FAIL(d, o->path, "set up the chunked layout of %s", name);
        goto done;
    }
    *out = H5Dcreate2(o->file, name, file_type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    if (*out < 0) {
        HDF5_FAIL(d, o->path, "create %s", name);
        goto done;
    }
    rc = 0;
done:
    nbep__output_close_id(&dcpl);
    nbep__output_close_id(&space);
    return rc;
}

/* Grows ds to new_rows rows and writes count (rank numbers: rows first) at row `first` from
 * buf as described by mem_type and mem_space. */
static int append_rows(const nbep_output *o, hid_t ds, const char *name, int rank,
                       hsize_t first, const hsize_t *count, hid_t mem_type, hid_t mem_space,
                       const void *buf, nbep_diag *d)
{
    hsize_t dims[3], start[3] = {first, 0, 0};
    dims[0] = first + count[0];
    for (int k = 1; k < rank; k++)
        dims[k] = count[k];
    if (H5Dset_extent(ds, dims) < 0) {
        HDF5_FAIL(d, o->path, "extend %s to %llu rows", name, (unsigned long long)dims[0]);
        return -1;
    }
    hsize_t points = 1;
    for (int k = 0; k < rank; k++)
        points *= count[k];
    if (points == 0)
        return 0;   /* a frame of a scene without spheres: the extent is all there is */
    int rc = -1;
    hid_t file_space = H5Dget_space(ds);
    if (file_space < 0 ||
        H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, NULL, count, NULL) < 0) {
        HDF5_FAIL(d, o->path, "select rows of %s", name);
        goto done;
    }
    if (H5Dwrite(ds, mem_type, mem_space, file_space, H5P_DEFAULT, buf) < 0) {
        HDF5_FAIL(d, o->path, "write rows %llu.. of %s", (unsigned long long)first, name);
        goto done;
    }
    rc = 0;
done:
    nbep__output_close_id(&file_space);
    return rc;
}

/* ---- create -------------------------------------------------------------------------------- */

static int write_root_attrs(nbep_output *o, const nbep_scene *sc, int threads, nbep_diag *d)
{
    hid_t root = o->file;
    const char *p = o->path;
    int64_t threads64 = threads;
    double gravity[3] = {sc->gravity.x, sc->gravity.y, sc->gravity.z};
    if (write_string_attr(root, p, "format", FORMAT_NAME, d) < 0 ||
        write_string_attr(root, p, "version", NBEP_VERSION, d) < 0 ||
        write_string_attr(root, p, "build_flags", NBEP_BUILD_FLAGS, d) < 0 ||
        write_string_attr(root, p, "build_commit", NBEP_BUILD_COMMIT, d) < 0 ||
        write_string_attr(root, p, "algorithm", sc->algorithm, d) < 0 ||
        write_attr(root, p, "steps", H5T_STD_U64LE, H5T_NATIVE_UINT64, 0, &sc->steps, d) < 0 ||
        write_attr(root, p, "dt", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &sc->dt, d) < 0 ||
        write_attr(root, p, "threads", H5T_STD_I64LE, H5T_NATIVE_INT64, 0, &threads64, d) < 0 ||
        write_attr(root, p, "seed", H5T_STD_U64LE, H5T_NATIVE_UINT64, 0, &sc->seed, d) < 0 ||
        write_attr(root, p, "restitution", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0,
                   &sc->restitution, d) < 0 ||
        write_attr(root, p, "gravity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3, gravity, d) < 0 ||
        write_string_attr(root, p, "deck_path", sc->deck_path, d) < 0 ||
        write_string_attr(root, p, "deck", sc->deck_text, d) < 0 ||
        write_string_attr(root, p, "overrides", sc->overrides, d) < 0)
        return -1;
    return 0;
}

static int write_bodies(nbep_output *o, const nbep_state *s, nbep_diag *d)
{
    hsize_t n1[1] = {s->n}, n3[2] = {s->n, 3};
    hsize_t p1[1] = {s->n_planes}, p3[2] = {s->n_planes, 3};
    if (make_group(o, "/spheres", NULL, d) < 0 ||
        write_fixed(o, "/spheres/radius", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, n1, s->radius,
                    d) < 0 ||
        write_fixed(o, "/spheres/mass", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, n1, s->mass, d) <
            0 ||
        write_fixed(o, "/spheres/acceleration", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, n3,
                    s->acc, d) < 0 ||
        make_group(o, "/planes", NULL, d) < 0 ||
        write_fixed(o, "/planes/normal", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 2, p3,
                    s->plane_normal, d) < 0 ||
        write_fixed(o, "/planes/offset", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 1, p1,
                    s->plane_offset, d) < 0)
        return -1;
    return 0;
}

static int create_frames(nbep_output *o, const nbep_scene *sc, nbep_diag *d)
{
    size_t n = sc->state.n;
    size_t per_chunk = FRAME_CHUNK_BYTES / (3 * sizeof(double));
    if (n < per_chunk)
        per_chunk = n;
    if (per_chunk == 0)
        per_chunk = 1;   /* HDF5 wants chunk sizes >= 1, even for a scene without spheres */
    hsize_t tail[2] = {n, 3}, chunk[3] = {1, per_chunk, 3}, series[1] = {SERIES_CHUNK_ROWS};
    if (make_group_with_count(o, "/frames", &o->frames_count, d) < 0 ||
        create_series(o, "/frames/step", H5T_STD_I64LE, 1, NULL, series, &o->frame_step, d) <
            0 ||
        create_series(o, "/frames/time", H5T_IEEE_F64LE, 1, NULL, series, &o->frame_time, d) <
            0)
        return -1;
    if (sc->out_position && create_series(o, "/frames/position", H5T_IEEE_F64LE, 3, tail,
                                          chunk, &o->frame_pos, d) < 0)
        return -1;
    if (sc->out_velocity && create_series(o, "/frames/velocity", H5T_IEEE_F64LE, 3, tail,
                                          chunk, &o->frame_vel, d) < 0)
        return -1;
    if (strcmp(sc->algorithm, "predictive") == 0) {
        hsize_t ck_tail[1] = {n}, ck_chunk[2] = {1, per_chunk};
        if (make_group(o, "/checkpoint", NULL, d) < 0)
            return -1;
        for (int c = 0; c < 4; c++)
            if (create_series(o, ck_columns[c].name, *ck_columns[c].file_type, 2, ck_tail,
                              ck_chunk, &o->ck[c], d) < 0)
                return -1;
    }
    return 0;
}

static hid_t column_file_type(enum column_type t)
{
    return t == COL_I64 ? H5T_STD_I64LE : t == COL_U64 ? H5T_STD_U64LE : H5T_IEEE_F64LE;
}

static hid_t column_mem_type(enum column_type t)
{
    return t == COL_I64 ? H5T_NATIVE_INT64 : t == COL_U64 ? H5T_NATIVE_UINT64 : H5T_NATIVE_DOUBLE;
}

static int create_stats(nbep_output *o, nbep_diag *d)
{
    hsize_t chunk[1] = {STATS_CHUNK_ROWS};
    if (make_group_with_count(o, "/stats", &o->stats_count, d) < 0)
        return -1;
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        if (create_series(o, stats_columns[c].name, column_file_type(stats_columns[c].type), 1,
                          NULL, chunk, &o->stats[c], d) < 0)
            return -1;
    return 0;
}

/* Closes every id, ignoring errors (the failure paths; nbep_output_close checks them). */
static void release(nbep_output **op)
{
    nbep_output *o = *op;
    if (!o)
        return;
    nbep__output_close_id(&o->frame_step);
    nbep__output_close_id(&o->frame_time);
    nbep__output_close_id(&o->frame_pos);
    nbep__output_close_id(&o->frame_vel);
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        nbep__output_close_id(&o->stats[c]);
    for (int c = 0; c < 4; c++)
        nbep__output_close_id(&o->ck[c]);
    nbep__output_close_id(&o->frames_count);
    nbep__output_close_id(&o->stats_count);
    nbep__output_close_id(&o->summary);
    nbep__output_close_id(&o->file);
    free(o->xmf_step);
    free(o->xmf_time);
    free(o->path);
    free(o);
    *op = NULL;
}

/* The frames the deck plans: step 0, every output_every-th step, and the last step. */
static uint64_t planned_frames(const nbep_scene *sc)
{
    uint64_t every = sc->output_every ? sc->output_every : 1;
    return sc->steps / every + 1 + (sc->steps % every != 0);
}

/* File creation properties: a chunk index K for the planned frames (see CHUNK_INDEX_K_MIN). */
static hid_t make_fcpl(const nbep_scene *sc)
{
    uint64_t frame_bytes = 3 * sizeof(double) * (uint64_t)sc->state.n;
    uint64_t k = (planned_frames(sc) + 1) / 2;
    uint64_t k_cap = frame_bytes / (2 * CHUNK_INDEX_ENTRY_BYTES);
    if (k > k_cap)
        k = k_cap;
    if (k > CHUNK_INDEX_K_MAX)
        k = CHUNK_INDEX_K_MAX;
    if (k < CHUNK_INDEX_K_MIN)
        k = CHUNK_INDEX_K_MIN;
    hid_t fcpl = H5Pcreate(H5P_FILE_CREATE);
    if (fcpl >= 0 && H5Pset_istore_k(fcpl, (unsigned)k) < 0)
        nbep__output_close_id(&fcpl);
    return fcpl;
}

/* File access for the writer (1.8 format bounds, no lock) or a reader (default bounds, a
 * shared lock where the file system has locks); see the top of this file for why. */
static hid_t make_fapl(bool writer)
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

nbep_status nbep_output_create(const char *path, const nbep_scene *sc, int threads,
                               nbep_output **out, nbep_diag *d)
{
    /* The file is made under a temporary name and renamed to path once its layout is on
     * disk: a run killed while creating leaves no half-made file at path (only PATH.partial,
     * which the next run overwrites), and an older file at path survives until then. */
    static const char suffix[] = ".partial";
    nbep_output *o = calloc(1, sizeof *o);
    char *tmp = malloc(strlen(path) + sizeof suffix);
    if (!o || !tmp || !(o->path = strdup(path))) {
        free(o);
        free(tmp);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: %s: no memory for the output handle", path);
    }
    strcat(strcpy(tmp, path), suffix);
    o->n_spheres = sc->state.n;
    o->file = o->summary = H5I_INVALID_HID;
    o->frame_step = o->frame_time = o->frame_pos = o->frame_vel = H5I_INVALID_HID;
    o->frames_count = o->stats_count = H5I_INVALID_HID;
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        o->stats[c] = H5I_INVALID_HID;
    for (int c = 0; c < 4; c++)
        o->ck[c] = H5I_INVALID_HID;

    hid_t fapl = make_fapl(true), fcpl = make_fcpl(sc);
    if (fapl < 0 || fcpl < 0) {
        HDF5_FAIL(d, path, "set up file properties");
        nbep__output_close_id(&fapl);
        nbep__output_close_id(&fcpl);
        goto fail_uncreated;
    }
    o->file = H5Fcreate(tmp, H5F_ACC_TRUNC, fcpl, fapl);
    if (o->file < 0) {
        HDF5_FAIL(d, path, "create the output file");
        nbep__output_close_id(&fapl);
        nbep__output_close_id(&fcpl);
        goto fail_uncreated;
    }
    nbep__output_close_id(&fapl);
    nbep__output_close_id(&fcpl);

    if (write_root_attrs(o, sc, threads, d) < 0 || write_bodies(o, &sc->state, d) < 0 ||
        create_frames(o, sc, d) < 0 || (sc->out_stats && create_stats(o, d) < 0) ||
        make_group(o, "/summary", &o->summary, d) < 0)
        goto fail;
    if (H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0) {
        HDF5_FAIL(d, path, "flush the file");
        goto fail;
    }
    /* HDF5 keeps writing through its open descriptor, whatever the file's name. */
    if (rename(tmp, path) != 0) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: cannot create the output file: %s",
                      path, strerror(errno));
        goto fail;
    }
    free(tmp);
    o->xmf = sc->out_position;
    if (!o->xmf) { /* a sidecar of an older run at this path would describe frames not here */
        char *x = nbep_xdmf_path(path);
        if (x)
            remove(x);
        free(x);
    } else if (!xmf_room(o, (size_t)planned_frames(sc))) {
        release(&o);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: %s: no memory for the frame list", path);
    }
    *out = o;
    return NBEP_OK;
fail:
    release(&o);
    remove(tmp);   /* bad output leaves no file behind (STYLE 4) */
    free(tmp);
    return NBEP_EIO;
fail_uncreated:
    release(&o);
    free(tmp);
    return NBEP_EIO;
}

/* ---- frames, stats, close ------------------------------------------------------------------ */

/* Makes the rows written so far durable in two flushes: the first writes the rows (data, then
 * extents and chunk indexes), the second the `count` attributes saying how many rows are
 * complete. HDF5 orders nothing within one flush: a kill during the first can leave a last row
 * whose extent is on disk but whose chunk is not (it reads as zeros, or fails to read). The
 * counts change only after that flush returned, and each is one small in-place write of an
 * object header, so they never count such a row. */
static int commit(nbep_output *o, hsize_t frames, nbep_diag *d)
{
    /* Global scope: the superblock's end-of-file address goes out with the metadata. */
    if (H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0) {
        HDF5_FAIL(d, o->path, "flush the file");
        return -1;
    }
    uint64_t n_frames = frames, n_stats = o->n_stats;
    if (H5Awrite(o->frames_count, H5T_NATIVE_UINT64, &n_frames) < 0) {
        HDF5_FAIL(d, o->path, "update the count attribute of /frames");
        return -1;
    }
    if (o->stats_count >= 0 && H5Awrite(o->stats_count, H5T_NATIVE_UINT64, &n_stats) < 0) {
        HDF5_FAIL(d, o->path, "update the count attribute of /stats");
        return -1;
    }
    if (H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0) {
        HDF5_FAIL(d, o->path, "flush the row counts");
        return -1;
    }
    o->n_frames = frames;
    return 0;
}

nbep_status nbep_output_frame(nbep_output *o, int64_t step, double dt, const nbep_state *s,
                              nbep_diag *d)
{
    return nbep_output_frame_events(o, step, dt, s, NULL, d);
}

nbep_status nbep_output_frame_events(nbep_output *o, int64_t step, double dt,
                                     const nbep_state *s, const nbep_events_view *ev,
                                     nbep_diag *d)
{
    assert(s->n == o->n_spheres);
    /* The module edge (STYLE 7): never put a NaN or inf in a file. */
    if (!nbep_state_all_finite(s))
        NBEP_FAIL(d, NBEP_ENUMERIC,
                  "nbep: %s: step %" PRId64 " has a non-finite position or velocity; frame not "
                  "written",
                  o->path, step);
    double t = (double)step * dt;
    hsize_t f = o->n_frames, one[1] = {1}, vec[3] = {1, s->n, 3}, flat = 3 * (hsize_t)s->n;
    hid_t one_space = H5Screate_simple(1, one, NULL);
    hid_t vec_space = H5Screate_simple(1, &flat, NULL);
    nbep_status st = NBEP_EIO;
    if (one_space < 0 || vec_space < 0) {
        HDF5_FAIL(d, o->path, "make the dataspaces of frame %llu", (unsigned long long)f);
        goto done;
    }
    /* Which rows are complete is said by the count attributes (see commit), not by the
     * datasets' lengths, so the order of these appends does not matter for crash safety. */
    if (o->frame_pos >= 0 && append_rows(o, o->frame_pos, "/frames/position", 3, f, vec,
                                         H5T_NATIVE_DOUBLE, vec_space, s->pos, d) < 0)
        goto done;
    if (o->frame_vel >= 0 && append_rows(o, o->frame_vel, "/frames/velocity", 3, f, vec,
                                         H5T_NATIVE_DOUBLE, vec_space, s->vel, d) < 0)
        goto done;
    if (ev && o->ck[0] >= 0) {
        hsize_t row[2] = {1, s->n}, nn = s->n;
        hid_t row_space = H5Screate_simple(1, &nn, NULL);
        const void *cols[4] = {ev->time, ev->partner, ev->kind, ev->rest};
        int bad = row_space < 0;
        for (int c = 0; c < 4 && !bad; c++)
            bad = append_rows(o, o->ck[c], ck_columns[c].name, 2, f, row,
                              *ck_columns[c].mem_type, row_space, cols[c], d) < 0;
        nbep__output_close_id(&row_space);
        if (bad)
            goto done;
    }
    if (append_rows(o, o->frame_time, "/frames/time", 1, f, one, H5T_NATIVE_DOUBLE, one_space,
                    &t, d) < 0 ||
        append_rows(o, o->frame_step, "/frames/step", 1, f, one, H5T_NATIVE_INT64, one_space,
                    &step, d) < 0)
        goto done;
    if (commit(o, f + 1, d) < 0)
        goto done;
    st = NBEP_OK;
    if (o->xmf) {
        if (!xmf_room(o, (size_t)f)) {
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the frame list",
                          o->path);
            st = NBEP_ENOMEM;
            goto done;
        }
        o->xmf_step[f] = step;
        o->xmf_time[f] = t;
        if (nbep_xdmf_due((size_t)o->n_frames, nbep_now() - o->xmf_last))
            st = xmf_write(o, d);
    }
done:
    nbep__output_close_id(&one_space);
    nbep__output_close_id(&vec_space);
    return st;
}

nbep_status nbep_output_stats(nbep_output *o, const nbep_step_stats *rows, size_t count,
                              nbep_diag *d)
{
    if (count == 0)
        return NBEP_OK;
    assert(o->stats[0] >= 0 && "nbep_output_stats called but the deck asked for no stats");
    if (o->stats[0] < 0)
        NBEP_FAIL(d, NBEP_EIO, "nbep: %s: cannot write /stats: the deck asked for no stats",
                  o->path);
    /* rows seen as count x STATS_N_COLUMNS 8-byte words; column c is every STATS_N_COLUMNS-th
     * word from word c, so each column goes out without copying it. */
    hsize_t words = (hsize_t)count * STATS_N_COLUMNS, n[1] = {count};
    hid_t mem = H5Screate_simple(1, &words, NULL);
    nbep_status st = NBEP_EIO;
    if (mem < 0) {
        HDF5_FAIL(d, o->path, "make the dataspace of %zu stats rows", count);
        goto done;
    }
    for (int c = 0; c < STATS_N_COLUMNS; c++) {
        hsize_t start[1] = {stats_columns[c].word}, stride[1] = {STATS_N_COLUMNS};
        if (H5Sselect_hyperslab(mem, H5S_SELECT_SET, start, stride, n, NULL) < 0) {
            HDF5_FAIL(d, o->path, "select column %s of the stats rows", stats_columns[c].name);
            goto done;
        }
        if (append_rows(o, o->stats[c], stats_columns[c].name, 1, o->n_stats, n,
                        column_mem_type(stats_columns[c].type), mem, rows, d) < 0)
            goto done;
    }
    o->n_stats += count;
    st = NBEP_OK;
done:
    nbep__output_close_id(&mem);
    return st;
}

/* Closes an id and reports a failure (the close flushes what belongs to it). */
static int checked_close(hid_t *id, const char *path, const char *what, nbep_diag *d)
{
    int rc = 0;
    if (*id >= 0 && H5Idec_ref(*id) < 0) {
        HDF5_FAIL(d, path, "close %s", what);
        rc = -1;
    }
    *id = H5I_INVALID_HID;
    return rc;
}

nbep_status nbep_output_close(nbep_output **op, const nbep_summary *s, nbep_diag *d)
{
    if (!op || !*op)
        return NBEP_OK;
    nbep_output *o = *op;
    /* Stats rows appended after the last frame get counted too. */
    int rc = commit(o, o->n_frames, d);
    if (rc == 0 && o->xmf && o->n_frames > 0 && xmf_write(o, d) != NBEP_OK)
        rc = -1;
    if (s && rc == 0) {
        char *json = nbep_summary_to_json(s);
        if (!json) {
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the JSON summary",
                          o->path);
            rc = -1;
        } else {
            rc = write_string_attr(o->summary, o->path, "json", json, d);
            free(json);
        }
    }
    rc |= checked_close(&o->frame_step, o->path, "/frames/step", d);
    rc |= checked_close(&o->frame_time, o->path, "/frames/time", d);
    rc |= checked_close(&o->frame_pos, o->path, "/frames/position", d);
    rc |= checked_close(&o->frame_vel, o->path, "/frames/velocity", d);
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        rc |= checked_close(&o->stats[c], o->path, stats_columns[c].name, d);
    for (int c = 0; c < 4; c++)
        rc |= checked_close(&o->ck[c], o->path, ck_columns[c].name, d);
    rc |= checked_close(&o->frames_count, o->path, "attribute count of /frames", d);
    rc |= checked_close(&o->stats_count, o->path, "attribute count of /stats", d);
    rc |= checked_close(&o->summary, o->path, "/summary", d);
    rc |= checked_close(&o->file, o->path, "the file", d);
    release(op);
    return rc ? NBEP_EIO : NBEP_OK;
}

void nbep_output_library_init(void)
{
    /* No clean-up at exit: after a write failure (disk full) a dataset can refuse to close,
     * and HDF5's exit handler then crashes closing it again. The process is ending anyway. */
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

/* ---- info ---------------------------------------------------------------------------------- */

/* Reads a scalar string attribute (variable or fixed length) into a malloc'd string. */
static int read_string_attr(hid_t loc, const char *path, const char *name, char **out,
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

static int read_attr(hid_t loc, const char *path, const char *name, hid_t mem_type, void *buf,
                     nbep_diag *d)
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

/* The first dimension of dataset name (its row count). */
static int dataset_rows(hid_t file, const char *path, const char *name, hsize_t *rows,
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

/* Reads row `row` of the 1-D dataset name as mem_type. */
static int read_row(hid_t file, const char *path, const char *name, hsize_t row,
                    hid_t mem_type, void *buf, nbep_diag *d)
{
    hsize_t one[1] = {1}, start[1] = {row};
    int rc = -1;
    hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
    hid_t space = ds < 0 ? H5I_INVALID_HID : H5Dget_space(ds);
    hid_t mem = H5Screate_simple(1, one, NULL);
    if (space < 0 || mem < 0 ||
        H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, one, NULL) < 0 ||
        H5Dread(ds, mem_type, mem, space, H5P_DEFAULT, buf) < 0) {
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

/* x with the fewest of 15, 16 or 17 significant digits that read back as x: "0.9", not
 * "0.90000000000000002", yet two different values never print alike. */
static const char *human_double(double x, char buf[32])
{
    for (int digits = 15; digits < 17; digits++) {
        snprintf(buf, 32, "%.*g", digits, x);
        if (strtod(buf, NULL) == x)
            return buf;
    }
    snprintf(buf, 32, "%.17g", x);
    return buf;
}

/* Everything `nbep info` prints, gathered before printing so that a bad file prints nothing
 * but its one error line. */
typedef struct run_info {
    char *version, *build_flags, *build_commit, *algorithm, *overrides, *summary;
    uint64_t steps, seed;
    int64_t threads;
    double dt, restitution, gravity[3];
    hsize_t spheres, planes;
    uint64_t frames, stats_rows;           /* complete rows: the count attributes */
    hsize_t frames_more, stats_more;       /* rows past them, cut off by a crash */
    bool has_stats;
    int64_t last_step;
    double last_time;
} run_info;

static void run_info_fini(run_info *r)
{
    free(r->version);
    free(r->build_flags);
    free(r->build_commit);
    free(r->algorithm);
    free(r->overrides);
    free(r->summary);
}

/* Prints a multi-line value with every line after the first indented under the first. */
static void print_lines(FILE *f, const char *label, const char *text)
{
    fprintf(f, "%-13s%s", label, text[0] ? "" : "\n");
    for (const char *line = text; *line;) {
        size_t len = strcspn(line, "\n");
        fprintf(f, "%s%.*s\n", line == text ? "" : "             ", (int)len, line);
        line += len + (line[len] == '\n');
    }
}

/* Complete rows of group's datasets (its count attribute; the length of dataset when a file
 * has no such attribute) and how many rows dataset holds past them. */
static int complete_rows(hid_t file, const char *path, const char *group, const char *dataset,
                         uint64_t *complete, hsize_t *more, nbep_diag *d)
{
    hsize_t rows;
    if (dataset_rows(file, path, dataset, &rows, d) < 0)
        return -1;
    htri_t has = H5Aexists_by_name(file, group, "count", H5P_DEFAULT);
    hid_t g = has > 0 ? H5Gopen2(file, group, H5P_DEFAULT) : H5I_INVALID_HID;
    if (has < 0 || (has > 0 && g < 0)) {
        HDF5_FAIL(d, path, "look for the count attribute of %s", group);
        return -1;
    }
    uint64_t count = rows;
    int rc = has > 0 ? read_attr(g, path, "count", H5T_NATIVE_UINT64, &count, d) : 0;
    nbep__output_close_id(&g);
    if (rc < 0)
        return -1;
    if (count > rows) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: %s counts %" PRIu64 " rows but %s has %llu",
                      path, group, count, dataset, (unsigned long long)rows);
        return -1;
    }
    *complete = count;
    *more = rows - count;
    return 0;
}

static int gather_info(hid_t file, const char *path, run_info *r, nbep_diag *d)
{
    htri_t has = H5Aexists(file, "format");
    if (has < 0) {
        HDF5_FAIL(d, path, "read the root attributes");
        return -1;
    }
    char *format = NULL;
    if (!has || read_string_attr(file, path, "format", &format, d) < 0 ||
        strcmp(format, FORMAT_NAME) != 0) {
        if (!has || format)
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: not an nbep-1 file (root attribute format is %s%s%s)", path,
                          format ? "\"" : "missing", format ? format : "", format ? "\"" : "");
        free(format);
        return -1;
    }
    free(format);
    if (read_string_attr(file, path, "version", &r->version, d) < 0 ||
        read_string_attr(file, path, "build_flags", &r->build_flags, d) < 0 ||
        read_string_attr(file, path, "build_commit", &r->build_commit, d) < 0 ||
        read_string_attr(file, path, "algorithm", &r->algorithm, d) < 0 ||
        read_string_attr(file, path, "overrides", &r->overrides, d) < 0 ||
        read_attr(file, path, "steps", H5T_NATIVE_UINT64, &r->steps, d) < 0 ||
        read_attr(file, path, "dt", H5T_NATIVE_DOUBLE, &r->dt, d) < 0 ||
        read_attr(file, path, "threads", H5T_NATIVE_INT64, &r->threads, d) < 0 ||
        read_attr(file, path, "seed", H5T_NATIVE_UINT64, &r->seed, d) < 0 ||
        read_attr(file, path, "restitution", H5T_NATIVE_DOUBLE, &r->restitution, d) < 0 ||
        read_attr(file, path, "gravity", H5T_NATIVE_DOUBLE, r->gravity, d) < 0 ||
        dataset_rows(file, path, "/spheres/radius", &r->spheres, d) < 0 ||
        dataset_rows(file, path, "/planes/offset", &r->planes, d) < 0 ||
        complete_rows(file, path, "/frames", "/frames/step", &r->frames, &r->frames_more, d) <
            0)
        return -1;
    if (r->frames > 0 &&
        (read_row(file, path, "/frames/step", r->frames - 1, H5T_NATIVE_INT64, &r->last_step,
                  d) < 0 ||
         read_row(file, path, "/frames/time", r->frames - 1, H5T_NATIVE_DOUBLE, &r->last_time,
                  d) < 0))
        return -1;
    htri_t stats = H5Lexists(file, "/stats", H5P_DEFAULT);
    if (stats < 0) {
        HDF5_FAIL(d, path, "look for /stats");
        return -1;
    }
    r->has_stats = stats > 0;
    if (r->has_stats &&
        complete_rows(file, path, "/stats", "/stats/step", &r->stats_rows, &r->stats_more, d) < 0)
        return -1;
    htri_t summary = H5Aexists_by_name(file, "/summary", "json", H5P_DEFAULT);
    if (summary < 0) {
        HDF5_FAIL(d, path, "look for the /summary json attribute");
        return -1;
    }
    if (summary > 0) {
        hid_t g = H5Gopen2(file, "/summary", H5P_DEFAULT);
        if (g < 0) {
            HDF5_FAIL(d, path, "open /summary");
            return -1;
        }
        int rc = read_string_attr(g, path, "json", &r->summary, d);
        nbep__output_close_id(&g);
        if (rc < 0)
            return -1;
    }
    return 0;
}

nbep_status nbep_output_info(const char *path, FILE *f, nbep_diag *d)
{
    hid_t fapl = make_fapl(false);
    if (fapl < 0) {
        HDF5_FAIL(d, path, "set up file access properties");
        return NBEP_EIO;
    }
    hid_t file = H5Fopen(path, H5F_ACC_RDONLY, fapl);
    if (file < 0) {
        HDF5_FAIL(d, path, "open as an HDF5 file");
        nbep__output_close_id(&fapl);
        return NBEP_EIO;
    }
    nbep__output_close_id(&fapl);
    run_info r = {0};
    int rc = gather_info(file, path, &r, d);
    if (H5Fclose(file) < 0 && rc == 0) {
        HDF5_FAIL(d, path, "close the file");
        rc = -1;
    }
    if (rc == 0) {
        fprintf(f, "%-13s%s\n", "file:", path);
        fprintf(f, "%-13s%s\n", "format:", FORMAT_NAME);
        fprintf(f, "%-13s%s (%s, commit %s)\n", "version:", r.version, r.build_flags,
                r.build_commit);
        fprintf(f, "%-13s%s\n", "algorithm:", r.algorithm);
        fprintf(f, "%-13s%llu\n", "spheres:", (unsigned long long)r.spheres);
        fprintf(f, "%-13s%llu\n", "planes:", (unsigned long long)r.planes);
        fprintf(f, "%-13s%" PRIu64 "\n", "steps asked:", r.steps);
        char b0[32], b1[32], b2[32];
        fprintf(f, "%-13s%s\n", "dt:", human_double(r.dt, b0));
        fprintf(f, "%-13s%" PRId64 "\n", "threads:", r.threads);
        fprintf(f, "%-13s%" PRIu64 "\n", "seed:", r.seed);
        fprintf(f, "%-13s%s\n", "restitution:", human_double(r.restitution, b0));
        fprintf(f, "%-13s[%s, %s, %s]\n", "gravity:", human_double(r.gravity[0], b0),
                human_double(r.gravity[1], b1), human_double(r.gravity[2], b2));
        if (r.overrides[0])
            print_lines(f, "overrides:", r.overrides);
        fprintf(f, "%-13s%" PRIu64, "frames:", r.frames);
        if (r.frames > 0)
            fprintf(f, " (last: step %" PRId64 ", time %s)", r.last_step,
                    human_double(r.last_time, b0));
        if (r.frames_more)
            fprintf(f, ", and %llu incomplete (its write was cut short: a kill, or a full disk)",
                    (unsigned long long)r.frames_more);
        fprintf(f, "\n");
        if (r.has_stats)
            fprintf(f, "%-13s%" PRIu64 "%s\n", "stats rows:", r.stats_rows,
                    r.stats_more ? ", and incomplete ones after them" : "");
        else
            fprintf(f, "%-13snone (not recorded)\n", "stats rows:");
        if (r.summary)
            print_lines(f, "summary:", r.summary);
        else
            fprintf(f, "%-13snone (run interrupted or still running)\n", "summary:");
    }
    run_info_fini(&r);
    return rc == 0 ? NBEP_OK : NBEP_EIO;
}

/* ---- resume -------------------------------------------------------------------------------- */

void nbep_resume_fini(nbep_resume *r)
{
    if (!r)
        return;
    free(r->pos);
    free(r->vel);
    free(r->event_time);
    free(r->event_partner);
    free(r->event_kind);
    free(r->rest);
    memset(r, 0, sizeof *r);
}

/* Reads row `row` of dataset name (rows first; the rest of the shape is `per_row` values of
 * mem_type) into buf. */
static int read_dataset_row(hid_t file, const char *path, const char *name, hsize_t row,
                            hsize_t per_row, hid_t mem_type, void *buf, nbep_diag *d)
{
    hsize_t dims[3] = {0, 0, 0}, start[3] = {row, 0, 0}, count[3] = {1, 0, 0};
    int rc = -1;
    hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
    hid_t space = ds < 0 ? H5I_INVALID_HID : H5Dget_space(ds);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_dims(space, dims, NULL);
    hid_t mem = H5Screate_simple(1, &per_row, NULL);
    if (rank < 1 || rank > 3 || mem < 0) {
        HDF5_FAIL(d, path, "read the shape of %s", name);
        goto done;
    }
    hsize_t values = 1;
    for (int k = 1; k < rank; k++)
        values *= (count[k] = dims[k]);
    if (values != per_row || row >= dims[0]) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: %s has the wrong shape for this deck's spheres", path, name);
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

/* Opens dataset name and cuts it to `rows` rows. */
static int open_cut(nbep_output *o, const char *name, hsize_t rows, hid_t *out, nbep_diag *d)
{
    hsize_t dims[3];
    *out = H5Dopen2(o->file, name, H5P_DEFAULT);
    hid_t space = *out < 0 ? H5I_INVALID_HID : H5Dget_space(*out);
    int rank = space < 0 ? -1 : H5Sget_simple_extent_dims(space, dims, NULL);
    nbep__output_close_id(&space);
    if (rank < 1) {
        HDF5_FAIL(d, o->path, "open %s", name);
        return -1;
    }
    dims[0] = rows;
    if (H5Dset_extent(*out, dims) < 0) {
        HDF5_FAIL(d, o->path, "cut %s to %llu rows", name, (unsigned long long)rows);
        return -1;
    }
    return 0;
}

/* The same deck? Sphere and plane counts, radii and masses must match bit for bit: -2 when
 * they do not, -1 when the file cannot be read. */
static int same_bodies(hid_t file, const char *path, const nbep_scene *sc, nbep_diag *d)
{
    const nbep_state *s = &sc->state;
    hsize_t n = 0, np = 0;
    if (dataset_rows(file, path, "/spheres/radius", &n, d) < 0 ||
        dataset_rows(file, path, "/planes/offset", &np, d) < 0)
        return -1;
    if (n != s->n || np != s->n_planes) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s holds %llu spheres and %llu planes but %s makes %zu and %zu; "
                      "resume with the deck (and --set options) that made it",
                      path, (unsigned long long)n, (unsigned long long)np, sc->deck_path, s->n,
                      s->n_planes);
        return -2;
    }
    double *buf = malloc((s->n ? s->n : 1) * sizeof *buf);
    if (!buf) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to read %s", path);
        return -1;
    }
    int rc = 0;
    const char *names[2] = {"/spheres/radius", "/spheres/mass"};
    const double *want[2] = {s->radius, s->mass};
    for (int k = 0; k < 2 && rc == 0; k++) {
        hid_t ds = H5Dopen2(file, names[k], H5P_DEFAULT);
        if (ds < 0 || (s->n && H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT,
                                       buf) < 0)) {
            HDF5_FAIL(d, path, "read %s", names[k]);
            rc = -1;
        } else if (s->n && memcmp(buf, want[k], s->n * sizeof *buf) != 0) {
            nbep_diag_add(d, __FILE__, __LINE__,
                          "nbep: %s: %s differ from what %s makes; resume with the deck (and "
                          "--set options) that made it",
                          path, names[k] + 9, sc->deck_path);
            rc = -2;
        }
        nbep__output_close_id(&ds);
    }
    free(buf);
    return rc;
}

nbep_status nbep_output_open_resume(const char *path, const nbep_scene *sc, nbep_output **out,
                                    nbep_resume *r, nbep_diag *d)
{
    nbep_resume res = {0};
    nbep_status st = NBEP_EIO;
    const size_t n = sc->state.n;
    nbep_output *o = calloc(1, sizeof *o);
    if (!o || !(o->path = strdup(path))) {
        free(o);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: %s: no memory for the output handle", path);
    }
    o->n_spheres = n;
    o->file = o->summary = H5I_INVALID_HID;
    o->frame_step = o->frame_time = o->frame_pos = o->frame_vel = H5I_INVALID_HID;
    o->frames_count = o->stats_count = H5I_INVALID_HID;
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        o->stats[c] = H5I_INVALID_HID;
    for (int c = 0; c < 4; c++)
        o->ck[c] = H5I_INVALID_HID;

    hid_t fapl = make_fapl(true);
    o->file = fapl < 0 ? H5I_INVALID_HID : H5Fopen(path, H5F_ACC_RDWR, fapl);
    nbep__output_close_id(&fapl);
    if (o->file < 0) {
        HDF5_FAIL(d, path, "open the run to resume it");
        goto fail;
    }
    char *format = NULL;
    htri_t has_format = H5Aexists(o->file, "format");
    if (has_format <= 0 || read_string_attr(o->file, path, "format", &format, d) < 0 ||
        strcmp(format, FORMAT_NAME) != 0) {
        free(format);
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s is not an %s run file", path,
                      FORMAT_NAME);
        goto fail;
    }
    free(format);
    int same = same_bodies(o->file, path, sc, d);
    if (same < 0) {
        st = same == -2 ? NBEP_EDECK : NBEP_EIO;
        goto fail;
    }
    uint64_t frames;
    hsize_t more;
    if (complete_rows(o->file, path, "/frames", "/frames/step", &frames, &more, d) < 0)
        goto fail;
    if (frames == 0) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s has no complete frame to resume from",
                      path);
        goto fail;
    }
    if (H5Lexists(o->file, "/frames/position", H5P_DEFAULT) <= 0 ||
        H5Lexists(o->file, "/frames/velocity", H5P_DEFAULT) <= 0) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s cannot be resumed: its frames lack positions or velocities "
                      "(output.fields)",
                      path);
        st = NBEP_EDECK;
        goto fail;
    }
    hsize_t last = frames - 1;
    res.n = n;
    res.pos = malloc((n ? n : 1) * sizeof *res.pos);
    res.vel = malloc((n ? n : 1) * sizeof *res.vel);
    if (!res.pos || !res.vel) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
        st = NBEP_ENOMEM;
        goto fail;
    }
    if (read_row(o->file, path, "/frames/step", last, H5T_NATIVE_INT64, &res.step, d) < 0 ||
        read_dataset_row(o->file, path, "/frames/position", last, 3 * (hsize_t)n,
                         H5T_NATIVE_DOUBLE, res.pos, d) < 0 ||
        read_dataset_row(o->file, path, "/frames/velocity", last, 3 * (hsize_t)n,
                         H5T_NATIVE_DOUBLE, res.vel, d) < 0)
        goto fail;
    /* The event slots: only a predictive file continued by a predictive deck can use them. */
    htri_t has_ck = H5Lexists(o->file, "/checkpoint", H5P_DEFAULT);
    if (has_ck > 0 && strcmp(sc->algorithm, "predictive") == 0) {
        res.has_events = true;
        res.event_time = malloc((n ? n : 1) * sizeof *res.event_time);
        res.event_partner = malloc((n ? n : 1) * sizeof *res.event_partner);
        res.event_kind = malloc((n ? n : 1) * sizeof *res.event_kind);
        res.rest = malloc((n ? n : 1) * sizeof *res.rest);
        void *cols[4] = {res.event_time, res.event_partner, res.event_kind, res.rest};
        if (!res.event_time || !res.event_partner || !res.event_kind || !res.rest) {
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
            st = NBEP_ENOMEM;
            goto fail;
        }
        for (int c = 0; c < 4; c++)
            if (read_dataset_row(o->file, path, ck_columns[c].name, last, n,
                                 *ck_columns[c].mem_type, cols[c], d) < 0)
                goto fail;
    }
    /* Continue appending after the last complete frame: cut everything written past it. */
    if (open_cut(o, "/frames/step", frames, &o->frame_step, d) < 0 ||
        open_cut(o, "/frames/time", frames, &o->frame_time, d) < 0 ||
        open_cut(o, "/frames/position", frames, &o->frame_pos, d) < 0 ||
        open_cut(o, "/frames/velocity", frames, &o->frame_vel, d) < 0)
        goto fail;
    if (has_ck > 0)
        for (int c = 0; c < 4; c++)
            if (open_cut(o, ck_columns[c].name, frames, &o->ck[c], d) < 0)
                goto fail;
    hid_t g = H5Gopen2(o->file, "/frames", H5P_DEFAULT);
    o->frames_count = g < 0 ? H5I_INVALID_HID : H5Aopen(g, "count", H5P_DEFAULT);
    nbep__output_close_id(&g);
    if (o->frames_count < 0) {
        HDF5_FAIL(d, path, "open the count attribute of /frames");
        goto fail;
    }
    o->n_frames = frames;
    o->xmf = true; /* resumed runs have positions */
    if (!xmf_room(o, (size_t)frames)) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to resume %s", path);
        st = NBEP_ENOMEM;
        goto fail;
    }
    for (hsize_t k = 0; k < frames; k++)
        if (read_row(o->file, path, "/frames/step", k, H5T_NATIVE_INT64, &o->xmf_step[k], d) <
                0 ||
            read_row(o->file, path, "/frames/time", k, H5T_NATIVE_DOUBLE, &o->xmf_time[k], d) <
                0)
            goto fail;
    if (H5Lexists(o->file, "/stats", H5P_DEFAULT) > 0) {
        uint64_t rows;
        if (complete_rows(o->file, path, "/stats", "/stats/step", &rows, &more, d) < 0)
            goto fail;
        /* one row per step from step 1: the rows up to the frame's step stay */
        uint64_t keep = rows < (uint64_t)res.step ? rows : (uint64_t)res.step;
        for (int c = 0; c < STATS_N_COLUMNS; c++)
            if (open_cut(o, stats_columns[c].name, keep, &o->stats[c], d) < 0)
                goto fail;
        hid_t sg = H5Gopen2(o->file, "/stats", H5P_DEFAULT);
        o->stats_count = sg < 0 ? H5I_INVALID_HID : H5Aopen(sg, "count", H5P_DEFAULT);
        nbep__output_close_id(&sg);
        if (o->stats_count < 0) {
            HDF5_FAIL(d, path, "open the count attribute of /stats");
            goto fail;
        }
        o->n_stats = keep;
    }
    /* The summary described the run as it ended; it is written again at the new end. */
    o->summary = H5Gopen2(o->file, "/summary", H5P_DEFAULT);
    if (o->summary < 0 ||
        (H5Aexists(o->summary, "json") > 0 && H5Adelete(o->summary, "json") < 0)) {
        HDF5_FAIL(d, path, "reset /summary");
        goto fail;
    }
    hid_t steps_attr = H5Aopen(o->file, "steps", H5P_DEFAULT);
    if (steps_attr < 0 || H5Awrite(steps_attr, H5T_NATIVE_UINT64, &sc->steps) < 0) {
        HDF5_FAIL(d, path, "update the root attribute steps");
        nbep__output_close_id(&steps_attr);
        goto fail;
    }
    nbep__output_close_id(&steps_attr);
    if (commit(o, frames, d) < 0)
        goto fail;
    *out = o;
    *r = res;
    return NBEP_OK;
fail:
    release(&o);
    nbep_resume_fini(&res);
    return st;
}
