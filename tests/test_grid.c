/* Tests of the uniform cell grid (grid.h): the build in parts, as threads share it in grid mode,
 * gives the serial build's arrays bit for bit for any split; every sphere is listed once, in the
 * cell of its centre, ids ascending within a cell; a block query finds every centre within its
 * reach (against a brute-force search). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/grid.h"
#include "nbep_test.h"
#include "nbep_test_watchdog.h"

static uint64_t lcg(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return *x >> 11;
}

static double unit(uint64_t *x)
{
    return (double)lcg(x) * 0x1p-53;
}

/* n centres: a uniform cloud and a dense clump (cells of very different fill). */
static nbep_vec3 *centres(size_t n, uint64_t seed)
{
    nbep_vec3 *p = malloc(n * sizeof *p);
    assert_non_null(p);
    for (size_t i = 0; i < n; i++) {
        double s = i % 3 == 0 ? 0.05 : 1.0;
        p[i] = nbep_vec3_make(s * unit(&seed) - 0.3, s * 2.0 * unit(&seed), s * unit(&seed) + 4);
    }
    return p;
}

static nbep_grid make(size_t n)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_grid g;
    assert_int_equal(nbep_grid_init(&g, n, &d), NBEP_OK);
    nbep_diag_fini(&d);
    return g;
}

/* The phases of grid.h run for `parts` threads one after another (each phase for every part
 * before the next phase: what the barriers give). */
static void build_in_parts(nbep_grid *g, const nbep_vec3 *pos, size_t n, double h, int parts)
{
    nbep_vec3 lo = {INFINITY, INFINITY, INFINITY}, hi = {-INFINITY, -INFINITY, -INFINITY};
    for (int t = 0; t < parts; t++) {
        nbep_vec3 l, u;
        nbep_grid_bounds(pos, n * (size_t)t / (size_t)parts, n * (size_t)(t + 1) / (size_t)parts,
                         &l, &u);
        lo = nbep_vec3_make(fmin(lo.x, l.x), fmin(lo.y, l.y), fmin(lo.z, l.z));
        hi = nbep_vec3_make(fmax(hi.x, u.x), fmax(hi.y, u.y), fmax(hi.z, u.z));
    }
    nbep_grid_size(g, lo, hi, n, h);
    for (int t = 0; t < parts; t++)
        nbep_grid_assign(g, pos, n * (size_t)t / (size_t)parts,
                         n * (size_t)(t + 1) / (size_t)parts);
    const size_t cells = nbep_grid_cells(g);
    size_t sums[16];
    for (int t = 0; t < parts; t++)
        sums[t] = nbep_grid_count(g, cells * (size_t)t / (size_t)parts,
                                  cells * (size_t)(t + 1) / (size_t)parts);
    size_t offset = 0;
    for (int t = 0; t < parts; t++) {
        nbep_grid_place(g, cells * (size_t)t / (size_t)parts,
                        cells * (size_t)(t + 1) / (size_t)parts, offset);
        offset += sums[t];
    }
}

static void test_a_build_in_parts_equals_the_serial_build_for_any_split(void **state)
{
    (void)state;
    enum { N = 5000 };
    nbep_vec3 *pos = centres(N, 3);
    nbep_grid a = make(N);
    nbep_grid_build(&a, pos, N, 0.04);
    const size_t cells = nbep_grid_cells(&a);
    assert_true(cells > 100);
    for (int parts = 1; parts <= 16; parts += parts < 4 ? 1 : 5) {
        nbep_grid b = make(N);
        build_in_parts(&b, pos, N, 0.04, parts);
        assert_int_equal(nbep_grid_cells(&b), cells);
        assert_true(a.h == b.h && nbep_vec3_equal(a.lo, b.lo));
        assert_memory_equal(a.start, b.start, (cells + 1) * sizeof *a.start);
        assert_memory_equal(a.item, b.item, N * sizeof *a.item);
        assert_memory_equal(a.cell, b.cell, N * sizeof *a.cell);
        nbep_grid_fini(&b);
    }
    nbep_grid_fini(&a);
    free(pos);
}

