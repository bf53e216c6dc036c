/* The detection algorithms: naive (paper Algorithm 1, Section 5.1) and seminaive (Section
 * 2.2). Each step: update every sphere by dt, then test every sphere against every plane and
 * every later sphere (seminaive: only the later spheres whose bounding boxes overlap in a
 * bounding volume hierarchy), and respond to pairs that overlap while approaching.
 *
 * Departure from the paper, for threads: "run the outer loop in parallel" lets two threads
 * respond to pairs that share a sphere at once (a race, and results that depend on timing).
 * Here threads only *find* overlapping pairs, in parallel over contiguous rows (positions do
 * not change while they look); then thread 0 responds to them in the serial order of the
 * paper's loop (row i ascending, planes before spheres, partner ascending). Finding is the
 * O(n^2) (naive) or O(n log n) (seminaive) part; responding is O(contacts). So the frames are
 * bitwise the same for any thread count, and seminaive finds and answers exactly the pairs
 * naive does.
 *
 * Layout: one parallel region over all steps, phases separated by nbep_barrier.
 *
 * A signal within a step (a job's time limit during a pass of tens of seconds: naive over
 * 100000 spheres, longer than Slurm's 30 s between SIGTERM and SIGKILL): every thread looks at
 * the stop signal every LOOK_COST of its rows' cost, and one that finds it ends its rows and
 * says so in the shared `quit`. Past the barrier that ends the pass every thread reads that
 * one flag, so all abandon the step or none do: each puts its own spheres back where the step
 * found them (the drift's writes, saved; the pass writes nothing else before responding), and
 * the run ends after the step before, as the predictive algorithm's abandoned steps do. */
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/barrier.h"
#include "nbep/bvh.h"
#include "nbep/periodic.h"
#include "nbep/physics.h"
#include "sim_impl.h"

/* A contact found by detection: sphere i with sphere j (j < n) or plane j - n. */
typedef struct contact {
    uint32_t i, j;
} contact;

typedef struct contact_list {
    alignas(NBEP_CACHELINE) contact *c;   /* owned */
    size_t len, cap;
    size_t row_lo, row_hi;                /* detection rows of this thread */
    uint64_t cost;                        /* their cost (row_cost), the progress's whole */
    /* seminaive: the row being queried and its hits, sorted before use */
    uint32_t *hits;                       /* owned */
    size_t n_hits, cap_hits;
    bool overflow;                        /* an allocation failed: the step is abandoned */
} contact_list;

typedef struct detect_ctx {
    bool use_bvh;
    nbep_barrier bar;
    contact_list *lists;   /* owned, one per thread */
    nbep_bvh *bvh;         /* owned, seminaive only */
    nbep_vec3 *pos0, *vel0; /* owned, n each: every sphere as the step found it (before its
                             * drift), what an abandoned step puts back */
    /* a periodic box (SPEC contract 2): its geometry, the largest radius (how near a face a
     * sphere's partners may lie across it) and every sphere's images as the step found them
     * (img0, owned, 3n; NULL without periodic axes), put back with pos0 */
    nbep_periodic pb;
    double rmax;
    int32_t *img0;
    /* set (for good) by a thread whose look in the pass found the stop signal; read by every
     * thread past the barrier that ends the pass */
    atomic_int quit;
} detect_ctx;

/* Every this many units of row cost (row_cost: about one pair or plane test each, some 0.1 ms
 * of them), a thread of the pass looks at the stop signal, and thread 0 updates the progress
 * line: a relaxed load and a clock read against the tests, and a signal is seen within a
 * millisecond or so. A naive row of 65536 spheres is one look; seminaive looks every few
 * thousand rows. */
#define LOOK_COST 65536u

/* Tests only (tests/test_detect_stop.c compiles its own copy with a hook that raises the
 * signal): whether the pass looks at the stop signal after row `row` of step `step` too. */
#ifndef NBEP_DETECT_LOOK_HOOK
#define NBEP_DETECT_LOOK_HOOK(step, row) false
#endif

static void detect_destroy(void *p)
{
    detect_ctx *ctx = p;
    if (!ctx)
        return;
    if (ctx->lists) {
        for (size_t t = 0; t < (size_t)ctx->bar.n; t++) {
            free(ctx->lists[t].c);
            free(ctx->lists[t].hits);
        }
        nbep_free_aligned(ctx->lists);
    }
    nbep_free_aligned(ctx->pos0);
    nbep_free_aligned(ctx->vel0);
    nbep_free_aligned(ctx->img0);
    nbep_bvh_destroy(&ctx->bvh);
    free(ctx);
}

