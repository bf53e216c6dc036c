/* The JSON summary (summary.h): writer and parser, both driven by NBEP_SUMMARY_FIELDS, on
 * jansson (README "Build" says why jansson). jansson.h is included here and where the other
 * JSON reports are made, check.c (nbep check's) and sweep.c (the sweep's totals), which write
 * their lines through nbep_summary_dump_line. */
#include "nbep/summary.h"

#include <assert.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "build_info.h"

#define SUMMARY_FORMAT_NAME "nbep-summary-1"
/* One line with SPEC's separators (", " and ": ", jansson's default without JSON_COMPACT or
 * JSON_INDENT), keys in insertion order, and reals with 17 significant digits so that every
 * double reads back to the bit. */
#define DUMP_FLAGS (JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(17))

/* ---- writing ------------------------------------------------------------------------------- */

/* Each returns a new reference, or NULL when the value has no JSON form or memory ran out. */
static json_t *value_TEXT(const char *v)
{
    return json_string(v);
}

static json_t *value_INT(int v)
{
    return json_integer(v);
}

static json_t *value_UINT(uint64_t v)
{
    /* jansson's integers are signed 64-bit; a counter past 2^63 (centuries of stepping) has
     * no exact JSON number here, and a rounded one would pass for exact: refuse it. */
    return v <= (uint64_t)LLONG_MAX ? json_integer((json_int_t)v) : NULL;
}

static json_t *value_REAL(double v)
{
    /* JSON has no inf or nan. The simulation guarantees finite numbers (it checks the state
     * before every frame), so a non-finite value here is a bug: caught by the assertion in
     * debug builds, written as 0 otherwise so that the summary still parses. */
    assert(isfinite(v));
    return json_real(isfinite(v) ? v : 0.0);
}

static json_t *value_NULLABLE(nbep_summary_nullable v)
{
    return v.known ? value_REAL(v.value) : json_null();
}

static json_t *value_STATUS(nbep_summary_status v)
{
    const char *text = nbep_summary_status_text(v);
    return text ? json_string(text) : json_null();
}

static json_t *value_COUNT(nbep_summary_count v)
{
    return v.known ? value_UINT(v.value) : json_null();
}

nbep_summary_status nbep_summary_status_of(nbep_status st)
{
    switch (st) {
    case NBEP_OK:
        return NBEP_SUMMARY_COMPLETED;
    case NBEP_ESIGINT:
        return NBEP_SUMMARY_INTERRUPTED;
    case NBEP_ESIGTERM:
        return NBEP_SUMMARY_TERMINATED;
    default:
        return NBEP_SUMMARY_FAILED;
    }
}

bool nbep_summary_ended(const nbep_summary *s)
{
    return s->status == NBEP_SUMMARY_COMPLETED || s->status == NBEP_SUMMARY_UNKNOWN;
}

const char *nbep_summary_status_text(nbep_summary_status s)
{
    switch (s) {
#define X_TEXT(name, text)                                                                   \
    case NBEP_SUMMARY_##name:                                                                \
        return text;
        NBEP_SUMMARY_STATUS_LIST(X_TEXT)
#undef X_TEXT
    }
    return NULL;
}

/* The summary as a jansson object, or NULL (out of memory, or a value without JSON form). */
static json_t *summary_object(const nbep_summary *s)
{
    json_t *o = json_object();
    int bad = !o;
    bad = bad || json_object_set_new(o, "format", json_string(SUMMARY_FORMAT_NAME)) != 0;
    bad = bad || json_object_set_new(o, "version", json_string(NBEP_VERSION)) != 0;
#define X_SET(field, kind) bad = bad || json_object_set_new(o, #field, value_##kind(s->field)) != 0;
    NBEP_SUMMARY_FIELDS(X_SET)
#undef X_SET
    if (bad) {
        json_decref(o);
        return NULL;
    }
    return o;
}

const char *nbep_format_real(double v, bool mark_real, char buf[NBEP_REAL_TEXT_MAX])
{
    for (int digits = 1; digits <= 17; digits++) {
        snprintf(buf, NBEP_REAL_TEXT_MAX, "%.*g", digits, v);
        if (strtod(buf, NULL) == v)
            break;
    }
    /* %g takes an exponent from the digits' count up; such a whole number is exact in a
     * double below 2^53, so %.0f writes the same value */
    if (strpbrk(buf, "eE") && fabs(v) >= 1.0 && fabs(v) < 1e15 && v == floor(v))
        snprintf(buf, NBEP_REAL_TEXT_MAX, "%.0f", v);
    if (mark_real && !strpbrk(buf, ".eEn")) /* (n: inf and nan, which JSON never gets) */
        strcat(buf, ".0");
    return buf;
}

