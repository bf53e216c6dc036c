/* A sphere's earliest event (paper Procedure 9): with its partners, each pair compared at the
 * later of the two spheres' local times, and with the planes. The all-pairs and grid modes call
 * it for every re-prediction; cells mode for its planes, and for its lists when something
 * accelerates (pred_cells.c has its own loop for a scene in free flight). Most pairs are
 * settled by a bound, without a root (pair_earliest, keep_pairs). */
#include "pred_impl.h"

#include <float.h>

/* The relative motion of spheres i (flying with ai) and j, each at its own local time, both
 * brought to the later of the two (t0): dp, dv, da and their contact distance. j is taken at
 * its position plus shift (its copy across periodic faces; zero otherwise). */
typedef struct pair_rel {
    nbep_vec3 dp, dv, da;
    double t0, sigma;
} pair_rel;

static pair_rel pair_relative(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 ai,
                              size_t j, nbep_vec3 shift)
{
    const double ti = c->tau[i], tj = c->tau[j];
    const double t0 = ti > tj ? ti : tj;
    nbep_vec3 pi = s->pos[i], vi = s->vel[i], pj = s->pos[j], vj = s->vel[j];
    if (c->pb.any)
        pj = nbep_vec3_add(pj, shift);
    const nbep_vec3 aj = effective_acc(c, s, j);
    if (ti < t0)
        nbep_physics_drift(&pi, &vi, ai, t0 - ti);
    if (tj < t0)
        nbep_physics_drift(&pj, &vj, aj, t0 - tj);
    return (pair_rel){nbep_vec3_sub(pj, pi), nbep_vec3_sub(vj, vi), nbep_vec3_sub(aj, ai), t0,
                      s->radius[i] + s->radius[j]};
}

/* The earliest the pair r can touch, from the step's start T0 (nbep_predict_pair_bound, or
 * nbep_predict_pair_quadratic_bound for a pair with equal accelerations, whose motion relative
 * to each other is straight): NBEP_NEVER where it never can. Rounding is monotone, so the time
 * of the root, no earlier than the bound, is no earlier than this either. Until 2026-11-27 a
 * pair with equal accelerations took no bound (its root, a quadratic's, was thought to cost
 * about what a bound would); the quadratic bound, without a square root or a branch, lets
 * keep_pairs skip the roots of receding and passing pairs and of those the best so far rules
 * out: paired runs, the same bits, 0.81 to 0.88 of the time for the paper's box in grid mode,
 * 0.93 for a 300-sphere pour, 0.96 for the 400-sphere hopper, about 0.9 for the 2000-sphere
 * pile at 1.6 s, all in cells mode but the box. */
static double pair_earliest(const pair_rel *r, double T0)
{
    if (r->da.x == 0.0 && r->da.y == 0.0 && r->da.z == 0.0) {
        const double lb = nbep_predict_pair_quadratic_bound(r->dp, r->dv, r->sigma);
        return lb == NBEP_NEVER ? NBEP_NEVER : T0 + (r->t0 + lb);
    }
    const double lb = nbep_predict_pair_bound(r->dp, r->dv, r->da, r->sigma);
    return lb == NBEP_NEVER ? NBEP_NEVER : T0 + (r->t0 + lb);
}

/* Whether a pair that can touch no earlier than `earliest` may still come before *best (ties
 * may: the partner decides them). */
static bool may_beat(const nbep_event *best, double earliest)
{
    return earliest < NBEP_NEVER && (best->kind == NBEP_EVENT_NONE || !(earliest > best->time));
}

/* How far from T0 + t0 a pair's contact may come and still beat *best or tie with it (for
 * nbep_predict_pair_within): T0 + (t0 + dt) can round to best's time or below only while dt
 * is below best - T0 - t0 plus the roundings of those sums, each under an ulp of the largest
 * of |best|, |T0|, |t0| and |dt| (dt is near best - T0 - t0 there); 16 ulps of their sum is
 * far more. No best: no limit. */
