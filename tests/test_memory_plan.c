/* nbep check's memory estimate, part by part, against what the code allocates. Each
 * algorithm's `bytes` (the estimate's share for its workspaces) promises the bytes its `create`
 * allocates for the same scene and thread count, and nbep_cells_bytes the most that
 * nbep_cells_init takes. test_cli.sh holds the whole estimate to a run's peak RSS within a
 * band; a term dropped, doubled or subtracted is tens of bytes a sphere, well inside it. Here
 * the allocator counts instead: this binary is linked with malloc, calloc, realloc, free and
 * nbep_alloc_aligned wrapped (Makefile: -Wl,--wrap), and while counting, each block's
 * requested size is kept by its address, so the bytes a create leaves allocated are known
 * exactly (blocks it frees again, and those of the shared libraries: GSL's root workspaces,
 * HDF5's, which the estimate leaves out, are not counted).
 *
 * Exact for every algorithm and mode but the cells mode's neighbour lists and cells, which the
 * estimate counts at their most (ESTIMATE_NEIGHBOURS a sphere listed, nbep_cells_bytes) where a
 * run sizes them to what it finds: there the test takes each side's own out of it. Each
 * destroy must free all its create made, and each allocation of a create, refused in turn,
 * must fail it whole. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/cells.h"
#include "nbep/feq.h"
#include "nbep/mail.h"
#include "nbep/nblist.h"
#include "nbep/slabcal.h"
#include "nbep/undo.h"
#include "nbep/warp.h"
#include "nbep/versions.h"
#include "nbep/vec3.h"
#include "evloop_impl.h"
#include "pred_impl.h"
#include "sim_impl.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"
#include "nbep_test_stamp.h"

/* ---- the counting allocator ------------------------------------------------------------------ */

void *__real_malloc(size_t size);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t size);
void __real_free(void *p);
void *__real_nbep_alloc_aligned(size_t n, size_t size);
void *__wrap_malloc(size_t size);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t size);
void __wrap_free(void *p);
void *__wrap_nbep_alloc_aligned(size_t n, size_t size);

/* Blocks made while counting, by address (a create makes a few dozen; the table's room is
 * checked). nbep_alloc_aligned's own aligned_alloc is not wrapped, so each of its blocks is
 * kept once, at the size asked for (its rounding to cache lines is the allocator's, not the
 * plan's); nbep_free_aligned frees through free, which is. */
#define MAX_BLOCKS 4096
static struct {
    void *p;
    size_t bytes;
    void *at; /* the caller's address */
} blocks[MAX_BLOCKS];
static size_t n_blocks;
static int counting;
/* While counting: the allocations asked for so far, and the one to refuse (0: none), as if
 * memory ran out there */
static size_t n_calls, fail_call;

/* Whether this allocation is to be refused (counting it). */
static bool refuse(void)
{
    return counting && ++n_calls == fail_call;
}

static void keep_at(void *p, size_t bytes, void *at)
{
    if (!counting || !p)
        return;
    assert_true(n_blocks < MAX_BLOCKS);
    blocks[n_blocks].p = p;
    blocks[n_blocks].bytes = bytes;
    blocks[n_blocks].at = at;
    n_blocks++;
}

#define keep(p, b) keep_at(p, b, __builtin_return_address(0))

static void drop(void *p)
{
    for (size_t k = 0; counting && p && k < n_blocks; k++)
        if (blocks[k].p == p) {
            blocks[k] = blocks[--n_blocks];
            return;
        }
}

void *__wrap_malloc(size_t size)
{
    void *p = refuse() ? NULL : __real_malloc(size);
    keep(p, size);
    return p;
}

void *__wrap_calloc(size_t n, size_t size)
{
    void *p = refuse() ? NULL : __real_calloc(n, size);
    keep(p, n * size);
    return p;
}

void *__wrap_realloc(void *p, size_t size)
{
    void *q = refuse() ? NULL : __real_realloc(p, size);
    if (q || size == 0)
        drop(p);
    keep(q, size);
    return q;
}

void __wrap_free(void *p)
{
    drop(p);
    __real_free(p);
}

/* While counting: the aligned allocations asked for (the sphere arrays'), refused or not. */
static size_t n_aligned_calls;

void *__wrap_nbep_alloc_aligned(size_t n, size_t size)
{
    n_aligned_calls += counting != 0;
    void *p = refuse() ? NULL : __real_nbep_alloc_aligned(n, size);
    keep(p, n * size);
    return p;
}

static void count_start(void)
{
    n_blocks = 0;
    n_calls = 0;
    n_aligned_calls = 0;
    counting = 1;
}

/* The bytes left allocated since count_start, counting on. */
static size_t count_now(void)
{
    size_t bytes = 0;
    for (size_t k = 0; k < n_blocks; k++)
        bytes += blocks[k].bytes;
    return bytes;
}

/* The same, counting stopped. */
static size_t count_stop(void)
{
    counting = 0;
    return count_now();
}

/* ---- scenes ---------------------------------------------------------------------------------- */

/* 80 spheres of radius 0.05 placed at random in the unit box (so that the rounds' shares split
 * unevenly over 3 threads: NBEP_BLOCK-sized blocks), with `physics` and `run`'s extra
 * settings; periodic when `periodic`. */
static void load(nbep_scene *sc, const char *algo, const char *neighbors, const char *run_extra,
                 const char *physics, bool periodic)
{
    char text[1024];
    snprintf(text, sizeof text,
             "run: { algorithm = \"%s\"; steps = 2; dt = 0.01; seed = 3; %s%s%s %s };\n"
             "physics: { %s };\n"
             "box: { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0];%s };\n"
             "spheres = ( { count = 80; radius = 0.05; mass = 1.0; place = \"random\";"
             " speed = 1.0; } );\n"
             "output: { every = 1; };\n",
             algo, neighbors ? "neighbors = \"" : "", neighbors ? neighbors : "",
             neighbors ? "\";" : "", run_extra, physics,
             periodic ? " periodic = [true, true, true];" : "");
    nbep_test_load_deck("memory-plan.deck", text, sc);
}

/* What cells g's layout takes: its heads, and a member and a link a sphere (one at least). */
static size_t layout_bytes(const nbep_cells *g)
{
    return g->n_cells * sizeof *g->head + (g->n ? g->n : 1) * (sizeof *g->m + sizeof *g->prev);
}

/* In cells mode, what the lists and cells hold after create taken out of *made, and what the
 * estimate counts for them at their most (ESTIMATE_NEIGHBOURS a sphere listed, 2 n + 8
 * cells: test_cell_lists_... below) out of *planned; nothing in the other modes. */
