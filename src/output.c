/* The writer of the run format "nbep-1" (SPEC "HDF5 output"): create, frames, stats, close.
 * One writing thread (thread 0 between barriers). Its siblings (output_impl.h): resume, info,
 * the HDF5 helpers; the JSON summary is summary.c's.
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
 *   create leaves nothing at PATH. (/checkpoint comes with the first frame, see
 *   create_checkpoint.)
 * - Each frame ends with a global H5Fflush: data, metadata, chunk index and the superblock's
 *   end of file, so the file on disk then holds every frame written so far, and later chunks
 *   go past that end of file. A second flush then bumps the `count` attributes (see commit):
 *   a kill inside the first can leave a half-written last row, never a counted one.
 * - A chunk-index node that splits in a flush cut short can take old frames with it; K is
 *   raised so that the index does not split for the planned frames (CHUNK_INDEX_K_MIN).
 * - The writer takes no HDF5 file lock, so `nbep info` and HDF5 tools can look at a run while
 *   it runs (they see the last flushed frame), and runs work on parallel file systems without
 *   flock support. Two runs into one file are kept apart by a lock of its own beside it,
 *   PATH.lock (nbep__output_lock).
 *
 * Errors: see output_hdf5.c. */
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
#include <sys/resource.h>
#include <sys/stat.h>

#include <hdf5.h>

#include "build_info.h"
#include "output_impl.h"

