/* Lasting contacts (granular scenes): the geometry of a sphere held by several contacts at
 * once. A contact is a unit normal n pointing from the support (a plane, or a sphere that does
 * not move) to the held sphere; the support can push along n but never pull. Pure functions
 * on values, no state: every algorithm (and any future scheduler) calls these. */
#ifndef NBEP_CONTACT_H
#define NBEP_CONTACT_H

#include <stdbool.h>

#include "nbep/vec3.h"

/* At most this many contacts hold one sphere at once (three independent ones fix it in 3D;
 * one more lets a sphere keep a candidate while it settles into a pocket). */
#define NBEP_CONTACT_MAX 4

/* Relative tolerance of the constraint tests: a component below 1e-12 of |a| counts as zero.
 * Each projection below takes a few roundings (~1e-16 relative), so this is far above their
 * round-off and far below any physical difference in accelerations. */
#define NBEP_CONTACT_TOL 1e-12

/* The motion a sphere with acceleration a can take while its k contacts n[0..k) push but never
 * pull: the point nearest to a of the cone {x : x.n_j >= 0 for all j} (the frictionless
 * contact forces, found by trying the active sets from the smallest up). Returns x and writes
 * in *active the bit mask of the contacts that carry load (x.n_j = 0, force >= 0). With one
 * active contact x = a - (a.n) n; with two, x runs along their common edge; with three
 * independent ones x = 0 exactly. A contact pulled away from (a.n_j > 0) is not active. */
nbep_vec3 nbep_contact_project(nbep_vec3 a, const nbep_vec3 *n, int k, unsigned *active);

/* nbep_contact_project, and what each contact pushes: x = a + sum_j mu[j] n[j] with
 * mu[j] >= 0 (to the tolerance above) on the active contacts and 0 on the others. Where
 * only degenerate sets are left (x = 0, normals dependent to round-off) the split is not
 * defined and every mu is 0. A sphere that leans on planes and is struck passes mu[j] times
 * the impulse to plane j (/stats/wall_impulse). */
nbep_vec3 nbep_contact_project_push(nbep_vec3 a, const nbep_vec3 *n, int k, unsigned *active,
                                    double mu[NBEP_CONTACT_MAX]);

/* v with its components along the contacts in mask removed (v tangent to every one of them):
 * v - (v.n) n for one, its part along the common edge for two, 0 for three or more
 * independent normals. */
nbep_vec3 nbep_contact_tangent(nbep_vec3 v, const nbep_vec3 *n, int k, unsigned mask);

#endif
