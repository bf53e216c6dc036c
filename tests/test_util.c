/* Tests of the shared helpers (compiler.h, util.c): the text of a byte count, which every size
 * nbep prints goes through (nbep check's memory and output lines printed "8.61e+04 MB" until
 * 2026-11-30): 3 significant figures in decimal units, the unit the one that keeps the rounded
 * figure below 1000; the text of a progress line's time to go; a path's directory; the
 * engines' arrays, zeroed, aligned, and on huge pages where they fill them. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

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

static void assert_duration(double seconds, const char *expected)
{
    char buf[NBEP_DURATION_TEXT_MAX];
    const char *got = nbep_format_duration(seconds, buf);
    assert_ptr_equal(got, buf);
    assert_string_equal(got, expected);
}

/* A progress line's ETA: the unit that keeps the rounded figure below 100 (days below 1000),
 * each unit taking over where the one before would print 100. */
static void test_a_time_to_go_reads_in_the_unit_that_keeps_it_short(void **state)
{
    (void)state;
    assert_duration(0.0, "0 s");
    assert_duration(42.4, "42 s");
    assert_duration(99.4, "99 s");
    assert_duration(99.5, "2 min"); /* not "100 s" */
    assert_duration(3100.0, "52 min");
    assert_duration(99.4 * 60.0, "99 min");
    assert_duration(99.5 * 60.0, "1.7 h"); /* not "100 min" */
    assert_duration(27.3 * 3600.0, "27.3 h");
    assert_duration(99.94 * 3600.0, "99.9 h");
    assert_duration(99.95 * 3600.0, "4 days"); /* not "100.0 h" */
    assert_duration(12.0 * 86400.0, "12 days");
    assert_duration(999.4 * 86400.0, "999 days");
    assert_duration(999.5 * 86400.0, "over 1000 days");
    assert_duration(5.4e14, "over 1000 days"); /* a run at 1e-12 steps a second */
}