/* The cost of detection row i of n spheres and n_planes planes, in pair tests: n_planes +
 * (n - 1 - i) naive; seminaive rows cost about the same, the few partners a query finds. */
static uint64_t row_cost(bool use_bvh, size_t n, size_t n_planes, size_t i)
{
    return n_planes + (use_bvh ? 8 : n - 1 - i);
}

/* Rows [lo, hi) per thread so that each thread makes about the same number of pair tests. */
static void split_rows(detect_ctx *ctx, size_t n, size_t n_planes, int nt)
{
    double total = 0.0;
    for (size_t i = 0; i < n; i++)
        total += (double)row_cost(ctx->use_bvh, n, n_planes, i);
    size_t i = 0;
    double acc = 0.0;
    for (int t = 0; t < nt; t++) {
        contact_list *l = &ctx->lists[t];
        l->row_lo = i;
        l->cost = 0;
        double goal = total * (double)(t + 1) / (double)nt;
        for (; i < n && (t == nt - 1 || acc < goal); i++) {
            const uint64_t c = row_cost(ctx->use_bvh, n, n_planes, i);
            acc += (double)c;
            l->cost += c;
        }
        l->row_hi = i;
    }
}

/* The room a contact list starts with for `rows` detection rows: a few contacts per sphere; a
 * denser pile grows the list (rare). */
static size_t list_room(size_t rows)
{
    return 4 * rows + 64;
}

/* The bytes detect_create_common allocates for a run of sc on nt threads (nbep check's memory
 * estimate): the contact lists at their starting room, the spheres as a step found them and,
 * with the BVH, a query's hits of up to n + 1 spheres per thread and the hierarchy. */
static size_t detect_bytes_common(const nbep_scene *sc, int nt, bool use_bvh)
{
    const size_t n = sc->state.n;
    const contact_list *l = NULL; /* for element sizes only: sizeof does not evaluate */
    /* the threads' rows cover the n spheres once */
    size_t bytes = sizeof(detect_ctx) + (size_t)nt * sizeof *l +
                   (list_room(n) + 64 * (size_t)(nt - 1)) * sizeof *l->c +
                   2 * n * sizeof(nbep_vec3);
    if (nbep_scene_any_periodic(sc))
        bytes += 3 * n * sizeof(int32_t); /* img0 */
    if (use_bvh)
        bytes += (size_t)nt * (n + 1) * sizeof *l->hits + nbep_bvh_bytes(n);
    return bytes;
}

static size_t naive_bytes(const nbep_scene *sc, int nt)
{
    return detect_bytes_common(sc, nt, false);
}

static size_t seminaive_bytes(const nbep_scene *sc, int nt)
{
    return detect_bytes_common(sc, nt, true);
}

static nbep_status detect_create_common(nbep_sim *sim, void **out, bool use_bvh, nbep_diag *d)
{
    detect_ctx *ctx = calloc(1, sizeof *ctx);
    if (!ctx)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the %s algorithm", sim->algo->name);
    ctx->use_bvh = use_bvh;
    nbep_barrier_init(&ctx->bar, (unsigned)sim->nt);
    atomic_init(&ctx->quit, 0);
    ctx->lists = nbep_alloc_aligned((size_t)sim->nt, sizeof *ctx->lists);
    ctx->pos0 = nbep_alloc_aligned(sim->st.n, sizeof *ctx->pos0);
    ctx->vel0 = nbep_alloc_aligned(sim->st.n, sizeof *ctx->vel0);
    ctx->pb = nbep_periodic_make(sim->scene->has_box ? sim->scene->periodic : NULL,
                                 sim->scene->box_min, sim->scene->box_max);
    if (ctx->pb.any) {
        ctx->img0 = nbep_alloc_aligned(3 * sim->st.n, sizeof *ctx->img0);
        for (size_t i = 0; i < sim->st.n; i++)
            ctx->rmax = fmax(ctx->rmax, sim->st.radius[i]);
    }
    if (!ctx->lists || (sim->st.n && (!ctx->pos0 || !ctx->vel0 || (ctx->pb.any && !ctx->img0)))) {
        detect_destroy(ctx);
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for the %s algorithm", sim->algo->name);
    }
    size_t n = sim->st.n;
    split_rows(ctx, n, sim->st.n_planes, sim->nt);
    for (int t = 0; t < sim->nt; t++) {
        contact_list *l = &ctx->lists[t];
        l->cap = list_room(l->row_hi - l->row_lo);
        l->c = malloc(l->cap * sizeof *l->c);
        /* a query reports at most n - 1 spheres: room for all, so a step never allocates */
        l->cap_hits = use_bvh ? n + 1 : 0;
        l->hits = use_bvh ? malloc(l->cap_hits * sizeof *l->hits) : NULL;
        if (!l->c || (use_bvh && !l->hits)) {
            detect_destroy(ctx);
            NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory for contact lists of %zu spheres", n);
        }
    }
    if (use_bvh) {
        nbep_status st = nbep_bvh_create(n, &ctx->bvh, d);
        if (st != NBEP_OK) {
            detect_destroy(ctx);
            return st;
        }
    }
    *out = ctx;
    return NBEP_OK;
}

