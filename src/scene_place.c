/* Generated groups and the overlap check at t0, both O(n) through hashed uniform cell grids.
 *
 * Grid: spheres are split into levels by radius, radii within a factor 2 sharing one (a
 * million small spheres and a few big ones must neither make the cells huge nor put a big
 * sphere in thousands of cells). A level's cells have side h = 2 rmax, its largest radius,
 * and hold each of its spheres in the cell of its centre; so a sphere of radius r that
 * overlaps one of them has its centre within r + rmax of that centre on every axis, and only
 * the cells over that reach are visited (3 per axis when r <= rmax). Cells are stored in
 * blocks of 4 x 4 x 4 found through a hash of the block coordinates: memory follows the
 * spheres, not the extent of the region, and the 27 cells around a sphere mostly lie in one
 * to four blocks, i.e. a few cache misses rather than 27.
 *
 * Random numbers come from a counter-based hash of (seed, entry, sphere, purpose, attempt):
 * no generator state is shared, so a sphere's numbers never depend on how many numbers
 * another sphere drew, and the placement is the same for a seed whatever else changes. */
#include "scene_impl.h"

#include "nbep/periodic.h"
#include "nbep/physics.h"

#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum {
    RANDOM_ATTEMPTS = 2000,    /* tries per sphere before a random fill gives up */
    OVERLAP_REPORT_MAX = 20,   /* overlaps listed by name; the rest are counted */
    LEVELS_MAX = 64,           /* radius ratios up to 2^63 get their own level */
    BLOCK_SHIFT = 2,           /* blocks of 4 x 4 x 4 cells */
    BLOCK_SIDE = 1 << BLOCK_SHIFT,
    BLOCK_CELLS = BLOCK_SIDE * BLOCK_SIDE * BLOCK_SIDE,
    /* spheres between two looks at the stop signal, in placement and the overlap check: a few
     * milliseconds of either (about 1 us a sphere), so a job's SIGTERM among tens of millions
     * of spheres ends the load at once (until 2026-11-30 it was taken once both had ended: 6 s
     * after it for 2 million random spheres signalled 1 s into their load here), for a relaxed
     * load every few thousand spheres' hashing and grid walks */
    PLACE_LOOK = 4096
};

/* Random-number purposes: one stream per use, so adding a use never shifts another. */
enum { PURPOSE_X, PURPOSE_Y, PURPOSE_Z, PURPOSE_DIR_Z, PURPOSE_DIR_PHI };

/* Spheres that touch are legal, and touching is decided in floating point: a centre carries
 * up to an ulp of its coordinates from how it was made (lo + i s on a lattice, decimal text in
 * a deck), and the distance adds a few ulps of the coordinates through the differences,
 * squares, sum and square root. 8 ulps of everything involved, 8 eps (|p1| + |p2| + r1 + r2)
 * with |p| the largest coordinate, bounds that with room and is still ~1e-15 relative: any
 * overlap a deck means is far above it. The plane test uses |offset| in place of |p2|. */
static const double TOUCH_ULPS = 8.0;

/* Sites along an axis of length L at spacing s are floor(L / s) + 1; when L is a multiple of s
 * mathematically, L / s may round to just below the integer and lose a site: 4 eps of slack. */
static const double LATTICE_SLACK = 4.0 * DBL_EPSILON;

/* Cell coordinates are clamped to [0, 2^30]: far cells merge, which costs time only, never
 * correctness, since the clamped map stays monotone. */
static const double CELL_MAX = 1073741824.0;

static const double TWO_PI = 6.283185307179586477;

/* Before sphere q of a loop of placement or the overlap check: what c->stop asks for, every
 * PLACE_LOOK spheres from the first (a signal before the loop ends it there), else NBEP_OK. */
static nbep_status look(const nbep__scene_ctx *c, uint64_t q)
{
    return q % PLACE_LOOK == 0 ? nbep_status_of_stop(c->stop) : NBEP_OK;
}

static uint64_t mix64(uint64_t x)
{
    /* splitmix64's finaliser (Steele, Lea, Flood 2014). */
    x += 0x9e3779b97f4a7c15u;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9u;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebu;
    return x ^ (x >> 31);
}

/* A number in [0, 1) from (seed, entry, sphere, purpose, attempt). */
static double uniform(uint64_t seed, uint64_t entry, uint64_t sphere, uint64_t purpose,
                      uint64_t attempt)
{
    uint64_t h = mix64(seed);
    h = mix64(h ^ entry);
    h = mix64(h ^ sphere);
    h = mix64(h ^ purpose);
    h = mix64(h ^ attempt);
    return (double)(h >> 11) * 0x1.0p-53;   /* 53 random bits: [0, 1) */
}

static double max_abs(nbep_vec3 p)
{
    return fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z)));
}

/* How far two bodies may overlap by round-off and still touch (TOUCH_ULPS): ulps of the
 * coordinates' magnitudes a and b and their contact distance sigma. */
static double touch_tol(double a, double b, double sigma)
{
    return TOUCH_ULPS * DBL_EPSILON * (a + b + sigma);
}

