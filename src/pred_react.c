/* A reaction (paper Procedure 8, and beyond it): the response to a sphere or plane contact,
 * and the lasting contacts a reaction makes or ends when something accelerates: resting on
 * planes, spheres held still on what carries them, cages, jams, the minimum bounce and the TC
 * model. Every mode reacts here (the rounds' react_phase, cells mode's cells_react). */
#include "pred_impl.h"

#include <assert.h>
#include <float.h>
#include <string.h>

/* Looks at jam_hold: the contacts it found to hold a sphere on (n), and those of each sphere
 * it held; tests/test_hold_contacts.c compiles its own copy of this file that counts the
 * first and checks the second; a build of nbep has nothing here. */
#ifndef NBEP_PRED_JAM_HOLD_HOOK
#define NBEP_PRED_JAM_HOLD_HOOK(n) ((void)(n))
#endif
#ifndef NBEP_PRED_HELD_HOOK
#define NBEP_PRED_HELD_HOOK(n) ((void)(n))
#endif
/* And at each of try_hold's holds (sphere i): the same test counts them and asks that each
 * held sphere be supported. */
#ifndef NBEP_PRED_TRY_HOLD_HOOK
#define NBEP_PRED_TRY_HOLD_HOOK(c, i) ((void)(c), (void)(i))
#endif

/* A bounce whose flight would last less than this fraction of a step ends in resting contact:
 * with restitution e the remaining bounces take 2 v/|a| / (1 - e) in all, so below this the
 * sphere is indistinguishable from resting at the step's resolution, and the kinetic energy
 * removed, m (a t/2)^2 / 2 with t = 1e-9 dt, is far below round-off of the total. */
#define NBEP_REST_FRACTION 1e-9
/* At e = 1 (no TC model) a bounce off a plane whose top would be below this fraction of the
 * sphere's radius ends in resting contact too: such a hop is within the precision the
 * predictive algorithm keeps its contacts to (round-off overlaps, up to about 1e-9 r at the
 * scales README's accuracy tables cover), so it is a resting sphere's jitter, not a flight;
 * kept, a sphere placed 1e-14 above a floor (a deck generator's round-off) bounced 22 million
 * times in 2 s (a review's find, 2026-12-02). The energy removed is below m |a| 1e-9 r. */
#define NBEP_ELASTIC_REST_HEIGHT 1e-9
/* Lasting sphere-sphere contacts (issue 9). A sphere whose contacts (planes, and spheres that
 * are themselves held still) leave it no acceleration is "held still": velocity and effective
 * acceleration exactly zero, so it costs no events and can carry others in turn; a settled
 * pile is a network of held spheres on planes.
 *
 * The rest speed (rest_speed, pred_impl.h) sets what is slow enough to hold: |a| t_min, twice
 * the separating speed of the minimum bounce (MIN_BOUNCE_STEP_FRACTION; 9.8e-4 m/s under
 * gravity at dt = 1e-3). A pressed pair leaves every response at least that fast, so any
 * lasting contact the model does not hold jitters at that speed for ever; a hold threshold
 * below it (1e-3 |a| dt, before) is never met
 * in a crowd: a 300-sphere pour had no sphere held at all after 0.8 s, and every jittering
 * impact on a held sphere knocked it loose again. So a supported sphere slower than the rest
 * speed is held when a partner meets it; a sphere that meets a held one no faster than the
 * rest speed (along the line of centres, and in all) joins it if the contacts it then has
 * (its planes, that sphere, and the other held spheres it touches: a pocket, pocket_gather)
 * leave it no motion, else bounces off it as off a wall (the held sphere, carried by the pile,
 * takes no momentum); a faster impact is an ordinary response and wakes what the held sphere
 * carried, unless the pile carries it (carried, below). Of a sphere held on planes alone,
 * both the hold and the slow landing need the pile to take its load (pile_takes, in react):
 * else the meeting is an ordinary response, which moves it however slowly; a sphere held on
 * spheres takes every push as its pile would. The kinetic energy removed by
 * holding, at most m (rest speed)^2 / 2 per hold (4.8e-7 J for 1 kg under gravity at
 * dt = 1e-3), is the model's, besides restitution. A held
 * sphere is let go (time-ordered, at the instant its support changed) as soon as any of its
 * supports reacts. */
/* Jams (run.max_reactions). A sphere that reacts more than run.max_reactions times within one
 * step is jammed: pressed between walls and neighbours that the contact model cannot hold
 * still (README, granular: a wedge), it would collide ever faster while time crawls on (1e-9 s
 * per event is typical), so the step never ends and the job's SIGTERM, read between steps, is
 * never seen. The run stops as a numerical failure instead, its frames intact. A real scene
 * stays far below the default of 1e6: a sphere collides about once per mean free time, so that
 * would be a step of a million mean free times (a fast sphere bouncing between walls close
 * together: thousands; the busiest sphere of the hopper and pile decks: 200 to 2000).
 * Counting costs 8 bytes a sphere (jam_count), not spent on elastic free flight, which cannot
 * jam. The limit is kept below UINT32_MAX, so a count never wraps before it trips. */
/* A sphere that has reacted this many times in one step is held where it is when it next
 * meets a held sphere slowly (along the line of centres no faster than the rest speed:
 * land_on_held; jam_hold) or faster (react), or any sphere while its planes carry it (react: a
 * row of spheres that fits a box exactly, a Newton's cradle without gaps; under gravity tilted
 * along the row its planes do not carry it, the next sphere does, and the row is held from the
 * sphere at its end, which its planes carry, each sphere on the one held before). Bounced
 * between a held sphere and a face across from it (a slot a diameter wide between a wall and a
 * held sphere a hair lower than it, so that its weight
 * presses it on that sphere's curve as it slides along the slot), a sphere re-meets the held
 * one 1e-10 to 1e-12 s after each minimum bounce (the cage takes the bounce back), a million
 * times before the step ends (a 300-sphere pour, seed 1, steps 892 and 898, sliding at 1.3
 * and 3.9 mm/s). The model holds spheres still on sphere supports but has no sliding contact
 * with one, and no geometry rule covers every such wedge; ten thousand reactions in a step is
 * far above any motion it resolves (the busiest sphere of the hopper and pile decks reacts 200
 * to 2000 times in a step). Energy: the sphere's kinetic energy at the hold, the model's,
 * besides restitution (1/2 m (3.9 mm/s)^2 = 7.6e-6 J per kg in the case measured). */
#define JAM_HOLD ((uint32_t)NBEP_JAM_HOLD) /* nbep/scene.h: --help-deck names it */
/* Impacts the pile carries (carried). A free sphere k meeting held sphere j faster than the rest
 * speed woke j (an ordinary response), and through let_go everything j carried. In a pile
 * whose upper layers still move at millimetres to centimetres a second, every such touch woke
 * part of it: the 2000-sphere deck run on from 2.5 s (median speed 1.6 mm/s, 99th percentile
 * 2 cm/s) held 801 spheres at 2.9 s and 259 at 3.1 s, each cascade letting spheres fall and
 * slide into the next, and did not settle. So held j stays put when k's push on it (along
 * the line of centres, from k to j) points into the cone of the faces that hold it -- its own
 * contacts, and the other held spheres and the planes it touches to within settle_gather's reach,
 * all immobile, as for a sphere that lands on j (land_on_held) -- and k closes no faster than
 * the speed of a fall from physics.carry_drop of j's radius, sqrt(2 |a| carry_drop r): 7.7 cm/s
 * for the pile deck's 3 cm spheres under g at the default, NBEP_CARRY_DROP = 0.01. That is
 * above the agitation of a settling pile (the deck's fastest sphere at 2.5 s: 5 cm/s) and far
 * below what a pour brings (a sphere falling one diameter onto it: 1.1 m/s). k then bounces
 * off j as off a wall (land_on_held: restitution, and the TC model); the momentum, at most
 * m (1 + e) times that speed, goes to the pile, as to a plane, and no energy does (j does not
 * move). A push j's faces cannot take (from the side of a sphere alone on a floor, from below)
 * or a faster one is an ordinary response, which wakes j. carry_drop = 0 turns the rule off. */
/* A cage's second face comes at zero time: the sphere has not moved off the first one. One
 * that has moved off it along its normal by more than this fraction of its radius had room to
 * bounce (a channel a little wider than the sphere): no cage. */
