/* Tests of the BVH pre-filter: against O(n^2) double loops on random scenes (radii varied 10x,
 * pairs touching exactly, pairs overlapping), on degenerate scenes (one sphere, two spheres,
 * all spheres at one point, spheres on a line), on rebuilds, and under concurrent queries.
 * NBEP_TEST_SCALE=small shrinks the scenes for valgrind. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/bvh.h"
#include "nbep_test.h"

/* Positions and radii are multiples of GRID (2^-20) below 2^12 in magnitude: sums and
 * differences then need at most 32 significant bits, so they are exact in double and a pair
 * built to touch touches exactly, in the test's arithmetic and in the BVH's. */
#define GRID 0x1.0p-20
/* Unit of the touching distances: a multiple of it times 5 or 7 splits exactly into the
 * Pythagorean directions below. */
#define TOUCH_UNIT 0x1.0p-10

/* ---- fixture ---------------------------------------------------------------------------- */

typedef struct fixture {
    nbep_diag d;
    nbep_state s;          /* the scene under test */
    nbep_bvh *b;
    uint32_t *got;         /* reported j of one query */
    size_t n_got, cap_got;
    uint32_t *stamp;       /* stamp[j] == i + 1 when query i reported j */
    size_t cap_stamp;
} fixture;

static int setup(void **state)
{
    fixture *f = calloc(1, sizeof *f);
    if (!f)
        return -1;
    nbep_diag_init(&f->d);
    *state = f;
    return 0;
}

static int teardown(void **state)
{
    fixture *f = *state;
    nbep_bvh_destroy(&f->b);
    nbep_state_fini(&f->s);
    nbep_diag_fini(&f->d);
    free(f->got);
    free(f->stamp);
    free(f);
    return 0;
}

static size_t scaled(size_t full, size_t small)
{
    const char *e = getenv("NBEP_TEST_SCALE");
    return e && strcmp(e, "small") == 0 ? small : full;
}

/* Replaces the fixture's scene with n zeroed spheres and makes room for its queries. */
static void new_scene(fixture *f, size_t n)
{
    nbep_state_fini(&f->s);
    assert_int_equal(nbep_state_init(&f->s, n, 0, &f->d), NBEP_OK);
    if (f->cap_got < n + 1) {
        free(f->got);
        free(f->stamp);
        f->cap_got = f->cap_stamp = n + 1;
        f->got = malloc(f->cap_got * sizeof *f->got);
        f->stamp = malloc(f->cap_stamp * sizeof *f->stamp);
        assert_non_null(f->got);
        assert_non_null(f->stamp);
    }
}

static void build(fixture *f, size_t n_max)
{
    if (!f->b)
        assert_int_equal(nbep_bvh_create(n_max, &f->b, &f->d), NBEP_OK);
    nbep_bvh_build(f->b, &f->s);
    assert_int_equal(nbep_bvh_check(f->b, &f->s, &f->d), 0);
}

static void collect(void *ctx, uint32_t j)
{
    fixture *f = ctx;
    if (f->n_got == f->cap_got)
        fail_msg("query reported more than n spheres");
    f->got[f->n_got++] = j;
}

/* Runs query i into f->got, checking that every j is > i, below n and reported once. */
static size_t query(fixture *f, size_t i)
{
    f->n_got = 0;
    size_t examined = nbep_bvh_query_later(f->b, &f->s, i, collect, f);
    for (size_t k = 0; k < f->n_got; k++) {
        uint32_t j = f->got[k];
        if (!(j > i && j < f->s.n))
            fail_msg("query %zu reported sphere %u, not in (i, n)", i, (unsigned)j);
        if (f->stamp[j] == i + 1)
            fail_msg("query %zu reported sphere %u twice", i, (unsigned)j);
        f->stamp[j] = (uint32_t)(i + 1);
    }
    return examined;
}

