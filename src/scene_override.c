/* --set PATH=VALUE: one override applied to the parsed deck before validation, so that the
 * overridden value goes through exactly the checks a deck value does. PATH is a schema path
 * whose list indices are "[N]" (spheres.[0].count; spheres[0].count is accepted too); VALUE
 * is libconfig value text, or a bare word taken as a string. Missing groups and lists on the
 * way are created; an index equal to a list's length appends an entry. Every setting made
 * here carries the override's label as its libconfig hook, which is how messages about it name
 * the option the user typed ("--set PATH=VALUE", or "-n abc" for an option that sets a deck
 * path) instead of "deck:line". */
#include "scene_impl.h"

#include <ctype.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { SEG_MAX = 16, NAME_LEN = 128, OV_PATH_LEN = 256 };

typedef struct seg {
    bool index;
    unsigned long idx;
    char name[NAME_LEN];
} seg;

#define OVERR(c, label, ...) ov_error((c), (label), __FILE__, __LINE__, __VA_ARGS__)

static void ov_error(nbep__scene_ctx *c, const char *label, const char *file, int line,
                     const char *fmt, ...) NBEP_PRINTF(5, 6);

static void ov_error(nbep__scene_ctx *c, const char *label, const char *file, int line,
                     const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    nbep_diag_add_ranked(c->d, nbep__scene_rank(c, label, 0), file, line, "%s: %s", label, msg);
}

static bool is_name_start(char ch)
{
    return isalpha((unsigned char)ch) || ch == '*';
}

static bool is_name_char(char ch)
{
    return isalnum((unsigned char)ch) || ch == '-' || ch == '_' || ch == '*';
}

/* Reads "[N]" at *p; false when it is not one. */
static bool read_index(const char **p, seg *s)
{
    const char *q = *p;
    if (*q != '[' || !isdigit((unsigned char)q[1]))
        return false;
    char *end;
    s->idx = strtoul(q + 1, &end, 10);
    if (*end != ']' || s->idx > 0x7fffffffUL)
        return false;
    s->index = true;
    *p = end + 1;
    return true;
}

/* Splits a path into names and indices; writes the canonical form (indices as ".[N]"). */
static bool split_path(const char *path, seg *segs, size_t *n, char *canon, size_t canon_len)
{
    const char *p = path;
    size_t k = 0, used = 0;
    canon[0] = '\0';
    while (*p) {
        if (k == SEG_MAX)
            return false;
        seg *s = &segs[k];
        memset(s, 0, sizeof *s);
        if (!read_index(&p, s)) {
            size_t len = 0;
            if (!is_name_start(*p))
                return false;
            while (is_name_char(p[len]))
                len++;
            if (len >= NAME_LEN)
                return false;
            memcpy(s->name, p, len);
            p += len;
        }
        int w = s->index ? snprintf(canon + used, canon_len - used, "%s[%lu]", k ? "." : "", s->idx)
                         : snprintf(canon + used, canon_len - used, "%s%s", k ? "." : "", s->name);
        if (w < 0 || (size_t)w >= canon_len - used)
            return false;
        used += (size_t)w;
        k++;
        if (*p == '.') {
            p++;
            if (!*p)
                return false;
        } else if (*p != '[' && *p) {
            return false;
        }
    }
    *n = k;
    return k > 0;
}

static char *trimmed(const char *s, size_t len)
{
    while (len && isspace((unsigned char)*s))
        s++, len--;
    while (len && isspace((unsigned char)s[len - 1]))
        len--;
    char *t = malloc(len + 1);
    if (t) {
        memcpy(t, s, len);
        t[len] = '\0';
    }
    return t;
}

/* A deep copy of src added to parent (name ignored in lists and arrays), every new setting
 * hooked to the override's label. NULL when libconfig refuses (say, a group inside an array). */
static config_setting_t *copy_value(config_setting_t *parent, const char *name,
                                    const config_setting_t *src, const char *label)
{
    int type = config_setting_type(src);
    config_setting_t *dst = config_setting_add(parent, name, type);
    if (!dst)
        return NULL;
    config_setting_set_hook(dst, (void *)label);
    switch (type) {
    case CONFIG_TYPE_INT: config_setting_set_int(dst, config_setting_get_int(src)); break;
    case CONFIG_TYPE_INT64: config_setting_set_int64(dst, config_setting_get_int64(src)); break;
    case CONFIG_TYPE_FLOAT: config_setting_set_float(dst, config_setting_get_float(src)); break;
    case CONFIG_TYPE_BOOL: config_setting_set_bool(dst, config_setting_get_bool(src)); break;
    case CONFIG_TYPE_STRING:
        if (!config_setting_set_string(dst, config_setting_get_string(src)))
            return NULL;
        break;
    default:
        for (int k = 0; k < config_setting_length(src); k++) {
            const config_setting_t *e = config_setting_get_elem(src, (unsigned)k);
            if (!copy_value(dst, config_setting_name(e), e, label))
                return NULL;
        }
    }
    return dst;
}