static void take_out_cells(const nbep_sim *sim, size_t *made, size_t *planned)
{
    if (!sim->scene->neighbors_cells)
        return;
    const pred_ctx *c = sim->algo_ctx;
    const nbep_nblist *l = &c->ev->nl;
    const size_t n = sim->st.n;
    *made -= n * sizeof *l->sp + l->pool_cap * sizeof *l->pool + layout_bytes(&c->ev->cells);
    *planned -= nbep_nblist_bytes(n, (size_t)(ESTIMATE_NEIGHBOURS * (double)n)) +
                nbep_cells_bytes(n);
}

/* What a create is checked on: the algorithm's alone (on a run made first, its algorithm
 * destroyed and made again), or the whole run's (nbep_sim_create, with a file opened first and
 * not counted) */
typedef enum { ALGORITHM, RUN } part;

/* One create of `what` on sim (the run, which the algorithm's belongs to) or a new run of sc. */
static nbep_status create(part what, const nbep_scene *sc, const nbep_sim_options *opt,
                          nbep_sim *sim, nbep_sim **made, nbep_diag *d)
{
    if (what == ALGORITHM) {
        *made = sim;
        return sim->algo->create(sim, &sim->algo_ctx, d);
    }
    return nbep_sim_create(sc, opt, made, d);
}

/* Its undoing, but for the run an algorithm's create belongs to. */
static void undo(part what, nbep_sim **made)
{
    if (what == ALGORITHM) {
        (*made)->algo->destroy((*made)->algo_ctx);
        (*made)->algo_ctx = NULL;
    } else {
        nbep_sim_destroy(made);
    }
}

/* sc's run on nt threads: the bytes the create of `what` leaves allocated, against its
 * estimate (the algorithm's bytes, or nbep check's: nbep_sim_memory_estimate less the frame
 * it counts in HDF5's buffers, which the library allocates), and its destroy freeing every
 * one. With refuse_each, each of that create's allocations is refused in turn too: every
 * refusal fails it with NBEP_ENOMEM and one line, and leaves nothing of it allocated. */
static void check(part what, const nbep_scene *sc, int nt, const char *name, bool refuse_each)
{
    nbep_diag d;
    nbep_diag_init(&d);
    char path[256];
    nbep_test_tmp("memory-plan.h5", path, sizeof path);
    nbep_output *out = NULL;
    assert_int_equal(nbep_output_create(path, sc, nbep_sim_resolve_threads(nt), &out, &d),
                     NBEP_OK);
    nbep_sim_options opt = {.threads = nt, .out = out};
    nbep_sim *sim = NULL;
    if (what == ALGORITHM) { /* the run the algorithm's create is counted on */
        assert_int_equal(nbep_sim_create(sc, &opt, &sim, &d), NBEP_OK);
        undo(ALGORITHM, &sim);
    }
    nbep_sim *made = NULL;
    count_start();
    assert_int_equal(create(what, sc, &opt, sim, &made, &d), NBEP_OK);
    size_t bytes = count_now();
    const size_t calls = n_calls, n = sc->state.n;
    size_t planned = what == ALGORITHM
                         ? made->algo->bytes(sc, nt)
                         : nbep_sim_memory_estimate(sc, nt) - n * 2 * sizeof(nbep_vec3);
    take_out_cells(made, &bytes, &planned);
    const char *const whose = what == ALGORITHM ? "its algorithm's" : "a run's";
    /* NBEP_TEST_BLOCKS=1: each block kept and its caller's address, for addr2line (run under
     * setarch -R, and subtract the program's load address, to find the allocation missed) */
    if (!refuse_each && bytes != planned && getenv("NBEP_TEST_BLOCKS"))
        for (size_t k = 0; k < n_blocks; k++)
            fprintf(stderr, "  block %zu: %zu %p\n", k, blocks[k].bytes, blocks[k].at);
    if (!refuse_each && bytes != planned)
        fail_msg("%s, %d thread%s: %s create allocates %zu bytes, its estimate counts %zu", name,
                 nt, nt == 1 ? "" : "s", whose, bytes, planned);
    /* undone, it leaves nothing of what it made (a destroy that forgot an array: valgrind's
     * to find in make valgrind, found here at once) */
    nbep_summary sum;
    nbep_sim_summary(made, &sum);
    undo(what, &made);
    const size_t kept = count_stop();
    if (kept != 0)
        fail_msg("%s, %d thread%s: %s destroy leaves %zu bytes of its create's", name, nt,
                 nt == 1 ? "" : "s", whose, kept);
    for (size_t k = 1; refuse_each && k <= calls; k++) {
        nbep_diag fd;
        nbep_diag_init(&fd);
        nbep_sim *again = NULL;
        fail_call = k;
        count_start();
        const nbep_status st = create(what, sc, &opt, made, &again, &fd);
        fail_call = 0;
        const size_t lines = fd.n_errors;
        nbep_diag_fini(&fd); /* its line's bytes, counted: freed */
        const size_t left = count_stop();
        const bool none = what == ALGORITHM ? !made->algo_ctx : !again;
        if (st != NBEP_ENOMEM || lines != 1 || left != 0 || !none)
            fail_msg("%s, %d thread%s: %s allocation %zu of %zu refused: status %d, %zu line%s, "
                     "%zu bytes left allocated", name, nt, nt == 1 ? "" : "s", whose, k, calls,
                     (int)st, lines, lines == 1 ? "" : "s", left);
    }
    nbep_sim_destroy(&made); /* an algorithm's run (its algorithm undone); a run's is NULL */
    assert_int_equal(nbep_output_close(&out, &sum, &d), NBEP_OK);
    remove(path);
    nbep_diag_fini(&d);
}

static const char *const elastic = "restitution = 1.0;";
static const char *const pile = "gravity = [0.0, 0.0, -9.81]; restitution = 0.5;";
static const char *const caged = "gravity = [0.0, 0.0, -9.81]; restitution = 0.5; tc = 1.0e-4;";
static const char *const cooling = "restitution = 0.8; tc = 1.0e-4;";

/* The checks of the scene load() makes, on nt_first to nt_last threads: each create's bytes and
 * destroy, and with refuse_each its refusals too. */
static void checks_of(const char *algo, const char *neighbors, const char *run_extra,
                      const char *physics, bool periodic, int nt_first, int nt_last,
                      bool refuse_each)
{
    nbep_scene sc;
    load(&sc, algo, neighbors, run_extra, physics, periodic);
    char what[256];
    snprintf(what, sizeof what, "%s%s%s %s%s, %s", algo, neighbors ? " " : "",
             neighbors ? neighbors : "", run_extra, periodic ? " periodic" : "", physics);
    for (int nt = nt_first; nt <= nt_last; nt++) {
        check(ALGORITHM, &sc, nt, what, refuse_each);
        check(RUN, &sc, nt, what, refuse_each);
    }
    nbep_scene_fini(&sc);
}

