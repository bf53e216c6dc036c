/* Bounding volume hierarchy over the spheres' axis-aligned boxes: the pre-filter of the
 * "seminaive" algorithm (paper Section 2.2), which keeps the naive algorithm's detection but
 * tests only the pairs whose boxes touch.
 *
 * Rebuild, not refit. Spheres of a gas move and mix: after a refit (same topology, boxes
 * recomputed bottom-up) two spheres that shared a leaf drift apart and their parent's box
 * spans the gap between them, so boxes only grow and every query examines more nodes step
 * after step. A fresh build costs little next to the n queries it serves (bench_bvh: 8-20% of
 * one step's queries on one thread, see the table below), so we rebuild every step and the
 * query cost stays that of a fresh tree for the whole run. The build is serial: with T threads
 * sharing the queries its share of a step grows about T times, the place to parallelise first
 * (radix sort passes, then the top subtrees) if seminaive must scale.
 *
 * Build: a linear BVH. Each sphere's centre gets a 63-bit Morton code (21 bits per axis, on
 * cubic cells over the centres' bounding box, so that elongated domains still get compact
 * nodes); an LSD radix sort orders spheres by code (stable, so equal codes stay in index order
 * and the build is deterministic). Then a top-down pass splits each range of codes where its
 * highest differing bit flips (Karras 2012), which halves the range's cell in space; a range
 * of equal codes (coincident or very close centres) is split at its median. Ranges of at most
 * LEAF_MAX spheres become leaves. Node boxes are computed bottom-up after the split as the
 * exact min/max of the children's boxes: no inflation, no rounding, so a node's box contains
 * every box below it. The code decides only the shape of the tree, never whether a pair is
 * found, so quantization and NaN or infinite extents cannot cause false negatives.
 *
 * Exactness of the filter: a sphere's box is [p - r, p + r] rounded to double, computed by the
 * same expressions in build and query, and boxes are compared with <=. Rounding is monotone,
 * so when two boxes touch or overlap in exact arithmetic their rounded bounds still satisfy
 * lo_i <= hi_j on every axis: touching spheres are never filtered out. Conversely, a dropped
 * pair has dx = p_j.x - p_i.x > r_i + r_j exactly on some axis, so fl(dx) >= fl(r_i + r_j)
 * and the caller's rounded |dp|^2 is >= its rounded sigma^2: a caller that calls a pair
 * overlapping when |dp|^2 < sigma^2 finds exactly the pairs the all-pairs loop finds. (With
 * <= there, an exact tie of a pair apart by under an ulp could still differ.)
 *
 * Depth: along any root-to-leaf path, every split of distinct codes happens on a bit strictly
 * below its parent's split bit (at most 63 of them), then median splits of equal codes halve
 * the range (at most log2(n) <= 31 of them): depth <= NBEP_BVH_MAX_DEPTH = 94. A depth-first
 * query that pushes both children and pops one holds at most one pending sibling per level,
 * plus the two children just pushed: depth + 1 entries, a fixed array on the C stack.
 *
 * Layout: nodes in depth-first order, the left child right after its parent, one node per
 * 64-byte cache line; each node keeps the largest sphere index below it, so that a query for
 * sphere i skips subtrees holding only spheres j <= i (their pairs belong to those spheres'
 * own queries). Leaf spheres' boxes are copied into Morton order so that a leaf reads one
 * contiguous run of memory.
 *
 * Measured by tests/bench/bench_bvh.c (gcc -O3, one thread on a shared 2-core machine, so
 * +-20%; uniform random spheres of one radius in a cube at packing fraction 0.05; per step one
 * build, then one query per sphere; "naive" is the all-pairs box test the filter replaces):
 *
 *       n   build ms   queries ms   nodes/query   candidates/sphere   depth   naive ms
 *    1024      0.025      0.13          24.5            0.37             11        1.4
 *    4096      0.13       1.3           29.6            0.36             13       28
 *   16384      0.62       6.9           35.1            0.37             16      520
 *   32768      1.3       15             37.9            0.37             17     2400
 *
 * The build is 8-20% of the queries it serves. LEAF_MAX 4 and 8 ran within noise of each other,
 * 1 and 2 were slower (more nodes per query). */
