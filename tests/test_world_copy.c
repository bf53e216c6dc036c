/* The physics runs on a world of copies (docs/optimistic-design.md, *What a world copies*): the
 * optimistic engine's slabs will each keep their own copy of the spheres' motion, and reach it
 * through the callbacks' context (pred_cells.c's cells_user: its pred_ctx and nbep_state) made
 * as shallow copies whose motion arrays are the slab's. That holds only while nothing the
 * callbacks reach reads or writes the run's state but through that context; this test checks
 * it on the engine as it runs.
 *
 * It compiles its own copy of the engine and of pred_cells.c, with a look before each event
 * is handled (one thread): a world is made (the context's pred_ctx and nbep_state copied, their
 * motion arrays (position, velocity, image, local time, response count, and the TC clock and
 * reaction count where the scene has them) copied into its own, its own counts, and a copy of
 * the thread's workspace record, whose scratch arrays it shares: a reaction writes them before
 * it reads them, and the run's own reaction comes after);
 * the event's sphere is predicted in the world (planes and its list's pairs) and flown to the
 * event's time, and both must come out as in the run, bit for bit; a fresh collision is reacted to in the world, which must leave
 * every array of the run as it was; and at the next look, once the run has handled the event
 * itself, the spheres the world's reaction changed must have the run's motion now, and fly to
 * the event's time as they flew in the world after its reaction, bit for bit.
 * In a periodic fluid at phi = 0.35 (elastic) and a dissipative one (e = 0.8, the TC model):
 * many predictions and reactions compared, none different, and the run with the looks ends
 * as the run without them, bit for bit. */
struct nbep_evloop;
struct nbep_evloop_ops;
#include <stdint.h>
#include "nbep/feq.h"
static void look_before(struct nbep_evloop *e, const struct nbep_evloop_ops *ops, void *u,
                        uint32_t i, const nbep_event *ev);
#define NBEP_EVLOOP_BEFORE_HOOK(e, ops, u, i, ev) look_before(e, ops, u, i, ev)
#include "../src/evloop.c"
#include "../src/evloop_team.c"
#include "../src/pred_cells.c"

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

/* A world: pred_cells.c's (the context's structs copied, their motion arrays its own, kept
 * apart as a struct copy may leave a NULL where the run has none), grown here as the run's n
 * needs. */
typedef struct {
    cells_world a;
    size_t n, cap;
} world;

static struct {
    bool on;
    uint64_t events;      /* events looked at (not expiries) */
    uint64_t predicted;   /* spheres predicted in a world and compared */
    uint64_t reacted;     /* reactions in a world */
    uint64_t compared;    /* spheres a world's reaction changed, compared with the run's */
    uint64_t differ;      /* predictions, motions or run arrays not as they should be */
    uint64_t skipped;     /* reactions not compared: their step ended after them */
} seen;
static world wd;
static const cells_user *pending_run; /* the run's context whose event the world reacted to */
static const nbep_evloop_ops *pending_run_ops;
static double pending_t0;             /* its step's start (a step's end moves every sphere) */
static uint32_t pending[64];
static size_t n_pending;
static double pending_time;             /* the world's reaction's time */
static nbep_vec3 pending_flight[64][3]; /* each changed sphere flown to it in the world, after */
/* the run's arrays before the world reacted (to see that it left them) */
static nbep_vec3 *run_pos, *run_vel;
static double *run_tau, *run_t_last;
static uint64_t *run_ver;
static int32_t *run_image;
static jam_count *run_jam;

#define GROW(p, n) ((p) = realloc((p), (n) * sizeof *(p)), assert_non_null(p))