/* On 1 to 3 threads, without refusals. */
static void plans_of(const char *algo, const char *neighbors, const char *run_extra,
                     const char *physics, bool periodic)
{
    checks_of(algo, neighbors, run_extra, physics, periodic, 1, 3, false);
}

/* ---- tests ----------------------------------------------------------------------------------- */

static void test_the_detecting_algorithms_allocate_what_they_estimate(void **state)
{
    (void)state;
    plans_of("naive", NULL, "", elastic, false);
    plans_of("naive", NULL, "", elastic, true); /* the periodic images' arrays */
    plans_of("seminaive", NULL, "", elastic, false);
    plans_of("seminaive", NULL, "", elastic, true);
    plans_of("seminaive", NULL, "", pile, false);
}

/* all pairs and grid: the rounds' bookkeeping (flags, claims, stamps, candidates) per thread
 * share, and each model a scene needs: none in free flight, rest sets and settling under
 * gravity at e < 1, the cage with the TC model, the time claims of run.order = "step", and
 * grid mode's crews on 2 and 3 threads */
static void test_the_rounds_modes_allocate_what_they_estimate(void **state)
{
    (void)state;
    const char *const modes[] = {"all", "grid"};
    for (int m = 0; m < 2; m++) {
        plans_of("predictive", modes[m], "", elastic, false);
        if (m == 0) /* grid mode refuses a periodic box */
            plans_of("predictive", modes[m], "", elastic, true);
        plans_of("predictive", modes[m], "", pile, false);
        plans_of("predictive", modes[m], "", caged, false);
        plans_of("predictive", modes[m], "", cooling, false);
        plans_of("predictive", modes[m], "order = \"step\";", elastic, false);
        plans_of("predictive", modes[m], "order = \"step\";", pile, false);
    }
}

/* cells mode: the event loop (calendar, cells), the team's rows on 2 and 3 threads where the
 * scene flies free, none where it accelerates */
static void test_the_cells_mode_allocates_what_it_estimates_but_its_lists(void **state)
{
    (void)state;
    plans_of("predictive", "cells", "", elastic, false);
    plans_of("predictive", "cells", "", elastic, true);
    plans_of("predictive", "cells", "", cooling, true);
    plans_of("predictive", "cells", "", pile, false);
    plans_of("predictive", "cells", "", caged, false);
    /* per-slab calendars (NBEP_SLABS), each with room for its share of the spheres and a
     * quarter more, and no team */
    setenv("NBEP_SLABS", "3", 1);
    plans_of("predictive", "cells", "", elastic, true);
    plans_of("predictive", "cells", "", pile, false);
    unsetenv("NBEP_SLABS");
}

/* Per-slab calendars are made as NBEP_SLABS asks and hold the engine's entries after a run,
 * each in the slab of its sphere's list centre's cell column (test_sim holds their runs to the
 * one calendar's bit for bit; that alone would pass with the slabs never made, or all entries
 * in one). 80 spheres in a periodic unit box: cells of a reach 0.1 and more, 3 to 9 columns. */
static void test_per_slab_calendars_hold_each_entry_in_its_spheres_slab(void **state)
{
    (void)state;
    for (int slabs = 2; slabs <= 3; slabs++) {
        nbep_scene sc;
        load(&sc, "predictive", "cells", "", elastic, true);
        char v[8];
        snprintf(v, sizeof v, "%d", slabs);
        setenv("NBEP_SLABS", v, 1);
        nbep_diag d;
        nbep_diag_init(&d);
        nbep_sim_options opt = {.threads = 2};
        nbep_sim *sim = NULL;
        assert_int_equal(nbep_sim_create(&sc, &opt, &sim, &d), NBEP_OK);
        unsetenv("NBEP_SLABS");
        assert_int_equal(nbep_sim_run(sim, &d), NBEP_OK);
        const pred_ctx *c = sim->algo_ctx;
        nbep_slabcal *sl = c->ev->slabcal;
        assert_non_null(sl);
        assert_int_equal(nbep_slabcal_slabs(sl), slabs);
        assert_int_equal(nbep_slabcal_check(sl), 0);
        assert_null(c->ev->cal); /* the slabs' calendars instead */
        const nbep_cells *g = &c->ev->cells;
        size_t held = 0;
        for (uint32_t i = 0; i < sim->st.n; i++) {
            const int k = nbep_slabcal_slab(sl, i);
            if (k < 0)
                continue;
            held++;
            const int want =
                nbep_slabcal_slab_of(g->m[i].cell % g->dim[0], g->dim[0], slabs);
            if (k != want)
                fail_msg("%d slabs: sphere %u's entry in slab %d, its list centre's column %u "
                         "of %zu in slab %d", slabs, i, k, (unsigned)(g->m[i].cell % g->dim[0]),
                         g->dim[0], want);
        }
        assert_int_equal(held, nbep_slabcal_size(sl));
        assert_true(held > sim->st.n / 2);
        for (int k = 0; k < slabs; k++)
            if (nbep_slabcal_size_of(sl, k) == 0)
                fail_msg("%d slabs: slab %d holds no entry (%zu columns)", slabs, k,
                         g->dim[0]);
        nbep_sim_destroy(&sim);
        nbep_diag_fini(&d);
        nbep_scene_fini(&sc);
    }
}

/* On nt threads, each allocation refused in turn. */
static void refusals_of(const char *algo, const char *neighbors, const char *physics,
                        bool periodic, int nt)
{
    checks_of(algo, neighbors, "", physics, periodic, nt, nt, true);
}

/* memory running out at any allocation of any algorithm's create: every mode and its models
 * (the pile's settling and jams, the TC model's cage), detection's periodic images, the
 * cells team and grid mode's crews on 2 threads */
static void test_a_create_refused_memory_anywhere_fails_whole_and_leaks_nothing(void **state)
{
    (void)state;
    refusals_of("naive", NULL, elastic, true, 1);
    refusals_of("seminaive", NULL, pile, false, 2);
    refusals_of("predictive", "all", caged, false, 2);
    refusals_of("predictive", "grid", pile, false, 2);
    refusals_of("predictive", "cells", elastic, true, 2);
    refusals_of("predictive", "cells", caged, false, 1);
    setenv("NBEP_SLABS", "2", 1); /* the slabs' calendars too */
    refusals_of("predictive", "cells", elastic, true, 2);
    unsetenv("NBEP_SLABS");
}

/* nbep_cells_init for n spheres over [0, side] with cells of reach (periodic along every axis
 * or none): what it allocates, exactly its layout's heads and a member and link a sphere (one
 * at least), never more than nbep_cells_bytes(n); *n_cells its cells */