#include "nbep/bvh.h"

#include <assert.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* Spheres per leaf at most: a leaf tests its few spheres' boxes from one contiguous run, which
 * is cheaper than the inner nodes that single-sphere leaves would need. Chosen by bench_bvh. */
#define LEAF_MAX 4

/* Morton code: 21 bits per axis, 3 * 21 = 63 bits in a uint64_t. */
#define MORTON_BITS 21
#define MORTON_CELLS ((uint32_t)1 << MORTON_BITS)

/* LSD radix sort of the codes: 8 passes of 8-bit digits cover the 63 bits. */
#define RADIX_BITS 8
#define RADIX_BUCKETS (1u << RADIX_BITS)
#define RADIX_PASSES 8

typedef struct bvh_node {
    nbep_vec3 lo, hi;   /* exact union of the boxes below */
    uint32_t max_id;    /* largest sphere index below: a query for i skips the node if <= i */
    uint32_t first;     /* leaf: first slot in Morton order; inner: index of the right child */
    uint32_t count;     /* leaf: its spheres, 1..LEAF_MAX; inner: 0 (left child is next) */
    uint32_t unused;
} bvh_node;
static_assert(sizeof(bvh_node) == 64, "one node per cache line");

typedef struct bvh_box {
    nbep_vec3 lo, hi;
} bvh_box;

struct nbep_bvh {
    size_t n_max;
    size_t n;              /* spheres in the last build */
    size_t n_nodes;        /* nodes in the last build */
    size_t depth;          /* edges from the root to the deepest leaf in the last build */
    bvh_node *node;        /* owned, room for 2 n_max - 1 */
    bvh_box *box;          /* owned, n_max: sphere boxes in Morton order */
    uint32_t *order;       /* owned, n_max: sphere index of each Morton slot */
    uint64_t *code;        /* owned, n_max: sorted Morton codes */
    uint64_t *code_tmp;    /* owned, n_max: radix sort buffer */
    uint32_t *order_tmp;   /* owned, n_max: radix sort buffer */
    uint32_t *hist;        /* owned, RADIX_PASSES * RADIX_BUCKETS digit counts */
};

static size_t node_capacity(size_t n_max)
{
    /* A binary tree with L >= 1 leaves has 2L - 1 nodes and L <= n. */
    return n_max > 0 ? 2 * n_max - 1 : 1;
}

size_t nbep_bvh_bytes(size_t n_max)
{
    return sizeof(nbep_bvh) + node_capacity(n_max) * sizeof(bvh_node) +
           n_max * (sizeof(bvh_box) + 2 * sizeof(uint32_t) + 2 * sizeof(uint64_t)) +
           RADIX_PASSES * RADIX_BUCKETS * sizeof(uint32_t);
}

nbep_status nbep_bvh_create(size_t n_max, nbep_bvh **out, nbep_diag *d)
{
    if (n_max > NBEP_BVH_MAX_SPHERES)
        NBEP_FAIL(d, NBEP_EUSAGE, "nbep: %zu spheres are more than the BVH holds (%zu)", n_max,
                  NBEP_BVH_MAX_SPHERES);
    nbep_bvh *b = calloc(1, sizeof *b);
    if (!b || !(b->node = nbep_alloc_aligned(node_capacity(n_max), sizeof *b->node)) ||
        !(b->box = nbep_alloc_aligned(n_max, sizeof *b->box)) ||
        !(b->order = nbep_alloc_aligned(n_max, sizeof *b->order)) ||
        !(b->code = nbep_alloc_aligned(n_max, sizeof *b->code)) ||
        !(b->code_tmp = nbep_alloc_aligned(n_max, sizeof *b->code_tmp)) ||
        !(b->order_tmp = nbep_alloc_aligned(n_max, sizeof *b->order_tmp)) ||
        !(b->hist = nbep_alloc_aligned(RADIX_PASSES * RADIX_BUCKETS, sizeof *b->hist))) {
        nbep_bvh_destroy(&b);
        char size[NBEP_BYTES_TEXT_MAX];
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for a BVH of %zu spheres (%s)", n_max,
                  nbep_format_bytes((double)nbep_bvh_bytes(n_max), size));
    }
    b->n_max = n_max;
    *out = b;
    return NBEP_OK;
}