#define CAGE_TOUCH_REL 1e-9
/* A sphere whose contacts carry its whole weight (it may still slide): a slow partner treats it
 * as part of the support. */
static bool supported(const pred_ctx *c, size_t i)
{
    return c->rest && c->rest[i].n > 0 && is_zero(c->aeff[i]);
}

/* Whether sphere i rests on another sphere (a held sphere's contacts name one). */
static bool rests_on_spheres(const pred_ctx *c, size_t i)
{
    for (int q = 0; q < c->rest[i].n; q++)
        if (c->rest[i].who[q] < 0)
            return true;
    return false;
}

/* Unit normals of the contacts of r, from support to sphere i. */
static void rest_normals(const pred_ctx *c, const nbep_state *s, size_t i, const rest_set *r,
                         nbep_vec3 *n)
{
    for (int k = 0; k < r->n; k++) {
        if (r->who[k] >= 0) {
            n[k] = s->plane_normal[r->who[k]];
        } else {
            nbep_vec3 d = sep(c, s, (size_t)(-1 - r->who[k]), i);
            double len = nbep_vec3_norm(d);
            n[k] = nbep_vec3_make(d.x / len, d.y / len, d.z / len);
        }
    }
}

/* Sphere contacts hold a sphere still when they leave it at most this fraction of its
 * acceleration. A sphere contact is taken on within a gap (the pocket and settling
 * tolerances: at most 8 MIN_BOUNCE_REL_HEIGHT of the radius, twice the highest hop of a
 * minimum bounce), so its normal is known to about 4 MIN_BOUNCE_REL_HEIGHT radians only; what
 * is left below that is a slope the geometry does not resolve (measured: a sphere in the
 * groove between two held floor spheres, another held one above it, a wall at its end; the
 * groove tilted 3e-7 by where the spheres had settled, and the sphere, not held, bounced a
 * million times in one step between the groove and the sphere above, a 300-sphere pour, seed
 * 3, step 1429). Planes are exact: on planes alone the tolerance is NBEP_CONTACT_TOL. */
#define HOLD_SLOPE MIN_BOUNCE_REL_HEIGHT

/* Solves the contacts r of sphere i with velocity *v: keeps the contacts that carry load,
 * writes the acceleration left (*a) and, when tangent, removes v's components along them;
 * where they take the whole acceleration and `hold`, a speed below the rest speed is stopped.
 * A sphere contact is only valid while the sphere is held still (a tangent plane would let
 * it float off a curved support); if the result is not still, sphere contacts are dropped
 * and the planes solved alone. Returns the still flag. */
bool nbep__pred_rest_solve(const pred_ctx *c, const nbep_state *s, size_t i, rest_set *r,
                           nbep_vec3 *v, nbep_vec3 *a, double dt, bool tangent, bool hold)
{
    nbep_vec3 n[NBEP_CONTACT_MAX];
    for (int pass = 0; pass < 2; pass++) {
        rest_normals(c, s, i, r, n);
        unsigned act;
        *a = nbep_contact_project(s->acc[i], n, r->n, &act);
        if (tangent)
            *v = nbep_contact_tangent(*v, n, r->n, act);
        rest_set k = {.n = 0};
        bool spheres = false;
        for (int j = 0; j < r->n; j++)
            if (act >> j & 1u) {
                k.who[k.n] = r->who[j];
                k.ver[k.n++] = r->ver[j];
                spheres |= r->who[j] < 0;
            }
        *r = k;
        double amag = nbep_vec3_norm(s->acc[i]);
        if (r->n > 0 && nbep_vec3_norm(*a) <= (spheres ? HOLD_SLOPE : NBEP_CONTACT_TOL) * amag) {
            *a = nbep_vec3_make(0.0, 0.0, 0.0);
            if (hold && nbep_vec3_norm(*v) <= rest_speed(s, i, amag, dt))
                *v = nbep_vec3_make(0.0, 0.0, 0.0);
        }
        r->still = r->n > 0 && is_zero(*a) && is_zero(*v);
        if (r->still || !spheres)
            return r->still;
        k.n = 0; /* sphere contacts without being held: planes only */
        for (int j = 0; j < r->n; j++)
            if (r->who[j] >= 0)
                k.who[k.n++] = r->who[j];
        *r = k;
    }
    return r->still;
}

/* What a struck sphere's planes take of a unit impulse along u (plane_mobility): plane[j]
 * pushes it by mu[j] along its normal, for each of k planes. */
typedef struct {
    int k;
    uint32_t plane[NBEP_CONTACT_MAX];
    double mu[NBEP_CONTACT_MAX];
} plane_share;

/* What sphere i's plane contacts leave of a unit impulse direction u (frictionless: they push,
 * never pull; contact.h): u itself when it has none. Sphere contacts do not count: a response
 * lets go of them. *leans is set when i has a plane contact; *sh gets what each plane takes. */
static nbep_vec3 plane_mobility(const pred_ctx *c, const nbep_state *s, size_t i, nbep_vec3 u,
                                bool *leans, plane_share *sh)
{
    sh->k = 0;
    if (!c->rest)
        return u;
    const rest_set *r = &c->rest[i];
    nbep_vec3 n[NBEP_CONTACT_MAX];
    for (int j = 0; j < r->n; j++)
        if (r->who[j] >= 0) {
            sh->plane[sh->k] = (uint32_t)r->who[j];
            n[sh->k++] = s->plane_normal[r->who[j]];
        }
    unsigned act;
    *leans |= sh->k > 0;
    if (sh->k == 0)
        return u;
    /* where the planes take u whole, the projection leaves round-off (a few 1e-17 of the unit
     * u): nothing. Two spheres that lean each on a plane across from the other (a jammed body's
     * sphere on the wall at its far end, and the sphere at that end on the wall there) would
     * otherwise share an impulse divided by that round-off squared: they flew off at 1.5e5 m/s */
    const nbep_vec3 d = nbep_contact_project_push(u, n, sh->k, &act, sh->mu);
    return nbep_vec3_norm(d) <= NBEP_CONTACT_TOL ? ZERO3 : d;
}

/* SPEC /stats/wall_impulse: an impulse J along a struck sphere's u is momentum its planes
 * take, J mu on each (counted outward, as a bounce's). Until 2026-12-03 it was dropped: a
 * sphere on the floor struck from above by one falling at 1.4 m/s put 2.7 N s into the floor
 * in naive and nothing in predictive (a helper's review). */
static void planes_take(nbep_thread_max *mx, const plane_share *sh, double J)
{
    for (int j = 0; j < sh->k; j++)
        if (sh->mu[j] > 0.0)
            nbep__pred_sum_add(mx, &mx->wall[sh->plane[j]], J * sh->mu[j]);
}

/* After a response, a sphere leaves every contact along whose normal it now moves (and its
 * sphere contacts if it moves at all); the rest are solved again. A plane counts as left only
 * beyond round-off: a response along a tilted plane leaves v.n at a few ulps of |v|, and of
 * the speeds v had before, which a sphere that slows keeps across its planes. So the round-off
 * is reckoned against the larger of |v| and the speed of a fall through its own radius,
 * sqrt(2 |a| r), the scale of a settling sphere's speeds (as carry_drop's): 1e-12 of it covers
 * the round-off of speeds up to 1e4 times it, falls of 1e8 radii, and is a drift of 1e-12 r
 * in the time of that fall. Against |v| alone, a sphere that slowed to a stop in the edge of
 * two planes (sliding up it, gravity pulling it back) at 3e-6 m/s still had the 5e-16 m/s
 * left across each plane from when it was fast: it left each plane as it met the other, and
 * met them in turn at zero time, a million reactions in the step (an inverted square pyramid
 * of four planes, a new user's hopper: run.max_reactions stopped it, and a pour of 60 into
 * it, in every mode). |a| dt, the first mend, held at dt = 1e-3 but not at 3e-5 (a review). */
