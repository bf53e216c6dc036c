/* The cells engine's neighbour lists, checked against a search of every sphere. A list holds
 * the spheres whose list centres lie within the cutoff of its own sphere's centre (evloop.c:
 * a walk of the 27-cell block at each rebuild, cells it need not read skipped, and the lists of
 * the neighbours gained and lost changed with it). A list that misses a sphere misses the
 * collisions with it only when they come, which the tests of results see now and then; this
 * test compiles its own copy of src/evloop.c with a hook after each event is handled and
 * checks, against every sphere's centre through nbep_periodic_image:
 *   - an expiry's new list (what its walk found, before its commit enters it): every sphere
 *     within the cutoff of its new centre and none beyond, each once;
 *   - every 4th other event's sphere's list as the lists are: the same, around its centre (lists
 *     built at a step's start by the full build, or kept since by the rebuilds of neighbours).
 * In a mixture each pair has its own cutoff, its contact distance plus the skin (the skin being
 * the engine's cutoff less the largest pair's contact distance), taken here from the scene's
 * radii. A sphere at the cutoff to within rounding may be in or out (the walk's test and this one
 * round differently); the test counts how close the scenes come, so that one that looked away
 * would fail. The walk's batches are made small (NEAR_BATCH), so that full ones are passed on
 * mid-walk in most walks. One thread (the hook reads every sphere's centre, which a team's
 * leader may be changing meanwhile). */
struct nbep_evloop;
struct evl_ws;
static void audit_handled(const struct nbep_evloop *e, const struct evl_ws *w);
#define NBEP_EVLOOP_HANDLED_HOOK(e, w, ev) audit_handled(e, w)
/* the walk passes what it finds on in batches of this many (64 in the program): a batch that
 * fills is passed on mid-walk, which 3 makes happen in most walks here */
#define NEAR_BATCH 3
/* a walk's room starts at 2 members, so that a list of 5 or more needs two doublings or more
 * at once (a walk that grew it once read a list of 260 past its room: a mutant) */
#define NBEP_EVLOOP_WS_CAP0 2
#include <stdint.h>
static uint64_t walks_short;  /* walks whose room did not hold the old list */
static uint64_t walks_grown2; /* walks that had to double their room twice or more */
#define NBEP_EVLOOP_WALK_HOOK(w, m, cap0) \
    (walks_short += (m) > (w)->cap, walks_grown2 += (m) > 2 * (cap0))
#include "../src/evloop.c"
#include "../src/evloop_team.c"

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

/* Distances within this relative band of the cutoff may go either way (a few units of 2^-52
 * in the walk's squares and in this test's, with room to spare). */
#define BAND 1e-12

static struct {
    uint64_t walks;   /* expiries' new lists checked */
    uint64_t lists;   /* lists checked as they are */
    uint64_t members; /* members those had in all */
    uint64_t missing; /* spheres within the cutoff not listed */
    uint64_t extra;   /* spheres listed beyond it, listed twice, or the sphere itself */
    uint64_t close;   /* spheres between 0.98 and 1 cutoff (the search came near its limit) */
    uint64_t across;  /* members within the cutoff only the periodic way round */
    uint64_t beyond;  /* lists not empty around a centre more than the cutoff past the cells */
    uint64_t events;  /* events that rebuilt no list */
    uint64_t longest; /* the most members of a list checked */
    double cut;       /* the engine's cutoff */
} seen;
static unsigned char *mark; /* run_audited's, a flag per sphere: listed */
static double *radius;      /* run_checked's: the scene's radii, and the largest */
static double radius_max;

/* The cutoff of spheres i and j's pair in engine e: the largest pair's (e->cut) less the
 * difference of their contact distances (scaled by the slack), where the radii differ. */
static double cut_of(const nbep_evloop *e, uint32_t i, uint32_t j)
{
    const double skin = e->cut / (1.0 + CUT_SLACK) - 2.0 * radius_max;
    return (radius[i] + radius[j] + skin) * (1.0 + CUT_SLACK);
}

