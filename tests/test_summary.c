/* Tests of the JSON summary (summary.h): every key of NBEP_SUMMARY_FIELDS is written and read
 * back to the bit, each one is required by the reader but those added later (status,
 * steps_requested: an older summary lacks them and reads with them unknown), a null key stays
 * null, and a run's status follows how it ended. The keys come from the same table as the
 * code under test, so a key of an existing kind added there is covered here without editing
 * this file; the values are chosen so that no two keys share one and every number needs all
 * its digits. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

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
/* (a status other than the first of the list, so that a reader that maps every text to it is
 * seen) */
static void fill_STATUS(nbep_summary_status *v, int k)
{
    (void)k;
    *v = NBEP_SUMMARY_TERMINATED;
}
static void fill_COUNT(nbep_summary_count *v, int k)
{
    *v = (nbep_summary_count){.known = true, .value = (UINT64_C(1) << 53) + 3 + (uint64_t)k};
}

/* Whether a key of this kind may be missing (a summary written before it was added). */
enum { OPTIONAL_TEXT = 0, OPTIONAL_INT = 0, OPTIONAL_UINT = 0, OPTIONAL_REAL = 0,
       OPTIONAL_NULLABLE = 0, OPTIONAL_STATUS = 1, OPTIONAL_COUNT = 1 };

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
#define X_FILL_STATUS(field) X_FILL_OTHER(field, STATUS)
#define X_FILL_COUNT(field) X_FILL_OTHER(field, COUNT)
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
#define X_SAME_STATUS(field) assert_int_equal(a->field, b->field)
#define X_SAME_COUNT(field)                                                                  \
    assert_int_equal(a->field.known, b->field.known);                                        \
    assert_true(!a->field.known || a->field.value == b->field.value)
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

/* Every key is written once; the reader refuses a text without one of the keys SPEC has had
 * from the start or since contract 2, and reads one without a key added later (status,
 * steps_requested), as an older nbep wrote it, with that key unknown and the others as they
 * were. */
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
    static const bool optional[] = {
#define X_OPTIONAL(field, kind) OPTIONAL_##kind,
        NBEP_SUMMARY_FIELDS(X_OPTIONAL)
#undef X_OPTIONAL
    };
    size_t n_optional = 0;
    for (size_t k = 0; k < sizeof keys / sizeof *keys; k++) {
        char *at = strstr(json, keys[k]);
        if (!at)
            fail_msg("key %s is not written: %s", keys[k], json);
        assert_null(strstr(at + 1, keys[k]));
        /* the same text with this one key renamed: no summary, or one without that key */
        at[1] = 'X';
        memset(&r, 0xA5, sizeof r);
        const bool read = nbep_summary_from_json(json, &r);
        at[1] = keys[k][1];
        if (read != optional[k])
            fail_msg("without %s the text %s", keys[k], read ? "reads" : "is refused");
        if (optional[k]) {
            nbep_summary want = s;
            if (strcmp(keys[k], "\"status\": ") == 0)
                want.status = NBEP_SUMMARY_UNKNOWN;
            else if (strcmp(keys[k], "\"steps_requested\": ") == 0)
                want.steps_requested = (nbep_summary_count){.known = false};
            else
                fail_msg("an optional key this test does not know: %s", keys[k]);
            assert_same_summary(&want, &r);
            n_optional++;
        }
    }
    assert_int_equal(n_optional, 2);
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

/* How a run ended follows its exit status (SPEC: 0 done, 1 failure at run time, 130 and 143
 * the signals), each with its own text. */
static void test_a_runs_status_follows_how_it_ended(void **state)
{
    (void)state;
    assert_int_equal(nbep_summary_status_of(NBEP_OK), NBEP_SUMMARY_COMPLETED);
    assert_int_equal(nbep_summary_status_of(NBEP_ESIGINT), NBEP_SUMMARY_INTERRUPTED);
    assert_int_equal(nbep_summary_status_of(NBEP_ESIGTERM), NBEP_SUMMARY_TERMINATED);
    const nbep_status failures[] = {NBEP_EIO, NBEP_ENOMEM, NBEP_ENUMERIC, NBEP_EDECK,
                                    NBEP_EUSAGE};
    for (size_t k = 0; k < sizeof failures / sizeof *failures; k++)
        assert_int_equal(nbep_summary_status_of(failures[k]), NBEP_SUMMARY_FAILED);
    assert_string_equal(nbep_summary_status_text(NBEP_SUMMARY_COMPLETED), "completed");
    assert_string_equal(nbep_summary_status_text(NBEP_SUMMARY_INTERRUPTED), "interrupted");
    assert_string_equal(nbep_summary_status_text(NBEP_SUMMARY_TERMINATED), "terminated");
    assert_string_equal(nbep_summary_status_text(NBEP_SUMMARY_FAILED), "failed");
    assert_null(nbep_summary_status_text(NBEP_SUMMARY_UNKNOWN));
}