/* jansson's text with every real number written as nbep_format_real does (jansson writes 17
 * digits, 0.050000000000000003 for 0.05; the same double either way, so every value still
 * reads back bit for bit); strings and integers as they are. NULL when out of memory. */
static char *shorten_reals(const char *text)
{
    /* a number does not grow (jansson's has 17 digits and the same form): room to spare */
    char *out = malloc(2 * strlen(text) + 1);
    if (!out)
        return NULL;
    char *w = out;
    for (const char *r = text; *r;) {
        if (*r == '"') { /* a string, escapes and all */
            *w++ = *r++;
            while (*r && *r != '"') {
                if (*r == '\\' && r[1])
                    *w++ = *r++;
                *w++ = *r++;
            }
            if (*r)
                *w++ = *r++;
            continue;
        }
        if (*r != '-' && !(*r >= '0' && *r <= '9')) {
            *w++ = *r++;
            continue;
        }
        const size_t len = strspn(r, "+-0123456789.eE");
        if (memchr(r, '.', len) || memchr(r, 'e', len) || memchr(r, 'E', len)) {
            char real[NBEP_REAL_TEXT_MAX];
            nbep_format_real(strtod(r, NULL), true, real);
            memcpy(w, real, strlen(real));
            w += strlen(real);
        } else {
            memcpy(w, r, len);
            w += len;
        }
        r += len;
    }
    *w = '\0';
    return out;
}

/* The length of the valid UTF-8 sequence at s (RFC 3629: no overlong form, no surrogate,
 * nothing past U+10FFFF), 0 where none starts there. */
static size_t utf8_sequence(const unsigned char *s)
{
    if (s[0] < 0x80)
        return 1;
    size_t len;
    unsigned lo = 0x80, hi = 0xBF; /* the second byte's range */
    if (s[0] >= 0xC2 && s[0] <= 0xDF) {
        len = 2;
    } else if (s[0] >= 0xE0 && s[0] <= 0xEF) {
        len = 3;
        lo = s[0] == 0xE0 ? 0xA0 : 0x80;
        hi = s[0] == 0xED ? 0x9F : 0xBF;
    } else if (s[0] >= 0xF0 && s[0] <= 0xF4) {
        len = 4;
        lo = s[0] == 0xF0 ? 0x90 : 0x80;
        hi = s[0] == 0xF4 ? 0x8F : 0xBF;
    } else {
        return 0;
    }
    if (s[1] < lo || s[1] > hi)
        return 0;
    for (size_t k = 2; k < len; k++)
        if (s[k] < 0x80 || s[k] > 0xBF)
            return 0;
    return len;
}

bool nbep_utf8_valid(const char *s)
{
    for (const unsigned char *r = (const unsigned char *)s; *r;) {
        const size_t len = utf8_sequence(r);
        if (!len)
            return false;
        r += len;
    }
    return true;
}

json_t *nbep_summary_json_text(const char *s)
{
    /* each byte at most the three of U+FFFD */
    char *valid = malloc(3 * strlen(s) + 1);
    if (!valid)
        return NULL;
    char *w = valid;
    for (const unsigned char *r = (const unsigned char *)s; *r;) {
        const size_t len = utf8_sequence(r);
        if (len) {
            memcpy(w, r, len);
            w += len;
            r += len;
        } else {
            memcpy(w, "\xEF\xBF\xBD", 3);
            w += 3;
            r++;
        }
    }
    *w = '\0';
    json_t *o = json_string(valid);
    free(valid);
    return o;
}

char *nbep_summary_dump_line(json_t *o)
{
    char *dumped = json_dumps(o, DUMP_FLAGS);
    char *text = dumped ? shorten_reals(dumped) : NULL;
    free(dumped);
    char *line = text ? malloc(strlen(text) + 2) : NULL;
    if (line) {
        strcpy(line, text);
        strcat(line, "\n");
    }
    free(text);
    return line;
}