static nbep_status naive_create(nbep_sim *sim, void **out, nbep_diag *d)
{
    return detect_create_common(sim, out, false, d);
}

static nbep_status seminaive_create(nbep_sim *sim, void **out, nbep_diag *d)
{
    return detect_create_common(sim, out, true, d);
}

/* Contact lists start with room for 4 contacts per row; a pile denser than that grows the list
 * inside a step, the one allocation a step can make (naive detection lets overlaps build up
 * in piles under gravity, so no fixed bound holds without O(n^2) memory). */
static void push_contact(contact_list *l, uint32_t i, uint32_t j)
{
    if (l->len == l->cap) {
        contact *c = realloc(l->c, 2 * l->cap * sizeof *c);
        if (!c) {
            l->overflow = true;
            return;
        }
        l->c = c;
        l->cap *= 2;
    }
    l->c[l->len++] = (contact){i, j};
}

/* The deepest overlap a thread's rows found in a step, absolute and relative to the smaller
 * radius: the step's maxima take it once the pass is whole (an abandoned step's, never). */
typedef struct deepest {
    double overlap, overlap_rel;
} deepest;

/* Exact overlap test of spheres i < j, by the minimum image in a periodic box (the places are
 * wrapped into it, so one period at most apart); records a contact and the overlap when they
 * overlap (touching, distance == r_i + r_j, is not overlapping). */
static void test_pair(const nbep_periodic *pb, const nbep_state *s, size_t i, size_t j,
                      contact_list *l, deepest *mx)
{
    nbep_vec3 dp = nbep_vec3_sub(s->pos[j], s->pos[i]);
    if (pb->any)
        dp = nbep_periodic_near_image(pb, dp);
    double sigma = s->radius[i] + s->radius[j];
    double d2 = nbep_vec3_norm2(dp);
    if (d2 < sigma * sigma) {
        push_contact(l, (uint32_t)i, (uint32_t)j);
        double ov = sigma - sqrt(d2);
        mx->overlap = fmax(mx->overlap, ov);
        mx->overlap_rel = fmax(mx->overlap_rel, ov / fmin(s->radius[i], s->radius[j]));
    }
}

static void collect_hit(void *p, uint32_t j)
{
    contact_list *l = p;
    l->hits[l->n_hits++] = j; /* cap_hits = n: never full */
}

/* A periodic box's query, through one copy of sphere i (i moved by -want): a partner is kept
 * only where that copy is the nearest way to it (the shift that brings its separation from i
 * to the minimum image is `want`), so that no partner is kept twice, through the copy in place
 * and another (a periodic side within a rounding of two diameters: until 2026-12-01 the pair
 * was tested twice, and nine of them wrote past the hits' room), and the exact test takes that
 * image. A pair that touches does so by its minimum image, whose copy is queried. */
typedef struct image_hits {
    contact_list *l;
    const nbep_state *s;
    const nbep_periodic *pb;
    size_t i;
    nbep_vec3 want;
} image_hits;

static void collect_image_hit(void *p, uint32_t j)
{
    image_hits *h = p;
    const nbep_vec3 ns =
        nbep_periodic_near_shift(h->pb, nbep_vec3_sub(h->s->pos[j], h->s->pos[h->i]));
    if (ns.x == h->want.x && ns.y == h->want.y && ns.z == h->want.z &&
        h->l->n_hits < h->l->cap_hits)
        h->l->hits[h->l->n_hits++] = j;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* Seminaive in a periodic box: the later spheres whose boxes touch i's, or those of its copies
 * across the faces it lies near (within its radius and the largest of a face: a partner across
 * it lies within the largest radius of the other face), each through the copy that is the
 * nearest way to it (collect_image_hit), into l's hits. One copy at most per axis (a side is
 * longer than two largest diameters). */
