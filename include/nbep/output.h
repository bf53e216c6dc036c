/* HDF5 output in layout "nbep-1" (SPEC); the JSON summary it stores is summary.h's. The
 * output module's files (output_impl.h) are the only users of hdf5.h. One writing thread:
 * call only from thread 0 between barriers, or outside parallel regions.
 *
 * Beyond SPEC's table the file holds root attributes build_flags, build_commit and deck_path,
 * and a u64 attribute `count` on /frames and on /stats: the rows known complete on disk. A run
 * killed while flushing a frame can leave one more row whose data did not reach the disk;
 * readers of interrupted runs should take the first `count` rows. Files use the HDF5 1.8
 * format so that HDF5 tools open them after a crash (see output.c). */
#ifndef NBEP_OUTPUT_H
#define NBEP_OUTPUT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "nbep/compiler.h"
#include "nbep/contact.h"
#include "nbep/scene.h"
#include "nbep/state.h"
#include "nbep/stats.h"
#include "nbep/status.h"
#include "nbep/summary.h"

typedef struct nbep_output nbep_output;

/* Creates path (replacing a file there) and writes the root attributes (format "nbep-1",
 * version, algorithm, steps, dt, threads, seed, restitution, gravity, deck, overrides, build
 * flags), /spheres/{radius,mass,acceleration}, /planes/{normal,offset}, and empty extendable
 * /frames/{step,time,position?,velocity?} and /stats/... (when sc->out_stats). sc is
 * borrowed (only read here); threads is the resolved thread count. The file is built as
 * "PATH.partial" and renamed to path when complete. NBEP_EIO with HDF5's reason on failure
 * ("nbep: PATH: cannot ...: reason"), and then no new file is left behind; NBEP_ENOMEM. */
NBEP_MUST_CHECK nbep_status nbep_output_create(const char *path, const nbep_scene *sc,
                                               int threads, nbep_output **out, nbep_diag *d);
/* nbep_output_create in two parts, for a caller that may still fail between them and must
 * then leave an older file at path as it was: the file is made under "PATH.partial" and
 * renamed to path by nbep_output_publish (NBEP_OK at once for a published or resumed handle;
 * a failed rename leaves the handle staged); closing a handle never published removes the
 * partial file and writes nothing at path. */
NBEP_MUST_CHECK nbep_status nbep_output_create_staged(const char *path, const nbep_scene *sc,
                                                      int threads, nbep_output **out,
                                                      nbep_diag *d);
NBEP_MUST_CHECK nbep_status nbep_output_publish(nbep_output *o, nbep_diag *d);
/* The frames a run of sc writes (the first, every output.every-th step's and the last step's)
 * and the bytes of its file, about: the data of the frames, the checkpoints beside them when
 * `events` (a run that keeps event slots, nbep_sim_keeps_events) and the lasting state of two
 * frames when also `contacts` (nbep_sim_keeps_contacts), the stats and HDF5's own headers (an
 * estimate for `nbep check`). */
uint64_t nbep_output_frames(const nbep_scene *sc);
double nbep_output_bytes(const nbep_scene *sc, bool events, bool contacts);
/* The bytes of the XDMF sidecar (output_xdmf.h) a run of sc writes at its end beside its file
 * at path (sc->output_file, or a sweep's run file: the sidecar names it): 0 when it writes none
 * (no positions in its frames). nbep_output_bytes leaves it out. */
double nbep_output_sidecar_bytes(const nbep_scene *sc, const char *path);
/* Whether o's frames have positions but its file's name cannot be written in the sidecar (not
 * UTF-8 text, nbep_xdmf_can_name), so that no sidecar is written: a run warns of it. */
bool nbep_output_sidecar_unnamed(const nbep_output *o);

/* Appends one frame (step, step*dt, and the fields the deck asked for) and flushes the file;
 * on NBEP_OK the frame and every stats row appended before it survive a kill -9. s is
 * borrowed and must have the scene's sphere count. NBEP_ENUMERIC (nothing written) when a
 * position or velocity is not finite, NBEP_EIO on a write failure. */
NBEP_MUST_CHECK nbep_status nbep_output_frame(nbep_output *o, int64_t step, double dt,
                                              const nbep_state *s, nbep_diag *d);

/* One sphere's lasting state in a dissipative predictive run (e < 1 with physics.tc > 0, or
 * anything accelerating), which no frame holds and without which a resumed run parts from the
 * uninterrupted one (/checkpoint/contacts, beyond SPEC): the TC clock, the acceleration it
 * flies with, its settling window, the immobile faces it met last (caged) and the contacts
 * holding it. No NaN or inf: times that are -inf in the run (none yet) are flagged instead. */