/* Replaces element idx of a list or array by a copy of v. libconfig has no call for that, and
 * adding appends at the end: so the copy is appended, swapped into place through the public
 * config_list_t, and the old element, now last, removed (which frees it). */
static bool replace_elem(config_setting_t *list, unsigned idx, const config_setting_t *v,
                         const char *label)
{
    if (!copy_value(list, NULL, v, label))
        return false;
    config_list_t *l = list->value.list;
    config_setting_t *old = l->elements[idx];
    l->elements[idx] = l->elements[l->length - 1];
    l->elements[l->length - 1] = old;
    return config_setting_remove_elem(list, l->length - 1) == CONFIG_TRUE;
}

/* The libconfig type to create for a missing container at path when the next segment is
 * next: a group before a name, else the list or array its schema kind asks for. */
static int container_type(const char *path, const seg *next)
{
    nbep__scene_kind kind;
    bool element;
    if (!next->index)
        return CONFIG_TYPE_GROUP;
    if (nbep__scene_schema_kind(path, &kind, &element) && !element &&
        (kind == NBEP__K_VEC3 || kind == NBEP__K_BOOL3 || kind == NBEP__K_STRINGS))
        return CONFIG_TYPE_ARRAY;
    return CONFIG_TYPE_LIST;
}

/* Parses VALUE into tmp's setting "v": libconfig text, or a bare word as a string. NULL after
 * reporting a value that is neither. */
static const config_setting_t *parse_value(nbep__scene_ctx *c, const char *label,
                                           const char *value, bool string_target, config_t *tmp)
{
    if (!(string_target && value[0] != '"')) {
        nbep__strbuf b = {0};
        nbep__strbuf_add(&b, "v = %s;", value);
        size_t n_bad = 0;
        char *text =
            b.oom ? NULL : nbep__scene_widen(c, nbep__strbuf_str(&b), label, &n_bad, NULL);
        nbep__strbuf_fini(&b);
        if (!text) {
            c->oom = true;
            return NULL;
        }
        int ok = config_read_string(tmp, text);
        free(text);
        if (n_bad)
            return NULL;
        if (ok && config_setting_length(config_root_setting(tmp)) == 1)
            return config_lookup(tmp, "v");
        /* A word that is no libconfig value (predictive, out.h5, /tmp/x.h5) is a string;
         * text that starts like a string, array, list or group is a malformed value. */
        if (value[0] && strchr("\"[({", value[0])) {
            OVERR(c, label, "bad value: %s", ok ? "more than one value" : config_error_text(tmp));
            return NULL;
        }
        config_destroy(tmp);
        config_init(tmp);
    }
    config_setting_t *s = config_setting_add(config_root_setting(tmp), "v", CONFIG_TYPE_STRING);
    if (!s || !config_setting_set_string(s, value)) {
        c->oom = true;
        return NULL;
    }
    return s;
}

/* An index past the end of a list of len entries (len itself appends one). */
static void index_past_end(nbep__scene_ctx *c, const char *label, const char *list,
                           unsigned len)
{
    OVERR(c, label, "%s has %u entr%s: the index can be at most %u (to add one)", list, len,
          len == 1 ? "y" : "ies", len);
}

/* Adds segment s to the path so far (names joined by dots, indices as ".[N]"). */
static void path_append(char *sofar, size_t cap, const seg *s)
{
    const size_t used = strlen(sofar);
    if (s->index)
        snprintf(sofar + used, cap - used, ".[%lu]", s->idx);
    else
        snprintf(sofar + used, cap - used, "%s%s", used ? "." : "", s->name);
}

void nbep__scene_path_canon(const char *path, char *canon, size_t len)
{
    seg segs[SEG_MAX];
    size_t n = 0;
    if (!split_path(path, segs, &n, canon, len))
        snprintf(canon, len, "%s", path);
}

bool nbep__scene_path_indices_exist(const config_setting_t *root, const char *path,
                                    char *list, size_t list_len, unsigned *len)
{
    seg segs[SEG_MAX];
    size_t n = 0;
    char canon[OV_PATH_LEN], sofar[OV_PATH_LEN] = "";
    if (!split_path(path, segs, &n, canon, sizeof canon))
        return true; /* not a path: the schema's check says so */
    const config_setting_t *node = root;
    for (size_t k = 0; k < n; k++) {
        const seg *s = &segs[k];
        if (s->index) {
            const unsigned have =
                node && config_setting_is_aggregate(node) ? (unsigned)config_setting_length(node)
                                                          : 0;
            if (s->idx >= have) {
                snprintf(list, list_len, "%s", sofar);
                *len = have;
                return false;
            }
            node = config_setting_get_elem(node, (unsigned)s->idx);
        } else {
            node = node && config_setting_is_group(node) ? config_setting_get_member(node, s->name)
                                                         : NULL;
        }
        path_append(sofar, sizeof sofar, s);
    }
    return true;
}

