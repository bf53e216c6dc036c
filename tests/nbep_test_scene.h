/* Scenes built by hand for the end-to-end tests (test_sim, test_extremes, ...): no deck, no box
 * unless set, no output; and running them. Include after <cmocka.h>. */
#ifndef NBEP_TEST_SCENE_H
#define NBEP_TEST_SCENE_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "nbep/output.h"
#include "nbep/run.h"
#include "nbep/scene.h"
#include "nbep/sim.h"
#include "nbep/vec3.h"

/* n spheres (zeroed) and np planes; e = 1, tc = 0, the deck's carry_drop, one thread, a frame
 * every step. */
static inline nbep_scene *nbep_test_scene_new(size_t n, size_t np, const char *algo,
                                              uint64_t steps, double dt)
{
    nbep_scene *sc = calloc(1, sizeof *sc);
    assert_non_null(sc);
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_state_init(&sc->state, n, np, &d), NBEP_OK);
    nbep_diag_fini(&d);
    snprintf(sc->algorithm, sizeof sc->algorithm, "%s", algo);
    sc->steps = steps;
    sc->dt = dt;
    sc->threads = 1;
    sc->restitution = 1.0;
    sc->carry_drop = NBEP_CARRY_DROP;
    sc->output_every = 1;
    sc->out_position = sc->out_velocity = true;
    sc->sweep_replicas = 1;
    return sc;
}

/* NULL-safe; NULLs the pointer. */
static inline void nbep_test_scene_free(nbep_scene **scp)
{
    if (!*scp)
        return;
    nbep_state_fini(&(*scp)->state);
    free(*scp);
    *scp = NULL;
}

/* Plane p = {x : n.x = offset}, n normalised here. */
static inline void nbep_test_set_plane(nbep_scene *sc, size_t p, nbep_vec3 n, double offset)
{
    sc->state.plane_normal[p] = nbep_vec3_scale(n, 1.0 / nbep_vec3_norm(n));
    sc->state.plane_offset[p] = offset;
}

/* The box [0, hi] as planes 0-5 (x, -x, y, -y, z, -z, inward), as a deck's box makes them. */
static inline void nbep_test_set_box_to(nbep_scene *sc, nbep_vec3 hi)
{
    sc->has_box = true;
    sc->box_min = (nbep_vec3){0.0, 0.0, 0.0};
    sc->box_max = hi;
    for (int k = 0; k < 3; k++) {
        nbep_vec3 e = {k == 0, k == 1, k == 2};
        nbep_test_set_plane(sc, (size_t)(2 * k), e, 0.0);
        nbep_test_set_plane(sc, (size_t)(2 * k + 1), nbep_vec3_scale(e, -1.0),
                            -nbep_vec3_dot(e, hi));
    }
}

/* The box [0, L]^3, as nbep_test_set_box_to. */
static inline void nbep_test_set_box(nbep_scene *sc, double L)
{
    nbep_test_set_box_to(sc, (nbep_vec3){L, L, L});
}

static inline void nbep_test_set_sphere(nbep_scene *sc, size_t i, nbep_vec3 p, nbep_vec3 v,
                                        double r, double m, nbep_vec3 a)
{
    sc->state.pos[i] = p;
    sc->state.vel[i] = v;
    sc->state.radius[i] = r;
    sc->state.mass[i] = m;
    sc->state.acc[i] = a;
}

/* Newton's cradle in cells mode, 400 steps of 1e-3, no box: k spheres of radius r and mass 1.1
 * at rest, touching in a row along x (numbered k - 1, ..., 0, centres 0.3 + 2 r q: exact for
 * r = 0.375, rounded for 0.37 or 0.25), and sphere k coming in at speed u from sphere k - 1's
 * side. Each contact's reaction makes the next pair's entry at its own time with a smaller key:
 * a cascade at one time (cascade.h), as deep as the row stays at one time. */