static size_t cells_made(size_t n, nbep_vec3 side, double reach, bool periodic, size_t *n_cells)
{
    const bool axes[3] = {periodic, periodic, periodic};
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_cells g;
    count_start();
    assert_int_equal(nbep_cells_init(&g, nbep_vec3_make(0.0, 0.0, 0.0), side, reach, n, axes, &d),
                     NBEP_OK);
    const size_t made = count_stop();
    *n_cells = g.n_cells;
    assert_int_equal(made, layout_bytes(&g));
    if (made > nbep_cells_bytes(n))
        fail_msg("%zu spheres in %g x %g x %g, reach %g%s: %zu cells take %zu bytes, the "
                 "estimate %zu", n, side.x, side.y, side.z, reach, periodic ? ", periodic" : "",
                 g.n_cells, made, nbep_cells_bytes(n));
    nbep_cells_fini(&g);
    nbep_diag_fini(&d);
    return made;
}

/* nbep_cells_bytes: the most nbep_cells_init takes for n spheres, whatever the box and reach:
 * 2 n + 8 cells as cells.c's lay_out caps them, or 27 in a periodic box (three a periodic axis
 * at least). Reached exactly where a box holds that many cells of the reach; never passed by
 * boxes of every shape, a reach far below the spacing or above the box. */
static void test_cell_lists_take_at_most_their_estimate_and_reach_it(void **state)
{
    (void)state;
    const size_t counts[] = {0, 1, 2, 7, 9, 10, 100, 1000};
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        const size_t n = counts[k];
        size_t cells;
        /* at the bound: a row of 2 n + 8 cells, and a periodic cube of 3 x 3 x 3 */
        const double row = (double)(2 * n + 8);
        if (2 * n + 8 >= 27) {
            assert_int_equal(cells_made(n, nbep_vec3_make(row, 1.0, 1.0), 1.0, false, &cells),
                             nbep_cells_bytes(n));
            assert_int_equal(cells, 2 * n + 8);
        } else {
            assert_int_equal(cells_made(n, nbep_vec3_make(3.0, 3.0, 3.0), 1.0, true, &cells),
                             nbep_cells_bytes(n));
            assert_int_equal(cells, 27);
        }
        /* under it: cubes, slabs and rods, fine cells and coarse ones, periodic or not (a
         * periodic side at least 3 reaches: the cells mode refuses a shorter one) */
        const double sides[][3] = {{1, 1, 1}, {10, 1, 1}, {7, 3, 5}, {3, 3, 100}, {40, 40, 3}};
        const double reaches[] = {1e-4, 0.07, 1.0};
        for (size_t b = 0; b < sizeof sides / sizeof sides[0]; b++)
            for (size_t r = 0; r < sizeof reaches / sizeof reaches[0]; r++)
                for (int per = 0; per < 2; per++) {
                    const nbep_vec3 side = nbep_vec3_make(sides[b][0], sides[b][1], sides[b][2]);
                    const double least = fmin(side.x, fmin(side.y, side.z));
                    if (per && least < nbep_evloop_min_periodic_side(reaches[r]))
                        continue;
                    (void)cells_made(n, side, reaches[r], per, &cells);
                }
    }
}

/* The event queue refuses only what 32-bit sphere ids cannot number, as the scene does: a
 * queue of UINT32_MAX spheres (ids 0 to UINT32_MAX - 1), the most a deck may hold, is not
 * "too large" but asks for its memory, and fails as any create does when that is refused (here
 * its first allocation, so nothing near its 128 GiB is ever asked for). test_feq holds one
 * sphere more to the refusal. */
static void test_an_event_queue_of_the_most_sphere_ids_asks_for_its_memory(void **state)
{
    (void)state;
    if (SIZE_MAX <= UINT32_MAX)
        skip();
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_feq *q = NULL;
    count_start();
    fail_call = 1;
    const nbep_status st = nbep_feq_create((size_t)UINT32_MAX, &q, &d);
    fail_call = 0;
    /* (a message is kept only where its own allocations were not the one refused) */
    const char *said = d.n_errors == 1 && d.cap > 0 && d.msg[0] ? d.msg[0] : "(none kept)";
    if (!strstr(said, "no memory for an event queue of 4294967295 spheres"))
        fail_msg("a queue of UINT32_MAX spheres: %zu message(s): %s", d.n_errors, said);
    nbep_diag_fini(&d);
    assert_int_equal(count_stop(), 0);
    assert_int_equal(st, NBEP_ENOMEM);
    assert_null(q);
}

/* Neighbour lists take fewer than UINT32_MAX spheres (nblist.h: a list entry is a sphere's
 * 32-bit number, and UINT32_MAX marks none): at UINT32_MAX, init refuses with its message and
 * asks for no memory at all (a mutant of the seed-14 draw asked for 48 GB first, and only a
 * machine without them refused it). */
static void test_neighbour_lists_of_too_many_spheres_are_refused_before_any_allocation(
    void **state)
{
    (void)state;
    if (SIZE_MAX <= UINT32_MAX)
        skip();
    nbep_diag d;
    nbep_diag_init(&d);
    /* the list's own arrays made before counting (a message's text is freed by clear) */
    nbep_diag_add(&d, __FILE__, __LINE__, "nbep: a first message");
    nbep_diag_clear(&d);
    nbep_nblist l;
    count_start();
    const nbep_status st = nbep_nblist_init(&l, (size_t)UINT32_MAX, &d);
    const size_t asked = n_aligned_calls;
    const bool said = d.n_errors == 1 && strstr(d.msg[0], "neighbour lists of 4294967295");
    nbep_diag_clear(&d); /* its message, counted */
    assert_int_equal(count_stop(), 0);
    assert_int_equal(st, NBEP_ENOMEM);
    assert_true(said);
    assert_int_equal(asked, 0);
    assert_null(l.sp);
    /* one fewer is asked for (refused here, at the first allocation) */
    count_start();
    fail_call = 1;
    assert_int_equal(nbep_nblist_init(&l, (size_t)UINT32_MAX - 1, &d), NBEP_ENOMEM);
    fail_call = 0;
    const size_t asked_one_fewer = n_aligned_calls;
    nbep_diag_clear(&d);
    assert_int_equal(count_stop(), 0);
    assert_int_equal(asked_one_fewer, 1);
    nbep_diag_fini(&d);
}

