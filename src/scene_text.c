/* Text helpers of the scene module: a growable string, the rewrite that makes libconfig 1.5
 * read integers and arrays the way users write them, libconfig text of a value (for sweep
 * values and "(got ...)" in messages) and the edit distance behind "did you mean". */
#include "scene_impl.h"

#include <ctype.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- growable strings ----------------------------------------------------------------------- */

static bool strbuf_reserve(nbep__strbuf *b, size_t extra)
{
    if (b->oom)
        return false;
    if (b->len + extra + 1 <= b->cap)
        return true;
    size_t cap = b->cap ? b->cap : 64;
    while (cap < b->len + extra + 1)
        cap *= 2;
    char *p = realloc(b->p, cap);
    if (!p) {
        b->oom = true;
        return false;
    }
    b->p = p;
    b->cap = cap;
    return true;
}

void nbep__strbuf_addn(nbep__strbuf *b, const char *s, size_t n)
{
    if (!strbuf_reserve(b, n))
        return;
    memcpy(b->p + b->len, s, n);
    b->len += n;
    b->p[b->len] = '\0';
}

void nbep__strbuf_add(nbep__strbuf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || !strbuf_reserve(b, (size_t)n))
        return;
    va_start(ap, fmt);
    vsnprintf(b->p + b->len, (size_t)n + 1, fmt, ap);
    va_end(ap);
    b->len += (size_t)n;
}

const char *nbep__strbuf_str(const nbep__strbuf *b)
{
    return b->p ? b->p : "";
}

void nbep__strbuf_fini(nbep__strbuf *b)
{
    free(b->p);
    memset(b, 0, sizeof *b);
}

/* ---- the libconfig 1.5 rewrite -------------------------------------------------------------- */

/* libconfig 1.5 reads a decimal integer without the L suffix into an int and silently wraps
 * it: `count = 5000000000;` becomes 705032704. It also rejects an array that mixes integers
 * and floats, so `gravity = [0, 0, -9.81]` is a syntax error although every number of a
 * vector is a float to us. Before parsing, the text is therefore rewritten token by token:
 *   - an integer beyond 32 bits gets the suffix L (read as 64-bit, as libconfig 1.7 does);
 *     in an array of integers, one such integer gives every integer the suffix, since an
 *     array must hold one type;
 *   - in an array holding a float, each plain decimal integer gets ".0".
 * Only insertions are made, never newlines, so libconfig's line numbers stay the deck's.
 * Strings, comments and setting names (which may hold digits and '-') are skipped. */

typedef struct widen_edit {
    size_t pos;      /* insert after this many bytes of the input */
    bool dot0;       /* ".0", else "L" */
} widen_edit;

typedef struct widen_int {
    size_t end;      /* just past its digits */
    bool big, hex, has_l;
} widen_int;

typedef struct widen {
    widen_edit *edit;
    size_t n_edit, cap_edit;
    widen_int *ints;         /* integers of the array being scanned */
    size_t n_ints, cap_ints;
    bool oom;
} widen;

static void widen_push_edit(widen *w, size_t pos, bool dot0)
{
    if (w->n_edit == w->cap_edit) {
        size_t cap = w->cap_edit ? 2 * w->cap_edit : 16;
        widen_edit *e = realloc(w->edit, cap * sizeof *e);
        if (!e) {
            w->oom = true;
            return;
        }
        w->edit = e;
        w->cap_edit = cap;
    }
    w->edit[w->n_edit++] = (widen_edit){pos, dot0};
}

static void widen_push_int(widen *w, widen_int v)
{
    if (w->n_ints == w->cap_ints) {
        size_t cap = w->cap_ints ? 2 * w->cap_ints : 16;
        widen_int *e = realloc(w->ints, cap * sizeof *e);
        if (!e) {
            w->oom = true;
            return;
        }
        w->ints = e;
        w->cap_ints = cap;
    }
    w->ints[w->n_ints++] = v;
}

