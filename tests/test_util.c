/* Tests of the shared helpers (compiler.h, util.c): the text of a byte count, which every size
 * nbep prints goes through (nbep check's memory and output lines printed "8.61e+04 MB" until
 * 2026-11-30): 3 significant figures in decimal units, the unit the one that keeps the rounded
 * figure below 1000. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>

#include "nbep/compiler.h"
#include "nbep_test.h"

static void assert_bytes(double bytes, const char *expected)
{
    char buf[NBEP_BYTES_TEXT_MAX];
    const char *got = nbep_format_bytes(bytes, buf);
    assert_ptr_equal(got, buf);
    assert_string_equal(got, expected);
}

static void test_sizes_read_in_decimal_units_to_three_figures(void **state)
{
    (void)state;
    assert_bytes(0.0, "0 B");
    assert_bytes(512.0, "512 B");
    assert_bytes(1234.0, "1.23 kB");
    assert_bytes(682e3, "682 kB");
    assert_bytes(1.82e6, "1.82 MB");
    assert_bytes(29.1e6, "29.1 MB");
    assert_bytes(8.61e10, "86.1 GB"); /* what nbep check printed as 8.61e+04 MB */
    assert_bytes(1.54e14, "154 TB");
    assert_bytes(2.5e15, "2.5 PB");
    assert_bytes(18.4e18, "18.4 EB"); /* 2^64 bytes: the largest a size_t counts */
    assert_bytes(1e9, "1 GB");        /* powers of 1000, not 1024 */
    assert_bytes(1073741824.0, "1.07 GB");
}

static void test_a_figure_that_rounds_to_1000_takes_the_next_unit(void **state)
{
    (void)state;
    assert_bytes(999.0, "999 B");
    assert_bytes(999.4, "999 B");
    assert_bytes(999.5, "1 kB");
    assert_bytes(999.4e3, "999 kB");
    assert_bytes(999.5e3, "1 MB");
    assert_bytes(999.96e6, "1 GB");
    assert_bytes(1e21, "1e+03 EB"); /* past the last unit, the figure grows */
}

static void test_what_is_not_a_size_is_still_printed(void **state)
{
    (void)state;
    assert_bytes(NAN, "nan B");
    assert_bytes(-2048.0, "-2.05 kB");
}

/* The directory of a path, as the run's and the sweep's path checks take it. */
static void test_a_paths_directory(void **state)
{
    (void)state;
    const char *cases[][2] = {{"a/b/c.h5", "a/b"}, {"c.h5", "."}, {"/c.h5", "/"},
                              {"/x/y", "/x"}, {"d/", "d"}};
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char *dir = nbep_path_dir(cases[k][0]);
        assert_non_null(dir);
        assert_string_equal(dir, cases[k][1]);
        free(dir);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sizes_read_in_decimal_units_to_three_figures),
        cmocka_unit_test(test_a_figure_that_rounds_to_1000_takes_the_next_unit),
        cmocka_unit_test(test_what_is_not_a_size_is_still_printed),
        cmocka_unit_test(test_a_paths_directory),
    };
    return cmocka_run_group_tests_name("util", tests, NULL, NULL);
}