/* Each status is written as its text and read back as itself; an unknown status and an unknown
 * steps_requested are written as null and read back unknown. */
static void test_each_status_is_its_text_and_unknown_is_null(void **state)
{
    (void)state;
    static const struct {
        nbep_summary_status status;
        const char *text;
    } cases[] = {
        {NBEP_SUMMARY_COMPLETED, "\"status\": \"completed\", "},
        {NBEP_SUMMARY_INTERRUPTED, "\"status\": \"interrupted\", "},
        {NBEP_SUMMARY_TERMINATED, "\"status\": \"terminated\", "},
        {NBEP_SUMMARY_FAILED, "\"status\": \"failed\", "},
        {NBEP_SUMMARY_UNKNOWN, "\"status\": null, "},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        nbep_summary s = every_key_set(), r;
        s.status = cases[k].status;
        s.steps_requested = (nbep_summary_count){.known = k % 2 == 0, .value = 1000 + k};
        char *json = nbep_summary_to_json(&s);
        assert_non_null(json);
        if (!strstr(json, cases[k].text))
            fail_msg("no %s in %s", cases[k].text, json);
        char want[64] = "\"steps_requested\": null}\n";
        if (k % 2 == 0)
            snprintf(want, sizeof want, "\"steps_requested\": %zu}\n", 1000 + k);
        if (!strstr(json, want))
            fail_msg("no %s in %s", want, json);
        memset(&r, 0xA5, sizeof r);
        assert_true(nbep_summary_from_json(json, &r));
        assert_int_equal(r.status, cases[k].status);
        assert_int_equal(r.steps_requested.known, k % 2 == 0);
        assert_same_summary(&s, &r);
        free(json);
    }
}

/* A summary as nbep wrote it before `status` and `steps_requested` (README's example of
 * 2026-11-29, verbatim) still reads, its keys as they were and the two unknown: a sweep or a
 * script reading an older study's summaries takes them. */
static void test_an_older_summary_without_status_reads_as_unknown(void **state)
{
    (void)state;
    static const char older[] =
        "{\"format\": \"nbep-summary-1\", \"version\": \"0.1.0\", \"algorithm\": "
        "\"predictive\", \"threads\": 2, \"spheres\": 2, \"planes\": 0, \"steps\": 2000, "
        "\"dt\": 0.001, \"setup_seconds\": 0.0006685859989374876, \"wall_seconds\": "
        "0.04387803200370399, \"steps_per_second\": 45580.89569357096, \"checks\": 4006, "
        "\"predictions\": 4, \"collisions\": 1, \"sphere_collisions\": 1, "
        "\"plane_collisions\": 0, \"quiet_steps\": 1999, \"energy_initial\": 6.0, "
        "\"energy_final\": 5.999999999999999, \"energy_rel_drift\": -1.4802973661668753e-16, "
        "\"max_overlap\": 1.1657341758564144e-15, \"max_overlap_rel\": 5.828670879282072e-15, "
        "\"peak_rss_bytes\": 16977920, \"pressure\": null}\n";
    nbep_summary r;
    memset(&r, 0xA5, sizeof r);
    assert_true(nbep_summary_from_json(older, &r));
    assert_int_equal(r.status, NBEP_SUMMARY_UNKNOWN);
    assert_false(r.steps_requested.known);
    assert_string_equal(r.algorithm, "predictive");
    assert_int_equal(r.steps, 2000);
    assert_int_equal(r.checks, 4006);
    assert_int_equal(r.peak_rss_bytes, 16977920);
    assert_true(r.energy_final == 5.999999999999999);
    assert_false(r.pressure.known);
}

/* A status that is none of the four texts (another case, a word nbep never writes, a number)
 * and a steps_requested that is no count are not what nbep wrote: refused, as a value out of
 * range is, so that a sweep never reuses a run on a status it cannot read. */