/* Decides the edits for the integers of one array, at its closing bracket. */
static void widen_flush_array(widen *w, bool has_float)
{
    bool any_big = false;
    for (size_t k = 0; k < w->n_ints; k++)
        any_big = any_big || (w->ints[k].big && !w->ints[k].has_l);
    for (size_t k = 0; k < w->n_ints; k++) {
        const widen_int *v = &w->ints[k];
        if (v->has_l)
            continue;
        if (has_float && !v->hex)
            widen_push_edit(w, v->end, true);
        else if (!has_float && any_big)
            widen_push_edit(w, v->end, false);
    }
    w->n_ints = 0;
}

static bool is_name_start(char ch)
{
    return isalpha((unsigned char)ch) || ch == '*';
}

static bool is_name_char(char ch)
{
    return isalnum((unsigned char)ch) || ch == '-' || ch == '_' || ch == '*';
}

static int hex_digit(char ch)
{
    if (ch >= '0' && ch <= '9')
        return ch - '0';
    return tolower((unsigned char)ch) - 'a' + 10;
}

/* Whether text[i] (an '@') starts libconfig's include directive: "@include" with only blanks
 * before it on its line and a blank after it (its scanner's `^[ \t]*@include[ \t]+\"`). */
static bool is_include(const char *text, size_t i)
{
    if (strncmp(text + i, "@include", 8) != 0 || (text[i + 8] != ' ' && text[i + 8] != '\t'))
        return false;
    while (i > 0 && (text[i - 1] == ' ' || text[i - 1] == '\t'))
        i--;
    return i == 0 || text[i - 1] == '\n';
}

/* Past what carries no value at text[*i] (n its length): a newline, a comment (#, // or
 * / * ... * /, as libconfig reads them) or a string (its escapes too), counting the lines it
 * passes in *line. False, nothing moved, at anything else. */
static bool skip_quiet(const char *text, size_t n, size_t *i, size_t *line)
{
    const char ch = text[*i];
    if (ch == '\n') {
        (*line)++;
        (*i)++;
    } else if (ch == '#' || (ch == '/' && text[*i + 1] == '/')) {
        while (*i < n && text[*i] != '\n')
            (*i)++;
    } else if (ch == '/' && text[*i + 1] == '*') {
        *i += 2;
        while (*i < n && !(text[*i] == '*' && text[*i + 1] == '/'))
            *line += text[(*i)++] == '\n';
        *i = *i + 2 < n ? *i + 2 : n;
    } else if (ch == '"') {
        for ((*i)++; *i < n && text[*i] != '"'; (*i)++) {
            if (text[*i] == '\\' && *i + 1 < n)
                (*i)++;
            *line += text[*i] == '\n';
        }
        (*i)++;
    } else {
        return false;
    }
    return true;
}

bool nbep__scene_unclosed(const char *text, size_t *line, char *opener)
{
    enum { DEPTH = 64 };
    char open[DEPTH];
    size_t at[DEPTH], depth = 0, ln = 1;
    const size_t n = strlen(text);
    for (size_t i = 0; i < n;) {
        if (skip_quiet(text, n, &i, &ln))
            continue;
        const char ch = text[i++];
        if (ch == '{' || ch == '(' || ch == '[') {
            if (depth < DEPTH) {
                open[depth] = ch;
                at[depth] = ln;
            }
            depth++;
        } else if ((ch == '}' || ch == ')' || ch == ']') && depth > 0) {
            depth--;
        }
    }
    if (depth == 0 || depth > DEPTH) /* (deeper than any deck: not said) */
        return false;
    *line = at[depth - 1];
    *opener = open[depth - 1];
    return true;
}

bool nbep__scene_trailing_comma(const char *text, size_t line, char *closer)
{
    const size_t n = strlen(text);
    size_t ln = 1;
    bool comma = false; /* the last thing read, strings and comments aside, was a comma */
    for (size_t i = 0; i < n;) {
        const bool string = text[i] == '"'; /* a value: skip_quiet passes it as a comment */
        if (skip_quiet(text, n, &i, &ln)) {
            comma = comma && !string;
            continue;
        }
        const char ch = text[i++];
        if ((ch == ')' || ch == ']') && comma && ln == line) {
            *closer = ch;
            return true;
        }
        if (ch != ' ' && ch != '\t' && ch != '\r')
            comma = ch == ',';
    }
    return false;
}

/* One line for a number the rewrite finds that libconfig would misread: at the deck's line,
 * or at the override `label` */