/* The two definitions the filter is specified by, written here independently. */
static bool boxes_touch(const nbep_state *s, size_t i, size_t j)
{
    const double *pi = &s->pos[i].x, *pj = &s->pos[j].x;
    double ri = s->radius[i], rj = s->radius[j];
    for (int a = 0; a < 3; a++)
        if (!(pi[a] - ri <= pj[a] + rj && pj[a] - rj <= pi[a] + ri))
            return false;
    return true;
}
static bool spheres_overlap(const nbep_state *s, size_t i, size_t j)
{
    nbep_vec3 dp = nbep_vec3_sub(s->pos[j], s->pos[i]);
    double sigma = s->radius[i] + s->radius[j];
    return nbep_vec3_dot(dp, dp) <= sigma * sigma;
}

/* Queries every sphere and compares with the double loops: the reported set equals the set of
 * later spheres whose boxes touch, and among them the overlapping spheres equal those of the
 * loop. Returns the number of overlapping pairs. */
static size_t compare_with_double_loop(fixture *f)
{
    const nbep_state *s = &f->s;
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    size_t n_overlap = 0;
    for (size_t i = 0; i < s->n; i++) {
        query(f, i);
        size_t overlap_reported = 0;
        for (size_t k = 0; k < f->n_got; k++)
            overlap_reported += spheres_overlap(s, i, f->got[k]);
        size_t overlap_loop = 0, box_loop = 0;
        for (size_t j = i + 1; j < s->n; j++) {
            bool reported = f->stamp[j] == i + 1;
            if (boxes_touch(s, i, j) != reported)
                fail_msg("pair (%zu, %zu): boxes touch %d, reported %d", i, j,
                         (int)boxes_touch(s, i, j), (int)reported);
            bool overlap = spheres_overlap(s, i, j);
            if (overlap && !reported)
                fail_msg("overlapping pair (%zu, %zu) not reported", i, j);
            box_loop += reported;
            overlap_loop += overlap;
        }
        assert_int_equal(f->n_got, box_loop);
        assert_int_equal(overlap_reported, overlap_loop);
        n_overlap += overlap_loop;
    }
    return n_overlap;
}

/* ---- random scenes ---------------------------------------------------------------------- */

/* splitmix64: a small generator whose state the caller owns. */
static uint64_t rng_next(uint64_t *x)
{
    uint64_t z = (*x += UINT64_C(0x9e3779b97f4a7c15));
    z = (z ^ (z >> 30)) * UINT64_C(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94d049bb133111eb);
    return z ^ (z >> 31);
}
static double rng_unit(uint64_t *x)
{
    return (double)(rng_next(x) >> 11) * 0x1.0p-53;
}
static double on_grid(double v)
{
    return round(v / GRID) * GRID;
}

/* Directions with integer components over an integer length (3-4-5, 2-3-6-7), so that a
 * distance that is a multiple of the length splits into exact components. */
static const int touch_dir[][4] = {
    {1, 0, 0, 1},  {0, -1, 0, 1}, {0, 0, 1, 1},  {3, 4, 0, 5},
    {0, -3, 4, 5}, {2, 3, 6, 7},  {-2, 3, -6, 7}, {6, -2, 3, 7},
};

/* n spheres, radii log-uniform over [0.05, 0.5) (10x), uniform in a cube at packing fraction
 * about 0.1. Every 7th sphere (7, 14, ...) is moved against a sphere that is not one of these
 * movers: the even ones (14, 28, ...) to touch it exactly, the odd ones to overlap it by half.
 * Returns the number of pairs built to touch; each is asserted to touch exactly. */
