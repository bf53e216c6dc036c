/* Internals shared by the output module's files, one job each:
 *   output_hdf5.c    HDF5 helpers: error text, id closing, attribute and row readers/writers
 *   output.c         the run format's writer (create, frames, stats, close)
 *   output_resume.c  reopening a run to continue it (--resume)
 *   output_info.c    `nbep info`
 *   output_sweep.c   the sweep's table and the reading back of a run's overrides and summary
 * The only place besides them that sees hdf5.h. */
#ifndef NBEP_OUTPUT_IMPL_H
#define NBEP_OUTPUT_IMPL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <hdf5.h>

#include "nbep/compiler.h"
#include "nbep/output.h"
#include "nbep/periodic.h"
#include "nbep/stats.h"
#include "nbep/status.h"

/* The run file's root attribute `format`. */
#define FORMAT_NAME "nbep-1"
/* A sweep's summary.h5 (output_sweep.c), which is no run (is_run names it) */
#define SWEEP_FORMAT_NAME "nbep-sweep-1"

/* ---- the run format (output.c; read by output_resume.c) --------------------------------- */

/* The /stats columns: dataset name = field of nbep_step_stats, and its type. Written straight
 * from the caller's array of rows, one strided column at a time, so every field must be 8
 * bytes at a multiple of 8 (checked in output.c). A column is added here and in
 * nbep_step_stats, nowhere else. */
#define STATS_COLUMN_LIST(X)                                                                 \
    X(step, I64)                                                                             \
    X(checks, U64)                                                                           \
    X(predictions, U64)                                                                      \
    X(collisions, U64)                                                                       \
    X(kinetic_energy, F64)                                                                   \
    X(potential_energy, F64)                                                                 \
    X(max_overlap, F64)                                                                      \
    X(virial, F64)

enum column_type { COL_I64, COL_U64, COL_F64 };

enum {
#define X_ENUM(field, type) STATS_COL_##field,
    STATS_COLUMN_LIST(X_ENUM)
#undef X_ENUM
    STATS_N_COLUMNS
};

struct nbep__stats_column {
    const char *name;       /* "/stats/<field>" */
    size_t word;            /* offset of the field in 8-byte words */
    enum column_type type;
};
extern const struct nbep__stats_column nbep__stats_columns[STATS_N_COLUMNS];

/* The per-frame columns a predictive run keeps for --resume, in nbep_events_view's order. */
enum { N_CK_COLUMNS = 4 };
struct nbep__ck_column {
    const char *name;
    hid_t *file_type, *mem_type;   /* HDF5's type ids are variables, not constants */
};
extern const struct nbep__ck_column nbep__ck_columns[N_CK_COLUMNS];

/* /frames/totals's compound type, nbep_run_totals field by field (the file's and memory's):
 * a new id to close; H5I_INVALID_HID on failure. */
hid_t nbep__output_totals_type(void);

/* The room for what a resumed part changed (note_resume): the four keys and their values. */
#define RESUME_CHANGED_MAX 128

/* Invariants of an open nbep_output: every id field is a valid HDF5 id or H5I_INVALID_HID, so
 * one release path closes them all; n_frames rows of each /frames dataset and n_stats rows of
 * each /stats dataset are written; /frames@count = n_frames on disk once a frame returned. */