static void update_rest(pred_ctx *c, nbep_state *s, size_t i, double dt, bool hold)
{
    if (!c->rest)
        return;
    if (c->rest[i].n == 0) { /* a held sphere without contacts that a response moved is held
                              * no more (until 2026-12-04 it stayed held, moving, and two held
                              * neighbours woke and held each other at zero time for ever: a
                              * tilted mixture at dt = 0.05, grid mode, step 17). A guard since
                              * 2026-12-05: that sphere had been held on nothing by jam_hold,
                              * which holds only on contacts now, as rest_solve does */
        c->rest[i].still = c->rest[i].still && is_zero(s->vel[i]);
        return;
    }
    rest_set *r = &c->rest[i];
    nbep_vec3 n[NBEP_CONTACT_MAX];
    rest_normals(c, s, i, r, n);
    rest_set k = {.n = 0};
    for (int j = 0; j < r->n; j++)
        if (r->who[j] >= 0 ? fabs(nbep_vec3_dot(s->vel[i], n[j])) <=
                                 NBEP_CONTACT_TOL *
                                     fmax(nbep_vec3_norm(s->vel[i]),
                                          sqrt(2.0 * nbep_vec3_norm(s->acc[i]) * s->radius[i]))
                           : nbep_vec3_dot(s->vel[i], n[j]) == 0.0 && is_zero(s->vel[i])) {
            k.who[k.n] = r->who[j];
            k.ver[k.n++] = r->ver[j];
        }
    *r = k;
    nbep__pred_rest_solve(c, s, i, r, &s->vel[i], &c->aeff[i], dt, true, hold);
}

static void note_overlap(nbep_thread_max *mx, double ov, double r)
{
    if (ov > mx->overlap)
        mx->overlap = ov;
    if (ov / r > mx->overlap_rel)
        mx->overlap_rel = ov / r;
}

/* See MIN_BOUNCE_STEP_FRACTION: a pair pressed together by its accelerations leaves with at
 * least the separating speed that keeps it apart for t_min, given as an impulse along the line
 * of centres shared by mass like a response (momentum is kept), or, where either sphere leans
 * on planes (leans: d_lo and d_hi are their mobilities along -n and n, plane_mobility), along
 * those as respond_pair_along's impulse is: the planes take their part. Either way the kick
 * adds (want^2 - u^2) / (2 w) of energy, w the pair's inverse mass along n, at most
 * mu (a t_min)^2 / 8 (MIN_BOUNCE_STEP_FRACTION). Until 2026-12-01 a sphere whose planes carry
 * its weight took no share at all, the other the whole kick: that changed the energy by
 * m (v.n) du, of either sign and as large as the speed the pair slides with along n (a new
 * user's e = 0.5 pile of 60: a kick added 5e-5 J, 400 times the bound, and the pile's energy
 * rose by 3e-6 of itself in a step). The projection keeps what that rule was for: a sphere
 * sitting on a floor under one that leans on it straight from above takes nothing (its
 * mobility along the vertical is none), so no kick drives the bottom of a pile into its floor
 * (a settled pile heated up when it took a share along n). */
static void min_bounce(const pred_ctx *c, nbep_state *s, double dt, uint32_t lo, uint32_t hi,
                       bool leans, nbep_vec3 d_lo, nbep_vec3 d_hi, const plane_share *sh_lo,
                       const plane_share *sh_hi, nbep_thread_max *mx)
{
    if (!c->aeff)
        return; /* nothing accelerates: nothing presses a pair together */
    nbep_vec3 dp = sep(c, s, lo, hi);
    double dist = nbep_vec3_norm(dp);
    if (!(dist > 0.0))
        return;
    nbep_vec3 n = nbep_vec3_scale(dp, 1.0 / dist);
    double an = nbep_vec3_dot(nbep_vec3_sub(effective_acc(c, s, hi), effective_acc(c, s, lo)), n);
    if (!(an < 0.0))
        return; /* nothing presses them together: they part for good */
    double rmin = fmin(s->radius[lo], s->radius[hi]);
    double t_min = min_bounce_time(rmin, -an, dt);
    double want = -an * t_min / 2.0;
    double u = nbep_vec3_dot(nbep_vec3_sub(s->vel[hi], s->vel[lo]), n);
    if (u >= want)
        return;
    const double du = want - u;
    if (leans) {
        /* an impulse J along the mobilities parts the pair by J w along n (a mobility is n
         * projected onto a cone, whose dot with n is its square) */
        const double w = nbep_vec3_dot(d_lo, d_lo) / s->mass[lo] +
                         nbep_vec3_dot(d_hi, d_hi) / s->mass[hi];
        if (!(w > 0.0))
            return; /* the planes take the whole kick: they keep the pair apart */
        const double J = du / w;
        s->vel[lo] = nbep_vec3_axpy(s->vel[lo], J / s->mass[lo], d_lo);
        s->vel[hi] = nbep_vec3_axpy(s->vel[hi], J / s->mass[hi], d_hi);
        planes_take(mx, sh_lo, J);
        planes_take(mx, sh_hi, J);
        return;
    }
    const double m = s->mass[lo] + s->mass[hi];
    s->vel[lo] = nbep_vec3_axpy(s->vel[lo], -du * s->mass[hi] / m, n);
    s->vel[hi] = nbep_vec3_axpy(s->vel[hi], du * s->mass[lo] / m, n);
}

/* A sphere k without support pressed onto a held sphere j (n from j to k) leaves it with at
 * least the separating speed that keeps it off for t_min (see MIN_BOUNCE_STEP_FRACTION); j, held
 * by the pile, does not move. */
static void min_bounce_held(const pred_ctx *c, nbep_state *s, double dt, size_t k, size_t j,
                            nbep_vec3 n)
{
    double an = nbep_vec3_dot(c->aeff[k], n);
    if (!(an < 0.0))
        return;
    double rmin = fmin(s->radius[k], s->radius[j]);
    double t_min = min_bounce_time(rmin, -an, dt);
    double want = -an * t_min / 2.0, u = nbep_vec3_dot(s->vel[k], n);
    if (u < want)
        s->vel[k] = nbep_vec3_axpy(s->vel[k], want - u, n);
}

/* The TC model (Luding and McNamara 1998; DynamO's choice): a collision within tc of the last
 * one of either sphere is elastic (here planes count too: a sphere squeezed between a wall and
 * a neighbour collapses just the same; for a plane, a == b). Inelastic collapse needs ever faster
 * re-collisions; these stop dissipating, so the sequence ends. tc is physically the duration
 * of a real contact, during which a hard-sphere model has no business dissipating twice. */
static double tc_restitution(pred_ctx *c, double tc, double e, double t_abs, size_t a, size_t b)
{
    if (!c->t_last) /* e = 1 or tc = 0: the model never changes e */
        return e;
    bool recent = t_abs - c->t_last[a] < tc || t_abs - c->t_last[b] < tc;
    c->t_last[a] = t_abs;
    c->t_last[b] = t_abs;
    return recent ? 1.0 : e;
}

static void fire(pred_ctx *c, thread_ws *w, const nbep_state *s, size_t i, bool was_still)
{
    c->ver[i]++;
    settle_note(c, s, i);
    if (was_still && c->settle) /* woken: its window starts again (a sphere let go at rest is
                                 * slow for a while as it starts to fall) */
        c->settle[i].slow = 0;
    if (c->jam) { /* run.max_reactions; i is this thread's to change (it reacts or lets go) */
        jam_count *j = &c->jam[i];
        if (j->step != w->jam_step)
            *j = (jam_count){.step = w->jam_step, .n = 0};
        if (++j->n > c->jam_max && (w->jammed == 0 || i + 1 < w->jammed))
            w->jammed = (uint32_t)i + 1;
    }
    w->fired[w->n_fired++] = (uint32_t)i;
    if (c->use_grid) /* the grid's speed bound (grid_prepare) */
        w->vmax_react = fmax(w->vmax_react, nbep_vec3_norm(s->vel[i]));
    if (was_still)
        w->woken++;
}


/* Holds a supported sphere still when slower than the rest speed (see rest_speed). */
static bool try_hold(pred_ctx *c, nbep_state *s, size_t i, double dt)
{
    if (!c->hold_slow || !supported(c, i) ||
        !(nbep_vec3_norm(s->vel[i]) <= rest_speed(s, i, nbep_vec3_norm(s->acc[i]), dt)))
        return false;
    s->vel[i] = nbep_vec3_make(0.0, 0.0, 0.0);
    c->rest[i].still = true;
    NBEP_PRED_TRY_HOLD_HOOK(c, i);
    return true;
}