/* The spheres js[0..m) against every sphere's distance from centre c (sphere i excluded). */
static void audit_list(const nbep_evloop *e, uint32_t i, nbep_vec3 c, const uint32_t *js,
                       size_t m)
{
    for (size_t k = 0; k < m; k++) {
        seen.extra += js[k] >= e->n || js[k] == i || mark[js[k]];
        if (js[k] < e->n)
            mark[js[k]] = 1;
    }
    seen.members += m;
    seen.longest = m > seen.longest ? m : seen.longest;
    seen.cut = e->cut;
    const nbep_cells *g = &e->cells;
    const double r = e->cut;
    seen.beyond += m > 0 && (c.x < g->lo.x - r || c.y < g->lo.y - r || c.z < g->lo.z - r ||
                             c.x > g->hi.x + r || c.y > g->hi.y + r || c.z > g->hi.z + r);
    for (uint32_t j = 0; j < e->n; j++) {
        const nbep_vec3 raw = nbep_vec3_sub(e->cells.m[j].at, c);
        const double d = nbep_vec3_norm(nbep_periodic_image(&e->pb, raw));
        const bool in = mark[j];
        mark[j] = 0;
        if (j == i)
            continue;
        const double cut = cut_of(e, i, j);
        seen.missing += !in && d < cut * (1.0 - BAND);
        seen.extra += in && d > cut * (1.0 + BAND);
        seen.close += d > 0.98 * cut && d < cut;
        seen.across += in && !(nbep_vec3_norm(raw) < cut);
    }
}

static void audit_handled(const nbep_evloop *e, const evl_ws *w)
{
    if (w->rebuilt) {
        seen.walks++;
        audit_list(e, w->item, w->at, w->near, w->n_near);
    }
    if (!w->rebuilt && seen.events++ % 4 == 0) { /* (a rebuilt list is entered at the commit) */
        size_t m;
        const uint32_t *js = nbep_nblist_of(&e->nl, w->item, &m);
        seen.lists++;
        audit_list(e, w->item, e->cells.m[w->item].at, js, m);
    }
}

/* Runs sc on one thread: every list checked was right, and the run checked many. */
static void run_checked(nbep_scene *sc)
{
    memset(&seen, 0, sizeof seen);
    walks_short = walks_grown2 = 0;
    mark = calloc(sc->state.n, 1);
    radius = malloc(sc->state.n * sizeof *radius);
    assert_non_null(mark);
    assert_non_null(radius);
    radius_max = 0.0;
    for (size_t i = 0; i < sc->state.n; i++) {
        radius[i] = sc->state.radius[i];
        radius_max = fmax(radius_max, radius[i]);
    }
    const nbep_summary s = nbep_test_run(sc, 1, NULL, NULL, NULL, NULL);
    free(mark);
    free(radius);
    mark = NULL;
    radius = NULL;
    assert_int_equal(walks_short, 0);
    assert_true(walks_grown2 > 0);
    assert_true(s.sphere_collisions > s.spheres);
    assert_int_equal(seen.missing, 0);
    assert_int_equal(seen.extra, 0);
    assert_true(seen.walks > s.spheres / 2);
}

/* run_checked, where the lists are those of a fluid: many lists checked as they are, not
 * empty, the cutoff often come near, and (periodic) members found across the faces. */
static void run_audited(nbep_scene *sc, bool periodic)
{
    run_checked(sc);
    const size_t n = sc->state.n;
    assert_true(seen.lists > n / 2);
    assert_true(seen.members > 2 * (seen.walks + seen.lists)); /* not empty lists */
    assert_true(seen.close > seen.walks / 8);
    if (periodic)
        assert_true(seen.across > seen.walks / 8);
}

/* The cutoff the run's engine had is contact distance (diameter 1) plus `skin`, the skin its
 * packing fraction asks for (these boxes are wide enough that it is not cut down), with the
 * engine's slack; to 1e-12 of it, as the fractions of these boxes are their targets to a few
 * roundings. */
static void assert_skin_of(double skin)
{
    const double want = (1.0 + skin) * (1.0 + CUT_SLACK);
    assert_close(seen.cut, want, 1e-12, 0.0);
}

/* A dense periodic fluid: lists across every face; at phi = 0.40, a skin between the dilute
 * and the dense one. */
static void test_lists_hold_every_sphere_near_their_centre_in_a_periodic_fluid(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_periodic_fluid(nbep_test_scaled(12, 9), 0.40,
                                              nbep_test_scaled(30, 15), 0.02, 5);
    const double phi = nbep_scene_packing_fraction(sc, &sc->state);
    assert_true(phi > NBEP_NBLIST_PHI_DILUTE && phi < NBEP_NBLIST_PHI_DENSE);
    run_audited(sc, true);
    assert_skin_of(0.55); /* halfway from the dilute skin, 0.6, to the dense one, 0.5 */
    nbep_test_scene_free(&sc);
}

/* A closed box: the edge cells' slabs open past the walls (centres clamped into them); at
 * phi = 0.35, about the dilute skin (whose lists last longer: the small scene runs 25 steps
 * for as many rebuilds as the thin skin's 15 gave). */