static void test_every_centre_is_listed_once_in_its_cell_and_found_by_block_queries(void **state)
{
    (void)state;
    enum { N = 3000 };
    nbep_vec3 *pos = centres(N, 9);
    nbep_grid g = make(N);
    build_in_parts(&g, pos, N, 0.1, 3);
    const size_t cells = nbep_grid_cells(&g);
    unsigned char *seen = calloc(N, 1);
    assert_non_null(seen);
    assert_int_equal(g.start[0], 0);
    assert_int_equal(g.start[cells], N);
    for (size_t c = 0; c < cells; c++) {
        for (uint32_t k = g.start[c]; k < g.start[c + 1]; k++) {
            const uint32_t i = g.item[k];
            assert_true(i < N && !seen[i]);
            seen[i] = 1;
            assert_int_equal(g.cell[i], c);
            if (k > g.start[c])
                assert_true(g.item[k - 1] < i); /* ascending within a cell */
        }
    }
    for (size_t i = 0; i < N; i++)
        assert_true(seen[i]);
    /* every centre within the reach of a query point is in the block the grid names */
    uint64_t x = 77;
    for (int q = 0; q < 200; q++) {
        const nbep_vec3 p = pos[lcg(&x) % N];
        const double reach = 0.1 * (1 + q % 3);
        size_t lo[3], hi[3];
        nbep_grid_block(&g, p, reach, lo, hi);
        for (size_t j = 0; j < N; j++) {
            if (nbep_vec3_norm(nbep_vec3_sub(pos[j], p)) > reach)
                continue;
            const size_t c = g.cell[j];
            const size_t cx = c % g.dim[0], cy = c / g.dim[0] % g.dim[1],
                         cz = c / (g.dim[0] * g.dim[1]);
            assert_true(cx >= lo[0] && cx <= hi[0] && cy >= lo[1] && cy <= hi[1] &&
                        cz >= lo[2] && cz <= hi[2]);
        }
    }
    free(seen);
    nbep_grid_fini(&g);
    free(pos);
}

/* nbep_grid_bounds gives the corners of the centres of its range (the threads' parts are
 * joined into the grid's), leaving a NaN centre out; the grid's corner is the lower one, and
 * every centre lies in the box of the cell it is listed in (to within a rounding of the
 * division), so that a cell holds the centres of its own box. */
static void test_bounds_are_the_centres_corners_and_each_centre_lies_in_its_cell(void **state)
{
    (void)state;
    enum { N = 2000 };
    nbep_vec3 *pos = centres(N, 21);
    for (size_t parts = 1; parts <= 3; parts++)
        for (size_t t = 0; t < parts; t++) {
            const size_t a = N * t / parts, b = N * (t + 1) / parts;
            nbep_vec3 lo, hi;
            nbep_grid_bounds(pos, a, b, &lo, &hi);
            nbep_vec3 l = pos[a], h = pos[a];
            for (size_t i = a; i < b; i++) {
                l = nbep_vec3_make(fmin(l.x, pos[i].x), fmin(l.y, pos[i].y), fmin(l.z, pos[i].z));
                h = nbep_vec3_make(fmax(h.x, pos[i].x), fmax(h.y, pos[i].y), fmax(h.z, pos[i].z));
            }
            assert_true(nbep_vec3_equal(lo, l) && nbep_vec3_equal(hi, h));
        }
    const nbep_vec3 keep = pos[5];
    pos[5].y = NAN;
    nbep_vec3 lo, hi;
    nbep_grid_bounds(pos, 0, N, &lo, &hi);
    assert_true(isfinite(lo.y) && isfinite(hi.y));
    pos[5] = keep;
    nbep_grid g = make(N);
    nbep_grid_build(&g, pos, N, 0.05);
    nbep_grid_bounds(pos, 0, N, &lo, &hi);
    assert_true(nbep_vec3_equal(g.lo, lo));
    const double o[3] = {g.lo.x, g.lo.y, g.lo.z}, eps = 1e-12 * g.h;
    for (size_t i = 0; i < N; i++) {
        const size_t c = g.cell[i];
        const size_t xyz[3] = {c % g.dim[0], c / g.dim[0] % g.dim[1], c / (g.dim[0] * g.dim[1])};
        const double x[3] = {pos[i].x, pos[i].y, pos[i].z};
        for (int k = 0; k < 3; k++) {
            assert_true(x[k] >= o[k] + (double)xyz[k] * g.h - eps);
            assert_true(x[k] <= o[k] + (double)(xyz[k] + 1) * g.h + eps);
        }
    }
    nbep_grid_fini(&g);
    free(pos);
}