/* Sphere k meets an immobile face `who` (a plane, or a held sphere) whose normal towards it
 * is n. Caged: a face it met within tc (the TC model's time) before, and has not moved off
 * since (CAGE_TOUCH_REL), faces this one (n.n' < 0: a bounce off either heads into the other):
 * a gap exactly its diameter wide, a rigid cage, where the bounces between the faces take no
 * time, and the TC model, which makes them elastic, would keep them going for ever (a sphere
 * on the floor between a wall and a held sphere one diameter from it: a million reactions in
 * a step). The cage takes the speed against every face it still touches instead (CAGE_FACES:
 * a channel of three): k's velocity becomes the nearest that leaves them all
 * (nbep_contact_project; e = 0 against the cage), its speed along them stays. Energy: that
 * normal kinetic energy, which restitution would have taken as the bounces collapsed. The
 * faces' normals are kept from the meetings, so no other sphere's state is read (threads
 * react to other events meanwhile). Returns whether caged; records this meeting either way
 * (newest first; an older meeting with the same face is passed over). */
static bool caged(pred_ctx *c, nbep_state *s, size_t k, int32_t who, nbep_vec3 n, double t_abs,
                  double tc)
{
    if (!c->face)
        return false;
    face_met *f = &c->face[k * CAGE_FACES];
    nbep_vec3 nn[NBEP_CONTACT_MAX] = {n};
    int m = 1;
    bool opposed = false;
    for (int j = 0; j < CAGE_FACES; j++)
        if (f[j].who != who && t_abs - f[j].t <= tc &&
            nbep_vec3_dot(f[j].n, nbep_vec3_sub(s->pos[k], f[j].p)) <=
                CAGE_TOUCH_REL * s->radius[k]) {
            nn[m++] = f[j].n;
            opposed = opposed || nbep_vec3_dot(f[j].n, n) < 0.0;
        }
    for (int j = CAGE_FACES - 1; j > 0; j--)
        f[j] = f[j - 1];
    f[0] = (face_met){.t = t_abs, .n = n, .p = s->pos[k], .who = who};
    if (!opposed)
        return false;
    unsigned act;
    s->vel[k] = nbep_contact_project(s->vel[k], nn, m, &act);
    return true;
}

/* Whether held sphere m rests on sphere k. Such an m is no support for k to be held on: the
 * two would hold each other, and each one's landing (a reaction: the spheres resting on it
 * let go) would let the other go, which lands again at the same instant (grid mode's
 * 120-sphere pour at e = 0.9 went round such a pair 100000 times at one time and stopped,
 * "events do not resolve"). When k is free, m's entry for k is stale (k moved since m took
 * its load) and m's let-go is pending. */
static bool leans_on(const pred_ctx *c, size_t m, size_t k)
{
    return c->rest[m].still && rest_has_sphere(&c->rest[m], k);
}

/* The sphere contacts of r (free sphere k's) that rest on k themselves, taken out (leans_on).
 * Nothing to take out today: a sphere that is not held keeps planes only (rest_solve keeps
 * sphere contacts only when it holds, and every hold sets still), so this guards a change
 * that would let a free sphere keep a sphere contact (mutate.py: land-keeps-what-rests-on-it,
 * equivalent). */
static void drop_leaning(const pred_ctx *c, size_t k, rest_set *r)
{
    int n = 0;
    for (int q = 0; q < r->n; q++)
        if (r->who[q] >= 0 || !leans_on(c, (size_t)(-1 - r->who[q]), k)) {
            r->who[n] = r->who[q];
            r->ver[n++] = r->ver[q];
        }
    r->n = n;
}

/* A pocket (see land_on_held): the held spheres besides j that sphere k touches to within tol,
 * added to its contacts r (up to NBEP_CONTACT_MAX); for supports to hold k on (`holds`), not
 * those that rest on k (leans_on). */
typedef struct pocket {
    const pred_ctx *c;
    const nbep_state *s;
    size_t k, j;
    double tol;
    rest_set *r;
    bool holds;
} pocket;

static void pocket_one(void *u, uint32_t m)
{
    pocket *x = u;
    if (m == x->k || m == x->j || x->r->n >= NBEP_CONTACT_MAX || !x->c->rest[m].still ||
        rest_has_sphere(x->r, m) || (x->holds && leans_on(x->c, m, x->k)))
        return;
    double gap = nbep_vec3_norm(sep(x->c, x->s, m, x->k)) - (x->s->radius[m] + x->s->radius[x->k]);
    if (gap <= x->tol) {
        x->r->who[x->r->n] = -1 - (int32_t)m;
        x->r->ver[x->r->n++] = x->c->ver[m];
    }
}

/* Cells mode: k's neighbour list names every sphere that can touch it, and the loop is serial.
 * Rounds modes: every sphere, except those this round's events claim (other threads may be
 * changing them now; the claims were made before a barrier and stay until the next round). */
static void pocket_gather(const pred_ctx *c, const nbep_state *s, const thread_ws *w, size_t k,
                          size_t j, double tol, bool holds, rest_set *r)
{
    pocket x = {c, s, k, j, tol, r, holds};
    if (c->ev) {
        nbep_evloop_visit_block(c->ev, (uint32_t)k, pocket_one, &x);
        return;
    }
    for (size_t m = 0; m < s->n && r->n < NBEP_CONTACT_MAX; m++)
        if (atomic_load_explicit(&c->claim[w->par][m], memory_order_relaxed) == KEY_FREE)
            pocket_one(&x, (uint32_t)m);
}

/* The planes besides those of r that sphere k touches to within tol, added to r (up to
 * NBEP_CONTACT_MAX): a wall beside it is part of a pocket too (a sphere on the curve of a held
 * one, pressed against a wall by it: a wedge that the two hold together and neither alone). */
static void pocket_planes(const nbep_state *s, size_t k, double tol, rest_set *r)
{
    for (size_t p = 0; p < s->n_planes && r->n < NBEP_CONTACT_MAX; p++)
        if (!rest_has_plane(r, p) &&
            nbep_physics_plane_gap(s->plane_normal[p], s->plane_offset[p], s->pos[k],
                                   s->radius[k]) <= tol) {
            r->who[r->n] = (int32_t)p;
            r->ver[r->n++] = 0;
        }
}

/* After k bounced off held sphere j: k must leave j receding by the predictor's own test
 * (d.v >= 0, d from j to k; j does not move), or the same contact returns at zero time: the
 * bounce's v.n with the normalised n can disagree with it in the last bit (a sphere sliding
 * under a held one while gravity pulls it off). The kernel's pair response with j immobile
 * (d1 = 0, d2 = n) does nothing to a receding pair and applies its round-off tie push
 * (physics.c) to one closing by round-off. */
static void leave_held(const pred_ctx *c, nbep_state *s, size_t k, size_t j, double e)
{
    nbep_vec3 d = sep(c, s, j, k), v_j = ZERO3;
    double len = nbep_vec3_norm(d);
    if (!(len > 0.0) || !(nbep_vec3_dot(d, s->vel[k]) < 0.0))
        return;
    nbep_vec3 n = nbep_vec3_make(d.x / len, d.y / len, d.z / len);
    /* k's image that touches j (pos[k] itself without periodic axes: the same subtraction as
     * the predictor's) */
    const nbep_vec3 p_k = c->pb.any ? nbep_vec3_add(s->pos[j], d) : s->pos[k];
    double J; /* the held pile takes it: a weight, not counted (README, wall_impulse) */
    (void)nbep_physics_respond_pair_along(s->pos[j], p_k, &v_j, &s->vel[k], s->mass[j],
                                          s->mass[k], e, ZERO3, n, &J);
}

/* Sphere k, which has reacted JAM_HOLD times or more in this step, meets held sphere j slowly
 * (land_on_held), or meets any sphere while its planes carry it (j = NO_SPHERE): it is held
 * where it is, on its planes, j and what it touches (pocket_gather, pocket_planes, within
 * the settle tolerance). See JAM_HOLD. */
#define NO_SPHERE SIZE_MAX
/* Sphere k's reactions in this step (run.max_reactions counts them: fire). */
static uint32_t step_reactions(const pred_ctx *c, const thread_ws *w, size_t k)
{
    return c->jam && c->jam[k].step == w->jam_step ? c->jam[k].n : 0;
}

static bool jammed(const pred_ctx *c, const thread_ws *w, size_t k)
{
    return step_reactions(c, w, k) >= JAM_HOLD;
}