static inline nbep_scene *nbep_test_cradle_beyond(size_t k, double r, double u, double gap);
static inline nbep_scene *nbep_test_cradle(size_t k, double r, double u)
{
    return nbep_test_cradle_beyond(k, r, u, -1.0);
}

/* The same with, where gap >= 0, one more sphere (k + 1) at rest beyond sphere 0, gap short of
 * touching it: sphere 0 sent off by the cascade meets it a little later (gap / u), so that
 * events of the same window follow the cascade's. */
static inline nbep_scene *nbep_test_cradle_beyond(size_t k, double r, double u, double gap)
{
    nbep_scene *sc = nbep_test_scene_new(k + 1 + (gap >= 0.0), 0, "predictive", 400, 1e-3);
    sc->neighbors_cells = true;
    const nbep_vec3 zero = {0.0, 0.0, 0.0};
    nbep_test_set_sphere(sc, k, (nbep_vec3){0.3 - 2.0 * r - 0.2, 0.7, -0.4},
                         (nbep_vec3){u, 0.0, 0.0}, r, 1.1, zero);
    for (size_t q = 0; q < k; q++)
        nbep_test_set_sphere(sc, k - 1 - q, (nbep_vec3){0.3 + 2.0 * r * (double)q, 0.7, -0.4},
                             zero, r, 1.1, zero);
    if (gap >= 0.0)
        nbep_test_set_sphere(sc, k + 1,
                             (nbep_vec3){0.3 + 2.0 * r * (double)k + gap, 0.7, -0.4}, zero, r,
                             1.1, zero);
    return sc;
}

/* A fixed pseudo-random sequence for hand-built scenes (xorshift64; any fixed one will do):
 * the next number in [0, 1). */
static inline double nbep_test_uniform(uint64_t *x)
{
    *x ^= *x << 13, *x ^= *x >> 7, *x ^= *x << 17;
    return (double)(*x >> 11) / 9007199254740992.0;
}

/* A velocity of the given speed in a direction from the sequence x. */
static inline nbep_vec3 nbep_test_random_velocity(uint64_t *x, double speed)
{
    nbep_vec3 u;
    u.x = nbep_test_uniform(x) - 0.5;
    u.y = nbep_test_uniform(x) - 0.5;
    u.z = nbep_test_uniform(x) - 0.5;
    return nbep_vec3_scale(u, speed / nbep_vec3_norm(u));
}

/* A hard-sphere fluid at packing fraction phi on a simple cubic lattice (side^3 spheres of
 * diameter 1 and mass 1) in a closed box, speeds sqrt(3) (kT = 1) in random directions. */
static inline nbep_scene *nbep_test_fluid(size_t side, double phi, uint64_t steps, double dt)
{
    size_t n = side * side * side;
    nbep_scene *sc = nbep_test_scene_new(n, 6, "predictive", steps, dt);
    const double L = cbrt((double)n * (4.0 * atan(1.0)) / 6.0 / phi), a = L / (double)side;
    nbep_test_set_box(sc, L);
    uint64_t x = 0x9E3779B97F4A7C15u;
    for (size_t i = 0; i < n; i++) {
        nbep_vec3 v = nbep_test_random_velocity(&x, sqrt(3.0));
        nbep_vec3 p = {a * ((double)(i % side) + 0.5), a * ((double)(i / side % side) + 0.5),
                       a * ((double)(i / side / side) + 0.5)};
        nbep_test_set_sphere(sc, i, p, v, 0.5, 1.0, (nbep_vec3){0.0, 0.0, 0.0});
    }
    return sc;
}

/* The box [0, L]^3, periodic along every axis (no planes). */
static inline void nbep_test_set_periodic_box(nbep_scene *sc, double L)
{
    sc->has_box = true;
    sc->box_max = (nbep_vec3){L, L, L};
    for (int k = 0; k < 3; k++) {
        sc->periodic[k] = true;
        sc->state.period[k] = L; /* as the deck loader sets it */
    }
}

