/* Tests of the cell lists: geometry (as many cells as fit with sides of at least the reach,
 * cells bounded), a build in two ranges on two threads equal to one serial build, and, along
 * straight flights whose spheres are placed at their centres at each sample (as the engine
 * places a list's centre at each rebuild), the two properties the engine relies on: every
 * place lies in its cell, and every two places within reach are in the same or adjacent
 * cells. Periodic axes: blocks wrap with the period of each neighbour, and there are three
 * cells at least. A layout fitted afresh to a new region (nbep_cells_refit) is the one a fresh
 * init makes; a member placed at a point of another cell moves there. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/cells.h"
#include "nbep_test.h"

static double unit(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*x >> 11) / 9007199254740992.0;
}

static void init_cells(nbep_cells *g, nbep_vec3 lo, nbep_vec3 hi, double reach, size_t n)
{
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_cells_init(g, lo, hi, reach, n, NULL, &d), NBEP_OK);
    nbep_diag_fini(&d);
}

static void test_geometry_sides_at_least_reach_and_cells_bounded(void **state)
{
    (void)state;
    nbep_cells g;
    init_cells(&g, (nbep_vec3){-1, 0, 0}, (nbep_vec3){9, 4.5, 0.5}, 1.0, 1000);
    assert_int_equal(g.dim[0], 10); /* 10 / 1 = 10 exactly: a side may be the reach itself */
    assert_int_equal(g.dim[1], 4);  /* 4.5 / 1 = 4.5: four, of 1.125 */
    assert_int_equal(g.dim[2], 1);  /* thinner than the reach: one */
    assert_true(g.h[0] == 1.0 && g.h[1] == 1.125 && g.h[2] == 0.5);
    nbep_cells_fini(&g);
    /* the same sides with the box off 0 on every axis, above it and below: the layout is of
     * the sides alone (a draw's mutant read hi.z + lo.z for z's, which every box with its low
     * z at 0 hid; such a periodic box overlapped spheres by 1.5 diameters) */
    const nbep_vec3 lows[2] = {{-1, 2, 3}, {-11, -7, -1}};
    for (int b = 0; b < 2; b++) {
        const nbep_vec3 lo = lows[b], hi = {lo.x + 10, lo.y + 4.5, lo.z + 0.5};
        init_cells(&g, lo, hi, 1.0, 1000);
        assert_int_equal(g.dim[0], 10);
        assert_int_equal(g.dim[1], 4);
        assert_int_equal(g.dim[2], 1);
        assert_true(g.h[0] == 1.0 && g.h[1] == 1.125 && g.h[2] == 0.5);
        nbep_cells_fini(&g);
    }
    /* just short of ten reaches: nine cells, as ten would be 0.999 wide, below the reach */
    init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){9.99, 1, 1}, 1.0, 1000);
    assert_int_equal(g.dim[0], 9);
    assert_true(g.h[0] >= 1.0);
    nbep_cells_fini(&g);
    /* a huge sparse box: cells capped at 2n + 8 = 28. Sides double from the reach, the axis
     * with the most cells first (x on a tie): at 128 on every axis 7^3 = 343 cells (1000 / 128
     * = 7.8); x at 256 (3.9: 3), 3 * 7 * 7 = 147; y, 63; z, 27, which fit: three per axis */
    init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){1e3, 1e3, 1e3}, 1.0, 10);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(g.dim[k], 3);
        assert_close(g.h[k], 1e3 / 3.0, 1e-15, 0.0);
    }
    nbep_cells_fini(&g);
    nbep_cells_fini(&g); /* safe twice */
    /* a region stretched along x (a scene without a box, one sphere flown far off) and too
     * long for cells of the reach everywhere (cap 2008): the axis with the most cells gives way
     * first. x's side doubles while x has the most: at 512, 19 (1e4 / 512 = 19.5) * 20 * 20 =
     * 7600; then y's 20 are the most, at side 2 19 * 10 * 20 = 3800; then z's, 19 * 10 * 10 =
     * 1900, which fit. So y and z keep cells of twice the reach (20 would be the reach's),
     * where growing every side alike left them one cell each */
    init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){1e4, 20, 20}, 1.0, 1000);
    assert_int_equal(g.dim[0], 19);
    assert_int_equal(g.dim[1], 10);
    assert_int_equal(g.dim[2], 10);
    nbep_cells_fini(&g);
    /* no spheres, so no reach: one cell, and init returns */
    init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){1, 1, 1}, 0.0, 0);
    assert_int_equal(g.n_cells, 1);
    nbep_cells_link(&g);
    nbep_cells_fini(&g);
}