/* Frames are written straight from nbep_vec3 arrays as n x 3 doubles. */
static_assert(sizeof(nbep_vec3) == 3 * sizeof(double), "nbep_vec3 must be 3 packed doubles");


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
const struct nbep__stats_column nbep__stats_columns[STATS_N_COLUMNS] = {
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

bool nbep__output_xmf_room(nbep_output *o, size_t f)
{
    if (f < o->xmf_cap)
        return true;
    /* a list of f + 1 entries of 8 bytes must be addressable: past that no doubling would
     * reach it (until 2026-12-01 cap * 8 wrapped to 0 for a deck of 2^60 planned frames, and
     * the loop never ended for 2^63) */
    if (f >= SIZE_MAX / (2 * sizeof(double)))
        return false;
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

bool nbep__output_writes_sidecar(bool positions, const char *path)
{
    return positions && nbep_xdmf_can_name(path);
}

bool nbep_output_sidecar_unnamed(const nbep_output *o)
{
    return o->xmf && !o->sidecar;
}

/* The sidecar's part of the room kept ahead (nbep__output_reserve): its rewrite listing one
 * frame more than the file has, at any later frame or at the close */
static int64_t sidecar_room(const nbep_output *o)
{
    if (!o->xmf || !o->sidecar)
        return 0;
    return (int64_t)nbep_xdmf_bytes_bound(o->path, o->n_spheres, (size_t)o->n_frames + 1,
                                          o->frame_vel >= 0);
}

static int hold_room(nbep_output *o, const char *what, int64_t held_end, nbep_diag *d);

nbep_status nbep__output_xmf_write(nbep_output *o, bool hold_again, nbep_diag *d)
{
    o->xmf_last = nbep_now();
    if (!o->sidecar) /* its name is not UTF-8 text (nbep_run says so as the run begins) */
        return NBEP_OK;
    /* The room held past the file's end counts this rewrite: given back first, so that the
     * rewrite finds it free. A full disk was met here, past the frame's room, as `cannot write
     * the XDMF sidecar` (until 2026-12-04); it is met at the frame's reservation now, as `no
     * room for frame N`, before anything of that frame is written. */
    const int64_t held_end = o->room > 0 ? o->reserved_end : 0;
    if (held_end > 0)
        nbep_file_unreserve_fd(o->room_fd, held_end);
    nbep_status st = nbep_xdmf_write(o->path, o->n_spheres, (size_t)o->n_frames, o->xmf_step,
                                     o->xmf_time, o->frame_vel >= 0, d);
    /* what was held for the steps to the next frame, held again: found free but for a race
     * (the rewrite took at most the sidecar's part, and its old file went) */
    if (st == NBEP_OK && hold_again && held_end > 0) {
        char what[64];
        snprintf(what, sizeof what, "the steps after frame %llu",
                 (unsigned long long)o->n_frames - 1);
        if (hold_room(o, what, held_end, d) < 0)
            st = NBEP_EIO;
    }
    return st;
}

const struct nbep__ck_column nbep__ck_columns[N_CK_COLUMNS] = {
    {"/checkpoint/event_time", &H5T_IEEE_F64LE_g, &H5T_NATIVE_DOUBLE_g},
    {"/checkpoint/event_partner", &H5T_STD_U32LE_g, &H5T_NATIVE_UINT32_g},
    {"/checkpoint/event_kind", &H5T_STD_U8LE_g, &H5T_NATIVE_UINT8_g},
    {"/checkpoint/rest", &H5T_STD_I32LE_g, &H5T_NATIVE_INT32_g},
};

/* ---- writing helpers ----------------------------------------------------------------------- */

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
 * rank - 1 dimensions (fixed; one of 0 is declared unlimited, as HDF5 wants a chunk at least
 * 1 wide and no wider than the dimension's maximum), chunk the chunk shape. */
static int create_series(nbep_output *o, const char *name, hid_t file_type, int rank,
                         const hsize_t *tail, const hsize_t *chunk, hid_t *out, nbep_diag *d)
{
    int rc = -1;
    hsize_t dims[3] = {0}, maxdims[3] = {H5S_UNLIMITED};
    assert(rank >= 1 && rank <= 3);
    for (int k = 1; k < rank; k++) {
        dims[k] = tail[k - 1];
        maxdims[k] = tail[k - 1] ? tail[k - 1] : H5S_UNLIMITED;
    }
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

/* Rows [first, end) of /checkpoint as stale slots (kind none, no resting plane: a resume from
 * such a frame predicts every sphere afresh), for the frames of a part that keeps no event
 * slots (naive or seminaive resuming a predictive file), so that /checkpoint keeps a row for
 * every frame (until 2026-11-30 it fell behind /frames, and a predictive resume from a later
 * frame failed, exit 1, "has no row"). */
int nbep__output_ck_stale(nbep_output *o, hsize_t first, hsize_t end, nbep_diag *d)
{
    const size_t n = o->n_spheres;
    double *zeros = calloc(n ? n : 1, sizeof *zeros); /* 8 bytes: time, partner and kind */
    int32_t *none = malloc((n ? n : 1) * sizeof *none);
    hsize_t row[2] = {1, n};
    hid_t row_space = H5Screate_simple(2, row, NULL);
    int rc = zeros && none && row_space >= 0 ? 0 : -1;
    if (rc < 0)
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the checkpoint rows",
                      o->path);
    for (size_t i = 0; none && i < n; i++)
        none[i] = -1;
    const void *cols[N_CK_COLUMNS] = {zeros, zeros, zeros, none};
    for (hsize_t f = first; f < end && rc == 0; f++)
        for (int c = 0; c < N_CK_COLUMNS && rc == 0; c++)
            rc = append_rows(o, o->ck[c], nbep__ck_columns[c].name, 2, f, row,
                             *nbep__ck_columns[c].mem_type, row_space, cols[c], d);
    nbep__output_close_id(&row_space);
    free(zeros);
    free(none);
    return rc;
}

/* ---- create -------------------------------------------------------------------------------- */

static int write_root_attrs(nbep_output *o, const nbep_scene *sc, int threads, nbep_diag *d)
{
    hid_t root = o->file;
    const char *p = o->path;
    int64_t threads64 = threads;
    double gravity[3] = {sc->gravity.x, sc->gravity.y, sc->gravity.z};
    if (nbep__output_write_string_attr(root, p, "format", FORMAT_NAME, d) < 0 ||
        nbep__output_write_string_attr(root, p, "version", NBEP_VERSION, d) < 0 ||
        nbep__output_write_string_attr(root, p, "build_flags", NBEP_BUILD_FLAGS, d) < 0 ||
        nbep__output_write_string_attr(root, p, "build_commit", NBEP_BUILD_COMMIT, d) < 0 ||
        nbep__output_write_string_attr(root, p, "algorithm", sc->algorithm, d) < 0 ||
        nbep__output_write_attr(root, p, "steps", H5T_STD_U64LE, H5T_NATIVE_UINT64, 0,
                                &sc->steps, d) < 0 ||
        nbep__output_write_attr(root, p, "dt", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &sc->dt,
                                d) < 0 ||
        nbep__output_write_attr(root, p, "threads", H5T_STD_I64LE, H5T_NATIVE_INT64, 0,
                                &threads64, d) < 0 ||
        nbep__output_write_attr(root, p, "seed", H5T_STD_U64LE, H5T_NATIVE_UINT64, 0, &sc->seed,
                                d) < 0 ||
        nbep__output_write_attr(root, p, "output_every", H5T_STD_U64LE, H5T_NATIVE_UINT64, 0,
                                &sc->output_every, d) < 0 ||
        nbep__output_write_attr(root, p, "restitution", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0,
                                &sc->restitution, d) < 0 ||
        nbep__output_write_attr(root, p, "gravity", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3,
                                gravity, d) < 0 ||
        nbep__output_write_string_attr(root, p, "deck_path", sc->deck_path, d) < 0 ||
        nbep__output_write_string_attr(root, p, "deck", sc->deck_text, d) < 0 ||
        nbep__output_write_string_attr(root, p, "overrides", sc->overrides, d) < 0)
        return -1;
    /* predictive: how it finds pairs and reacts (run.neighbors, run.order), which nbep info
     * prints beside the algorithm (the deck and overrides say it too, but not at a glance) */
    if (strcmp(sc->algorithm, "predictive") == 0 &&
        (nbep__output_write_string_attr(root, p, "neighbors", nbep_scene_neighbors_name(sc),
                                        d) < 0 ||
         nbep__output_write_string_attr(root, p, "order", nbep_scene_order_name(sc), d) < 0))
        return -1;
    /* and at e < 1 the collision model's settings, which change a granular run's outcome as
     * much as e does (nbep info prints them; a new user found them only in the deck text) */
    if (strcmp(sc->algorithm, "predictive") == 0 && sc->restitution < 1.0 &&
        (nbep__output_write_attr(root, p, "tc", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0, &sc->tc,
                                 d) < 0 ||
         nbep__output_write_attr(root, p, "carry_drop", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 0,
                                 &sc->carry_drop, d) < 0))
        return -1;
    const int32_t periodic[3] = {sc->has_box && sc->periodic[0], sc->has_box && sc->periodic[1],
                                 sc->has_box && sc->periodic[2]};
    if (nbep__output_write_attr(root, p, "periodic", H5T_STD_I32LE, H5T_NATIVE_INT32, 3,
                                periodic, d) < 0)
        return -1;
    /* the box, where the deck has one: the periods of /frames/image, and what a resume checks
     * (on a periodic axis no wall records it) */
    if (sc->has_box &&
        (nbep__output_write_attr(root, p, "box_min", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3,
                                 &sc->box_min, d) < 0 ||
         nbep__output_write_attr(root, p, "box_max", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, 3,
                                 &sc->box_max, d) < 0))
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

/* Spheres per chunk of a frame-shaped dataset: one frame per chunk, or, past
 * FRAME_CHUNK_BYTES, the frame in equal chunks below it. HDF5 stores a frame's last chunk
 * whole: chunks of the cap would pad a frame of 256000 spheres to 349524 (73 % of the file's
 * frames were data). */
static hsize_t frame_chunk_spheres(size_t n)
{
    const size_t cap = FRAME_CHUNK_BYTES / (3 * sizeof(double));
    const size_t chunks = (n + cap - 1) / cap;
    return chunks ? (n + chunks - 1) / chunks : 1; /* HDF5 wants chunks >= 1, even for a
                                                    * scene without spheres */
}

uint64_t nbep_output_frames(const nbep_scene *sc)
{
    return sc->steps / sc->output_every + 1 + (sc->steps % sc->output_every ? 1 : 0);
}

bool nbep_output_same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return a && b && stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

/* What a chunk's entry in its dataset's index takes on disk, measured: the 1-sphere bounce deck
 * (six series a chunk a frame) grows by 381 bytes a frame, of which 81 are data, so about 50 a
 * chunk (a small, many-frame deck's estimate was 30 % low without it; a fluid's frames are
 * megabytes, where it does not show). */
#define CHUNK_INDEX_BYTES 50.0
/* What a file takes besides its datasets' values (the groups' and datasets' headers, the
 * attributes with the deck's text, the chunk indexes' first blocks), measured: 45 to 55 kB for
 * the shipped decks' files of one frame (bounce 56 kB, two-spheres 54 kB, paper-box 45 kB). */
#define FILE_META_BYTES 50e3

/* rows rounded up to whole chunks of `chunk` rows: a growing dataset's last chunk is whole */
static double whole_chunks(uint64_t rows, uint64_t chunk)
{
    return (double)((rows + chunk - 1) / chunk * chunk);
}

double nbep_output_bytes(const nbep_scene *sc, bool events, bool contacts)
{
    const double n = (double)sc->state.n, np = (double)sc->state.n_planes;
    const bool periodic = nbep_scene_any_periodic(sc);
    const uint64_t frames = nbep_output_frames(sc);
    double sphere = 24.0 * (sc->out_position + sc->out_velocity) + (periodic ? 12.0 : 0.0);
    /* the series stored a chunk (or more) a frame: each chunk costs its index entry too */
    double series = (double)(sc->out_position + sc->out_velocity) + (periodic ? 1.0 : 0.0);
    for (int c = 0; events && c < N_CK_COLUMNS; c++) {
        sphere += (double)H5Tget_size(*nbep__ck_columns[c].file_type);
        series += 1.0;
    }
    const hsize_t per_chunk = frame_chunk_spheres(sc->state.n);
    const double stored = whole_chunks(sc->state.n, per_chunk);
    const double chunks = stored / (double)per_chunk; /* a frame's chunks in each series */
    double bytes = n * 40.0 + np * 32.0 +                           /* /spheres, /planes */
                   (16.0 + (double)sizeof(nbep_run_totals)) *   /* step, time, totals */
                       whole_chunks(frames, SERIES_CHUNK_ROWS) +
                   (double)frames * stored * sphere +               /* frames, whole chunks */
                   (double)frames * chunks * series * CHUNK_INDEX_BYTES;
    if (sc->out_stats) { /* the columns, and wall_impulse in chunks of as many values (create_stats) */
        const uint64_t wide = sc->state.n_planes ? sc->state.n_planes : 1;
        const uint64_t wrows = STATS_CHUNK_ROWS / wide ? STATS_CHUNK_ROWS / wide : 1;
        bytes += 8.0 * STATS_N_COLUMNS * whole_chunks(sc->steps, STATS_CHUNK_ROWS) +
                 8.0 * np * whole_chunks(sc->steps, wrows);
    }
    if (events && contacts)
        bytes += nbep__output_contacts_bytes(sc->state.n);
    bytes += FILE_META_BYTES;
    return bytes;
}

/* The room beyond a frame's estimated growth (nbep__output_room): a frame's flush may move a
 * chunk index's node or a heap's block past the file's end (a few kB), and a run stopped for
 * room writes its summary (a few kB). */
#define ROOM_SLACK_BYTES ((int64_t)256 << 10)

void nbep__output_room(nbep_output *o, const nbep_scene *sc)
{
    /* A frame: its rows of every series it may write (positions, velocities, images, event
     * slots: more room than needed costs disk blocks held for a while, not data), in whole
     * chunks with their index entries; a new chunk of step, time and totals; and at e < 1 the
     * lasting contacts' records (the predictive algorithm's, two frames' worth at most). */
    double sphere = 24.0 * 2.0 + 12.0, series = 3.0;
    for (int c = 0; c < N_CK_COLUMNS; c++) {
        sphere += (double)H5Tget_size(*nbep__ck_columns[c].file_type);
        series += 1.0;
    }
    const hsize_t per_chunk = frame_chunk_spheres(sc->state.n);
    const double stored = whole_chunks(sc->state.n, per_chunk);
    double frame = stored * sphere + stored / (double)per_chunk * series * CHUNK_INDEX_BYTES +
                   (16.0 + (double)sizeof(nbep_run_totals)) * SERIES_CHUNK_ROWS;
    if (sc->restitution < 1.0)
        frame += nbep__output_contacts_bytes(sc->state.n);
    /* The /stats rows of a frame's interval: a new chunk of each column and of wall_impulse
     * (STATS_CHUNK_ROWS values each) where the interval's rows reach into one. Counted twice:
     * a run stopped for room commits the rows since its last frame at its close, after that
     * frame took its own. An interval holds no more rows than the run has steps: every =
     * 1e9 over 20 steps (the first and last frames only) held 144 GB for 20 rows, and a run
     * on any disk stopped for room at its first frame (a review, 2026-12-05). */
    const uint64_t rows = sc->output_every < sc->steps ? sc->output_every : sc->steps;
    double stats = 0.0;
    if (sc->out_stats)
        stats = 8.0 * (STATS_N_COLUMNS + 1) *
                (whole_chunks(rows, STATS_CHUNK_ROWS) +
                 (rows > STATS_CHUNK_ROWS ? STATS_CHUNK_ROWS : 0));
    o->room = (int64_t)(frame + 2.0 * stats) + ROOM_SLACK_BYTES;
    /* the descriptor HDF5 writes through: its default (sec2) driver's, an int */
    hid_t fapl = H5Fget_access_plist(o->file);
    const bool sec2 = fapl >= 0 && H5Pget_driver(fapl) == H5FD_SEC2;
    nbep__output_close_id(&fapl);
    int *fd = NULL;
    if (!sec2 || H5Fget_vfd_handle(o->file, H5P_DEFAULT, (void **)&fd) < 0 || !fd)
        o->room = 0;
    else
        o->room_fd = *fd;
}

/* Reserves the room past the file's end: o->room and the sidecar's next rewrite; or, where
 * held_end > 0 (after a rewrite that gave the room back), what was held up to held_end less
 * the rewrite's part */
static int hold_room(nbep_output *o, const char *what, int64_t held_end, nbep_diag *d)
{
    struct stat sb;
    if (o->room <= 0)
        return 0;
    if (fstat(o->room_fd, &sb) != 0) {
        o->room = 0;
        return 0;
    }
    const int64_t end = (int64_t)sb.st_size;
    const int64_t room = held_end > 0 ? held_end - end - sidecar_room(o)
                                      : o->room + sidecar_room(o);
    if (room <= 0)
        return 0;
    /* a file-size limit is not met by a reservation (the size does not change): said as the
     * write past it would (EFBIG), which by default ends the process with SIGXFSZ mid-write.
     * The sidecar is another file: its part of the room counts against the disk only */
    struct rlimit limit;
    int err = getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY &&
                      (uint64_t)(end + (room < o->room ? room : o->room)) >
                          (uint64_t)limit.rlim_cur
                  ? EFBIG
                  : nbep_file_reserve(o->room_fd, end, room);
    if (err == 0) {
        if (end + room > o->reserved_end)
            o->reserved_end = end + room;
        return 0;
    }
    if (err != ENOSPC && err != EDQUOT && err != EFBIG) { /* cannot reserve here: as before */
        o->room = 0;
        return 0;
    }
    char room_text[NBEP_BYTES_TEXT_MAX];
    nbep_diag_add(d, __FILE__, __LINE__,
                  "nbep: %s: no room for %s (%s kept free ahead of the file, for a frame to "
                  "be written whole): %s%s; the frames before it are kept",
                  o->path, what, nbep_format_bytes((double)room, room_text), strerror(err),
                  err == EFBIG ? " (the file-size limit, ulimit -f)" : "");
    return -1;
}

int nbep__output_reserve(nbep_output *o, const char *what, nbep_diag *d)
{
    return hold_room(o, what, 0, d);
}

double nbep_output_sidecar_bytes(const nbep_scene *sc, const char *path)
{
    /* as nbep_output_create_staged decides it and the frames' velocity is written */
    if (!nbep__output_writes_sidecar(sc->out_position, path))
        return 0.0;
    return nbep_xdmf_bytes(path, sc->state.n, sc->steps, sc->output_every, sc->dt,
                           sc->out_velocity);
}

static int create_frames(nbep_output *o, const nbep_scene *sc, nbep_diag *d)
{
    size_t n = sc->state.n;
    hsize_t tail[2] = {n, 3}, chunk[3] = {1, frame_chunk_spheres(n), 3};
    hsize_t series[1] = {SERIES_CHUNK_ROWS};
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
    if (o->pb.any && create_series(o, "/frames/image", H5T_STD_I32LE, 3, tail, chunk,
                                   &o->frame_img, d) < 0)
        return -1;
    if ((o->tot_type = nbep__output_totals_type()) < 0) {
        HDF5_FAIL(d, o->path, "make the type of /frames/totals");
        return -1;
    }
    return create_series(o, "/frames/totals", o->tot_type, 1, NULL, series, &o->frame_tot, d);
}

/* /checkpoint, made with a new file's first frame when that frame comes with event slots:
 * which runs keep them is the algorithm table's business (sim.c), not a name known here. */
static int create_checkpoint(nbep_output *o, nbep_diag *d)
{
    hsize_t ck_tail[1] = {o->n_spheres}, ck_chunk[2] = {1, frame_chunk_spheres(o->n_spheres)};
    if (make_group(o, "/checkpoint", NULL, d) < 0)
        return -1;
    for (int c = 0; c < N_CK_COLUMNS; c++)
        if (create_series(o, nbep__ck_columns[c].name, *nbep__ck_columns[c].file_type, 2,
                          ck_tail, ck_chunk, &o->ck[c], d) < 0)
            return -1;
    return 0;
}

hid_t nbep__output_totals_type(void)
{
    hid_t t = H5Tcreate(H5T_COMPOUND, sizeof(nbep_run_totals));
    bool ok = t >= 0;
#define TOTAL(name, type) ok = ok && H5Tinsert(t, #name, HOFFSET(nbep_run_totals, name), (type)) >= 0
    TOTAL(checks, H5T_NATIVE_UINT64);
    TOTAL(predictions, H5T_NATIVE_UINT64);
    TOTAL(sphere_collisions, H5T_NATIVE_UINT64);
    TOTAL(plane_collisions, H5T_NATIVE_UINT64);
    TOTAL(quiet_steps, H5T_NATIVE_UINT64);
    TOTAL(energy_initial, H5T_NATIVE_DOUBLE);
    TOTAL(max_overlap, H5T_NATIVE_DOUBLE);
    TOTAL(max_overlap_rel, H5T_NATIVE_DOUBLE);
    TOTAL(virial, H5T_NATIVE_DOUBLE);
    TOTAL(kinetic_energy, H5T_NATIVE_DOUBLE);
#undef TOTAL
    if (!ok && t >= 0)
        H5Tclose(t);
    return ok ? t : H5I_INVALID_HID;
}

void nbep_output_totals(nbep_output *o, const nbep_run_totals *t)
{
    o->tot = *t;
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
        if (create_series(o, nbep__stats_columns[c].name,
                          column_file_type(nbep__stats_columns[c].type), 1, NULL, chunk,
                          &o->stats[c], d) < 0)
            return -1;
    /* (S, P), chunks of about as many values as a column's; (S, 0) without planes (SPEC lists
     * it in every file with stats: a script reads it without asking first) */
    const hsize_t wide = o->n_planes ? o->n_planes : 1;
    hsize_t tail[1] = {o->n_planes};
    hsize_t rows = STATS_CHUNK_ROWS / wide, wchunk[2] = {rows ? rows : 1, wide};
    return create_series(o, "/stats/wall_impulse", H5T_IEEE_F64LE, 2, tail, wchunk,
                         &o->stats_wall, d);
}

int nbep__output_periodic(nbep_output *o, const nbep_scene *sc, nbep_diag *d)
{
    o->pb = nbep_periodic_make(sc->has_box ? sc->periodic : NULL, sc->box_min, sc->box_max);
    if (!o->pb.any)
        return 0;
    size_t n = o->n_spheres ? o->n_spheres : 1;
    o->wrap_pos = malloc(n * sizeof *o->wrap_pos);
    o->wrap_img = malloc(3 * n * sizeof *o->wrap_img);
    if (!o->wrap_pos || !o->wrap_img) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for wrapped frames", o->path);
        return -1;
    }
    return 0;
}

nbep_output *nbep__output_new(const char *path, size_t n_spheres, nbep_diag *d)
{
    nbep_output *o = calloc(1, sizeof *o);
    if (!o || !(o->path = strdup(path))) {
        free(o);
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the output handle", path);
        return NULL;
    }
    o->n_spheres = n_spheres;
    o->file = o->summary = H5I_INVALID_HID;
    o->frame_step = o->frame_time = o->frame_pos = o->frame_vel = H5I_INVALID_HID;
    o->frame_img = o->frame_tot = o->tot_type = o->stats_wall = H5I_INVALID_HID;
    o->frames_count = o->stats_count = H5I_INVALID_HID;
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        o->stats[c] = H5I_INVALID_HID;
    for (int c = 0; c < N_CK_COLUMNS; c++)
        o->ck[c] = H5I_INVALID_HID;
    o->contacts[0] = o->contacts[1] = o->contacts_type = H5I_INVALID_HID;
    o->lock_fd = o->room_fd = -1;
    return o;
}

/* Two runs into one file (a job resubmitted while the first still runs, an array job whose
 * tasks all name out.h5) wrote over each other: the second's file was renamed over the
 * first's, which went on writing a file no longer there and ended with exit 0, or both
 * resumed one file and interleaved their frames (until 2026-12-01). The lock is a file of its
 * own beside the output, not the output: readers take HDF5's locks (flock) on the output, which
 * on NFS are byte-range locks of the whole file and would meet a writer's there. */
nbep_status nbep__output_lock(nbep_output *o, bool resume, nbep_diag *d)
{
    /* A resume writes the file the path leads to: through a symbolic link (link.h5 to
     * out.h5), the lock is that file's (out.h5.lock), which its own writer holds. A new file
     * replaces a link at its path, and the lock is the path's. (A link to the folder leads to
     * the same lock file: nothing to resolve.) */
    char *target = resume ? nbep_link_target(o->path) : NULL;
    o->lock_path = nbep_lock_path(target ? target : o->path);
    free(target);
    if (!o->lock_path)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: %s: no memory for the output handle", o->path);
    bool busy;
    o->lock_fd = nbep_lock_take(o->lock_path, &busy);
    if (busy) {
        nbep_diag_add(d, __FILE__, __LINE__,
                      "nbep: %s: another nbep run is writing this file (it holds %s); wait "
                      "for it to end, or give this run another output",
                      o->path, o->lock_path);
        free(o->lock_path); /* not ours to remove */
        o->lock_path = NULL;
        return NBEP_EBUSY;
    }
    return NBEP_OK;
}

void nbep__output_release(nbep_output **op)
{
    nbep_output *o = *op;
    if (!o)
        return;
    nbep__output_close_id(&o->frame_step);
    nbep__output_close_id(&o->frame_time);
    nbep__output_close_id(&o->frame_pos);
    nbep__output_close_id(&o->frame_vel);
    nbep__output_close_id(&o->frame_img);
    nbep__output_close_id(&o->frame_tot);
    nbep__output_close_id(&o->tot_type);
    nbep__output_close_id(&o->stats_wall);
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        nbep__output_close_id(&o->stats[c]);
    for (int c = 0; c < N_CK_COLUMNS; c++)
        nbep__output_close_id(&o->ck[c]);
    nbep__output_close_id(&o->contacts[0]);
    nbep__output_close_id(&o->contacts[1]);
    nbep__output_close_id(&o->contacts_type);
    free(o->contacts_buf);
    nbep__output_close_id(&o->frames_count);
    nbep__output_close_id(&o->stats_count);
    nbep__output_close_id(&o->summary);
    nbep__output_close_id(&o->file);
    free(o->xmf_step);
    free(o->xmf_time);
    free(o->wrap_pos);
    free(o->wrap_img);
    if (o->staged) /* never published: the temporary file goes, whatever is at path stays */
        remove(o->staged);
    free(o->staged);
    nbep_lock_drop(o->lock_fd, o->lock_path); /* last: all written */
    free(o->lock_path);
    free(o->path);
    free(o);
    *op = NULL;
}

/* The sidecar's frame list made before the first step: at most this many frames (16 bytes
 * each, 1 MiB), the rest as they come. */
#define XMF_RESERVE_MAX ((uint64_t)1 << 16)

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

nbep_status nbep_output_create_staged(const char *path, const nbep_scene *sc, int threads,
                                      nbep_output **out, nbep_diag *d)
{
    /* The file is made under a temporary name and renamed to path once its layout is on
     * disk: a run killed while creating leaves no half-made file at path (only PATH.partial,
     * which the next run overwrites), and an older file at path survives until then. */
    nbep_output *o = nbep__output_new(path, sc->state.n, d);
    if (!o)
        return NBEP_ENOMEM;
    char *tmp = nbep_partial_path(path);
    if (!tmp) {
        nbep__output_release(&o);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: %s: no memory for the output handle", path);
    }
    o->ck_allowed = true;
    o->n_planes = sc->state.n_planes;
    nbep_status lock_st = nbep__output_lock(o, false, d); /* before PATH.partial is made afresh */
    if (lock_st != NBEP_OK) {
        free(tmp);
        nbep__output_release(&o);
        return lock_st;
    }
    if (nbep__output_periodic(o, sc, d) < 0) {
        free(tmp);
        nbep__output_release(&o);
        return NBEP_ENOMEM;
    }

    nbep_status create_st = NBEP_EIO; /* how a failure to make the file is classed */
    hid_t fapl = nbep__output_fapl(true), fcpl = make_fcpl(sc);
    if (fapl < 0 || fcpl < 0) {
        HDF5_FAIL(d, path, "set up file properties");
        nbep__output_close_id(&fapl);
        nbep__output_close_id(&fcpl);
        goto fail_uncreated;
    }
    o->file = H5Fcreate(tmp, H5F_ACC_TRUNC, fcpl, fapl);
    if (o->file < 0) {
        HDF5_FAIL(d, path, "create the output file");
        /* a missing directory or one not ours to write is the user's to fix, exit 2 like a
         * missing deck (nbep_status_of_open); a full disk or failing device is run time's.
         * errno after HDF5 may be left from a look it took first (it opens the name before it
         * creates it: ENOENT), so the system is asked again, plainly. */
        FILE *probe = fopen(tmp, "w");
        if (probe) {
            fclose(probe);
            remove(tmp);
        } else {
            create_st = nbep_status_of_open(errno);
        }
        nbep__output_close_id(&fapl);
        nbep__output_close_id(&fcpl);
        goto fail_uncreated;
    }
    nbep__output_close_id(&fapl);
    nbep__output_close_id(&fcpl);

    if (write_root_attrs(o, sc, threads, d) < 0 || write_bodies(o, &sc->state, d) < 0 ||
        create_frames(o, sc, d) < 0 || (sc->out_stats && create_stats(o, d) < 0))
        goto fail; /* (no /summary until the run ends: nbep_output_close) */
    if (H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0) {
        HDF5_FAIL(d, path, "flush the file");
        goto fail;
    }
    o->xmf = sc->out_position;
    o->sidecar = nbep__output_writes_sidecar(o->xmf, path);
    nbep__output_room(o, sc);
    /* the frame list's room for the planned frames, up to XMF_RESERVE_MAX of them: a frame past
     * it grows the list as it is written (a deck may plan more frames than memory holds, a run
     * meant to end on its job's time limit; until 2026-12-01 the whole list was made here, and
     * 2^40 planned frames failed for memory before the first step) */
    const uint64_t planned = planned_frames(sc);
    const uint64_t reserve = planned < XMF_RESERVE_MAX ? planned : XMF_RESERVE_MAX;
    o->staged = tmp; /* renamed to path by nbep_output_publish; removed if it never is */
    if (o->xmf && !nbep__output_xmf_room(o, (size_t)reserve)) {
        nbep__output_release(&o);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: %s: no memory for the frame list", path);
    }
    *out = o;
    return NBEP_OK;
fail:
    /* bad output leaves no file behind (STYLE 4): the release removes PATH.partial while it
     * still holds the lock (removed after, until 2026-12-01, it could be the next run's) */
    o->staged = tmp;
    nbep__output_release(&o);
    return create_st;
fail_uncreated:
    nbep__output_release(&o);
    free(tmp);
    return create_st;
}

/* Removes the sidecar of the run file at path, if there is one. */
static void remove_sidecar(const char *path)
{
    char *x = nbep_xdmf_path(path);
    if (x)
        remove(x);
    free(x);
}

nbep_status nbep_output_publish(nbep_output *o, nbep_diag *d)
{
    if (!o->staged)
        return NBEP_OK;
    /* HDF5 keeps writing through its open descriptor, whatever the file's name. */
    if (rename(o->staged, o->path) != 0) {
        const int err = errno;
        NBEP_FAIL(d, nbep_status_of_open(err), /* a directory at path: the user's (exit 2) */
                  "nbep: %s: cannot create the output file: %s", o->path, strerror(err));
    }
    free(o->staged);
    o->staged = NULL;
    /* a sidecar at path is an older run's: it lists frames not in this file. Removed whether
     * or not this run writes one (its own comes with its first frame): until 2026-12-05 it
     * stayed where this run writes one, and a run stopped before its first frame (a full
     * disk) left it beside the new file, naming 2 spheres' frames in a file of 32000 and
     * none (a review) */
    remove_sidecar(o->path);
    return NBEP_OK;
}

void nbep__output_sidecar_stale(const nbep_output *o)
{
    if (!o->sidecar)
        remove_sidecar(o->path);
}

nbep_status nbep_output_create(const char *path, const nbep_scene *sc, int threads,
                               nbep_output **out, nbep_diag *d)
{
    nbep_status st = nbep_output_create_staged(path, sc, threads, out, d);
    if (st == NBEP_OK && (st = nbep_output_publish(*out, d)) != NBEP_OK)
        nbep__output_release(out); /* removes the staged file */
    return st;
}

/* ---- frames, stats, close ------------------------------------------------------------------ */

/* Makes the rows written so far durable in two flushes: the first writes the rows (data, then
 * extents and chunk indexes), the second the `count` attributes saying how many rows are
 * complete. HDF5 orders nothing within one flush: a kill during the first can leave a last row
 * whose extent is on disk but whose chunk is not (it reads as zeros, or fails to read). The
 * counts change only after that flush returned, and each is one small in-place write of an
 * object header, so they never count such a row. */
int nbep__output_commit(nbep_output *o, hsize_t frames, nbep_diag *d)
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
    /* A periodic box: positions wrapped into it, the periods removed added to the images
     * (the algorithm may hold positions a little outside, see cells.h); a sphere whose count
     * of periods crossed leaves /frames/image's int32 cannot be written (nbep_periodic_wrap) */
    if (o->pb.any) {
        memcpy(o->wrap_pos, s->pos, s->n * sizeof *o->wrap_pos);
        memcpy(o->wrap_img, s->image, 3 * s->n * sizeof *o->wrap_img);
        for (size_t i = 0; i < s->n; i++)
            if (!nbep_periodic_wrap(&o->pb, &o->wrap_pos[i], &o->wrap_img[3 * i]))
                NBEP_FAIL(d, NBEP_ENUMERIC,
                          "nbep: %s: step %" PRId64 ": sphere %zu has crossed the periodic box "
                          "more than 2^31 times along an axis, beyond what /frames/image (int32) "
                          "counts (its speed %.3g, the box's sides %g, %g, %g); frame not written",
                          o->path, step, i, nbep_vec3_norm(s->vel[i]), o->pb.len[0],
                          o->pb.len[1], o->pb.len[2]);
    }
    char what[64];
    snprintf(what, sizeof what, "frame %llu (step %" PRId64 ")", (unsigned long long)o->n_frames,
             step);
    if (nbep__output_reserve(o, what, d) < 0)
        return NBEP_EIO;
    double t = (double)step * dt;
    /* memory spaces of the file selection's shape: a flat one made HDF5 map each element
     * to its chunk apart (a sixth of a frame step's time at N = 256000) */
    hsize_t f = o->n_frames, one[1] = {1}, vec[3] = {1, s->n, 3};
    hid_t one_space = H5Screate_simple(1, one, NULL);
    hid_t vec_space = H5Screate_simple(3, vec, NULL);
    nbep_status st = NBEP_EIO;
    if (one_space < 0 || vec_space < 0) {
        HDF5_FAIL(d, o->path, "make the dataspaces of frame %llu", (unsigned long long)f);
        goto done;
    }
    /* A resumed file's stop frame off output.every's grid (nbep_output_open_resume) gives way
     * to this one: the count lowered and made durable first, then the rows cut by the appends
     * below, the image rows' first among them (each sets its dataset's extent to f + 1), so a
     * kill between leaves a readable file ending at the frame before. */
    if (o->resume.trim > 0 && o->resume.trim < f) { /* 0: nothing to replace */
        const uint64_t n_frames = o->resume.trim;
        if (H5Awrite(o->frames_count, H5T_NATIVE_UINT64, &n_frames) < 0 ||
            H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0) {
            HDF5_FAIL(d, o->path, "drop the stop's frame off output.every's grid");
            goto done;
        }
        o->n_frames = f = o->resume.trim;
    }
    o->resume.trim = 0;
    const nbep_vec3 *pos = s->pos;
    if (o->pb.any) { /* wrapped above */
        pos = o->wrap_pos;
        if (o->frame_img >= 0 && append_rows(o, o->frame_img, "/frames/image", 3, f, vec,
                                             H5T_NATIVE_INT32, vec_space, o->wrap_img, d) < 0)
            goto done;
    }
    /* Which rows are complete is said by the count attributes (see commit), not by the
     * datasets' lengths, so the order of these appends does not matter for crash safety. */
    if (o->frame_pos >= 0 && append_rows(o, o->frame_pos, "/frames/position", 3, f, vec,
                                         H5T_NATIVE_DOUBLE, vec_space, pos, d) < 0)
        goto done;
    if (o->frame_vel >= 0 && append_rows(o, o->frame_vel, "/frames/velocity", 3, f, vec,
                                         H5T_NATIVE_DOUBLE, vec_space, s->vel, d) < 0)
        goto done;
    if (ev && o->ck[0] < 0 && o->ck_allowed && f == 0 && create_checkpoint(o, d) < 0)
        goto done;
    if (!ev && o->ck[0] >= 0 && nbep__output_ck_stale(o, f, f + 1, d) < 0)
        goto done;
    if (ev && o->ck[0] >= 0) {
        hsize_t row[2] = {1, s->n};
        hid_t row_space = H5Screate_simple(2, row, NULL);
        const void *cols[N_CK_COLUMNS] = {ev->time, ev->partner, ev->kind, ev->rest};
        int bad = row_space < 0;
        for (int c = 0; c < N_CK_COLUMNS && !bad; c++)
            bad = append_rows(o, o->ck[c], nbep__ck_columns[c].name, 2, f, row,
                              *nbep__ck_columns[c].mem_type, row_space, cols[c], d) < 0;
        nbep__output_close_id(&row_space);
        if (bad)
            goto done;
    }
    if (o->ck[0] >= 0 && nbep__output_contacts_write(o, f, ev, d) < 0)
        goto done;
    if (o->frame_tot >= 0 && append_rows(o, o->frame_tot, "/frames/totals", 1, f, one,
                                         o->tot_type, one_space, &o->tot, d) < 0)
        goto done;
    if (append_rows(o, o->frame_time, "/frames/time", 1, f, one, H5T_NATIVE_DOUBLE, one_space,
                    &t, d) < 0 ||
        append_rows(o, o->frame_step, "/frames/step", 1, f, one, H5T_NATIVE_INT64, one_space,
                    &step, d) < 0)
        goto done;
    /* the sidecar's list has room for the frame before the frame counts: a frame counted
     * without it was listed at close from past the list's end (until 2026-12-01, a review;
     * a run of more than the 2^16 frames made room for up front grows it here) */
    if (o->xmf && !nbep__output_xmf_room(o, (size_t)f)) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the frame list", o->path);
        st = NBEP_ENOMEM;
        goto done;
    }
    if (nbep__output_commit(o, f + 1, d) < 0)
        goto done;
    st = NBEP_OK;
    if (o->xmf) {
        o->xmf_step[f] = step;
        o->xmf_time[f] = t;
        if (nbep_xdmf_due((size_t)o->n_frames, nbep_now() - o->xmf_last))
            st = nbep__output_xmf_write(o, true, d);
    }
done:
    nbep__output_close_id(&one_space);
    nbep__output_close_id(&vec_space);
    return st;
}

/* count rows of /stats/wall_impulse from wall (NULL: zeros). */
static int write_wall(nbep_output *o, const double *wall, size_t count, nbep_diag *d)
{
    hsize_t values = (hsize_t)count * o->n_planes, rows[2] = {count, o->n_planes};
    double *zeros = wall ? NULL : calloc(values ? (size_t)values : 1, sizeof *zeros);
    hid_t mem = H5Screate_simple(1, &values, NULL);
    int rc = -1;
    if (!wall && !zeros)
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for /stats/wall_impulse",
                      o->path);
    else if (mem < 0)
        HDF5_FAIL(d, o->path, "make the dataspace of %zu wall_impulse rows", count);
    else
        rc = append_rows(o, o->stats_wall, "/stats/wall_impulse", 2, o->n_stats, rows,
                         H5T_NATIVE_DOUBLE, mem, wall ? wall : zeros, d);
    nbep__output_close_id(&mem);
    free(zeros);
    return rc;
}