/* side^3 spheres of radius 0.5 and mass 1 on a jittered lattice of spacing 1.25 around the
 * origin, velocities uniform in [-1, 1]^3, no planes, no box, nothing accelerating, steps of
 * 0.05: a cluster that collides at first and then expands into free space. */
static inline nbep_scene *nbep_test_cluster(const char *algo, size_t side, uint64_t steps)
{
    const size_t n = side * side * side;
    nbep_scene *sc = nbep_test_scene_new(n, 0, algo, steps, 0.05);
    uint64_t x = 0x2545F4914F6CDD1Du;
    for (size_t i = 0; i < n; i++) {
        double u[6];
        for (int k = 0; k < 6; k++)
            u[k] = nbep_test_uniform(&x);
        const double h = 1.25, o = -0.5 * h * (double)side;
        nbep_vec3 p = {o + h * ((double)(i % side) + 0.4 + 0.2 * u[0]),
                       o + h * ((double)(i / side % side) + 0.4 + 0.2 * u[1]),
                       o + h * ((double)(i / side / side) + 0.4 + 0.2 * u[2])};
        nbep_vec3 v = {2.0 * u[3] - 1.0, 2.0 * u[4] - 1.0, 2.0 * u[5] - 1.0};
        nbep_test_set_sphere(sc, i, p, v, 0.5, 1.0, (nbep_vec3){0.0, 0.0, 0.0});
    }
    return sc;
}

/* A hard-sphere fluid at packing fraction phi in a fully periodic cube, cells mode: side^3
 * spheres of diameter 1 and mass 1 on a simple cubic lattice filling the box, speeds sqrt(3)
 * (kT = 1) in random directions (from seed) with the mean removed (zero total momentum). */
static inline nbep_scene *nbep_test_periodic_fluid(size_t side, double phi, uint64_t steps,
                                                   double dt, uint64_t seed)
{
    size_t n = side * side * side;
    const double L = cbrt((double)n * (4.0 * atan(1.0)) / 6.0 / phi), a = L / (double)side;
    nbep_scene *sc = nbep_test_scene_new(n, 0, "predictive", steps, dt);
    sc->neighbors_cells = true;
    nbep_test_set_periodic_box(sc, L);
    uint64_t x = 0x9E3779B97F4A7C15u ^ (seed * 0xD1B54A32D192ED03u);
    nbep_vec3 mean = {0.0, 0.0, 0.0};
    for (size_t i = 0; i < n; i++) {
        nbep_vec3 v = nbep_test_random_velocity(&x, sqrt(3.0));
        mean = nbep_vec3_add(mean, nbep_vec3_scale(v, 1.0 / (double)n));
        nbep_vec3 p = {a * ((double)(i % side) + 0.5), a * ((double)(i / side % side) + 0.5),
                       a * ((double)(i / side / side) + 0.5)};
        nbep_test_set_sphere(sc, i, p, v, 0.5, 1.0, (nbep_vec3){0.0, 0.0, 0.0});
    }
    for (size_t i = 0; i < n; i++)
        sc->state.vel[i] = nbep_vec3_sub(sc->state.vel[i], mean);
    return sc;
}

/* ---- runs ------------------------------------------------------------------------------------ */

/* Smaller problems under valgrind (scripts/run-tests.sh sets NBEP_TEST_SCALE=small). */
static inline size_t nbep_test_scaled(size_t big, size_t small)
{
    const char *s = getenv("NBEP_TEST_SCALE");
    return s && strcmp(s, "small") == 0 ? small : big;
}

/* Every frame's positions and velocities (data: per frame n positions, then n velocities)
 * and image counts (3 per sphere), appended by nbep_test_keep_frame. */
typedef struct nbep_test_frames {
    size_t n_frames, n;
    nbep_vec3 *data;
    int32_t *image;
} nbep_test_frames;

