/* Contact times (paper Appendix 1): sphere-sphere as a closed-form quadratic when the two
 * accelerations are equal, as a quartic through GSL's polynomial solver (then Newton-polished)
 * when they differ; sphere-plane as a quadratic. The only user of GSL. */
#ifndef NBEP_PREDICT_H
#define NBEP_PREDICT_H

#include <math.h>
#include <stdbool.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

/* "No contact ahead". */
#define NBEP_NEVER INFINITY

/* Per-thread workspace for the quartic (GSL's companion-matrix solver). Create before any
 * parallel region; one per thread; not shared. */
typedef struct nbep_predict_ws nbep_predict_ws;
NBEP_MUST_CHECK nbep_status nbep_predict_ws_create(nbep_predict_ws **out, nbep_diag *d);
void nbep_predict_ws_destroy(nbep_predict_ws **ws);

/* Earliest t >= 0 at which |dp + dv t| = sigma while closing (d|dp|/dt < 0), for a pair with
 * equal accelerations; dp = p2 - p1, dv = v2 - v1, sigma = r1 + r2. NBEP_NEVER when they do
 * not meet. A pair already touching or overlapping (|dp| <= sigma) and closing returns 0. */
double nbep_predict_pair_quadratic(nbep_vec3 dp, nbep_vec3 dv, double sigma);

/* The same for any relative acceleration da = a2 - a1: quadratic when da is exactly zero,
 * otherwise the smallest valid real root of the quartic |dp + dv t + da t^2/2|^2 = sigma^2,
 * polished by Newton. ws may be NULL only when da is zero. */
double nbep_predict_pair(nbep_vec3 dp, nbep_vec3 dv, nbep_vec3 da, double sigma,
                         nbep_predict_ws *ws);

/* Earliest t >= 0 at which a sphere's gap to a plane, g(t) = gap + vn t + an t^2/2, reaches
 * zero while closing (g'(t) < 0). gap = n.p - offset - r, vn = n.v, an = n.a. NBEP_NEVER when
 * it never does. Touching or overlapping (gap <= 0) and closing (vn < 0) returns 0. */
double nbep_predict_plane(double gap, double vn, double an);

#endif