#define NBEP_CONTACT_FACES (NBEP_CONTACT_MAX - 1) /* faces remembered per sphere (CAGE_FACES, pred_impl.h) */
typedef struct nbep_contact_rec {
    double t_last;                          /* last sphere collision (when has_last) */
    double aeff[3];                         /* the acceleration it flies with */
    double peak2;                           /* settling: highest speed^2 since the step began */
    double face_t[NBEP_CONTACT_FACES];      /* faces met, newest first: when (0 for none) */
    double face_n[NBEP_CONTACT_FACES][3];   /* the face's normal towards the sphere */
    double face_p[NBEP_CONTACT_FACES][3];   /* the sphere's centre then */
    int32_t face_who[NBEP_CONTACT_FACES];   /* plane p, held sphere j as -1 - j, INT32_MIN none */
    int32_t rest_who[NBEP_CONTACT_MAX];                  /* contacts holding it, as face_who (rest_n of them) */
    uint32_t slow;                          /* settling: whole steps slow in a row */
    uint8_t has_last;                       /* t_last is a collision's time (else none yet) */
    uint8_t rest_n;
    uint8_t rest_still;                     /* held still */
    uint8_t rest_current[NBEP_CONTACT_MAX];              /* a sphere contact's support has not reacted since
                                             * it took the load (1; planes 0) */
} nbep_contact_rec;

/* What a predictive run keeps beside each frame so that `--resume` continues exactly as an
 * uninterrupted run would: every sphere's event slot (kind NONE where the slot was stale) and
 * the plane it rests on (-1 for none). Arrays of N, borrowed. A dissipative run also keeps
 * its spheres' lasting state (contacts, not NULL): contacts(ctx, lo, hi, out) writes spheres
 * [lo, hi)'s records into out; the file keeps those of its last two frames. */
typedef struct nbep_events_view {
    const double *time;
    const uint32_t *partner;
    const uint8_t *kind;
    const int32_t *rest;
    void (*contacts)(const void *ctx, size_t lo, size_t hi, nbep_contact_rec *out);
    const void *contacts_ctx;
} nbep_events_view;

/* nbep_output_frame plus, when ev is not NULL, the frame's row of
 * /checkpoint/{event_time,event_partner,event_kind,rest}: a new file gets /checkpoint with its
 * first frame when that frame has events (runs whose algorithm keeps event slots: predictive);
 * a resumed file has it or not as it was made. All rows of one frame become visible together
 * (the /frames count attribute). */
NBEP_MUST_CHECK nbep_status nbep_output_frame_events(nbep_output *o, int64_t step, double dt,
                                                     const nbep_state *s,
                                                     const nbep_events_view *ev, nbep_diag *d);

/* The run's totals from its step 0 up to a frame (/frames/totals, a compound dataset of one
 * row a frame, beyond SPEC): what its summary counts and sums over the steps, so that a
 * resumed run's summary is the whole run's, as the uninterrupted run's (until 2026-11-30 it
 * counted the resumed part alone: a granular run stopped by a job's time limit reported the
 * energy it lost since the resume, and a sweep could not continue such a run). */
typedef struct nbep_run_totals {
    uint64_t checks, predictions;           /* the summary's counters */
    uint64_t sphere_collisions, plane_collisions;
    uint64_t quiet_steps;
    double energy_initial;                  /* at step 0 */
    double max_overlap, max_overlap_rel;    /* the largest so far */
    double virial, kinetic_energy;          /* /stats/virial and kinetic_energy summed over
                                             * the steps (the summary's pressure) */
} nbep_run_totals;
/* The totals the next frame's row of /frames/totals holds (a run sets them before each
 * frame; a frame written without is a row of zeros). */
void nbep_output_totals(nbep_output *o, const nbep_run_totals *t);

/* Where a run continues from: its last complete frame. */
typedef struct nbep_resume {
    int64_t step;                 /* the frame's step */
    int64_t last_step;            /* the file's last complete frame's step (later than step
                                   * where cells mode resumes from an earlier frame) */
    int64_t kept_step;            /* the file's last frame kept: step, or the frame before it
                                   * where step is off output.every's grid (a stop's own
                                   * frame, which the uninterrupted run does not write) */
    bool restitution_kept;        /* the deck's restitution is the file's (a dissipative run
                                   * resumed without its lasting state, contacts NULL, then
                                   * parts from the uninterrupted run: run.c says so) */
    size_t n;
    nbep_vec3 *pos, *vel;         /* owned, n each, until nbep_resume_apply moves them */
    bool has_events;              /* the file has /checkpoint rows for this frame */
    double *event_time;           /* owned when has_events, n each */
    uint32_t *event_partner;
    uint8_t *event_kind;
    int32_t *rest;
    int32_t *image;               /* owned when the box is periodic: 3n image counts */
    nbep_contact_rec *contacts;   /* owned: the frame's lasting state, n (NULL: the file has
                                   * none for it) */
    bool has_totals;              /* the file has /frames/totals for this frame */
    nbep_run_totals totals;       /* then the run's totals at it */
} nbep_resume;
void nbep_resume_fini(nbep_resume *r);
/* Puts r's positions, velocities and image counts into s (a state of r's n spheres, the scene
 * the run is made from) and frees r's copies, so that the run's own structures are allocated
 * while only one copy of them is held (at N = 256000 the copies were 15 MB, an eighth of the
 * run's peak memory). r keeps its step and event slots. */