/* Whether sphere k takes part in a jam: JAM_JOIN reactions in this step. A jammed body
 * (jam_lock) takes in such spheres, not only jammed ones: the spheres of a jam react in
 * proportion to their contacts, so a row's ends (a wall and one neighbour) had an eighth to a
 * fifth of its middle's reactions when the middle pair first locked, and left out of the body
 * they fed it the momentum of their minimum bounces again at once (a row of five in a corner
 * pour, its middle pair locked 7597 times in one step until run.max_reactions = 20000 stopped
 * it; the falling row of test_settle.sh at run.max_reactions = 11000). A tenth of JAM_HOLD is
 * no more than the busiest spheres of the pile and hopper decks reach in a step (200 to 2000:
 * README, granular scenes), but it is read only where a lock is made, which those decks never
 * do. */
#define JAM_JOIN ((uint32_t)NBEP_JAM_JOIN) /* nbep/scene.h: --help-deck names it */
static bool in_jam(const pred_ctx *c, const thread_ws *w, size_t k)
{
    return step_reactions(c, w, k) >= JAM_JOIN;
}

static bool jam_hold(pred_ctx *c, nbep_state *s, thread_ws *w, size_t k, size_t j, double dt)
{
    if (!c->settle || !jammed(c, w, k))
        return false;
    const double vs = settle_speed(s, k, dt), amag = nbep_vec3_norm(s->acc[k]);
    rest_set r = c->rest[k];
    drop_leaning(c, k, &r);
    if (j != NO_SPHERE && r.n < NBEP_CONTACT_MAX && !leans_on(c, j, k)) {
        r.who[r.n] = -1 - (int32_t)j;
        r.ver[r.n++] = c->ver[j];
    }
    pocket_gather(c, s, w, k, j, vs * vs / amag, true, &r);
    pocket_planes(s, k, vs * vs / amag, &r);
    /* nothing to be held on (j rests on k, and nothing else touches it: a mixture poured at
     * dt = 0.05, grid mode, held a sphere of radius 0.02 under one of 0.04 that rested on it,
     * 0.1 m above the floor, with no contact at all, until 2026-12-05): its meeting is an
     * ordinary one, as rest_solve holds only with contacts */
    NBEP_PRED_JAM_HOLD_HOOK(r.n);
    if (r.n == 0)
        return false;
    r.still = true;
    c->rest[k] = r;
    NBEP_PRED_HELD_HOOK(c->rest[k].n);
    s->vel[k] = ZERO3;
    c->aeff[k] = ZERO3;
    fire(c, w, s, k, false);
    return true;
}

/* A jammed body (jam_lock): its spheres, found one contact after another from the pair that
 * met, every one in the jam (in_jam), none held, each touching one found before to within tol
 * (the settle tolerance, as the pockets of the jam hold). 64: the bodies of the pours measured
 * had 2 to 7, and each lock walks, for every member, its block (cells mode) or every sphere
 * (the rounds modes). */
#define LOCK_MAX 64
typedef struct lock_walk {
    pred_ctx *c;
    nbep_state *s;
    const thread_ws *w;
    double t_local, tol;
    uint32_t m[LOCK_MAX];
    size_t n, at;
    bool full; /* a sphere in the jam touches the body past LOCK_MAX: no lock */
} lock_walk;

static void lock_one(void *u, uint32_t q)
{
    lock_walk *x = u;
    if (x->full || x->c->rest[q].still || !in_jam(x->c, x->w, q) ||
        (x->c->lock_mark && x->c->lock_mark[q])) /* (rounds modes: in a body of this phase) */
        return;
    for (size_t i = 0; i < x->n; i++)
        if (x->m[i] == q)
            return;
    const uint32_t a = x->m[x->at];
    advance_to(x->c, x->s, q, x->t_local); /* (its motion as it was: only its clock moves) */
    if (!(nbep_vec3_norm(sep(x->c, x->s, a, q)) - (x->s->radius[a] + x->s->radius[q]) <= x->tol))
        return;
    if (x->n == LOCK_MAX) {
        x->full = true;
        return;
    }
    x->m[x->n++] = q;
}

/* pred_ctx's unlocked for a pair with hi, in w's step */
static uint64_t unlocked_key(const thread_ws *w, size_t hi)
{
    return (uint64_t)w->jam_step << 32 | ((uint32_t)hi + 1u);
}

/* Whether lo and hi, which meet, make a jammed body (jam_lock): one jammed and the other in
 * the jam, neither held, in a dissipative scene that settles, in time order (the paper's step
 * reacts at many times in one round). Not both jammed: a sphere pressed between a wall and a
 * neighbour meets each in turn, twice as often as the neighbour meets it, so it reached
 * run.max_reactions = 20000 when its neighbour had 9992 reactions (a corner pour, cells mode,
 * with responses that add no energy: those that did had shot such spheres apart). */
static bool lockable(const pred_ctx *c, const thread_ws *w, size_t lo, size_t hi)
{
    return c->settle && !c->order_step && !c->rest[lo].still && !c->rest[hi].still &&
           ((jammed(c, w, lo) && in_jam(c, w, hi)) || (jammed(c, w, hi) && in_jam(c, w, lo)));
}

/* Jammed bodies (README, granular scenes): lo and hi, lockable, meet (cells mode, whose loop
 * is serial: in the reaction, walking the neighbour lists; the rounds modes: at the round's
 * end, walking every sphere, nbep__pred_lock_phase). With every sphere in the jam that touches
 * them, contact after contact (lock_walk), they move on as one body: each takes the body's
 * velocity (its spheres' mean by mass, along its contacts), its contacts (the planes any of
 * them touches, less any it moves to or from faster than the rest speed) and its acceleration
 * on them (its spheres' mean). The limit of the inelastic collapse that the TC model stops short of: a row spanning a box
 * exactly, in mid-air and pressed into one wall by tilted gravity, met itself at zero time for
 * ever, fed by the minimum bounce at the pressed end (test_settle.sh). Where its contacts carry
 * it, it stops on them (settling holds it). False, changing no sphere's motion, where the body
 * has more than LOCK_MAX spheres. */
static bool jam_lock(pred_ctx *c, nbep_state *s, thread_ws *w, size_t lo, size_t hi, double dt,
                     double t_local)
{
    /* (a sphere without acceleration of its own, in a scene where others have one: touching
     * to 0, not 0/0, which would join every sphere of the block in the jam) */
    const double vs = settle_speed(s, lo, dt), amag = nbep_vec3_norm(s->acc[lo]);
    lock_walk x = {.c = c, .s = s, .w = w, .t_local = t_local,
                   .tol = amag > 0.0 ? vs * vs / amag : 0.0,
                   .m = {(uint32_t)lo, (uint32_t)hi}, .n = 2};
    for (x.at = 0; x.at < x.n && !x.full; x.at++)
        if (c->ev) /* cells mode: the spheres that can touch it */
            nbep_evloop_visit_block(c->ev, x.m[x.at], lock_one, &x);
        else { /* rounds modes: every sphere (lock_phase; lock_one takes those in the jam),
                * while no other thread runs: never in a reaction, which runs beside others */
            assert(c->locking);
            for (size_t k = 0; k < s->n; k++)
                lock_one(&x, (uint32_t)k);
        }
    if (x.full)
        return false;
    rest_set planes = {.n = 0}; /* those its spheres touch (a contact kept from an earlier
                                 * body need not be: its sphere that touched it may be gone) */
    nbep_vec3 mom = ZERO3, force = ZERO3;
    double mass = 0.0;
    for (size_t i = 0; i < x.n; i++) {
        const uint32_t m = x.m[i];
        pocket_planes(s, m, x.tol, &planes);
        mom = nbep_vec3_add(mom, nbep_vec3_scale(s->vel[m], s->mass[m]));
        force = nbep_vec3_add(force, nbep_vec3_scale(s->acc[m], s->mass[m]));
        mass += s->mass[m];
    }
    /* the contacts: the planes it moves to or from no faster than the rest speed, its motion
     * along them. One that it leaves faster is no contact (held as one, the body would strike
     * a sphere as a wall moving off it, and give it that speed twice over at each strike: a
     * sphere between the body and a wall was sped up so, 0.03 m/s a round trip, until the
     * stall check stopped the run), nor one it heads into faster (it meets it, as any plane);
     * one it leaves slower is (a body leaving a wall at 5e-324 m/s, dropped from its contacts,
     * fell back into the wall at once, and its lock took it off again, a million times) */
    nbep_vec3 n[NBEP_CONTACT_MAX];
    for (int q = 0; q < planes.n; q++)
        n[q] = s->plane_normal[planes.who[q]];
    nbep_vec3 v = nbep_vec3_scale(mom, 1.0 / mass);
    const double v_rest = rest_speed(s, lo, amag, dt);
    rest_set along = {.n = 0};
    for (int q = 0; q < planes.n; q++)
        if (fabs(nbep_vec3_dot(v, n[q])) <= v_rest) {
            n[along.n] = n[q];
            along.who[along.n] = planes.who[q];
            along.ver[along.n++] = 0;
        }
    planes = along;
    v = nbep_contact_tangent(v, n, planes.n, (1u << planes.n) - 1u);
    unsigned act;
    const nbep_vec3 a = nbep_contact_project(nbep_vec3_scale(force, 1.0 / mass), n, planes.n, &act);
    for (size_t i = 0; i < x.n; i++) {
        const uint32_t m = x.m[i];
        c->rest[m] = planes;
        s->vel[m] = v;
        c->aeff[m] = a;
        fire(c, w, s, m, false);
    }
    return true;
}

