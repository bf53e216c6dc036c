/* Tests of the diag's order: nbep_diag_sort puts messages by rank, those of one rank in the
 * order they were added, unranked ones (nbep_diag_add) last, and leaves the messages before the
 * first it is given where they were; also when no memory can be had (it sorts in place and
 * needs none), which this test makes happen with its own copy of src/status.c whose malloc
 * fails on demand. The scene's load sorts its messages so (test_scene). */
#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>

static bool malloc_fails; /* the copy's malloc returns NULL while set */
static void *test_malloc(size_t n)
{
    return malloc_fails ? NULL : malloc(n);
}
#define malloc test_malloc
#include "../src/status.c"
#undef malloc

#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>

#include "nbep_test.h"

/* The diag holds exactly these messages, in this order. */
static void assert_msgs(const nbep_diag *d, const char *const *want, size_t n)
{
    assert_int_equal(d->n_errors, n);
    for (size_t k = 0; k < n; k++)
        assert_string_equal(d->msg[k], want[k]);
}

#define ASSERT_MSGS(d, ...)                                                                   \
    do {                                                                                      \
        const char *const want_[] = {__VA_ARGS__};                                            \
        assert_msgs((d), want_, sizeof want_ / sizeof *want_);                               \
    } while (0)

static void test_sort_orders_by_rank_and_keeps_the_order_of_equal_ranks(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_diag_add_ranked(&d, 7, __FILE__, __LINE__, "seven a");
    nbep_diag_add(&d, __FILE__, __LINE__, "unranked a");
    nbep_diag_add_ranked(&d, 3, __FILE__, __LINE__, "three a");
    nbep_diag_add_ranked(&d, 7, __FILE__, __LINE__, "seven b");
    nbep_diag_add_ranked(&d, 3, __FILE__, __LINE__, "three b");
    nbep_diag_add(&d, __FILE__, __LINE__, "unranked b");
    const int zero_line = __LINE__;
    nbep_diag_add_ranked(&d, 0, __FILE__, zero_line, "zero");
    nbep_diag_add_ranked(&d, 7, __FILE__, __LINE__, "seven c");
    nbep_diag_sort(&d, 0);
    ASSERT_MSGS(&d, "zero", "three a", "three b", "seven a", "seven b", "seven c", "unranked a",
                "unranked b");
    /* each message keeps its own source place (NBEP_DEBUG's "raised at") and rank */
    assert_int_equal(d.rank[0], 0);
    assert_int_equal(d.rank[7], NBEP_DIAG_UNRANKED);
    char where[64];
    snprintf(where, sizeof where, "%s:%d", __FILE__, zero_line);
    assert_string_equal(d.where[0], where);
    nbep_diag_fini(&d);
}

/* Many messages (past the first growth of the arrays), in reverse: every one in place. */
static void test_sort_orders_many_messages(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    enum { N = 100 };
    for (int k = N - 1; k >= 0; k--)
        nbep_diag_add_ranked(&d, (uint64_t)k / 2, __FILE__, __LINE__, "%d", k);
    nbep_diag_sort(&d, 0);
    assert_int_equal(d.n_errors, N);
    for (int k = 0; k < N; k++) { /* ranks k / 2: of each pair, the odd one was added first */
        char want[16];
        snprintf(want, sizeof want, "%d", k % 2 ? k - 1 : k + 1);
        assert_string_equal(d.msg[k], want);
    }
    nbep_diag_fini(&d);
}

/* Without memory to be had, the sort orders the list in place, as stably. */
static void test_sort_without_memory_orders_in_place(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_diag_add(&d, __FILE__, __LINE__, "earlier");
    nbep_diag_add_ranked(&d, 5, __FILE__, __LINE__, "five a");
    nbep_diag_add(&d, __FILE__, __LINE__, "unranked");
    nbep_diag_add_ranked(&d, 2, __FILE__, __LINE__, "two");
    nbep_diag_add_ranked(&d, 5, __FILE__, __LINE__, "five b");
    nbep_diag_add_ranked(&d, 1, __FILE__, __LINE__, "one");
    malloc_fails = true;
    nbep_diag_sort(&d, 1);
    malloc_fails = false;
    ASSERT_MSGS(&d, "earlier", "one", "two", "five a", "five b", "unranked");
    assert_int_equal(d.rank[1], 1);
    assert_int_equal(d.rank[5], NBEP_DIAG_UNRANKED);
    nbep_diag_fini(&d);
}

