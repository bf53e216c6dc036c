/* The input deck (libconfig) -> nbep_scene. One schema table (SCENE_SCHEMA, scene_schema.h)
 * gives every setting's path, type, default and meaning; it drives the unknown-setting check
 * (with "did you mean"), the typed getters and their range checks here, --set
 * (scene_override.c) and the reference printed by nbep_scene_print_reference
 * (scene_schema.c).
 *
 * A load runs in one pass and reports every problem it finds, one line each, before failing:
 *   read the file -> rewrite for libconfig 1.5 (scene_text.c) -> parse -> apply overrides ->
 *   unknown settings -> typed values, ranges and cross-checks -> count and memory checks ->
 *   planes, placement of generated groups (scene_place.c) -> overlap check.
 * Placement needs valid geometry, so it runs only when the box, planes, spheres and seed are
 * valid; errors elsewhere (say run.algorithm or physics.restitution) do not hide placement
 * problems.
 * Locations are "deck:line" from libconfig, or "--set PATH=VALUE" for a setting an override
 * made: such settings carry the override text in their libconfig hook. The problems are listed
 * by location, not in the order found (nbep__scene_rank): the command line's options in the
 * order given, then the deck's lines from the top, then any that name neither. */
#include "nbep/scene.h"

#include "nbep/calendar.h"
#include "nbep/nblist.h"
#include "nbep/physics.h"

#include <assert.h>
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "evloop.h"
#include "scene_impl.h"
#include "scene_schema.h"

/* The schema table, by its short name. */
static const schema_entry *const schema = nbep__scene_schema;

static const char *const algorithm_names[] = {"naive", "seminaive", "predictive"};
static const char *const neighbor_names[] = {"all", "grid", "cells"};
static const char *const order_names[] = {"time", "step"};
static const char *const place_names[] = {"random", "lattice", "fcc"};
static const char *const field_names[] = {"position", "velocity"};
enum { N_ALGORITHMS = 3, N_PLACES = 3, N_FIELDS = 2 };

/* Spheres' own arrays plus what the algorithms allocate per sphere (event slot, reacted tag,
 * BVH leaf, frame buffers): a deliberately round upper estimate for the memory check. */
enum { WORKSPACE_BYTES_PER_SPHERE = 200 };

#define ERR(L, s, ...) NBEP__SCENE_ERR(&(L)->c, (s), __VA_ARGS__)

/* ---- typed getters -------------------------------------------------------------------------- */

/* A sweep axis as the deck gives it: its entry's index in sweep.vary, and its values. */
typedef struct axis_at {
    size_t index;
    const config_setting_t *values;   /* borrowed */
} axis_at;

typedef struct load {
    nbep__scene_ctx c;
    const config_setting_t *def[S_COUNT];   /* borrowed: parsed literal defaults */
    axis_at *axes;                          /* owned: per entry of the scene's sweep_axes */
    /* borrowed, or NULL: run.algorithm's and run.neighbors' settings, which a message about
     * what goes with the run's mode (run.order, box.periodic) may be blamed on */
    const config_setting_t *algorithm_at, *neighbors_at;
} load;

typedef enum got { GOT, NONE, BAD } got;

/* Of the n settings s (NULL ones left out) that a message is about, the one an override gave
 * (a --set, -a, -n ..., a sweep axis, or of one of its elements), the one typed first where
 * several were: that is what the user changed; else `otherwise`, at its deck line. */
static const config_setting_t *first_set(const load *L, const config_setting_t *const *s,
                                         size_t n, const config_setting_t *otherwise)
{
    const config_setting_t *best = otherwise;
    uint64_t best_rank = NBEP_DIAG_UNRANKED;
    for (size_t k = 0; k < n; k++) {
        uint64_t r;
        if (s[k] && nbep__scene_set_by(&L->c, s[k], &r) && r < best_rank) {
            best = s[k];
            best_rank = r;
        }
    }
    return best;
}

/* What a message that setting `s` needs another mode is blamed on: of s, run.algorithm and
 * run.neighbors, the first typed (first_set), else s at its deck line. */
static const config_setting_t *mode_at(const load *L, const config_setting_t *s)
{
    const config_setting_t *const three[3] = {s, L->algorithm_at, L->neighbors_at};
    return first_set(L, three, 3, s);
}

static void path_join(char *out, const char *prefix, const char *name)
{
    cut_printf(out, PATH_LEN, "%s%s%s", prefix, *prefix ? "." : "", name);
}

/* Entry id under parent (NULL: the group is absent): the deck's setting, else the literal
 * default, else NONE, with "is missing" when it is required and its group exists. */
static got find(load *L, const config_setting_t *parent, const char *prefix, int id,
                const config_setting_t **out)
{
    const char *name = leaf_of(schema[id].path);
    const config_setting_t *s = parent ? config_setting_get_member(parent, name) : NULL;
    if (!s)
        s = L->def[id];
    if (s) {
        *out = s;
        return GOT;
    }
    if (parent && (schema[id].flags & F_REQUIRED)) {
        char path[PATH_LEN];
        path_join(path, prefix, name);
        ERR(L, parent, "%s is missing", path);
        return BAD;
    }
    return NONE;
}

static void type_error(load *L, const config_setting_t *s, const char *path, const char *what)
{
    nbep__strbuf b = {0};
    nbep__scene_describe(s, &b);
    ERR(L, s, "%s must be %s (got %s)", path, what, nbep__strbuf_str(&b));
    L->c.oom = L->c.oom || b.oom;
    nbep__strbuf_fini(&b);
}

/* find, and the setting's kind checked (a type error at its line: BAD); path gets its dotted
 * name for the caller's own messages. */
static got find_kind(load *L, const config_setting_t *parent, const char *prefix, int id,
                     nbep__scene_kind kind, const config_setting_t **out, char path[PATH_LEN])
{
    got g = find(L, parent, prefix, id, out);
    if (g != GOT)
        return g;
    path_join(path, prefix, leaf_of(schema[id].path));
    const char *words;
    if (!nbep__scene_kind_holds(kind, false, *out, &words)) {
        type_error(L, *out, path, words);
        return BAD;
    }
    return GOT;
}

static double number_of(const config_setting_t *s)
{
    return config_setting_type(s) == CONFIG_TYPE_FLOAT ? config_setting_get_float(s)
                                                       : (double)config_setting_get_int64(s);
}

static got get_int(load *L, const config_setting_t *parent, const char *prefix, int id,
                   int64_t *out, const config_setting_t **at)
{
    const config_setting_t *s;
    char path[PATH_LEN];
    got g = find_kind(L, parent, prefix, id, NBEP__K_INT, &s, path);
    if (g != GOT)
        return g;
    int64_t v = config_setting_get_int64(s);
    unsigned f = schema[id].flags;
    if (((f & F_GE0) && v < 0) || ((f & F_GE1) && v < 1)) {
        ERR(L, s, "%s must be >= %d (got %" PRId64 ")", path, (f & F_GE1) ? 1 : 0, v);
        return BAD;
    }
    *out = v;
    if (at)
        *at = s;
    return GOT;
}

/* NBEP_DECK_SCALE_MIN and _MAX (scene.h): the magnitudes whose squared products stay normal */
#define SCALE_HINT "; choose units that bring it within (README, The deck: units)"

static bool in_scale(double magnitude)
{
    return magnitude == 0.0 ||
           (magnitude >= NBEP_DECK_SCALE_MIN && magnitude <= NBEP_DECK_SCALE_MAX);
}

/* v divided by its largest component's magnitude *m (v finite, not zero): within [-1, 1],
 * so that its squares neither overflow nor underflow. Divided, not multiplied by 1 / *m,
 * which is inf for a subnormal *m (a plane normal [0, 0, 1e-320] became NaN, and its run
 * asserted). */
static nbep_vec3 by_largest(nbep_vec3 v, double *m)
{
    *m = fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
    return nbep_vec3_make(v.x / *m, v.y / *m, v.z / *m);
}

/* |v| without overflow or underflow of the squares (v finite) */
static double scaled_norm(nbep_vec3 v)
{
    double m;
    const nbep_vec3 u = by_largest(v, &m);
    return m > 0.0 ? m * nbep_vec3_norm(u) : 0.0;
}

static got get_float(load *L, const config_setting_t *parent, const char *prefix, int id,
                     double *out)
{
    const config_setting_t *s;
    char path[PATH_LEN];
    got g = find_kind(L, parent, prefix, id, NBEP__K_FLOAT, &s, path);
    if (g != GOT)
        return g;
    double v = number_of(s);
    unsigned f = schema[id].flags;
    if (!isfinite(v)) {
        ERR(L, s, "%s must be finite (got %s)", path, NBEP_G(v));
        return BAD;
    }
    if ((f & F_GT0) && !(v > 0.0)) {
        ERR(L, s, "%s must be > 0 (got %s)", path, NBEP_G(v));
        return BAD;
    }
    if ((f & F_GE0) && !(v >= 0.0)) {
        ERR(L, s, "%s must be >= 0 (got %s)", path, NBEP_G(v));
        return BAD;
    }
    if ((f & F_IN01) && !(v >= 0.0 && v <= 1.0)) {
        ERR(L, s, "%s must be in [0, 1] (got %s)", path, NBEP_G(v));
        return BAD;
    }
    if ((f & F_SCALE) && !in_scale(fabs(v))) {
        ERR(L, s, "%s must be %s" SCALE_RANGE " in magnitude (got %s)%s", path,
            f & F_GT0 ? "" : "0 or ", NBEP_G(v), SCALE_HINT);
        return BAD;
    }
    *out = v;
    return GOT;
}

static got get_vec3(load *L, const config_setting_t *parent, const char *prefix, int id,
                    nbep_vec3 *out, const config_setting_t **at)
{
    const config_setting_t *s;
    char path[PATH_LEN];
    got g = find_kind(L, parent, prefix, id, NBEP__K_VEC3, &s, path);
    if (g != GOT)
        return g;
    nbep_vec3 v = {number_of(config_setting_get_elem(s, 0)),
                   number_of(config_setting_get_elem(s, 1)),
                   number_of(config_setting_get_elem(s, 2))};
    if (!nbep_vec3_isfinite(v)) {
        ERR(L, s, "%s must be finite (got [%g, %g, %g])", path, v.x, v.y, v.z);
        return BAD;
    }
    if ((schema[id].flags & F_SCALE) && !in_scale(scaled_norm(v))) {
        ERR(L, s, "%s must be 0 or " SCALE_RANGE " in length (got [%s, %s, %s], length %g)%s",
            path, NBEP_G(v.x), NBEP_G(v.y), NBEP_G(v.z), scaled_norm(v), SCALE_HINT);
        return BAD;
    }
    *out = v;
    if (at)
        *at = s;
    return GOT;
}

static got get_string(load *L, const config_setting_t *parent, const char *prefix, int id,
                      const char **out, const config_setting_t **at)
{
    const config_setting_t *s;
    char path[PATH_LEN];
    got g = find_kind(L, parent, prefix, id, NBEP__K_STRING, &s, path);
    if (g != GOT)
        return g;
    *out = config_setting_get_string(s);
    if (at)
        *at = s;
    return GOT;
}

static got get_bool(load *L, const config_setting_t *parent, const char *prefix, int id,
                    bool *out)
{
    const config_setting_t *s;
    char path[PATH_LEN];
    got g = find_kind(L, parent, prefix, id, NBEP__K_BOOL, &s, path);
    if (g != GOT)
        return g;
    *out = config_setting_get_bool(s) != 0;
    return GOT;
}