/* Sphere k (not held) meets held sphere j at a normal speed no faster than the rest speed, or
 * one that j's pile carries (carried): it joins the held pile if pressed onto j, no faster
 * than the rest speed in all, and its contacts then leave it no motion; else it bounces off j
 * as off a wall (j is carried by the pile; the momentum, below m (1 + e) times the rest speed,
 * or the carry speed, goes to it as to a plane), or is
 * caged if the face it met before faces this one and it still touches that (caged).
 * Not held by its planes and j alone, it may be by the pocket they make with the other held
 * spheres it touches (pocket_gather). */
static void land_on_held(pred_ctx *c, nbep_state *s, double e, double dt, size_t k, size_t j,
                         double t_abs, double tc, thread_ws *w, nbep_counters *cnt)
{
    nbep_vec3 d = sep(c, s, j, k);
    double len = nbep_vec3_norm(d);
    nbep_vec3 n = nbep_vec3_make(d.x / len, d.y / len, d.z / len);
    double u = nbep_vec3_dot(s->vel[k], n), an = nbep_vec3_dot(c->aeff[k], n);
    rest_set r = c->rest[k];
    drop_leaning(c, k, &r);
    const double amag = nbep_vec3_norm(s->acc[k]), v_rest = rest_speed(s, k, amag, dt);
    /* not on a j that rests on k (leans_on): it bounces, and meets j again after j's let-go */
    if (an < 0.0 && fabs(u) <= v_rest && nbep_vec3_norm(s->vel[k]) <= v_rest &&
        r.n < NBEP_CONTACT_MAX && !leans_on(c, j, k)) {
        r.who[r.n] = -1 - (int32_t)j;
        r.ver[r.n++] = c->ver[j];
        const rest_set r0 = r;
        nbep_vec3 v = s->vel[k], a;
        bool held = nbep__pred_rest_solve(c, s, k, &r, &v, &a, dt, true, c->hold_slow);
        if (!held) { /* a pocket: j with the other held spheres k touches (within twice the
                      * highest hop of the rest speed, |a| t_min^2) */
            r = r0;
            pocket_gather(c, s, w, k, j, v_rest * v_rest / amag, true, &r);
            pocket_planes(s, k, v_rest * v_rest / amag, &r);
            if (r.n > r0.n) {
                v = s->vel[k];
                held = nbep__pred_rest_solve(c, s, k, &r, &v, &a, dt, true, c->hold_slow);
            }
        }
        if (held) {
            c->rest[k] = r;
            s->vel[k] = v;
            c->aeff[k] = a;
            fire(c, w, s, k, false);
            return;
        }
    }
    if (jam_hold(c, s, w, k, j, dt))
        return;
    const double e_k = tc_restitution(c, tc, e, t_abs, k, k);
    if (caged(c, s, k, -1 - (int32_t)j, n, t_abs, tc) ||
        nbep_physics_respond_plane(n, &s->vel[k], e_k))
        cnt->c[NBEP_COUNTER_SPHERE_COLLISIONS]++;
    update_rest(c, s, k, dt, c->hold_slow);
    min_bounce_held(c, s, dt, k, j, n);
    update_rest(c, s, k, dt, c->hold_slow);
    leave_held(c, s, k, j, e);
    fire(c, w, s, k, false);
}

/* Whether the faces of r (sphere i's contacts) take a push on i along m: m projected onto the
 * cone of motions they allow is nothing, to HOLD_SLOPE of |m| (the normals of sphere contacts
 * are known to a few 1e-6 rad: HOLD_SLOPE). */
static bool faces_take(const pred_ctx *c, const nbep_state *s, size_t i, const rest_set *r,
                       nbep_vec3 m)
{
    nbep_vec3 n[NBEP_CONTACT_MAX];
    rest_normals(c, s, i, r, n);
    unsigned act;
    return nbep_vec3_norm(nbep_contact_project(m, n, r->n, &act)) <=
           HOLD_SLOPE * nbep_vec3_norm(m);
}

/* Whether the pile takes a push along m on sphere j (held, or carried by its planes) from
 * sphere k: the faces that hold j take it, its own contacts first, then with the planes it
 * touches, then with the held spheres, then with both (within settle_gather's reach: the rest
 * of the held pile is immobile). A contact set holds NBEP_CONTACT_MAX faces, so the planes are
 * tried before the spheres fill it: a sphere in a box's floor corner touches two walls and two
 * held neighbours, and a push into the corner is taken by the walls. */
static bool pile_takes(const pred_ctx *c, const nbep_state *s, const thread_ws *w, size_t j,
                       size_t k, nbep_vec3 m, double dt)
{
    rest_set r = c->rest[j];
    if (faces_take(c, s, j, &r, m))
        return true;
    const double amag = nbep_vec3_norm(s->acc[j]);
    if (!(amag > 0.0))
        return false;
    const double vs = settle_speed(s, j, dt), reach = vs * vs / amag;
    rest_set p = r;
    pocket_planes(s, j, reach, &p);
    if (p.n > r.n && faces_take(c, s, j, &p, m))
        return true;
    pocket_gather(c, s, w, j, k, reach, false, &r);
    const int spheres = r.n;
    if (spheres > c->rest[j].n && faces_take(c, s, j, &r, m))
        return true;
    pocket_planes(s, j, reach, &r);
    return r.n > spheres && faces_take(c, s, j, &r, m);
}

/* Held sphere j carries the impact of free sphere k, closing at speed u along m (their line of
 * centres, from k to j): slow enough (no faster than a fall from physics.carry_drop of j's
 * radius), and pushed into the faces of its pile (pile_takes). */
static bool carried(const pred_ctx *c, const nbep_state *s, const thread_ws *w, size_t j,
                    size_t k, double u, nbep_vec3 m, double carry_drop, double dt)
{
    const double amag = nbep_vec3_norm(s->acc[j]);
    return carry_drop > 0.0 && amag > 0.0 && u <= sqrt(2.0 * amag * carry_drop * s->radius[j]) &&
           pile_takes(c, s, w, j, k, m, dt);
}