static size_t make_random_scene(fixture *f, size_t n, uint64_t seed)
{
    new_scene(f, n);
    nbep_state *s = &f->s;
    uint64_t x = seed;
    double side = 0.657 * cbrt((double)n);   /* mean sphere volume 0.0284 at phi = 0.1 */
    for (size_t i = 0; i < n; i++) {
        s->radius[i] = on_grid(0.05 * pow(10.0, rng_unit(&x)));
        s->pos[i] = nbep_vec3_make(on_grid(side * rng_unit(&x)), on_grid(side * rng_unit(&x)),
                                   on_grid(side * rng_unit(&x)));
    }
    size_t n_touch = 0;
    for (size_t i = 7; i < n; i += 7) {
        size_t j;
        do
            j = (size_t)(rng_next(&x) % n);
        while (j % 7 == 0 && j != 0);
        const int *dir = touch_dir[rng_next(&x) % (sizeof touch_dir / sizeof *touch_dir)];
        /* sigma = r_i + r_j: a multiple of dir's length in TOUCH_UNITs, above r_j + 0.05 */
        double len = dir[3] * TOUCH_UNIT;
        double sigma = ceil((s->radius[j] + 0.05 + 0.45 * rng_unit(&x)) / len) * len;
        s->radius[i] = sigma - s->radius[j];
        double t = sigma / dir[3] * ((i / 7) % 2 == 0 ? 1.0 : 0.5);
        s->pos[i] = nbep_vec3_make(s->pos[j].x + dir[0] * t, s->pos[j].y + dir[1] * t,
                                   s->pos[j].z + dir[2] * t);
        if ((i / 7) % 2 == 0) {
            nbep_vec3 dp = nbep_vec3_sub(s->pos[i], s->pos[j]);
            double sum = s->radius[i] + s->radius[j];
            assert_true(nbep_vec3_dot(dp, dp) == sum * sum);   /* touching to the last bit */
            n_touch++;
        }
    }
    return n_touch;
}

static void test_random_scenes_report_exactly_the_pairs_of_the_double_loop(void **state)
{
    fixture *f = *state;
    const size_t sizes[] = {scaled(2000, 300), scaled(1000, 150), scaled(313, 77), 9, 5, 2};
    const uint64_t seeds[] = {1, 0x5eed, 20240917, 77};
    for (size_t a = 0; a < sizeof sizes / sizeof *sizes; a++)
        for (size_t k = 0; k < sizeof seeds / sizeof *seeds; k++) {
            size_t n_touch = make_random_scene(f, sizes[a], seeds[k] + a);
            nbep_bvh_destroy(&f->b);
            build(f, sizes[a]);
            size_t n_overlap = compare_with_double_loop(f);
            assert_true(n_overlap >= n_touch);
            assert_true(nbep_bvh_depth(f->b) <= NBEP_BVH_MAX_DEPTH);
        }
}

/* A copy whose box touches a later box exactly, face to face along one axis, as the copy's
 * own place (the position plus the shift, rounded once) and the boxes' sums give it: the
 * query must report it. Its widening covers the roundings the tree's boxes and the copy's
 * place add (a few ulps of the coordinates, 2^-48 of them); a query box narrower than the
 * radius by as much (a sign flipped in the widening) misses these pairs by some 1e-14, which
 * random places never come so near (the test above). Places and radii not dyadic, so that
 * the sums round; copies a period up and down each axis (a copy nearer the origin than its
 * shift is long narrows a query that subtracts |shift|); the partner nudged by ulps until the
 * copy's gap is at most 0 and the next ulp out would open it. */
static void test_a_shifted_query_reports_a_box_its_copy_touches_exactly(void **state)
{
    fixture *f = *state;
    const double L = 6.0;
    const nbep_vec3 places[3] = {{0.3, 2.1, 5.7}, {5.9, 0.1, 3.3}, {1.7, 5.65, 0.2}};
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 6; a++) /* a period up and down each axis */
            for (int side = -1; side <= 1; side += 2) {
                const int ax = a / 2;
                new_scene(f, 2);
                f->s.pos[0] = places[k];
                f->s.radius[0] = 0.37;
                f->s.radius[1] = 0.29;
                nbep_vec3 sh = {0.0, 0.0, 0.0};
                (&sh.x)[ax] = a % 2 ? -L : L;
                const nbep_vec3 c = nbep_vec3_add(f->s.pos[0], sh); /* as the query places it */
                const double rs = f->s.radius[0] + f->s.radius[1];
                nbep_vec3 pj = c; /* overlapping along the other axes */
                double *x = &pj.x + ax;
                const double cx = (&c.x)[ax];
                *x = cx + side * rs;
                while (fabs(cx - *x) - rs > 0.0) /* in until touching */
                    *x = nextafter(*x, cx);
                while (fabs(cx - nextafter(*x, side * INFINITY)) - rs <= 0.0) /* out while so */
                    *x = nextafter(*x, side * INFINITY);
                f->s.pos[1] = pj;
                nbep_bvh_destroy(&f->b);
                build(f, 2);
                f->n_got = 0;
                (void)nbep_bvh_query_later_shifted(f->b, &f->s, 0, sh, collect, f);
                if (!(f->n_got == 1 && f->got[0] == 1))
                    fail_msg("place %d, shift %d, side %d: a box touching the copy exactly "
                             "not reported (%zu reported)", k, a, side, f->n_got);
            }
}