static got get_bool3(load *L, const config_setting_t *parent, const char *prefix, int id,
                     bool out[3], const config_setting_t **at)
{
    const config_setting_t *s;
    char path[PATH_LEN];
    got g = find_kind(L, parent, prefix, id, NBEP__K_BOOL3, &s, path);
    if (g != GOT)
        return g;
    for (unsigned k = 0; k < 3; k++)
        out[k] = config_setting_get_bool(config_setting_get_elem(s, k)) != 0;
    if (at)
        *at = s;
    return GOT;
}

/* A group entry, or a list entry (an empty [] counts as an empty list). */
static got get_aggregate(load *L, const config_setting_t *parent, const char *prefix, int id,
                         const config_setting_t **out)
{
    const config_setting_t *s;
    char path[PATH_LEN];
    got g = find_kind(L, parent, prefix, id, schema[id].kind, &s, path);
    if (g != GOT)
        return g;
    *out = s;
    return GOT;
}

/* Index of s among names, or -1 with an error listing the valid ones. */
static int one_of(load *L, const config_setting_t *at, const char *path, const char *s,
                  const char *const *names, int n)
{
    for (int k = 0; k < n; k++)
        if (strcmp(s, names[k]) == 0)
            return k;
    nbep__strbuf b = {0}, typed = {0};
    for (int k = 0; k < n; k++)
        nbep__strbuf_add(&b, "%s\"%s\"", k ? ", " : "", names[k]);
    /* what was typed as a libconfig literal, a quote in it escaped (until 2026-12-05 `(got
     * "fa"st")`), as the deck text nbep stores writes it */
    nbep__scene_value_text(at, &typed);
    ERR(L, at, "%s must be one of %s (got %s)", path, nbep__strbuf_str(&b),
        nbep__strbuf_str(&typed));
    L->c.oom = L->c.oom || b.oom || typed.oom;
    nbep__strbuf_fini(&b);
    nbep__strbuf_fini(&typed);
    return -1;
}

/* ---- sections ------------------------------------------------------------------------------- */

static void parse_run(load *L, const config_setting_t *root, nbep_scene *sc, bool *seed_ok)
{
    const config_setting_t *run = NULL, *at = NULL;
    if (get_aggregate(L, root, "", S_RUN, &run) != GOT)
        run = NULL;
    const char *algorithm;
    if (get_string(L, run, "run", S_RUN_ALGORITHM, &algorithm, &at) == GOT &&
        one_of(L, at, "run.algorithm", algorithm, algorithm_names, N_ALGORITHMS) >= 0) {
        snprintf(sc->algorithm, sizeof sc->algorithm, "%s", algorithm);
        L->algorithm_at = at;
    }
    const char *neighbors;
    if (get_string(L, run, "run", S_RUN_NEIGHBORS, &neighbors, &at) == GOT) {
        int k = one_of(L, at, "run.neighbors", neighbors, neighbor_names, 3);
        sc->neighbors_grid = k == 1;
        sc->neighbors_cells = k == 2;
        L->neighbors_at = at;
    }
    /* The paper's step (run.order = "step") is a way of running the predictive algorithm's
     * rounds ("all" and "grid"); the cells mode's event loop takes one event at a time and the
     * detection algorithms have no events, so it means nothing there: refused, not ignored.
     * Blamed on what the user typed of the three (-a naive under a deck's step order named
     * run.order's deck line until 2026-11-30), else run.order's line. */
    const char *order;
    if (get_string(L, run, "run", S_RUN_ORDER, &order, &at) == GOT &&
        (sc->order_step = one_of(L, at, "run.order", order, order_names, 2) == 1) &&
        (strcmp(sc->algorithm, "predictive") != 0 || sc->neighbors_cells))
        ERR(L, mode_at(L, at),
            "run.order = \"step\" needs run.algorithm = \"predictive\" with run.neighbors = "
            "\"all\" or \"grid\" (got \"%s\"%s): only their rounds can react to a step's "
            "events at once",
            sc->algorithm, strcmp(sc->algorithm, "predictive") == 0 ? ", \"cells\"" : "");
    int64_t v;
    if (get_int(L, run, "run", S_RUN_STEPS, &v, NULL) == GOT)
        sc->steps = (uint64_t)v;
    (void)get_float(L, run, "run", S_RUN_DT, &sc->dt);
    if (get_int(L, run, "run", S_RUN_THREADS, &v, &at) == GOT) {
        if (v > NBEP_THREADS_MAX)
            ERR(L, at, "run.threads must be <= %d (got %" PRId64 ")", NBEP_THREADS_MAX, v);
        else
            sc->threads = (int)v;
    }
    if (get_int(L, run, "run", S_RUN_MAX_REACTIONS, &v, NULL) == GOT)
        sc->max_reactions = (uint64_t)v;
    *seed_ok = get_int(L, run, "run", S_RUN_SEED, &v, NULL) == GOT;
    if (*seed_ok)
        sc->seed = (uint64_t)v;
}

static void parse_physics(load *L, const config_setting_t *root, nbep_scene *sc)
{
    const config_setting_t *physics = NULL;
    if (get_aggregate(L, root, "", S_PHYSICS, &physics) != GOT)
        physics = NULL;
    (void)get_vec3(L, physics, "physics", S_PHYSICS_GRAVITY, &sc->gravity, NULL);
    (void)get_float(L, physics, "physics", S_PHYSICS_RESTITUTION, &sc->restitution);
    (void)get_float(L, physics, "physics", S_PHYSICS_TC, &sc->tc);
    sc->tc_given = physics && config_setting_get_member(physics, "tc"); /* not the default */
    (void)get_float(L, physics, "physics", S_PHYSICS_CARRY_DROP, &sc->carry_drop);
    (void)get_bool(L, physics, "physics", S_PHYSICS_ZERO_MOMENTUM, &sc->zero_momentum);
}

/* What a message about both corners of a box or region (min at min, max at max) is blamed on:
 * a corner that an override gave (a --set or sweep axis of it, or of one of its elements, as
 * its own messages are named), the one typed first where both were (the list ranks the message
 * there); else max, at its deck line. (The deck having min but not max leaves max missing, or
 * an override's.) Until 2026-11-30 always max: a --set of box.min was blamed on the deck's
 * line of box.max, which the user had not touched. */
static const config_setting_t *corners_at(const load *L, const config_setting_t *min,
                                          const config_setting_t *max)
{
    const config_setting_t *const both[2] = {min, max};
    return first_set(L, both, 2, max);
}

/* min < max on every axis, else one error at `at` (corners_at) naming each failing axis. */
static bool check_corners(load *L, const config_setting_t *at, const char *prefix, nbep_vec3 lo,
                          nbep_vec3 hi)
{
    const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    char axes[160] = "";
    size_t used = 0;
    for (int k = 0; k < 3; k++)
        if (!(l[k] < h[k]))
            used += (size_t)snprintf(axes + used, sizeof axes - used, "%s%c: %s >= %s",
                                     used ? ", " : "", "xyz"[k], NBEP_G(l[k]), NBEP_G(h[k]));
    if (used) {
        ERR(L, at, "%s.min must be < %s.max on every axis (got %s)", prefix, prefix, axes);
        return false;
    }
    /* a side is a length (NBEP_DECK_SCALE_MIN, _MAX), a region's too */
    for (int k = 0; k < 3; k++)
        if (!in_scale(h[k] - l[k]))
            used += (size_t)snprintf(axes + used, sizeof axes - used, "%s%c: %s",
                                     used ? ", " : "", "xyz"[k], NBEP_G(h[k] - l[k]));
    if (!used)
        return true;
    ERR(L, at, "%s: every side must be " SCALE_RANGE " long (got %s)%s", prefix, axes,
        SCALE_HINT);
    return false;
}

/* A group's region must meet the deck's box along every wall axis (a region wholly outside it
 * places nothing: the random placement said it could place no sphere, the lattice listed every
 * sphere against a wall). One that lies partly outside is taken: its spheres land in the part
 * inside. Along a periodic axis any region is taken: its places wrap into the box (SPEC:
 * region and placement work as before there). The message is blamed as corners_at blames the
 * region's (at), or on a corner of the box (entry e's deck's) that an override gave and that
 * was typed before: a --set or sweep axis of box.min or box.max that moved the box off the
 * region is what made it (until 2026-11-30 the region's deck line was named). */
static bool check_region_meets_box(load *L, const config_setting_t *e,
                                   const config_setting_t *at, const char *prefix,
                                   const nbep_scene *sc, nbep_vec3 lo, nbep_vec3 hi)
{
    const config_setting_t *list = config_setting_parent(e);
    const config_setting_t *root = list ? config_setting_parent(list) : NULL;
    const config_setting_t *box = root ? config_setting_get_member(root, "box") : NULL;
    if (box) {
        const config_setting_t *corner = corners_at(L, config_setting_get_member(box, "min"),
                                                    config_setting_get_member(box, "max"));
        uint64_t r_at, r_corner;
        (void)nbep__scene_set_by(&L->c, at, &r_at);
        (void)nbep__scene_set_by(&L->c, corner, &r_corner);
        if (r_corner < r_at)
            at = corner;
    }
    const double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
    const double bl[3] = {sc->box_min.x, sc->box_min.y, sc->box_min.z};
    const double bh[3] = {sc->box_max.x, sc->box_max.y, sc->box_max.z};
    char axes[320] = "";
    size_t used = 0;
    for (int k = 0; k < 3; k++)
        if (!sc->periodic[k] && !(h[k] > bl[k] && l[k] < bh[k]))
            used += (size_t)snprintf(axes + used, sizeof axes - used,
                                     "%s%c: region [%g, %g], box [%g, %g]", used ? ", " : "",
                                     "xyz"[k], l[k], h[k], bl[k], bh[k]);
    if (!used)
        return true;
    ERR(L, at, "%s lies outside the box (%s)", prefix, axes);
    return false;
}

/* *periodic_at: the box.periodic setting when the deck (or --set) gives one with an axis on. */
static void parse_box(load *L, const config_setting_t *root, nbep_scene *sc,
                      const config_setting_t **periodic_at)
{
    const config_setting_t *box = NULL, *min = NULL, *max = NULL, *per = NULL;
    *periodic_at = NULL;
    if (get_aggregate(L, root, "", S_BOX, &box) != GOT)
        return;
    got g_min = get_vec3(L, box, "box", S_BOX_MIN, &sc->box_min, &min);
    got g_max = get_vec3(L, box, "box", S_BOX_MAX, &sc->box_max, &max);
    if (g_min == GOT && g_max == GOT &&
        check_corners(L, corners_at(L, min, max), "box", sc->box_min, sc->box_max))
        sc->has_box = true;
    if (get_bool3(L, box, "box", S_BOX_PERIODIC, sc->periodic, &per) == GOT &&
        (sc->periodic[0] || sc->periodic[1] || sc->periodic[2]))
        *periodic_at = per;
}

/* libconfig's syntax error in the deck's text, at its line `at`, with what libconfig says
 * beyond "syntax error" (its most common text: not said twice) and what helps find it (until
 * 2026-12-01 that line and text alone: a new user's `steps = = 10;` read "deck:1: syntax
 * error", and a group left open "deck:3: syntax error" in a deck of two lines):
 *   - the deck ended (the line past its last) inside a group, list or array: that one's line,
 *     "this '{' is never closed";
 *   - else the line's own text, up to LINE_SHOWN characters. */