static inline nbep_status nbep_test_keep_frame(void *ctx, int64_t step, const nbep_state *s,
                                               nbep_diag *d)
{
    (void)step, (void)d;
    nbep_test_frames *f = ctx;
    f->n = s->n;
    f->data = realloc(f->data, (f->n_frames + 1) * 2 * s->n * sizeof *f->data);
    f->image = realloc(f->image, (f->n_frames + 1) * 3 * s->n * sizeof *f->image);
    assert_non_null(f->data);
    assert_non_null(f->image);
    memcpy(f->data + f->n_frames * 2 * s->n, s->pos, s->n * sizeof *s->pos);
    memcpy(f->data + f->n_frames * 2 * s->n + s->n, s->vel, s->n * sizeof *s->vel);
    memcpy(f->image + f->n_frames * 3 * s->n, s->image, 3 * s->n * sizeof *s->image);
    f->n_frames++;
    return NBEP_OK;
}

static inline void nbep_test_frames_free(nbep_test_frames *f)
{
    free(f->data);
    free(f->image);
    memset(f, 0, sizeof *f);
}

/* Runs sc on nt threads, each frame to on_frame(ctx) (NULL: none), and when path is not NULL
 * into that HDF5 file (frames and stats as sc asks); the run must end with NBEP_OK (a stall
 * is a failure). The final state goes to *final (caller finis) and every counter's total to
 * counts[NBEP_COUNTER_COUNT], each when not NULL. */
static inline nbep_summary nbep_test_run_to(const nbep_scene *sc, int nt, nbep_frame_fn on_frame,
                                            void *ctx, const char *path, nbep_state *final,
                                            uint64_t *counts)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_output *out = NULL;
    if (path)
        assert_int_equal(
            nbep_output_create(path, sc, nbep_sim_resolve_threads(nt), &out, &d), NBEP_OK);
    nbep_sim_options opt = {
        .threads = nt, .out = out, .on_frame = on_frame, .on_frame_ctx = ctx};
    nbep_sim *sim = NULL;
    assert_int_equal(nbep_sim_create(sc, &opt, &sim, &d), NBEP_OK);
    nbep_status st = nbep_sim_run(sim, &d);
    if (st != NBEP_OK)
        nbep_diag_print(&d, stderr);
    assert_int_equal(st, NBEP_OK);
    nbep_summary sum;
    nbep_sim_summary(sim, &sum);
    if (final)
        assert_int_equal(nbep_state_copy(final, nbep_sim_state(sim), &d), NBEP_OK);
    for (int k = 0; counts && k < NBEP_COUNTER_COUNT; k++)
        counts[k] = nbep_sim_counter(sim, k);
    nbep_sim_destroy(&sim);
    assert_int_equal(nbep_output_close(&out, &sum, &d), NBEP_OK);
    nbep_diag_fini(&d);
    return sum;
}

/* nbep_test_run_to without a file. */
static inline nbep_summary nbep_test_run_counted(const nbep_scene *sc, int nt,
                                                 nbep_frame_fn on_frame, void *ctx,
                                                 nbep_state *final, uint64_t *counts)
{
    return nbep_test_run_to(sc, nt, on_frame, ctx, NULL, final, counts);
}

/* Two runs' final states (nbep_test_run's), which must end the same bit for bit: positions and
 * velocities; both finished with. */
static inline void nbep_test_same_end(nbep_state *a, nbep_state *b)
{
    assert_int_equal(a->n, b->n);
    assert_int_equal(memcmp(a->pos, b->pos, a->n * sizeof *a->pos), 0);
    assert_int_equal(memcmp(a->vel, b->vel, a->n * sizeof *a->vel), 0);
    nbep_state_fini(a);
    nbep_state_fini(b);
}

