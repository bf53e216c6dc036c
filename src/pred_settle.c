/* Settling (issue 9; SETTLE_STEPS and SETTLE_SPEED_FACTOR are in pred_impl.h).
 *
 * try_hold and land_on_held (pred_react.c) hold a sphere on what it touches at one meeting,
 * which must already be held: a pile whose spheres carry each other (one on two
 * neighbours that lean on it in turn) never freezes that way, and jitters near the rest speed
 * for ever, at a cost that rises as it cools (a 300-sphere pour: 150 to 260 collisions per
 * sphere per step after 0.9 s, rising). Speed over time shows what one meeting cannot: a sphere
 * whose speed stayed at or below its settle speed v_s = SETTLE_SPEED_FACTOR x its rest speed
 * for SETTLE_STEPS whole steps changed velocity by at most 2 v_s over that window, so the mean
 * net force on it was at most 2 v_s / (SETTLE_STEPS dt) / |a| of its weight: with t_min <=
 * 0.1 dt (min_bounce_time), at most 2 x 2 x 0.1 / 10 = 4 %, at any dt. Its contacts carry
 * it. It is held where it is (settle_phases), on the planes and the spheres below it (against
 * its acceleration) that it touches within v_s^2 / |a| (twice its highest hop at that speed)
 * and that are held already or settle in the same step (candidates whose own supports do not
 * settle do not: settle_recheck); then it wakes as any held sphere does (an
 * impact faster than the rest speed, or a support that reacts). The speed test is exact:
 * between events |v + a t| is convex in t, so a step's highest speed is at an event (advance_to
 * before a reaction, fire after it) or at its ends (the update). Only dissipative scenes
 * (e < 1) with accelerations settle: an elastic pile keeps its energy. Energy: at most
 * m v_s^2 / 2 per hold (1.9e-6 J for 1 kg under gravity at dt = 1e-3), the model's, besides
 * restitution. A resumed run continues its windows where they were (pred_contacts, the file's
 * /checkpoint/contacts). */
#include "pred_impl.h"

/* The update, own sphere i at the step's end: counts the step if its highest speed stayed at or
 * below the settle speed, starts the next step's peak from here, and takes the snapshot that
 * settle_gather reads. Returns whether i is a candidate to settle. */
bool nbep__pred_settle_count(pred_ctx *c, const nbep_state *s, size_t i, double dt)
{
    settle_rec *x = &c->settle[i];
    const double v2 = nbep_vec3_norm2(s->vel[i]), vs = settle_speed(s, i, dt);
    const bool slow = vs > 0.0 && fmax(x->peak2, v2) <= vs * vs;
    x->slow = slow ? (x->slow < SETTLE_STEPS ? x->slow + 1 : SETTLE_STEPS) : 0;
    x->peak2 = v2;
    x->still = c->rest[i].still;
    x->cand = !x->still && x->slow >= SETTLE_STEPS;
    return x->cand;
}

/* What settle_gather gathers for sphere i: its supports r, each scored by the cosine between its
 * normal and i's acceleration (planes -2: kept first; the most nearly below kept when more
 * than NBEP_CONTACT_MAX touch). */
typedef struct settle_gather_ws {
    const pred_ctx *c;
    const nbep_state *s;
    size_t i;
    nbep_vec3 a;      /* i's acceleration, unit */
    double tol;       /* largest gap that counts as touching */
    int par;          /* candidates count as supports: all (-1), or those live at this parity */
    bool more;        /* more touched than r holds */
    rest_set r;
    double score[NBEP_CONTACT_MAX];
} settle_gather_ws;

static void settle_add(settle_gather_ws *g, int32_t who, double score)
{
    int k = g->r.n;
    if (k == NBEP_CONTACT_MAX) { /* replace the least nearly below, if this one is more so */
        g->more = true;
        k = 0;
        for (int m = 1; m < g->r.n; m++)
            if (g->score[m] > g->score[k])
                k = m;
        if (!(score < g->score[k]))
            return;
    } else {
        g->r.n++;
    }
    g->r.who[k] = who;
    g->score[k] = score;
}

