/* Bounding volume hierarchy over the spheres' axis-aligned boxes, the pre-filter of the
 * "seminaive" algorithm (paper Section 2.2): rebuilt every step from the current positions,
 * then queried once per sphere for the later spheres whose boxes touch its own. The filter has
 * no false negatives: every pair whose boxes overlap or touch, in exact arithmetic on the
 * stored doubles, is reported; the caller makes the exact sphere test afterwards. */
#ifndef NBEP_BVH_H
#define NBEP_BVH_H

#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/state.h"
#include "nbep/status.h"

/* Most spheres nbep_bvh_create accepts: node indices (up to 2n - 1) stay below 2^32. */
#define NBEP_BVH_MAX_SPHERES ((size_t)1 << 31)

/* Bound on the edges from the root to any leaf. Each split either halves a run of equal
 * Morton codes or separates codes on a bit strictly lower than its parent's (63 code bits), so
 * no path holds more than 63 + log2(NBEP_BVH_MAX_SPHERES) = 94 splits. Queries keep their
 * pending nodes in a fixed array of NBEP_BVH_MAX_DEPTH + 1 entries on the C stack. */
#define NBEP_BVH_MAX_DEPTH 94

typedef struct nbep_bvh nbep_bvh;

/* Allocates, once, everything a hierarchy over up to n_max spheres needs (about
 * nbep_bvh_bytes(n_max) bytes); the result holds no tree until nbep_bvh_build. *out is owned
 * by the caller (free with nbep_bvh_destroy) and written only on success. Returns NBEP_ENOMEM
 * when memory runs out, NBEP_EUSAGE when n_max > NBEP_BVH_MAX_SPHERES, each with a message. */
NBEP_MUST_CHECK nbep_status nbep_bvh_create(size_t n_max, nbep_bvh **out, nbep_diag *d);
/* NULL-safe; NULLs the pointer. */
void nbep_bvh_destroy(nbep_bvh **b);
/* Bytes nbep_bvh_create(n_max) allocates, for memory estimates. */
size_t nbep_bvh_bytes(size_t n_max);

/* Rebuilds the tree over the boxes [pos - radius, pos + radius] of the s->n spheres of s
 * (s->n <= n_max; s is borrowed and must not change until the queries of this build are done).
 * Allocates nothing; O(n) for the Morton-code radix sort plus O(n log n) for the splits. Not
 * thread-safe: one thread builds while no thread queries. */
void nbep_bvh_build(nbep_bvh *b, const nbep_state *s);

/* Calls visit(ctx, j) once for every sphere j > i whose box overlaps or touches the box of
 * sphere i (both boxes from s, which must be the state the tree was built from), in no
 * particular order, though the same order on every call. Read-only on the tree: any number of
 * threads may query at once. Uses no heap, only a fixed stack array. Returns the number of
 * tree nodes examined (a measure of the filter's cost). */
size_t nbep_bvh_query_later(const nbep_bvh *b, const nbep_state *s, size_t i,
                            void (*visit)(void *ctx, uint32_t j), void *ctx);

/* The same for sphere i's box moved by shift (a periodic box's copy of i, whose partners
 * across a face lie within reach of it), widened by a few roundings so that no pair within
 * touch of the copy is missed. */
size_t nbep_bvh_query_later_shifted(const nbep_bvh *b, const nbep_state *s, size_t i,
                                    nbep_vec3 shift, void (*visit)(void *ctx, uint32_t j),
                                    void *ctx);

/* Edges from the root to the deepest leaf of the last build (0 for a single leaf or an empty
 * tree); never above NBEP_BVH_MAX_DEPTH. */
size_t nbep_bvh_depth(const nbep_bvh *b);
/* Nodes in the last build (0 when it had no spheres). */
size_t nbep_bvh_node_count(const nbep_bvh *b);

/* Invariant check for tests: every sphere of s sits in exactly one leaf, every node's box
 * contains its children's (or its spheres') boxes exactly, every node's largest sphere index
 * is right, and the depth is within NBEP_BVH_MAX_DEPTH. Returns the number of problems found
 * and describes the first in *d. */
size_t nbep_bvh_check(const nbep_bvh *b, const nbep_state *s, nbep_diag *d);

#endif