#define LINE_SHOWN 60
static void syntax_error(load *L, const char *deck, const char *text, const char *what, int at)
{
    const bool plain = strcmp(what, "syntax error") == 0;
    size_t lines = 1, open_line;
    char opener;
    for (const char *p = text; *p; p++)
        lines += *p == '\n';
    if (plain && at > 0 && (size_t)at >= lines && nbep__scene_unclosed(text, &open_line, &opener)) {
        nbep_diag_add_ranked(L->c.d, nbep__scene_rank(&L->c, NULL, open_line), __FILE__, __LINE__,
                             "%s:%zu: syntax error: this '%c' is never closed (the deck ends "
                             "inside it)",
                             deck, open_line, opener);
        return;
    }
    /* a comma after a list's last element, as JSON and Python take it (a review's): libconfig
     * says only "syntax error" at the closer's line */
    char closer;
    const bool comma = plain && at > 0 && nbep__scene_trailing_comma(text, (size_t)at, &closer);
    char hint[96] = "";
    if (comma)
        snprintf(hint, sizeof hint, ": a comma before this line's '%c' (a list or array takes "
                 "none after its last element)", closer);
    const char *p = text; /* the line's text, less its leading and trailing blanks */
    for (int k = 1; k < at && *p; p++)
        k += *p == '\n';
    while (*p == ' ' || *p == '\t')
        p++;
    size_t len = strcspn(p, "\r\n");
    while (len > 0 && (p[len - 1] == ' ' || p[len - 1] == '\t'))
        len--;
    nbep_diag_add_ranked(L->c.d, nbep__scene_rank(&L->c, NULL, at > 0 ? (uint64_t)at : 0),
                         __FILE__, __LINE__, "%s:%d: syntax error%s%s%s%s%.*s%s%s", deck, at,
                         plain ? "" : ": ", plain ? "" : what, hint, len ? " (the line: " : "",
                         (int)(len > LINE_SHOWN ? LINE_SHOWN : len), p,
                         len > LINE_SHOWN ? " ..." : "", len ? ")" : "");
}

/* Periodic axes (SPEC contract 2): each longer than twice the largest diameter (the minimum
 * image needs it), and a run mode that supports them: naive and seminaive (the minimum image
 * of every pair they test, the hierarchy queried for the copies of a sphere near a face too,
 * algo_detect.c; since 2026-12-01, as SPEC has them take any deck), the predictive
 * algorithm's all-pairs mode (nearest images with an image horizon, algo_predictive.c) and
 * cells mode, whose cell blocks wrap around the box (three cells at least per periodic axis,
 * so that a neighbour is one image only). Grid mode would need its own image handling; it is
 * refused rather than run wrong. */
static void check_periodic(load *L, const config_setting_t *at, const nbep_scene *sc,
                           const nbep__scene_entry *e, size_t n_entries)
{
    double rmax = 0.0;
    for (size_t k = 0; k < n_entries; k++)
        if (e[k].count > 0)
            rmax = fmax(rmax, e[k].radius);
    const double len[3] = {sc->box_max.x - sc->box_min.x, sc->box_max.y - sc->box_min.y,
                           sc->box_max.z - sc->box_min.z};
    /* a box whose corners were refused (said already) has no sides to measure: until
     * 2026-11-30 a box.max of two numbers added "the box's x side (0) must be longer ..." for
     * each periodic axis */
    /* blamed on what the user typed first of the box's periodic axes and corners, else
     * box.periodic's line (until 2026-12-01 always that line: a --set of box.max that made the
     * box too small named the deck's box.periodic) */
    const config_setting_t *box = config_setting_parent(at);
    const config_setting_t *const by[3] = {at, box ? config_setting_get_member(box, "min") : NULL,
                                           box ? config_setting_get_member(box, "max") : NULL};
    const config_setting_t *blame = first_set(L, by, 3, at);
    for (int k = 0; k < 3 && sc->has_box; k++) {
        if (!sc->periodic[k])
            continue;
        if (!(len[k] > 4.0 * rmax))
            ERR(L, blame,
                "box.periodic: the box's %c side (%s) must be longer than %s, twice the largest "
                "sphere diameter (%s)",
                "xyz"[k], NBEP_G(len[k]), NBEP_G(4.0 * rmax), NBEP_G(2.0 * rmax));
        /* three cells of the neighbour lists' cutoff across (evloop.h) */
        else if (sc->neighbors_cells && !(len[k] >= nbep_evloop_min_periodic_side(2.0 * rmax)))
            ERR(L, blame,
                "box.periodic: run.neighbors = \"cells\" needs the box's %c side (%.10g) to be "
                "at least %.10g, %.4g times the largest radius (%g) and a millionth more, three "
                "cells across (run.neighbors = \"all\" takes a side longer than %s)",
                "xyz"[k], len[k], nbep_evloop_min_periodic_side(2.0 * rmax),
                2.0 * nbep_evloop_min_periodic_side(1.0), rmax, NBEP_G(4.0 * rmax));
    }
    /* blamed as run.order's message is (parse_run): what the user typed of the three, else
     * box.periodic's line (--set run.neighbors="grid" named the deck's box.periodic line) */
    if (strcmp(sc->algorithm, "predictive") == 0 && sc->neighbors_grid)
        ERR(L, mode_at(L, at),
            "box.periodic needs run.neighbors = \"cells\" or \"all\" with the predictive "
            "algorithm (got \"grid\"): grid mode does not handle periodic images");
}

typedef struct plane {
    nbep_vec3 normal;   /* unit */
    double offset;
    nbep_vec3 point;    /* as given, and its setting (check_span) */
    const config_setting_t *point_at;
    const config_setting_t *group; /* its entry in `planes` (planes_placed_by) */
    nbep_vec3 typed;    /* the normal as given, and its setting (check_periodic_planes) */
    const config_setting_t *normal_at;
} plane;

/* Parses `planes` into *out (owned, *n of them). */
static void parse_planes(load *L, const config_setting_t *root, plane **out, size_t *n)
{
    const config_setting_t *list = NULL;
    *out = NULL;
    *n = 0;
    if (get_aggregate(L, root, "", S_PLANES, &list) != GOT)
        return;
    size_t len = (size_t)config_setting_length(list);
    plane *p = calloc(len ? len : 1, sizeof *p);
    if (!p) {
        L->c.oom = true;
        return;
    }
    for (size_t k = 0; k < len; k++) {
        const config_setting_t *e = config_setting_get_elem(list, (unsigned)k), *at = NULL;
        char prefix[PATH_LEN];
        snprintf(prefix, sizeof prefix, "planes.[%zu]", k);
        if (!config_setting_is_group(e)) {
            type_error(L, e, prefix, "a group { normal = [...]; point = [...]; }");
            continue;
        }
        nbep_vec3 normal, point;
        const config_setting_t *point_at = NULL;
        if (get_vec3(L, e, prefix, S_PLANE_NORMAL, &normal, &at) != GOT ||
            get_vec3(L, e, prefix, S_PLANE_POINT, &point, &point_at) != GOT)
            continue;
        /* divided by its largest component first (by_largest), so that tiny or huge normals
         * normalize without underflow or overflow */
        double scale;
        const nbep_vec3 u = by_largest(normal, &scale);
        if (!(scale > 0.0)) {
            ERR(L, at, "%s.normal must not be zero (got [%g, %g, %g])", prefix, normal.x,
                normal.y, normal.z);
            continue;
        }
        /* + 0.0 turns a typed -0.0 into 0 (x + 0 is x otherwise), as the box's walls have */
        const nbep_vec3 unit =
            nbep_vec3_add(nbep_vec3_scale(u, 1.0 / nbep_vec3_norm(u)), nbep_vec3_make(0, 0, 0));
        const double offset = nbep_vec3_dot(unit, point);
        /* a point near the doubles' end can make n . point overflow; a deck without spheres
         * has no radius for check_span to hold it to, and inf reached /planes/offset (until
         * 2026-12-01, a review) */
        if (!isfinite(offset)) {
            ERR(L, point_at, "%s.point [%g, %g, %g] is too far from the origin: the plane's "
                "offset (normal . point) is not a finite number",
                prefix, point.x, point.y, point.z);
            continue;
        }
        p[k] = (plane){unit, offset, point, point_at, e, normal, at};
    }
    *out = p;
    *n = len;
}

/* A plane must lie along every periodic axis: its normal without a part there. Its half-space
 * does not repeat along an axis it crosses, so a sphere that leaves through that axis's
 * periodic face comes back behind the plane (a plane x = 0 in a box periodic along x: the
 * sphere wrapped from x = L to 0 overlaps it, and the run went on with overlaps of a fifth of a
 * radius, exit 0, until 2026-11-30). A wall across that axis is the box's own: the axis not
 * periodic. One line per plane, blamed on its normal or on the element of box.periodic (`per`)
 * that made an axis it crosses periodic, the one an override gave first (first_set), else the
 * normal's deck line. */
static void check_periodic_planes(load *L, const config_setting_t *per, const nbep_scene *sc,
                                  const plane *p, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        if (!p[k].normal_at) /* a bad plane: said already */
            continue;
        const double part[3] = {p[k].normal.x, p[k].normal.y, p[k].normal.z};
        char axes[16] = "";
        int crossed = 0;
        /* the normal, and box.periodic's element of each axis it crosses */
        const config_setting_t *by[4] = {p[k].normal_at, NULL, NULL, NULL};
        for (int a = 0; a < 3; a++)
            if (sc->periodic[a] && part[a] != 0.0) {
                by[1 + a] = config_setting_get_elem(per, (unsigned)a);
                snprintf(axes + strlen(axes), sizeof axes - strlen(axes), "%s%c",
                         crossed++ ? " and " : "", "xyz"[a]);
            }
        if (!crossed)
            continue;
        ERR(L, first_set(L, by, 4, p[k].normal_at),
            "planes.[%zu].normal [%g, %g, %g] crosses the periodic %s %s: a plane must lie "
            "along every periodic axis (a sphere leaving through a periodic face would come "
            "back behind it); wall %s (box.periodic) or give the normal no part along %s",
            k, p[k].typed.x, p[k].typed.y, p[k].typed.z, crossed > 1 ? "axes" : "axis", axes,
            crossed > 1 ? "them" : "it", crossed > 1 ? "them" : "it");
    }
}

/* Every per-entry setting that belongs only to the other kind of entry is an error. */
static bool check_entry_kind(load *L, const config_setting_t *e, const char *prefix, bool group)
{
    bool ok = true;
    for (int id = 0; id < S_COUNT; id++) {
        const char *path = schema[id].path;
        unsigned wrong = group ? F_ONE : F_GROUP;
        if (strncmp(path, "spheres.[].", 11) != 0 || strchr(path + 11, '.') ||
            !(schema[id].flags & wrong))
            continue;
        const config_setting_t *m = config_setting_get_member(e, leaf_of(path));
        if (!m)
            continue;
        ERR(L, m, "%s.%s is only for %s", prefix, leaf_of(path),
            group ? "a single sphere (with position)" : "a generated group (with count)");
        ok = false;
    }
    return ok;
}

