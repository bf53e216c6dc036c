/* Tests of the JSON summary (summary.h): every key of NBEP_SUMMARY_FIELDS is written and read
 * back to the bit, each one is required by the reader, and a null key stays null. The keys
 * come from the same table as the code under test, so a key added there is covered here
 * without editing this file; the values are chosen so that no two keys share one and every
 * number needs all its digits. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "nbep/summary.h"
#include "nbep_test.h"

/* k-th key's value. Integers above 2^53 (a double would round them: the summary's counters
 * are exact); reals 1/(k + 3) - 1e-17 k, which need 17 significant digits. */
static void fill_TEXT(char *v, size_t cap, int k) { snprintf(v, cap, "algo%d", k); }
static void fill_INT(int *v, int k) { *v = 100000 + k; }
static void fill_UINT(uint64_t *v, int k) { *v = (UINT64_C(1) << 53) + 1 + (uint64_t)k; }
static void fill_REAL(double *v, int k) { *v = 1.0 / (k + 3) - 1e-17 * k; }
static void fill_NULLABLE(nbep_summary_nullable *v, int k)
{
    *v = (nbep_summary_nullable){.known = true, .value = -1.0 / (k + 7)};
}

static nbep_summary every_key_set(void)
{
    nbep_summary s;
    memset(&s, 0, sizeof s);
    int k = 0;
#define X_FILL_TEXT(field) fill_TEXT(s.field, sizeof s.field, k++)
#define X_FILL_OTHER(field, kind) fill_##kind(&s.field, k++)
#define X_FILL_INT(field) X_FILL_OTHER(field, INT)
#define X_FILL_UINT(field) X_FILL_OTHER(field, UINT)
#define X_FILL_REAL(field) X_FILL_OTHER(field, REAL)
#define X_FILL_NULLABLE(field) X_FILL_OTHER(field, NULLABLE)
#define X_FILL(field, kind) X_FILL_##kind(field);
    NBEP_SUMMARY_FIELDS(X_FILL)
#undef X_FILL
    return s;
}