void nbep_bvh_destroy(nbep_bvh **bp)
{
    if (!bp || !*bp)
        return;
    nbep_bvh *b = *bp;
    nbep_free_aligned(b->node);
    nbep_free_aligned(b->box);
    nbep_free_aligned(b->order);
    nbep_free_aligned(b->code);
    nbep_free_aligned(b->code_tmp);
    nbep_free_aligned(b->order_tmp);
    nbep_free_aligned(b->hist);
    free(b);
    *bp = NULL;
}

size_t nbep_bvh_depth(const nbep_bvh *b)
{
    return b->depth;
}

size_t nbep_bvh_node_count(const nbep_bvh *b)
{
    return b->n_nodes;
}

/* ---- build ------------------------------------------------------------------------------ */

/* Sphere i's box. Build, query and check all use this one function, so their bounds agree to
 * the bit. */
static inline bvh_box sphere_box(const nbep_state *s, size_t i)
{
    nbep_vec3 p = s->pos[i];
    double r = s->radius[i];
    return (bvh_box){{p.x - r, p.y - r, p.z - r}, {p.x + r, p.y + r, p.z + r}};
}

static inline double min2(double a, double b)
{
    return b < a ? b : a;
}
static inline double max2(double a, double b)
{
    return b > a ? b : a;
}

static inline void box_grow(bvh_box *a, const bvh_box *b)
{
    a->lo.x = min2(a->lo.x, b->lo.x);
    a->lo.y = min2(a->lo.y, b->lo.y);
    a->lo.z = min2(a->lo.z, b->lo.z);
    a->hi.x = max2(a->hi.x, b->hi.x);
    a->hi.y = max2(a->hi.y, b->hi.y);
    a->hi.z = max2(a->hi.z, b->hi.z);
}

/* Closed boxes: touching counts, since two touching spheres have touching boxes. */
static inline bool boxes_touch(nbep_vec3 alo, nbep_vec3 ahi, nbep_vec3 blo, nbep_vec3 bhi)
{
    return alo.x <= bhi.x && blo.x <= ahi.x && alo.y <= bhi.y && blo.y <= ahi.y &&
           alo.z <= bhi.z && blo.z <= ahi.z;
}

/* The 21 low bits of v moved to bits 0, 3, 6, ..., 60 (so three axes interleave). */
static uint64_t spread_bits(uint32_t v)
{
    uint64_t x = v & (MORTON_CELLS - 1);
    x = (x | x << 32) & UINT64_C(0x001f00000000ffff);
    x = (x | x << 16) & UINT64_C(0x001f0000ff0000ff);
    x = (x | x << 8) & UINT64_C(0x100f00f00f00f00f);
    x = (x | x << 4) & UINT64_C(0x10c30c30c30c30c3);
    x = (x | x << 2) & UINT64_C(0x1249249249249249);
    return x;
}

/* Cell index of coordinate c along one axis, clamped to [0, MORTON_CELLS - 1]; NaN gives 0 (the
 * code shapes the tree only, so any value is safe; the test keeps the conversion defined). */
static uint32_t quantize(double c, double lo, double scale)
{
    double q = (c - lo) * scale;
    if (!(q >= 0.0))
        return 0;
    if (q >= (double)(MORTON_CELLS - 1))
        return MORTON_CELLS - 1;
    return (uint32_t)q;
}

