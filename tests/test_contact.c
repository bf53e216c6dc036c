/* The lasting-contact kernel (contact.h) against answers worked out by hand from its contract:
 * the motion is the point of the cone {x : x.n_j >= 0} nearest to the acceleration (the KKT
 * conditions: x - a = sum mu_j n_j with every mu_j >= 0, mu_j = 0 unless x.n_j = 0), and the
 * active sets are tried from the smallest up, so the reported set is the smallest that
 * carries the load. Each expected answer is also checked against those conditions here. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>

#include "nbep/contact.h"
#include "nbep_test.h"

static nbep_vec3 unit(double x, double y, double z)
{
    nbep_vec3 v = {x, y, z};
    return nbep_vec3_scale(v, 1.0 / nbep_vec3_norm(v));
}

/* A sphere on a floor slides along a wall without being pushed into it (a.n = 0): the floor
 * alone carries the load, so the wall is not active, and a velocity leaving the wall keeps its
 * normal part (a frictionless wall that does not push cannot hold the sphere back). */
static void test_a_wall_the_motion_only_grazes_carries_no_load(void **state)
{
    (void)state;
    const nbep_vec3 n[2] = {{0, 0, 1}, {1, 0, 0}}; /* floor, wall */
    unsigned act = 99;
    nbep_vec3 x = nbep_contact_project((nbep_vec3){0, 2, -9.81}, n, 2, &act);
    assert_int_equal(act, 1u);
    assert_true(x.x == 0.0 && x.y == 2.0 && x.z == 0.0);
    nbep_vec3 v = nbep_contact_tangent((nbep_vec3){1, 2, 0.5}, n, 2, act);
    assert_true(v.x == 1.0 && v.y == 2.0 && v.z == 0.0);
}

/* Floor n0 = z, a sloped wall n1 = (-1, 0, 1)/sqrt2 the sphere is pulled away from, and a
 * vertical wall n2 = (1, 1, 0)/sqrt2 it is pushed into, with a = (-2, 1, -10). Worked by hand:
 * - alone, no contact will do: along the floor (-2, 1, 0) goes into n2; n1 alone leaves
 *   (-6, 1, -6), into the floor; n2 alone (-1.5, 1.5, -10), into the floor;
 * - floor and n1 hold it only by pulling: along their edge (y) x = (0, 1, 0), and
 *   x - a = (2, 0, 10) = mu0 n0 + mu1 n1 needs mu1 = -2 sqrt2 < 0;
 * - floor and n2: along their edge t = (-1, 1, 0)/sqrt2, x = (a.t) t = (-1.5, 1.5, 0), and
 *   x - a = (0.5, 0.5, 10) = 10 n0 + (sqrt2 / 2) n2, both pushing; x leaves n1 (x.n1 > 0).
 * So x = (-1.5, 1.5, 0) with contacts 0 and 2 active. The floor and the sloped wall meet at
 * 45 degrees (n0.n1 = 1/sqrt2), so the pulling contact's push is found by elimination; it is
 * tried in both places of that pair (sloped wall second, then first: active contacts 0 and 2,
 * then 1 and 2). Round-off of the normals: 1e-12. */
static void test_an_edge_held_by_a_pulling_contact_is_not_the_answer(void **state)
{
    (void)state;
    const nbep_vec3 floor_n = {0, 0, 1}, sloped = unit(-1, 0, 1), wall = unit(1, 1, 0);
    const nbep_vec3 orders[2][3] = {{floor_n, sloped, wall}, {sloped, floor_n, wall}};
    const unsigned want[2] = {5u, 6u};
    const nbep_vec3 a = {-2, 1, -10};
    for (int o = 0; o < 2; o++) {
        const nbep_vec3 *n = orders[o];
        unsigned act = 99;
        nbep_vec3 x = nbep_contact_project(a, n, 3, &act);
        assert_int_equal(act, want[o]);
        assert_close(x.x, -1.5, 0.0, 1e-12);
        assert_close(x.y, 1.5, 0.0, 1e-12);
        assert_close(x.z, 0.0, 0.0, 1e-12);
        /* the KKT conditions for the answer: in the cone, and x - a pushes along the floor
         * and the vertical wall */
        for (int j = 0; j < 3; j++)
            assert_true(nbep_vec3_dot(x, n[j]) >= -1e-12);
        nbep_vec3 r = nbep_vec3_sub(x, a);
        assert_close(r.x, 0.5, 0.0, 1e-12);
        assert_close(r.y, 0.5, 0.0, 1e-12);
        assert_close(r.z, 10.0, 0.0, 1e-12);
    }
}

