/* The thread count is resolved in one place (nbep_sim_resolve_threads) to what a run really
 * uses, and the run's summary and its file's root attribute `threads` record that number: a
 * serial build (make OMP=0) asked for 4 threads runs, and says, 1. The expected numbers come
 * from how this test itself was compiled (_OPENMP), the same flags as the library. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <hdf5.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "nbep/output.h"
#include "nbep/run.h"
#include "nbep/sim.h"
#include "nbep_test.h"
#include "nbep_test_scene.h"

#ifdef _OPENMP
#include <omp.h>
enum { SERIAL = 0 };
#else
enum { SERIAL = 1 };
#endif

static void test_an_explicit_count_resolves_to_what_the_build_can_run(void **state)
{
    (void)state;
    assert_int_equal(nbep_sim_resolve_threads(1), 1);
    assert_int_equal(nbep_sim_resolve_threads(4), SERIAL ? 1 : 4);
    assert_int_equal(nbep_sim_resolve_threads(64), SERIAL ? 1 : 64);
}

static void test_zero_resolves_to_the_openmp_default_or_one(void **state)
{
    (void)state;
#ifdef _OPENMP
    assert_int_equal(nbep_sim_resolve_threads(0), omp_get_max_threads());
#else
    assert_int_equal(nbep_sim_resolve_threads(0), 1);
#endif
}

static void test_a_run_records_the_threads_it_ran_with(void **state)
{
    (void)state;
    char deck[256], out[256];
    nbep_test_tmp("threads.deck", deck, sizeof deck);
    nbep_test_tmp("threads.h5", out, sizeof out);
    FILE *f = fopen(deck, "w");
    assert_non_null(f);
    fputs("run: { algorithm = \"predictive\"; steps = 5; dt = 1.0e-3; threads = 4; };\n"
          "box: { min = [0.0, 0.0, 0.0]; max = [1.0, 1.0, 1.0]; };\n"
          "spheres = ( { count = 8; radius = 0.05; mass = 1.0; place = \"lattice\"; "
          "speed = 1.0; } );\n",
          f);
    fclose(f);
    const nbep_run_result res = nbep_test_run_deck(deck, out);
    const int want = SERIAL ? 1 : 4;
    assert_int_equal(res.summary.threads, want);
    hid_t file = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(file >= 0);
    int64_t threads = -1;
    hid_t attr = H5Aopen(file, "threads", H5P_DEFAULT);
    assert_true(attr >= 0);
    assert_true(H5Aread(attr, H5T_NATIVE_INT64, &threads) >= 0);
    H5Aclose(attr);
    H5Fclose(file);
    assert_int_equal(threads, want);
}

int main(void)
{
    const char *dirs[] = {"build", "build/tests", "build/tests/tmp"};
    for (size_t k = 0; k < sizeof dirs / sizeof *dirs; k++)
        if (mkdir(dirs[k], 0777) != 0 && errno != EEXIST) {
            perror(dirs[k]);
            return 1;
        }
    nbep_output_library_init();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_explicit_count_resolves_to_what_the_build_can_run),
        cmocka_unit_test(test_zero_resolves_to_the_openmp_default_or_one),
        cmocka_unit_test(test_a_run_records_the_threads_it_ran_with),
    };
    return cmocka_run_group_tests_name("threads", tests, NULL, NULL);
}