nbep_status nbep_output_stats(nbep_output *o, const nbep_step_stats *rows, const double *wall,
                              size_t count, nbep_diag *d)
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
        hsize_t start[1] = {nbep__stats_columns[c].word}, stride[1] = {STATS_N_COLUMNS};
        if (H5Sselect_hyperslab(mem, H5S_SELECT_SET, start, stride, n, NULL) < 0) {
            HDF5_FAIL(d, o->path, "select column %s of the stats rows",
                      nbep__stats_columns[c].name);
            goto done;
        }
        if (append_rows(o, o->stats[c], nbep__stats_columns[c].name, 1, o->n_stats, n,
                        column_mem_type(nbep__stats_columns[c].type), mem, rows, d) < 0)
            goto done;
    }
    if (o->stats_wall >= 0 && write_wall(o, wall, count, d) < 0)
        goto done;
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
    /* a resume refused before it began: the file as it was; a new file never published: its
     * partial file goes (release), and whatever is at its path stays */
    if (o->resume.pending || o->staged) {
        nbep__output_release(op);
        return NBEP_OK;
    }
    /* Stats rows appended after the last frame get counted too. */
    int rc = nbep__output_commit(o, o->n_frames, d);
    if (rc == 0 && o->xmf && o->n_frames > 0 && nbep__output_xmf_write(o, false, d) != NBEP_OK)
        rc = -1;
    if (s && rc == 0) {
        char *json = nbep_summary_to_json(s);
        if (!json) {
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: %s: no memory for the JSON summary",
                          o->path);
            rc = -1;
        } else {
            /* the group is made here, with its one attribute: a file whose run never got
             * here (killed, a full disk) has no /summary, as SPEC's readers expect (until
             * 2026-12-01 it had one without its json, from the start: a script's
             * "'summary' in f" took such a run for finished) */
            rc = o->summary < 0 ? make_group(o, "/summary", &o->summary, d) : 0;
            if (rc == 0)
                rc = nbep__output_write_string_attr(o->summary, o->path, "json", json, d);
            free(json);
        }
    }
    rc |= checked_close(&o->frame_step, o->path, "/frames/step", d);
    rc |= checked_close(&o->frame_time, o->path, "/frames/time", d);
    rc |= checked_close(&o->frame_pos, o->path, "/frames/position", d);
    rc |= checked_close(&o->frame_vel, o->path, "/frames/velocity", d);
    rc |= checked_close(&o->frame_img, o->path, "/frames/image", d);
    rc |= checked_close(&o->frame_tot, o->path, "/frames/totals", d);
    nbep__output_close_id(&o->tot_type);
    rc |= checked_close(&o->stats_wall, o->path, "/stats/wall_impulse", d);
    for (int c = 0; c < STATS_N_COLUMNS; c++)
        rc |= checked_close(&o->stats[c], o->path, nbep__stats_columns[c].name, d);
    for (int c = 0; c < N_CK_COLUMNS; c++)
        rc |= checked_close(&o->ck[c], o->path, nbep__ck_columns[c].name, d);
    rc |= checked_close(&o->frames_count, o->path, "attribute count of /frames", d);
    rc |= checked_close(&o->stats_count, o->path, "attribute count of /stats", d);
    rc |= checked_close(&o->summary, o->path, "/summary", d);
    rc |= checked_close(&o->file, o->path, "the file", d);
    if (o->reserved_end > 0) /* what no frame took goes back to the disk */
        nbep_file_unreserve(o->path, o->reserved_end);
    nbep__output_release(op);
    return rc ? NBEP_EIO : NBEP_OK;
}