struct nbep_output {
    char *path;                    /* owned copy, for messages */
    size_t n_spheres;
    hid_t file;
    hid_t summary;                 /* the /summary group; its json attribute comes at close */
    hid_t frame_step, frame_time;  /* /frames/step, /frames/time */
    hid_t frame_pos, frame_vel;    /* H5I_INVALID_HID when the deck did not ask for them */
    hid_t frame_img;               /* /frames/image, when the box has a periodic axis */
    hid_t frame_tot;               /* /frames/totals (a resumed file made before 2026-11-30 has
                                    * none, and gets none) */
    nbep_run_totals tot;           /* the row the next frame writes there (nbep_output_totals) */
    hid_t tot_type;                /* its type (nbep__output_totals_type), with frame_tot */
    hid_t stats_wall;              /* /stats/wall_impulse (S, P), with stats and P > 0 */
    size_t n_planes;
    nbep_periodic pb;              /* the box's periodic axes: frames are written wrapped */
    nbep_vec3 *wrap_pos;           /* owned when pb.any: a frame's wrapped positions */
    int32_t *wrap_img;             /* and their image counts (3 per sphere) */
    hid_t stats[STATS_N_COLUMNS];  /* all H5I_INVALID_HID when the deck did not ask for them */
    hid_t frames_count;            /* the `count` attribute of /frames */
    hid_t stats_count;             /* the `count` attribute of /stats, if any */
    hsize_t n_frames, n_stats;     /* rows written */
    hid_t ck[N_CK_COLUMNS];        /* /checkpoint series (runs that keep event slots) */
    bool ck_allowed;               /* a new file: the first frame with events may add them */
    hid_t contacts[2];             /* /checkpoint/contacts and contacts_frame, once used */
    hid_t contacts_type;           /* with them: a record's type (output_contacts.c) */
    nbep_contact_rec *contacts_buf; /* owned, once used: a batch of records to write */
    /* the XDMF sidecar (RUN.xmf) that lets ParaView and VisIt open the run: rewritten as
     * frames come (nbep_xdmf_due) and at close; needs positions */
    bool xmf;                      /* the frames have positions: their steps and times listed */
    bool sidecar;                  /* and the sidecar written: decided once, as the handle opens
                                    * (nbep__output_writes_sidecar) */
    int64_t *xmf_step;             /* owned, xmf_cap: every frame's step and time so far */
    double *xmf_time;
    size_t xmf_cap;
    double xmf_last;               /* monotonic seconds of the last rewrite */
    /* a new file not yet renamed to path (nbep_output_create_staged): its temporary name,
     * owned, until nbep_output_publish; NULL once published or for a resumed file */
    char *staged;
    /* PATH.lock, held while the handle is open (nbep__output_lock), or -1 and NULL */
    int lock_fd;
    char *lock_path;
    /* Room kept on the disk ahead of the file (nbep__output_reserve): each frame first
     * reserves `room` bytes past the file's end, so that a disk, quota or file-size limit
     * that runs out is met there, before anything of the frame is written, with room left
     * for the close. room 0: none kept (a file system that cannot reserve, an HDF5 file
     * driver without a descriptor); reserved_end: the farthest offset reserved, given back
     * at close. */
    int64_t room, reserved_end;
    int room_fd;                   /* the descriptor HDF5 writes the file through, with room */
    /* a run opened to be resumed (nbep_output_open_resume), not yet changed: pending until
     * nbep_output_resume_begin, and closing it then writes nothing */
    struct {
        bool pending;              /* (the frames kept, up to the one resumed from: n_frames) */
        uint64_t stats_keep;       /* the /stats rows kept (stats: the file has /stats) */
        bool image, checkpoint, stats, wall, totals; /* the series the file has that a run
                                    * appends to */
        bool dropped;              /* complete frames after it are dropped (cells mode) */
        int64_t from;              /* the step of the frame resumed from */
        hsize_t trim;              /* frames kept once the run writes one: those before the
                                    * frames off output.every's grid that end the file (the
                                    * stop's own, which the first frame written replaces) */
        hsize_t ck_rows;           /* /checkpoint rows the file holds for its kept frames (fewer
                                    * where a part without event slots wrote the rest) */
        char changed[RESUME_CHANGED_MAX]; /* what this part runs with that the first part did not
                                    * (note_resume's ", restitution 0.9, order step"), or "" */
        bool other_algorithm;      /* an earlier part ran another algorithm than this one */
    } resume;
};

/* Sets the room a run of sc keeps ahead of o's open file (o->room, o->room_fd): a frame's rows
 * of every series, two intervals' /stats chunks, at e < 1 the contacts' records, and slack for
 * HDF5's metadata and the summary; none where HDF5 writes through no descriptor of its own
 * (another file driver than its default). */
void nbep__output_room(nbep_output *o, const nbep_scene *sc);
/* Reserves o->room bytes past the file's end (once o->file is open) before `what` is written:
 * -1 with a line when the disk, the quota or the process's file-size limit (ulimit -f) has no
 * room, the file as its last flush left it; 0 otherwise (a file system that cannot reserve
 * turns the room off: the run goes on as without it). */
int nbep__output_reserve(nbep_output *o, const char *what, nbep_diag *d);