static double beat_cap(const nbep_event *best, double T0, double t0)
{
    if (best->kind == NBEP_EVENT_NONE || !(best->time < NBEP_NEVER))
        return INFINITY;
    const double d = best->time - T0 - t0;
    return d + 16.0 * DBL_EPSILON * (fabs(best->time) + fabs(T0) + fabs(t0));
}

/* The contact of spheres i (flying with ai) and j (pair_relative), stamped with both response
 * counts: the paper's all-pairs loop, which solves every pair (its pairs share one
 * acceleration in the paper's box, and a bound per pair slowed its step by a quarter). */
static nbep_event pair_event(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 ai,
                             size_t j, nbep_vec3 shift, double T0, thread_ws *w)
{
    const pair_rel r = pair_relative(c, s, i, ai, j, shift);
    const double dt = nbep_predict_pair(r.dp, r.dv, r.da, r.sigma, w->pws);
    return (nbep_event){T0 + (r.t0 + dt), (uint32_t)j, NBEP_EVENT_SPHERE, c->ver[i], c->ver[j]};
}

/* keep_earlier of the contact of spheres i and j, moving relative to each other as r says
 * (pair_relative), stamped with both response counts; not solved where it can touch no
 * earlier than `earliest` (pair_earliest) and that cannot come before *best: *best ends the
 * same, bit for bit. */
static void keep_rel(nbep_event *best, const pred_ctx *c, size_t i, size_t j, const pair_rel *r,
                     double earliest, double T0, thread_ws *w)
{
    if (!may_beat(best, earliest))
        return;
    const double dt =
        nbep_predict_pair_within(r->dp, r->dv, r->da, r->sigma, beat_cap(best, T0, r->t0), w->pws);
    keep_earlier(best, (nbep_event){T0 + (r->t0 + dt), (uint32_t)j, NBEP_EVENT_SPHERE, c->ver[i],
                                    c->ver[j]});
}

/* Partners whose relative motions keep_pairs holds at once (a list of a fluid or a pile has
 * about 10 to 40; a grid block as many or more, taken 32 at a time). */
#define PAIRS_BATCH 32

/* keep_rel of sphere i (flying with ai) and each of js[0..m) (pair_relative, pair_earliest), j
 * at its nearest image when images: *best ends the same, bit for bit, as solving every pair in
 * list order would leave it. In each
 * batch of partners the pair that can touch first is solved first, so that its root (a
 * quartic where the two accelerate differently: a settling pile, where this was most of the
 * run) lets most of the others go unsolved; keep_earlier's winner is the same in any order
 * (cells_pairs_free). */
void nbep__pred_keep_pairs(nbep_event *best, const pred_ctx *c, const nbep_state *s, uint32_t i,
                           nbep_vec3 ai, const uint32_t *js, size_t m, bool images, double T0,
                           thread_ws *w)
{
    pair_rel rel[PAIRS_BATCH];
    double earliest[PAIRS_BATCH];
    for (size_t k0 = 0; k0 < m; k0 += PAIRS_BATCH) {
        const size_t n = m - k0 < PAIRS_BATCH ? m - k0 : PAIRS_BATCH;
        size_t first = 0;
        for (size_t q = 0; q < n; q++) {
            const uint32_t j = js[k0 + q];
            rel[q] = pair_relative(c, s, i, ai, j, images ? neighbour_shift(c, s, i, j) : ZERO3);
            earliest[q] = pair_earliest(&rel[q], T0);
            first = earliest[q] < earliest[first] ? q : first;
        }
        for (size_t q = 0; q < n; q++) { /* first, then the others in list order */
            const size_t k = q == 0 ? first : q == first ? 0 : q;
            keep_rel(best, c, i, js[k0 + k], &rel[k], earliest[k], T0, w);
        }
    }
}

/* keep_earlier of the earliest contact of i with j at the images `nearest` + -1, 0 or +1 period
 * along each periodic axis (one along the others), in a fixed order: 27 predictions, counted
 * beyond the pair's one. */