/* Morton codes of the n sphere centres into b->code, in sphere order; b->order = identity. */
static void compute_codes(nbep_bvh *b, const nbep_state *s)
{
    size_t n = s->n;
    nbep_vec3 lo = s->pos[0], hi = s->pos[0];
    for (size_t i = 1; i < n; i++) {
        nbep_vec3 p = s->pos[i];
        lo = (nbep_vec3){min2(lo.x, p.x), min2(lo.y, p.y), min2(lo.z, p.z)};
        hi = (nbep_vec3){max2(hi.x, p.x), max2(hi.y, p.y), max2(hi.z, p.z)};
    }
    /* Cubic cells: one scale for all axes, from the longest extent. Zero or infinite extent
     * gives scale 0, every code 0, and median splits: a balanced tree all the same. */
    double extent = max2(hi.x - lo.x, max2(hi.y - lo.y, hi.z - lo.z));
    double scale = extent > 0.0 ? (double)MORTON_CELLS / extent : 0.0;
    if (!(scale < INFINITY))
        scale = 0.0;
    for (size_t i = 0; i < n; i++) {
        nbep_vec3 p = s->pos[i];
        b->code[i] = spread_bits(quantize(p.x, lo.x, scale)) << 2 |
                     spread_bits(quantize(p.y, lo.y, scale)) << 1 |
                     spread_bits(quantize(p.z, lo.z, scale));
        b->order[i] = (uint32_t)i;
    }
}

/* Stable LSD radix sort of (code, order) by code. Digits on which every code agrees are
 * skipped (common for the top bits of clustered scenes). */
static void sort_codes(nbep_bvh *b, size_t n)
{
    memset(b->hist, 0, RADIX_PASSES * RADIX_BUCKETS * sizeof *b->hist);
    for (size_t i = 0; i < n; i++) {
        uint64_t c = b->code[i];
        for (unsigned p = 0; p < RADIX_PASSES; p++)
            b->hist[p * RADIX_BUCKETS + ((c >> (p * RADIX_BITS)) & (RADIX_BUCKETS - 1))]++;
    }
    for (unsigned p = 0; p < RADIX_PASSES; p++) {
        uint32_t *h = b->hist + p * RADIX_BUCKETS;
        unsigned shift = p * RADIX_BITS;
        if (h[(b->code[0] >> shift) & (RADIX_BUCKETS - 1)] == n)
            continue;
        uint32_t sum = 0;
        for (unsigned k = 0; k < RADIX_BUCKETS; k++) {
            uint32_t c = h[k];
            h[k] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++) {
            uint64_t c = b->code[i];
            uint32_t dst = h[(c >> shift) & (RADIX_BUCKETS - 1)]++;
            b->code_tmp[dst] = c;
            b->order_tmp[dst] = b->order[i];
        }
        uint64_t *tc = b->code;
        b->code = b->code_tmp;
        b->code_tmp = tc;
        uint32_t *to = b->order;
        b->order = b->order_tmp;
        b->order_tmp = to;
    }
}

/* Where to split the sorted codes [lo, hi) (hi - lo >= 2): at the first code whose highest bit
 * differing within the range is set, or at the middle when all codes are equal. Both sides are
 * non-empty. */
static size_t split_index(const uint64_t *code, size_t lo, size_t hi)
{
    uint64_t diff = code[lo] ^ code[hi - 1];
    if (diff == 0)
        return lo + (hi - lo) / 2;
    /* Smear the highest set bit downwards, then keep it alone. */
    diff |= diff >> 1;
    diff |= diff >> 2;
    diff |= diff >> 4;
    diff |= diff >> 8;
    diff |= diff >> 16;
    diff |= diff >> 32;
    uint64_t top = diff ^ (diff >> 1);
    /* The range shares every bit above top and is sorted, so codes with top clear come first:
     * code[lo] has it clear, code[hi - 1] set. Find the first set in (lo, hi - 1]. */
    size_t a = lo + 1, z = hi - 1;
    while (a < z) {
        size_t m = a + (z - a) / 2;
        if (code[m] & top)
            z = m;
        else
            a = m + 1;
    }
    return a;
}