/* A handle for path with every id invalid; NULL (and NBEP_ENOMEM in d) when out of memory. */
nbep_output *nbep__output_new(const char *path, size_t n_spheres, nbep_diag *d);
/* One writer of a path at a time: takes the lock on PATH.lock (a resume through a symbolic
 * link to a file: the file's) for the handle's life (released,
 * and the file removed, with the handle). Another process's run writing path holds it:
 * NBEP_EUSAGE and a line naming both. A lock that cannot be had for another reason (a file
 * system without locks, a folder that takes no new file) is done without. */
nbep_status nbep__output_lock(nbep_output *o, bool resume, nbep_diag *d);
/* Sets o's periodic geometry from sc and, when it has a periodic axis, the buffers frames are
 * wrapped in; -1 (NBEP_ENOMEM's message in d) when out of memory. */
int nbep__output_periodic(nbep_output *o, const nbep_scene *sc, nbep_diag *d);
/* Closes every id, ignoring errors (the failure paths; nbep_output_close checks them), frees
 * the handle and NULLs the pointer; NULL-safe. */
void nbep__output_release(nbep_output **op);
/* Makes the first `frames` frames and the stats rows so far durable and counted; -1 with the
 * reason in d on failure. */
int nbep__output_commit(nbep_output *o, hsize_t frames, nbep_diag *d);
/* Writes rows [first, end) of /checkpoint (o->ck open) as stale slots: kind none, rest -1; -1
 * with the reason in d on failure. */
int nbep__output_ck_stale(nbep_output *o, hsize_t first, hsize_t end, nbep_diag *d);
/* ---- the lasting state of dissipative runs (output_contacts.c) --------------------------- */

/* Frame row f's lasting state (ev->contacts), into /checkpoint/contacts (made when the file
 * has none); a frame without it (ev or ev->contacts NULL) marks its row as holding none
 * where the file has the datasets. 0, or -1 with the reason in d. */
int nbep__output_contacts_write(nbep_output *o, hsize_t f, const nbep_events_view *ev,
                                nbep_diag *d);
/* Frame row f's lasting state into a malloc'd *out (n_spheres records), or *out NULL when the
 * file keeps none for that frame. 0, -1 with the reason in d, or -2 (one line in d) where the
 * dataset's records lack a field of a run's (nbep__output_fields_missing). */
int nbep__output_contacts_read(nbep_output *o, hsize_t f, nbep_contact_rec **out, nbep_diag *d);
/* The bytes the datasets take in a file of n spheres (nbep_output_bytes). */
double nbep__output_contacts_bytes(size_t n);

/* Room for frame row f in the sidecar's lists; false when memory runs out. */
bool nbep__output_xmf_room(nbep_output *o, size_t f);
/* Whether a run whose frames have positions (or not) writes the sidecar of its file at path:
 * the one place that decides it (the name must be UTF-8 text, nbep_xdmf_can_name). */
bool nbep__output_writes_sidecar(bool positions, const char *path);
/* Removes the sidecar at o's path where o writes none: one an older run (or build) left there
 * would describe frames not in the file. As a resumed one is begun (a new file published
 * removes any, nbep_output_publish). */
void nbep__output_sidecar_stale(const nbep_output *o);
/* Rewrites the sidecar (RUN.xmf) for o's frames so far in the room kept ahead for it, given
 * back first; hold_again: then keeps the room again for the steps that follow (not at the
 * close), NBEP_EIO where there is none. NBEP_EIO, NBEP_ENOMEM. */
nbep_status nbep__output_xmf_write(nbep_output *o, bool hold_again, nbep_diag *d);

/* ---- HDF5 helpers (output_hdf5.c) ------------------------------------------------------- */

/* Adds "nbep: PATH: cannot WHAT: REASON", REASON being HDF5's innermost (most specific) error,
 * or the system's text for file-open failures, on one line. Call right after the failing HDF5
 * call: any later HDF5 call (even a close) clears the error stack. */
void nbep__output_hdf5_fail(nbep_diag *d, const char *file, int line, const char *path,
                            const char *what_fmt, ...) NBEP_PRINTF(5, 6);
