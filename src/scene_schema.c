/* The deck's schema table (scene_schema.h) and what only reads it: the schema kind of a
 * concrete path, the "did you mean" suggestion for an unknown one, the check of a deck's
 * settings against it (unknown names; the types of what an override replaces), and the
 * reference that `nbep --help-deck` prints. */
#include "nbep/scene.h"

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "scene_schema.h"

const schema_entry nbep__scene_schema[S_COUNT] = {
#define X_ROW(id, path, kind, flags, def, def_doc, meaning) \
    {path, NBEP__K_##kind, flags, def, def_doc, meaning},
    SCENE_SCHEMA(X_ROW)
#undef X_ROW
};


/* The table, by its short name (as scene.c reads it). */
static const schema_entry *const schema = nbep__scene_schema;

/* ---- types -------------------------------------------------------------------------------- */

/* Whether s is an array or list of n entries (n < 0: any number) each of kind e. */
static bool all_of(const config_setting_t *s, int n, nbep__scene_kind e)
{
    if (!config_setting_is_array(s) && !config_setting_is_list(s))
        return false;
    const int len = config_setting_length(s);
    if (n >= 0 && len != n)
        return false;
    const char *ignored;
    for (int k = 0; k < len; k++)
        if (!nbep__scene_kind_holds(e, false, config_setting_get_elem(s, (unsigned)k), &ignored))
            return false;
    return true;
}

bool nbep__scene_kind_holds(nbep__scene_kind k, bool element, const config_setting_t *s,
                            const char **words)
{
    if (element) { /* the kind of an element of a container of kind k */
        switch (k) {
        case NBEP__K_LIST: k = NBEP__K_GROUP; break;
        case NBEP__K_VEC3: k = NBEP__K_FLOAT; break;
        case NBEP__K_BOOL3: k = NBEP__K_BOOL; break;
        case NBEP__K_STRINGS: k = NBEP__K_STRING; break;
        default: *words = "a value"; return true; /* a sweep's values: each checked as a --set */
        }
    }
    const int t = config_setting_type(s);
    switch (k) {
    case NBEP__K_GROUP:
        *words = "a group { ... }";
        return config_setting_is_group(s);
    case NBEP__K_LIST: /* an empty [] counts as an empty list */
        *words = "a list ( {...}, ... )";
        return config_setting_is_list(s) ||
               (config_setting_is_array(s) && config_setting_length(s) == 0);
    case NBEP__K_STRING:
        *words = "a string";
        return t == CONFIG_TYPE_STRING;
    case NBEP__K_INT:
        *words = "an integer";
        return t == CONFIG_TYPE_INT || t == CONFIG_TYPE_INT64;
    case NBEP__K_FLOAT:
        *words = "a number";
        return config_setting_is_number(s);
    case NBEP__K_BOOL:
        *words = "true or false";
        return t == CONFIG_TYPE_BOOL;
    case NBEP__K_VEC3:
        *words = "3 numbers [x, y, z]";
        return all_of(s, 3, NBEP__K_FLOAT);
    case NBEP__K_BOOL3:
        *words = "3 booleans [x, y, z]";
        return all_of(s, 3, NBEP__K_BOOL);
    case NBEP__K_STRINGS:
        *words = "an array of strings";
        return all_of(s, -1, NBEP__K_STRING);
    case NBEP__K_VALUES:
        *words = "a non-empty array or list of values";
        return (config_setting_is_array(s) || config_setting_is_list(s)) &&
               config_setting_length(s) > 0;
    }
    *words = "?";
    return false;
}

/* ---- path queries ------------------------------------------------------------------------- */

int nbep__scene_schema_find(const char *abstract)
{
    for (int id = 0; id < S_COUNT; id++)
        if (strcmp(schema[id].path, abstract) == 0)
            return id;
    return -1;
}

/* The schema path of a concrete path: every "[N]" becomes "[]". False on bad syntax. */
static bool abstract_of(const char *path, char *out, size_t len)
{
    size_t o = 0;
    bool seg_start = true;
    for (const char *p = path; *p; p++) {
        if (o + 3 >= len)
            return false;
        if (seg_start && *p == '[') {
            const char *q = p + 1;
            while (*q >= '0' && *q <= '9')
                q++;
            if (q == p + 1 || *q != ']')
                return false;
            out[o++] = '[';
            out[o++] = ']';
            p = q;
            seg_start = false;
            continue;
        }
        if (*p == '.') {
            if (seg_start)
                return false;
            seg_start = true;
        } else {
            seg_start = false;
        }
        out[o++] = *p;
    }
    out[o] = '\0';
    return o > 0 && !seg_start;
}

static bool kind_is_container(nbep__scene_kind k)
{
    return k == NBEP__K_LIST || k == NBEP__K_VEC3 || k == NBEP__K_BOOL3 || k == NBEP__K_STRINGS ||
           k == NBEP__K_VALUES;
}

static bool schema_kind_abstract(const char *abstract, nbep__scene_kind *kind, bool *element)
{
    int id = nbep__scene_schema_find(abstract);
    if (id >= 0) {
        *kind = schema[id].kind;
        *element = false;
        return true;
    }
    size_t n = strlen(abstract);
    if (n > 3 && strcmp(abstract + n - 3, ".[]") == 0) {
        char parent[PATH_LEN];
        memcpy(parent, abstract, n - 3);
        parent[n - 3] = '\0';
        id = nbep__scene_schema_find(parent);
        if (id >= 0 && kind_is_container(schema[id].kind)) {
            *kind = schema[id].kind;
            *element = true;
            return true;
        }
    }
    return false;
}

bool nbep__scene_schema_kind(const char *path, nbep__scene_kind *kind, bool *element)
{
    char abstract[PATH_LEN];
    return abstract_of(path, abstract, sizeof abstract) &&
           schema_kind_abstract(abstract, kind, element);
}

/* Whether a's letters appear in b in order (a prefix among them). */
static bool subsequence(const char *a, const char *b)
{
    for (; *a && *b; b++)
        a += *a == *b;
    return *a == '\0';
}

/* A close known path for an unknown one: the first unknown name is compared with its known
 * siblings (a typo: physics.gravty -> physics.gravity), else, when it is the last name, with
 * every setting of that exact name elsewhere (a misplaced one: run.gravity -> physics.gravity). */
static bool suggest(const char *path, char *out, size_t len)
{
    char known_c[PATH_LEN] = "", known_a[PATH_LEN] = "";
    const char *p = path;
    while (*p) {
        const char *dot = strchr(p, '.');
        size_t seg_len = dot ? (size_t)(dot - p) : strlen(p);
        if (seg_len == 0 || seg_len >= PATH_LEN)
            return false;
        char seg[PATH_LEN], cand_c[PATH_LEN], cand_a[PATH_LEN];
        memcpy(seg, p, seg_len);
        seg[seg_len] = '\0';
        cut_printf(cand_c, sizeof cand_c, "%s%s%s", known_c, *known_c ? "." : "", seg);
        nbep__scene_kind kind;
        bool element;
        if (abstract_of(cand_c, cand_a, sizeof cand_a) &&
            schema_kind_abstract(cand_a, &kind, &element)) {
            memcpy(known_c, cand_c, sizeof known_c);
            memcpy(known_a, cand_a, sizeof known_a);
            p += seg_len + (dot != NULL);
            continue;
        }
        if (seg[0] == '[')
            return false;
        const char *rest = dot ? dot : "";
        /* A typo: at most a third of the name's letters wrong (one for short names). */
        size_t limit = seg_len / 3 > 1 ? seg_len / 3 : 1, best = SIZE_MAX;
        int best_id = -1;
        for (int id = 0; id < S_COUNT; id++) {
            const char *leaf = leaf_of(schema[id].path);
            size_t parent_len = (size_t)(leaf - schema[id].path);
            parent_len -= parent_len > 0;
            if (parent_len != strlen(known_a) || strncmp(schema[id].path, known_a, parent_len))
                continue;
            size_t dist = nbep__scene_edit_distance(seg, leaf);
            /* A cut-short name (phys for physics) counts as a typo too, and so does a
             * shorthand that keeps the name's first letter and drops others (vals for values,
             * rads for radius: a new user's "vals" got no suggestion) */
            if (seg_len >= 3 && seg[0] == leaf[0] && subsequence(seg, leaf) && limit < dist)
                dist = limit;
            if (dist <= limit && dist < best) {
                best = dist;
                best_id = id;
            }
        }
        if (best_id >= 0) {
            cut_printf(out, len, "%s%s%s%s", known_c, *known_c ? "." : "",
                     leaf_of(schema[best_id].path), rest);
            return nbep__scene_schema_kind(out, &kind, &element);
        }
        if (*rest)
            return false;
        for (int id = 0; id < S_COUNT; id++)
            if (strcmp(leaf_of(schema[id].path), seg) == 0 && !strstr(schema[id].path, "[]")) {
                snprintf(out, len, "%s", schema[id].path);
                return true;
            }
        return false;
    }
    return false;
}

void nbep__scene_unknown_text(const char *path, nbep__strbuf *b)
{
    char s[PATH_LEN];
    nbep__strbuf_add(b, "unknown setting %s", path);
    if (suggest(path, s, sizeof s))
        nbep__strbuf_add(b, " (did you mean %s?)", s);
}

/* ---- the deck's settings against the schema ----------------------------------------------- */

/* The words every message about a setting an override replaces ends with: the run goes on the
 * override's value, but the deck, run without it, must be right. */
#define REPLACED_WORDS "%s replaces it, but the deck must be right without it"

static void check_members(nbep__scene_ctx *c, const config_setting_t *group, const char *prefix_c,
                          const char *prefix_a, const char *replaced_by);

/* Setting s, known, of kind k (an element of a container of kind k when `element`), at
 * concrete path path_c and schema path path_a. The deck's own load (replaced_by NULL) checks
 * its types later, setting by setting, where it reads them: here only the groups under it are
 * walked. A setting that the override replaced_by removes is never read: its type is held here,
 * under it too (until 2026-12-02 `--set output={file="x.h5";}` dropped a deck's
 * `every = "x";` unchecked). Its value is not checked further: a --set may mend a value out of
 * range. A setting an earlier override made has no line of the deck (copy_value makes it),
 * and is that override's. */
static void check_setting(nbep__scene_ctx *c, const config_setting_t *s, const char *path_c,
                          const char *path_a, nbep__scene_kind k, bool element,
                          const char *replaced_by)
{
    if (replaced_by) {
        const char *words;
        if (config_setting_source_line(s) == 0)
            return;
        if (!nbep__scene_kind_holds(k, element, s, &words)) {
            nbep__strbuf got = {0};
            nbep__scene_describe(s, &got);
            NBEP__SCENE_ERR(c, s, "%s must be %s (got %s; " REPLACED_WORDS ")", path_c, words,
                            nbep__strbuf_str(&got), replaced_by);
            c->oom = c->oom || got.oom;
            nbep__strbuf_fini(&got);
            return;
        }
    }
    if ((element ? k == NBEP__K_LIST : k == NBEP__K_GROUP) && config_setting_is_group(s))
        check_members(c, s, path_c, path_a, replaced_by);
    if (!element && k == NBEP__K_LIST && config_setting_is_list(s)) {
        char elem_c[PATH_LEN], elem_a[PATH_LEN];
        cut_printf(elem_a, sizeof elem_a, "%s.[]", path_a);
        for (int i = 0; i < config_setting_length(s); i++) {
            cut_printf(elem_c, sizeof elem_c, "%s.[%d]", path_c, i);
            check_setting(c, config_setting_get_elem(s, (unsigned)i), elem_c, elem_a, k, true,
                          replaced_by);
        }
    }
}

/* Each member of group (at concrete path prefix_c, schema path prefix_a; "" at the root):
 * unknown ones reported at their lines, known ones walked by check_setting. */
static void check_members(nbep__scene_ctx *c, const config_setting_t *group, const char *prefix_c,
                          const char *prefix_a, const char *replaced_by)
{
    for (int i = 0; i < config_setting_length(group); i++) {
        const config_setting_t *m = config_setting_get_elem(group, (unsigned)i);
        const char *name = config_setting_name(m);
        char path_c[PATH_LEN], path_a[PATH_LEN];
        cut_printf(path_c, sizeof path_c, "%s%s%s", prefix_c, *prefix_c ? "." : "", name);
        cut_printf(path_a, sizeof path_a, "%s%s%s", prefix_a, *prefix_a ? "." : "", name);
        const int id = nbep__scene_schema_find(path_a);
        if (id >= 0) {
            check_setting(c, m, path_c, path_a, schema[id].kind, false, replaced_by);
            continue;
        }
        nbep__strbuf b = {0}; /* (no override makes an unknown setting: it is refused) */
        nbep__scene_unknown_text(path_c, &b);
        if (replaced_by)
            nbep__strbuf_add(&b, " (" REPLACED_WORDS ")", replaced_by);
        NBEP__SCENE_ERR(c, m, "%s", nbep__strbuf_str(&b));
        c->oom = c->oom || b.oom;
        nbep__strbuf_fini(&b);
    }
}

void nbep__scene_check_known(nbep__scene_ctx *c, const config_setting_t *root)
{
    check_members(c, root, "", "", NULL);
}

void nbep__scene_check_replaced(nbep__scene_ctx *c, const config_setting_t *old,
                                const char *canon, const char *label)
{
    char abstract[PATH_LEN];
    nbep__scene_kind k;
    bool element;
    if (old && abstract_of(canon, abstract, sizeof abstract) &&
        schema_kind_abstract(abstract, &k, &element))
        check_setting(c, old, canon, abstract, k, element, label);
}

/* ---- the reference (--help-deck) ---------------------------------------------------------- */

static const char *kind_name(nbep__scene_kind k)
{
    switch (k) {
    case NBEP__K_GROUP: return "group";
    case NBEP__K_LIST: return "list of groups";
    case NBEP__K_STRING: return "string";
    case NBEP__K_INT: return "integer";
    case NBEP__K_FLOAT: return "number";
    case NBEP__K_BOOL: return "true/false";
    case NBEP__K_VEC3: return "[x, y, z]";
    case NBEP__K_BOOL3: return "[bool, bool, bool]";
    case NBEP__K_STRINGS: return "array of strings";
    case NBEP__K_VALUES: return "array or list";
    }
    return "?";
}

void nbep_scene_print_reference(FILE *f)
{
    fprintf(f, "| path | type | default | meaning |\n| --- | --- | --- | --- |\n");
    for (int id = 0; id < S_COUNT; id++) {
        const schema_entry *e = &schema[id];
        fprintf(f, "| `");
        for (const char *p = e->path; *p; p++) {
            if (p[0] == '[' && p[1] == ']') {
                fputs("[i]", f);
                p++;
            } else {
                fputc(*p, f);
            }
        }
        fprintf(f, "` | %s | ", kind_name(e->kind));
        if (e->def)
            fprintf(f, "`%s`", e->def);
        else
            fprintf(f, "%s", e->def_doc);
        fprintf(f, " | %s", e->meaning);
        if (e->flags & F_GT0)
            fprintf(f, "; > 0");
        if (e->flags & F_GE0)
            fprintf(f, "; >= 0");
        if (e->flags & F_GE1)
            fprintf(f, "; >= 1");
        if (e->flags & F_IN01)
            fprintf(f, "; in [0, 1]");
        if (e->flags & F_SCALE)
            fprintf(f, "; %s" SCALE_RANGE " in magnitude", e->flags & F_GT0 ? "" : "0 or ");
        if (e->flags & F_ONE)
            fprintf(f, "; single sphere only");
        if (e->flags & F_GROUP)
            fprintf(f, "; generated group only");
        fprintf(f, " |\n");
    }
}