/* A detection step's contact list grows inside the step when a pile outgrows its room (4 a
 * row and 64: algo_detect.c), the one allocation a step makes. Refused, the step is abandoned
 * as a signal's is: NBEP_ENOMEM, one line naming the step, no step of it counted and the
 * spheres where it found them; not (until 2026-12-06) responding to the contacts it kept and
 * recording the step, nor (a mutant of the tenth draw) going on without a word to end
 * "completed". Two spheres sinking through 100 coincident floors make 200 contacts in the
 * first step, past the room of 72 (one thread) or 68 a thread (two, each a row); counting
 * starts after the create, so the step's first allocation is the list's growth. */
static void test_a_step_refused_its_contact_list_growth_stops_the_run_with_the_step_named(
    void **state)
{
    (void)state;
    const char *const algos[] = {"naive", "seminaive"};
    const size_t floors = 100;
    for (int a = 0; a < 2; a++)
        for (int nt = 1; nt <= 2; nt++) {
            nbep_scene *sc = nbep_test_scene_new(2, floors, algos[a], 3, 0.05);
            for (size_t p = 0; p < floors; p++)
                nbep_test_set_plane(sc, p, (nbep_vec3){0.0, 0.0, 1.0}, 0.0);
            for (size_t i = 0; i < 2; i++)
                nbep_test_set_sphere(sc, i, (nbep_vec3){(double)i, 0.0, 0.09},
                                     (nbep_vec3){0.0, 0.0, -1.0}, 0.1, 1.0,
                                     (nbep_vec3){0.0, 0.0, 0.0});
            nbep_diag d;
            nbep_diag_init(&d);
            nbep_sim_options opt = {.threads = nt};
            nbep_sim *sim = NULL;
            assert_int_equal(nbep_sim_create(sc, &opt, &sim, &d), NBEP_OK);
            count_start();
            fail_call = 1;
            const nbep_status st = nbep_sim_run(sim, &d);
            fail_call = 0;
            (void)count_stop();
            nbep_summary sum;
            nbep_sim_summary(sim, &sum);
            const char *said = d.n_errors >= 1 && d.cap > 0 && d.msg[0] ? d.msg[0] : "(none)";
            if (st != NBEP_ENOMEM || d.n_errors != 1 ||
                !strstr(said, "nbep: no memory for the contacts of step 1; the run ends after "
                              "step 0") ||
                sum.steps != 0)
                fail_msg("%s, %d thread%s: the contact list's growth refused: status %d, %zu "
                         "line(s): %s; %llu step(s) done", algos[a], nt, nt == 1 ? "" : "s",
                         (int)st, d.n_errors, said, (unsigned long long)sum.steps);
            for (size_t i = 0; i < 2; i++) /* put back: where the step found them */
                if (memcmp(&sim->st.pos[i], &sc->state.pos[i], sizeof sim->st.pos[i]) != 0 ||
                    memcmp(&sim->st.vel[i], &sc->state.vel[i], sizeof sim->st.vel[i]) != 0)
                    fail_msg("%s, %d thread%s: sphere %zu moved by the abandoned step",
                             algos[a], nt, nt == 1 ? "" : "s", i);
            nbep_sim_destroy(&sim);
            nbep_diag_fini(&d);
            nbep_test_scene_free(&sc);
        }
}

/* A slab that outgrows its room grows (doubled, at most n) with its entries and their order
 * kept; each allocation of a growth refused in turn refuses the entry that needed it and
 * changes nothing: the item stays in the slab it was in, the room as it was, nothing of the
 * growth left allocated. Slab 0 is filled to its room with entries whose ties in (time, key)
 * come out by item, not by local number (filled from the highest item down); then an item of
 * slab 1 moves in. */
static void test_a_slab_outgrowing_its_room_grows_or_refuses_whole(void **state)
{
    (void)state;
    enum { N = 200 };
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_slabcal *s = NULL;
    nbep_calendar *one = NULL;
    assert_int_equal(nbep_slabcal_create(N, 2, &s, &d), NBEP_OK);
    assert_int_equal(nbep_calendar_create(N, &one, &d), NBEP_OK);
    const size_t room = nbep_slabcal_room_of(s, 0);
    assert_true(room < N - 1);
    for (size_t k = 0; k < room; k++) {
        const uint32_t i = (uint32_t)(room - k); /* items room down to 1 */
        const double t = (double)(i % 7);
        assert_true(nbep_slabcal_set(s, 0, i, t, i % 3));
        nbep_calendar_set(one, i, t, i % 3);
    }
    const uint32_t mover = (uint32_t)room + 1;
    assert_true(nbep_slabcal_set(s, 1, mover, 2.0, 1));
    nbep_calendar_set(one, mover, 2.0, 1);
    size_t k = 1, calls = 0;
    for (;; k++) {
        fail_call = k;
        count_start();
        const bool ok = nbep_slabcal_set(s, 0, mover, 2.0, 1);
        fail_call = 0;
        calls = n_calls;
        const size_t left = count_stop();
        if (ok)
            break;
        if (nbep_slabcal_slab(s, mover) != 1 || nbep_slabcal_room_of(s, 0) != room ||
            nbep_slabcal_check(s) != 0 || nbep_slabcal_size(s) != room + 1 || left != 0)
            fail_msg("allocation %zu of a growth refused: the mover in slab %d, room %zu of "
                     "%zu, %zu violations, %zu entries, %zu bytes left", k,
                     nbep_slabcal_slab(s, mover), nbep_slabcal_room_of(s, 0), room,
                     nbep_slabcal_check(s), nbep_slabcal_size(s), left);
    }
    assert_int_equal(k - 1, calls); /* every allocation of the growth was refused once */
    assert_true(calls >= 2);
    assert_int_equal(nbep_slabcal_slab(s, mover), 0);
    assert_int_equal(nbep_slabcal_room_of(s, 0), 2 * room < N ? 2 * room : N);
    assert_int_equal(nbep_slabcal_check(s), 0);
    nbep_calendar_entry a, b;
    while (nbep_calendar_first(one, &b)) { /* the one calendar's order, ties by item */
        assert_true(nbep_slabcal_first(s, &a));
        if (a.item != b.item || a.time != b.time || a.key != b.key)
            fail_msg("after the growth: item %u (t %g, key %llu) came out, the one calendar's "
                     "%u (t %g, key %llu)", a.item, a.time, (unsigned long long)a.key, b.item,
                     b.time, (unsigned long long)b.key);
        nbep_slabcal_remove(s, a.item);
        nbep_calendar_remove(one, b.item);
    }
    assert_false(nbep_slabcal_first(s, &a));
    nbep_calendar_destroy(&one);
    nbep_slabcal_destroy(&s);
    nbep_diag_fini(&d);
}

/* Refuses each of a create's `calls` allocations in turn: each must fail it whole (NBEP_ENOMEM,
 * one line saying `says`, nothing left allocated, nothing made). try: the create, its messages
 * on d; *made: whether it made its object (then destroyed). */