static void query_images(const detect_ctx *ctx, const nbep_state *s, size_t i, contact_list *l)
{
    const nbep_periodic *pb = &ctx->pb;
    const double p[3] = {s->pos[i].x, s->pos[i].y, s->pos[i].z};
    const double reach = s->radius[i] + ctx->rmax;
    double shift[3][2];
    int cnt[3];
    for (int k = 0; k < 3; k++) {
        shift[k][0] = 0.0;
        cnt[k] = 1;
        if (!pb->axis[k])
            continue;
        if (p[k] + reach >= pb->lo[k] + pb->len[k]) /* near the upper face: the copy below */
            shift[k][cnt[k]++] = -pb->len[k];
        else if (p[k] - reach <= pb->lo[k]) /* near the lower face: the copy above */
            shift[k][cnt[k]++] = pb->len[k];
    }
    image_hits h = {.l = l, .s = s, .pb = pb, .i = i};
    for (int a = 0; a < cnt[0]; a++)
        for (int b = 0; b < cnt[1]; b++)
            for (int c = 0; c < cnt[2]; c++) {
                const nbep_vec3 sh = nbep_vec3_make(shift[0][a], shift[1][b], shift[2][c]);
                h.want = nbep_vec3_make(-sh.x, -sh.y, -sh.z);
                if (a || b || c)
                    nbep_bvh_query_later_shifted(ctx->bvh, s, i, sh, collect_image_hit, &h);
                else /* the copy in place */
                    nbep_bvh_query_later(ctx->bvh, s, i, collect_image_hit, &h);
            }
}

/* Finds this thread's contacts among rows [row_lo, row_hi) of step `step`, the deepest
 * overlap into *mx; returns the tests made. Every LOOK_COST of row cost it looks at the stop
 * signal: one found ends the rows there, with ctx->quit set (detect_run then abandons the
 * step); thread 0 (tid) also shows the part of its rows done on the progress line, the share
 * of the pass it stands for (the rows are shared by cost). */
static uint64_t detect_rows(detect_ctx *ctx, nbep_sim *sim, uint64_t step, int tid,
                            contact_list *l, deepest *mx)
{
    const nbep_state *s = &sim->st;
    const size_t n = s->n, np = s->n_planes;
    uint64_t checks = 0, done = 0, look = LOOK_COST;
    l->len = 0;
    for (size_t i = l->row_lo; i < l->row_hi; i++) {
        for (size_t p = 0; p < np; p++) {
            double gap = nbep_physics_plane_gap(s->plane_normal[p], s->plane_offset[p],
                                                s->pos[i], s->radius[i]);
            if (gap < 0.0) {
                push_contact(l, (uint32_t)i, (uint32_t)(n + p));
                mx->overlap = fmax(mx->overlap, -gap);
                mx->overlap_rel = fmax(mx->overlap_rel, -gap / s->radius[i]);
            }
        }
        checks += np;
        if (ctx->use_bvh) {
            l->n_hits = 0;
            if (ctx->pb.any)
                query_images(ctx, s, i, l);
            else
                nbep_bvh_query_later(ctx->bvh, s, i, collect_hit, l);
            /* the paper's loop meets partners in index order; so do we */
            qsort(l->hits, l->n_hits, sizeof *l->hits, cmp_u32);
            for (size_t k = 0; k < l->n_hits; k++)
                test_pair(&ctx->pb, s, i, l->hits[k], l, mx);
            checks += l->n_hits;
        } else {
            for (size_t j = i + 1; j < n; j++)
                test_pair(&ctx->pb, s, i, j, l, mx);
            checks += n - 1 - i;
        }
        done += row_cost(ctx->use_bvh, n, np, i);
        if (done >= look || NBEP_DETECT_LOOK_HOOK(step, i)) {
            look = done + LOOK_COST;
            /* relaxed, as every look at it: the handler stores the signal with no other data
             * to pass; and quit's readers are past the barrier that ends the pass */
            if (nbep_sim_stop_status(sim->opt.stop_signal) != NBEP_OK) {
                atomic_store_explicit(&ctx->quit, 1, memory_order_relaxed);
                break;
            }
            if (tid == 0)
                nbep__sim_progress_part(sim, step, (double)done / (double)l->cost);
        }
    }
    return checks;
}

