/* The BVH's self-check (nbep_bvh_check, which test_bvh calls after every build) against
 * trees broken from inside: this file compiles its own copy of src/bvh.c, so that it can reach
 * a node and shrink its box. A node's box is the exact union of what lies below it, so each of
 * its six bounds is some child's or sphere's: moved inward by one ulp, that child or sphere
 * sticks out, and the check must say so, bound by bound (a containment test that looked at
 * fewer bounds, or at any one of them, would pass a broken tree whose queries miss pairs); and
 * an inner node's right child out of its place. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "../src/bvh.c"

#include "nbep_test.h"
#include "nbep_test_scene.h"

/* n spheres of radii 0.2 to 0.4 at pseudo-random places in a cube of side 6 */
static nbep_scene *scene(size_t n)
{
    nbep_scene *sc = nbep_test_scene_new(n, 0, "seminaive", 1, 0.01);
    uint64_t x = 0x9e3779b97f4a7c15u;
    for (size_t i = 0; i < n; i++) {
        const nbep_vec3 p = nbep_vec3_make(6.0 * nbep_test_uniform(&x),
                                           6.0 * nbep_test_uniform(&x),
                                           6.0 * nbep_test_uniform(&x));
        nbep_test_set_sphere(sc, i, p, nbep_vec3_make(0.0, 0.0, 0.0),
                             0.2 + 0.2 * nbep_test_uniform(&x), 1.0,
                             nbep_vec3_make(0.0, 0.0, 0.0));
    }
    return sc;
}

/* Bound k of a box: lo.x, lo.y, lo.z, hi.x, hi.y, hi.z. */
static double *bound(bvh_node *nd, int k)
{
    nbep_vec3 *v = k < 3 ? &nd->lo : &nd->hi;
    return k % 3 == 0 ? &v->x : k % 3 == 1 ? &v->y : &v->z;
}

/* Node k's bound moved one ulp inward: the check finds one problem or more, its line `what`;
 * put back, none. */
static void shrunk_is_found(nbep_bvh *b, const nbep_state *s, uint32_t node, const char *what)
{
    for (int k = 0; k < 6; k++) {
        double *v = bound(&b->node[node], k);
        const double was = *v;
        *v = nextafter(was, k < 3 ? INFINITY : -INFINITY);
        nbep_diag d;
        nbep_diag_init(&d);
        const size_t problems = nbep_bvh_check(b, s, &d);
        if (problems == 0 || d.n_errors != 1 || !strstr(d.msg[0], what))
            fail_msg("node %u's bound %d moved inward: %zu problems, %s", (unsigned)node, k,
                     problems, d.n_errors ? d.msg[0] : "no line");
        nbep_diag_fini(&d);
        *v = was;
        nbep_diag_init(&d);
        assert_int_equal(nbep_bvh_check(b, s, &d), 0);
        nbep_diag_fini(&d);
    }
}

/* sc's tree, built and sound (its check finds nothing), its root an inner node. */
static nbep_bvh *built(const nbep_scene *sc)
{
    const size_t n = sc->state.n;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_bvh *b = NULL;
    assert_int_equal(nbep_bvh_create(n, &b, &d), NBEP_OK);
    nbep_bvh_build(b, &sc->state);
    assert_int_equal(nbep_bvh_check(b, &sc->state, &d), 0);
    nbep_diag_fini(&d);
    assert_int_equal(b->node[0].count, 0);
    return b;
}

static void test_a_node_box_shrunk_at_any_bound_is_found(void **state)
{
    (void)state;
    const size_t n = 200;
    nbep_scene *sc = scene(n);
    nbep_bvh *b = built(sc);
    /* the root (an inner node: 200 spheres, at most LEAF_MAX a leaf), and every leaf */
    shrunk_is_found(b, &sc->state, 0, "box does not contain a child's box");
    size_t leaves = 0;
    for (uint32_t k = 0; k < b->n_nodes; k++)
        if (b->node[k].count > 0) {
            shrunk_is_found(b, &sc->state, k, "leaf box does not contain a sphere's box");
            leaves++;
        }
    assert_true(leaves >= n / LEAF_MAX);
    nbep_bvh_destroy(&b);
    nbep_test_scene_free(&sc);
}

/* An inner node's right child where it cannot be: its left one (the node after it: the same
 * subtree walked twice), before it, or past the last node (a read out of the tree). The check
 * must stop there with that line, the first it gives; put back, none. */
static void test_a_right_child_out_of_place_is_found(void **state)
{
    (void)state;
    nbep_scene *sc = scene(200);
    nbep_bvh *b = built(sc);
    nbep_diag d;
    const uint32_t was = b->node[0].first;
    const uint32_t wrong[3] = {1, 0, (uint32_t)b->n_nodes};
    for (int k = 0; k < 3; k++) {
        b->node[0].first = wrong[k];
        nbep_diag_init(&d);
        const size_t problems = nbep_bvh_check(b, &sc->state, &d);
        if (problems == 0 || d.n_errors < 1 ||
            !strstr(d.msg[0], "right child is not after the left one"))
            fail_msg("the root's right child at %u: %zu problems, %s", (unsigned)wrong[k],
                     problems, d.n_errors ? d.msg[0] : "no line");
        nbep_diag_fini(&d);
    }
    b->node[0].first = was;
    nbep_diag_init(&d);
    assert_int_equal(nbep_bvh_check(b, &sc->state, &d), 0);
    nbep_diag_fini(&d);
    nbep_bvh_destroy(&b);
    nbep_test_scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_node_box_shrunk_at_any_bound_is_found),
        cmocka_unit_test(test_a_right_child_out_of_place_is_found),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