typedef nbep_status (*create_try)(nbep_diag *d, bool *made);
static void refuse_each(const char *what, size_t calls, const char *says, create_try try)
{
    nbep_diag d;
    nbep_diag_init(&d);
    /* the list's own arrays made before counting (a message's text is freed by clear) */
    nbep_diag_add(&d, __FILE__, __LINE__, "nbep: a first message");
    nbep_diag_clear(&d);
    for (size_t k = 1; k <= calls; k++) {
        nbep_diag_clear(&d);
        fail_call = k;
        count_start();
        bool made = false;
        const nbep_status st = try(&d, &made);
        fail_call = 0;
        const bool said = d.n_errors == 1 && strstr(d.msg[0], says);
        const size_t lines = d.n_errors;
        nbep_diag_clear(&d); /* its message, counted */
        const size_t left = count_stop();
        if (st != NBEP_ENOMEM || made || !said || left != 0)
            fail_msg("%s: allocation %zu of %zu refused: status %d, %zu line(s), %zu bytes left",
                     what, k, calls, (int)st, lines, left);
    }
    nbep_diag_fini(&d);
}

enum { VER_N = 100, VER_SIZE = 96, VER_SLABS = 3, VER_ROOM = 50 };

static nbep_status versions_try(nbep_diag *d, bool *made)
{
    nbep_versions *v = NULL;
    const nbep_status st = nbep_versions_create(VER_N, VER_SIZE, VER_SLABS, VER_ROOM, &v, d);
    *made = v != NULL;
    nbep_versions_destroy(&v);
    return st;
}

/* The spheres' versions (versions.h) allocate what nbep_versions_bytes says, create and the
 * tracked spheres' slots; each of create's allocations refused in turn fails it whole
 * (NBEP_ENOMEM, one line, nothing left); a sphere whose slot cannot be had is not tracked and
 * nothing changes; a window whose list of touched spheres cannot grow forgets everything at
 * its close all the same. */
static void test_versions_allocate_what_they_estimate_and_refuse_whole(void **state)
{
    (void)state;
    enum { N = VER_N, SIZE = VER_SIZE, SLABS = VER_SLABS, ROOM = VER_ROOM };
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_versions *v = NULL;
    count_start();
    assert_int_equal(nbep_versions_create(N, SIZE, SLABS, ROOM, &v, &d), NBEP_OK);
    const size_t calls = n_calls;
    assert_int_equal(count_now(), nbep_versions_bytes(N, SIZE, SLABS, ROOM, 0));
    /* slots for the spheres tracked, room doubled as outgrown */
    for (uint32_t i = 0; i < N / 2; i++)
        assert_true(nbep_versions_track(v, N - 1 - i));
    assert_int_equal(count_now(), nbep_versions_bytes(N, SIZE, SLABS, ROOM, N / 2));
    /* a growth refused: false, nothing changed */
    uint32_t i = N / 2;
    for (; i < N; i++) {
        const size_t before = count_now();
        fail_call = n_calls + 1;
        const bool ok = nbep_versions_track(v, N - 1 - i);
        fail_call = 0;
        if (ok)
            continue;
        assert_false(nbep_versions_tracked(v, N - 1 - i));
        assert_int_equal(nbep_versions_count(v), i);
        assert_int_equal(count_now(), before);
        assert_true(nbep_versions_track(v, N - 1 - i));
        break;
    }
    assert_true(i < N); /* one growth at least was refused */
    for (; i < N; i++)
        assert_true(nbep_versions_track(v, N - 1 - i));
    assert_int_equal(count_now(), nbep_versions_bytes(N, SIZE, SLABS, ROOM, N));
    /* a window whose lists of spheres touched cannot grow still forgets all at its close: a
     * put's (sphere 7's version) and a read's (sphere 8's note) */
    nbep_versions_open(v);
    char data[SIZE] = {0};
    uint64_t roll = 0;
    const nbep_stamp s0 = nbep_stamp_at(1.0, 0, 0), s1 = nbep_stamp_at(2.0, 0, 0);
    fail_call = n_calls + 1; /* slab 1's list's first room */
    assert_true(nbep_versions_put(v, 1, 7, s0, data, &roll));
    fail_call = n_calls + 1; /* slab 2's */
    assert_false(nbep_versions_read(v, 2, 8, s1, NULL, NULL));
    fail_call = 0;
    nbep_versions_close(v);
    nbep_versions_open(v);
    assert_null(nbep_versions_newest(v, 7));
    assert_true(nbep_versions_put(v, 1, 8, s0, data, &roll));
    assert_int_equal(roll, 0); /* the last window's read forgotten */
    nbep_versions_close(v);
    nbep_versions_destroy(&v);
    assert_int_equal(count_stop(), 0);
    assert_true(calls >= 3);
    nbep_diag_fini(&d);
    refuse_each("versions", calls, "no memory for the spheres' versions", versions_try);
}

enum { MAIL_SLABS = 5, MAIL_SIZE = 96, MAIL_ROOM = 100 };

static nbep_status mail_try(nbep_diag *d, bool *made)
{
    nbep_mail *m = NULL;
    const nbep_status st = nbep_mail_create(MAIL_SLABS, MAIL_SIZE, MAIL_ROOM, &m, d);
    *made = m != NULL;
    nbep_mail_destroy(&m);
    return st;
}

/* Mail between slabs (mail.h) allocates what nbep_mail_bytes says (boxes of 100 rounded up to
 * 128); each of create's allocations refused in turn fails it whole (NBEP_ENOMEM, one line,
 * nothing left). */
static void test_mail_allocates_what_it_estimates_and_refuses_whole(void **state)
{
    (void)state;
    enum { SLABS = MAIL_SLABS, SIZE = MAIL_SIZE, ROOM = MAIL_ROOM };
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_mail *m = NULL;
    count_start();
    assert_int_equal(nbep_mail_create(SLABS, SIZE, ROOM, &m, &d), NBEP_OK);
    const size_t calls = n_calls;
    assert_int_equal(count_now(), nbep_mail_bytes(SLABS, SIZE, ROOM));
    assert_true(nbep_mail_bytes(SLABS, SIZE, ROOM) > (size_t)SLABS * 128 * SIZE);
    nbep_mail_destroy(&m);
    assert_int_equal(count_stop(), 0);
    assert_true(calls >= 3);
    nbep_diag_fini(&d);
    refuse_each("mail", calls, "no memory for the slabs' mail", mail_try);
}

/* A model for the scheduler (warp.h): two slabs, each an event a time unit on its one item,
 * which sends the other slab its count; enough to grow every array warp.c keeps. */
typedef struct {
    double next[2];
    uint64_t count[2];
    uint64_t seen[2];
} pingpong;