static void test_a_build_in_two_ranges_on_two_threads_equals_a_serial_one(void **state)
{
    (void)state;
    enum { N = 5000 };
    nbep_vec3 *pos = malloc(N * sizeof *pos);
    uint64_t x = 7;
    for (size_t i = 0; i < N; i++)
        pos[i] = (nbep_vec3){20 * unit(&x), 20 * unit(&x), 20 * unit(&x)};
    nbep_cells a, b;
    init_cells(&a, (nbep_vec3){0, 0, 0}, (nbep_vec3){20, 20, 20}, 1.0, N);
    init_cells(&b, (nbep_vec3){0, 0, 0}, (nbep_vec3){20, 20, 20}, 1.0, N);
    nbep_cells_assign(&a, pos, 0, N);
    nbep_cells_link(&a);
    /* (a serial build runs the two ranges one after the other) */
#pragma omp parallel for num_threads(2) schedule(static, 1)
    for (int t = 0; t < 2; t++)
        nbep_cells_assign(&b, pos, t ? N / 3 : 0, t ? N : N / 3);
    nbep_cells_link(&b);
    assert_memory_equal(a.head, b.head, a.n_cells * sizeof *a.head);
    for (size_t i = 0; i < N; i++) { /* the same cells, links and places */
        assert_int_equal(a.m[i].cell, b.m[i].cell);
        assert_int_equal(a.m[i].next, b.m[i].next);
        assert_true(nbep_vec3_equal(a.m[i].at, pos[i]) && nbep_vec3_equal(b.m[i].at, pos[i]));
    }
    assert_int_equal(nbep_cells_check(&a), 0);
    /* ids ascend within a list */
    for (size_t c = 0; c < a.n_cells; c++)
        for (uint32_t i = a.head[c]; i != NBEP_CELLS_NONE && a.m[i].next != NBEP_CELLS_NONE;
             i = a.m[i].next)
            assert_true(a.m[i].next > i);
    nbep_cells_fini(&a);
    nbep_cells_fini(&b);
    free(pos);
}

/* A layout fitted afresh (a scene without a box, at each rebuild): the geometry a fresh init
 * over the new region would have, room for more cells when it needs them (a small region
 * first, then one with many more cells), and a build over it that keeps the invariant, with
 * spheres outside the region clamped into its edge cells. */
static void test_refit_lays_the_cells_out_as_a_fresh_init_would(void **state)
{
    (void)state;
    enum { N = 2000 };
    nbep_vec3 *pos = malloc(N * sizeof *pos);
    uint64_t x = 11;
    for (size_t i = 0; i < N; i++) /* a quarter of them outside [0, 12]^3 */
        pos[i] = (nbep_vec3){15 * unit(&x) - 1.5, 15 * unit(&x) - 1.5, 12 * unit(&x)};
    nbep_cells g, fresh;
    init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){2, 3, 2}, 1.0, N);
    assert_int_equal(g.n_cells, 2 * 3 * 2); /* sides of the reach 1 */
    const nbep_vec3 lo = {0, 0, 0}, hi = {12, 12, 12};
    nbep_diag d;
    nbep_diag_init(&d);
    assert_int_equal(nbep_cells_refit(&g, lo, hi, 1.0, &d), NBEP_OK);
    nbep_diag_fini(&d);
    init_cells(&fresh, lo, hi, 1.0, N);
    assert_int_equal(g.n_cells, fresh.n_cells);
    assert_true(g.n_cells == 12 * 12 * 12); /* 12 / 1 = 12 */
    assert_true(g.cap_cells >= g.n_cells);
    for (int k = 0; k < 3; k++) {
        assert_int_equal(g.dim[k], fresh.dim[k]);
        assert_true(g.h[k] == fresh.h[k]);
    }
    assert_true(nbep_vec3_equal(g.lo, lo) && nbep_vec3_equal(g.hi, hi));
    nbep_cells_assign(&g, pos, 0, N);
    nbep_cells_link(&g);
    nbep_cells_assign(&fresh, pos, 0, N);
    nbep_cells_link(&fresh);
    assert_memory_equal(g.head, fresh.head, g.n_cells * sizeof *g.head);
    assert_int_equal(nbep_cells_check(&g), 0);
    /* outside along x: in the edge cells */
    for (size_t i = 0; i < N; i++)
        if (pos[i].x < 0.0 || pos[i].x > 12.0)
            assert_int_equal(g.m[i].cell % g.dim[0], pos[i].x < 0.0 ? 0 : g.dim[0] - 1);
    nbep_cells_fini(&g);
    nbep_cells_fini(&fresh);
    free(pos);
}