void nbep__scene_apply_override(nbep__scene_ctx *c, config_t *cfg, const char *ov,
                                const char *label)
{
    const char *eq = strchr(ov, '=');
    if (!eq) {
        OVERR(c, label, "expected PATH=VALUE, e.g. physics.restitution=0.9");
        return;
    }
    char *path = trimmed(ov, (size_t)(eq - ov)), *value = trimmed(eq + 1, strlen(eq + 1));
    config_t tmp;
    config_init(&tmp);
    seg segs[SEG_MAX];
    size_t n = 0;
    char canon[OV_PATH_LEN];
    config_setting_t *made = NULL; /* the first setting the walk below makes */
    bool placed = false;           /* the value in the deck */
    if (!path || !value) {
        c->oom = true;
        goto out;
    }
    if (!split_path(path, segs, &n, canon, sizeof canon)) {
        OVERR(c, label, "bad path \"%s\": names and [N] indices joined by dots, e.g. "
                     "spheres.[0].count",
              path);
        goto out;
    }
    nbep__scene_kind kind;
    bool element;
    if (!nbep__scene_schema_kind(canon, &kind, &element)) {
        nbep__strbuf b = {0};
        nbep__scene_unknown_text(canon, &b);
        OVERR(c, label, "%s", nbep__strbuf_str(&b));
        c->oom = c->oom || b.oom;
        nbep__strbuf_fini(&b);
        goto out;
    }
    bool string_target = element ? kind == NBEP__K_STRINGS : kind == NBEP__K_STRING;
    const config_setting_t *v = parse_value(c, label, value, string_target, &tmp);
    if (!v)
        goto out;

    /* Walk to the parent of the last segment, making what is missing: the first setting made
     * (made) goes again where the value is not placed, so that a --set refused names one
     * problem (`--set physics.gravity.[3]=1.0` on a deck without gravity said its index, and
     * then that the gravity it had made was not 3 numbers; a review, 2026-12-05). */
    config_setting_t *node = config_root_setting(cfg);
    char sofar[OV_PATH_LEN] = "";
    for (size_t k = 0; k + 1 < n; k++) {
        const seg *s = &segs[k];
        config_setting_t *child = NULL;
        const size_t used = strlen(sofar);
        path_append(sofar, sizeof sofar, s);
        if (!s->index) {
            if (!config_setting_is_group(node)) {
                sofar[used] = '\0';
                OVERR(c, label, "%s is not a group", sofar);
                goto out;
            }
            child = config_setting_get_member(node, s->name);
            if (!child) {
                child = config_setting_add(node, s->name, container_type(sofar, &segs[k + 1]));
                made = made ? made : child;
            }
        } else {
            unsigned len = (unsigned)config_setting_length(node);
            if (!config_setting_is_list(node)) {
                sofar[used] = '\0';
                OVERR(c, label, "%s is not a list", sofar);
                goto out;
            }
            if (s->idx < len) {
                child = config_setting_get_elem(node, (unsigned)s->idx);
            } else if (s->idx == len) {
                child = config_setting_add(node, NULL, container_type(sofar, &segs[k + 1]));
                made = made ? made : child;
            } else {
                sofar[used] = '\0';
                index_past_end(c, label, sofar, len);
                goto out;
            }
        }
        if (!child) {
            OVERR(c, label, "cannot make %s here (is its parent a group?)", sofar);
            goto out;
        }
        if (!config_setting_get_hook(child) && config_setting_source_line(child) == 0)
            config_setting_set_hook(child, (void *)label);
        node = child;
    }

    const seg *last = &segs[n - 1];
    if (!last->index) {
        if (!config_setting_is_group(node)) {
            OVERR(c, label, "%s is not a group", sofar);
            goto out;
        }
        nbep__scene_check_replaced(c, config_setting_get_member(node, last->name), canon, label);
        if (config_setting_get_member(node, last->name))
            config_setting_remove(node, last->name);
        placed = copy_value(node, last->name, v, label) != NULL;
        c->oom = c->oom || !placed;
        goto out;
    }
    if (!config_setting_is_list(node) && !config_setting_is_array(node)) {
        OVERR(c, label, "%s is not a list or array", sofar);
        goto out;
    }
    if (config_setting_is_array(node) && config_setting_is_aggregate(v)) {
        OVERR(c, label, "an element of the array %s must be a number, string or boolean", sofar);
        goto out;
    }
    unsigned len = (unsigned)config_setting_length(node);
    bool ok = true;
    if (last->idx < len) {
        nbep__scene_check_replaced(c, config_setting_get_elem(node, (unsigned)last->idx), canon,
                                   label);
        ok = replace_elem(node, (unsigned)last->idx, v, label);
        placed = ok;
    } else if (last->idx == len) {
        ok = copy_value(node, NULL, v, label) != NULL;
        placed = ok;
    } else {
        index_past_end(c, label, sofar, len);
    }
    c->oom = c->oom || !ok;
out:
    if (made && !placed)
        config_setting_remove_elem(config_setting_parent(made),
                                   (unsigned)config_setting_index(made));
    config_destroy(&tmp);
    free(path);
    free(value);
}