static void test_a_status_or_steps_requested_nbep_never_writes_is_refused(void **state)
{
    (void)state;
    nbep_summary s = every_key_set(), r;
    s.status = NBEP_SUMMARY_COMPLETED;
    s.steps_requested = (nbep_summary_count){.known = true, .value = 20};
    char *json = nbep_summary_to_json(&s);
    assert_non_null(json);
    assert_true(nbep_summary_from_json(json, &r));
    const char *const bad[][2] = {
        {"\"status\": \"completed\"", "\"status\": \"Completed\""},
        {"\"status\": \"completed\"", "\"status\": \"done\""},
        {"\"status\": \"completed\"", "\"status\": \"\""},
        {"\"status\": \"completed\"", "\"status\": 0"},
        {"\"status\": \"completed\"", "\"status\": [\"completed\"]"},
        {"\"steps_requested\": 20", "\"steps_requested\": -20"},
        {"\"steps_requested\": 20", "\"steps_requested\": 20.0"},
        {"\"steps_requested\": 20", "\"steps_requested\": \"20\""},
    };
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        char *e = edited(json, bad[k][0], bad[k][1]);
        if (nbep_summary_from_json(e, &r))
            fail_msg("read as a summary: %s", e);
        free(e);
    }
    free(json);
}

/* A path as a JSON string (nbep check's and the sweep's reports): valid UTF-8 kept as it is,
 * each byte outside a valid sequence U+FFFD (jansson refuses text that is not UTF-8: a deck
 * named in Latin-1 made the whole report fail as out of memory), the text after it kept. */
static void test_a_path_of_any_bytes_is_a_json_string(void **state)
{
    (void)state;
    static const char *const cases[][2] = {
        {"run.h5", "run.h5"},
        {"", ""},
        {"r\xc3\xa9s/\xe6\x97\xa5/\xf0\x9f\x98\x80.h5",                 /* 2, 3 and 4 bytes */
         "r\xc3\xa9s/\xe6\x97\xa5/\xf0\x9f\x98\x80.h5"},
        {"r\xe9sultats/a.h5", "r\xef\xbf\xbdsultats/a.h5"},  /* Latin-1 */
        {"a\xc0\xaf" "b", "a\xef\xbf\xbd\xef\xbf\xbd" "b"},      /* overlong '/' */
        {"a\xe0\x80\xaf" "b",                                 /* overlong, 3 bytes */
         "a\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd" "b"},
        {"a\xf0\x80\x80\xaf",                                 /* overlong, 4 bytes */
         "a\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"},
        {"a\xed\xa0\x80" "b", "a\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd" "b"}, /* a surrogate */
        {"a\xf4\x90\x80\x80",                                   /* past U+10FFFF */
         "a\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd"},
        {"a\xe6\x97", "a\xef\xbf\xbd\xef\xbf\xbd"},          /* cut short at the end */
        {"\xc3\xa9\xc3", "\xc3\xa9\xef\xbf\xbd"},
        {"\x7f\x80", "\x7f\xef\xbf\xbd"},
        /* a quote and a backslash within the text, then what reads as a number: the line's
         * numbers are shortened (1.50 to 1.5) only outside strings, whose escapes it steps
         * over (a deck named x"1.50.deck came out as x\"1.5deck) */
        {"x\"1.50.deck", "x\"1.50.deck"},
        {"x\\\"2.50e+00\\", "x\\\"2.50e+00\\"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        json_t *o = nbep_summary_json_text(cases[k][0]);
        assert_non_null(o);
        assert_string_equal(json_string_value(o), cases[k][1]);
        /* and the line written of it reads back as JSON, the same text */
        json_t *obj = json_pack("{s:o}", "path", o);
        assert_non_null(obj);
        char *line = nbep_summary_dump_line(obj);
        assert_non_null(line);
        json_decref(obj);
        json_t *back = json_loads(line, 0, NULL);
        assert_non_null(back);
        assert_string_equal(json_string_value(json_object_get(back, "path")), cases[k][1]);
        json_decref(back);
        free(line);
    }
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
        cmocka_unit_test(test_a_runs_status_follows_how_it_ended),
        cmocka_unit_test(test_each_status_is_its_text_and_unknown_is_null),
        cmocka_unit_test(test_an_older_summary_without_status_reads_as_unknown),
        cmocka_unit_test(test_a_status_or_steps_requested_nbep_never_writes_is_refused),
        cmocka_unit_test(test_a_path_of_any_bytes_is_a_json_string),
    };
    return cmocka_run_group_tests_name("summary", tests, NULL, NULL);
}