/* Thread 0: responds to every contact in the paper's serial order; returns collisions by kind
 * through the counters. A contact responds only while approaching (physics kernels).
 * Departure from the paper (issue 9): every overlap found is also undone by moving the
 * sphere(s) back to touching (position projection). Without it a sphere resting under gravity
 * gains -g dt each step, is found inside the plane, responds with e < 1 and sinks a little
 * more every step (measured: bounce.deck 0.023 m into the floor after 100 s). With it a
 * resting sphere never goes deeper than one step's fall, g dt^2, and a stack does not sink
 * into itself; the potential energy this puts back is at most m |a| g dt^2 per contact and
 * step, the same order as the detection error the algorithms already have. */
static void respond_all(const detect_ctx *ctx, nbep_state *s, double e, int nt,
                        nbep_counters *cnt, nbep_thread_max *mx)
{
    const size_t n = s->n;
    const nbep_periodic *pb = &ctx->pb;
    for (int t = 0; t < nt; t++) {
        const contact_list *l = &ctx->lists[t];
        for (size_t k = 0; k < l->len; k++) {
            uint32_t i = l->c[k].i, j = l->c[k].j;
            if (j >= n) {
                const nbep_vec3 pn = s->plane_normal[j - n];
                const double vn0 = nbep_vec3_dot(pn, s->vel[i]);
                if (nbep_physics_respond_plane(pn, &s->vel[i], e))
                    cnt->c[NBEP_COUNTER_PLANE_COLLISIONS]++;
                /* SPEC /stats/wall_impulse: the normal momentum the plane received */
                nbep_xsum_add(&mx->wall[j - n],
                              s->mass[i] * (nbep_vec3_dot(pn, s->vel[i]) - vn0));
                nbep_physics_separate_plane(s->plane_normal[j - n], s->plane_offset[j - n],
                                            &s->pos[i], s->radius[i]);
            } else {
                const nbep_vec3 vj = s->vel[j];
                /* j's copy nearest i in a periodic box (test_pair's minimum image) */
                const nbep_vec3 pj0 = pb->any ? nbep_vec3_add(s->pos[i], nbep_periodic_near_image(
                                                    pb, nbep_vec3_sub(s->pos[j], s->pos[i])))
                                              : s->pos[j];
                if (nbep_physics_respond_pair(s->pos[i], pj0, &s->vel[i], &s->vel[j],
                                              s->mass[i], s->mass[j], e))
                    cnt->c[NBEP_COUNTER_SPHERE_COLLISIONS]++;
                /* SPEC /stats/virial: r12 . dp2, r12 the minimum-image line of centres as
                 * found (after the step's flight, overlapped), at the touching distance
                 * (until 2026-12-01 the overlapped |r12|: a pressure biased low by the
                 * overlap, 2.2 % on a head-on pair at dt = 0.0137) */
                nbep_xsum_add(&mx->virial,
                              nbep_physics_virial_at_touch(
                                  nbep_vec3_sub(pj0, s->pos[i]),
                                  nbep_vec3_scale(nbep_vec3_sub(s->vel[j], vj), s->mass[j]),
                                  s->radius[i] + s->radius[j]));
                if (!pb->any) {
                    nbep_physics_separate_pair(&s->pos[i], &s->pos[j], s->radius[i],
                                               s->radius[j], s->mass[i], s->mass[j]);
                } else { /* j moves as its copy does, and both are wrapped again */
                    nbep_vec3 pj = pj0;
                    nbep_physics_separate_pair(&s->pos[i], &pj, s->radius[i], s->radius[j],
                                               s->mass[i], s->mass[j]);
                    s->pos[j] = nbep_vec3_add(s->pos[j], nbep_vec3_sub(pj, pj0));
                    nbep_periodic_wrap(pb, &s->pos[i], &s->image[3 * i]);
                    nbep_periodic_wrap(pb, &s->pos[j], &s->image[3 * j]);
                }
            }
        }
    }
}