/* A copy of a sphere moved by a shift (seminaive in a periodic box: a sphere near a face and
 * its partners across it) pairs with every later sphere whose box touches the copy's, itself
 * reported once, and with no earlier one: random spheres of radii 0.2 to 0.5 in [0, 6)^3,
 * every sphere's copies a period (6) away along each axis and diagonal, against a double loop
 * of the boxes moved by the shift. The query widens the copy by a few roundings, so a box that
 * misses by more than that is not reported (a loose margin would only cost tests). */
static void test_a_shifted_query_pairs_with_the_boxes_its_copy_touches(void **state)
{
    fixture *f = *state;
    const size_t n = scaled(400, 200);
    const double L = 6.0;
    new_scene(f, n);
    uint64_t x = 0x1234567u;
    for (size_t i = 0; i < n; i++) {
        f->s.pos[i] = (nbep_vec3){L * rng_unit(&x), L * rng_unit(&x), L * rng_unit(&x)};
        f->s.radius[i] = 0.2 + 0.3 * rng_unit(&x);
    }
    nbep_bvh_destroy(&f->b);
    build(f, n);
    const double shifts[][3] = {{L, 0, 0}, {-L, 0, 0}, {0, L, 0}, {0, 0, -L}, {L, -L, 0},
                                {-L, L, L}};
    size_t found = 0;
    for (size_t a = 0; a < sizeof shifts / sizeof *shifts; a++) {
        const nbep_vec3 sh = {shifts[a][0], shifts[a][1], shifts[a][2]};
        memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
        for (size_t i = 0; i < n; i++) {
            f->n_got = 0;
            (void)nbep_bvh_query_later_shifted(f->b, &f->s, i, sh, collect, f);
            for (size_t k = 0; k < f->n_got; k++) {
                const uint32_t j = f->got[k];
                if (!(j > i && j < n) || f->stamp[j] == i + 1)
                    fail_msg("shifted query %zu reported %u out of (i, n) or twice", i, (unsigned)j);
                f->stamp[j] = (uint32_t)(i + 1);
            }
            const nbep_vec3 c = nbep_vec3_add(f->s.pos[i], sh);
            for (size_t j = i + 1; j < n; j++) {
                const double *pc = &c.x, *pj = &f->s.pos[j].x;
                const double rs = f->s.radius[i] + f->s.radius[j];
                bool touch = true, far = false;
                for (int ax = 0; ax < 3; ax++) {
                    const double gap = fabs(pc[ax] - pj[ax]) - rs;
                    touch &= gap <= 0.0;
                    far |= gap > 1e-12; /* past the query's few roundings */
                }
                const bool reported = f->stamp[j] == i + 1;
                if (touch && !reported)
                    fail_msg("shift %zu: copy of %zu touches %zu, not reported", a, i, j);
                if (far && reported)
                    fail_msg("shift %zu: copy of %zu reported %zu, whose box it misses", a, i, j);
                found += reported;
            }
        }
    }
    fprintf(stderr, "# %zu pairs of a copy and a sphere\n", found);
    assert_true(found > n / 10); /* spheres near the faces have partners across them */
}