/* nbep_test_run_counted with the reactions counter alone to *reactions (may be NULL). */
static inline nbep_summary nbep_test_run(const nbep_scene *sc, int nt, nbep_frame_fn on_frame,
                                         void *ctx, nbep_state *final, uint64_t *reactions)
{
    uint64_t counts[NBEP_COUNTER_COUNT];
    nbep_summary sum = nbep_test_run_counted(sc, nt, on_frame, ctx, final, counts);
    if (reactions)
        *reactions = counts[NBEP_COUNTER_REACTIONS];
    return sum;
}

/* A run of sc on nt threads that may fail (a jam, a fault): its status, its one message (""
 * when it ended), the counter `ahead` (events the cells team handled ahead of their turn),
 * every counter where counts is not NULL, and the state it stopped in, into *fin (the
 * caller's to nbep_state_fini). */
static inline nbep_status nbep_test_run_to_end_counted(const nbep_scene *sc, int nt, char *msg,
                                                       size_t cap, uint64_t *ahead,
                                                       nbep_state *fin, uint64_t *counts)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_sim_options opt = {.threads = nt};
    nbep_sim *sim = NULL;
    assert_int_equal(nbep_sim_create(sc, &opt, &sim, &d), NBEP_OK);
    const nbep_status st = nbep_sim_run(sim, &d);
    assert_int_equal(d.n_errors, st == NBEP_OK ? 0 : 1);
    snprintf(msg, cap, "%s", d.n_errors ? d.msg[0] : "");
    *ahead = nbep_sim_counter(sim, NBEP_COUNTER_AHEAD);
    for (int k = 0; counts && k < NBEP_COUNTER_COUNT; k++)
        counts[k] = nbep_sim_counter(sim, (enum nbep_counter)k);
    assert_int_equal(nbep_state_copy(fin, nbep_sim_state(sim), &d), NBEP_OK);
    nbep_sim_destroy(&sim);
    nbep_diag_fini(&d);
    return st;
}

/* nbep_test_run_to_end_counted without the counters */
static inline nbep_status nbep_test_run_to_end(const nbep_scene *sc, int nt, char *msg,
                                               size_t cap, uint64_t *ahead, nbep_state *fin)
{
    return nbep_test_run_to_end_counted(sc, nt, msg, cap, ahead, fin, NULL);
}

/* Runs the deck at deck_path through nbep's one run pipeline (what `nbep run` does), writing
 * output_path; the run must end with NBEP_OK. */
static inline nbep_run_result nbep_test_run_deck(const char *deck_path, const char *output_path)
{
    const nbep_run_request rq = {.deck_path = deck_path, .output_path = output_path};
    nbep_run_result res;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_status st = nbep_run(&rq, &res, &d);
    if (st != NBEP_OK)
        nbep_diag_print(&d, stderr);
    assert_int_equal(st, NBEP_OK);
    nbep_diag_fini(&d);
    return res;
}

/* The deck `text` written to a temporary file NAME (build/tests/tmp), its path in path (len
 * bytes). */
static inline void nbep_test_write_deck(const char *name, const char *text, char *path,
                                        size_t len)
{
    mkdir("build", 0777);
    mkdir("build/tests", 0777);
    mkdir("build/tests/tmp", 0777);
    nbep_test_tmp(name, path, len);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_true(fputs(text, f) >= 0);
    assert_int_equal(fclose(f), 0);
}

/* The deck `text` written to a temporary file NAME (build/tests/tmp), loaded into *sc (the
 * caller's to nbep_scene_fini; it must load) and removed. */
static inline void nbep_test_load_deck(const char *name, const char *text, nbep_scene *sc)
{
    char path[256];
    nbep_test_write_deck(name, text, path, sizeof path);
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_status st = nbep_scene_load(path, NULL, 0, sc, &d);
    if (st != NBEP_OK)
        nbep_diag_print(&d, stderr);
    assert_int_equal(st, NBEP_OK);
    nbep_diag_fini(&d);
    remove(path);
}

#endif