static bool parse_entry(load *L, const config_setting_t *e, const char *prefix,
                        const nbep_scene *sc, nbep__scene_entry *out)
{
    if (!config_setting_is_group(e)) {
        type_error(L, e, prefix, "a group { ... }");
        return false;
    }
    bool has_pos = config_setting_get_member(e, "position") != NULL;
    bool has_count = config_setting_get_member(e, "count") != NULL;
    if (has_pos && has_count) {
        ERR(L, e, "%s has both position (one sphere) and count (a group)", prefix);
        return false;
    }
    if (!has_pos && !has_count) {
        ERR(L, e, "%s needs position (one sphere) or count (a group)", prefix);
        return false;
    }
    bool ok = check_entry_kind(L, e, prefix, has_count);
    out->setting = e;
    ok = get_float(L, e, prefix, S_SPH_RADIUS, &out->radius) == GOT && ok;
    ok = get_float(L, e, prefix, S_SPH_MASS, &out->mass) == GOT && ok;
    got g = get_vec3(L, e, prefix, S_SPH_ACCELERATION, &out->acc, NULL);
    if (g == NONE)
        out->acc = sc->gravity;
    ok = g != BAD && ok;
    if (has_pos) {
        out->place = NBEP__PLACE_ONE;
        out->count = 1;
        ok = get_vec3(L, e, prefix, S_SPH_POSITION, &out->position, NULL) == GOT && ok;
        ok = get_vec3(L, e, prefix, S_SPH_VELOCITY, &out->velocity, NULL) == GOT && ok;
        return ok;
    }
    int64_t count;
    if (get_int(L, e, prefix, S_SPH_COUNT, &count, &out->count_at) == GOT)
        out->count = (uint64_t)count;
    else
        ok = false;
    const char *place;
    const config_setting_t *at = NULL, *region = NULL;
    char path[PATH_LEN];
    path_join(path, prefix, "place");
    int k = -1;
    if (get_string(L, e, prefix, S_SPH_PLACE, &place, &at) == GOT)
        k = one_of(L, at, path, place, place_names, N_PLACES);
    out->place = k == 2 ? NBEP__PLACE_FCC : k == 1 ? NBEP__PLACE_LATTICE : NBEP__PLACE_RANDOM;
    ok = k >= 0 && ok;
    ok = get_float(L, e, prefix, S_SPH_SPEED, &out->speed) == GOT && ok;
    g = get_aggregate(L, e, prefix, S_SPH_REGION, &region);
    if (g == GOT) {
        path_join(path, prefix, "region");
        const config_setting_t *min = NULL, *max = NULL;
        got g_min = get_vec3(L, region, path, S_SPH_REGION_MIN, &out->lo, &min);
        got g_max = get_vec3(L, region, path, S_SPH_REGION_MAX, &out->hi, &max);
        /* a corner left out is the box's, as a group without a region takes the whole box
         * (SPEC: region defaults to the box): `--set spheres.[0].region.max=[...]` on a group
         * without one was refused, "region.min is missing", until 2026-11-30 */
        if ((g_min == NONE || g_max == NONE) && sc->has_box) {
            if (g_min == NONE)
                out->lo = sc->box_min;
            if (g_max == NONE)
                out->hi = sc->box_max;
            g_min = g_min == NONE ? GOT : g_min;
            g_max = g_max == NONE ? GOT : g_max;
        } else if ((g_min == NONE || g_max == NONE) &&
                   !config_setting_get_member(config_setting_parent(config_setting_parent(e)),
                                              "box")) { /* (a box given but bad: said already) */
            ERR(L, region, "%s.%s is missing, and the deck has no box to take it from", path,
                g_min == NONE ? "min" : "max");
        }
        at = g_min == GOT && g_max == GOT ? corners_at(L, min, max ? max : region) : NULL;
        ok = g_min == GOT && g_max == GOT && check_corners(L, at, path, out->lo, out->hi) &&
             (!sc->has_box || check_region_meets_box(L, e, at, path, sc, out->lo, out->hi)) && ok;
        if (ok && sc->has_box) {
            /* a group fills the part of its region inside the box (until 2026-11-30 a lattice
             * filled the whole region and every sphere outside was reported against a wall;
             * until 2026-12-01 random places were drawn over the whole region, and a region
             * mostly outside used up a sphere's tries against the walls: 4 of 100 placed at a
             * packing of 0.004 inside; the message's packing was the whole region's too) */
            double lo[3] = {out->lo.x, out->lo.y, out->lo.z}, hi[3] = {out->hi.x, out->hi.y,
                                                                       out->hi.z};
            const double bl[3] = {sc->box_min.x, sc->box_min.y, sc->box_min.z};
            const double bh[3] = {sc->box_max.x, sc->box_max.y, sc->box_max.z};
            for (int a = 0; a < 3; a++)
                if (!sc->periodic[a]) { /* a periodic axis wraps its places, as before */
                    lo[a] = fmax(lo[a], bl[a]);
                    hi[a] = fmin(hi[a], bh[a]);
                }
            out->lo = nbep_vec3_make(lo[0], lo[1], lo[2]);
            out->hi = nbep_vec3_make(hi[0], hi[1], hi[2]);
        }
    } else if (g == NONE && sc->has_box) {
        out->lo = sc->box_min;
        out->hi = sc->box_max;
    } else if (g == NONE) {
        /* A box that is present but invalid was reported already. */
        if (!config_setting_get_member(config_setting_parent(config_setting_parent(e)), "box"))
            ERR(L, e, "%s has no region and the deck has no box", prefix);
        ok = false;
    } else {
        ok = false;
    }
    return ok;
}

static void parse_spheres(load *L, const config_setting_t *root, const nbep_scene *sc,
                          nbep__scene_entry **out, size_t *n)
{
    const config_setting_t *list = NULL;
    *out = NULL;
    *n = 0;
    got g = get_aggregate(L, root, "", S_SPHERES, &list);
    /* No `spheres` at all is almost always a mistake (an empty or truncated file, the list
     * misnamed or commented out) that would otherwise run every step of nothing and exit 0;
     * a scene without spheres has to be asked for with an explicit empty list. */
    if (g == NONE) /* no line to name: listed after the lines' messages */
        nbep_diag_add(L->c.d, __FILE__, __LINE__,
                      "%s: no spheres: the deck has no `spheres` list (write `spheres = ();` "
                      "for a scene without spheres)",
                      L->c.deck);
    if (g != GOT)
        return;
    size_t len = (size_t)config_setting_length(list);
    nbep__scene_entry *e = calloc(len ? len : 1, sizeof *e);
    if (!e) {
        L->c.oom = true;
        return;
    }
    for (size_t k = 0; k < len; k++) {
        char prefix[PATH_LEN];
        snprintf(prefix, sizeof prefix, "spheres.[%zu]", k);
        (void)parse_entry(L, config_setting_get_elem(list, (unsigned)k), prefix, sc, &e[k]);
    }
    *out = e;
    *n = len;
}

/* One point of the deck against NBEP_DECK_SPAN_MAX smallest radii (rmin) from the origin;
 * *far raised to how many smallest radii it lies from it, along its farthest axis. */
static void span_one(load *L, const config_setting_t *at, const char *what, nbep_vec3 v,
                     double rmin, double *far_radii)
{
    const double c[3] = {v.x, v.y, v.z};
    int far = 0; /* the coordinate farthest out */
    for (int k = 1; k < 3; k++)
        far = fabs(c[k]) > fabs(c[far]) ? k : far;
    const double m = fabs(c[far]);
    /* the limit and the rounding it allows, from the constant (2^40: 2^-12 of a radius) */
    const int span_log2 = ilogb(NBEP_DECK_SPAN_MAX), ulp_log2 = span_log2 - (DBL_MANT_DIG - 1);
    const double radii = m / rmin; /* inf past DBL_MAX: said as "more than" that */
    if (m > NBEP_DECK_SPAN_MAX * rmin)
        ERR(L, at,
            "%s lies %s%.3g smallest radii (%g) from the origin, beyond 2^%d = %.2g (a "
            "coordinate of %g: positions there round by more than 2^%d of a radius); move "
            "the origin nearer the scene (README, The deck: units)",
            what, isfinite(radii) ? "" : "more than ", isfinite(radii) ? radii : DBL_MAX, rmin,
            span_log2, NBEP_DECK_SPAN_MAX, c[far], ulp_log2);
    *far_radii = fmax(*far_radii, radii);
}

/* Every coordinate the deck gives within NBEP_DECK_SPAN_MAX of its smallest radius from the
 * origin: sphere positions, box and region corners, plane points (a deck without spheres
 * has no scale to hold them to). */
static void check_span(load *L, const config_setting_t *root, nbep_scene *sc,
                       const plane *planes, size_t n_planes, const nbep__scene_entry *e,
                       size_t n_entries)
{
    double rmin = INFINITY;
    for (size_t k = 0; k < n_entries; k++)
        if (e[k].count > 0 && e[k].radius > 0.0)
            rmin = fmin(rmin, e[k].radius);
    if (!(rmin < INFINITY))
        return;
    const config_setting_t *box = config_setting_get_member(root, "box");
    if (sc->has_box && box) {
        span_one(L, config_setting_get_member(box, "min"), "box.min", sc->box_min, rmin,
                 &sc->span);
        span_one(L, config_setting_get_member(box, "max"), "box.max", sc->box_max, rmin,
                 &sc->span);
    }
    char what[PATH_LEN + 16];
    for (size_t k = 0; k < n_planes; k++)
        if (planes[k].point_at) {
            snprintf(what, sizeof what, "planes.[%zu].point", k);
            span_one(L, planes[k].point_at, what, planes[k].point, rmin, &sc->span);
        }
    for (size_t k = 0; k < n_entries; k++) {
        if (!e[k].setting || e[k].count == 0)
            continue;
        const config_setting_t *region = config_setting_get_member(e[k].setting, "region");
        if (e[k].place == NBEP__PLACE_ONE) {
            snprintf(what, sizeof what, "spheres.[%zu].position", k);
            span_one(L, config_setting_get_member(e[k].setting, "position"), what,
                     e[k].position, rmin, &sc->span);
        } else if (region) {
            snprintf(what, sizeof what, "spheres.[%zu].region.min", k);
            span_one(L, config_setting_get_member(region, "min"), what, e[k].lo, rmin,
                     &sc->span);
            snprintf(what, sizeof what, "spheres.[%zu].region.max", k);
            span_one(L, config_setting_get_member(region, "max"), what, e[k].hi, rmin,
                     &sc->span);
        }
    }
}

static char *dup_string(load *L, const char *s)
{
    char *p = malloc(strlen(s) + 1);
    if (!p)
        L->c.oom = true;
    else
        strcpy(p, s);
    return p;
}

/* The deck's file name with its extension replaced by .h5, in the current directory. */
static char *default_output(load *L, const char *deck)
{
    const char *base = strrchr(deck, '/');
    base = base ? base + 1 : deck;
    const char *dot = strrchr(base, '.');
    size_t stem = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    char *p = malloc(stem + 4);
    if (!p) {
        L->c.oom = true;
        return NULL;
    }
    memcpy(p, base, stem);
    memcpy(p + stem, ".h5", 4);
    return p;
}

static void parse_output(load *L, const config_setting_t *root, nbep_scene *sc)
{
    const config_setting_t *output = NULL, *at = NULL;
    if (get_aggregate(L, root, "", S_OUTPUT, &output) != GOT)
        output = NULL;
    const char *file;
    got g = get_string(L, output, "output", S_OUTPUT_FILE, &file, &at);
    if (g == GOT && !*file)
        ERR(L, at, "output.file must not be empty");
    else if (g == GOT) {
        sc->output_file = dup_string(L, file);
        /* set by the command line (-o, --set output.file=, --set output={file=...}): a
         * resumed run refuses another file */
        unsigned line;
        const char *label = nbep__scene_origin(at, false, &line);
        if (label)
            sc->output_file_origin = dup_string(L, label);
        else
            sc->output_file_line = line;
    } else if (g == NONE)
        sc->output_file = default_output(L, L->c.deck);
    int64_t every;
    if (get_int(L, output, "output", S_OUTPUT_EVERY, &every, NULL) == GOT)
        sc->output_every = (uint64_t)every;
    (void)get_bool(L, output, "output", S_OUTPUT_STATS, &sc->out_stats);

    if (find(L, output, "output", S_OUTPUT_FIELDS, &at) != GOT)
        return;
    const char *words;
    if (!nbep__scene_kind_holds(NBEP__K_STRINGS, false, at, &words)) {
        type_error(L, at, "output.fields", words);
        return;
    }
    for (int k = 0; k < config_setting_length(at); k++) {
        char path[PATH_LEN];
        snprintf(path, sizeof path, "output.fields.[%d]", k);
        const config_setting_t *f = config_setting_get_elem(at, (unsigned)k);
        int which = one_of(L, f, path, config_setting_get_string(f), field_names, N_FIELDS);
        /* a field named twice says nothing more: a slip, said at its line (until 2026-12-05
         * taken silently) */
        if ((which == 0 && sc->out_position) || (which == 1 && sc->out_velocity))
            ERR(L, f, "%s: \"%s\" is listed twice in output.fields", path, field_names[which]);
        sc->out_position = sc->out_position || which == 0;
        sc->out_velocity = sc->out_velocity || which == 1;
    }
}