#define HDF5_FAIL(d, path, ...) nbep__output_hdf5_fail((d), __FILE__, __LINE__, (path), __VA_ARGS__)
/* NBEP_OK when path is a run file (an HDF5 file whose root attribute `format` is FORMAT_NAME)
 * that may be opened with `mode` (access(2): R_OK, W_OK); else one line, "nbep: PATH: cannot
 * WHAT: REASON" (the system's, "not an HDF5 file") or "nbep: PATH: not an nbep-1 file (root
 * attribute format is ...)", and NBEP_EUSAGE for a name that is no file, a directory or the
 * wrong file (exit 2: the user's mistake), nbep_status_of_open's class for the system's other
 * refusals, NBEP_EIO where HDF5 fails to read it. For the files a user names (--resume, nbep
 * info), checked read-only before they are opened for what they are for: *file (when file is
 * not NULL) is then the file open read-only, for the caller to close, else it is closed. */
nbep_status nbep__output_run_openable(const char *path, int mode, const char *what,
                                      hid_t *file, nbep_diag *d);

/* Releases an id (ignoring errors: failure paths) and sets it invalid. */
void nbep__output_close_id(hid_t *id);
/* A variable-length UTF-8 string type (caller closes), or a negative id. */
hid_t nbep__output_utf8_string_type(void);
/* File access for the writer (1.8 format bounds, no lock) or a reader (default bounds, a
 * shared lock where the file system has locks); output.c's top comment says why. */
hid_t nbep__output_fapl(bool writer);

/* The readers and writers below return 0, or -1 with one line in d ("nbep: PATH: ..."). */
/* Writes attribute name on loc: n values (a scalar when n == 0) of mem_type as file_type. */
int nbep__output_write_attr(hid_t loc, const char *path, const char *name, hid_t file_type,
                            hid_t mem_type, hsize_t n, const void *buf, nbep_diag *d);
/* A UTF-8 string attribute, variable length so that h5dump prints it as text; NULL is "". */
int nbep__output_write_string_attr(hid_t loc, const char *path, const char *name,
                                   const char *value, nbep_diag *d);
/* A scalar string attribute (variable or fixed length) into a malloc'd *out; 0, or -2 when a
 * variable-length one points into a damaged global heap (which HDF5 would read past its
 * buffer), -1 on another failure, with a line in d. */
int nbep__output_read_string_attr(hid_t loc, const char *path, const char *name, char **out,
                                  nbep_diag *d);
/* Whether dataset name's type holds every field of the compound type want, each of its class:
 * the first that it lacks into missing ("" when none). HDF5 reads the fields both types have
 * and leaves the others as they were, so a file whose type lacks one (damaged, or edited by
 * hand) would pass for one that holds it: until 2026-11-30 totals without energy_initial
 * resumed with it 0. 0, or -1 with HDF5's reason in d. */
#define NBEP_FIELD_NAME_MAX 32
int nbep__output_fields_missing(hid_t file, const char *path, const char *name, hid_t want,
                                char missing[NBEP_FIELD_NAME_MAX], nbep_diag *d);
/* The run's JSON summary (the /summary group's json attribute) into a malloc'd *json, NULL
 * where the file has none (a run killed before its end; before its first frame, without the
 * group too). 0, or -1 with HDF5's reason in d. */
int nbep__output_summary_json(hid_t file, const char *path, char **json, nbep_diag *d);
/* A numeric attribute as mem_type into buf. */
int nbep__output_read_attr(hid_t loc, const char *path, const char *name, hid_t mem_type,
                           void *buf, nbep_diag *d);
/* The first dimension of dataset name (its row count). */
int nbep__output_dataset_rows(hid_t file, const char *path, const char *name, hsize_t *rows,
                              nbep_diag *d);
/* Row `row` of dataset name (rows first; the rest of its shape is per_row values: 1 for a
 * 1-D dataset) as mem_type into buf. */
int nbep__output_read_row(hid_t file, const char *path, const char *name, hsize_t row,
                          hsize_t per_row, hid_t mem_type, void *buf, nbep_diag *d);
/* Complete rows of group's datasets (its count attribute; the length of dataset when a file
 * has no such attribute) and how many rows dataset holds past them: 0; -1 after a failure,
 * -2 where the count is past the rows (a damaged file), each after a message. */
int nbep__output_complete_rows(hid_t file, const char *path, const char *group,
                               const char *dataset, uint64_t *complete, hsize_t *more,
                               nbep_diag *d);

#endif
