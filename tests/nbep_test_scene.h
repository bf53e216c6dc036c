/* Scenes built by hand for the end-to-end tests (test_sim, test_extremes): no deck, no box
 * unless set, no output. Include after <cmocka.h>. */
#ifndef NBEP_TEST_SCENE_H
#define NBEP_TEST_SCENE_H

#include <stdio.h>
#include <stdlib.h>

#include "nbep/scene.h"
#include "nbep/vec3.h"

/* n spheres (zeroed) and np planes; e = 1, one thread, a frame every step. */
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

static inline void nbep_test_set_sphere(nbep_scene *sc, size_t i, nbep_vec3 p, nbep_vec3 v,
                                        double r, double m, nbep_vec3 a)
{
    sc->state.pos[i] = p;
    sc->state.vel[i] = v;
    sc->state.radius[i] = r;
    sc->state.mass[i] = m;
    sc->state.acc[i] = a;
}

#endif