/* Whether setting path `inner` lies inside setting path `outer` (physics.gravity.[2] inside
 * physics.gravity, spheres.[0].radius inside spheres.[0]): a run that sets outer sets inner
 * too. Both as nbep__scene_path_canon writes them (indices by number: "[02]" beside "[2]"
 * varied one setting twice, unseen; a review). */
static bool key_within(const char *outer, const char *inner)
{
    const size_t n = strlen(outer);
    return strncmp(outer, inner, n) == 0 && inner[n] == '.';
}

/* Why key cannot be a sweep axis, or NULL if it can: settings the sweep itself sets per run,
 * the groups that hold them, and the names of the sweep's table's own columns (an axis's
 * column is named by its key: a `spheres` axis gave the table two `spheres` columns, and
 * summary.h5 failed once every run had finished). */
static const char *axis_key_refused(const char *key)
{
    if (strcmp(key, "run.seed") == 0)
        return "the sweep sets it: replica r runs with run.seed + r";
    if (strcmp(key, "output.file") == 0)
        return "the sweep sets it: each run writes its own file in the sweep's directory";
    if (strcmp(key, "run") == 0 || strcmp(key, "output") == 0)
        return "it holds run.seed and run.steps or output.file, which the sweep sets or reads "
               "per run: vary the settings in it one by one";
    if (strcmp(key, "spheres") == 0 || strcmp(key, "planes") == 0)
        return "the sweep's table has a column of that name already: vary a setting in it, "
               "such as spheres.[0].count";
    if (strncmp(key, "sweep.", 6) == 0)
        return "the sweep's own settings cannot vary within it";
    return NULL;
}

/* The axes of the sweep group: sweep.vary's entries, each checked. */
static void parse_axes(load *L, const config_setting_t *sweep, nbep_scene *sc)
{
    const config_setting_t *vary = NULL;
    if (get_aggregate(L, sweep, "sweep", S_SWEEP_VARY, &vary) != GOT)
        return;
    size_t n = (size_t)config_setting_length(vary);
    if (n == 0)
        return;
    const config_setting_t *root = sweep; /* the deck's root, where an axis's path starts */
    while (config_setting_parent(root))
        root = config_setting_parent(root);
    if (!(sc->sweep_axes = calloc(n, sizeof *sc->sweep_axes)) ||
        !(L->axes = calloc(n, sizeof *L->axes))) {
        L->c.oom = true;
        return;
    }
    for (size_t k = 0; k < n; k++) {
        const config_setting_t *e = config_setting_get_elem(vary, (unsigned)k), *at = NULL;
        char prefix[PATH_LEN];
        snprintf(prefix, sizeof prefix, "sweep.vary.[%zu]", k);
        if (!config_setting_is_group(e)) {
            type_error(L, e, prefix, "a group { key = \"...\"; values = [...]; }");
            continue;
        }
        const char *key;
        got g_key = get_string(L, e, prefix, S_SWEEP_KEY, &key, &at);
        nbep__scene_kind kind;
        bool element;
        if (g_key == GOT && !nbep__scene_schema_kind(key, &kind, &element)) {
            nbep__strbuf b = {0};
            nbep__scene_unknown_text(key, &b);
            ERR(L, at, "%s.key: %s", prefix, nbep__strbuf_str(&b));
            L->c.oom = L->c.oom || b.oom;
            nbep__strbuf_fini(&b);
            g_key = BAD;
        } else if (g_key == GOT) {
            const char *refused = axis_key_refused(key);
            char list[PATH_LEN];
            unsigned len;
            if (refused) {
                ERR(L, at, "%s.key: %s cannot be varied (%s)", prefix, key, refused);
                g_key = BAD;
            } else if (!nbep__scene_path_indices_exist(root, key, list, sizeof list, &len)) {
                /* each run would append an entry with this one setting (until 2026-11-30
                 * every run failed, exit 1, and the deck check passed) */
                ERR(L, at, "%s.key: %s has %u entr%s: %s names none (vary a setting the "
                    "deck has)",
                    prefix, list, len, len == 1 ? "y" : "ies", key);
                g_key = BAD;
            }
        }
        for (size_t j = 0; g_key == GOT && j < k; j++) {
            const char *kj;
            char a[PATH_LEN], b[PATH_LEN];
            if (config_setting_lookup_string(config_setting_get_elem(vary, (unsigned)j), "key",
                                             &kj) != CONFIG_TRUE)
                continue;
            nbep__scene_path_canon(kj, a, sizeof a);
            nbep__scene_path_canon(key, b, sizeof b);
            if (strcmp(a, b) == 0) {
                ERR(L, at, "%s.key: %s is already varied by sweep.vary.[%zu]", prefix, key, j);
                g_key = BAD;
            } else if (key_within(a, b) || key_within(b, a)) {
                /* the axis of the whole would overwrite the part in every run, whose rows
                 * would then name values that never ran */
                ERR(L, at, "%s.key: %s and %s (sweep.vary.[%zu]) vary the same setting, one "
                    "inside the other; vary one of them",
                    prefix, key, kj, j);
                g_key = BAD;
            }
        }
        const config_setting_t *values;
        got g_values = find(L, e, prefix, S_SWEEP_VALUES, &values);
        const char *words;
        if (g_values == GOT && !nbep__scene_kind_holds(NBEP__K_VALUES, false, values, &words)) {
            char path[PATH_LEN];
            path_join(path, prefix, "values");
            type_error(L, values, path, words);
            g_values = BAD;
        }
        if (g_key != GOT || g_values != GOT)
            continue;
        /* each value is checked by check_axis_values, once the deck is (run.steps too: the
         * sweep compares a finished run's steps with its value to reuse it) */
        L->axes[sc->sweep_n_axes] = (axis_at){.index = k, .values = values};
        nbep_sweep_axis *axis = &sc->sweep_axes[sc->sweep_n_axes++];
        axis->key = dup_string(L, key);
        /* its line, for the messages of runs that reject a value (sweep.c); none where an
         * override gave the values or one of them (--set sweep.vary.[k].values.[v]=...) */
        (void)nbep__scene_origin(values, true, &axis->line);
        size_t n_values = (size_t)config_setting_length(values);
        if (!(axis->values = calloc(n_values, sizeof *axis->values))) {
            L->c.oom = true;
            continue;
        }
        for (size_t v = 0; v < n_values; v++) {
            nbep__strbuf b = {0};
            nbep__scene_value_text(config_setting_get_elem(values, (unsigned)v), &b);
            L->c.oom = L->c.oom || b.oom;
            axis->values[axis->n_values++] = b.p ? b.p : dup_string(L, "");
        }
    }
}

/* The deck's sweep group; `run`: a sweep's run (nbep_scene_load_run), whose run.seed is its
 * replica's, base + r, checked with the base seed by the study's own load. */
static void parse_sweep(load *L, const config_setting_t *root, nbep_scene *sc, bool run)
{
    const config_setting_t *sweep = NULL;
    sc->sweep_replicas = 1;
    if (get_aggregate(L, root, "", S_SWEEP, &sweep) != GOT)
        return;
    int64_t replicas;
    if (get_int(L, sweep, "sweep", S_SWEEP_REPLICAS, &replicas, NULL) == GOT)
        sc->sweep_replicas = (uint64_t)replicas;
    parse_axes(L, sweep, sc);
    /* replica r runs with run.seed + r, which must still be a deck's integer (a run past it
     * failed with a message about a --set nobody typed); not again in a run, whose seed is
     * its replica's (until 2026-12-02 a study with the last seed exactly 2^63 - 1 passed,
     * and every run of a later replica failed on this check) */
    if (!run && sc->sweep_replicas > 1 &&
        sc->seed > (uint64_t)INT64_MAX - (sc->sweep_replicas - 1))
        ERR(L, sweep,
            "sweep.replicas = %" PRIu64 " with run.seed = %" PRIu64 ": the last replica's seed "
            "would pass %" PRId64,
            sc->sweep_replicas, sc->seed, INT64_MAX);
    uint64_t runs = sc->sweep_replicas;
    for (size_t k = 0; k < sc->sweep_n_axes && runs <= NBEP_SWEEP_RUNS_MAX; k++)
        runs *= sc->sweep_axes[k].n_values; /* at most 10^7 times a list length < 2^31 */
    /* said at sweep.replicas where the deck or a --set gives it (a --set of a billion was
     * put at the deck's sweep line, until 2026-12-04, a review), else at the group */
    const config_setting_t *many = config_setting_get_member(sweep, "replicas");
    if (runs > NBEP_SWEEP_RUNS_MAX)
        ERR(L, many && sc->sweep_replicas > 1 ? many : sweep,
            "sweep: replicas times the product of the axes' lengths is more than %" PRIu64
            " runs",
            NBEP_SWEEP_RUNS_MAX);
}

/* ---- counts, memory, and the state ---------------------------------------------------------- */

static bool check_counts(load *L, const nbep_scene *sc, nbep__scene_entry *e, size_t n_entries,
                         size_t n_planes, size_t *total_out)
{
    uint64_t total = 0;
    size_t largest = SIZE_MAX;
    for (size_t k = 0; k < n_entries; k++) {
        e[k].first = (size_t)total;
        if (e[k].count > (uint64_t)UINT32_MAX - total) {
            char what[PATH_LEN + 40];
            if (e[k].place == NBEP__PLACE_ONE)
                snprintf(what, sizeof what, "spheres.[%zu]", k);
            else
                snprintf(what, sizeof what, "spheres.[%zu].count = %" PRIu64, k, e[k].count);
            ERR(L, e[k].count_at ? e[k].count_at : e[k].setting,
                "%s brings the total to %" PRIu64 " spheres, more than %" PRIu32
                " (sphere ids are 32-bit)",
                what, e[k].count > UINT64_MAX - total ? UINT64_MAX : total + e[k].count,
                UINT32_MAX);
            return false;
        }
        total += e[k].count;
        if (e[k].place != NBEP__PLACE_ONE && (largest == SIZE_MAX || e[k].count > e[largest].count))
            largest = k;
    }
    if (sc->neighbors_cells && total > NBEP_CALENDAR_MAX && largest != SIZE_MAX) {
        ERR(L, e[largest].count_at,
            "spheres.[%zu].count = %" PRIu64 " brings the total to %" PRIu64 " spheres, more "
            "than run.neighbors = \"cells\" takes (%zu: its event calendar's links are 32-bit)",
            largest, e[largest].count, total, NBEP_CALENDAR_MAX);
        return false;
    }
    /* Checked before allocating: an overcommitting kernel would otherwise accept the
     * allocation and kill the run later, at first touch. */
    long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    double bytes = (double)nbep_state_bytes((size_t)total, n_planes) +
                   (double)WORKSPACE_BYTES_PER_SPHERE * (double)total;
    if (pages > 0 && page > 0 && largest != SIZE_MAX && bytes > (double)pages * (double)page) {
        char need[NBEP_BYTES_TEXT_MAX], have[NBEP_BYTES_TEXT_MAX];
        ERR(L, e[largest].count_at,
            "spheres.[%zu].count = %" PRIu64 " needs %s, more than this machine's %s", largest,
            e[largest].count, nbep_format_bytes(bytes, need),
            nbep_format_bytes((double)pages * (double)page, have));
        return false;
    }
    *total_out = (size_t)total;
    return true;
}