static nbep_warp *pp_warp; /* the one the model's handlers keep and send through */

static bool pp_next(void *u, int slab, nbep_stamp *s)
{
    const pingpong *p = u;
    *s = nbep_stamp_at(p->next[slab], (uint64_t)slab, 0);
    return true;
}

static void pp_handle(void *u, int slab, const nbep_stamp *s)
{
    (void)s;
    pingpong *p = u;
    uint64_t *kept = nbep_warp_keep_room(pp_warp, slab, (uint32_t)slab); /* (apply copies in) */
    if (!kept)
        return;
    kept[0] = p->count[slab];
    kept[1] = p->seen[slab];
    p->count[slab]++;
    p->next[slab] += 1.0;
    (void)nbep_warp_send(pp_warp, slab, 1 - slab, (uint32_t)(1 - slab), &p->count[slab]);
}

static void pp_apply(void *u, int slab, int from, const nbep_stamp *s, uint32_t item,
                     const void *data)
{
    (void)from, (void)s, (void)item;
    pingpong *p = u;
    const uint64_t kept[2] = {p->count[slab], p->seen[slab]};
    if (nbep_warp_keep(pp_warp, slab, (uint32_t)slab, kept))
        memcpy(&p->seen[slab], data, sizeof p->seen[slab]);
}

static void pp_restore(void *u, int slab, uint32_t item, const void *state)
{
    (void)item;
    pingpong *p = u;
    uint64_t kept[2];
    memcpy(kept, state, sizeof kept);
    p->count[slab] = kept[0];
    p->seen[slab] = kept[1];
    p->next[slab] = 1.0 + (double)kept[0];
}

static const nbep_warp_ops pp_ops = {pp_next, pp_handle, pp_apply, pp_restore, NULL, NULL};

static nbep_status warp_try(nbep_diag *d, bool *made)
{
    nbep_warp *w = NULL;
    pingpong p = {{1.0, 1.0}, {0, 0}, {0, 0}};
    const nbep_status st = nbep_warp_create(2, 16, 8, 4, &pp_ops, &p, &w, d);
    *made = w != NULL;
    nbep_warp_destroy(&w);
    return st;
}

/* Two windows of the ping-pong, slab 0 held to one action a turn (so slab 1 runs ahead and goes
 * back); false when a window took past a bound of turns (a hang). */
static bool pp_run(nbep_warp *w)
{
    for (int win = 1; win <= 2; win++) {
        nbep_warp_open(w, 150.0 * win);
        bool done[2] = {false, false};
        for (long turn = 0; !(done[0] && done[1]); turn++) {
            if (turn > 1000000)
                return false;
            done[1] = done[1] || nbep_warp_run(w, 1, 7);
            done[0] = done[0] || nbep_warp_run(w, 0, 1);
        }
    }
    return true;
}

/* The scheduler (warp.h): each of create's allocations refused in turn fails it whole; each
 * allocation of a run (its queues, outboxes and logs growing) refused in turn fails the window
 * (nbep_warp_failed), which still ends: no hang, nothing leaked. */
static void test_the_scheduler_refuses_whole_and_fails_a_window_without_hanging(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    count_start();
    bool made = false;
    assert_int_equal(warp_try(&d, &made), NBEP_OK);
    const size_t calls = n_calls;
    assert_true(made);
    assert_int_equal(count_stop(), 0);
    nbep_diag_fini(&d);
    refuse_each("the scheduler", calls, "nbep: no memory for the", warp_try);
    /* a whole run: how many allocations it makes, then each refused */
    pingpong p = {{1.0, 1.0}, {0, 0}, {0, 0}};
    nbep_diag_init(&d);
    count_start();
    assert_int_equal(nbep_warp_create(2, 16, 8, 4, &pp_ops, &p, &pp_warp, &d), NBEP_OK);
    const size_t made_calls = n_calls;
    assert_true(pp_run(pp_warp));
    const size_t run_calls = n_calls - made_calls;
    assert_false(nbep_warp_failed(pp_warp));
    assert_int_equal(p.count[0] + p.count[1], 2 * 299);
    assert_true(nbep_warp_tally_of(pp_warp, 0).rollbacks +
                    nbep_warp_tally_of(pp_warp, 1).rollbacks >
                0);
    nbep_warp_destroy(&pp_warp);
    assert_int_equal(count_stop(), 0);
    assert_true(run_calls >= 5);
    for (size_t k = 1; k <= run_calls; k++) {
        p = (pingpong){{1.0, 1.0}, {0, 0}, {0, 0}};
        count_start();
        assert_int_equal(nbep_warp_create(2, 16, 8, 4, &pp_ops, &p, &pp_warp, &d), NBEP_OK);
        fail_call = n_calls + k;
        const bool ended = pp_run(pp_warp);
        fail_call = 0;
        const bool failed = nbep_warp_failed(pp_warp);
        nbep_warp_destroy(&pp_warp);
        const size_t left = count_stop();
        if (!ended || !failed || left != 0)
            fail_msg("the scheduler's run, allocation %zu of %zu refused: %s, %s, %zu bytes left",
                     k, run_calls, ended ? "ended" : "hung", failed ? "failed" : "not failed",
                     left);
    }
    nbep_diag_fini(&d);
}

static nbep_status undo_try(nbep_diag *d, bool *made)
{
    nbep_undo *u = NULL;
    const nbep_status st = nbep_undo_create(4, 96, &u, d);
    *made = u != NULL;
    nbep_undo_destroy(&u);
    return st;
}

static void undo_restore(void *arg, uint32_t i, const void *state)
{
    (void)state;
    *(uint32_t *)arg += 1000 + i;
}

static void undo_cancel(void *arg, const nbep_undo_sent *m)
{
    *(uint32_t *)arg += (uint32_t)m->id;
}

/* The slabs' undo logs (undo.h): each of create's allocations refused in turn fails it whole;
 * each growth of a slab's records, states, sends and stamps' deeper levels refused is false and
 * changes nothing (the rollback after it undoes what was logged, no more); destroy frees all
 * the growths. */