/* A caller sorts only its own messages: those before `first` (another call's) stay. */
static void test_sort_leaves_the_messages_before_first_alone(void **state)
{
    (void)state;
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_diag_add_ranked(&d, 9, __FILE__, __LINE__, "earlier nine");
    nbep_diag_add(&d, __FILE__, __LINE__, "earlier unranked");
    nbep_diag_add_ranked(&d, 2, __FILE__, __LINE__, "two");
    nbep_diag_add_ranked(&d, 1, __FILE__, __LINE__, "one");
    nbep_diag_sort(&d, 2);
    ASSERT_MSGS(&d, "earlier nine", "earlier unranked", "one", "two");
    nbep_diag_sort(&d, 4); /* nothing of its own: nothing moves */
    nbep_diag_sort(&d, 9);
    ASSERT_MSGS(&d, "earlier nine", "earlier unranked", "one", "two");
    nbep_diag_clear(&d);
    nbep_diag_sort(&d, 0); /* an empty list */
    assert_int_equal(d.n_errors, 0);
    nbep_diag_fini(&d);
}

/* A path the command line names that cannot be opened: the user's (exit 2) where it names
 * nothing there, a directory, or a place that takes no writes (no permission, a read-only
 * file system: exit 1 until 2026-12-01; a place that allows no new file, EPERM: until
 * 2026-12-04); a full disk or a failing device is run time's. */
static void test_open_failures_are_the_users_or_run_times(void **state)
{
    (void)state;
    const int users[] = {ENOENT, ENOTDIR, EISDIR, EACCES, EPERM, EROFS, ENAMETOOLONG, ELOOP};
    for (size_t k = 0; k < sizeof users / sizeof *users; k++)
        assert_int_equal(nbep_status_exit_code(nbep_status_of_open(users[k])), 2);
    const int run_time[] = {ENOSPC, EIO, EDQUOT, ENOMEM};
    for (size_t k = 0; k < sizeof run_time / sizeof *run_time; k++)
        assert_int_equal(nbep_status_exit_code(nbep_status_of_open(run_time[k])), 1);
}

/* A user's text quoted in a message keeps it one line: each control character (below the
 * space, and DEL) written as C writes it, every other byte (UTF-8 too) as it is; and so does
 * every message the diag holds. */
static void test_control_characters_are_written_as_c_writes_them(void **state)
{
    (void)state;
    char *s = nbep_one_line("a\nb\tc\rd\x1b[31m\x7f\x01\xc3\xa9 ok");
    assert_non_null(s);
    assert_string_equal(s, "a\\nb\\tc\\rd\\x1b[31m\\x7f\\x01\xc3\xa9 ok");
    free(s);
    s = nbep_one_line("");
    assert_string_equal(s, "");
    free(s);
    nbep_diag d;
    nbep_diag_init(&d);
    nbep_diag_add(&d, __FILE__, __LINE__, "deck:1: x (got \"%s\")", "pre\ndictive");
    assert_string_equal(d.msg[0], "deck:1: x (got \"pre\\ndictive\")");
    nbep_diag_fini(&d);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sort_orders_by_rank_and_keeps_the_order_of_equal_ranks),
        cmocka_unit_test(test_sort_orders_many_messages),
        cmocka_unit_test(test_sort_without_memory_orders_in_place),
        cmocka_unit_test(test_sort_leaves_the_messages_before_first_alone),
        cmocka_unit_test(test_open_failures_are_the_users_or_run_times),
        cmocka_unit_test(test_control_characters_are_written_as_c_writes_them),
    };
    return cmocka_run_group_tests_name("status", tests, NULL, NULL);
}