static void bad_number(nbep__scene_ctx *c, const char *label, size_t line, bool neg,
                       const char *digits, size_t n_digits, const char *kind, const char *why)
{
    if (!label)
        nbep_diag_add_ranked(c->d, nbep__scene_rank(c, NULL, line), __FILE__, __LINE__,
                             "%s:%zu: %s %s%.*s %s", c->deck, line, kind, neg ? "-" : "",
                             (int)n_digits, digits, why);
    else
        nbep_diag_add_ranked(c->d, nbep__scene_rank(c, label, 0), __FILE__, __LINE__,
                             "%s: %s %s%.*s %s", label, kind, neg ? "-" : "", (int)n_digits,
                             digits, why);
}

char *nbep__scene_widen(nbep__scene_ctx *c, const char *text, const char *label, size_t *n_bad,
                        size_t *n_unread)
{
    widen w = {0};
    const size_t n = strlen(text);
    size_t i = 0, line = 1;
    bool in_array = false, array_float = false;
    *n_bad = 0;
    if (n_unread)
        *n_unread = 0;

    while (i < n) {
        char ch = text[i];
        if (ch == '/' && text[i + 1] == '*' && !strstr(text + i + 2, "*/")) {
            /* libconfig reads an unclosed block comment to the end of the text, and every
             * setting after it was dropped without a word (until 2026-12-01, a review) */
            (*n_bad)++;
            if (n_unread) /* nothing after it to read: libconfig's errors would be its own */
                (*n_unread)++;
            if (!label)
                nbep_diag_add_ranked(c->d, nbep__scene_rank(c, NULL, line), __FILE__, __LINE__,
                                     "%s:%zu: this /* comment is never closed with */: every "
                                     "line after it would be read as the comment",
                                     c->deck, line);
            else
                nbep_diag_add_ranked(c->d, nbep__scene_rank(c, label, 0), __FILE__, __LINE__,
                                     "%s: a /* comment is never closed with */", label);
            break;
        }
        if (skip_quiet(text, n, &i, &line)) {
            continue;
        } else if (ch == '@' && is_include(text, i)) {
            /* A run keeps its deck's text (SPEC: the root's `deck`, the full text) and names
             * errors by its lines; an included file's text is in neither, and libconfig 1.5
             * reads it without this rewrite (a seed of 4294967297 there became 1). An
             * override's value is libconfig text too, kept as typed in the run's file: one
             * that spans lines can hold the directive (until 2026-11-30 it was read) */
            (*n_bad)++;
            if (n_unread)
                (*n_unread)++;
            if (!label)
                nbep_diag_add_ranked(c->d, nbep__scene_rank(c, NULL, line), __FILE__, __LINE__,
                                     "%s:%zu: @include is not supported: a run keeps its deck's "
                                     "text and names errors by its lines; put the included "
                                     "settings in the deck",
                                     c->deck, line);
            else
                nbep_diag_add_ranked(c->d, nbep__scene_rank(c, label, 0), __FILE__, __LINE__,
                                     "%s: @include is not supported: a run keeps its overrides "
                                     "as typed; give the included settings themselves",
                                     label);
            i += 8;
        } else if (is_name_start(ch)) {
            while (i < n && is_name_char(text[i]))
                i++;
        } else if (ch == '[') {
            in_array = true;
            array_float = false;
            w.n_ints = 0;
            i++;
        } else if (ch == ']') {
            if (in_array)
                widen_flush_array(&w, array_float);
            in_array = false;
            i++;
        } else if (isdigit((unsigned char)ch) ||
                   (ch == '.' && isdigit((unsigned char)text[i + 1]))) {
            size_t start = i;
            bool neg = start > 0 && text[start - 1] == '-';
            bool hex = false, is_float = false, overflow = false;
            uint64_t v = 0;
            if (ch == '0' && (text[i + 1] == 'x' || text[i + 1] == 'X') &&
                isxdigit((unsigned char)text[i + 2])) {
                hex = true;
                for (i += 2; isxdigit((unsigned char)text[i]); i++) {
                    overflow = overflow || v > (UINT64_MAX >> 4);
                    v = (v << 4) | (uint64_t)hex_digit(text[i]);
                }
            } else {
                for (; isdigit((unsigned char)text[i]); i++) {
                    uint64_t digit = (uint64_t)(text[i] - '0');
                    overflow = overflow || v > (UINT64_MAX - digit) / 10;
                    v = v * 10 + digit;
                }
                if (text[i] == '.') {
                    is_float = true;
                    for (i++; isdigit((unsigned char)text[i]); i++)
                        ;
                }
                if ((text[i] == 'e' || text[i] == 'E') &&
                    (isdigit((unsigned char)text[i + 1]) ||
                     ((text[i + 1] == '+' || text[i + 1] == '-') &&
                      isdigit((unsigned char)text[i + 2])))) {
                    is_float = true;
                    for (i += 2; isdigit((unsigned char)text[i]); i++)
                        ;
                }
            }
            if (is_float) {
                /* libconfig reads a float beyond a double's range as 0 (or as inf), and a run
                 * said `run.dt must be > 0 (got 0)` of `dt = 1e-400;` (until 2026-12-04) */
                bool nonzero = false;
                for (size_t k = start; k < i && text[k] != 'e' && text[k] != 'E'; k++)
                    nonzero = nonzero || (text[k] >= '1' && text[k] <= '9');
                const double x = strtod(text + start, NULL);
                if ((nonzero && x == 0.0) || isinf(x)) {
                    (*n_bad)++;
                    if (n_unread) /* not read on: its setting's check would say it again */
                        (*n_unread)++;
                    bad_number(c, label, line, neg, text + start, i - start, "number",
                               x == 0.0 ? "is beyond the range of a double (it would read as 0)"
                                        : "is beyond the range of a double (it would read as "
                                          "inf)");
                }
                array_float = array_float || in_array;
                continue;
            }
            size_t end = i;
            bool has_l = text[i] == 'L';
            while (text[i] == 'L')
                i++;
            const uint64_t max64 = neg ? (uint64_t)INT64_MAX + 1 : (uint64_t)INT64_MAX;
            const uint64_t max32 = neg ? (uint64_t)INT32_MAX + 1 : (uint64_t)INT32_MAX;
            if (overflow || v > max64) {
                (*n_bad)++;
                /* (libconfig's integers are signed: 2^64 - 1, a seed that fits 64 bits
                 * unsigned, does not; a review read "64 bits" as wrong for it) */
                bad_number(c, label, line, neg, text + start, end - start, "integer",
                           neg ? "does not fit in a signed 64-bit integer (at least "
                                 "-9223372036854775808)"
                               : "does not fit in a signed 64-bit integer (at most "
                                 "9223372036854775807)");
                /* Then read as 64-bit, where libconfig saturates a decimal: no second
                 * message. A hex one it wraps (0xFFFFFFFFFFFFFFFFF reads as -1, and the
                 * setting's check said "must be >= 0 (got -1)" after this line until
                 * 2026-12-05): not read on, as a float out of range. */
                if (hex && n_unread)
                    (*n_unread)++;
            }
            widen_int t = {end, overflow || v > max32, hex, has_l};
            if (in_array)
                widen_push_int(&w, t);
            else if (t.big && !has_l)
                widen_push_edit(&w, end, false);
        } else {
            i++;
        }
    }
    if (in_array)
        widen_flush_array(&w, array_float);

    char *out = NULL;
    if (!w.oom && (out = malloc(n + 2 * w.n_edit + 1))) {
        size_t o = 0, from = 0;
        for (size_t k = 0; k < w.n_edit; k++) {
            memcpy(out + o, text + from, w.edit[k].pos - from);
            o += w.edit[k].pos - from;
            from = w.edit[k].pos;
            if (w.edit[k].dot0) {
                out[o++] = '.';
                out[o++] = '0';
            } else {
                out[o++] = 'L';
            }
        }
        memcpy(out + o, text + from, n - from);
        out[o + n - from] = '\0';
    }
    free(w.edit);
    free(w.ints);
    return out;
}