/* The box's walls: two per axis that is not periodic. */
static size_t box_walls(const nbep_scene *sc)
{
    return 2u * (size_t)(!sc->periodic[0] + !sc->periodic[1] + !sc->periodic[2]);
}

/* Box planes first (inward: +x at min.x, -x at max.x, ...; none on periodic axes), then
 * `planes`. */
static void fill_planes(nbep_state *s, const nbep_scene *sc, const plane *p, size_t n_p)
{
    size_t k = 0;
    if (sc->has_box) {
        const double lo[3] = {sc->box_min.x, sc->box_min.y, sc->box_min.z};
        const double hi[3] = {sc->box_max.x, sc->box_max.y, sc->box_max.z};
        for (int axis = 0; axis < 3; axis++) {
            if (sc->periodic[axis])
                continue;
            double u[3] = {0.0, 0.0, 0.0};
            u[axis] = 1.0;
            s->plane_normal[k] = nbep_vec3_make(u[0], u[1], u[2]);
            s->plane_offset[k++] = lo[axis];
            u[axis] = -1.0; /* not -u, whose zeros are -0: /planes/normal held [-0, -1, -0] */
            s->plane_normal[k] = nbep_vec3_make(u[0], u[1], u[2]);
            s->plane_offset[k++] = -hi[axis];
        }
    }
    for (size_t j = 0; j < n_p; j++, k++) {
        s->plane_normal[k] = p[j].normal;
        s->plane_offset[k] = p[j].offset;
    }
}

/* What decides where each of the scene's n_all planes lies, two settings a plane in
 * fill_planes's order (malloc'd, NULL without memory): a box wall's element of box.min or
 * box.max along its axis and the element of box.periodic that walls the axis (a --set of it
 * to false makes the wall); a deck plane's group (its point and normal) and NULL; NULL where
 * the deck has none (nbep__scene_check_overlaps blames an overlap with a plane that a --set
 * moved or made on that --set). */
static const config_setting_t **planes_placed_by(const config_setting_t *root,
                                                 const nbep_scene *sc, const plane *p,
                                                 size_t n_p, size_t n_all)
{
    const config_setting_t **at = calloc(2 * (n_all ? n_all : 1), sizeof *at);
    if (!at)
        return NULL;
    size_t k = 0;
    const config_setting_t *box = config_setting_get_member(root, "box");
    const config_setting_t *lo = box ? config_setting_get_member(box, "min") : NULL;
    const config_setting_t *hi = box ? config_setting_get_member(box, "max") : NULL;
    const config_setting_t *per = box ? config_setting_get_member(box, "periodic") : NULL;
    for (int axis = 0; sc->has_box && axis < 3; axis++) {
        if (sc->periodic[axis])
            continue;
        const config_setting_t *walled = per ? config_setting_get_elem(per, (unsigned)axis) : NULL;
        at[k++] = lo ? config_setting_get_elem(lo, (unsigned)axis) : NULL;
        at[k++] = walled;
        at[k++] = hi ? config_setting_get_elem(hi, (unsigned)axis) : NULL;
        at[k++] = walled;
    }
    for (size_t j = 0; j < n_p && k < 2 * n_all; j++, k += 2)
        at[k] = p[j].group;
    return at;
}

/* ---- reading the deck ----------------------------------------------------------------------- */

/* A deck read from a pipe or a FIFO waits for its writer: a stop signal then interrupts the
 * read (EINTR), and the load stops there as it does while placing, with no message of its own
 * (until 2026-12-02 "cannot read /dev/fd/63: Interrupted system call", exit 1). */
static nbep_status read_text(const char *path, const atomic_int *stop, char **out, nbep_diag *d)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        const int err = errno;
        if (err == EINTR && nbep_status_of_stop(stop) != NBEP_OK)
            return nbep_status_of_stop(stop);
        NBEP_FAIL(d, nbep_status_of_open(err), "nbep: cannot read %s: %s", path, strerror(err));
    }
    size_t len = 0, cap = 4096;
    char *text = malloc(cap);
    while (text) {
        len += fread(text + len, 1, cap - 1 - len, f);
        if (len < cap - 1)
            break;
        char *t = realloc(text, 2 * cap);
        if (!t) {
            free(text);
            text = NULL;
            break;
        }
        text = t;
        cap *= 2;
    }
    int failed = ferror(f), err = errno;
    fclose(f);
    if (!text)
        NBEP_FAIL(d, NBEP_ENOMEM, "nbep: no memory to read %s", path);
    if (failed) {
        free(text);
        if (err == EINTR && nbep_status_of_stop(stop) != NBEP_OK)
            return nbep_status_of_stop(stop);
        NBEP_FAIL(d, nbep_status_of_open(err), "nbep: cannot read %s: %s", path, strerror(err));
    }
    text[len] = '\0';
    /* a UTF-8 byte order mark (an editor's on some systems) is no part of the deck: libconfig
     * took it for a syntax error at line 1, shown as an invisible character (a review) */
    if (len >= 3 && memcmp(text, "\xef\xbb\xbf", 3) == 0) {
        memmove(text, text + 3, len - 2);
        len -= 3;
    }
    /* a deck is text: what follows a NUL byte was read by no one (libconfig stops there, and
     * the run's `deck` attribute kept the text up to it; until 2026-12-01, a review) */
    const char *nul = memchr(text, '\0', len);
    if (nul && len >= NBEP_HDF5_SIGNATURE_LEN &&
        memcmp(text, NBEP_HDF5_SIGNATURE, NBEP_HDF5_SIGNATURE_LEN) == 0) {
        free(text);
        NBEP_FAIL(d, NBEP_EDECK,
                  "%s: an HDF5 file, not a deck (a run's file: nbep info reads it, and it holds "
                  "the deck that made it)",
                  path);
    }
    if (nul) {
        size_t line = 1;
        for (const char *c = text; c < nul; c++)
            line += *c == '\n';
        free(text);
        NBEP_FAIL(d, NBEP_EDECK, "%s:%zu: a NUL byte: a deck is text (is this the deck?)", path,
                  line);
    }
    *out = text;
    return NBEP_OK;
}

static char *join_overrides(load *L, const char *const *ov, size_t n)
{
    nbep__strbuf b = {0};
    nbep__strbuf_addn(&b, "", 0);
    for (size_t k = 0; k < n; k++)
        nbep__strbuf_add(&b, "%s%s", k ? "\n" : "", ov[k]);
    if (b.oom || !b.p) {
        L->c.oom = true;
        nbep__strbuf_fini(&b);
        return NULL;
    }
    return b.p;
}

/* Parses every literal default once; a schema default that does not parse is a bug. */
static void load_defaults(load *L, config_t *defaults)
{
    nbep__strbuf b = {0};
    for (int id = 0; id < S_COUNT; id++)
        if (schema[id].def)
            nbep__strbuf_add(&b, "d%d = %s;\n", id, schema[id].def);
    if (b.oom) {
        L->c.oom = true;
    } else {
        int parsed = config_read_string(defaults, nbep__strbuf_str(&b));
        assert(parsed && "every schema default is valid libconfig");
        for (int id = 0; parsed && id < S_COUNT; id++) {
            char name[16];
            snprintf(name, sizeof name, "d%d", id);
            L->def[id] = schema[id].def ? config_lookup(defaults, name) : NULL;
        }
    }
    nbep__strbuf_fini(&b);
}

nbep_status nbep_scene_load(const char *deck_path, const char *const *overrides,
                            size_t n_overrides, nbep_scene *out, nbep_diag *d)
{
    return nbep_scene_load_from(deck_path, overrides, NULL, n_overrides, NULL, out, d);
}

/* Override k's label for messages (nbep_scene_load_from); NULL when out of memory. */
static char *override_label(const char *const *overrides, const char *const *origins, size_t k)
{
    if (origins && origins[k])
        return strdup(origins[k]);
    nbep__strbuf b = {0};
    nbep__strbuf_add(&b, "--set %s", overrides[k]);
    if (b.oom)
        nbep__strbuf_fini(&b);
    return b.p;
}

/* What a load does (load_deck). */
typedef enum load_mode {
    LOAD_DECK,    /* everything, every sweep axis value checked on its own (nbep check, run) */
    LOAD_RUN,     /* everything but the axis values: a sweep's run, whose plan checked them */
    LOAD_VALUE    /* one axis value's check (check_axis_values): no sweep group, no spheres */
} load_mode;

static nbep_status load_deck(const char *deck_path, const char *deck_text,
                             const char *const *overrides, const char *const *origins,
                             size_t n_overrides, load_mode mode, const atomic_int *stop,
                             nbep_scene *out, nbep_diag *d);

/* Whether d holds message msg among its messages from the first'th on. */
static bool diag_has(const nbep_diag *d, size_t first, const char *msg)
{
    for (size_t k = first; k < d->n_errors; k++)
        if (d->msg && d->msg[k] && strcmp(d->msg[k], msg) == 0)
            return true;
    return false;
}

/* The deck loaded as one axis value's check (LOAD_VALUE) with the n overrides ov (labelled
 * origin), its scene let go: whether it takes them, its messages in d. */
static nbep_status load_value(const load *L, const char *deck_text, const char **ov,
                              const char **origin, size_t n, nbep_diag *d)
{
    nbep_scene value;
    const nbep_status st =
        load_deck(L->c.deck, deck_text, ov, origin, n, LOAD_VALUE, NULL, &value, d);
    if (st == NBEP_OK)
        nbep_scene_fini(&value);
    return st;
}

/* Whether the value of axis a that the deck refuses alone (ov[n_overrides], as
 * check_axis_values set it, labelled label) is taken with some value of another axis: a
 * box.min on one axis and a box.max on another, each past the deck's other corner, make a box
 * in every run (until 2026-12-02 such a study was refused, each value checked against the
 * deck's own corners only). ov and origin have room for one more override. One value of one
 * other axis at a time: what needs three axes together, and which combinations fail, stay the
 * runs' to find. */
static bool value_with_another(load *L, const nbep_scene *sc, const char *deck_text,
                               const char **ov, const char **origin, size_t n_overrides,
                               size_t a, const char *label)
{
    for (size_t b = 0; b < sc->sweep_n_axes && !L->c.oom; b++) {
        const nbep_sweep_axis *other = &sc->sweep_axes[b];
        for (size_t w = 0; b != a && w < other->n_values && !L->c.oom; w++) {
            nbep__strbuf with = {0};
            nbep__strbuf_add(&with, "%s=%s", other->key, other->values[w]);
            nbep_diag quiet;
            nbep_diag_init(&quiet);
            nbep_status st = NBEP_ENOMEM;
            if (!with.oom) {
                ov[n_overrides + 1] = with.p;
                origin[n_overrides + 1] = label;
                st = load_value(L, deck_text, ov, origin, n_overrides + 2, &quiet);
            }
            L->c.oom = L->c.oom || st == NBEP_ENOMEM;
            nbep_diag_fini(&quiet);
            nbep__strbuf_fini(&with);
            if (st == NBEP_OK)
                return true;
        }
    }
    return false;
}