void nbep__pred_react(pred_ctx *c, nbep_state *s, const nbep_scene *sc, double t_abs,
                      double t_local, uint32_t lo, uint32_t hi, const nbep_event *ev, thread_ws *w,
                      nbep_counters *cnt, nbep_thread_max *mx)
{
    const double e = sc->restitution, dt = sc->dt;
    advance_to(c, s, lo, t_local);
    const bool still_lo = c->rest && c->rest[lo].still;
    if (ev->kind == NBEP_EVENT_HORIZON) { /* image horizon: re-predicted from here */
        fire(c, w, s, lo, still_lo);
        return;
    }
    if (ev->kind == NBEP_EVENT_PLANE) {
        uint32_t p = UINT32_MAX - hi;
        nbep_vec3 n = s->plane_normal[p];
        double gap = nbep_physics_plane_gap(n, s->plane_offset[p], s->pos[lo], s->radius[lo]);
        note_overlap(mx, -gap, s->radius[lo]);
        const double vn0 = nbep_vec3_dot(n, s->vel[lo]);
        const double e_pl = tc_restitution(c, sc->tc, e, t_abs, lo, lo);
        if (caged(c, s, lo, (int32_t)p, n, t_abs, sc->tc) ||
            nbep_physics_respond_plane(n, &s->vel[lo], e_pl))
            cnt->c[NBEP_COUNTER_PLANE_COLLISIONS]++;
        /* SPEC /stats/wall_impulse: the normal momentum the plane received, pushed outward */
        nbep__pred_sum_add(mx, &mx->wall[p],
                           s->mass[lo] * (nbep_vec3_dot(n, s->vel[lo]) - vn0));
        update_rest(c, s, lo, dt, c->hold_slow);
        rest_set *r = c->rest ? &c->rest[lo] : NULL; /* NULL: nothing accelerates */
        /* the part against p of the acceleration it flies with (its own, less what the faces
         * it rests on take): a ball sliding down a ramp into a wall across its foot is pressed
         * into the wall by the ramp's push, though gravity has no part against it. Until
         * 2026-11-30 its own acceleration's part: 0 there, so the ball never rested on the wall
         * and the cage took each bounce back at zero time (65 million collisions in 1.5 s).
         * Faces at right angles (a box's floor and walls, the hopper's groove) give the same
         * part either way (the frames of the pile, hopper and bounce decks kept their bits). */
        double an = nbep_vec3_dot(r && r->n > 0 ? c->aeff[lo] : s->acc[lo], n),
               vn = nbep_vec3_dot(s->vel[lo], n);
        /* a bounce shorter than tc would be elastic (TC) and never shrink: rest; and one that
         * the TC model made elastic (the sphere is squeezed: it met something within tc) rests
         * no faster than the rest speed, what the minimum bounce of its neighbours leaves it
         * with. A lone sphere's bounces are all kept down to the first rule. Only where the
         * TC model acts (e < 1): at e = 1 a bounce is elastic whatever tc, and kept down to
         * 1e-9 of a step (until 2026-12-02 tc counted there too, and a nanometre sphere's
         * bounces, shorter than the default tc, ended at rest: 91 % of its energy lost) */
        const double rest_below = nbep_scene_tc_model(sc)
                                      ? fmax(NBEP_REST_FRACTION * dt, sc->tc)
                                      : NBEP_REST_FRACTION * dt;
        /* at e = 1, and a top below NBEP_ELASTIC_REST_HEIGHT of the radius: vn^2 / (2 |an|) */
        const bool hop =
            e >= 1.0 && vn * vn <= -2.0 * an * NBEP_ELASTIC_REST_HEIGHT * s->radius[lo];
        if (r && an < 0.0 && vn >= 0.0 &&
            (2.0 * vn <= -an * rest_below || hop ||
             (e_pl != e && vn <= rest_speed(s, lo, -an, dt))) &&
            r->n < NBEP_CONTACT_MAX) {
            r->who[r->n] = (int32_t)p;
            r->ver[r->n++] = 0;
            nbep__pred_rest_solve(c, s, lo, r, &s->vel[lo], &c->aeff[lo], dt, true,
                                  c->hold_slow);
        }
        fire(c, w, s, lo, still_lo);
        return;
    }
    advance_to(c, s, hi, t_local);
    const bool still_hi = c->rest && c->rest[hi].still;
    double sigma = s->radius[lo] + s->radius[hi];
    const nbep_vec3 r12 = sep(c, s, lo, hi);
    note_overlap(mx, sigma - nbep_vec3_norm(r12),
                 fmin(s->radius[lo], s->radius[hi]));
    /* a sphere its planes carry (j), met by one they do not (k), stays held, or is held now
     * if slow enough, only where its pile takes its load (pile_takes: its weight, and k's if k
     * is pressed onto it); a load it cannot take (from the side, on a sphere alone on a
     * floor) makes the meeting an ordinary response below, which moves it however slowly
     * (at e < 1: at e = 1 nothing is held by its speed, hold_slow, and the test is not
     * needed). Until 2026-12-02 the hold and the slow landing did not ask: a sphere held on a
     * floor, another balanced 2 cm off-centre on it (radius 0.1, e = 0.5), was pushed ten
     * times a step as it slid off, each push taken as a wall would take it, and the pair left
     * with 0.76 kg m/s that nothing gave it (static friction; they part at -0.43 and 0.43 m/s
     * now, as when both start free). A sphere held on other spheres is not asked: the loads
     * that pass through a pile's network (what rests on it, what its supports rest on) are
     * not resolved by the model, which takes a held sphere's supports as immobile, and asked
     * with its weight and k's alone the upper layers of a pour woke each other for ever (600
     * spheres, cells: 348 held at step 2500 and 55000 collisions a step, where all were held
     * by step 2276 with the pile taking every push, and are again by step 2318). */
    size_t sj = NO_SPHERE;
    if (c->rest && supported(c, lo) != supported(c, hi))
        sj = supported(c, lo) ? lo : hi;
    else if (c->rest && c->rest[lo].still != c->rest[hi].still)
        sj = c->rest[lo].still ? lo : hi; /* held, met by one sliding on its planes */
    const size_t sk = sj == lo ? hi : lo; /* (read only when sj is one of them) */
    bool taken = true; /* by sj's pile */
    if (sj != NO_SPHERE) {
        const nbep_vec3 d = sep(c, s, sj, sk); /* from j to k */
        /* the lasting load on j: its weight, and k's where k is pressed onto it (a slow
         * meeting is a minimum bounce, whose kicks carry that load on average) */
        const double len = nbep_vec3_norm(d), an = nbep_vec3_dot(effective_acc(c, s, sk), d);
        nbep_vec3 load = nbep_vec3_scale(s->acc[sj], s->mass[sj]);
        if (an < 0.0)
            load = nbep_vec3_axpy(load, s->mass[sk] * an / (len * len), d);
        taken = !c->hold_slow || rests_on_spheres(c, sj) || pile_takes(c, s, w, sj, sk, load, dt);
        if (taken && !c->rest[sj].still && try_hold(c, s, sj, dt))
            fire(c, w, s, sj, false);
        /* one of them held, the other not (free, or sliding on planes): a slow meeting lands
         * on the held one, and so does one its pile carries (carried); any other is an
         * ordinary response below, which wakes it */
        const double u = nbep_vec3_dot(s->vel[sk], d) / len;
        /* (not by its speed at e = 1, hold_slow: a sphere lying still on a floor, caught at
         * 0.6 mm/s by one sliding along it, sent it back as off a wall, momentum reversed,
         * until 2026-12-02; what its pile carries, it still lands) */
        if (c->rest[sj].still && !c->rest[sk].still &&
            ((c->hold_slow && taken &&
              fabs(u) <= rest_speed(s, sk, nbep_vec3_norm(s->acc[sk]), dt)) ||
             carried(c, s, w, sj, sk, -u, nbep_vec3_scale(d, -1.0), sc->carry_drop, dt))) {
            land_on_held(c, s, e, dt, sk, sj, t_abs, sc->tc, w, cnt);
            return;
        }
    }
    /* a jammed sphere that its planes carry, or that meets a held sphere however fast (not
     * one resting on it), is held where it is, on the held one too (JAM_HOLD: a row of spheres
     * that fits a box exactly passes its momentum to and fro at zero time; with gravity tilted
     * along the row, the row's planes carry only its end sphere: a faster meeting would wake
     * each held sphere again); the other takes no response and, unless held (as land_on_held
     * leaves the held sphere), is predicted again against it */
    for (int q = 0; c->rest && q < 2; q++) {
        const size_t k = q ? hi : lo, o = q ? lo : hi;
        const bool on_held = c->rest[o].still && !leans_on(c, o, k);
        if (!c->rest[k].still && (supported(c, k) || on_held) &&
            jam_hold(c, s, w, k, on_held ? o : NO_SPHERE, dt)) {
            if (!c->rest[o].still)
                fire(c, w, s, o, false);
            return;
        }
    }
    if (lockable(c, w, lo, hi)) {
        if (!c->ev && c->unlocked[lo] == unlocked_key(w, hi)) {
            c->unlocked[lo] = 0; /* its body could not be made: it meets as any pair, below */
        } else if (!c->ev) { /* rounds modes: at the round's end, on one thread (lock_phase);
                              * the pair is predicted again after it, and meets again */
            w->lock[w->n_lock++] = (uint64_t)lo << 32 | hi;
            fire(c, w, s, lo, false);
            fire(c, w, s, hi, false);
            return;
        } else if (jam_lock(c, s, w, lo, hi, dt, t_local)) {
            return;
        }
    }
    /* hi's image that touches lo (the same as pos[hi] without periodic axes) */
    const nbep_vec3 p_hi = c->pb.any ? nbep_vec3_add(s->pos[lo], r12) : s->pos[hi];
    const nbep_vec3 v_hi = s->vel[hi];
    /* spheres leaning on planes move only along them: the planes take their share (a free
     * pair keeps the paper's formula, bit for bit); only scenes with lasting contacts
     * (c->rest) have any, and only they need the normal for it (a square root and three
     * divisions in every collision of a fluid) */
    bool leans = false;
    nbep_vec3 d_lo = {0.0, 0.0, 0.0}, d_hi = {0.0, 0.0, 0.0};
    plane_share sh_lo = {.k = 0}, sh_hi = {.k = 0};
    if (c->rest) {
        const double len = nbep_vec3_norm(r12);
        const nbep_vec3 n =
            len > 0.0 ? nbep_vec3_make(r12.x / len, r12.y / len, r12.z / len) : r12;
        d_lo = plane_mobility(c, s, lo, nbep_vec3_scale(n, -1.0), &leans, &sh_lo);
        d_hi = plane_mobility(c, s, hi, n, &leans, &sh_hi);
    }
    const double e_pair = tc_restitution(c, sc->tc, e, t_abs, lo, hi);
    const double m_lo = c->mass_all > 0.0 ? c->mass_all : s->mass[lo];
    const double m_hi = c->mass_all > 0.0 ? c->mass_all : s->mass[hi];
    double J = 0.0; /* along d_lo and d_hi, where the spheres lean */
    if (leans ? nbep_physics_respond_pair_along(s->pos[lo], p_hi, &s->vel[lo], &s->vel[hi], m_lo,
                                                m_hi, e_pair, d_lo, d_hi, &J)
              : nbep_physics_respond_pair(s->pos[lo], p_hi, &s->vel[lo], &s->vel[hi], m_lo,
                                          m_hi, e_pair))
        cnt->c[NBEP_COUNTER_SPHERE_COLLISIONS]++;
    planes_take(mx, &sh_lo, J);
    planes_take(mx, &sh_hi, J);
    min_bounce(c, s, dt, lo, hi, leans, d_lo, d_hi, &sh_lo, &sh_hi, mx);
    /* SPEC /stats/virial: r12 . dp2, dp2 the momentum hi received. The exact orders react at
     * contact (|r12| = sigma to round-off: the plain product, a square root and a division
     * less a collision); step order reacts to a shadowed pair where it finds it, overlapped,
     * and takes it at the touching distance as naive does (until 2026-12-03 the overlapped
     * |r12|: a fluid at phi = 0.5, dt = 0.1 read 5.3 % low, a helper's review) */
    const nbep_vec3 dp_hi = nbep_vec3_scale(nbep_vec3_sub(s->vel[hi], v_hi), m_hi);
    nbep__pred_sum_add(mx, &mx->virial,
                       c->order_step ? nbep_physics_virial_at_touch(r12, dp_hi, sigma)
                                     : nbep_vec3_dot(r12, dp_hi));
    /* j, pushed where its pile cannot take it, keeps the push however slow (a hold would
     * take it back, and the push's momentum with it) */
    update_rest(c, s, lo, dt, c->hold_slow && (taken || lo != sj));
    update_rest(c, s, hi, dt, c->hold_slow && (taken || hi != sj));
    fire(c, w, s, lo, still_lo);
    fire(c, w, s, hi, still_hi);
}