/* A grid built again over other centres (grid mode builds one every step) is the grid a fresh
 * one builds over them: nothing of the last build's counts or cells is left. */
static void test_a_rebuild_is_a_fresh_build(void **state)
{
    (void)state;
    enum { N = 3000 };
    nbep_vec3 *a = centres(N, 31), *b = centres(N, 32);
    nbep_grid g = make(N), fresh = make(N);
    nbep_grid_build(&g, a, N, 0.04);
    build_in_parts(&g, b, N, 0.04, 3);
    nbep_grid_build(&fresh, b, N, 0.04);
    const size_t cells = nbep_grid_cells(&fresh);
    assert_int_equal(nbep_grid_cells(&g), cells);
    assert_memory_equal(g.start, fresh.start, (cells + 1) * sizeof *g.start);
    assert_memory_equal(g.item, fresh.item, N * sizeof *g.item);
    nbep_grid_fini(&g);
    nbep_grid_fini(&fresh);
    free(a);
    free(b);
}

/* The cells never outnumber the room (2 n + 8), for clouds sparse in one, two or three
 * dimensions with cells asked far smaller than the spacing; and a block query, about any
 * point and of any reach, names cells of the grid only (clamped at its faces), its lower
 * corner at or below its upper one. */
static void test_cells_fit_the_room_and_blocks_stay_in_the_grid(void **state)
{
    (void)state;
    const size_t ns[] = {1, 7, 50, 500};
    uint64_t x = 41;
    for (size_t a = 0; a < sizeof ns / sizeof *ns; a++)
        for (int shape = 0; shape < 4; shape++) {
            const size_t n = ns[a];
            nbep_vec3 *p = malloc(n * sizeof *p);
            assert_non_null(p);
            for (size_t i = 0; i < n; i++)
                p[i] = nbep_vec3_make(100.0 * unit(&x), shape > 0 ? 37.0 * unit(&x) : 1.0,
                                      shape > 1 ? 13.0 * unit(&x) : shape == 0 ? 2.0 : 0.5);
            nbep_grid g = make(n);
            nbep_grid_build(&g, p, n, 1e-3);
            assert_true(nbep_grid_cells(&g) <= g.cap_cells);
            for (int q = 0; q < 50; q++) {
                const nbep_vec3 c = nbep_vec3_make(130.0 * unit(&x) - 15.0,
                                                   50.0 * unit(&x) - 6.0, 20.0 * unit(&x) - 3.0);
                const double reach = q % 2 ? g.h * unit(&x) : 3.0 * unit(&x);
                size_t lo[3], hi[3];
                nbep_grid_block(&g, q < 5 ? p[q % n] : c, reach, lo, hi);
                for (int k = 0; k < 3; k++)
                    assert_true(lo[k] <= hi[k] && hi[k] < g.dim[k]);
            }
            nbep_grid_fini(&g);
            free(p);
        }
}

/* Cells no coarser than the room asks: centres along one axis (no volume, so the room alone
 * widens the cells) get the first doubling of the side asked whose cells fit 2 n + 8, not a
 * later one: the side decides grid mode's blocks (its predictions) and its horizon. */