/* Builds the subtree over Morton slots [lo, hi) at the given depth; returns its node index. */
static uint32_t build_range(nbep_bvh *b, size_t lo, size_t hi, size_t depth)
{
    assert(hi > lo && depth <= NBEP_BVH_MAX_DEPTH);
    uint32_t k = (uint32_t)b->n_nodes++;
    bvh_node *nd = &b->node[k];
    if (hi - lo <= LEAF_MAX) {
        bvh_box box = b->box[lo];
        uint32_t max_id = b->order[lo];
        for (size_t m = lo + 1; m < hi; m++) {
            box_grow(&box, &b->box[m]);
            max_id = b->order[m] > max_id ? b->order[m] : max_id;
        }
        *nd = (bvh_node){box.lo, box.hi, max_id, (uint32_t)lo, (uint32_t)(hi - lo), 0};
        b->depth = depth > b->depth ? depth : b->depth;
        return k;
    }
    size_t mid = split_index(b->code, lo, hi);
    uint32_t left = build_range(b, lo, mid, depth + 1);
    uint32_t right = build_range(b, mid, hi, depth + 1);
    const bvh_node *l = &b->node[left], *r = &b->node[right];
    bvh_box box = {l->lo, l->hi};
    box_grow(&box, &(bvh_box){r->lo, r->hi});
    *nd = (bvh_node){box.lo, box.hi, l->max_id > r->max_id ? l->max_id : r->max_id, right, 0,
                     0};
    return k;
}

void nbep_bvh_build(nbep_bvh *b, const nbep_state *s)
{
    assert(s->n <= b->n_max);
    b->n = s->n;
    b->n_nodes = 0;
    b->depth = 0;
    if (s->n == 0)
        return;
    compute_codes(b, s);
    sort_codes(b, s->n);
    for (size_t m = 0; m < s->n; m++)
        b->box[m] = sphere_box(s, b->order[m]);
    build_range(b, 0, s->n, 0);
    assert(b->n_nodes <= node_capacity(b->n_max));
}

/* ---- query ------------------------------------------------------------------------------ */

/* The later spheres' boxes that touch q, sphere i's own box or a copy of it. */
static size_t query_box(const nbep_bvh *b, size_t i, bvh_box q,
                        void (*visit)(void *ctx, uint32_t j), void *ctx)
{
    if (b->n_nodes == 0)
        return 0;
    uint32_t stack[NBEP_BVH_MAX_DEPTH + 1];
    size_t top = 0, examined = 0;
    stack[top++] = 0;
    while (top > 0) {
        uint32_t k = stack[--top];
        const bvh_node *nd = &b->node[k];
        examined++;
        if (nd->max_id <= i || !boxes_touch(q.lo, q.hi, nd->lo, nd->hi))
            continue;
        if (nd->count > 0) {
            for (uint32_t m = nd->first; m < nd->first + nd->count; m++) {
                uint32_t j = b->order[m];
                if (j > i && boxes_touch(q.lo, q.hi, b->box[m].lo, b->box[m].hi))
                    visit(ctx, j);
            }
        } else {
            assert(top + 2 <= NBEP_BVH_MAX_DEPTH + 1);
            stack[top++] = nd->first;   /* right child, examined after the left subtree */
            stack[top++] = k + 1;       /* left child */
        }
    }
    return examined;
}

size_t nbep_bvh_query_later(const nbep_bvh *b, const nbep_state *s, size_t i,
                            void (*visit)(void *ctx, uint32_t j), void *ctx)
{
    assert(i < b->n && b->n == s->n);
    return query_box(b, i, sphere_box(s, i), visit, ctx);
}

size_t nbep_bvh_query_later_shifted(const nbep_bvh *b, const nbep_state *s, size_t i,
                                    nbep_vec3 shift, void (*visit)(void *ctx, uint32_t j),
                                    void *ctx)
{
    assert(i < b->n && b->n == s->n);
    const nbep_vec3 p = nbep_vec3_add(s->pos[i], shift);
    /* widened by a few units in the last place of the coordinates involved: the shifted
     * place is rounded once more than the stored one, and the exact test that follows (on
     * the minimum image of the separation) must meet every pair it would find */
    const double r = s->radius[i], c = 0x1p-48;
    const nbep_vec3 w = {r + (fabs(p.x) + fabs(shift.x) + r) * c,
                         r + (fabs(p.y) + fabs(shift.y) + r) * c,
                         r + (fabs(p.z) + fabs(shift.z) + r) * c};
    const bvh_box q = {nbep_vec3_sub(p, w), nbep_vec3_add(p, w)};
    return query_box(b, i, q, visit, ctx);
}

/* ---- invariant check -------------------------------------------------------------------- */

typedef struct check_walk {
    const nbep_bvh *b;
    const nbep_state *s;
    nbep_diag *d;
    size_t problems;
    size_t next_slot;      /* leaves cover the slots left to right in depth-first order */
    size_t nodes_seen;
    size_t depth;
} check_walk;