void nbep_resume_apply(nbep_resume *r, nbep_state *s);

/* Whether a and b name one existing file (the same device and inode): an output path that
 * names the deck would replace it. */
bool nbep_output_same_file(const char *a, const char *b);

/* `nbep run DECK --resume RUN.h5`: opens an existing run for appending. Checks that it is an
 * nbep-1 file of the run sc makes (sphere and plane counts, radii, masses, accelerations,
 * planes, box and dt), that its frames hold positions and velocities, and that run.steps lies
 * past the frame it continues from; reads that frame (the last complete one; with
 * run.neighbors = "cells" the last at a multiple of output.every, where such a run continues
 * bit for bit) and, where the file has /checkpoint, its event slots into *r. Writes nothing:
 * closing the handle now leaves the file as it was (a run refused after this).
 * NBEP_EIO for a file that cannot be read, NBEP_EDECK when deck and file disagree or there is
 * nothing to continue. */
NBEP_MUST_CHECK nbep_status nbep_output_open_resume(const char *path, const nbep_scene *sc,
                                                    nbep_output **out, nbep_resume *r,
                                                    nbep_diag *d);
/* The resumed run starts: drops the rows written after that frame (later frames, incomplete
 * ones, stats rows of later steps), removes the old summary, sets the root attribute `steps`
 * to sc->steps and adds a line to the root attribute `resumed` (the step resumed from,
 * `threads`, this build and sc's overrides). Frames and stats then append as after
 * nbep_output_create. NBEP_OK at once for a handle not opened by nbep_output_open_resume or
 * begun already; NBEP_EIO when the file cannot be written. */
NBEP_MUST_CHECK nbep_status nbep_output_resume_begin(nbep_output *o, const nbep_scene *sc,
                                                     int threads, nbep_diag *d);
/* What the part that nbep_output_resume_begin began runs with that the file's first part did
 * not ("restitution 0.9, order step": the words its line in `resumed` ends with), or NULL
 * (none, or not a resumed run). Valid until the handle is closed. */
const char *nbep_output_resume_changes(const nbep_output *o);
/* Whether an earlier part of the file ran another algorithm than that part (the first or
 * any resumed one; false where not resumed). */
bool nbep_output_resume_other_algorithm(const nbep_output *o);
/* Appends count rows (borrowed) to /stats, and their rows of /stats/wall_impulse from wall
 * (count x n_planes, row by row; NULL: zeros); they reach the disk with the next frame or
 * close. Only when the scene asked for stats. NBEP_EIO on failure. */
NBEP_MUST_CHECK nbep_status nbep_output_stats(nbep_output *o, const nbep_step_stats *rows,
                                              const double *wall, size_t count, nbep_diag *d);
/* Writes the /summary json attribute (when s is not NULL), flushes and closes; NULL-safe,
 * NULLs the pointer. Even on error (NBEP_EIO) the handle and all HDF5 ids are released. */
NBEP_MUST_CHECK nbep_status nbep_output_close(nbep_output **o, const nbep_summary *s,
                                              nbep_diag *d);

/* `nbep info RUN.h5`: prints the run's metadata (root attributes but the deck text, counts of
 * spheres, planes, frames and stats rows, last frame's step and time) and its summary to f.
 * Works on interrupted runs and runs still being written (no summary yet: says so); prints
 * nothing on failure. NBEP_EIO with one line when the file cannot be read or is not an
 * nbep-1 file. */
NBEP_MUST_CHECK nbep_status nbep_output_info(const char *path, FILE *f, nbep_diag *d);

/* Disables HDF5's automatic error printing; call once in main before any thread starts. */
void nbep_output_library_init(void);

/* Whether a run file's root attribute `resumed` (its lines as nbep_output_resume_begin writes
 * them) says a part ran with another algorithm, restitution, neighbour mode or order than the
 * file's first part (a sweep then takes the file for another run's). */
bool nbep_output_resumed_changed(const char *resumed);

#endif