static void test_rebuilding_after_spheres_move_reports_the_new_pairs(void **state)
{
    fixture *f = *state;
    size_t n_max = scaled(1500, 200);
    make_random_scene(f, n_max, 3);
    build(f, n_max);
    compare_with_double_loop(f);
    /* The same object, a fewer spheres somewhere else: nothing from the last build remains. */
    make_random_scene(f, n_max * 2 / 3, 4);
    for (size_t i = 0; i < f->s.n; i++)
        f->s.pos[i] = nbep_vec3_add(f->s.pos[i], nbep_vec3_make(-40.5, 3.25, 1024.0));
    build(f, n_max);
    compare_with_double_loop(f);
    /* Then back to the full size with the spheres scattered within the same box. */
    make_random_scene(f, n_max, 5);
    build(f, n_max);
    compare_with_double_loop(f);
}

/* ---- small and degenerate scenes -------------------------------------------------------- */

static void test_one_sphere_has_no_partner(void **state)
{
    fixture *f = *state;
    new_scene(f, 1);
    f->s.pos[0] = nbep_vec3_make(3.17, -1.43, 0.5);
    f->s.radius[0] = 0.25;
    build(f, 1);
    assert_int_equal(nbep_bvh_node_count(f->b), 1);
    assert_int_equal(nbep_bvh_depth(f->b), 0);
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    assert_int_equal(query(f, 0), 1);
    assert_int_equal(f->n_got, 0);
}

static void test_an_empty_scene_builds_an_empty_tree(void **state)
{
    fixture *f = *state;
    new_scene(f, 0);
    build(f, 4);
    assert_int_equal(nbep_bvh_node_count(f->b), 0);
}

/* Two spheres r = 0.375 and 0.625 at a distance d along y: returns what query 0 reports. */
static size_t two_spheres_at(fixture *f, double d)
{
    new_scene(f, 2);
    f->s.pos[0] = nbep_vec3_make(1.5, -2.25, 0.75);
    f->s.pos[1] = nbep_vec3_make(1.5, -2.25 + d, 0.75);
    f->s.radius[0] = 0.375;
    f->s.radius[1] = 0.625;
    build(f, 2);
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    query(f, 1);
    assert_int_equal(f->n_got, 0);   /* sphere 1 has no later partner */
    query(f, 0);
    return f->n_got;
}

static void test_two_spheres_are_paired_when_touching_or_overlapping_only(void **state)
{
    fixture *f = *state;
    assert_int_equal(two_spheres_at(f, 1.0), 1);          /* touching: 0.375 + 0.625 */
    assert_int_equal(f->got[0], 1);
    assert_int_equal(two_spheres_at(f, -1.0), 1);         /* touching from the other side */
    assert_int_equal(two_spheres_at(f, 0.4375), 1);       /* overlapping */
    assert_int_equal(two_spheres_at(f, 0.0), 1);          /* concentric */
    assert_int_equal(two_spheres_at(f, 1.0 + 0x1.0p-40), 0);   /* a hair apart */
    assert_int_equal(two_spheres_at(f, 3.17), 0);         /* apart */
}

static void test_two_spheres_touching_diagonally_are_paired(void **state)
{
    fixture *f = *state;
    /* dp = (0.75, 1.0, 0), |dp| = 1.25 = 0.5 + 0.75 (a 3-4-5 triangle): touching exactly, in a
     * direction where the boxes overlap deeply; the filter passes it, the sphere test agrees. */
    new_scene(f, 2);
    f->s.pos[0] = nbep_vec3_make(-0.5, 0.25, 2.0);
    f->s.pos[1] = nbep_vec3_make(-0.5 + 0.75, 0.25 + 1.0, 2.0);
    f->s.radius[0] = 0.5;
    f->s.radius[1] = 0.75;
    build(f, 2);
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    query(f, 0);
    assert_int_equal(f->n_got, 1);
    assert_true(spheres_overlap(&f->s, 0, 1));   /* touching exactly: |dp| = 1.25 */
}

static void test_spheres_at_one_point_pair_with_every_later_sphere(void **state)
{
    fixture *f = *state;
    size_t n = scaled(257, 67);
    new_scene(f, n);
    for (size_t i = 0; i < n; i++) {
        f->s.pos[i] = nbep_vec3_make(1.25, -2.5, 3.75);
        f->s.radius[i] = 0.1 + 0.01 * (double)(i % 13);
    }
    build(f, n);
    /* Equal Morton codes are split at their median: a balanced tree. */
    assert_true(nbep_bvh_depth(f->b) <= (size_t)ceil(log2((double)n)));
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    for (size_t i = 0; i < n; i++) {
        query(f, i);
        assert_int_equal(f->n_got, n - 1 - i);
    }
}

