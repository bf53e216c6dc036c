/* XDMF sidecars: RUN.xmf beside RUN.h5 describes the run's frames to ParaView and VisIt (open
 * RUN.xmf with the "XDMF Reader"; VisIt: the Xdmf plugin) as a time series of point sets, one
 * point per sphere, without copying any data: every frame is a hyperslab of /frames/position
 * (and /frames/velocity), with the radius and mass from /spheres as point attributes. In
 * ParaView, the Point Gaussian representation with "Scale By Array" = radius (scale factor 1,
 * "Use Scale Function" off) draws the spheres at their true size.
 *
 * Plain text: no HDF5 or XML library. The file names the run file by its base name, so RUN.h5
 * and RUN.xmf can be moved together. */
#ifndef NBEP_OUTPUT_XDMF_H
#define NBEP_OUTPUT_XDMF_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"

/* The sidecar's path for a run file: h5_path with a trailing ".h5" replaced by ".xmf" (".xmf"
 * appended when h5_path does not end in ".h5"). malloc'd; NULL when out of memory. */
char *nbep_xdmf_path(const char *h5_path);

/* Whether a sidecar can name the run file h5_path: its base name is UTF-8 without control
 * characters, as XML text must be. A name of other bytes (Latin-1, "r\xe9sultat.h5") cannot
 * be written into XML, and the file it would name is not the one a reader's UTF-8 opens: such
 * a run writes no sidecar (until 2026-12-02 it wrote one that XML parsers refuse). */
bool nbep_xdmf_can_name(const char *h5_path);

/* Whether the file at path is an XDMF sidecar (what `nbep info` and `--resume` are often
 * handed instead of their run: the two lie side by side), and the run file it describes, its
 * name as nbep's sidecar records it at its top, into name ("" where the sidecar does not say:
 * one not written by nbep). */
bool nbep_xdmf_run_of(const char *path, char *name, size_t len);

/* The other run file whose sidecar is h5_path's, when it is there and the sidecar names it
 * (nbep_xdmf_run_of): `-o x` and `-o x.h5` have one sidecar, x.xmf, so a run at x would
 * replace x.h5's. malloc'd; NULL when none, or out of memory. */
char *nbep_xdmf_other_run(const char *h5_path);

/* Writes the sidecar of the run file h5_path describing its first n_frames frames: frame k
 * (row k of /frames/position) is at step steps[k] and time times[k] (both borrowed, n_frames
 * entries; steps may be NULL, then frames are named by their index). n_spheres is the row
 * length of /frames/position; has_velocity says whether /frames/velocity exists. Call only
 * for runs that write positions. The whole file is written to "SIDECAR.tmp" and renamed over
 * the sidecar, so a reader (or a kill) sees the old or the new file, never a mix. NBEP_EIO
 * ("nbep: PATH: cannot write the XDMF sidecar: REASON"), NBEP_ENOMEM. One writing thread. */
NBEP_MUST_CHECK nbep_status nbep_xdmf_write(const char *h5_path, size_t n_spheres,
                                            size_t n_frames, const int64_t *steps,
                                            const double *times, bool has_velocity,
                                            nbep_diag *d);

/* The bytes of the sidecar a run of n_spheres writes beside h5_path at its end: frames at steps
 * 0, every, 2 every, ... and at `steps` (the last), frame k at time step * dt, as the run writes
 * them (nbep_output_frame_events). Exact to the byte up to 256 frames (the text measured with
 * the very calls that write it); past that, 256 frames spread over the run stand for the rest
 * (within a few bytes a frame). 0 when every is 0. `nbep check` counts it in the run's output. */
double nbep_xdmf_bytes(const char *h5_path, size_t n_spheres, uint64_t steps, uint64_t every,
                       double dt, bool has_velocity);

/* At least the bytes of a sidecar beside h5_path listing n_frames frames of n_spheres, whatever
 * their steps and times (every frame counted at the longest text a step and a time can take:
 * a few dozen bytes a frame over). O(1): the room a writer keeps ahead for its next rewrite. */
double nbep_xdmf_bytes_bound(const char *h5_path, size_t n_spheres, size_t n_frames,
                             bool has_velocity);

/* Seconds between rewrites of a growing sidecar once its frame count is past the first few:
 * a run killed at any moment has a sidecar at most this old. */
#define NBEP_XDMF_REWRITE_SECONDS 30.0

/* Whether a writer that has just added frame number n_frames (1-based count) should rewrite
 * the sidecar now, seconds_since_last after its previous rewrite: for the first 8 frames,
 * whenever the count reaches a power of two, and once NBEP_XDMF_REWRITE_SECONDS have passed.
 * A rewrite costs O(frames) (about 1.5 kB per frame), so rewriting after every frame would
 * cost O(frames^2) over a run; this keeps the total to about twice the final sidecar plus one
 * sidecar per 30 s. The run's close rewrites it always. */
bool nbep_xdmf_due(size_t n_frames, double seconds_since_last);

#endif