/* Sphere j is a support of i if it is held, or a candidate that may settle in this step (the
 * snapshot: every candidate, or those still live after the round before), touches i within
 * tol and lies against i's acceleration. */
static void settle_one(void *u, uint32_t j)
{
    settle_gather_ws *g = u;
    const settle_rec *y = &g->c->settle[j];
    if (j == g->i || !(y->still || (y->cand && (g->par < 0 || y->live[g->par]))))
        return;
    const nbep_vec3 d = sep(g->c, g->s, j, g->i);
    const double len = nbep_vec3_norm(d);
    if (!(len - (g->s->radius[j] + g->s->radius[g->i]) <= g->tol))
        return;
    const double cosine = nbep_vec3_dot(d, g->a) / len;
    if (cosine < 0.0)
        settle_add(g, -1 - (int32_t)j, cosine);
}

/* Own candidate i, at the step's end: gathers its supports (settle_one, and the planes it
 * touches below it) into its record (sup, more). par as settle_gather_ws's. Reads other
 * spheres' positions, radii and snapshots only, which nothing writes in these sub-phases.
 * Returns whether it has any. */
static bool settle_gather(pred_ctx *c, const nbep_state *s, size_t i, double dt, int par)
{
    const double amag = nbep_vec3_norm(s->acc[i]), vs = settle_speed(s, i, dt);
    settle_gather_ws g = {.c = c, .s = s, .i = i, .a = nbep_vec3_scale(s->acc[i], 1.0 / amag),
                          .tol = vs * vs / amag, .par = par};
    for (size_t p = 0; p < s->n_planes; p++)
        if (nbep_vec3_dot(s->plane_normal[p], g.a) < 0.0 &&
            nbep_physics_plane_gap(s->plane_normal[p], s->plane_offset[p], s->pos[i],
                                   s->radius[i]) <= g.tol)
            settle_add(&g, (int32_t)p, -2.0);
    if (c->ev) {
        nbep_evloop_visit_block(c->ev, (uint32_t)i, settle_one, &g);
    } else if (c->use_grid) { /* the grid of the step's end (grid_prepare) */
        size_t lo[3], hi[3];
        nbep_grid_block(&c->grid, s->pos[i], s->radius[i] + c->rmax + g.tol, lo, hi);
        for (size_t z = lo[2]; z <= hi[2]; z++)
            for (size_t y = lo[1]; y <= hi[1]; y++)
                for (size_t x = lo[0]; x <= hi[0]; x++) {
                    size_t cell = nbep_grid_index(&c->grid, x, y, z);
                    for (size_t k = c->grid.start[cell]; k < c->grid.start[cell + 1]; k++)
                        settle_one(&g, c->grid.item[k]);
                }
    } else {
        for (size_t j = 0; j < s->n; j++)
            settle_one(&g, (uint32_t)j);
    }
    settle_rec *x = &c->settle[i];
    x->more = g.more;
    x->n_sup = g.r.n;
    for (int k = 0; k < g.r.n; k++)
        x->sup[k] = g.r.who[k];
    return g.r.n > 0;
}

/* Own candidate i, live after the round before (parity prev): drops the candidates among its
 * supports that were not live then (they have lost theirs: no support under them settles).
 * Its supports are then those settle_gather would find among what is still live: the same
 * list less those, unless it had left some out (more), when it gathers again. Returns whether
 * any is left. */
static bool settle_recheck(pred_ctx *c, const nbep_state *s, size_t i, double dt, int prev)
{
    settle_rec *x = &c->settle[i];
    uint8_t n = 0;
    for (int k = 0; k < x->n_sup; k++) {
        const int32_t who = x->sup[k];
        if (who >= 0 || c->settle[-1 - who].still || c->settle[-1 - who].live[prev])
            x->sup[n++] = who;
    }
    if (n == x->n_sup)
        return n > 0;
    if (x->more)
        return settle_gather(c, s, i, dt, prev);
    x->n_sup = n;
    return n > 0;
}