/* n spheres of radius 0.4375 in a touching chain along direction (a, b, c) / len (integers), ids
 * shuffled along the chain; each must pair with exactly its later chain neighbours. */
static void chain_pairs_only_neighbours(fixture *f, size_t n, const int dir[4], uint64_t seed)
{
    new_scene(f, n);
    uint32_t *slot_of = malloc(n * sizeof *slot_of), *id_at = malloc(n * sizeof *id_at);
    assert_non_null(slot_of);
    assert_non_null(id_at);
    for (size_t k = 0; k < n; k++)
        id_at[k] = (uint32_t)k;
    uint64_t x = seed;
    for (size_t k = n - 1; k > 0; k--) {   /* Fisher-Yates */
        size_t m = (size_t)(rng_next(&x) % (k + 1));
        uint32_t t = id_at[k];
        id_at[k] = id_at[m];
        id_at[m] = t;
    }
    /* Spacing 2r = 0.875 = 7 * 0.125 = dir[3] * step: the components dir[a] * step are exact. */
    double step = 0.875 / dir[3];
    for (size_t k = 0; k < n; k++) {
        uint32_t id = id_at[k];
        slot_of[id] = (uint32_t)k;
        double t = step * (double)k;
        f->s.pos[id] = nbep_vec3_make(7.5 + dir[0] * t, -3.0 + dir[1] * t, 0.5 + dir[2] * t);
        f->s.radius[id] = 0.4375;
    }
    build(f, n);
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    for (size_t i = 0; i < n; i++) {
        query(f, i);
        size_t want = 0;
        for (int side = -1; side <= 1; side += 2) {
            size_t k = slot_of[i] + (size_t)(ptrdiff_t)side;
            if (k < n && id_at[k] > i) {
                want++;
                if (f->stamp[id_at[k]] != i + 1)
                    fail_msg("chain neighbour %u of %zu not reported", (unsigned)id_at[k], i);
                assert_true(spheres_overlap(&f->s, i, id_at[k]));   /* touching exactly */
            }
        }
        assert_int_equal(f->n_got, want);
    }
    free(slot_of);
    free(id_at);
}

static void test_spheres_on_an_axis_line_pair_with_their_neighbours_only(void **state)
{
    static const int along_x[4] = {1, 0, 0, 1};
    chain_pairs_only_neighbours(*state, scaled(600, 90), along_x, 11);
}

static void test_spheres_on_a_diagonal_line_pair_with_their_neighbours_only(void **state)
{
    /* Second neighbours are 2 * 0.875 * 6/7 = 1.5 apart along z, their boxes 1.5 - 0.875. */
    static const int along_diagonal[4] = {2, -3, 6, 7};
    chain_pairs_only_neighbours(*state, scaled(600, 90), along_diagonal, 12);
}

static void test_geometrically_shrinking_spacing_stays_within_the_depth_bound(void **state)
{
    fixture *f = *state;
    /* Centres at 1000 * 2^-k (1, 1, 1): each Morton split peels off one sphere until the cells
     * run out, the most unbalanced tree the codes allow; radii 500 * 2^-k make neighbours'
     * boxes touch (500 <= 750) while the spheres stay apart (866 > 750). */
    size_t n = scaled(300, 120);
    new_scene(f, n);
    for (size_t k = 0; k < n; k++) {
        double c = ldexp(1000.0, -(int)k);
        f->s.pos[k] = nbep_vec3_make(c, c, c);
        f->s.radius[k] = ldexp(500.0, -(int)k);
    }
    build(f, n);
    assert_true(nbep_bvh_depth(f->b) <= NBEP_BVH_MAX_DEPTH);
    assert_true(nbep_bvh_depth(f->b) > (size_t)ceil(log2((double)n)));   /* really unbalanced */
    assert_int_equal(compare_with_double_loop(f), 0);
}

/* ---- pruning, checker, errors ----------------------------------------------------------- */