typedef struct flight {
    nbep_vec3 p0, v, a;
} flight;

static nbep_vec3 at(const flight *f, double t)
{
    return nbep_vec3_axpy(nbep_vec3_axpy(f->p0, t, f->v), 0.5 * t * t, f->a);
}

/* Cell cb is in the block of cell ca. */
static bool in_block(const nbep_cells *g, size_t ca, size_t cb)
{
    nbep_cells_block b;
    nbep_cells_block_of(g, ca, &b);
    const size_t xyz[3] = {cb % g->dim[0], cb / g->dim[0] % g->dim[1],
                           cb / (g->dim[0] * g->dim[1])};
    for (int k = 0; k < 3; k++) {
        bool found = false;
        for (int m = 0; m < b.cnt[k]; m++)
            found = found || b.idx[k][m] == xyz[k];
        if (!found)
            return false;
    }
    return true;
}

/* Spheres flying straight (some grazing along a face, no velocity across it; many leave the
 * box, clamped into its edge cells), in pairs that fly together a hair short of the reach
 * apart along one axis, placed at their centres at each sample as the engine places a list's
 * centre at each rebuild: every place lies in its cell's slab (no gap along any axis,
 * nbep_cells_gap2), and every two places within reach are in the same or adjacent cells. The
 * box, 6.95 long, holds six cells 1.158 wide per axis (216 in all, within the cap 2N + 8):
 * cells only a little narrower than the reach would put some pairs two apart. */
static void test_placed_flights_keep_places_in_their_cells_and_contacts_adjacent(void **state)
{
    (void)state;
    enum { N = 300, SAMPLES = 200 };
    const double L = 6.95, reach = 1.0, T = 20.0;
    flight *f = malloc(N * sizeof *f);
    nbep_vec3 *pos = malloc(N * sizeof *pos);
    uint64_t x = 5;
    for (size_t i = 0; i < N; i += 2) {
        f[i].p0 = (nbep_vec3){L * unit(&x), L * unit(&x), L * unit(&x)};
        f[i].v = (nbep_vec3){unit(&x) - 0.5, unit(&x) - 0.5, unit(&x) - 0.5};
        if (i % 17 == 0)
            f[i].v.x = 0.0;
        f[i].a = (nbep_vec3){0};
        f[i + 1] = f[i];
        const double d = reach * (1.0 - 1e-9);
        const int k = (int)(i / 2 % 3);
        f[i + 1].p0 = nbep_vec3_add(f[i].p0, (nbep_vec3){k == 0 ? d : 0, k == 1 ? d : 0,
                                                           k == 2 ? d : 0});
    }
    for (size_t i = 0; i < N; i++)
        pos[i] = f[i].p0;
    nbep_cells g;
    init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){L, L, L}, reach, N);
    assert_int_equal(g.n_cells, 6 * 6 * 6);
    nbep_cells_assign(&g, pos, 0, N);
    nbep_cells_link(&g);
    size_t moves = 0;
    for (int s = 1; s <= SAMPLES; s++) {
        const double ts = T * s / SAMPLES;
        for (uint32_t i = 0; i < N; i++) {
            pos[i] = at(&f[i], ts);
            const size_t c = nbep_cells_locate(&g, pos[i]);
            moves += c != g.m[i].cell;
            nbep_cells_place(&g, i, pos[i], c);
        }
        assert_int_equal(nbep_cells_check(&g), 0);
        for (size_t i = 0; i < N; i++) {
            const size_t c = g.m[i].cell, xyz[3] = {c % g.dim[0], c / g.dim[0] % g.dim[1],
                                                    c / (g.dim[0] * g.dim[1])};
            const double p[3] = {pos[i].x, pos[i].y, pos[i].z};
            for (int k = 0; k < 3; k++)
                assert_true(nbep_cells_gap2(&g, k, xyz[k], p[k]) == 0.0);
        }
        for (size_t a = 0; a < N; a++)
            for (size_t b = a + 1; b < N; b++) {
                if (nbep_vec3_norm(nbep_vec3_sub(pos[a], pos[b])) > reach)
                    continue;
                assert_true(in_block(&g, g.m[a].cell, g.m[b].cell));
            }
    }
    assert_true(moves > N); /* the flights did cross cells */
    nbep_cells_fini(&g);
    free(f);
    free(pos);
}