/* ---- libconfig text of values --------------------------------------------------------------- */

/* Shortest "%.*g" that reads back to the same double, with ".0" added when it would otherwise
 * read as an integer. */
static void float_text(double x, nbep__strbuf *b)
{
    char buf[40];
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(buf, sizeof buf, "%.*g", prec, x);
        if (strtod(buf, NULL) == x)
            break;
    }
    nbep__strbuf_add(b, "%s", buf);
    if (!strpbrk(buf, ".eEni"))   /* "inf" and "nan" only appear in messages */
        nbep__strbuf_add(b, ".0");
}

static void string_text(const char *s, nbep__strbuf *b)
{
    nbep__strbuf_addn(b, "\"", 1);
    for (; *s; s++) {
        unsigned char ch = (unsigned char)*s;
        switch (ch) {
        case '"': nbep__strbuf_add(b, "\\\""); break;
        case '\\': nbep__strbuf_add(b, "\\\\"); break;
        case '\n': nbep__strbuf_add(b, "\\n"); break;
        case '\t': nbep__strbuf_add(b, "\\t"); break;
        case '\r': nbep__strbuf_add(b, "\\r"); break;
        case '\f': nbep__strbuf_add(b, "\\f"); break;
        default:
            if (ch < 0x20)
                nbep__strbuf_add(b, "\\x%02x", ch);
            else
                nbep__strbuf_addn(b, (const char *)&ch, 1);
        }
    }
    nbep__strbuf_addn(b, "\"", 1);
}