static void wide_images(nbep_event *best, const pred_ctx *c, const nbep_state *s, size_t i,
                        nbep_vec3 ai, size_t j, const int nearest[3], double T0, thread_ws *w,
                        nbep_counters *cnt)
{
    int d[3]; /* -1 .. d along a periodic axis, 0 along another */
    for (int k = 0; k < 3; k++)
        d[k] = c->pb.axis[k] ? 1 : 0;
    uint64_t made = 0;
    for (int ox = -d[0]; ox <= d[0]; ox++)
        for (int oy = -d[1]; oy <= d[1]; oy++)
            for (int oz = -d[2]; oz <= d[2]; oz++) {
                const int cells[3] = {nearest[0] + ox, nearest[1] + oy, nearest[2] + oz};
                keep_earlier(best, pair_event(c, s, i, ai, j, nbep_periodic_shift(&c->pb, cells),
                                              T0, w));
                made++;
            }
    cnt->c[NBEP_COUNTER_PREDICTIONS] += made - 1;
}

/* All-pairs mode in a periodic box: when sphere i (at its local time) will have strayed
 * its reach (pred_impl.h) from here along a periodic axis (kind HORIZON, partner n_planes so that it ranks
 * after the planes); NBEP_NEVER when it does not move. */
static nbep_event image_horizon(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 ai,
                                double T0)
{
    /* r_i and the largest radius of the others (pred_impl.h) */
    const double sigma_i = s->radius[i] + (i == c->big ? c->rmax_other : c->rmax);
    const double D = c->image_wide ? nbep_periodic_reach_wide(&c->pb, sigma_i)
                                   : nbep_periodic_reach(&c->pb, sigma_i);
    const double v[3] = {s->vel[i].x, s->vel[i].y, s->vel[i].z}, a[3] = {ai.x, ai.y, ai.z};
    double t = NBEP_NEVER;
    for (int k = 0; k < 3; k++)
        if (c->pb.axis[k])
            t = fmin(t, fmin(nbep_predict_plane(D, v[k], a[k]),
                             nbep_predict_plane(D, -v[k], -a[k])));
    return (nbep_event){T0 + (c->tau[i] + t), (uint32_t)s->n_planes, NBEP_EVENT_HORIZON,
                        c->ver[i], 0};
}

/* Paper Procedure 9, one thread's share: the earliest event of sphere i with the spheres
 * [lo, hi) (each at its own local time; a pair is compared at the later of the two) and, when
 * with_planes, with every plane. T0 is the step's start time. Returns kind NONE if none. */
nbep_event nbep__pred_predict_some(const pred_ctx *c, const nbep_state *s, size_t i, size_t lo,
                                   size_t hi, bool with_planes, double T0, thread_ws *w,
                                   nbep_counters *cnt)
{
    nbep_event best = {.time = NBEP_NEVER, .kind = NBEP_EVENT_NONE};
    const double ti = c->tau[i];
    const nbep_vec3 ai = effective_acc(c, s, i);
    if (with_planes) {
        const double speed = nbep_vec3_norm(s->vel[i]);
        for (size_t p = 0; p < s->n_planes; p++) {
            if (c->rest && rest_has_plane(&c->rest[i], p))
                continue;
            nbep_vec3 n = s->plane_normal[p];
            double gap = nbep_physics_plane_gap(n, s->plane_offset[p], s->pos[i], s->radius[i]);
            double dt = nbep_predict_plane_contact(gap, nbep_vec3_dot(n, s->vel[i]),
                                                   nbep_vec3_dot(n, ai), speed);
            keep_earlier(&best, (nbep_event){T0 + (ti + dt), (uint32_t)p, NBEP_EVENT_PLANE,
                                             c->ver[i], 0});
        }
        cnt->c[NBEP_COUNTER_PREDICTIONS] += s->n_planes;
        if (c->image_horizon)
            keep_earlier(&best, image_horizon(c, s, i, ai, T0));
    }
    for (size_t j = lo; j < hi; j++) {
        if (j == i)
            continue;
        nbep_vec3 shift = ZERO3;
        if (c->pb.any) { /* all-pairs in a periodic box: j's nearest image */
            int cells[3];
            nbep_periodic_nearest(&c->pb, nbep_vec3_sub(s->pos[j], s->pos[i]), cells);
            if (c->image_wide) { /* and the 26 around it (pred_impl.h) */
                wide_images(&best, c, s, i, ai, j, cells, T0, w, cnt);
                continue;
            }
            shift = nbep_periodic_shift(&c->pb, cells);
        }
        keep_earlier(&best, pair_event(c, s, i, ai, j, shift, T0, w));
    }
    cnt->c[NBEP_COUNTER_PREDICTIONS] += hi - lo - (i >= lo && i < hi);
    return best;
}