/* Every thread at a step's end, after a barrier that follows the update (settle_count): holds
 * the candidates whose supports end up held. Sub-phases, so that no thread reads what another
 * writes: each candidate gathers its supports among the planes, the held spheres and the
 * candidates (settle_gather); then, round after round, candidates whose supports have all
 * lost theirs lose them too (settle_recheck: a sphere on one that rests on a sliding sphere
 * is no more held than that one), until a round loses none (each round reads the round
 * before's snapshot, live[]: the same rounds on every thread and for any thread count; a
 * candidate never comes back, so there are at most as many rounds as candidates, and one more
 * than the longest chain that loses its supports, in practice); then those left are held where
 * they are, their response counts move on (their slots and every prediction naming them are
 * stale) and their block energies are taken again; then each stamps its sphere supports'
 * counts. Every held sphere thus rests on planes and held spheres only: never on one that goes
 * on moving (before, the candidate's own support was enough, and a sphere on a sphere that
 * failed to settle hung in the air). Candidates that support each other in a ring (possible
 * only where accelerations differ) keep each other. Returns whether any sphere was held. */
bool nbep__pred_settle_phases(nbep_sim *sim, pred_ctx *c, nbep_range own, thread_ws *w)
{
    if (!c->settle)
        return false;
    size_t cands = 0;
    for (int t = 0; t < c->nt; t++)
        cands += c->ws[t].n_settle;
    if (cands == 0)
        return false;
    nbep_state *s = &sim->st;
    nbep_barrier_wait(&c->bar); /* grid mode: the grid is placed */
    w->n_live[0] = w->n_lost[0] = 0;
    for (size_t i = own.lo; i < own.hi; i++) {
        if (!c->settle[i].cand)
            continue;
        const bool on = settle_gather(c, s, i, sim->dt, -1);
        c->settle[i].live[0] = on;
        w->n_live[0] += on;
        w->n_lost[0] += !on;
    }
    int round = 0;
    for (;;) {
        nbep_barrier_wait(&c->bar);
        size_t live = 0, lost = 0;
        for (int t = 0; t < c->nt; t++) {
            live += c->ws[t].n_live[round & 1];
            lost += c->ws[t].n_lost[round & 1];
        }
        if (live == 0)
            return false;
        if (lost == 0)
            break;
        round++; /* written at its parity, read by all after the barrier */
        const int prev = (round - 1) & 1, cur = round & 1;
        w->n_live[cur] = w->n_lost[cur] = 0;
        for (size_t i = own.lo; i < own.hi; i++) {
            settle_rec *x = &c->settle[i];
            if (!x->cand)
                continue;
            const bool on = x->live[prev] && settle_recheck(c, s, i, sim->dt, prev);
            x->live[cur] = on;
            w->n_live[cur] += on;
            w->n_lost[cur] += x->live[prev] && !on;
        }
    }
    w->n_settled = 0;
    for (size_t i = own.lo; i < own.hi; i++) {
        settle_rec *x = &c->settle[i];
        if (!x->cand || !x->live[round & 1])
            continue;
        rest_set *r = &c->rest[i];
        *r = (rest_set){.n = x->n_sup, .still = true};
        for (int k = 0; k < x->n_sup; k++)
            r->who[k] = x->sup[k];
        s->vel[i] = ZERO3;
        c->aeff[i] = ZERO3;
        x->held_now = true;
        c->ver[i]++;
        w->n_settled++;
    }
    if (w->n_settled > 0)
        nbep__sim_block_energy(sim, own);
    nbep_barrier_wait(&c->bar);
    for (size_t i = own.lo; w->n_settled > 0 && i < own.hi; i++) {
        if (!c->settle[i].held_now)
            continue;
        rest_set *r = &c->rest[i];
        for (int k = 0; k < r->n; k++)
            r->ver[k] = r->who[k] < 0 ? c->ver[-1 - r->who[k]] : 0;
        c->settle[i].held_now = false;
    }
    /* every thread's supports recorded before any reads them: thread 0 writes the step's
     * frame next, whose lasting state (pred_contacts) reads every sphere's (until 2026-12-02
     * it could read one another thread had not yet written: on 2 threads a settled pile's
     * checkpoint said a support had changed where 1 thread's said not, and a run extended
     * from its file went another way; a new user's find) */
    nbep_barrier_wait(&c->bar);
    return true;
}