static void world_make(const cells_user *x)
{
    const size_t n = x->s->n;
    if (wd.cap < n) {
        GROW(wd.a.pos, n);
        GROW(wd.a.vel, n);
        GROW(wd.a.image, 3 * n);
        GROW(wd.a.tau, n);
        GROW(wd.a.ver, n);
        GROW(wd.a.t_last, n);
        GROW(wd.a.jam, n);
        GROW(run_pos, n);
        GROW(run_vel, n);
        GROW(run_tau, n);
        GROW(run_ver, n);
        GROW(run_image, 3 * n);
        GROW(run_t_last, n);
        GROW(run_jam, n);
        wd.cap = n;
    }
    /* the structs as they are, then the motion arrays the world's own */
    memcpy(&wd.a.c, x->c, sizeof wd.a.c);
    wd.a.s = *x->s;
    wd.a.w = *x->w;
    wd.a.s.pos = memcpy(wd.a.pos, x->s->pos, n * sizeof *wd.a.pos);
    wd.a.s.vel = memcpy(wd.a.vel, x->s->vel, n * sizeof *wd.a.vel);
    wd.a.s.image = x->s->image ? memcpy(wd.a.image, x->s->image, 3 * n * sizeof *wd.a.image)
                             : NULL;
    wd.a.c.tau = memcpy(wd.a.tau, x->c->tau, n * sizeof *wd.a.tau);
    wd.a.c.ver = memcpy(wd.a.ver, x->c->ver, n * sizeof *wd.a.ver);
    wd.a.c.t_last = x->c->t_last ? memcpy(wd.a.t_last, x->c->t_last, n * sizeof *wd.a.t_last)
                               : NULL;
    wd.a.c.jam = x->c->jam ? memcpy(wd.a.jam, x->c->jam, n * sizeof *wd.a.jam) : NULL;
    /* free flight only (the team loop's scenes): nothing rests, holds or settles */
    assert_null(x->c->rest);
    assert_null(x->c->aeff);
    memset(&wd.a.cnt, 0, sizeof wd.a.cnt);
    memset(&wd.a.mx, 0, sizeof wd.a.mx);
    wd.a.u = *x;
    wd.a.u.c = &wd.a.c;
    wd.a.u.s = &wd.a.s;
    wd.a.u.w = &wd.a.w;
    wd.a.u.cnt = &wd.a.cnt;
    wd.a.u.mx = &wd.a.mx;
    wd.n = n;
    memcpy(run_pos, x->s->pos, n * sizeof *run_pos);
    memcpy(run_vel, x->s->vel, n * sizeof *run_vel);
    memcpy(run_tau, x->c->tau, n * sizeof *run_tau);
    memcpy(run_ver, x->c->ver, n * sizeof *run_ver);
    if (x->s->image)
        memcpy(run_image, x->s->image, 3 * n * sizeof *run_image);
    if (x->c->t_last)
        memcpy(run_t_last, x->c->t_last, n * sizeof *run_t_last);
    if (x->c->jam)
        memcpy(run_jam, x->c->jam, n * sizeof *run_jam);
}

static bool same_event(const nbep_event *a, const nbep_event *b)
{
    return memcmp(&a->time, &b->time, sizeof a->time) == 0 && a->partner == b->partner &&
           a->kind == b->kind && a->ver_self == b->ver_self && a->ver_partner == b->ver_partner;
}

/* Sphere i's earliest event in context u (its planes, then its list's pairs). */
static nbep_event predicted(const nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i)
{
    nbep_event best = ops->planes(u, i);
    size_t m;
    const uint32_t *js = nbep_nblist_of(&e->nl, i, &m);
    ops->pairs(u, i, js, m, true, &best);
    return best;
}