/* Grid mode (beyond the paper): the earliest event of sphere i before the horizon, testing
 * every plane but only the spheres that can reach i by then; "horizon" when there is none.
 * A partner j sat in its cell at the step's start and has moved at most V t + amax t^2 / 2
 * since (V: the fastest sphere at the step's start or after any reaction so far this step), and
 * i moves at most |v_i| H + |a_i| H^2 / 2 before the horizon, so partners farther than the sum
 * of those and the radii cannot touch i before it. A partner whose course changes later is
 * re-predicted itself and finds i then, as in the paper's argument for one-sided inserts. */
nbep_event nbep__pred_predict_grid(const pred_ctx *c, const nbep_state *s, size_t i, double T0,
                                   double V, thread_ws *w, nbep_counters *cnt)
{
    nbep_event best = nbep__pred_predict_some(c, s, i, 0, 0, true, T0, w, cnt); /* the planes */
    /* beyond the horizon nothing is known (a partner from farther away may come first): the
     * horizon stands for anything later before the pairs are tried, so that a pair that
     * cannot touch by then goes unsolved (most of a settling pile's quartics). A pair
     * touching at the horizon itself still comes first, as it did when the horizon replaced
     * a later best at the end: at one time a sphere event ranks before a horizon. */
    if (best.kind == NBEP_EVENT_NONE || !(best.time <= c->horizon))
        best = (nbep_event){c->horizon, 0, NBEP_EVENT_HORIZON, c->ver[i], 0};
    const double H = c->horizon - T0;
    const nbep_vec3 ai = effective_acc(c, s, i);
    double reach = s->radius[i] + c->rmax + nbep_vec3_norm(s->vel[i]) * H +
                   0.5 * nbep_vec3_norm(ai) * H * H + V * H + 0.5 * c->amax * H * H;
    size_t lo[3], hi[3];
    uint64_t tested = 0;
    uint32_t js[PAIRS_BATCH]; /* the partners, a batch at a time (keep_pairs) */
    size_t m = 0;
    nbep_grid_block(&c->grid, s->pos[i], reach, lo, hi);
    for (size_t z = lo[2]; z <= hi[2]; z++)
        for (size_t y = lo[1]; y <= hi[1]; y++)
            for (size_t x = lo[0]; x <= hi[0]; x++) {
                size_t cell = nbep_grid_index(&c->grid, x, y, z);
                for (size_t k = c->grid.start[cell]; k < c->grid.start[cell + 1]; k++) {
                    const uint32_t j = c->grid.item[k];
                    if (j == i)
                        continue;
                    js[m++] = j;
                    if (m == PAIRS_BATCH) {
                        nbep__pred_keep_pairs(&best, c, s, (uint32_t)i, ai, js, m, false, T0, w);
                        tested += m;
                        m = 0;
                    }
                }
            }
    nbep__pred_keep_pairs(&best, c, s, (uint32_t)i, ai, js, m, false, T0, w);
    tested += m;
    cnt->c[NBEP_COUNTER_PREDICTIONS] += tested;
    return best;
}
