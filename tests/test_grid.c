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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_build_in_parts_equals_the_serial_build_for_any_split),
        cmocka_unit_test(test_every_centre_is_listed_once_in_its_cell_and_found_by_block_queries),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