/* Periodic axes: at least three cells across (a sparse box would get fewer), the first and
 * last cells are neighbours with the period the neighbour lies in, while a wall axis keeps its
 * clamped block. */
static void test_periodic_axes_wrap_blocks(void **state)
{
    (void)state;
    const bool xz[3] = {true, false, true};
    nbep_cells g;
    nbep_diag d;
    nbep_diag_init(&d);
    /* 10 spheres: the cap (28 cells) leaves 3 per axis (the sides double from 1 to 256 on x and
     * y: 1000 / 256 = 3.9; 3 * 3 * 3 = 27, and 3 * 7 * 3 = 63 at 128 on y); the thin z axis
     * (3.4: three sides of 1 fit) keeps its three */
    assert_int_equal(
        nbep_cells_init(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){1e3, 1e3, 3.4}, 1.0, 10, xz, &d),
        NBEP_OK);
    nbep_diag_fini(&d);
    assert_true(g.dim[0] == 3 && g.dim[1] == 3 && g.dim[2] == 3);
    nbep_cells_block b;
    nbep_cells_block_of(&g, nbep_cells_index(&g, 0, 0, 0), &b);
    /* x: the last cell below (one period down), 0 and 1; y (walls): 0 and 1; z likewise x */
    assert_int_equal(b.cnt[0], 3);
    assert_true(b.idx[0][0] == g.dim[0] - 1 && b.per[0][0] == -1);
    assert_true(b.idx[0][1] == 0 && b.per[0][1] == 0 && b.idx[0][2] == 1 && b.per[0][2] == 0);
    assert_int_equal(b.cnt[1], 2);
    assert_true(b.idx[1][0] == 0 && b.idx[1][1] == 1 && b.per[1][0] == 0 && b.per[1][1] == 0);
    assert_int_equal(b.cnt[2], 3);
    nbep_cells_block_of(&g, nbep_cells_index(&g, g.dim[0] - 1, 0, 2), &b);
    assert_true(b.idx[0][2] == 0 && b.per[0][2] == 1);
    assert_true(b.idx[2][2] == 0 && b.per[2][2] == 1);
    nbep_cells_fini(&g);
    /* a box so sparse that the cap (2 n + 8 = 10 cells) would leave two cells or one along an
     * axis: every periodic axis still gets three, so that a cell's neighbours below and above
     * are two cells, each one copy away; the wall axis takes what the cap leaves */
    const bool all3[3] = {true, true, true}, xy[3] = {true, true, false};
    for (int walls = 0; walls < 2; walls++) {
        nbep_diag_init(&d);
        assert_int_equal(nbep_cells_init(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){40, 40, 40}, 1.0,
                                         1, walls ? xy : all3, &d),
                         NBEP_OK);
        nbep_diag_fini(&d);
        for (int k = 0; k < 3; k++) {
            if (walls && k == 2)
                continue;
            assert_int_equal(g.dim[k], 3);
            assert_close(g.h[k], 40.0 / 3.0, 1e-15, 0.0);
        }
        nbep_cells_block_of(&g, 0, &b);
        assert_int_equal(b.cnt[0], 3);
        assert_true(b.idx[0][0] == 2 && b.per[0][0] == -1 && b.idx[0][2] == 1);
        nbep_cells_fini(&g);
    }
}

/* A place is the point a member's cell was chosen by: placing a member at a point of another
 * cell moves it there (out of its old list, into the new one), at a point of its own cell
 * only the place changes; the lists stay whole either way, and a point at or past the box's
 * upper corner is in the last cell along each axis (clamped, as a point below the lower
 * corner is in the first). */