static void look_before(nbep_evloop *e, const nbep_evloop_ops *ops, void *u, uint32_t i,
                        const nbep_event *ev)
{
    if (!seen.on)
        return;
    const cells_user *x = u;
    /* the event before, handled by the run since: the world's changes are the run's (within
     * its step: the step's end brings every sphere to it) */
    if (n_pending > 0 && x->T0 != pending_t0) {
        seen.skipped++;
        n_pending = 0;
    }
    for (size_t k = 0; k < n_pending; k++) {
        const uint32_t j = pending[k];
        nbep_vec3 f[3];
        pending_run_ops->flight((void *)pending_run, j, pending_time, &f[0], &f[1], &f[2]);
        seen.differ += memcmp(f, pending_flight[k], sizeof f) != 0;
        seen.compared++;
        seen.differ += memcmp(&pending_run->s->pos[j], &wd.a.s.pos[j], sizeof wd.a.s.pos[j]) != 0 ||
                       memcmp(&pending_run->s->vel[j], &wd.a.s.vel[j], sizeof wd.a.s.vel[j]) != 0 ||
                       memcmp(&pending_run->c->tau[j], &wd.a.c.tau[j], sizeof wd.a.c.tau[j]) != 0 ||
                       pending_run->c->ver[j] != wd.a.c.ver[j] ||
                       (wd.a.c.t_last && memcmp(&pending_run->c->t_last[j], &wd.a.c.t_last[j],
                                              sizeof wd.a.c.t_last[j]) != 0);
    }
    n_pending = 0;
    if (ev->kind == NBEP_EVENT_HORIZON || seen.events++ % 3 != 0) /* (every third: time) */
        return;
    world_make(x);
    const nbep_event a = predicted(e, ops, u, i), b = predicted(e, ops, &wd.a.u, i);
    seen.predicted++;
    seen.differ += !same_event(&a, &b);
    nbep_vec3 pv[2][3]; /* its flight to the event's time, in the run and in the world */
    ops->flight(u, i, ev->time, &pv[0][0], &pv[0][1], &pv[0][2]);
    ops->flight(&wd.a.u, i, ev->time, &pv[1][0], &pv[1][1], &pv[1][2]);
    seen.differ += memcmp(pv[0], pv[1], sizeof pv[0]) != 0;
    if (!ops->fresh(u, i, ev))
        return;
    const uint32_t *changed;
    bool stop = false;
    const size_t m = ops->react(&wd.a.u, i, ev, &changed, &stop);
    seen.reacted++;
    const size_t n = wd.n;
    seen.differ += memcmp(run_pos, x->s->pos, n * sizeof *run_pos) != 0 ||
                   memcmp(run_vel, x->s->vel, n * sizeof *run_vel) != 0 ||
                   memcmp(run_tau, x->c->tau, n * sizeof *run_tau) != 0 ||
                   memcmp(run_ver, x->c->ver, n * sizeof *run_ver) != 0 ||
                   (x->s->image && memcmp(run_image, x->s->image, 3 * n * sizeof *run_image)) ||
                   (x->c->t_last && memcmp(run_t_last, x->c->t_last, n * sizeof *run_t_last)) ||
                   (x->c->jam && memcmp(run_jam, x->c->jam, n * sizeof *run_jam));
    assert_true(m <= sizeof pending / sizeof pending[0]);
    memcpy(pending, changed, m * sizeof *changed);
    n_pending = m;
    pending_run = x;
    pending_run_ops = ops;
    pending_t0 = x->T0;
    pending_time = ev->time;
    for (size_t k = 0; k < m; k++)
        ops->flight(&wd.a.u, changed[k], ev->time, &pending_flight[k][0], &pending_flight[k][1],
                    &pending_flight[k][2]);
}

/* sc on one thread without the looks and with them: the looks compared many predictions and
 * reactions, none different, and the two runs end the same, bit for bit. */
static void the_same_in_a_world(const nbep_scene *sc, uint64_t least)
{
    nbep_state plain, looked;
    memset(&seen, 0, sizeof seen);
    const nbep_summary s0 = nbep_test_run(sc, 1, NULL, NULL, &plain, NULL);
    seen.on = true;
    n_pending = 0;
    const nbep_summary s1 = nbep_test_run(sc, 1, NULL, NULL, &looked, NULL);
    seen.on = false;
    fprintf(stderr,
            "%llu predictions in a world, %llu reactions, %llu spheres they changed compared, "
            "%llu different, %llu not compared (their step ended); %llu collisions\n",
            (unsigned long long)seen.predicted, (unsigned long long)seen.reacted,
            (unsigned long long)seen.compared, (unsigned long long)seen.differ,
            (unsigned long long)seen.skipped, (unsigned long long)s1.sphere_collisions);
    assert_int_equal(seen.differ, 0);
    /* two spheres a reaction (a free flight's), but those whose step ended first, and the last */
    assert_true(seen.reacted >= least && seen.skipped < seen.reacted / 10);
    assert_true(seen.compared >= 2 * (seen.reacted - seen.skipped - 1));
    assert_int_equal(s1.sphere_collisions, s0.sphere_collisions);
    nbep_test_same_end(&plain, &looked);
}

static void test_an_elastic_fluid_runs_the_same_in_a_world(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(8, 0.35, 30, 0.02, 5);
    the_same_in_a_world(sc, 500);
    nbep_test_scene_free(&sc);
}

/* e = 0.8 with the TC model: a reaction moves the TC clock and the reaction count too */
static void test_a_dissipative_fluid_runs_the_same_in_a_world(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(8, 0.35, 30, 0.02, 6);
    sc->restitution = 0.8;
    sc->tc = 1e-3;
    the_same_in_a_world(sc, 500);
    nbep_test_scene_free(&sc);
}

static int teardown(void **state)
{
    (void)state;
    free(wd.a.pos);
    free(wd.a.vel);
    free(wd.a.image);
    free(wd.a.tau);
    free(wd.a.ver);
    free(wd.a.t_last);
    free(wd.a.jam);
    free(run_pos);
    free(run_vel);
    free(run_tau);
    free(run_ver);
    free(run_image);
    free(run_t_last);
    free(run_jam);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_elastic_fluid_runs_the_same_in_a_world),
        cmocka_unit_test(test_a_dissipative_fluid_runs_the_same_in_a_world),
    };
    return cmocka_run_group_tests(tests, NULL, teardown);
}