/* A sphere pushed into a corner (floor and two walls) by a = (-1, -2, -9.81) is held still by
 * all three (x = 0: -a = 9.81 n_floor + 1 n_x + 2 n_y, every force pushing), whichever order
 * the contacts come in (their triple product's sign), while a fourth contact it is pulled
 * away from (a.n3 > 0) carries no load: the three, not all four, are active. With the fourth
 * left out, the three are all there is. */
static void test_a_corner_holds_still_in_either_order_and_a_fourth_contact_carries_nothing(
    void **state)
{
    (void)state;
    const nbep_vec3 floor_n = {0, 0, 1}, wall_x = {1, 0, 0}, wall_y = {0, 1, 0};
    const nbep_vec3 away = unit(-1, -1, -1);
    const nbep_vec3 a = {-1, -2, -9.81};
    assert_true(nbep_vec3_dot(a, away) > 0.0);
    const nbep_vec3 orders[2][4] = {{floor_n, wall_x, wall_y, away},  /* right-handed */
                                    {floor_n, wall_y, wall_x, away}}; /* left-handed */
    for (int o = 0; o < 2; o++) {
        for (int k = 3; k <= 4; k++) {
            unsigned act = 99;
            nbep_vec3 x = nbep_contact_project(a, orders[o], k, &act);
            assert_int_equal(act, 7u);
            assert_true(x.x == 0.0 && x.y == 0.0 && x.z == 0.0);
        }
    }
}

/* What each contact pushes (nbep_contact_project_push): in the corner above, 9.81 by the floor,
 * 1 and 2 by the walls (whichever order they come in), 0 by the fourth, pulled away from; in a
 * V of two planes at 45 degrees, a = (0, 0, -g) is pushed back by g / sqrt(2) along each, and
 * a = (-1, 0, -g) by (g + 1) / sqrt(2) along the one facing +x and (g - 1) / sqrt(2) along the
 * other; on one floor, a = (3, 0, -g): g by the floor; on a floor and a slope at 45 degrees to
 * it, rising towards +x (normal (-1, 0, 1)/sqrt2; not square to the floor: n0.n1 = 1/sqrt2,
 * the pushes found by elimination), a = (1, 0, -g) is held still, x = 0, the slope pushing 1
 * back along x, sqrt2 along its normal, and the floor the g - 1 left (either order). Every
 * answer rebuilds
 * x = a + sum mu n. */
static void check_push(nbep_vec3 a, const nbep_vec3 *n, int k, const double *want)
{
    unsigned act;
    double mu[NBEP_CONTACT_MAX];
    const nbep_vec3 x = nbep_contact_project_push(a, n, k, &act, mu);
    nbep_vec3 back = a;
    for (int j = 0; j < k; j++) {
        /* relative to |a| ~ 10: a few roundings of the solve */
        assert_close(mu[j], want[j], 0.0, 1e-14 * nbep_vec3_norm(a));
        back = nbep_vec3_axpy(back, mu[j], n[j]);
    }
    assert_true(nbep_vec3_norm(nbep_vec3_sub(back, x)) <= 1e-14 * nbep_vec3_norm(a));
}

static void test_each_contact_pushes_its_share(void **state)
{
    (void)state;
    const nbep_vec3 floor_n = {0, 0, 1}, wall_x = {1, 0, 0}, wall_y = {0, 1, 0};
    const nbep_vec3 away = unit(-1, -1, -1), a = {-1, -2, -9.81};
    const nbep_vec3 right[4] = {floor_n, wall_x, wall_y, away};
    const nbep_vec3 left[4] = {floor_n, wall_y, wall_x, away};
    check_push(a, right, 4, (double[]){9.81, 1.0, 2.0, 0.0});
    check_push(a, left, 4, (double[]){9.81, 2.0, 1.0, 0.0});
    const double g = 9.81, s = sqrt(0.5);
    const nbep_vec3 vee[2] = {unit(1, 0, 1), unit(-1, 0, 1)};
    check_push((nbep_vec3){0, 0, -g}, vee, 2, (double[]){g * s, g * s});
    check_push((nbep_vec3){-1, 0, -g}, vee, 2, (double[]){(g + 1) * s, (g - 1) * s});
    check_push((nbep_vec3){3, 0, -g}, &floor_n, 1, (double[]){g});
    const nbep_vec3 floor_slope[2] = {floor_n, unit(-1, 0, 1)};
    const nbep_vec3 slope_floor[2] = {unit(-1, 0, 1), floor_n};
    check_push((nbep_vec3){1, 0, -g}, floor_slope, 2, (double[]){g - 1.0, sqrt(2.0)});
    check_push((nbep_vec3){1, 0, -g}, slope_floor, 2, (double[]){sqrt(2.0), g - 1.0});
    /* a contact pulled away from pushes nothing: the wall facing +x, a = (3, 0, -g) */
    const nbep_vec3 floor_wall[2] = {floor_n, wall_x};
    check_push((nbep_vec3){3, 0, -g}, floor_wall, 2, (double[]){g, 0.0});
    const nbep_vec3 wall_floor[2] = {wall_x, floor_n}; /* the one that pushes comes second */
    check_push((nbep_vec3){3, 0, -g}, wall_floor, 2, (double[]){0.0, g});
}