/* Checks every value of every sweep axis on its own against the base deck (the deck's text
 * and the command line's overrides, labels), so that a value no run can take is a deck error
 * of nbep check, nbep run and the sweep's plan, not a run that fails after the others have
 * run (until 2026-11-30 such a study passed the check and nbep sweep exited 1).
 *
 * A value is loaded as its runs load it, the base plus KEY=VALUE, in LOAD_VALUE mode: the
 * deck's text parsed again and every type, range and cross check made (a box.max below the
 * deck's min, a radius the periodic box cannot take, counts past memory), so that a value
 * gets exactly the message a --set of it gets; but without the sweep group, and without
 * allocating or placing spheres, so each value costs a parse of the deck, not the placement
 * of millions of spheres. (Checking the value against the schema alone, its type and range
 * flags, would be cheaper but miss the cross checks and word its messages anew.) What only
 * placement finds (an overlap at t0, a group that does not fit) and what two axes do together
 * (a radius on one, a box on another) stay the runs' to find; a value refused alone is tried
 * with each value of each other axis (value_with_another) before it counts as refused.
 *
 * The value's messages are named as the value, "DECK:LINE: sweep.vary.[k].values.[v]" (the
 * element's line) or "--set ...: sweep.vary.[k].values.[v]" where a --set gave it; a message
 * about something else the value broke says which value, "...values.[v]: with KEY=VALUE, ";
 * messages the base load has too (d's from errors0 on, a problem of the deck itself) are not
 * repeated. */
static void check_axis_values(load *L, const nbep_scene *sc, const char *deck_text,
                              const char *const *overrides, const char *const *labels,
                              size_t n_overrides, size_t errors0)
{
    const char **ov = calloc(n_overrides + 2, sizeof *ov); /* and value_with_another's two */
    const char **origin = calloc(n_overrides + 2, sizeof *origin);
    if (!ov || !origin) {
        L->c.oom = true;
        goto out;
    }
    for (size_t k = 0; k < n_overrides; k++) {
        ov[k] = overrides[k];
        origin[k] = labels[k];
    }
    for (size_t a = 0; a < sc->sweep_n_axes && !L->c.oom; a++) {
        const nbep_sweep_axis *axis = &sc->sweep_axes[a];
        for (size_t v = 0; v < axis->n_values && !L->c.oom; v++) {
            unsigned line;
            const char *by = nbep__scene_origin(
                config_setting_get_elem(L->axes[a].values, (unsigned)v), false, &line);
            nbep__strbuf set = {0}, label = {0};
            nbep__strbuf_add(&set, "%s=%s", axis->key, axis->values[v]);
            if (by)
                nbep__strbuf_add(&label, "%s: ", by);
            else
                nbep__strbuf_add(&label, "%s:%u: ", L->c.deck, line ? line : 1);
            nbep__strbuf_add(&label, "sweep.vary.[%zu].values.[%zu]", L->axes[a].index, v);
            nbep_diag one;
            nbep_diag_init(&one);
            nbep_status st = NBEP_ENOMEM;
            if (!set.oom && !label.oom) {
                ov[n_overrides] = set.p;
                origin[n_overrides] = label.p;
                st = load_value(L, deck_text, ov, origin, n_overrides + 1, &one);
                if (st == NBEP_EDECK &&
                    value_with_another(L, sc, deck_text, ov, origin, n_overrides, a, label.p))
                    st = NBEP_OK; /* a run's combination takes it */
            }
            L->c.oom = L->c.oom || st == NBEP_ENOMEM;
            const uint64_t rank = nbep__scene_rank(&L->c, by, by ? 0 : line);
            const size_t n_label = strlen(nbep__strbuf_str(&label));
            for (size_t k = 0; st == NBEP_EDECK && k < one.n_errors; k++) {
                const char *msg = one.msg ? one.msg[k] : NULL;
                if (!msg || diag_has(L->c.d, errors0, msg))
                    continue;
                if (strncmp(msg, label.p, n_label) == 0 && msg[n_label] == ':')
                    nbep_diag_add_ranked(L->c.d, rank, __FILE__, __LINE__, "%s", msg);
                else
                    nbep_diag_add_ranked(L->c.d, rank, __FILE__, __LINE__, "%s: with %s, %s",
                                         label.p, set.p, msg);
            }
            nbep_diag_fini(&one);
            nbep__strbuf_fini(&set);
            nbep__strbuf_fini(&label);
        }
    }
out:
    free(ov);
    free(origin);
}

nbep_status nbep_scene_load_from(const char *deck_path, const char *const *overrides,
                                 const char *const *origins, size_t n_overrides,
                                 const atomic_int *stop, nbep_scene *out, nbep_diag *d)
{
    return load_deck(deck_path, NULL, overrides, origins, n_overrides, LOAD_DECK, stop, out, d);
}

nbep_status nbep_scene_load_run(const char *deck_path, const char *const *overrides,
                                const char *const *origins, size_t n_overrides,
                                const atomic_int *stop, nbep_scene *out, nbep_diag *d)
{
    return load_deck(deck_path, NULL, overrides, origins, n_overrides, LOAD_RUN, stop, out, d);
}

/* The deck at deck_path (its text deck_text, or NULL to read it) loaded as mode says; stop as
 * nbep_scene_load_from takes it (an axis value's load places nothing, and takes NULL). */
static nbep_status load_deck(const char *deck_path, const char *deck_text,
                             const char *const *overrides, const char *const *origins,
                             size_t n_overrides, load_mode mode, const atomic_int *stop,
                             nbep_scene *out, nbep_diag *d)
{
    load L = {.c = {.deck = deck_path, .d = d, .stop = stop}};
    nbep_scene sc;
    memset(&sc, 0, sizeof sc);
    config_t cfg, defaults;
    config_init(&cfg);
    config_init(&defaults);
    nbep__scene_entry *entries = NULL;
    plane *planes = NULL;
    size_t n_entries = 0, n_planes = 0;
    char *text = NULL;
    /* the overrides' labels, the hooks of the settings they make: freed with the tree */
    char **labels = calloc(n_overrides ? n_overrides : 1, sizeof *labels);
    L.c.labels = (const char *const *)labels;
    L.c.n_labels = n_overrides;
    const size_t errors0 = d->n_errors;

    nbep_status st = NBEP_OK;
    if (!deck_text) {
        if ((st = read_text(deck_path, stop, &sc.deck_text, d)) != NBEP_OK)
            goto done;
        deck_text = sc.deck_text;
    }
    sc.deck_path = dup_string(&L, deck_path);
    sc.overrides = join_overrides(&L, overrides, n_overrides);
    size_t n_bad, n_unread;
    if (!(text = nbep__scene_widen(&L.c, deck_text, NULL, &n_bad, &n_unread))) {
        L.c.oom = true;
        goto finish;
    }
    if (n_unread) /* refused, each at its line: libconfig must not read the file */
        goto finish;
    if (!config_read_string(&cfg, text)) {
        syntax_error(&L, deck_path, deck_text, config_error_text(&cfg), config_error_line(&cfg));
        goto finish;
    }
    for (size_t k = 0; k < n_overrides && !L.c.oom; k++) {
        if (!labels || !(labels[k] = override_label(overrides, origins, k)))
            L.c.oom = true;
        else
            nbep__scene_apply_override(&L.c, &cfg, overrides[k], labels[k]);
    }
    load_defaults(&L, &defaults);

    const config_setting_t *root = config_root_setting(&cfg);
    nbep__scene_check_known(&L.c, root);
    bool seed_ok;
    parse_run(&L, root, &sc, &seed_ok);
    /* placement reads no physics (a group's spheres take gravity as it stands, and only the
     * run flies them): a restitution out of range hid every overlap and misplaced sphere
     * until 2026-12-04 (a review's), against "every problem is listed at once" */
    parse_physics(&L, root, &sc);
    const size_t geometry0 = d->n_errors;
    const config_setting_t *periodic_at;
    parse_box(&L, root, &sc, &periodic_at);
    parse_planes(&L, root, &planes, &n_planes);
    parse_spheres(&L, root, &sc, &entries, &n_entries);
    if (periodic_at) {
        check_periodic(&L, periodic_at, &sc, entries, n_entries);
        check_periodic_planes(&L, periodic_at, &sc, planes, n_planes);
    }
    check_span(&L, root, &sc, planes, n_planes, entries, n_entries);
    const bool geometry_ok = seed_ok && d->n_errors == geometry0 && !L.c.oom;
    parse_output(&L, root, &sc);
    if (mode != LOAD_VALUE)
        parse_sweep(&L, root, &sc, mode == LOAD_RUN);
    if (mode == LOAD_DECK && sc.sweep_n_axes && !L.c.oom)
        check_axis_values(&L, &sc, deck_text, overrides, (const char *const *)labels,
                          n_overrides, errors0);

    size_t total, n_all_planes = n_planes + (sc.has_box ? box_walls(&sc) : 0);
    if (geometry_ok && check_counts(&L, &sc, entries, n_entries, n_all_planes, &total) &&
        mode != LOAD_VALUE) {
        st = nbep_state_init(&sc.state, total, n_all_planes, d);
        if (st != NBEP_OK)
            goto done;
        fill_planes(&sc.state, &sc, planes, n_planes);
        const double side[3] = {sc.box_max.x - sc.box_min.x, sc.box_max.y - sc.box_min.y,
                                sc.box_max.z - sc.box_min.z};
        for (int k = 0; k < 3; k++)
            sc.state.period[k] = sc.has_box && sc.periodic[k] ? side[k] : 0.0;
        const size_t fill0 = d->n_errors;
        /* what moved each plane: a group that finds no room, or an overlap, is blamed on it */
        const config_setting_t **plane_at =
            planes_placed_by(root, &sc, planes, n_planes, n_all_planes);
        st = plane_at ? NBEP_OK : NBEP_ENOMEM;
        if (!plane_at)
            nbep_diag_add(d, __FILE__, __LINE__, "nbep: out of memory while loading %s",
                          deck_path);
        if (st == NBEP_OK)
            st = nbep__scene_place(&L.c, &sc.state, entries, n_entries, sc.seed,
                                   sc.has_box ? sc.periodic : NULL, sc.box_min, sc.box_max,
                                   plane_at);
        if (st == NBEP_OK && d->n_errors == fill0)
            st = nbep__scene_check_overlaps(&L.c, &sc.state, entries, n_entries,
                                            sc.has_box ? sc.periodic : NULL, sc.box_min,
                                            sc.box_max, plane_at);
        if (st == NBEP_OK && d->n_errors == fill0 && sc.zero_momentum)
            nbep_physics_zero_momentum(&sc.state);
        free(plane_at);
        if (st != NBEP_OK)
            goto done;
    }
finish:
    if (L.c.oom) {
        nbep_diag_add(d, __FILE__, __LINE__, "nbep: out of memory while loading %s", deck_path);
        st = NBEP_ENOMEM;
    } else {
        st = d->n_errors > errors0 ? NBEP_EDECK : NBEP_OK;
    }
done:
    /* the load's messages in the order a user reads and fixes them (nbep__scene_rank): found
     * check by check, they would jump about the deck */
    nbep_diag_sort(d, errors0);
    free(entries);
    free(planes);
    free(L.axes);
    free(text);
    config_destroy(&defaults);
    config_destroy(&cfg);
    for (size_t k = 0; labels && k < n_overrides; k++)
        free(labels[k]);
    free(labels);
    if (st == NBEP_OK)
        *out = sc;
    else
        nbep_scene_fini(&sc);
    return st;
}

