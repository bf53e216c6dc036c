/* The JSON summary (summary.h): writer and parser, both driven by NBEP_SUMMARY_FIELDS. */
#include "nbep/summary.h"

#include <assert.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "build_info.h"
#include "nbep/compiler.h"

#define SUMMARY_FORMAT_NAME "nbep-summary-1"

/* ---- writing ------------------------------------------------------------------------------- */

/* A stream, the bytes written to it so far and the keys written; bad once a write failed. */
typedef struct json_out {
    FILE *f;
    long n;
    int keys;
    int bad;
} json_out;

NBEP_PRINTF(2, 3)
static void jprintf(json_out *j, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int k = vfprintf(j->f, fmt, ap);
    va_end(ap);
    if (k < 0)
        j->bad = 1;
    else
        j->n += k;
}

/* `"key": ` with the separator SPEC's sample uses (", ") before every key but the first. */
static void jkey(json_out *j, const char *key)
{
    jprintf(j, "%s\"%s\": ", j->keys++ ? ", " : "", key);
}

static void put_TEXT(json_out *j, const char *key, const char *v)
{
    jkey(j, key);
    jprintf(j, "\"");
    for (const unsigned char *c = (const unsigned char *)v; *c; c++) {
        if (*c == '"' || *c == '\\')
            jprintf(j, "\\%c", *c);
        else if (*c < 0x20)
            jprintf(j, "\\u%04x", *c);
        else
            jprintf(j, "%c", *c);
    }
    jprintf(j, "\"");
}

static void put_REAL(json_out *j, const char *key, double v)
{
    /* JSON has no inf or nan. The simulation guarantees finite numbers (it checks the state
     * before every frame), so a non-finite value here is a bug: caught by the assertion in
     * debug builds, written as 0 otherwise so that the summary still parses. */
    assert(isfinite(v));
    if (!isfinite(v))
        v = 0.0;
    jkey(j, key);
    jprintf(j, "%.17g", v);
}

static void put_NULLABLE(json_out *j, const char *key, nbep_summary_nullable v)
{
    if (v.known) {
        put_REAL(j, key, v.value);
    } else {
        jkey(j, key);
        jprintf(j, "null");
    }
}

static void put_UINT(json_out *j, const char *key, uint64_t v)
{
    jkey(j, key);
    jprintf(j, "%" PRIu64, v);
}

static void put_INT(json_out *j, const char *key, int v)
{
    jkey(j, key);
    jprintf(j, "%d", v);
}

int nbep_summary_write_json(const nbep_summary *s, FILE *f)
{
    json_out j = {f, 0, 0, 0};
    jprintf(&j, "{");
    put_TEXT(&j, "format", SUMMARY_FORMAT_NAME);
    put_TEXT(&j, "version", NBEP_VERSION);
#define X_PUT(field, kind) put_##kind(&j, #field, s->field);
    NBEP_SUMMARY_FIELDS(X_PUT)
#undef X_PUT
    jprintf(&j, "}\n");
    return j.bad || ferror(f) ? -1 : (int)j.n;
}

char *nbep_summary_to_json(const nbep_summary *s)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f)
        return NULL;
    int n = nbep_summary_write_json(s, f);
    if (fclose(f) != 0 || n < 0) {
        free(buf);
        return NULL;
    }
    return buf;
}

/* ---- reading ------------------------------------------------------------------------------- */

/* The position of the value of "key" in a flat JSON object, or NULL. */
static const char *json_value(const char *json, const char *key)
{
    size_t klen = strlen(key);
    for (const char *q = strchr(json, '"'); q; q = strchr(q + 1, '"')) {
        if (strncmp(q + 1, key, klen) == 0 && q[1 + klen] == '"') {
            const char *v = q + 2 + klen;
            while (*v == ' ')
                v++;
            if (*v != ':')
                continue;
            v++;
            while (*v == ' ')
                v++;
            return v;
        }
    }
    return NULL;
}

static bool get_REAL(const char *json, const char *key, double *out)
{
    const char *v = json_value(json, key);
    char *end;
    if (!v)
        return false;
    double x = strtod(v, &end);
    if (end == v)
        return false;
    *out = x;
    return true;
}

static bool get_NULLABLE(const char *json, const char *key, nbep_summary_nullable *out)
{
    const char *v = json_value(json, key);
    if (v && strncmp(v, "null", 4) == 0) {
        *out = (nbep_summary_nullable){.known = false};
        return true;
    }
    out->known = true;
    return get_REAL(json, key, &out->value);
}

static bool get_UINT(const char *json, const char *key, uint64_t *out)
{
    const char *v = json_value(json, key);
    char *end;
    if (!v || *v == '-')
        return false;
    errno = 0;
    unsigned long long x = strtoull(v, &end, 10);
    if (end == v || errno)
        return false;
    *out = (uint64_t)x;
    return true;
}

static bool get_INT(const char *json, const char *key, int *out)
{
    uint64_t u;
    if (!get_UINT(json, key, &u) || u > INT32_MAX)
        return false;
    *out = (int)u;
    return true;
}

/* A string without escapes (the algorithm's name) of fewer than cap bytes. */
static bool get_string(const char *json, const char *key, char *out, size_t cap)
{
    const char *v = json_value(json, key);
    if (!v || *v != '"')
        return false;
    size_t n = strcspn(v + 1, "\"\\");
    if (v[1 + n] != '"' || n >= cap)
        return false;
    memcpy(out, v + 1, n);
    out[n] = '\0';
    return true;
}

bool nbep_summary_from_json(const char *json, nbep_summary *sum)
{
    nbep_summary s;
    memset(&s, 0, sizeof s);
    char format[sizeof SUMMARY_FORMAT_NAME + 1];
    if (!json || !get_string(json, "format", format, sizeof format) ||
        strcmp(format, SUMMARY_FORMAT_NAME) != 0)
        return false;
    bool ok = true;
#define X_GET_TEXT(field) get_string(json, #field, s.field, sizeof s.field)
#define X_GET_OTHER(field, kind) get_##kind(json, #field, &s.field)
#define X_GET_INT(field) X_GET_OTHER(field, INT)
#define X_GET_UINT(field) X_GET_OTHER(field, UINT)
#define X_GET_REAL(field) X_GET_OTHER(field, REAL)
#define X_GET_NULLABLE(field) X_GET_OTHER(field, NULLABLE)
#define X_GET(field, kind) ok = ok && X_GET_##kind(field);
    NBEP_SUMMARY_FIELDS(X_GET)
#undef X_GET
    if (!ok)
        return false;
    *sum = s;
    return true;
}