/* What is not a time to go still prints as words, never "nan s", "inf s" or "-0 s". */
static void test_what_is_not_a_time_to_go_is_still_words(void **state)
{
    (void)state;
    assert_duration(INFINITY, "over 1000 days");
    assert_duration(NAN, "over 1000 days");
    assert_duration(-0.0, "0 s");
    assert_duration(-3.0, "0 s");
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

/* The arrays nbep_alloc_aligned makes, small and large: zero-filled, aligned to a cache line,
 * and those that fill a huge page, or all but at most a sixteenth of themselves, to a huge page
 * (1973824 bytes: the fewest whole cache lines that make 16/17 of one; 256000 doubles). */
static const size_t ARRAY_BYTES[] = {
    1, 100 * sizeof(double), 1973824, 256000 * sizeof(double), 3 << 20, 8 << 20};

static void *(*volatile fill)(void *, int, size_t) = memset;

static void test_arrays_are_zeroed_and_aligned(void **state)
{
    (void)state;
    nbep_memory_init();
    for (size_t k = 0; k < sizeof ARRAY_BYTES / sizeof *ARRAY_BYTES; k++) {
        const size_t n = ARRAY_BYTES[k];
        unsigned char *p = nbep_alloc_aligned(n, 1);
        assert_non_null(p);
        assert_int_equal((uintptr_t)p % NBEP_CACHELINE, 0);
        if (n >= NBEP_HUGE || 17 * n >= 16 * NBEP_HUGE) /* huge - n <= n / 16 */
            assert_int_equal((uintptr_t)p % NBEP_HUGE, 0);
        size_t nonzero = 0;
        for (size_t i = 0; i < n; i++)
            nonzero += p[i] != 0;
        assert_int_equal(nonzero, 0);
        memset(p, 0xff, n); /* all of it is ours */
        nbep_free_aligned(p);
    }
    /* zeroed where the memory was used before too: a block dirtied and freed just before goes
     * back to the heap's free lists, where the next small array is carved from it (glibc;
     * fresh mappings, all the large ones above, are zero in any case; until 2026-12-01 this
     * test made no array that was not, and passed without the clearing) */
    for (int round = 0; round < 4; round++) {
        unsigned char *dirt = malloc(1 << 12), *guard = malloc(64); /* (the guard keeps it from
                                                                      * the heap's top, which a
                                                                      * free may give back) */
        assert_true(dirt && guard);
        fill(dirt, 0xff, 1 << 12); /* (through a pointer it cannot see through: else the
                                     * compiler drops the filling of a block freed unread) */
        free(dirt);
        unsigned char *q = nbep_alloc_aligned(100, sizeof(double));
        assert_non_null(q);
        size_t nonzero = 0;
        for (size_t i = 0; i < 100 * sizeof(double); i++)
            nonzero += q[i] != 0;
        assert_int_equal(nonzero, 0);
        nbep_free_aligned(q);
        free(guard);
    }
    assert_null(nbep_alloc_aligned(SIZE_MAX / 2, 4)); /* overflow */
    /* sizes that fit a size_t but whose roundings would not (a request of SIZE_MAX bytes
     * returned a block of 64 before 2026-12-01) */
    assert_null(nbep_alloc_aligned(SIZE_MAX, 1));
    assert_null(nbep_alloc_aligned(SIZE_MAX - 10, 1));
    assert_null(nbep_alloc_aligned(1, SIZE_MAX - (1u << 20)));
}

/* Whether the kernel's mapping of address a asks for huge pages (the "hg" of its VmFlags in
 * /proc/self/smaps): 1 yes, 0 no, -1 not found. */
static int asks_huge(const void *a)
{
    FILE *f = fopen("/proc/self/smaps", "r");
    if (!f)
        return -1;
    char line[512];
    int in = 0, found = -1;
    while (found < 0 && fgets(line, sizeof line, f)) {
        unsigned long lo, hi;
        if (sscanf(line, "%lx-%lx ", &lo, &hi) == 2) /* a mapping's first line ("Key:" the
                                                       * others: none is hex then "-") */
            in = (uintptr_t)a >= lo && (uintptr_t)a < hi;
        else if (in && strncmp(line, "VmFlags:", 8) == 0)
            found = strstr(line, " hg") != NULL;
    }
    fclose(f);
    return found;
}

/* An array read at random is on huge pages where they are to be had (Linux's transparent huge
 * pages): those it fills, and the last where at most a sixteenth of it more becomes resident,
 * no other (an array of 256000 doubles: its one page; 3 MB: its first page, not its second,
 * which would make a third more resident). */
static void test_large_arrays_ask_for_huge_pages(void **state)
{
    (void)state;
    if (access("/sys/kernel/mm/transparent_hugepage/enabled", R_OK) != 0 ||
        access("/proc/self/smaps", R_OK) != 0)
        skip(); /* no transparent huge pages here: small pages, which work as well */
    nbep_memory_init();
    unsigned char *d = nbep_alloc_aligned(256000, sizeof(double));
    unsigned char *m3 = nbep_alloc_aligned(3 << 20, 1);
    unsigned char *m8 = nbep_alloc_aligned(8 << 20, 1);
    assert_true(d && m3 && m8);
    assert_int_equal(asks_huge(d), 1);
    assert_int_equal(asks_huge(d + 256000 * sizeof(double) - 1), 1);
    assert_int_equal(asks_huge(m3), 1);
    assert_int_equal(asks_huge(m3 + (3 << 20) - 1), 0);
    assert_int_equal(asks_huge(m8), 1);
    assert_int_equal(asks_huge(m8 + (8 << 20) - 1), 1);
    nbep_free_aligned(d);
    nbep_free_aligned(m3);
    nbep_free_aligned(m8);
}

/* A lock excludes every other descriptor (in this process too) until dropped; dropped with
 * its name, the file goes, and the next taker makes a new one. */
static void test_a_lock_excludes_every_other_taker_until_dropped(void **state)
{
    (void)state;
    char path[256];
    nbep_test_tmp("util.lock", path, sizeof path);
    unlink(path);
    bool busy = true;
    const int a = nbep_lock_take(path, &busy);
    assert_true(a >= 0);
    assert_false(busy);
    assert_int_equal(nbep_lock_take(path, &busy), -1);
    assert_true(busy);
    nbep_lock_drop(a, NULL); /* the file stays (a sweep's folder keeps its .lock) */
    assert_int_equal(access(path, F_OK), 0);
    const int b = nbep_lock_take(path, &busy);
    assert_true(b >= 0);
    assert_false(busy);
    nbep_lock_drop(b, path);
    assert_int_equal(access(path, F_OK), -1);
    nbep_lock_drop(-1, path); /* nothing */
}

/* A lock that cannot be made (no such folder) is no one else's: -1, not busy. */
static void test_a_lock_that_cannot_be_made_is_no_one_elses(void **state)
{
    (void)state;
    bool busy = true;
    assert_int_equal(nbep_lock_take("/nonexistent-dir/x.lock", &busy), -1);
    assert_false(busy);
}

/* A lock stands only while its name leads to the file it holds: not once the name is removed
 * (its holder ended) nor once it leads to a new file (the next holder's). */
static void test_a_lock_names_its_file_only_while_the_name_leads_there(void **state)
{
    (void)state;
    char path[256];
    nbep_test_tmp("util_names.lock", path, sizeof path);
    unlink(path);
    bool busy;
    const int a = nbep_lock_take(path, &busy);
    assert_true(a >= 0);
    assert_true(nbep_lock_names(a, path));
    unlink(path);
    assert_false(nbep_lock_names(a, path));
    const int b = nbep_lock_take(path, &busy); /* a new file: a's lock is not on it */
    assert_true(b >= 0);
    assert_false(nbep_lock_names(a, path));
    assert_true(nbep_lock_names(b, path));
    nbep_lock_drop(a, NULL);
    nbep_lock_drop(b, path);
}

/* In a child that cannot write the lock file (another user's, 0644: as root, the child becomes
 * nobody; else the file is made read-only): 0 when it met what `want` says, 77 when it cannot
 * reach the file at all, 1 otherwise. want 'b': busy; want 'h': holds the lock until told
 * (one byte on `go`), after saying so on `said`. */
static int lock_as_another(const char *path, char want, int said, int go)
{
    alarm(30); /* a hang is a failure */
    if (geteuid() == 0 && (setgid(65534) != 0 || setuid(65534) != 0))
        return 77;
    if (access(path, R_OK) != 0)
        return 77;
    if (access(path, W_OK) == 0)
        return 1; /* the case under test is a file this user cannot write */
    bool busy;
    const int fd = nbep_lock_take(path, &busy);
    if (want == 'b')
        return fd < 0 && busy ? 0 : 1;
    if (fd < 0)
        return 1;
    char c = 'h';
    if (write(said, &c, 1) != 1 || read(go, &c, 1) != 1)
        return 1;
    nbep_lock_drop(fd, NULL);
    return 0;
}

static int child_status(pid_t pid)
{
    int ws;
    if (waitpid(pid, &ws, 0) != pid || !WIFEXITED(ws))
        return -1;
    return WEXITSTATUS(ws);
}

/* A lock file this user cannot write (another user's, in a folder a group shares) still
 * guards: its holder's lock makes the other user busy, and the other user's read lock makes
 * the holder busy (until 2026-12-01 the other user's run went on unguarded). */
static void test_a_lock_file_another_user_cannot_write_still_guards(void **state)
{
    (void)state;
    /* a folder of its own in /tmp, open to every user (the test's own folder may lie in one
     * closed to others: a mutation run's copy of the tree, say) */
    char dir[] = "/tmp/nbep-util-XXXXXX", path[64];
    assert_non_null(mkdtemp(dir));
    assert_int_equal(chmod(dir, 0755), 0);
    snprintf(path, sizeof path, "%s/shared.lock", dir);
    bool busy;
    const int a = nbep_lock_take(path, &busy);
    assert_true(a >= 0);
    assert_int_equal(fchmod(a, geteuid() == 0 ? 0644 : 0444), 0);
    fflush(NULL);
    pid_t pid = fork();
    if (pid == 0)
        _exit(lock_as_another(path, 'b', -1, -1));
    const int first = child_status(pid);
    if (first == 77) {
        nbep_lock_drop(a, path);
        rmdir(dir);
        skip(); /* the folder is closed to the other user */
    }
    assert_int_equal(first, 0);
    nbep_lock_drop(a, NULL); /* the file stays, no one's lock on it */
    int said[2], go[2];
    assert_int_equal(pipe(said), 0);
    assert_int_equal(pipe(go), 0);
    pid = fork();
    if (pid == 0) {
        close(said[0]);
        close(go[1]);
        _exit(lock_as_another(path, 'h', said[1], go[0]));
    }
    close(said[1]);
    close(go[0]);
    char c = 0;
    assert_int_equal(read(said[0], &c, 1), 1); /* the other user holds it now */
    assert_int_equal(nbep_lock_take(path, &busy), -1);
    assert_true(busy);
    assert_int_equal(write(go[1], &c, 1), 1);
    assert_int_equal(child_status(pid), 0);
    close(said[0]);
    close(go[1]);
    const int b = nbep_lock_take(path, &busy); /* let go: the owner's again */
    assert_true(b >= 0);
    nbep_lock_drop(b, path);
    assert_int_equal(access(path, F_OK), -1);
    assert_int_equal(rmdir(dir), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sizes_read_in_decimal_units_to_three_figures),
        cmocka_unit_test(test_a_figure_that_rounds_to_1000_takes_the_next_unit),
        cmocka_unit_test(test_what_is_not_a_size_is_still_printed),
        cmocka_unit_test(test_a_time_to_go_reads_in_the_unit_that_keeps_it_short),
        cmocka_unit_test(test_what_is_not_a_time_to_go_is_still_words),
        cmocka_unit_test(test_a_paths_directory),
        cmocka_unit_test(test_arrays_are_zeroed_and_aligned),
        cmocka_unit_test(test_large_arrays_ask_for_huge_pages),
        cmocka_unit_test(test_a_lock_excludes_every_other_taker_until_dropped),
        cmocka_unit_test(test_a_lock_that_cannot_be_made_is_no_one_elses),
        cmocka_unit_test(test_a_lock_names_its_file_only_while_the_name_leads_there),
        cmocka_unit_test(test_a_lock_file_another_user_cannot_write_still_guards),
    };
    return cmocka_run_group_tests_name("util", tests, NULL, NULL);
}