void nbep_scene_fini(nbep_scene *sc)
{
    if (!sc)
        return;
    free(sc->deck_path);
    free(sc->deck_text);
    free(sc->overrides);
    free(sc->output_file);
    free(sc->output_file_origin);
    nbep_state_fini(&sc->state);
    for (size_t k = 0; sc->sweep_axes && k < sc->sweep_n_axes; k++) {
        free(sc->sweep_axes[k].key);
        for (size_t v = 0; v < sc->sweep_axes[k].n_values; v++)
            free(sc->sweep_axes[k].values[v]);
        free(sc->sweep_axes[k].values);
    }
    free(sc->sweep_axes);
    memset(sc, 0, sizeof *sc);
}

/* ---- pair counting -------------------------------------------------------------------------- */

static int cmp_vec3(const void *a, const void *b)
{
    const nbep_vec3 *u = a, *v = b;
    if (u->x != v->x)
        return u->x < v->x ? -1 : 1;
    if (u->y != v->y)
        return u->y < v->y ? -1 : 1;
    if (u->z != v->z)
        return u->z < v->z ? -1 : 1;
    return 0;
}

const char *nbep_scene_neighbors_name(const nbep_scene *sc)
{
    return sc->neighbors_cells ? "cells" : sc->neighbors_grid ? "grid" : "all";
}

const char *nbep_scene_order_name(const nbep_scene *sc)
{
    return sc->order_step ? "step" : "time";
}

/* The default tc (1e-6) is a time for grains in SI units, where a step is about 1e-3 s and
 * the TC model's window a thousandth of it. A default over a tenth of the step says the deck's
 * time unit is another (a micron-scale gas at dt = 1e-7: the window 10 steps wide, and most
 * collisions of its cooling elastic, twice the energy kept against the same gas in unit
 * scale; a new user's find): a warning, not an error, since such a window may be meant. */
#define TC_DEFAULT_STEP_SHARE 0.1

bool nbep_scene_tc_model(const nbep_scene *sc)
{
    return sc->tc > 0.0 && sc->restitution < 1.0;
}

bool nbep_scene_all_pairs(const nbep_scene *sc)
{
    return strcmp(sc->algorithm, "predictive") == 0 && !sc->neighbors_grid &&
           !sc->neighbors_cells;
}

bool nbep_scene_any_periodic(const nbep_scene *sc)
{
    return sc->has_box && (sc->periodic[0] || sc->periodic[1] || sc->periodic[2]);
}

const char *nbep_scene_tc_warning(const nbep_scene *sc, char *buf, size_t len)
{
    if (sc->tc_given || !nbep_scene_tc_model(sc) || strcmp(sc->algorithm, "predictive") != 0 ||
        !(sc->tc > TC_DEFAULT_STEP_SHARE * sc->dt))
        return NULL;
    snprintf(buf, len,
             "nbep: warning: %s: physics.tc is at its default, %g, %.3g times run.dt (%g): the "
             "TC model makes a collision within tc of a sphere's last elastic and ends a bounce "
             "shorter than tc at rest, and the default is a contact time in seconds (SI grains, "
             "dt about 1e-3); where the deck's time "
             "unit is another, or its contacts are shorter, set physics.tc (0: off)",
             sc->deck_path, sc->tc, sc->tc / sc->dt, sc->dt);
    return buf;
}

bool nbep_scene_cells_engine(const nbep_scene *sc)
{
    return sc->neighbors_cells && strcmp(sc->algorithm, "predictive") == 0;
}

bool nbep_scene_resume_point(const nbep_scene *sc, int64_t step)
{
    return !nbep_scene_cells_engine(sc) || step % (int64_t)sc->output_every == 0;
}

double nbep_scene_packing_fraction(const nbep_scene *sc, const nbep_state *st)
{
    if (!sc->has_box)
        return NAN;
    double vol = 1.0, spheres = 0.0;
    vol *= sc->box_max.x - sc->box_min.x;
    vol *= sc->box_max.y - sc->box_min.y;
    vol *= sc->box_max.z - sc->box_min.z;
    for (size_t i = 0; i < st->n; i++)
        spheres += 4.0 / 3.0 * 3.14159265358979323846 * pow(st->radius[i], 3.0);
    return spheres / vol;
}

/* Nothing dissipates: no sparse start crowds later (nbep_nblist_skin_for). */
static bool elastic(const nbep_scene *sc)
{
    return sc->restitution == 1.0;
}

double nbep_scene_list_skin(const nbep_scene *sc, const nbep_state *st)
{
    return nbep_nblist_skin_for(nbep_scene_packing_fraction(sc, st), nbep_state_free_flight(st),
                                elastic(sc));
}

bool nbep_scene_list_sparse(const nbep_scene *sc, const nbep_state *st)
{
    return nbep_nblist_sparse(nbep_scene_packing_fraction(sc, st), elastic(sc));
}

bool nbep_scene_neighbors_aside(const nbep_scene *sc)
{
    return strcmp(sc->algorithm, "predictive") != 0 && (sc->neighbors_grid || sc->neighbors_cells);
}

double nbep_scene_list_skin_taken(const nbep_scene *sc, const nbep_state *st)
{
    const double skin = nbep_scene_list_skin(sc, st), rmax = nbep_state_max_radius(st);
    if (!sc->has_box || !(rmax > 0.0))
        return skin;
    return nbep_evloop_skin_in(skin, 2.0 * rmax, sc->periodic, sc->box_min, sc->box_max) /
           (2.0 * rmax);
}

void nbep_scene_count_pairs(const nbep_state *s, uint64_t *quadratic, uint64_t *quartic)
{
    const uint64_t n = s->n, all = n * (n ? n - 1 : 0) / 2;
    uint64_t same = 0;
    nbep_vec3 *a = n ? malloc(n * sizeof *a) : NULL;
    if (a) {
        /* Sorted, equal accelerations are runs; a run of c spheres holds c(c-1)/2 pairs. */
        memcpy(a, s->acc, n * sizeof *a);
        qsort(a, n, sizeof *a, cmp_vec3);
        for (uint64_t i = 0, j; i < n; i = j) {
            for (j = i + 1; j < n && nbep_vec3_equal(a[j], a[i]); j++)
                ;
            same += (j - i) * (j - i - 1) / 2;
        }
        free(a);
    } else {
        /* No memory to sort: the common case (every sphere under gravity alone) in O(n),
         * else pair by pair. */
        bool uniform = true;
        for (uint64_t i = 1; uniform && i < n; i++)
            uniform = nbep_vec3_equal(s->acc[i], s->acc[0]);
        if (uniform)
            same = all;
        for (uint64_t i = 0; !uniform && i < n; i++)
            for (uint64_t j = i + 1; j < n; j++)
                same += nbep_vec3_equal(s->acc[i], s->acc[j]);
    }
    *quadratic = same;
    *quartic = all - same;
}

/* ---- decks alike (a sweep's reuse) ------------------------------------------------------------ */

/* Whether member m of a group (parent's name pname, NULL at the root) is neutral for
 * nbep_scene_decks_alike: as the sweep's neutral overrides (sweep.c, override_is_neutral). */
static bool alike_neutral(const char *pname, const config_setting_t *parent,
                          const config_setting_t *m)
{
    const char *name = config_setting_name(m);
    if (!name || !config_setting_is_group(parent))
        return false;
    if (config_setting_is_root(parent))
        return strcmp(name, "sweep") == 0;
    if (!config_setting_is_root(config_setting_parent(parent)) || !pname)
        return false;
    return (strcmp(pname, "run") == 0 && (strcmp(name, "steps") == 0 || strcmp(name, "threads") == 0)) ||
           (strcmp(pname, "output") == 0 && strcmp(name, "file") == 0);
}

/* The k-th member of aggregate s from *at on that is not neutral, or NULL; *at moves past it. */
static const config_setting_t *alike_next(const config_setting_t *s, int *at)
{
    const char *pname = config_setting_name(s);
    for (config_setting_t *m; (m = config_setting_get_elem(s, (unsigned)*at)) != NULL;) {
        (*at)++;
        if (!alike_neutral(pname, s, m))
            return m;
    }
    return NULL;
}

/* An integer and a float of the same value are one number to the load (`mass = 1` is
 * `mass = 1.0`; until 2026-12-05 a study's folder was refused as another deck's for it, a
 * review's find): alike when each converts to the other exactly. */
static bool numbers_alike(const config_setting_t *a, const config_setting_t *b)
{
    const bool fa = config_setting_type(a) == CONFIG_TYPE_FLOAT;
    const config_setting_t *f = fa ? a : b, *i = fa ? b : a;
    const double x = config_setting_get_float(f);
    const long long n = config_setting_get_int64(i);
    /* 2^63 as a double is past every int64: the range test keeps the cast defined */
    return x >= -0x1p63 && x < 0x1p63 && (long long)x == n && (double)n == x;
}

static bool settings_alike(const config_setting_t *a, const config_setting_t *b)
{
    const char *na = config_setting_name(a), *nb = config_setting_name(b);
    if ((!na) != (!nb) || (na && strcmp(na, nb) != 0))
        return false;
    const int ta = config_setting_type(a), tb = config_setting_type(b);
    const bool int_a = ta == CONFIG_TYPE_INT || ta == CONFIG_TYPE_INT64;
    const bool int_b = tb == CONFIG_TYPE_INT || tb == CONFIG_TYPE_INT64;
    if ((int_a && tb == CONFIG_TYPE_FLOAT) || (ta == CONFIG_TYPE_FLOAT && int_b))
        return numbers_alike(a, b);
    if (ta != tb && !(int_a && int_b))
        return false;
    switch (config_setting_type(a)) {
    case CONFIG_TYPE_INT:
    case CONFIG_TYPE_INT64:
        return config_setting_get_int64(a) == config_setting_get_int64(b);
    case CONFIG_TYPE_FLOAT: /* the same text gives the same double; -0.0 and 0.0 alike */
        return config_setting_get_float(a) == config_setting_get_float(b);
    case CONFIG_TYPE_BOOL:
        return config_setting_get_bool(a) == config_setting_get_bool(b);
    case CONFIG_TYPE_STRING:
        return strcmp(config_setting_get_string(a), config_setting_get_string(b)) == 0;
    default: { /* group, array, list: member by member, the neutral ones skipped */
        int ia = 0, ib = 0;
        for (;;) {
            const config_setting_t *ma = alike_next(a, &ia), *mb = alike_next(b, &ib);
            if (!ma || !mb)
                return !ma && !mb;
            if (!settings_alike(ma, mb))
                return false;
        }
    }
    }
}

/* Reads a deck's text into cfg as the load does (widened for libconfig 1.5); false when it
 * cannot (a syntax error, an @include, out of memory: messages into a diag dropped here). */
static bool alike_read(config_t *cfg, const char *text)
{
    nbep_diag d;
    nbep_diag_init(&d);
    nbep__scene_ctx c = {.deck = "", .d = &d};
    size_t n_bad = 0, n_unread = 0;
    char *wide = nbep__scene_widen(&c, text, NULL, &n_bad, &n_unread);
    const bool ok = wide && !n_bad && config_read_string(cfg, wide);
    free(wide);
    nbep_diag_fini(&d);
    return ok;
}

bool nbep_scene_decks_alike(const char *a, const char *b)
{
    config_t ca, cb;
    config_init(&ca);
    config_init(&cb);
    const bool alike = alike_read(&ca, a) && alike_read(&cb, b) &&
                       settings_alike(config_root_setting(&ca), config_root_setting(&cb));
    config_destroy(&ca);
    config_destroy(&cb);
    return alike;
}