static void detect_run(nbep_sim *sim, void *p)
{
    detect_ctx *ctx = p;
#pragma omp parallel num_threads(sim->nt) default(none) shared(sim, ctx)
    {
        const int tid = nbep__thread_id();
        const int nt = sim->nt;
        nbep_state *s = &sim->st;
        const nbep_range own = nbep__range_split(s->n, tid, nt);
        contact_list *mine = &ctx->lists[tid];
        /* see pred_run: makes OpenMP's hand-over visible to ThreadSanitizer */
        nbep_barrier_wait(&ctx->bar);
        for (uint64_t step = sim->step_first; step <= sim->step_end; step++) {
            const int par = (int)(step & 1);
            /* update: free flight of own spheres, each kept as it was first */
            for (size_t i = own.lo; i < own.hi; i++) {
                ctx->pos0[i] = s->pos[i];
                ctx->vel0[i] = s->vel[i];
                nbep_physics_drift(&s->pos[i], &s->vel[i], s->acc[i], sim->dt);
            }
            if (ctx->pb.any) /* back into the box, the periods crossed counted */
                for (size_t i = own.lo; i < own.hi; i++) {
                    memcpy(&ctx->img0[3 * i], &s->image[3 * i], 3 * sizeof *ctx->img0);
                    nbep_periodic_wrap(&ctx->pb, &s->pos[i], &s->image[3 * i]);
                }
            nbep_barrier_wait(&ctx->bar);
            if (ctx->use_bvh) {
                if (tid == 0)
                    nbep_bvh_build(ctx->bvh, s);
                nbep_barrier_wait(&ctx->bar);
            }
            deepest deep = {0.0, 0.0};
            const uint64_t checks = detect_rows(ctx, sim, step, tid, mine, &deep);
            nbep_barrier_wait(&ctx->bar);
            /* relaxed: the barrier above ordered every store of quit, and none comes until
             * the run ends, so every thread reads the same: all abandon the step, or none.
             * Each list's overflow, written by its thread before that barrier, reads the
             * same to all too. */
            bool overflow = false;
            for (int t = 0; t < nt; t++)
                overflow |= ctx->lists[t].overflow;
            if (overflow || atomic_load_explicit(&ctx->quit, memory_order_relaxed)) {
                /* a signal during the pass, or a contact list that could not grow (the step's
                 * contacts past its room unknown): the step is abandoned (no row, frame or
                 * counts of it), the spheres as the step found them; the run ends after the
                 * step before (the barrier after the steps publishes the puts back). Until
                 * 2026-12-06 a refused growth went on to respond to the contacts it had and
                 * recorded that step (its row, and its frame where one was due) */
                for (size_t i = own.lo; i < own.hi; i++) {
                    s->pos[i] = ctx->pos0[i];
                    s->vel[i] = ctx->vel0[i];
                    if (ctx->pb.any)
                        memcpy(&s->image[3 * i], &ctx->img0[3 * i], 3 * sizeof *ctx->img0);
                }
                if (tid == 0) {
                    nbep__sim_abandon(sim);
                    if (overflow) {
                        nbep_diag_add(sim->diag, __FILE__, __LINE__,
                                      "nbep: no memory for the contacts of step %llu; the run "
                                      "ends after step %llu",
                                      (unsigned long long)step, (unsigned long long)(step - 1));
                        sim->status = NBEP_ENOMEM;
                    }
                }
                break;
            }
            nbep_thread_max *mx = &sim->tmax[par][tid];
            mx->overlap = fmax(mx->overlap, deep.overlap);
            mx->overlap_rel = fmax(mx->overlap_rel, deep.overlap_rel);
            sim->counters[par][tid].c[NBEP_COUNTER_CHECKS] += checks;
            if (tid == 0)
                respond_all(ctx, s, sim->scene->restitution, nt, &sim->counters[par][0],
                            &sim->tmax[par][0]);
            nbep_barrier_wait(&ctx->bar);
            nbep__sim_block_energy(sim, own);
            nbep_barrier_wait(&ctx->bar);
            if (tid == 0)
                nbep__sim_end_step(sim, step);
            nbep_barrier_wait(&ctx->bar);
            /* relaxed: the barrier above ordered thread 0's store before this load */
            if (atomic_load_explicit(&sim->stop, memory_order_relaxed))
                break;
        }
        nbep_barrier_wait(&ctx->bar);
    }
}

static void detect_threads_use(const nbep_scene *sc, int nt, char *buf, size_t len)
{
    (void)sc;
    snprintf(buf, len, "all %d find each step's contacts; thread 0 responds to them in order", nt);
}

/* Their whole state is positions and velocities: a resumed run needs nothing else. */
const nbep_algo nbep__algo_naive = {.name = "naive",
                                    .exact_overlap = true,
                                    .create = naive_create,
                                    .run = detect_run,
                                    .destroy = detect_destroy,
                                    .bytes = naive_bytes,
                                    .threads_use = detect_threads_use};
const nbep_algo nbep__algo_seminaive = {.name = "seminaive",
                                        .exact_overlap = true,
                                        .create = seminaive_create,
                                        .run = detect_run,
                                        .destroy = detect_destroy,
                                        .bytes = seminaive_bytes,
                                        .threads_use = detect_threads_use};