static void test_the_last_sphere_examines_only_the_root(void **state)
{
    fixture *f = *state;
    size_t n = scaled(500, 60);
    make_random_scene(f, n, 8);
    build(f, n);
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    assert_int_equal(query(f, n - 1), 1);
    assert_int_equal(f->n_got, 0);
}

static void test_queries_on_a_sparse_lattice_examine_few_nodes(void **state)
{
    fixture *f = *state;
    size_t side = scaled(12, 6), n = side * side * side;
    new_scene(f, n);
    /* Spacing 1.0 > 2 r = 0.6: no two boxes touch. */
    for (size_t i = 0; i < n; i++) {
        f->s.pos[i] = nbep_vec3_make((double)(i % side), (double)(i / side % side),
                                     (double)(i / side / side));
        f->s.radius[i] = 0.3;
    }
    build(f, n);
    memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
    size_t examined = 0;
    for (size_t i = 0; i < n; i++) {
        examined += query(f, i);
        assert_int_equal(f->n_got, 0);
    }
    /* A scan would examine every node for every sphere; the tree must prune most of that. */
    assert_true(examined * 8 < nbep_bvh_node_count(f->b) * n);
}

/* A query on a lattice of spheres whose boxes touch nothing (spacing 1, radius 0.3) follows
 * one path down: the Morton splits cut space into aligned cells, so a sibling's box (the
 * exact union of the boxes in its cell) stays 0.4 away from the query's, and each level
 * examines the two children of the one node it descends from: at most 1 + 2 depth nodes, for
 * every sphere, whichever axes the lattice spans (codes that lost an axis, or whose cells
 * are coarser than the spacing, split space along the wrong lines and examine more). */
static void test_a_query_on_a_sparse_lattice_examines_one_path_down(void **state)
{
    fixture *f = *state;
    const size_t side = scaled(12, 6), flat = scaled(40, 12);
    const size_t shapes[][3] = {{side, side, side}, {flat, flat, 1}, {flat, 1, flat},
                                {1, flat, flat}};
    for (size_t k = 0; k < sizeof shapes / sizeof *shapes; k++) {
        const size_t nx = shapes[k][0], ny = shapes[k][1], n = nx * ny * shapes[k][2];
        new_scene(f, n);
        for (size_t i = 0; i < n; i++) {
            f->s.pos[i] = nbep_vec3_make((double)(i % nx), (double)(i / nx % ny),
                                         (double)(i / nx / ny));
            f->s.radius[i] = 0.3;
        }
        nbep_bvh_destroy(&f->b);
        build(f, n);
        const size_t bound = 1 + 2 * nbep_bvh_depth(f->b);
        memset(f->stamp, 0, f->cap_stamp * sizeof *f->stamp);
        for (size_t i = 0; i < n; i++) {
            const size_t examined = query(f, i);
            assert_int_equal(f->n_got, 0);
            if (examined > bound)
                fail_msg("lattice %zux%zux%zu: sphere %zu examined %zu nodes, more than 1 + 2 "
                         "depth = %zu",
                         nx, ny, shapes[k][2], i, examined, bound);
        }
    }
}

static void test_check_finds_a_tree_built_from_another_state(void **state)
{
    fixture *f = *state;
    size_t n = scaled(200, 40);
    make_random_scene(f, n, 9);
    build(f, n);
    f->s.pos[n / 2].x += 0.5;
    assert_true(nbep_bvh_check(f->b, &f->s, &f->d) > 0);
    assert_int_equal(f->d.n_errors, 1);
    assert_non_null(strstr(f->d.msg[0], "differs from its state"));
}

static void test_create_refuses_more_spheres_than_it_can_index(void **state)
{
    fixture *f = *state;
    char sentinel_object;
    nbep_bvh *const sentinel = (nbep_bvh *)(void *)&sentinel_object;
    nbep_bvh *b = sentinel;   /* must stay untouched on failure */
    assert_int_equal(nbep_bvh_create(NBEP_BVH_MAX_SPHERES + 1, &b, &f->d), NBEP_EUSAGE);
    assert_ptr_equal(b, sentinel);
    assert_int_equal(f->d.n_errors, 1);
    assert_non_null(strstr(f->d.msg[0], "more than the BVH holds"));
}