/* The entry holding sphere id: the last one starting at or before it. */
static size_t entry_of(const nbep__scene_entry *e, size_t n, size_t id)
{
    size_t lo = 0, hi = n;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (e[mid].first <= id)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* ---- the grid ------------------------------------------------------------------------------- */

typedef struct slot {
    uint32_t k[3];     /* block coordinates */
    uint32_t block;    /* index into the level's heads, UINT32_MAX: empty slot */
} slot;

typedef struct level {
    double rmax;       /* largest radius in it; 0: the level is unused */
    double inv_h;      /* 1 / cell side, the side being 2 rmax */
    slot *slots;       /* owned: hash of block coordinates, open addressing, cap slots */
    size_t cap, n_blocks;
    uint32_t *heads;   /* owned: BLOCK_CELLS first-sphere ids per block, UINT32_MAX: none */
    size_t cap_blocks;
} level;

typedef struct grid {
    const nbep_state *s;   /* borrowed: positions and radii of inserted spheres */
    const nbep__scene_entry *e; /* borrowed: the entries they come from (entry_of) */
    size_t n_entries;
    const nbep_periodic *pb; /* borrowed, or NULL: a sphere's cell is that of its position
                              * wrapped into the box along these periodic axes (placement) */
    nbep_vec3 origin;      /* cell coordinates count from here */
    double r_min;
    level lv[LEVELS_MAX];
    uint32_t *next;        /* owned, per sphere id: next in its cell, UINT32_MAX ends */
} grid;

static void grid_fini(grid *g)
{
    for (int l = 0; l < LEVELS_MAX; l++) {
        free(g->lv[l].slots);
        free(g->lv[l].heads);
    }
    free(g->next);
    memset(g, 0, sizeof *g);
}

/* ceil(log2(r / r_min)): radii within a factor 2 share a level. */
static int level_of(const grid *g, double r)
{
    int e;
    double m = frexp(r / g->r_min, &e);
    int l = e - (m == 0.5);
    return l < 0 ? 0 : l >= LEVELS_MAX ? LEVELS_MAX - 1 : l;
}

/* Levels and origin from the entries (every sphere comes from one). */
static bool grid_init(grid *g, const nbep_state *s, const nbep__scene_entry *e, size_t n)
{
    memset(g, 0, sizeof *g);
    g->s = s;
    g->e = e;
    g->n_entries = n;
    g->r_min = INFINITY;
    g->origin = nbep_vec3_make(INFINITY, INFINITY, INFINITY);
    for (size_t k = 0; k < n; k++) {
        if (e[k].count == 0)
            continue;
        g->r_min = fmin(g->r_min, e[k].radius);
        nbep_vec3 lo = e[k].place == NBEP__PLACE_ONE
                           ? nbep_vec3_sub(e[k].position,
                                           nbep_vec3_make(e[k].radius, e[k].radius, e[k].radius))
                           : e[k].lo;
        g->origin = nbep_vec3_make(fmin(g->origin.x, lo.x), fmin(g->origin.y, lo.y),
                                   fmin(g->origin.z, lo.z));
    }
    if (!isfinite(g->r_min)) {
        g->r_min = 1.0;
        g->origin = nbep_vec3_make(0.0, 0.0, 0.0);
    }
    for (size_t k = 0; k < n; k++)
        if (e[k].count > 0) {
            level *L = &g->lv[level_of(g, e[k].radius)];
            L->rmax = fmax(L->rmax, e[k].radius);
        }
    for (int l = 0; l < LEVELS_MAX; l++)
        if (g->lv[l].rmax > 0.0)
            g->lv[l].inv_h = 1.0 / (2.0 * g->lv[l].rmax);
    g->next = malloc((s->n ? s->n : 1) * sizeof *g->next);
    return g->next != NULL;
}

static uint32_t cell_coord(double x, double origin, double inv_h)
{
    double c = floor((x - origin) * inv_h);
    if (!(c > 0.0))
        return 0;
    if (c > CELL_MAX)
        return (uint32_t)CELL_MAX;
    return (uint32_t)c;
}

static size_t slot_hash(const uint32_t k[3], size_t cap)
{
    uint64_t h = mix64(((uint64_t)k[0] << 32 | k[1]) ^ mix64(k[2]));
    return (size_t)(h & (cap - 1));
}

/* The slot of block k: its own, or the empty one where it would go. */
static slot *find_slot(slot *slots, size_t cap, const uint32_t k[3])
{
    for (size_t i = slot_hash(k, cap);; i = (i + 1) & (cap - 1)) {
        slot *t = &slots[i];
        if (t->block == UINT32_MAX || (t->k[0] == k[0] && t->k[1] == k[1] && t->k[2] == k[2]))
            return t;
    }
}

static bool grow_slots(level *L)
{
    size_t cap = L->cap ? 2 * L->cap : 64;
    slot *slots = malloc(cap * sizeof *slots);
    if (!slots)
        return false;
    for (size_t i = 0; i < cap; i++)
        slots[i].block = UINT32_MAX;
    for (size_t i = 0; i < L->cap; i++)
        if (L->slots[i].block != UINT32_MAX)
            *find_slot(slots, cap, L->slots[i].k) = L->slots[i];
    free(L->slots);
    L->slots = slots;
    L->cap = cap;
    return true;
}

static uint32_t *cell_head(uint32_t *heads, uint32_t block, const uint32_t c[3])
{
    const uint32_t m = BLOCK_SIDE - 1;
    return &heads[(size_t)block * BLOCK_CELLS +
                  ((c[2] & m) * BLOCK_SIDE + (c[1] & m)) * BLOCK_SIDE + (c[0] & m)];
}

static bool grid_insert(grid *g, size_t id)
{
    level *L = &g->lv[level_of(g, g->s->radius[id])];
    nbep_vec3 p = g->s->pos[id];
    if (g->pb) {
        int32_t image[3] = {0, 0, 0};
        nbep_periodic_wrap(g->pb, &p, image);
    }
    const uint32_t c[3] = {cell_coord(p.x, g->origin.x, L->inv_h),
                           cell_coord(p.y, g->origin.y, L->inv_h),
                           cell_coord(p.z, g->origin.z, L->inv_h)};
    const uint32_t k[3] = {c[0] >> BLOCK_SHIFT, c[1] >> BLOCK_SHIFT, c[2] >> BLOCK_SHIFT};
    if (2 * (L->n_blocks + 1) > L->cap && !grow_slots(L))   /* load factor <= 1/2 */
        return false;
    slot *t = find_slot(L->slots, L->cap, k);
    if (t->block == UINT32_MAX) {
        if (L->n_blocks == L->cap_blocks) {
            size_t cap = L->cap_blocks ? 2 * L->cap_blocks : 16;
            uint32_t *h = realloc(L->heads, cap * BLOCK_CELLS * sizeof *h);
            if (!h)
                return false;
            L->heads = h;
            L->cap_blocks = cap;
        }
        for (size_t i = 0; i < BLOCK_CELLS; i++)
            L->heads[L->n_blocks * BLOCK_CELLS + i] = UINT32_MAX;
        *t = (slot){{k[0], k[1], k[2]}, (uint32_t)L->n_blocks++};
    }
    uint32_t *head = cell_head(L->heads, t->block, c);
    g->next[id] = *head;
    *head = (uint32_t)id;
    return true;
}

/* Calls visit(arg, id) for every sphere of level L whose centre may lie within reach of p on
 * each axis (a superset of those overlapping a sphere of radius reach - L->rmax at p); stops
 * when visit returns true, and then returns true. */
typedef bool (*grid_visit)(void *arg, size_t id);

static bool visit_chain(const grid *g, uint32_t id, grid_visit visit, void *arg)
{
    for (; id != UINT32_MAX; id = g->next[id])
        if (visit(arg, id))
            return true;
    return false;
}

static bool level_near(const grid *g, const level *L, nbep_vec3 p, double reach,
                       grid_visit visit, void *arg)
{
    if (L->n_blocks == 0)
        return false;
    reach *= 1.0 + 4.0 * DBL_EPSILON;   /* covers the rounding of reach itself */
    const double o[3] = {g->origin.x, g->origin.y, g->origin.z}, q[3] = {p.x, p.y, p.z};
    uint32_t lo[3], hi[3], blo[3], bhi[3];
    double n_range = 1.0;
    for (int a = 0; a < 3; a++) {
        lo[a] = cell_coord(q[a] - reach, o[a], L->inv_h);
        hi[a] = cell_coord(q[a] + reach, o[a], L->inv_h);
        blo[a] = lo[a] >> BLOCK_SHIFT;
        bhi[a] = hi[a] >> BLOCK_SHIFT;
        n_range *= (double)(bhi[a] - blo[a]) + 1.0;
    }
    if (n_range > (double)L->n_blocks) {
        /* A reach wider than the populated blocks (a big sphere against small ones). */
        for (size_t i = 0; i < L->n_blocks * BLOCK_CELLS; i++)
            if (visit_chain(g, L->heads[i], visit, arg))
                return true;
        return false;
    }
    for (uint32_t bz = blo[2]; bz <= bhi[2]; bz++)
        for (uint32_t by = blo[1]; by <= bhi[1]; by++)
            for (uint32_t bx = blo[0]; bx <= bhi[0]; bx++) {
                const uint32_t k[3] = {bx, by, bz};
                const slot *t = find_slot(L->slots, L->cap, k);
                if (t->block == UINT32_MAX)
                    continue;
                uint32_t c[3], from[3], to[3];
                for (int a = 0; a < 3; a++) {
                    uint32_t first = k[a] << BLOCK_SHIFT, last = first + (BLOCK_SIDE - 1);
                    from[a] = lo[a] > first ? lo[a] : first;
                    to[a] = hi[a] < last ? hi[a] : last;
                }
                for (c[2] = from[2]; c[2] <= to[2]; c[2]++)
                    for (c[1] = from[1]; c[1] <= to[1]; c[1]++)
                        for (c[0] = from[0]; c[0] <= to[0]; c[0]++)
                            if (visit_chain(g, *cell_head(L->heads, t->block, c), visit, arg))
                                return true;
            }
    return false;
}

/* Every inserted sphere that may overlap a sphere of radius r at p, level by level. */
static bool grid_near(const grid *g, nbep_vec3 p, double r, grid_visit visit, void *arg)
{
    for (int l = 0; l < LEVELS_MAX; l++)
        if (g->lv[l].rmax > 0.0 && level_near(g, &g->lv[l], p, r + g->lv[l].rmax, visit, arg))
            return true;
    return false;
}

/* ---- placement ------------------------------------------------------------------------------ */

/* What an overlap is blamed on: an override's label (nbep__scene_origin's), or else the deck's
 * line; and the rank its message takes (nbep__scene_rank). */
typedef struct blame {
    const char *label;    /* borrowed: one of the load's labels, or NULL */
    unsigned line;        /* where label is NULL: >= 1 */
    uint64_t rank;
} blame;

/* The members of an entry that decide where its spheres go and how big they are: a --set of
 * any of them (or a sweep axis, which is one) can make an overlap the deck alone did not have.
 * A region's corners are asked one by one: a --set of one of their elements hooks only that
 * element (nbep__scene_origin looks one level down). Velocity, speed, mass and acceleration
 * move nothing at t0. */
static const char *const placing[][2] = {{"position", NULL}, {"radius", NULL}, {"count", NULL},
                                          {"place", NULL},    {"region", "min"}, {"region", "max"}};

/* *b becomes the override that made setting m (may be NULL; nbep__scene_set_by) when one did
 * and was typed before *b's: of several, the list ranks the message with the first typed. */
static void blame_first(const nbep__scene_ctx *c, blame *b, const config_setting_t *m)
{
    uint64_t rank;
    const char *ov = nbep__scene_set_by(c, m, &rank);
    if (rank < b->rank)
        *b = (blame){ov, 0, rank};
}

/* blame_first of what moved or made a plane (plane_at's two settings: a box wall's element of
 * box.min or box.max and of box.periodic, a deck plane's group: its point or normal). */
static void plane_blame(const nbep__scene_ctx *c, blame *b, const config_setting_t *const *at)
{
    if (at[0] && config_setting_is_group(at[0])) {
        blame_first(c, b, config_setting_get_member(at[0], "point"));
        blame_first(c, b, config_setting_get_member(at[0], "normal"));
    } else {
        blame_first(c, b, at[0]);
        blame_first(c, b, at[1]);
    }
}


/* The override of a member of entry g in `placing` that was typed first, into *b. */
static void members_blame(const nbep__scene_ctx *c, blame *b, const config_setting_t *g)
{
    for (size_t k = 0; k < sizeof placing / sizeof *placing; k++) {
        const config_setting_t *m = config_setting_get_member(g, placing[k][0]);
        if (m && placing[k][1])
            m = config_setting_get_member(m, placing[k][1]);
        blame_first(c, b, m);
    }
}

/* What placed the spheres of entry g: the override of a member in `placing` (the one typed
 * first where several were), else the deck's line of its position (a single sphere) or of the
 * entry (a group). */
static blame entry_blame(const nbep__scene_ctx *c, const config_setting_t *g)
{
    blame b = {NULL, 0, NBEP_DIAG_UNRANKED};
    members_blame(c, &b, g);
    if (b.label)
        return b;
    const config_setting_t *pos = config_setting_get_member(g, "position");
    (void)nbep__scene_origin(pos ? pos : g, false, &b.line);
    b.line = b.line ? b.line : 1;
    b.rank = nbep__scene_rank(c, NULL, b.line);
    return b;
}

/* Whether plane p of s lies at or inside the box [lo, hi]: some corner of it is not on the
 * plane's free side. */
static bool plane_reaches(const nbep_state *s, size_t p, nbep_vec3 lo, nbep_vec3 hi)
{
    const nbep_vec3 n = s->plane_normal[p];
    const double least = n.x * (n.x > 0.0 ? lo.x : hi.x) + n.y * (n.y > 0.0 ? lo.y : hi.y) +
                         n.z * (n.z > 0.0 ? lo.z : hi.z);
    return !(least > s->plane_offset[p]);
}

/* The deck's box (its root's `box`), from entry g's setting: the entry's list's parent is the
 * root. NULL where the deck has none. */
static const config_setting_t *box_of(const config_setting_t *g)
{
    const config_setting_t *list = config_setting_parent(g);
    const config_setting_t *root = list ? config_setting_parent(list) : NULL;
    return root ? config_setting_get_member(root, "box") : NULL;
}

/* What a group that cannot be placed is blamed on: the override typed first of what places
 * its spheres (members_blame), of what placed the spheres in its way (`in_way`: kept_out_by's,
 * the placing overrides of the other entries whose spheres its tries met; none for a lattice,
 * which looks at no sphere) and of what bounds the room they go in: the box's corners where
 * the group has no region (the box is its region), and each plane at or inside its region
 * (plane_at's settings: a wall's element of box.min or box.max, a deck plane's point and
 * normal), every plane for random places (they keep clear of each), the box's walls alone for
 * a lattice (they clip its region; it does not look at the others). Label NULL where none was
 * typed. (Until 2026-11-30 a --set or sweep axis of the box or of a plane that left a group no
 * room was not named: the message stood at the group's count; nor was one of an earlier
 * group's count or radius whose spheres took the room.) */
static blame fill_blame(const nbep__scene_ctx *c, const nbep_state *s,
                        const nbep__scene_entry *e, const config_setting_t *const *plane_at,
                        blame in_way)
{
    blame b = in_way;
    members_blame(c, &b, e->setting);
    if (!config_setting_get_member(e->setting, "region")) {
        const config_setting_t *box = box_of(e->setting);
        if (box) {
            blame_first(c, &b, config_setting_get_member(box, "min"));
            blame_first(c, &b, config_setting_get_member(box, "max"));
        }
    }
    for (size_t p = 0; plane_at && p < s->n_planes; p++) {
        const config_setting_t *at = plane_at[2 * p];
        const bool wall = !(at && config_setting_is_group(at));
        if ((!wall && nbep__place_is_lattice(e->place)) || !plane_reaches(s, p, e->lo, e->hi))
            continue;
        plane_blame(c, &b, &plane_at[2 * p]);
    }
    return b;
}


/* A group whose spheres cannot be placed: the message is blamed as fill_blame says (the --set
 * or sweep axis typed first of what places them, of what placed the spheres in their way,
 * in_way, and of what bounds their room), else put at the deck's line of its count. */
static void fill_failed(nbep__scene_ctx *c, const nbep_state *s, const nbep__scene_entry *e,
                        const config_setting_t *const *plane_at, blame in_way,
                        const char *fmt, ...) NBEP_PRINTF(6, 7);
static void fill_failed(nbep__scene_ctx *c, const nbep_state *s, const nbep__scene_entry *e,
                        const config_setting_t *const *plane_at, blame in_way,
                        const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    const blame b = fill_blame(c, s, e, plane_at, in_way);
    if (b.label)
        nbep__scene_error_from(c, b.label, 0, __FILE__, __LINE__, "%s", msg);
    else
        NBEP__SCENE_ERR(c, e->count_at, "%s", msg);
}


typedef struct probe {
    const nbep_state *s;
    const nbep_periodic *pb; /* NULL, or the periodic axes: distances by the nearest image */
    nbep_vec3 p;
    double r;
    const grid *g;           /* with met: the grid, whose entries (entry_of) are marked */
    bool *met;               /* NULL: the first sphere it overlaps ends the look; else every
                              * one's entry is marked here and the look goes on (kept_out_by) */
    /* own_hi > own_lo: only spheres own_lo .. own_hi - 1 (a lattice's own, lattice_wraps_onto),
     * touching within round-off as the overlap check takes it, the first overlap's sphere and
     * depth written to hit_id, hit_by */
    size_t own_lo, own_hi, hit_id;
    double hit_by;
} probe;

/* True when sphere id and the probe sphere overlap (touching is fine); with q->met, marks its
 * entry and returns false, so that every sphere it overlaps is seen. */
static bool probe_hits(void *arg, size_t id)
{
    probe *q = arg;
    double sigma = q->r + q->s->radius[id];
    nbep_vec3 d = nbep_vec3_sub(q->s->pos[id], q->p);
    if (q->pb)
        d = nbep_periodic_image(q->pb, d);
    if (q->own_hi > q->own_lo) {
        if (id < q->own_lo || id >= q->own_hi)
            return false;
        const double by = sigma - nbep_vec3_norm(d);
        if (!(by > touch_tol(max_abs(q->s->pos[id]), max_abs(q->p), sigma)))
            return false;
        q->hit_id = id;
        q->hit_by = by;
        return true;
    }
    const bool hit = nbep_vec3_norm2(d) < sigma * sigma;
    if (hit && q->met) {
        q->met[entry_of(q->g->e, q->g->n_entries, id)] = true;
        return false;
    }
    return hit;
}

/* Whether the probe sphere overlaps one in the grid. Along periodic axes (q->pb, the grid's
 * too) its position is wrapped into the box and looked up there and, near a face, across it
 * (within reach, the largest contact distance; a periodic side exceeds twice the largest
 * diameter, so one face per axis at most, alone and in combination: edges, corners), as the
 * overlap check of the deck looks (nbep__scene_check_overlaps). */
static bool probe_near(const grid *g, probe *q, double reach)
{
    if (!q->pb)
        return grid_near(g, q->p, q->r, probe_hits, q);
    nbep_vec3 w = q->p;
    int32_t image[3] = {0, 0, 0};
    nbep_periodic_wrap(q->pb, &w, image);
    const double x[3] = {w.x, w.y, w.z};
    double near[3] = {0.0, 0.0, 0.0};
    for (int a = 0; a < 3; a++) {
        if (q->pb->axis[a] && x[a] - q->pb->lo[a] < reach)
            near[a] = q->pb->len[a];
        else if (q->pb->axis[a] && q->pb->lo[a] + q->pb->len[a] - x[a] < reach)
            near[a] = -q->pb->len[a];
    }
    for (int m = 0; m < 8; m++) {
        if (((m & 1) && near[0] == 0.0) || ((m & 2) && near[1] == 0.0) ||
            ((m & 4) && near[2] == 0.0))
            continue;
        const nbep_vec3 shift = nbep_vec3_make(m & 1 ? near[0] : 0.0, m & 2 ? near[1] : 0.0,
                                               m & 4 ? near[2] : 0.0);
        if (grid_near(g, nbep_vec3_add(w, shift), q->r, probe_hits, q))
            return true;
    }
    return false;
}

static bool clear_of_planes(const nbep_state *s, nbep_vec3 p, double r)
{
    for (size_t k = 0; k < s->n_planes; k++)
        if (nbep_vec3_dot(s->plane_normal[k], p) - s->plane_offset[k] < r)
            return false;
    return true;
}

static nbep_vec3 random_velocity(uint64_t seed, size_t entry, uint64_t q, double speed)
{
    if (speed == 0.0)
        return nbep_vec3_make(0.0, 0.0, 0.0);
    /* Uniform on the sphere: z uniform in [-1, 1], azimuth uniform (Archimedes). */
    double z = 2.0 * uniform(seed, entry, q, PURPOSE_DIR_Z, 0) - 1.0;
    double phi = TWO_PI * uniform(seed, entry, q, PURPOSE_DIR_PHI, 0);
    double rho = sqrt(fmax(0.0, 1.0 - z * z));
    return nbep_vec3_make(speed * rho * cos(phi), speed * rho * sin(phi), speed * z);
}

static double ball_volume(double r)
{
    return 4.0 / 3.0 * (TWO_PI / 2.0) * r * r * r;
}

static double box_volume(nbep_vec3 lo, nbep_vec3 hi)
{
    return (hi.x - lo.x) * (hi.y - lo.y) * (hi.z - lo.z);
}

static void set_sphere(nbep_state *s, const nbep__scene_entry *e, size_t id, nbep_vec3 p,
                       nbep_vec3 v)
{
    s->pos[id] = p;
    s->vel[id] = v;
    s->acc[id] = e->acc;
    s->radius[id] = e->radius;
    s->mass[id] = e->mass;
}

/* Try a at sphere q of group k: uniform in [lo, hi], the region shrunk by the radius. */
static nbep_vec3 try_at(uint64_t seed, size_t k, uint64_t q, uint64_t a, nbep_vec3 lo,
                        nbep_vec3 hi)
{
    return nbep_vec3_make(lo.x + uniform(seed, k, q, PURPOSE_X, a) * (hi.x - lo.x),
                          lo.y + uniform(seed, k, q, PURPOSE_Y, a) * (hi.y - lo.y),
                          lo.z + uniform(seed, k, q, PURPOSE_Z, a) * (hi.z - lo.z));
}

/* What placed the spheres that kept sphere q of group k out, every try of it having failed
 * (`tries` of them, made again): the placing overrides (members_blame) of each entry with a
 * sphere that a try clear of the planes overlapped (every one, not the first found), into *b.
 * A try a plane kept out is the plane's (fill_blame: a --set that moved a plane over the
 * whole region is named, not a group's spheres there too), and an entry whose spheres no try
 * met took none of the room, whatever a --set did to it. Returns false when out of memory. */
static bool kept_out_by(const nbep__scene_ctx *c, const grid *g, probe *pr, double reach,
                        size_t k, uint64_t q, uint64_t seed, nbep_vec3 lo, nbep_vec3 hi,
                        uint64_t tries, blame *b)
{
    bool *met = calloc(g->n_entries ? g->n_entries : 1, sizeof *met);
    if (!met)
        return false;
    pr->g = g;
    pr->met = met;
    for (uint64_t a = 0; a < tries; a++) {
        pr->p = try_at(seed, k, q, a, lo, hi);
        if (clear_of_planes(g->s, pr->p, pr->r))
            (void)probe_near(g, pr, reach);
    }
    for (size_t j = 0; j < g->n_entries; j++)
        if (met[j])
            members_blame(c, b, g->e[j].setting);
    free(met);
    return true;
}

/* Whether x lies in [lo, hi] along axis a, or (a periodic axis: places wrap into the box) one
 * period either side of it. */
static bool within(const nbep_periodic *pb, int a, double x, double lo, double hi)
{
    if (x >= lo && x <= hi)
        return true;
    return pb && pb->axis[a] &&
           ((x + pb->len[a] >= lo && x + pb->len[a] <= hi) ||
            (x - pb->len[a] >= lo && x - pb->len[a] <= hi));
}

/* The volume of the spheres placed before entry k's (single spheres, and the groups before it)
 * whose centres lie in the region [lo, hi]: the room they took from it, for the message of a
 * group that does not fit (its own packing alone read 0.00 where another group had filled its
 * region). On that path only: O(n). */
static double placed_before_in(const grid *g, size_t k, nbep_vec3 lo, nbep_vec3 hi)
{
    double v = 0.0;
    for (size_t j = 0; j < g->n_entries; j++) {
        const nbep__scene_entry *o = &g->e[j];
        if (j == k || (o->place != NBEP__PLACE_ONE && j > k))
            continue;
        const uint64_t n = o->place == NBEP__PLACE_ONE ? 1 : o->count;
        for (uint64_t q = 0; q < n; q++) {
            const size_t i = o->first + (size_t)q;
            const nbep_vec3 p = g->s->pos[i];
            if (within(g->pb, 0, p.x, lo.x, hi.x) && within(g->pb, 1, p.y, lo.y, hi.y) &&
                within(g->pb, 2, p.z, lo.z, hi.z))
                v += ball_volume(g->s->radius[i]);
        }
    }
    return v;
}

/* Why a group finds no room at all, for the end of its message (else ""): the axes along which
 * its region [lo, hi] is narrower than a diameter 2r (until 2026-11-30 the message said only
 * "placed 0 (packing fraction 0.00)", as if the region had filled up), or, every place tried
 * having overlapped a plane (plane_out of tries), the planes. */
static void no_room_why(nbep_vec3 lo, nbep_vec3 hi, double r, uint64_t plane_out, uint64_t tries,
                        char *buf, size_t len)
{
    const double side[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    char axes[96] = "";
    for (int a = 0; a < 3; a++)
        if (side[a] < 2.0 * r) {
            size_t used = strlen(axes);
            snprintf(axes + used, sizeof axes - used, "%s%c (%g)", used ? ", " : "", "xyz"[a],
                     side[a]);
        }
    if (axes[0])
        snprintf(buf, len, ": the region is narrower than their diameter, %g, along %s", 2.0 * r,
                 axes);
    else if (tries > 0 && plane_out == tries)
        snprintf(buf, len, ": every place tried in the region overlaps a plane");
    else if (len)
        buf[0] = '\0';
}

/* Uniform in the region shrunk by the radius, rejecting overlaps with every sphere placed so
 * far (by the nearest image along periodic axes, g->pb) and with the planes; along a periodic
 * axis that the region spans whole (a period or more: the box's own extent, the default, too),
 * uniform over the period, not shrunk: there the faces are no walls, and the shrink left an
 * empty slab a diameter thick at them (until 2026-12-01). Returns NBEP_ENOMEM when out of
 * memory (no message), the stop status where it looked (look), else NBEP_OK. */
static nbep_status place_random(nbep__scene_ctx *c, grid *g, nbep_state *s, const nbep__scene_entry *e,
                         size_t k, uint64_t seed, const config_setting_t *const *plane_at)
{
    const double r = e->radius;
    double reach = 0.0; /* r and the largest radius placed: the largest contact distance */
    for (int l = 0; l < LEVELS_MAX; l++)
        reach = fmax(reach, r + g->lv[l].rmax);
    double l[3] = {e->lo.x + r, e->lo.y + r, e->lo.z + r};
    double h[3] = {e->hi.x - r, e->hi.y - r, e->hi.z - r};
    /* the room the places are drawn in, along each axis: the region's extent, or a period */
    double room_of[3] = {e->hi.x - e->lo.x, e->hi.y - e->lo.y, e->hi.z - e->lo.z};
    for (int a = 0; a < 3; a++)
        if (g->pb && g->pb->axis[a] && room_of[a] >= g->pb->len[a]) {
            /* a place at the high face (by rounding) is the low face's: set-up wraps it */
            l[a] = g->pb->lo[a];
            h[a] = g->pb->lo[a] + g->pb->len[a];
            room_of[a] = g->pb->len[a];
        }
    const nbep_vec3 lo = nbep_vec3_make(l[0], l[1], l[2]);
    const nbep_vec3 hi = nbep_vec3_make(h[0], h[1], h[2]);
    const bool room = lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z;
    for (uint64_t q = 0; q < e->count; q++) {
        const nbep_status stop = look(c, q);
        if (stop != NBEP_OK)
            return stop;
        probe pr = {s, g->pb, {0.0, 0.0, 0.0}, r, NULL, NULL, 0, 0, 0, 0.0};
        bool placed = false;
        uint64_t a = 0, plane_out = 0;
        for (; room && !placed && a < RANDOM_ATTEMPTS; a++) {
            pr.p = try_at(seed, k, q, a, lo, hi);
            const bool clear = clear_of_planes(s, pr.p, r);
            plane_out += !clear;
            placed = clear && !probe_near(g, &pr, reach);
        }
        if (!placed) {
            blame in_way = {NULL, 0, NBEP_DIAG_UNRANKED};
            if (!kept_out_by(c, g, &pr, reach, k, q, seed, lo, hi, a, &in_way))
                return NBEP_ENOMEM;
            /* the room the places were drawn in (a region three periods long had three
             * periods' volume, and the message a third of the packing: until 2026-12-01) */
            const double vol = room_of[0] * room_of[1] * room_of[2];
            const double before = placed_before_in(g, k, e->lo, e->hi);
            char others[96] = "";
            if (before > 0.0)
                snprintf(others, sizeof others,
                         "; %.2f with the spheres placed before it in the region",
                         ((double)q * ball_volume(r) + before) / vol);
            char why[160], hint[256] = "";
            no_room_why(e->lo, e->hi, r, plane_out, a, why, sizeof why);
            /* random placement jams near a packing fraction of 0.3 (random sequential
             * addition's limit is 0.38); where the region alone asks for no more than a lattice
             * holds (simple cubic 0.52, face-centred 0.74, less at its walls), say so: a dense
             * pile or fluid starts from one (until 2026-11-30 the line gave no way on) */
            const double asked = (double)e->count * ball_volume(r) / vol;
            if (!why[0] && before == 0.0 && asked <= 0.74)
                snprintf(hint, sizeof hint,
                         "; random places jam near a packing fraction of 0.3 and %.2f is asked: "
                         "try place = %s",
                         asked,
                         asked <= 0.52 ? "\"lattice\" (up to 0.52) or \"fcc\" (up to 0.74)"
                                       : "\"fcc\" (up to 0.74), a crystal: a fluid this dense "
                                         "is made by compressing one, which nbep does not do");
            fill_failed(c, s, e, plane_at, in_way,
                        "spheres.[%zu]: could not place %" PRIu64
                        " spheres of radius %g in the region: placed %" PRIu64
                        " (packing fraction %.2f%s)%s%s",
                        k, e->count, r, q, (double)q * ball_volume(r) / vol, others, why,
                        hint);
            return NBEP_OK;
        }
        size_t id = e->first + (size_t)q;
        set_sphere(s, e, id, pr.p, random_velocity(seed, k, q, e->speed));
        if (!grid_insert(g, id))
            return NBEP_ENOMEM;
    }
    return NBEP_OK;
}

/* A lattice's axis: its width and whether it wraps. Along an axis that does not, the sites
 * run from a radius past the region's low side to a radius short of its high side, the first
 * and last on those bounds; along a periodic axis that an "fcc" group's region spans whole,
 * they wrap, an even number of them evenly spaced from half a spacing past the box's low face,
 * so that the crystal repeats across the face as inside (a simple cubic "lattice" keeps the
 * bounds there too: its spheres touch across the face, a start that melts). */
typedef struct lattice_axis {
    double len;
    bool wraps;
} lattice_axis;

static double lattice_sites(lattice_axis x, double spacing)
{
    if (x.len < 0.0)
        return 0.0;
    if (isinf(spacing))
        return 1.0;
    const double k = floor(x.len / spacing * (1.0 + LATTICE_SLACK));
    return x.wraps ? 2.0 * floor(k / 2.0) : k + 1.0;
}

/* A lattice's sites at spacing s: simple cubic, the points (i, j, k) s from the first; face-
 * centred cubic, those of them with i + j + k even (a cube of side 2 s holds a conventional
 * cell's 4; nearest neighbours s sqrt 2 apart, next ones 2 s), of which there are half, the
 * corner (0, 0, 0) counted where all three counts are odd. */
static double lattice_capacity(const lattice_axis ax[3], double spacing, bool fcc)
{
    const double n[3] = {lattice_sites(ax[0], spacing), lattice_sites(ax[1], spacing),
                         lattice_sites(ax[2], spacing)};
    const double all = n[0] * n[1] * n[2];
    if (!fcc)
        return all;
    const bool odd = fmod(n[0], 2.0) == 1.0 && fmod(n[1], 2.0) == 1.0 && fmod(n[2], 2.0) == 1.0;
    return (all + (odd ? 1.0 : 0.0)) / 2.0;
}

/* The smallest spacing at which spheres of radius r on the sites touch: 2r for simple cubic,
 * sqrt(2) r for face-centred cubic (its nearest neighbours are sqrt(2) spacings apart; their
 * distance, rounded, may fall an ulp short of 2r: touching within round-off, which the
 * overlap check allows). */
static double lattice_min_spacing(double r, bool fcc)
{
    return fcc ? sqrt(2.0) * r : 2.0 * r;
}

/* The largest spacing s >= lattice_min_spacing at which count sites fit. The capacity only
 * drops where s passes len[a] / k for an axis a and integer k, so the answer is one of those:
 * per axis, the smallest k that still holds count, found by bisection; then the largest over
 * axes. Returns 0 when even the smallest spacing holds too few, INFINITY for at most one
 * sphere. */
static double lattice_spacing(const lattice_axis ax[3], double r, uint64_t count, bool fcc)
{
    const double least = lattice_min_spacing(r, fcc);
    if (lattice_capacity(ax, least, fcc) < (double)count)
        return 0.0;
    if (count <= 1)
        return INFINITY;
    double best = least;
    for (int a = 0; a < 3; a++) {
        double kmax = floor(ax[a].len / least * (1.0 + LATTICE_SLACK));
        if (!(kmax >= 1.0) || lattice_capacity(ax, ax[a].len / kmax, fcc) < (double)count)
            continue;
        double lo = 1.0, hi = kmax;   /* integers, exact in a double */
        while (lo < hi) {
            double mid = floor((lo + hi) / 2.0);
            if (lattice_capacity(ax, ax[a].len / mid, fcc) >= (double)count)
                hi = mid;
            else
                lo = mid + 1.0;
        }
        best = fmax(best, ax[a].len / lo);
    }
    return best;
}

/* The site after idx, x fastest (nx, ny: sites along x and y). */
static void lattice_next(uint64_t idx[3], uint64_t nx, uint64_t ny)
{
    if (++idx[0] < nx)
        return;
    idx[0] = 0;
    if (++idx[1] < ny)
        return;
    idx[1] = 0;
    idx[2]++;
}

/* The axes of a lattice in the region [rlo, rhi] of spheres of radius r (wrap: an "fcc" fill,
 * which wraps along the periodic axes the region spans whole, spans), with the first and last
 * sites' bounds lo and hi (lattice_axis). */
static void lattice_axes(const double rlo[3], const double rhi[3], double r, const bool spans[3],
                         bool wrap, lattice_axis ax[3], double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++) {
        ax[a].wraps = wrap && spans[a];
        lo[a] = ax[a].wraps ? rlo[a] : rlo[a] + r;
        hi[a] = ax[a].wraps ? rhi[a] : rhi[a] - r;
        ax[a].len = hi[a] - lo[a];
    }
}

/* Whether sphere id, a lattice site of entry e (radius r), lands on one of e's earlier sites
 * where the places wrap into a periodic box (along `longer`, the periodic axes its region is
 * longer than a period along: a region within one period keeps its sites apart across the
 * faces, and is not looked at); then its message, one line at the group, is given. A region
 * one period long that rounding made an ulp longer places sites that touch within round-off,
 * which are taken, as the overlap check takes them. Until 2026-11-30 the overlap check listed
 * such sites as 20 overlaps "across a periodic face" of spheres nbep had placed itself, and
 * 20 more not listed. */
static bool lattice_wraps_onto(nbep__scene_ctx *c, const grid *g, const nbep_state *s,
                               const nbep__scene_entry *e, size_t k, size_t id, double r,
                               const char *longer, const config_setting_t *const *plane_at)
{
    probe pr = {s, g->pb, s->pos[id], r, NULL, NULL, e->first, id, 0, 0.0};
    if (!probe_near(g, &pr, 2.0 * r))
        return false;
    fill_failed(c, s, e, plane_at, (blame){NULL, 0, NBEP_DIAG_UNRANKED},
                "spheres.[%zu]: could not place %" PRIu64 " spheres of radius %g in the region: "
                "it is longer than the periodic box along %s, and the lattice's places wrap "
                "into the box onto one another (sphere %zu on sphere %zu, by %g); keep a "
                "lattice's region within one period along a periodic axis",
                k, e->count, r, longer, id, pr.hit_id, pr.hit_by);
    return true;
}

/* Whether a lattice of entry e that moves (speed > 0; radius r, n sites along each axis at
 * `spacing`, x fastest; ax its axes) is jammed, packed so tight that nothing in it can move,
 * when a speed along its rows is passed to and fro at zero time for ever and the run stalls at
 * t = 0 (a simple cubic 1000 of radius 0.05 in a unit box ran for more than ten minutes without
 * a step in all-pairs mode, and cells mode past a minute, time creeping by round-off; 27
 * stopped on the stall check after two seconds; a close-packed "fcc" of 63 did not pass a step
 * in half a minute); then its message is given, at the group. Its ends are held by the box's
 * walls where its region meets them, or by itself across the faces of a periodic axis that its
 * region spans whole (a simple cubic lattice keeps a radius from those faces, so a row that
 * spans a period touches across them; "fcc" spaces its sites round the period). "Tight" is
 * within the round-off of the coordinates, as the overlap check takes touching: 16 ulps of the
 * region's corners.
 *   simple cubic: some axis's rows whole (not the last, partly filled), their spheres touching
 *     one another and both held ends: what the row's diameters leave of the region's length
 *     (of the period, across it), none;
 *   "fcc": nearest neighbours touching, every site filled, and the sites reaching both held
 *     ends along two axes or three (each plane of those two is a square of touching spheres
 *     from end to end; measured with the stalls above: 63 close-packed with room along z
 *     alone, or 40 of them filling its lower layers, stalled; with room along y and z, or 20
 *     spheres at a wider spacing, they ran). Partly filled crystals at touching spacing (the
 *     40) are not looked at: which of them jam depends on which planes the fill completes.
 * Planes (which may lie anywhere) are not looked at: a region clear of a wall has room. */
static bool lattice_jams(nbep__scene_ctx *c, const nbep_state *s, const nbep__scene_entry *e,
                         size_t k, const lattice_axis ax[3], double spacing, const uint64_t n[3],
                         const bool *box_periodic, const bool spans[3], const double blo[3],
                         const double bhi[3], const config_setting_t *const *plane_at)
{
    if (!box_periodic || !(e->speed > 0.0)) /* no box: nothing holds the ends */
        return false;
    const bool fcc = e->place == NBEP__PLACE_FCC;
    const double r = e->radius;
    const double rlo[3] = {e->lo.x, e->lo.y, e->lo.z}, rhi[3] = {e->hi.x, e->hi.y, e->hi.z};
    /* the spheres a whole row along each axis needs placed first (x fastest) */
    const uint64_t whole[3] = {n[0], n[0] * (n[1] - 1) + 1, n[0] * n[1] * (n[2] - 1) + 1};
    int tight[3], n_tight = 0, first = -1;
    for (int a = 0; a < 3; a++) {
        const double tol = 16.0 * DBL_EPSILON * (fabs(rlo[a]) + fabs(rhi[a]));
        const bool held = box_periodic[a] ? spans[a]
                                          : rlo[a] <= blo[a] + tol && rhi[a] >= bhi[a] - tol;
        /* the room the sites leave along a: simple cubic, what the row's diameters leave of
         * the region (and of the period across it); "fcc", past its last site (round the
         * period where it wraps) */
        const double room = !fcc        ? (rhi[a] - rlo[a]) - 2.0 * r * (double)n[a]
                            : ax[a].wraps ? ax[a].len - spacing * (double)n[a]
                            : n[a] == 1   ? ax[a].len /* (one sphere's spacing is inf) */
                                          : ax[a].len - spacing * (double)(n[a] - 1);
        tight[a] = held && n[a] > 0 && room <= tol && (fcc || e->count >= whole[a]);
        n_tight += tight[a];
        if (tight[a] && first < 0)
            first = a;
    }
    /* "fcc" of one layer between the walls along an axis: each sphere spans them, as a simple
     * cubic row of one (a review's one sphere of radius 0.5 in a box 1 wide passed the check
     * and stalled at step 1, where "lattice" was refused) */
    for (int a = 0; fcc && a < 3; a++)
        if (tight[a] && n[a] == 1 && !ax[a].wraps) {
            fill_failed(c, s, e, plane_at, (blame){NULL, 0, NBEP_DIAG_UNRANKED},
                        "spheres.[%zu]: this face-centred cubic lattice has one layer along %c, "
                        "each sphere of radius %g touching both walls, so with speed %g no "
                        "sphere can move along %c, and the run would not pass t = 0 (endless "
                        "collisions at zero time); give the region more room along %c than 1 "
                        "diameter (%g), or speed = 0",
                        k, "xyz"[a], r, e->speed, "xyz"[a], "xyz"[a], 2.0 * r);
            return true;
        }
    if (fcc ? !(n_tight >= 2 &&
                spacing <= lattice_min_spacing(r, true) * (1.0 + 4.0 * LATTICE_SLACK) &&
                (double)e->count >= lattice_capacity(ax, spacing, true))
            : n_tight == 0)
        return false;
    if (fcc) {
        char axes[16] = ""; /* "x and y", "x, y and z" */
        for (int a = 0, m = 0; a < 3; a++)
            if (tight[a]) {
                const size_t used = strlen(axes);
                snprintf(axes + used, sizeof axes - used, "%s%c",
                         m == 0 ? "" : m == n_tight - 1 ? " and " : ", ", "xyz"[a]);
                m++;
            }
        fill_failed(c, s, e, plane_at, (blame){NULL, 0, NBEP_DIAG_UNRANKED},
                    "spheres.[%zu]: this face-centred cubic lattice is packed tight along %s: "
                    "each sphere touches its neighbours, every site is filled, and the crystal "
                    "reaches its region's ends along them, so with speed %g no sphere can move, "
                    "and the run would not pass t = 0 (endless collisions at zero time); give "
                    "the region room along all but one axis, fewer spheres, or speed = 0",
                    k, axes, e->speed);
    } else
        fill_failed(c, s, e, plane_at, (blame){NULL, 0, NBEP_DIAG_UNRANKED},
                    "spheres.[%zu]: this simple cubic lattice is packed tight along %c: rows of "
                    "%" PRIu64 " spheres of radius %g touch one another and %s, so with speed %g "
                    "no sphere can move along %c, and the run would not pass t = 0 (endless "
                    "collisions at zero time); give the region more room along %c than %" PRIu64
                    " diameters (%g), fewer spheres, or speed = 0",
                    k, "xyz"[first], n[first], r,
                    box_periodic[first] ? "close round the periodic box" : "both walls", e->speed,
                    "xyz"[first], "xyz"[first],
                    n[first], 2.0 * r * (double)n[first]);
    return true;
}

/* A lattice filling the region (simple cubic, or face-centred cubic for "fcc"); returns as
 * place_random does. */
static nbep_status place_lattice(nbep__scene_ctx *c, grid *g, nbep_state *s,
                                 const nbep__scene_entry *e, size_t k, uint64_t seed,
                                 const config_setting_t *const *plane_at,
                                 const bool *box_periodic, nbep_vec3 box_lo, nbep_vec3 box_hi)
{
    const double r = e->radius;
    const bool fcc = e->place == NBEP__PLACE_FCC;
    const double rlo[3] = {e->lo.x, e->lo.y, e->lo.z}, rhi[3] = {e->hi.x, e->hi.y, e->hi.z};
    const double blo[3] = {box_lo.x, box_lo.y, box_lo.z}, bhi[3] = {box_hi.x, box_hi.y, box_hi.z};
    bool spans[3]; /* a periodic axis the region spans whole */
    for (int a = 0; a < 3; a++)
        spans[a] = box_periodic && box_periodic[a] && rlo[a] == blo[a] && rhi[a] == bhi[a];
    double lo[3], hi[3];
    lattice_axis ax[3];
    lattice_axes(rlo, rhi, r, spans, fcc, ax, lo, hi);
    if (e->count == 0)
        return NBEP_OK;
    double spacing = lattice_spacing(ax, r, e->count, fcc);
    if (spacing == 0.0) {
        const double vol = box_volume(e->lo, e->hi);
        const double most = lattice_capacity(ax, lattice_min_spacing(r, fcc), fcc);
        /* a simple cubic fill that fails names the face-centred one where that holds them
         * (the densest simple cubic fill is 0.52; hard-sphere crystals are studied to 0.74) */
        lattice_axis fax[3]; /* the axes "fcc" would take */
        double flo[3], fhi[3];
        lattice_axes(rlo, rhi, r, spans, true, fax, flo, fhi);
        const double most_fcc = lattice_capacity(fax, lattice_min_spacing(r, true), true);
        char hint[96] = "", why[160];
        no_room_why(e->lo, e->hi, r, 0, 0, why, sizeof why);
        if (!fcc && most_fcc >= (double)e->count)
            snprintf(hint, sizeof hint,
                     "; place = \"fcc\" holds up to %.0f (packing fraction %.2f)", most_fcc,
                     most_fcc * ball_volume(r) / vol);
        fill_failed(c, s, e, plane_at, (blame){NULL, 0, NBEP_DIAG_UNRANKED},
                        "spheres.[%zu]: could not place %" PRIu64
                        " spheres of radius %g in the region: a %s lattice holds at "
                        "most %.0f (packing fraction %.2f)%s%s",
                        k, e->count, r, fcc ? "face-centred cubic" : "simple cubic", most,
                        most * ball_volume(r) / vol, why, hint);
        return NBEP_OK;
    }
    char longer[160] = ""; /* the periodic axes its region is longer than a period along */
    for (int a = 0; a < 3; a++)
        if (box_periodic && box_periodic[a] && rhi[a] - rlo[a] > bhi[a] - blo[a]) {
            const size_t used = strlen(longer);
            snprintf(longer + used, sizeof longer - used, "%s%c (%g > %g)", used ? ", " : "",
                     "xyz"[a], rhi[a] - rlo[a], bhi[a] - blo[a]);
        }
    uint64_t n[3];
    double step[3];
    for (int a = 0; a < 3; a++) {
        n[a] = (uint64_t)lattice_sites(ax[a], spacing);
        /* a wrapping axis spaces its n sites evenly round the period (at least the spacing) */
        step[a] = ax[a].wraps ? ax[a].len / (double)n[a] : spacing;
    }
    if (lattice_jams(c, s, e, k, ax, spacing, n, box_periodic, spans, blo, bhi, plane_at))
        return NBEP_OK;
    uint64_t idx[3] = {0, 0, 0};
    for (uint64_t q = 0; q < e->count; q++, lattice_next(idx, n[0], n[1])) {
        const nbep_status stop = look(c, q);
        if (stop != NBEP_OK)
            return stop;
        while (fcc && (idx[0] + idx[1] + idx[2]) % 2 != 0)
            lattice_next(idx, n[0], n[1]);
        double x[3];
        for (int a = 0; a < 3; a++)   /* never past the far side by rounding */
            x[a] = ax[a].wraps ? lo[a] + ((double)idx[a] + 0.5) * step[a]
                   : idx[a] == 0 ? lo[a]
                                 : fmin(lo[a] + (double)idx[a] * spacing, hi[a]);
        size_t id = e->first + (size_t)q;
        set_sphere(s, e, id, nbep_vec3_make(x[0], x[1], x[2]),
                   random_velocity(seed, k, q, e->speed));
        if (longer[0] && lattice_wraps_onto(c, g, s, e, k, id, r, longer, plane_at))
            return NBEP_OK;
        if (!grid_insert(g, id))
            return NBEP_ENOMEM;
    }
    return NBEP_OK;
}

nbep_status nbep__scene_place(nbep__scene_ctx *c, nbep_state *s, const nbep__scene_entry *e,
                              size_t n_entries, uint64_t seed, const bool *box_periodic,
                              nbep_vec3 box_lo, nbep_vec3 box_hi,
                              const config_setting_t *const *plane_at)
{
    grid g;
    if (!grid_init(&g, s, e, n_entries)) {
        grid_fini(&g);
        NBEP_FAIL(c->d, NBEP_ENOMEM, "nbep: no memory to place %zu spheres", s->n);
    }
    /* periodic axes: a group's places wrap into the box (README, The deck), so the random
     * ones keep clear across the faces too (until 2026-11-30 they measured plain distances,
     * and a region past a face gave overlaps the deck check then refused) */
    const nbep_periodic pb = nbep_periodic_make(box_periodic, box_lo, box_hi);
    g.pb = pb.any ? &pb : NULL;
    nbep_status st = NBEP_OK;
    /* Single spheres first, wherever they are in the deck, so that no group lands on one (a
     * deck lists few: they do not look at the stop signal). */
    for (size_t k = 0; st == NBEP_OK && k < n_entries; k++)
        if (e[k].place == NBEP__PLACE_ONE) {
            set_sphere(s, &e[k], e[k].first, e[k].position, e[k].velocity);
            st = grid_insert(&g, e[k].first) ? NBEP_OK : NBEP_ENOMEM;
        }
    for (size_t k = 0; st == NBEP_OK && k < n_entries; k++) {
        if (e[k].place == NBEP__PLACE_RANDOM)
            st = place_random(c, &g, s, &e[k], k, seed, plane_at);
        else if (nbep__place_is_lattice(e[k].place))
            st = place_lattice(c, &g, s, &e[k], k, seed, plane_at, box_periodic, box_lo,
                               box_hi);
    }
    grid_fini(&g);
    if (st == NBEP_ENOMEM)
        NBEP_FAIL(c->d, NBEP_ENOMEM, "nbep: no memory to place %zu spheres", s->n);
    return st;
}

/* ---- the overlap check ---------------------------------------------------------------------- */

/* Whether a sphere's centre lies past the plane it overlaps, and which: a sphere outside the
 * box, or behind a deck plane, overlaps it by more than its radius, and is said to be on the
 * wrong side (a new user read "overlaps box x-max by 6.1" of a sphere 6 past the wall as a
 * placement a hair off). */
/* PAST_SPANS: no overlap, a sphere touching both walls of an axis while moving along it */
typedef enum { PAST_NOT, PAST_BOX_WALL, PAST_PLANE, PAST_SPANS } past_kind;

/* An overlap to be listed by name. */
typedef struct listed {
    uint64_t seq;                   /* how many were found before it */
    blame at;                       /* what it is blamed on, and its message's rank */
    size_t entry, a;                /* sphere a, of that entry, */
    char other[96];                 /* overlaps this; where it spans: the axis and sizes */
    double by;                      /* by this much; or, where past: its centre is this far
                                     * past the plane `other`; where it spans: its velocity
                                     * along the axis */
    past_kind past;
} listed;

typedef struct overlaps {
    nbep__scene_ctx *c;
    const nbep_state *s;
    const nbep__scene_entry *e;
    size_t n_entries;
    const blame *placed;  /* per entry: what placed its spheres (entry_blame) */
    const config_setting_t *box; /* the deck's box (box_of), for what moved a periodic face */
    /* the positions measured: s->pos, or in a periodic box those wrapped into it, with the
     * periods removed (image, else NULL) */
    const nbep_vec3 *pos;
    const int32_t (*image)[3];
    size_t i;             /* the sphere whose neighbours are visited */
    nbep_vec3 shift;      /* at its position plus this (a copy across periodic faces) */
    bool same_level;      /* they are in its level: only smaller ids count */
    uint64_t found;
    /* the first OVERLAP_REPORT_MAX by rank, which the load lists first, not the first found:
     * planes are checked before pairs, and a pair is found from either sphere's side, so the
     * first found can leave out the deck's first lines (and a --set's, listed before them) */
    listed kept[OVERLAP_REPORT_MAX];
    size_t n_kept;
    size_t last;          /* once all are kept: the one last by rank (then found) */
} overlaps;

/* Sphere a overlaps `other` (a sphere or a plane, which bb blames: what placed the sphere and
 * moved the faces between them, or what moved the plane) by `by`. The overlap is blamed on
 * whichever of the two an override placed or moved, the one typed first where both were (the
 * list ranks the message there), else on a's deck line (a, the later sphere, as before): the
 * change that made the overlap, not the deck line the user did not touch. */
static void report(overlaps *o, size_t a, blame bb, const char *other, double by,
                   past_kind past)
{
    const uint64_t seq = o->found++;
    blame at = o->placed[entry_of(o->e, o->n_entries, a)];
    if (bb.label && bb.rank < at.rank) /* a deck line's rank is past every option's */
        at = bb;
    size_t k;
    if (o->n_kept < OVERLAP_REPORT_MAX)
        k = o->n_kept++;
    else if (at.rank < o->kept[o->last].at.rank) /* found later: before the last only by rank */
        k = o->last;
    else
        return;
    listed *l = &o->kept[k];
    *l = (listed){.seq = seq, .at = at, .entry = entry_of(o->e, o->n_entries, a),
                  .a = a, .by = by, .past = past};
    snprintf(l->other, sizeof l->other, "%s", other);
    if (o->n_kept < OVERLAP_REPORT_MAX)
        return;
    o->last = 0;
    for (size_t j = 1; j < o->n_kept; j++)
        if (o->kept[j].at.rank > o->kept[o->last].at.rank ||
            (o->kept[j].at.rank == o->kept[o->last].at.rank &&
             o->kept[j].seq > o->kept[o->last].seq))
            o->last = j;
}

static int cmp_seq(const void *x, const void *y)
{
    const listed *u = x, *v = y;
    return u->seq < v->seq ? -1 : u->seq > v->seq;
}

/* The kept overlaps, in the order they were found (the load's sort puts them by rank). */
static void list_kept(overlaps *o)
{
    qsort(o->kept, o->n_kept, sizeof *o->kept, cmp_seq);
    for (size_t k = 0; k < o->n_kept; k++) {
        const listed *l = &o->kept[k];
        char what[160];
        if (l->past == PAST_BOX_WALL)
            snprintf(what, sizeof what, "lies outside the box: its centre is %g past %s", l->by,
                     l->other);
        else if (l->past == PAST_PLANE)
            snprintf(what, sizeof what, "lies behind %s: its centre is %g past it", l->other,
                     l->by);
        else if (l->past == PAST_SPANS) {
            const char axis = l->other[0];
            nbep__scene_error_from(
                o->c, l->at.label, l->at.line, __FILE__, __LINE__,
                "spheres.[%zu] (sphere %zu) touches both walls along %c (%s) while moving along "
                "%c at %g, so the run would not pass t = 0 (endless collisions at zero time); "
                "give the box more room along %c, or the sphere no velocity along %c",
                l->entry, l->a, axis, l->other + 2, axis, l->by, axis, axis);
            continue;
        }
        else
            snprintf(what, sizeof what, "overlaps %s by %g", l->other, l->by);
        nbep__scene_error_from(o->c, l->at.label, l->at.line, __FILE__, __LINE__,
                               "spheres.[%zu] (sphere %zu) %s", l->entry, l->a, what);
    }
}

/* The elements of the box along an axis that put its periodic faces where they are: a copy of
 * a sphere across them lies a period, max - min, away, and periodic made them faces. */
static const char *const face_corners[3] = {"min", "max", "periodic"};

static void check_pair(overlaps *o, size_t i, size_t j)
{
    const nbep_state *s = o->s;
    const nbep_vec3 *pos = o->pos;
    double dist = nbep_vec3_norm(nbep_vec3_sub(nbep_vec3_add(pos[i], o->shift), pos[j]));
    double by = s->radius[i] + s->radius[j] - dist;
    double tol = touch_tol(max_abs(pos[i]), max_abs(pos[j]), s->radius[i] + s->radius[j]);
    if (by > tol) {
        size_t a = i > j ? i : j, b = i > j ? j : i;
        /* the axes the pair meets across: the copy's shift, or the two given a period or
         * more apart there (wrapped by different counts of periods) */
        const double shift[3] = {o->shift.x, o->shift.y, o->shift.z};
        bool across[3], any = false;
        for (int axis = 0; axis < 3; axis++) {
            across[axis] = shift[axis] != 0.0 ||
                           (o->image && o->image[i][axis] != o->image[j][axis]);
            any = any || across[axis];
        }
        char other[96];
        snprintf(other, sizeof other, "spheres.[%zu] (sphere %zu)%s",
                 entry_of(o->e, o->n_entries, b), b, any ? " across a periodic face" : "");
        /* what placed b, and what moved the faces the pair meets across: a --set of box.max,
         * say, that brought the faces' two sides together (until 2026-11-30 the overlap was
         * blamed on the spheres' lines) */
        blame bb = o->placed[entry_of(o->e, o->n_entries, b)];
        for (int axis = 0; o->box && axis < 3; axis++) {
            if (!across[axis])
                continue;
            for (int m = 0; m < 3; m++) {
                const config_setting_t *v = config_setting_get_member(o->box, face_corners[m]);
                blame_first(o->c, &bb, v ? config_setting_get_elem(v, (unsigned)axis) : NULL);
            }
        }
        report(o, a, bb, other, by, PAST_NOT);
    }
}

/* A grid neighbour of o->i; in its own level, only one with a smaller id. */
static bool pair_visit(void *arg, size_t j)
{
    overlaps *o = arg;
    if (j < o->i || (!o->same_level && j != o->i))
        check_pair(o, o->i, j);
    return false;
}

/* In the order fill_planes (scene.c) makes them. */
static const char *const box_names[6] = {"box x-min", "box x-max", "box y-min",
                                         "box y-max", "box z-min", "box z-max"};

nbep_status nbep__scene_check_overlaps(nbep__scene_ctx *c, const nbep_state *s,
                                       const nbep__scene_entry *e, size_t n_entries,
                                       const bool *box_periodic, nbep_vec3 box_lo,
                                       nbep_vec3 box_hi, const config_setting_t *const *plane_at)
{
    /* the box's walls in fill_planes's order: the two of each axis that is not periodic */
    const char *names[6];
    size_t n_box = 0;
    for (int a = 0; box_periodic && a < 3; a++)
        if (!box_periodic[a]) {
            names[n_box++] = box_names[2 * a];
            names[n_box++] = box_names[2 * a + 1];
        }
    blame *placed = malloc((n_entries + s->n_planes + 1) * sizeof *placed);
    if (!placed)
        NBEP_FAIL(c->d, NBEP_ENOMEM, "nbep: no memory to check %zu spheres for overlaps", s->n);
    blame *walls = placed + n_entries;
    for (size_t k = 0; k < n_entries; k++)
        placed[k] = entry_blame(c, e[k].setting);
    for (size_t p = 0; p < s->n_planes; p++) {
        walls[p] = (blame){NULL, 0, NBEP_DIAG_UNRANKED}; /* none: an overlap stays its sphere's */
        plane_blame(c, &walls[p], &plane_at[2 * p]);
    }
    /* Along periodic axes the spheres are measured where the run puts them, wrapped into the
     * box: a single sphere's position or a lattice's region may lie periods away (until
     * 2026-11-30 the grid and the faces' copies took the positions as given, and spheres at
     * x = 15 and 5.2 in a period of 10 passed, to overlap by 0.8 of a diameter in the run). */
    const nbep_periodic pb = nbep_periodic_make(box_periodic, box_lo, box_hi);
    nbep_vec3 *wrapped = NULL;
    int32_t(*image)[3] = NULL;
    if (pb.any) {
        wrapped = malloc((s->n ? s->n : 1) * sizeof *wrapped);
        image = calloc(s->n ? s->n : 1, sizeof *image);
        if (!wrapped || !image) {
            free(wrapped);
            free(image);
            free(placed);
            NBEP_FAIL(c->d, NBEP_ENOMEM, "nbep: no memory to check %zu spheres for overlaps",
                      s->n);
        }
        for (size_t i = 0; i < s->n; i++) {
            wrapped[i] = s->pos[i];
            nbep_periodic_wrap(&pb, &wrapped[i], image[i]);
        }
    }
    overlaps o = {.c = c, .s = s, .e = e, .n_entries = n_entries, .placed = placed,
                  .box = n_entries ? box_of(e[0].setting) : NULL,
                  .pos = pb.any ? wrapped : s->pos, .image = (const int32_t(*)[3])image};
    const double blo[3] = {box_lo.x, box_lo.y, box_lo.z}, bhi[3] = {box_hi.x, box_hi.y, box_hi.z};
    for (size_t i = 0; i < s->n; i++)
        for (size_t p = 0; p < s->n_planes; p++) {
            const double d = nbep_vec3_dot(s->plane_normal[p], s->pos[i]) - s->plane_offset[p];
            double by = s->radius[i] - d;
            double tol = touch_tol(max_abs(s->pos[i]), fabs(s->plane_offset[p]), s->radius[i]);
            if (by > tol) {
                char name[48];
                if (p < n_box)
                    snprintf(name, sizeof name, "%s", names[p]);
                else
                    snprintf(name, sizeof name, "planes.[%zu]", p - n_box);
                /* its centre past the plane by more than the touch tolerance: outside */
                const bool past = -d > tol;
                report(&o, i, walls[p], name, past ? -d : by,
                       !past ? PAST_NOT : p < n_box ? PAST_BOX_WALL : PAST_PLANE);
            }
        }

    /* A sphere as wide as the box between two walls, moving along their axis: each wall sends
     * it into the other at the same instant, and a predictive run stalls at t = 0 (found
     * 2026-12-05: random placement of one sphere, or one given by position, passed the check
     * that refuses such a lattice, lattice_jams, and stopped at step 1 after 11 s). Touching
     * is each wall's touch tolerance, as for an overlap; an overlap beyond it is reported
     * above instead. Gravity alone presses it into one wall: resting contact, which runs. */
    for (size_t i = 0; box_periodic && i < s->n; i++) {
        const double r = s->radius[i];
        const double x[3] = {s->pos[i].x, s->pos[i].y, s->pos[i].z};
        const double v[3] = {s->vel[i].x, s->vel[i].y, s->vel[i].z};
        for (int a = 0; a < 3; a++) {
            if (box_periodic[a] || v[a] == 0.0)
                continue;
            const double lo = r - (x[a] - blo[a]), hi = r - (bhi[a] - x[a]);
            const double tlo = touch_tol(fabs(x[a]), fabs(blo[a]), r);
            const double thi = touch_tol(fabs(x[a]), fabs(bhi[a]), r);
            if (fabs(lo) <= tlo && fabs(hi) <= thi) {
                char what[96];
                snprintf(what, sizeof what, "%c diameter %g, the box %g wide", "xyz"[a], 2.0 * r,
                         bhi[a] - blo[a]);
                report(&o, i, (blame){NULL, 0, NBEP_DIAG_UNRANKED}, what, v[a], PAST_SPANS);
                break;
            }
        }
    }

    grid g;
    bool ok = grid_init(&g, s, e, n_entries);
    g.pb = pb.any ? &pb : NULL; /* cells of the wrapped positions, o.pos */
    for (size_t i = 0; ok && i < s->n; i++)
        ok = grid_insert(&g, i);
    /* Each pair once: a sphere looks at its own level (partners of smaller id) and at the
     * levels of larger spheres (all partners), never at smaller spheres, whose cells would be
     * many for its reach; those pairs are found from the smaller sphere's side. */
    double rmax_all = 0.0;
    for (int l = 0; ok && l < LEVELS_MAX; l++)
        rmax_all = fmax(rmax_all, g.lv[l].rmax);
    /* the check's time (the planes' and the grid's loops above are a few per cent of it) */
    nbep_status stop = NBEP_OK;
    for (size_t i = 0; ok && i < s->n && (stop = look(c, i)) == NBEP_OK; i++) {
        o.i = i;
        int own = level_of(&g, s->radius[i]);
        /* periodic faces: the copies of i across each face it is near (within the largest
         * contact distance), alone and in combination (edges, corners); a pair is near in one
         * copy only, since a periodic side exceeds twice the largest diameter */
        const double x[3] = {o.pos[i].x, o.pos[i].y, o.pos[i].z};
        double near[3] = {0.0, 0.0, 0.0};
        for (int a = 0; box_periodic && a < 3; a++) {
            double reach = s->radius[i] + rmax_all;
            if (box_periodic[a] && x[a] - blo[a] < reach)
                near[a] = bhi[a] - blo[a];
            else if (box_periodic[a] && bhi[a] - x[a] < reach)
                near[a] = blo[a] - bhi[a];
        }
        for (int m = 0; m < 8; m++) {
            if (((m & 1) && near[0] == 0.0) || ((m & 2) && near[1] == 0.0) ||
                ((m & 4) && near[2] == 0.0))
                continue;
            o.shift = nbep_vec3_make(m & 1 ? near[0] : 0.0, m & 2 ? near[1] : 0.0,
                                     m & 4 ? near[2] : 0.0);
            for (int l = own; l < LEVELS_MAX; l++) {
                o.same_level = l == own;
                if (g.lv[l].rmax > 0.0)
                    (void)level_near(&g, &g.lv[l], nbep_vec3_add(o.pos[i], o.shift),
                                     s->radius[i] + g.lv[l].rmax, pair_visit, &o);
            }
        }
    }
    grid_fini(&g);
    free(placed);
    free(wrapped);
    free(image);
    if (stop != NBEP_OK) /* the overlaps found so far are not all: none is listed */
        return stop;
    list_kept(&o);
    if (!ok)
        NBEP_FAIL(c->d, NBEP_ENOMEM, "nbep: no memory to check %zu spheres for overlaps", s->n);
    /* the count goes right after the overlaps listed: at the last one's rank, added after it
     * (the sort is stable), not among the messages that name no line, after later lines' */
    uint64_t last_rank = 0;
    for (size_t k = 0; k < o.n_kept; k++)
        last_rank = o.kept[k].at.rank > last_rank ? o.kept[k].at.rank : last_rank;
    if (o.found > OVERLAP_REPORT_MAX)
        nbep_diag_add_ranked(c->d, last_rank, __FILE__, __LINE__,
                             "nbep: %s: %" PRIu64 " more overlaps not listed", c->deck,
                             o.found - OVERLAP_REPORT_MAX);
    return NBEP_OK;
}