/* The velocity left to a sphere held by two contacts runs along their common edge: a floor
 * and a wall (edge along y) leave v = (1, 2, 3) its y part only, in either order; three
 * independent contacts leave nothing; a third whose normal is square to that edge (a slope
 * along it) adds no constraint, so the edge's motion is kept. */
static void test_the_tangent_velocity_runs_along_the_edge_of_two_contacts(void **state)
{
    (void)state;
    const nbep_vec3 v = {1, 2, 3};
    const nbep_vec3 two[2] = {{0, 0, 1}, {1, 0, 0}}, owt[2] = {{1, 0, 0}, {0, 0, 1}};
    nbep_vec3 t = nbep_contact_tangent(v, two, 2, 3u);
    assert_close(t.x, 0.0, 0.0, 1e-15);
    assert_close(t.y, 2.0, 0.0, 1e-15);
    assert_close(t.z, 0.0, 0.0, 1e-15);
    t = nbep_contact_tangent(v, owt, 2, 3u);
    assert_close(t.x, 0.0, 0.0, 1e-15);
    assert_close(t.y, 2.0, 0.0, 1e-15);
    assert_close(t.z, 0.0, 0.0, 1e-15);
    const nbep_vec3 corner[3] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}};
    t = nbep_contact_tangent(v, corner, 3, 7u);
    assert_true(t.x == 0.0 && t.y == 0.0 && t.z == 0.0);
    const nbep_vec3 sloped[3] = {{0, 0, 1}, {1, 0, 0}, unit(1, 0, 1)};
    t = nbep_contact_tangent(v, sloped, 3, 7u);
    assert_close(t.x, 0.0, 0.0, 1e-15);
    assert_close(t.y, 2.0, 0.0, 1e-15);
    assert_close(t.z, 0.0, 0.0, 1e-15);
    /* only the active ones count: the wall left out of the mask, the floor's part alone goes */
    t = nbep_contact_tangent(v, corner, 3, 1u);
    assert_true(t.x == 1.0 && t.y == 2.0 && t.z == 0.0);
    /* a normal parallel to one before it adds nothing (two floors at one height, a wall): the
     * floors' edge with the wall still runs along y, wherever the wall comes; the floors alone
     * leave the floor's tangent part (a coverage run showed no test gave parallel normals) */
    const nbep_vec3 floors[3] = {{0, 0, 1}, {0, 0, 1}, {1, 0, 0}};
    const nbep_vec3 wall_between[3] = {{0, 0, 1}, {1, 0, 0}, {0, 0, 1}};
    for (int k = 0; k < 2; k++) {
        t = nbep_contact_tangent(v, k == 0 ? floors : wall_between, 3, 7u);
        assert_close(t.x, 0.0, 0.0, 1e-15);
        assert_close(t.y, 2.0, 0.0, 1e-15);
        assert_close(t.z, 0.0, 0.0, 1e-15);
    }
    t = nbep_contact_tangent(v, floors, 3, 3u);
    assert_true(t.x == 1.0 && t.y == 2.0 && t.z == 0.0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_wall_the_motion_only_grazes_carries_no_load),
        cmocka_unit_test(test_an_edge_held_by_a_pulling_contact_is_not_the_answer),
        cmocka_unit_test(
            test_a_corner_holds_still_in_either_order_and_a_fourth_contact_carries_nothing),
        cmocka_unit_test(test_each_contact_pushes_its_share),
        cmocka_unit_test(test_the_tangent_velocity_runs_along_the_edge_of_two_contacts),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