/* Sphere i is held and a sphere it rests on has reacted since it took the load. */
bool nbep__pred_held_on_changed(const pred_ctx *c, size_t i)
{
    if (!c->rest || !c->rest[i].still)
        return false;
    const rest_set *r = &c->rest[i];
    for (int k = 0; k < r->n; k++)
        if (r->who[k] < 0 && r->ver[k] != c->ver[-1 - r->who[k]])
            return true;
    return false;
}

/* Held sphere i lets go of the sphere supports that reacted, at local time t_local; it fires
 * (moves again) unless what is left still holds it. */
void nbep__pred_let_go(pred_ctx *c, nbep_state *s, size_t i, double dt, double t_local,
                       thread_ws *w)
{
    rest_set *r = &c->rest[i];
    rest_set k = {.n = 0};
    for (int j = 0; j < r->n; j++)
        if (r->who[j] >= 0 || r->ver[j] == c->ver[-1 - r->who[j]]) {
            k.who[k.n] = r->who[j];
            k.ver[k.n++] = r->ver[j];
        }
    *r = k;
    advance_to(c, s, i, t_local);
    if (!nbep__pred_rest_solve(c, s, i, r, &s->vel[i], &c->aeff[i], dt, false, c->hold_slow))
        fire(c, w, s, i, true);
}

/* run.max_reactions: sphere i reacted too often in one step, at about time t; the run stops. */
void nbep__pred_jam_fail(nbep_sim *sim, uint64_t step, size_t i, double t)
{
    const nbep_scene *sc = sim->scene; /* its state is the run's now: sim->st */
    /* Without planes nothing holds a sphere still: at e < 1 and physics.tc = 0 this is
     * inelastic collapse, a row closing in ever faster collisions, which tc > 0 stops (until
     * 2026-12-05 a periodic box's collapse was said to be jammed between walls) */
    char why[160];
    if (sim->st.n_planes == 0 && sc->restitution < 1.0 && sc->tc == 0.0)
        snprintf(why, sizeof why,
                 "inelastic collapse, collisions at e = %g closing in ever faster, with "
                 "physics.tc = 0; a tc > 0 (the TC model, README) stops it",
                 sc->restitution);
    else
        snprintf(why, sizeof why,
                 "jammed between %s that nbep cannot hold still (README, granular scenes: not "
                 "solved yet)",
                 sim->st.n_planes > 0 ? "walls and neighbours" : "neighbours");
    nbep_diag_add(sim->diag, __FILE__, __LINE__,
                  "nbep: step %llu: sphere %zu reacted over %llu times in one step (t = %.17g, "
                  "run.max_reactions): %s; stopping",
                  (unsigned long long)step, i, (unsigned long long)sc->max_reactions, t, why);
    sim->status = NBEP_ENUMERIC;
}

void nbep__pred_lock_phase(pred_ctx *c, nbep_state *s, int crew, double dt, double t_local,
                           thread_ws *w)
{
    const size_t first = w->n_fired;
    c->locking = true;
    /* the pairs in the order of their keys, whichever thread met them: the same bodies for any
     * thread count (a pair's key names it; each met once in a round); a sphere joins one body
     * a phase (lock_mark), so the bodies fire at most n spheres, the room kept for them. The
     * crew's lists alone: a thread that the step's crew leaves out still holds the pairs of
     * its last react phase, maybe steps before, and a body made of such a pair would depend on
     * the crews, which the run picks by timing (a corner pour on 2 threads, grid mode, the
     * ways in turn: a pair kept so from the step before was read in 603 lock phases of one
     * step, in 12 of them lockable and not met; a body of a pair met had taken it in each
     * time, so the frames stayed the one thread's) */
    for (uint64_t last = 0;;) {
        uint64_t key = UINT64_MAX;
        for (int t = 0; t < crew; t++)
            for (size_t k = 0; k < c->ws[t].n_lock; k++)
                if (c->ws[t].lock[k] > last && c->ws[t].lock[k] < key)
                    key = c->ws[t].lock[k];
        if (key == UINT64_MAX)
            break;
        last = key;
        const size_t lo = (size_t)(key >> 32), hi = (size_t)(key & UINT32_MAX);
        const size_t before = w->n_fired;
        if (c->lock_mark[lo] || c->lock_mark[hi] || !lockable(c, w, lo, hi))
            continue;
        if (jam_lock(c, s, w, lo, hi, dt, t_local))
            for (size_t k = before; k < w->n_fired; k++)
                c->lock_mark[w->fired[k]] = 1;
        else /* no body (past LOCK_MAX): the pair's next meeting, at this time, is an ordinary
              * response, as cells mode's is at once; until 2026-12-04 it had none, and met
              * again at zero time until the stall check stopped the run (a pile of 100 at
              * dt = 0.05, all pairs, step 14) */
            c->unlocked[lo] = unlocked_key(w, hi);
    }
    for (size_t k = first; k < w->n_fired; k++)
        c->lock_mark[w->fired[k]] = 0;
    c->locking = false;
}