static void test_undo_logs_refuse_whole_and_grow_or_change_nothing(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_undo *u = NULL;
    count_start();
    assert_int_equal(nbep_undo_create(4, 96, &u, &d), NBEP_OK);
    const size_t calls = n_calls;
    char data[96] = {0};
    /* each first growth refused, then taken */
    fail_call = n_calls + 1;
    assert_false(nbep_undo_begin(u, 2, STAMP_AT(1.0, 0, 0)));
    assert_int_equal(nbep_undo_count(u, 2), 0);
    assert_true(nbep_undo_begin(u, 2, STAMP_AT(1.0, 0, 0)));
    fail_call = n_calls + 1;
    assert_false(nbep_undo_keep(u, 2, 7, data));
    assert_true(nbep_undo_keep(u, 2, 7, data));
    const nbep_undo_sent m = {.stamp = {1.0, 0}, .id = 5, .sphere = 1, .to = 0};
    fail_call = n_calls + 1;
    assert_false(nbep_undo_sent_one(u, 2, &m));
    assert_true(nbep_undo_sent_one(u, 2, &m));
    /* past the first room of 64: grown, and a growth refused changes nothing */
    for (uint32_t k = 1; k < 64; k++) {
        assert_true(nbep_undo_begin(u, 2, STAMP_AT(1.0 + k, 0, 0)));
        assert_true(nbep_undo_keep(u, 2, k, data));
    }
    fail_call = n_calls + 1;
    assert_false(nbep_undo_begin(u, 2, STAMP_AT(100.0, 0, 0)));
    assert_int_equal(nbep_undo_count(u, 2), 64);
    /* a stamp deeper than a root (a child in a cascade at 100): its records' room grown, then
     * the first room for its deeper levels refused: false, nothing logged; then taken, and read
     * back whole */
    nbep_stamp child;
    const nbep_stamp parent = nbep_stamp_at(100.0, 9, 9);
    assert_true(nbep_cascade_made(&parent, 100.0, 3, 1, &child));
    assert_int_equal(child.depth, 2);
    fail_call = n_calls + 2;
    assert_false(nbep_undo_begin(u, 2, &child));
    assert_int_equal(nbep_undo_count(u, 2), 64);
    fail_call = 0;
    assert_true(nbep_undo_begin(u, 2, &child));
    nbep_stamp last;
    assert_true(nbep_undo_last(u, 2, &last));
    assert_true(nbep_stamp_same(last, child));
    uint32_t sum = 0;
    assert_int_equal(nbep_undo_back_to(u, 2, STAMP_AT(0.0, 0, 0), undo_restore, undo_cancel,
                                       &sum),
                     65);
    assert_int_equal(sum, 64 * 1000 + 7 + 63 * 64 / 2 + 5);
    nbep_undo_destroy(&u);
    assert_int_equal(count_stop(), 0);
    assert_true(calls >= 2);
    nbep_diag_fini(&d);
    refuse_each("undo logs", calls, "no memory for the slabs' undo logs", undo_try);
}

/* In a run, a slab that must grow and cannot stops the run with NBEP_ENOMEM and one line
 * naming the step, whichever of the run's allocations is refused. 80 spheres in the low fifth
 * of a box long across x, on 2 slabs: all in slab 0, past its first room (50 and a quarter, and
 * 16), so the first step's scheduling grows it (the run unrefused shows it did). */
static void test_a_run_whose_slab_cannot_grow_stops_with_the_step_named(void **state)
{
    (void)state;
    nbep_scene sc;
    nbep_test_load_deck("memory-plan-slabs.deck",
                        "run: { algorithm = \"predictive\"; neighbors = \"cells\"; steps = 2; "
                        "dt = 0.01; seed = 3; };\n"
                        "physics: { restitution = 1.0; };\n"
                        "box: { min = [0.0, 0.0, 0.0]; max = [5.0, 1.0, 1.0]; };\n"
                        "spheres = ( { count = 80; radius = 0.05; mass = 1.0; place = \"random\";"
                        " speed = 1.0; region = { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0];"
                        " }; } );\n"
                        "output: { every = 1; };\n",
                        &sc);
    setenv("NBEP_SLABS", "2", 1);
    size_t calls = 0;
    for (size_t k = 0; k == 0 || k <= calls; k++) {
        nbep_diag d;
        nbep_diag_init(&d);
        nbep_sim_options opt = {.threads = 1};
        nbep_sim *sim = NULL;
        assert_int_equal(nbep_sim_create(&sc, &opt, &sim, &d), NBEP_OK);
        const pred_ctx *c = sim->algo_ctx;
        const size_t room = nbep_slabcal_room_of(c->ev->slabcal, 0);
        fail_call = k;
        count_start();
        const nbep_status st = nbep_sim_run(sim, &d);
        fail_call = 0;
        (void)count_stop();
        if (k == 0) { /* unrefused: slab 0 grew, and the run's allocations were counted */
            calls = n_calls;
            assert_int_equal(st, NBEP_OK);
            assert_int_equal(nbep_slabcal_size_of(c->ev->slabcal, 0), sc.state.n);
            assert_true(nbep_slabcal_room_of(c->ev->slabcal, 0) > room);
            assert_true(calls >= 2);
        } else {
            const char *said = d.n_errors >= 1 && d.cap > 0 && d.msg[0] ? d.msg[0] : "(none)";
            if (st != NBEP_ENOMEM || d.n_errors != 1 || !strstr(said, "step 1: no memory for"))
                fail_msg("the run's allocation %zu of %zu refused: status %d, %zu line(s): %s",
                         k, calls, (int)st, d.n_errors, said);
        }
        nbep_sim_destroy(&sim);
        nbep_diag_fini(&d);
    }
    unsetenv("NBEP_SLABS");
    nbep_scene_fini(&sc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_the_detecting_algorithms_allocate_what_they_estimate),
        cmocka_unit_test(test_the_rounds_modes_allocate_what_they_estimate),
        cmocka_unit_test(test_the_cells_mode_allocates_what_it_estimates_but_its_lists),
        cmocka_unit_test(test_per_slab_calendars_hold_each_entry_in_its_spheres_slab),
        cmocka_unit_test(test_cell_lists_take_at_most_their_estimate_and_reach_it),
        cmocka_unit_test(test_a_create_refused_memory_anywhere_fails_whole_and_leaks_nothing),
        cmocka_unit_test(test_an_event_queue_of_the_most_sphere_ids_asks_for_its_memory),
        cmocka_unit_test(test_neighbour_lists_of_too_many_spheres_are_refused_before_any_allocation),
        cmocka_unit_test(test_a_step_refused_its_contact_list_growth_stops_the_run_with_the_step_named),
        cmocka_unit_test(test_a_slab_outgrowing_its_room_grows_or_refuses_whole),
        cmocka_unit_test(test_versions_allocate_what_they_estimate_and_refuse_whole),
        cmocka_unit_test(test_mail_allocates_what_it_estimates_and_refuses_whole),
        cmocka_unit_test(test_undo_logs_refuse_whole_and_grow_or_change_nothing),
        cmocka_unit_test(test_the_scheduler_refuses_whole_and_fails_a_window_without_hanging),
        cmocka_unit_test(test_a_run_whose_slab_cannot_grow_stops_with_the_step_named),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