static void test_lists_hold_every_sphere_near_their_centre_in_a_closed_box(void **state)
{
    (void)state;
    nbep_scene *sc = nbep_test_fluid(nbep_test_scaled(12, 9), 0.35, nbep_test_scaled(30, 25),
                                     0.02);
    sc->neighbors_cells = true;
    run_audited(sc, false);
    assert_skin_of(0.6);
    nbep_test_scene_free(&sc);
}

/* Without a box: an expanding cluster, its cells laid out afresh as it grows. */
static void test_lists_hold_every_sphere_near_their_centre_in_a_cluster_without_a_box(void **s)
{
    (void)s;
    nbep_scene *sc = nbep_test_cluster("predictive", nbep_test_scaled(10, 8),
                                       nbep_test_scaled(60, 40));
    sc->neighbors_cells = true;
    run_audited(sc, false);
    nbep_test_scene_free(&sc);
}

/* The same with steps so long that spheres fly out of the cells' region by more than the
 * cutoff before it is laid out again at the step's end (their places clamped into the edge
 * cells, searched from centres beyond the faces too). */
static void test_lists_hold_every_sphere_near_their_centre_past_the_cells_region(void **s)
{
    (void)s;
    nbep_scene *sc = nbep_test_cluster("predictive", 10, 6); /* (not smaller: it must go far) */
    sc->neighbors_cells = true;
    sc->dt = 3.0;
    run_checked(sc);
    assert_true(seen.beyond > 10);
    nbep_test_scene_free(&sc);
}

/* Spheres of two sizes, periodic: big ones (diameter 1, one site in 64) among small ones
 * (diameter 0.25) on a lattice of spacing 0.35. Each pair's cutoff is its own contact
 * distance plus the skin (0.6; 0.4 in the small box, which cuts the skin down): a small
 * sphere's list holds the small ones within 0.85 (or 0.65) and the big ones within 1.225 (or
 * 1.025), none beyond (with the big pairs' 1.6 for every pair, until 2026-12-01, they held
 * up to 178 spheres). A big sphere's list holds up to about 126: past the 64 a walk's
 * workspace starts with, so walks grow it (grow_ws, which no other test reached) while every
 * list is checked. */
static void test_lists_hold_every_sphere_near_their_centre_with_two_sizes(void **state)
{
    (void)state;
    const size_t side = nbep_test_scaled(16, 12), sites = side * side * side; /* 4 k */
    const double a = 0.35, L = a * (double)side;
    /* a site's kind: 2 big, 1 small, 0 none (the 26 sites around a big sphere: it reaches
     * 0.625 from its centre) */
    unsigned char *kind = malloc(sites);
    assert_non_null(kind);
    size_t n = 0, big = 0;
    for (size_t q = 0; q < sites; q++) {
        const size_t c[3] = {q % side, q / side % side, q / side / side};
        bool at_big = true, by_big = true;
        for (int k = 0; k < 3; k++) {
            at_big = at_big && c[k] % 4 == 0;
            by_big = by_big && c[k] % 4 != 2;
        }
        kind[q] = at_big ? 2 : by_big ? 0 : 1;
        n += kind[q] != 0;
        big += at_big;
    }
    nbep_scene *sc = nbep_test_scene_new(n, 0, "predictive", nbep_test_scaled(40, 25), 0.01);
    sc->neighbors_cells = true;
    nbep_test_set_periodic_box(sc, L);
    uint64_t x = 0x5DEECE66Du;
    for (size_t q = 0, i = 0; q < sites; q++) {
        if (!kind[q])
            continue;
        const nbep_vec3 p = {a * (double)(q % side), a * (double)(q / side % side),
                             a * (double)(q / side / side)};
        nbep_test_set_sphere(sc, i++, p, nbep_test_random_velocity(&x, sqrt(3.0)),
                             kind[q] == 2 ? 0.5 : 0.125, 1.0, (nbep_vec3){0.0, 0.0, 0.0});
    }
    free(kind);
    run_checked(sc);
    assert_true(big >= 27);
    assert_true(seen.longest > 64); /* the workspace grew (126 seen) */
    nbep_test_scene_free(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lists_hold_every_sphere_near_their_centre_in_a_periodic_fluid),
        cmocka_unit_test(test_lists_hold_every_sphere_near_their_centre_in_a_closed_box),
        cmocka_unit_test(
            test_lists_hold_every_sphere_near_their_centre_in_a_cluster_without_a_box),
        cmocka_unit_test(test_lists_hold_every_sphere_near_their_centre_past_the_cells_region),
        cmocka_unit_test(test_lists_hold_every_sphere_near_their_centre_with_two_sizes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