void nbep__scene_value_text(const config_setting_t *s, nbep__strbuf *b)
{
    int n = config_setting_is_aggregate(s) ? config_setting_length(s) : 0;
    switch (config_setting_type(s)) {
    case CONFIG_TYPE_INT: nbep__strbuf_add(b, "%d", config_setting_get_int(s)); break;
    case CONFIG_TYPE_INT64: nbep__strbuf_add(b, "%lldL", config_setting_get_int64(s)); break;
    case CONFIG_TYPE_FLOAT: float_text(config_setting_get_float(s), b); break;
    case CONFIG_TYPE_STRING: string_text(config_setting_get_string(s), b); break;
    case CONFIG_TYPE_BOOL:
        nbep__strbuf_add(b, "%s", config_setting_get_bool(s) ? "true" : "false");
        break;
    case CONFIG_TYPE_GROUP:
        nbep__strbuf_add(b, "{");
        for (int i = 0; i < n; i++) {
            const config_setting_t *m = config_setting_get_elem(s, (unsigned)i);
            nbep__strbuf_add(b, " %s = ", config_setting_name(m));
            nbep__scene_value_text(m, b);
            nbep__strbuf_add(b, ";");
        }
        nbep__strbuf_add(b, " }");
        break;
    case CONFIG_TYPE_ARRAY:
    case CONFIG_TYPE_LIST: {
        bool array = config_setting_type(s) == CONFIG_TYPE_ARRAY;
        nbep__strbuf_add(b, array ? "[" : "(");
        for (int i = 0; i < n; i++) {
            if (i)
                nbep__strbuf_add(b, ", ");
            nbep__scene_value_text(config_setting_get_elem(s, (unsigned)i), b);
        }
        nbep__strbuf_add(b, array ? "]" : ")");
        break;
    }
    default: nbep__strbuf_add(b, "nothing"); break;
    }
}

/* Longer values are described by their kind, so that one line stays one readable line. */
enum { DESCRIBE_MAX_CHARS = 40 };

void nbep__scene_describe(const config_setting_t *s, nbep__strbuf *b)
{
    nbep__strbuf t = {0};
    nbep__scene_value_text(s, &t);
    if (!config_setting_is_aggregate(s) || (!t.oom && t.len <= DESCRIBE_MAX_CHARS)) {
        nbep__strbuf_add(b, "%s", nbep__strbuf_str(&t));
    } else {
        int n = config_setting_length(s);
        switch (config_setting_type(s)) {
        case CONFIG_TYPE_GROUP: nbep__strbuf_add(b, "a group of %d settings", n); break;
        case CONFIG_TYPE_LIST: nbep__strbuf_add(b, "a list of %d", n); break;
        default: nbep__strbuf_add(b, "an array of %d", n); break;
        }
    }
    nbep__strbuf_fini(&t);
}

/* ---- edit distance -------------------------------------------------------------------------- */