static void test_placing_a_member_moves_it_to_the_cell_of_its_place(void **state)
{
    (void)state;
    enum { N = 30 };
    nbep_cells g;
    init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){9, 9, 9}, 2.5, N);
    nbep_vec3 pos[N];
    uint64_t x = 3;
    for (size_t i = 0; i < N; i++)
        pos[i] = (nbep_vec3){9 * unit(&x), 9 * unit(&x), 9 * unit(&x)};
    nbep_cells_assign(&g, pos, 0, N);
    nbep_cells_link(&g);
    const size_t last = nbep_cells_index(&g, g.dim[0] - 1, g.dim[1] - 1, g.dim[2] - 1);
    assert_int_equal(nbep_cells_locate(&g, g.hi), last);
    assert_int_equal(nbep_cells_locate(&g, (nbep_vec3){9.5, 20.0, 9.0}), last);
    assert_int_equal(nbep_cells_locate(&g, (nbep_vec3){-1.0, -0.0, -3.0}), 0);
    for (int step = 0; step < 200; step++) {
        const uint32_t i = (uint32_t)(step % N);
        /* half the time a little way off (often the same cell), else anywhere in the box */
        const nbep_vec3 off = {unit(&x) - 0.5, unit(&x) - 0.5, unit(&x) - 0.5};
        const nbep_vec3 p = step % 2 ? (nbep_vec3){9 * unit(&x), 9 * unit(&x), 9 * unit(&x)}
                                     : nbep_vec3_axpy(pos[i], 0.3, off);
        const size_t c = nbep_cells_locate(&g, p);
        nbep_cells_place(&g, i, p, c);
        pos[i] = p;
        assert_int_equal(g.m[i].cell, c);
        assert_true(nbep_vec3_equal(g.m[i].at, p));
        bool listed = false;
        for (uint32_t j = g.head[c]; j != NBEP_CELLS_NONE; j = g.m[j].next)
            listed = listed || j == i;
        assert_true(listed);
        assert_int_equal(nbep_cells_check(&g), 0);
    }
    nbep_cells_fini(&g);
}

/* Sphere i taken out of its cell's list (the links around it joined), as a lost member. */
static void unlink_member(nbep_cells *g, uint32_t i)
{
    const uint32_t next = g->m[i].next, before = g->prev[i];
    if (before == NBEP_CELLS_NONE)
        g->head[g->m[i].cell] = next;
    else
        g->m[before].next = next;
    if (next != NBEP_CELLS_NONE)
        g->prev[next] = before;
}

/* The self-check counts each fault (the tests above rely on its 0): a member whose place lies
 * in another cell, one listed in no cell, both (2: each is counted, neither hides the other),
 * and a list whose backward link is broken. */
static void test_the_check_counts_each_fault(void **state)
{
    (void)state;
    enum { N = 27 };
    nbep_vec3 pos[N];
    for (size_t i = 0; i < N; i++) /* one a cell, at its centre */
        pos[i] = (nbep_vec3){0.5 + (double)(i % 3), 0.5 + (double)(i / 3 % 3),
                             0.5 + (double)(i / 9)};
    nbep_cells g;
    for (int fault = 0; fault < 4; fault++) {
        init_cells(&g, (nbep_vec3){0, 0, 0}, (nbep_vec3){3, 3, 3}, 1.0, N);
        assert_int_equal(g.n_cells, N);
        nbep_cells_assign(&g, pos, 0, N);
        nbep_cells_link(&g);
        assert_int_equal(nbep_cells_check(&g), 0);
        if (fault == 0 || fault == 2) /* sphere 4's place moved a cell along x */
            g.m[4].at.x += 1.0;
        if (fault == 1 || fault == 2) /* sphere 13 lost from its cell's list */
            unlink_member(&g, 13);
        if (fault == 3) /* sphere 20's backward link pointing at itself */
            g.prev[20] = 20;
        const size_t want = fault == 2 ? 2 : 1;
        if (nbep_cells_check(&g) != want)
            fail_msg("fault %d: the check counts %zu, want %zu", fault, nbep_cells_check(&g),
                     want);
        nbep_cells_fini(&g);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_geometry_sides_at_least_reach_and_cells_bounded),
        cmocka_unit_test(test_the_check_counts_each_fault),
        cmocka_unit_test(test_a_build_in_two_ranges_on_two_threads_equals_a_serial_one),
        cmocka_unit_test(test_refit_lays_the_cells_out_as_a_fresh_init_would),
        cmocka_unit_test(test_placed_flights_keep_places_in_their_cells_and_contacts_adjacent),
        cmocka_unit_test(test_periodic_axes_wrap_blocks),
        cmocka_unit_test(test_placing_a_member_moves_it_to_the_cell_of_its_place),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