/* Asserts field by field that b holds a's values (doubles bitwise, by ==). */
static void assert_same_summary(const nbep_summary *a, const nbep_summary *b)
{
#define X_SAME_TEXT(field) assert_string_equal(a->field, b->field)
#define X_SAME_INT(field) assert_int_equal(a->field, b->field)
#define X_SAME_UINT(field) assert_true(a->field == b->field)
#define X_SAME_REAL(field)                                                                   \
    if (!(a->field == b->field))                                                             \
    fail_msg(#field ": %.17g read back as %.17g", a->field, b->field)
#define X_SAME_NULLABLE(field)                                                               \
    assert_int_equal(a->field.known, b->field.known);                                        \
    if (a->field.known && !(a->field.value == b->field.value))                               \
    fail_msg(#field ": %.17g read back as %.17g", a->field.value, b->field.value)
#define X_SAME(field, kind) X_SAME_##kind(field);
    NBEP_SUMMARY_FIELDS(X_SAME)
#undef X_SAME
}

static void test_every_key_round_trips_exactly(void **state)
{
    (void)state;
    nbep_summary s = every_key_set(), r;
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    memset(&r, 0xA5, sizeof r);
    assert_true(nbep_summary_from_json(json, &r));
    assert_same_summary(&s, &r);
    free(json);
}

static void test_every_key_is_written_once_and_required_by_the_reader(void **state)
{
    (void)state;
    nbep_summary s = every_key_set(), r;
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    static const char *const keys[] = {
#define X_KEY(field, kind) "\"" #field "\": ",
        NBEP_SUMMARY_FIELDS(X_KEY)
#undef X_KEY
    };
    for (size_t k = 0; k < sizeof keys / sizeof *keys; k++) {
        char *at = strstr(json, keys[k]);
        if (!at)
            fail_msg("key %s is not written: %s", keys[k], json);
        assert_null(strstr(at + 1, keys[k]));
        /* the same text with this one key renamed is not a summary */
        at[1] = 'X';
        assert_false(nbep_summary_from_json(json, &r));
        at[1] = keys[k][1];
    }
    assert_true(nbep_summary_from_json(json, &r));
    free(json);
}

static void test_an_unknown_pressure_is_null_and_reads_back_unknown(void **state)
{
    (void)state;
    nbep_summary s = every_key_set(), r;
    s.pressure = (nbep_summary_nullable){.known = false};
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    assert_non_null(strstr(json, "\"pressure\": null"));
    assert_true(nbep_summary_from_json(json, &r));
    assert_false(r.pressure.known);
    assert_same_summary(&s, &r);
    free(json);
}

static void test_text_that_is_not_a_summary_is_refused(void **state)
{
    (void)state;
    nbep_summary r;
    assert_false(nbep_summary_from_json(NULL, &r));
    assert_false(nbep_summary_from_json("", &r));
    assert_false(nbep_summary_from_json("not json", &r));
    assert_false(nbep_summary_from_json("{\"format\": \"nbep-summary-1\"}", &r));
    nbep_summary s = every_key_set();
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    char *fmt = strstr(json, "nbep-summary-1");
    assert_non_null(fmt);
    fmt[strlen("nbep-summary-")] = '9'; /* another format */
    assert_false(nbep_summary_from_json(json, &r));
    free(json);
}

/* json with the text `from` (which must occur once) replaced by `to`: a new string. */
static char *edited(const char *json, const char *from, const char *to)
{
    const char *at = strstr(json, from);
    assert_non_null(at);
    assert_null(strstr(at + 1, from));
    char *out = malloc(strlen(json) + strlen(to) + 1);
    assert_non_null(out);
    memcpy(out, json, (size_t)(at - json));
    strcpy(out + (at - json), to);
    strcat(out, at + strlen(from));
    return out;
}

/* A key out of its range is no summary nbep wrote (threads >= 0 in an int, counters >= 0), nor
 * is an object with a key twice (which value would be the run's?): the reader refuses them, as
 * a sweep reusing a finished run must not take its numbers. The unedited text reads. */
static void test_values_out_of_range_and_repeated_keys_are_refused(void **state)
{
    (void)state;
    nbep_summary s = every_key_set(), r;
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    assert_true(nbep_summary_from_json(json, &r));
    char threads[64], checks[64];
    snprintf(threads, sizeof threads, "\"threads\": %d,", s.threads);
    snprintf(checks, sizeof checks, "\"checks\": %llu,", (unsigned long long)s.checks);
    const char *const bad[][2] = {
        {threads, "\"threads\": -1,"},
        {threads, "\"threads\": 2147483648,"},
        {checks, "\"checks\": -1,"},
        {threads, "\"threads\": 3, \"threads\": 4,"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        char *e = edited(json, bad[k][0], bad[k][1]);
        if (nbep_summary_from_json(e, &r))
            fail_msg("read as a summary: %s", e);
        free(e);
    }
    free(json);
}

static void test_escapes_nested_values_and_old_integral_reals_are_read(void **state)
{
    (void)state;
    nbep_summary s = every_key_set(), r;
    snprintf(s.algorithm, sizeof s.algorithm, "a\"b\\c\td");
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    assert_true(nbep_summary_from_json(json, &r));
    assert_string_equal(r.algorithm, "a\"b\\c\td");
    free(json);
    /* A later writer may add keys, nested ones too; nbep 0.1.0 wrote an integral double
     * without a fraction ("energy_initial": 6). */
    s = every_key_set();
    s.energy_initial = 6.0;
    json = nbep_summary_to_json(&s);
    assert_non_null(json);
    char *at = strstr(json, "\"energy_initial\": 6.0");
    assert_non_null(at);
    memmove(at + strlen("\"energy_initial\": 6"), at + strlen("\"energy_initial\": 6.0"),
            strlen(at + strlen("\"energy_initial\": 6.0")) + 1);
    char *longer = malloc(strlen(json) + 64);
    assert_non_null(longer);
    snprintf(longer, strlen(json) + 64, "{\"later\": {\"a\": [1, null, \"}\"]}, %s", json + 1);
    assert_true(nbep_summary_from_json(longer, &r));
    assert_true(r.energy_initial == 6.0);
    assert_same_summary(&s, &r);
    free(longer);
    free(json);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_key_round_trips_exactly),
        cmocka_unit_test(test_every_key_is_written_once_and_required_by_the_reader),
        cmocka_unit_test(test_an_unknown_pressure_is_null_and_reads_back_unknown),
        cmocka_unit_test(test_text_that_is_not_a_summary_is_refused),
        cmocka_unit_test(test_escapes_nested_values_and_old_integral_reals_are_read),
        cmocka_unit_test(test_values_out_of_range_and_repeated_keys_are_refused),
    };
    return cmocka_run_group_tests_name("summary", tests, NULL, NULL);
}