size_t nbep__scene_edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    size_t *row = malloc(3 * (lb + 1) * sizeof *row);
    if (!row)
        return SIZE_MAX;
    size_t *prev2 = row, *prev = row + lb + 1, *cur = row + 2 * (lb + 1);
    for (size_t j = 0; j <= lb; j++)
        prev[j] = j;
    for (size_t i = 1; i <= la; i++) {
        cur[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t cost = a[i - 1] != b[j - 1];
            size_t best = prev[j - 1] + cost;
            if (prev[j] + 1 < best)
                best = prev[j] + 1;
            if (cur[j - 1] + 1 < best)
                best = cur[j - 1] + 1;
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
                prev2[j - 2] + 1 < best)
                best = prev2[j - 2] + 1;
            cur[j] = best;
        }
        size_t *t = prev2;
        prev2 = prev;
        prev = cur;
        cur = t;
    }
    size_t dist = prev[lb];
    free(row);
    return dist;
}

/* ---- messages ------------------------------------------------------------------------------- */

const char *nbep__scene_origin(const config_setting_t *s, bool elements, unsigned *line)
{
    const char *ov = NULL;
    *line = 0;
    for (int k = 0; s && elements && !ov && k < config_setting_length(s); k++)
        ov = config_setting_get_hook(config_setting_get_elem(s, (unsigned)k));
    for (const config_setting_t *t = s; t && !ov && !*line; t = config_setting_parent(t)) {
        ov = config_setting_get_hook(t);
        *line = config_setting_source_line(t);
    }
    if (ov)
        *line = 0;
    return ov;
}

const char *nbep__scene_set_by(const nbep__scene_ctx *c, const config_setting_t *s,
                               uint64_t *rank)
{
    unsigned line;
    const char *ov = s ? nbep__scene_origin(s, config_setting_is_array(s), &line) : NULL;
    *rank = ov ? nbep__scene_rank(c, ov, 0) : NBEP_DIAG_UNRANKED;
    return ov;
}

uint64_t nbep__scene_rank(const nbep__scene_ctx *c, const char *label, uint64_t line)
{
    if (label) { /* a label not among them (none is) would go after the others */
        size_t k = 0;
        while (k < c->n_labels && !(c->labels && c->labels[k] == label))
            k++;
        return k;
    }
    const uint64_t past = (uint64_t)c->n_labels; /* the deck's lines after every option */
    return line < NBEP_DIAG_UNRANKED - past ? past + line : NBEP_DIAG_UNRANKED - 1;
}

/* What a message about setting s names: the override's label, or else (NULL) the deck's
 * line *at (1 where the setting has none). */
static const char *named_by(const config_setting_t *s, unsigned *at)
{
    /* a vector (array) with an element a --set replaced (physics.gravity.[0]="a"): the --set
     * broke it (until 2026-11-30 the message named the deck's line, which was fine) */
    const char *ov = nbep__scene_origin(s, s && config_setting_is_array(s), at);
    if (!ov && !*at)
        *at = 1;
    return ov;
}

static void error_from(nbep__scene_ctx *c, const char *ov, unsigned at, const char *file,
                       int line, const char *fmt, va_list ap)
{
    char msg[1024];
    vsnprintf(msg, sizeof msg, fmt, ap);
    if (!ov && !at)
        at = 1;
    const uint64_t rank = nbep__scene_rank(c, ov, at);
    if (ov) /* the override's label (scene_override.c) */
        nbep_diag_add_ranked(c->d, rank, file, line, "%s: %s", ov, msg);
    else
        nbep_diag_add_ranked(c->d, rank, file, line, "%s:%u: %s", c->deck, at, msg);
}

void nbep__scene_error(nbep__scene_ctx *c, const config_setting_t *s, const char *file, int line,
                       const char *fmt, ...)
{
    unsigned at;
    const char *ov = named_by(s, &at);
    va_list ap;
    va_start(ap, fmt);
    error_from(c, ov, at, file, line, fmt, ap);
    va_end(ap);
}

void nbep__scene_error_from(nbep__scene_ctx *c, const char *label, unsigned at, const char *file,
                            int line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    error_from(c, label, at, file, line, fmt, ap);
    va_end(ap);
}