char *nbep_summary_to_json(const nbep_summary *s)
{
    json_t *o = summary_object(s);
    char *line = o ? nbep_summary_dump_line(o) : NULL;
    json_decref(o);
    return line;
}

int nbep_summary_write_json(const nbep_summary *s, FILE *f)
{
    char *line = nbep_summary_to_json(s);
    if (!line)
        return -1;
    size_t n = strlen(line);
    int bad = fputs(line, f) == EOF || ferror(f) || n > INT_MAX;
    free(line);
    return bad ? -1 : (int)n;
}

/* ---- reading ------------------------------------------------------------------------------- */

/* Each reads one value (NULL when the key is missing) and returns false for the wrong type or
 * a value out of the field's range. */
static bool get_TEXT(const json_t *v, char *out, size_t cap)
{
    const char *text = json_string_value(v);
    if (!text || strlen(text) >= cap)
        return false;
    strcpy(out, text);
    return true;
}

static bool get_INT(const json_t *v, int *out)
{
    if (!json_is_integer(v) || json_integer_value(v) < 0 || json_integer_value(v) > INT_MAX)
        return false;
    *out = (int)json_integer_value(v);
    return true;
}

static bool get_UINT(const json_t *v, uint64_t *out)
{
    if (!json_is_integer(v) || json_integer_value(v) < 0)
        return false;
    *out = (uint64_t)json_integer_value(v);
    return true;
}

/* An integral real may have been written without a fraction ("6" by nbep 0.1.0's writer). */
static bool get_REAL(const json_t *v, double *out)
{
    if (!json_is_number(v))
        return false;
    *out = json_number_value(v);
    return true;
}

static bool get_NULLABLE(const json_t *v, nbep_summary_nullable *out)
{
    if (json_is_null(v)) {
        *out = (nbep_summary_nullable){.known = false};
        return true;
    }
    out->known = true;
    return get_REAL(v, &out->value);
}

/* Keys added later (STATUS and COUNT kinds) may be missing: a summary written before them. */
static bool get_STATUS(const json_t *v, nbep_summary_status *out)
{
    if (!v || json_is_null(v)) {
        *out = NBEP_SUMMARY_UNKNOWN;
        return true;
    }
    const char *text = json_string_value(v);
#define X_ONE(name, text) +1
    enum { N_STATUS = 0 NBEP_SUMMARY_STATUS_LIST(X_ONE) };
#undef X_ONE
    for (int k = 0; text && k < N_STATUS; k++) {
        const char *name = nbep_summary_status_text((nbep_summary_status)k);
        if (name && strcmp(text, name) == 0) {
            *out = (nbep_summary_status)k;
            return true;
        }
    }
    return false; /* a number, or a text that is no status: not a summary nbep wrote */
}

static bool get_COUNT(const json_t *v, nbep_summary_count *out)
{
    if (!v || json_is_null(v)) {
        *out = (nbep_summary_count){.known = false};
        return true;
    }
    out->known = true;
    return get_UINT(v, &out->value);
}

bool nbep_summary_from_json(const char *json, nbep_summary *sum)
{
    if (!json)
        return false;
    json_t *o = json_loads(json, JSON_REJECT_DUPLICATES, NULL);
    const char *format = json_string_value(json_object_get(o, "format"));
    bool ok = json_is_object(o) && format && strcmp(format, SUMMARY_FORMAT_NAME) == 0;
    nbep_summary s;
    memset(&s, 0, sizeof s);
#define X_GET_TEXT(field) get_TEXT(json_object_get(o, #field), s.field, sizeof s.field)
#define X_GET_OTHER(field, kind) get_##kind(json_object_get(o, #field), &s.field)
#define X_GET_INT(field) X_GET_OTHER(field, INT)
#define X_GET_UINT(field) X_GET_OTHER(field, UINT)
#define X_GET_REAL(field) X_GET_OTHER(field, REAL)
#define X_GET_NULLABLE(field) X_GET_OTHER(field, NULLABLE)
#define X_GET_STATUS(field) X_GET_OTHER(field, STATUS)
#define X_GET_COUNT(field) X_GET_OTHER(field, COUNT)
#define X_GET(field, kind) ok = ok && X_GET_##kind(field);
    NBEP_SUMMARY_FIELDS(X_GET)
#undef X_GET
    json_decref(o);
    if (ok)
        *sum = s;
    return ok;
}