static void test_a_line_of_centres_gets_the_finest_doubling_that_fits(void **state)
{
    (void)state;
    const size_t ns[] = {1, 2, 10, 50};
    const double lens[] = {3.0, 49.5, 100.0, 1000.0, 12345.0};
    for (size_t a = 0; a < sizeof ns / sizeof *ns; a++)
        for (size_t b = 0; b < sizeof lens / sizeof *lens; b++)
            for (int axis = 0; axis < 3; axis++) {
                const size_t n = ns[a];
                nbep_vec3 *p = malloc(n * sizeof *p);
                assert_non_null(p);
                double len = 0.0; /* the centres' extent along the axis */
                for (size_t i = 0; i < n; i++) {
                    const double t = n > 1 ? lens[b] * (double)i / (double)(n - 1) : 0.0;
                    p[i] = nbep_vec3_make(axis == 0 ? t : 0.5, axis == 1 ? t : -2.0,
                                          axis == 2 ? t : 7.0);
                    len = fmax(len, t);
                }
                nbep_grid g = make(n);
                nbep_grid_build(&g, p, n, 1.0);
                double want = 1.0;
                while (floor(len / want) + 1.0 > (double)g.cap_cells)
                    want *= 2.0;
                if (g.h != want)
                    fail_msg("%zu centres over %g along axis %d: cells of %g, want %g", n, len,
                             axis, g.h, want);
                for (int k = 0; k < 3; k++)
                    assert_int_equal(g.dim[k], k == axis ? (size_t)(floor(len / want) + 1.0) : 1);
                nbep_grid_fini(&g);
                free(p);
            }
}

/* A cell size that is none (0, negative, infinite: the caller's 2 rmax of a scene without
 * spheres) is taken as 1: a unit box in cells of 1, and an empty grid (no centre, bounds the
 * wrong way round) one cell of 1. Taken as given (a mutant of the seed-14 draw), 0 would never
 * end the sizing of an empty grid (a grid-mode run of a deck with no spheres spun, deaf to
 * SIGTERM: the watchdog fails it), infinity would make one cell of h = inf, and -0.5 cells past
 * counting. */
static void test_a_cell_size_that_is_none_is_taken_as_one(void **state)
{
    (void)state;
    nbep_test_watchdog_arm(10, "test_grid: sizing a grid did not end in 10 s\n");
    nbep_grid g = make(4);
    const nbep_vec3 lo = {0, 0, 0}, hi = {1, 1, 1};
    const double none[] = {0.0, -0.5, INFINITY, NAN};
    for (size_t k = 0; k < sizeof none / sizeof none[0]; k++) {
        nbep_grid_size(&g, lo, hi, 4, none[k]);
        assert_true(g.h == 1.0);
        assert_int_equal(g.dim[0], 2);
        assert_int_equal(g.dim[1], 2);
        assert_int_equal(g.dim[2], 2);
    }
    const nbep_vec3 empty_lo = {INFINITY, INFINITY, INFINITY};
    const nbep_vec3 empty_hi = {-INFINITY, -INFINITY, -INFINITY};
    nbep_grid_size(&g, empty_lo, empty_hi, 0, 0.0);
    assert_true(g.h == 1.0);
    assert_int_equal(nbep_grid_cells(&g), 1);
    nbep_test_watchdog_disarm();
    nbep_grid_fini(&g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_build_in_parts_equals_the_serial_build_for_any_split),
        cmocka_unit_test(test_every_centre_is_listed_once_in_its_cell_and_found_by_block_queries),
        cmocka_unit_test(test_bounds_are_the_centres_corners_and_each_centre_lies_in_its_cell),
        cmocka_unit_test(test_a_rebuild_is_a_fresh_build),
        cmocka_unit_test(test_cells_fit_the_room_and_blocks_stay_in_the_grid),
        cmocka_unit_test(test_a_line_of_centres_gets_the_finest_doubling_that_fits),
        cmocka_unit_test(test_a_cell_size_that_is_none_is_taken_as_one),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
