/* Spheres and planes as a struct of arrays: sphere i is index i everywhere (frames, event
 * slots, BVH leaves). Only state.c allocates or frees these arrays; they never grow in a run. */
#ifndef NBEP_STATE_H
#define NBEP_STATE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

typedef struct nbep_state {
    size_t n;                  /* spheres */
    nbep_vec3 *pos, *vel;      /* owned, length n, at the current time */
    nbep_vec3 *acc;            /* owned: own uniform acceleration (gravity unless overridden) */
    double *radius, *mass;     /* owned, length n */
    int32_t *image;            /* owned, length 3n: periods crossed per periodic axis (SPEC
                                * /frames/image); all 0 without periodic axes */
    double period[3];          /* the box's side on periodic axes, 0 on others: the unwrapped
                                * centre is pos + image * period (potential energy) */
    size_t n_planes;
    nbep_vec3 *plane_normal;   /* owned, unit, pointing into the live region */
    double *plane_offset;      /* owned: plane = {x : n.x = offset}, live where n.x > offset */
} nbep_state;

/* Allocates zeroed arrays for n spheres and n_planes planes (64-byte aligned). On failure the
 * state is left empty (safe to fini) and NBEP_ENOMEM is returned with a message naming n. */
NBEP_MUST_CHECK nbep_status nbep_state_init(nbep_state *s, size_t n, size_t n_planes,
                                            nbep_diag *d);
/* Frees the arrays; safe on a zeroed or already finalised state. */
void nbep_state_fini(nbep_state *s);
/* Deep copy of src into dst (dst uninitialised on entry). */
NBEP_MUST_CHECK nbep_status nbep_state_copy(nbep_state *dst, const nbep_state *src,
                                            nbep_diag *d);
/* dst (uninitialised on entry) gets src's arrays themselves; src keeps its counts and
 * period, with NULL for every array. A run's start with one copy of the spheres, never two:
 * a copy left the scene's radii and masses beside the run's for the whole run, and the
 * motion twice at once while the run was set up. */
void nbep_state_take(nbep_state *dst, nbep_state *src);
/* Bytes nbep_state_init would allocate, for memory estimates. */
size_t nbep_state_bytes(size_t n, size_t n_planes);

/* True when every position, velocity and acceleration is finite. */
bool nbep_state_all_finite(const nbep_state *s);
/* The largest radius of s's spheres (0 when it has none). */
double nbep_state_max_radius(const nbep_state *s);
/* True when no sphere accelerates (every acceleration exactly zero): every sphere flies
 * straight, nothing rests (the predictive algorithm's plan, the cells mode's skin). */
bool nbep_state_free_flight(const nbep_state *s);

struct nbep_grid;
/* Largest overlap r_i + r_j - |p_i - p_j| over sphere pairs and r_i - (n.p_i - offset) over
 * sphere-plane pairs, 0 when none overlap; on a periodic axis (s->period) a pair's distance is
 * the nearest way round, as the engine takes it. rel_out (may be NULL) receives the largest overlap
 * divided by the smaller radius involved. Uses a uniform cell grid: O(n) expected time. ws
 * (borrowed) is a grid with room for s->n spheres, reused so that a run allocates nothing per
 * call; NULL makes one for this call (tests, start-up). i_out/j_out (may be NULL) receive the
 * worst pair, j_out = n + p for plane p; both SIZE_MAX when nothing overlaps. */
NBEP_MUST_CHECK nbep_status nbep_state_max_overlap(const nbep_state *s, struct nbep_grid *ws,
                                                   double *max_out, double *rel_out,
                                                   size_t *i_out, size_t *j_out,
                                                   nbep_diag *d);

/* The largest overlap found so far (as nbep_state_max_overlap reports it): its depth, its
 * depth over the smaller radius, and the pair (SIZE_MAX: none). */
typedef struct nbep_overlap {
    double max, rel;
    size_t i, j;
} nbep_overlap;
#define NBEP_OVERLAP_NONE ((nbep_overlap){0.0, 0.0, SIZE_MAX, SIZE_MAX})

/* nbep_state_max_overlap in parts, for threads that share it: one thread sorts the centres
 * into g (room for s->n spheres) and gets the largest radius, then each thread, after a
 * barrier, folds the overlaps of spheres [lo, hi) (with their planes, and with every other
 * sphere) into its own best. The largest depth and relative depth over the parts are the
 * whole check's, whatever the split. */
double nbep_state_overlap_grid(const nbep_state *s, struct nbep_grid *g);
void nbep_state_overlap_part(const nbep_state *s, const struct nbep_grid *g, double rmax,
                             size_t lo, size_t hi, nbep_overlap *best);

#endif