/* ---- threads ---------------------------------------------------------------------------- */

typedef struct query_job {
    const nbep_bvh *b;
    const nbep_state *s;
    uint64_t *count, *sum;   /* per sphere: how many j and their sum; owned by this job */
} query_job;

static void tally(void *ctx, uint32_t j)
{
    uint64_t *acc = ctx;   /* acc[0] counts, acc[1] sums */
    acc[0]++;
    acc[1] += j;
}

static void *query_all(void *arg)
{
    query_job *job = arg;
    for (size_t i = 0; i < job->s->n; i++) {
        uint64_t acc[2] = {0, 0};
        nbep_bvh_query_later(job->b, job->s, i, tally, acc);
        job->count[i] = acc[0];
        job->sum[i] = acc[1];
    }
    return NULL;
}

static void test_threads_querying_at_once_see_what_one_thread_sees(void **state)
{
    fixture *f = *state;
    enum { N_THREADS = 4 };
    size_t n = scaled(1500, 150);
    make_random_scene(f, n, 10);
    build(f, n);
    query_job jobs[N_THREADS + 1];
    uint64_t *mem = calloc(2 * n * (N_THREADS + 1), sizeof *mem);
    assert_non_null(mem);
    for (int t = 0; t <= N_THREADS; t++)
        jobs[t] = (query_job){f->b, &f->s, mem + 2 * n * (size_t)t, mem + 2 * n * (size_t)t + n};
    query_all(&jobs[N_THREADS]);   /* the serial reference */
    pthread_t tid[N_THREADS];
    int started = 0;
    for (; started < N_THREADS; started++)
        if (pthread_create(&tid[started], NULL, query_all, &jobs[started]) != 0)
            break;
    for (int t = 0; t < started; t++)
        pthread_join(tid[t], NULL);
    bool same = started == N_THREADS;
    for (int t = 0; t < started; t++)
        same = same && memcmp(jobs[t].count, jobs[N_THREADS].count, 2 * n * sizeof *mem) == 0;
    free(mem);
    assert_true(same);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_setup_teardown(
            test_random_scenes_report_exactly_the_pairs_of_the_double_loop, setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_rebuilding_after_spheres_move_reports_the_new_pairs, setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_a_shifted_query_pairs_with_the_boxes_its_copy_touches, setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_a_shifted_query_reports_a_box_its_copy_touches_exactly, setup, teardown),
        cmocka_unit_test_setup_teardown(test_one_sphere_has_no_partner, setup, teardown),
        cmocka_unit_test_setup_teardown(test_an_empty_scene_builds_an_empty_tree, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(
            test_two_spheres_are_paired_when_touching_or_overlapping_only, setup, teardown),
        cmocka_unit_test_setup_teardown(test_two_spheres_touching_diagonally_are_paired, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(
            test_spheres_at_one_point_pair_with_every_later_sphere, setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_spheres_on_an_axis_line_pair_with_their_neighbours_only, setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_spheres_on_a_diagonal_line_pair_with_their_neighbours_only, setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_geometrically_shrinking_spacing_stays_within_the_depth_bound, setup, teardown),
        cmocka_unit_test_setup_teardown(test_the_last_sphere_examines_only_the_root, setup,
                                        teardown),
        cmocka_unit_test_setup_teardown(test_queries_on_a_sparse_lattice_examine_few_nodes,
                                        setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_a_query_on_a_sparse_lattice_examines_one_path_down, setup, teardown),
        cmocka_unit_test_setup_teardown(test_check_finds_a_tree_built_from_another_state,
                                        setup, teardown),
        cmocka_unit_test_setup_teardown(test_create_refuses_more_spheres_than_it_can_index,
                                        setup, teardown),
        cmocka_unit_test_setup_teardown(
            test_threads_querying_at_once_see_what_one_thread_sees, setup, teardown),
    };
    return cmocka_run_group_tests_name("bvh", tests, NULL, NULL);
}