static void check_problem(check_walk *w, const char *what, size_t node)
{
    if (w->problems++ == 0)
        nbep_diag_add(w->d, __FILE__, __LINE__, "nbep: BVH node %zu: %s", node, what);
}

static bool box_contains(const bvh_node *nd, nbep_vec3 lo, nbep_vec3 hi)
{
    return nd->lo.x <= lo.x && nd->lo.y <= lo.y && nd->lo.z <= lo.z && hi.x <= nd->hi.x &&
           hi.y <= nd->hi.y && hi.z <= nd->hi.z;
}

/* Returns false when the walk must stop (a broken link could loop or run off the arrays). */
static bool check_node(check_walk *w, uint32_t k, size_t depth)
{
    const nbep_bvh *b = w->b;
    if (k >= b->n_nodes || depth > NBEP_BVH_MAX_DEPTH || ++w->nodes_seen > b->n_nodes) {
        check_problem(w, "link out of range, or tree deeper than NBEP_BVH_MAX_DEPTH", k);
        return false;
    }
    w->depth = depth > w->depth ? depth : w->depth;
    const bvh_node *nd = &b->node[k];
    if (nd->count > 0) {
        if (nd->count > LEAF_MAX || nd->first != w->next_slot || nd->first + nd->count > b->n) {
            check_problem(w, "leaf slots are not the next ones in order", k);
            return false;
        }
        uint32_t max_id = 0;
        for (size_t m = nd->first; m < nd->first + nd->count; m++) {
            uint32_t id = b->order[m];
            max_id = id > max_id ? id : max_id;
            bvh_box want = sphere_box(w->s, id);
            if (memcmp(&want, &b->box[m], sizeof want) != 0)
                check_problem(w, "a sphere's stored box differs from its state", k);
            if (!box_contains(nd, want.lo, want.hi))
                check_problem(w, "leaf box does not contain a sphere's box", k);
        }
        if (max_id != nd->max_id)
            check_problem(w, "wrong largest sphere index", k);
        w->next_slot += nd->count;
        return true;
    }
    uint32_t left = k + 1, right = nd->first;
    if (right <= left || right >= b->n_nodes) {
        check_problem(w, "right child is not after the left one", k);
        return false;
    }
    if (!check_node(w, left, depth + 1) || !check_node(w, right, depth + 1))
        return false;
    const bvh_node *l = &b->node[left], *r = &b->node[right];
    if (!box_contains(nd, l->lo, l->hi) || !box_contains(nd, r->lo, r->hi))
        check_problem(w, "box does not contain a child's box", k);
    if (nd->max_id != (l->max_id > r->max_id ? l->max_id : r->max_id))
        check_problem(w, "wrong largest sphere index", k);
    return true;
}

size_t nbep_bvh_check(const nbep_bvh *b, const nbep_state *s, nbep_diag *d)
{
    check_walk w = {.b = b, .s = s, .d = d};
    if (b->n != s->n) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: BVH built over %zu spheres, state has %zu",
                      b->n, s->n);
        return 1;
    }
    if (b->n == 0) {
        if (b->n_nodes != 0)
            check_problem(&w, "nodes in a tree of no spheres", 0);
        return w.problems;
    }
    /* Every sphere in exactly one slot. */
    bool *seen = calloc(b->n, sizeof *seen);
    if (!seen) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: no memory to check a BVH of %zu spheres",
                      b->n);
        return 1;
    }
    for (size_t m = 0; m < b->n; m++) {
        uint32_t id = b->order[m];
        if (id >= b->n || seen[id])
            check_problem(&w, "sphere order is not a permutation", 0);
        else
            seen[id] = true;
    }
    free(seen);
    if (w.problems == 0 && check_node(&w, 0, 0)) {
        if (w.next_slot != b->n || w.nodes_seen != b->n_nodes)
            check_problem(&w, "leaves do not cover every sphere once", 0);
        if (w.depth != b->depth)
            check_problem(&w, "recorded depth differs from the tree's", 0);
    }
    return w.problems;
}
