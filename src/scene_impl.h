/* Internals shared by the scene module's files: scene.c (parsing, validation),
 * scene_schema.c/.h (the schema table and its queries), scene_text.c (messages and text
 * helpers around libconfig), scene_override.c (--set) and scene_place.c (generated groups and
 * the overlap check). Calls go one way: scene.c -> override, place, schema, text;
 * override -> schema, text; schema -> text; place -> text. Nothing here is used outside the
 * scene module. */
#ifndef NBEP_SCENE_IMPL_H
#define NBEP_SCENE_IMPL_H

#include <libconfig.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/state.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

/* ---- one load's context --------------------------------------------------------------------- */

typedef struct nbep__scene_ctx {
    const char *deck;   /* borrowed: the deck path as given, for "deck:line:" */
    nbep_diag *d;       /* borrowed */
    bool oom;           /* an allocation failed: the load ends with NBEP_ENOMEM */
    const char *const *labels;   /* borrowed: the overrides' labels in the order given (n_labels
                                  * of them, NULL where not made yet), for nbep__scene_rank */
    size_t n_labels;
    const atomic_int *stop;      /* borrowed, may be NULL: the signal flag placement looks at */
} nbep__scene_ctx;

/* A message's rank in the load's list (nbep_diag_add_ranked; the load sorts its messages when
 * it ends): the command line's options first, in the order given (label, one of c->labels),
 * then the deck's lines from the top (label NULL, line >= 1); messages that name neither are
 * added unranked (nbep_diag_add) and come last, but for the count of overlaps not listed,
 * which follows the last listed (at its rank). Of one rank, messages keep the order of the
 * checks. In scene_text.c. */
uint64_t nbep__scene_rank(const nbep__scene_ctx *c, const char *label, uint64_t line);

/* Adds "WHERE: message" for setting s, WHERE being "deck:line" or, for a setting an override
 * made (its libconfig hook holds the override text), "--set PATH=VALUE". file/line are ours.
 * In scene_text.c. */
void nbep__scene_error(nbep__scene_ctx *c, const config_setting_t *s, const char *file, int line,
                       const char *fmt, ...) NBEP_PRINTF(5, 6);
/* Where setting s came from: the label of the override that made it, or one of its elements
 * when `elements` (a vector the deck gave, one value of which a --set replaced: that --set is
 * what changed it), or a group above it that an override made or replaced; else NULL and
 * *line the deck's line (0 where there is none). In scene_text.c. */
const char *nbep__scene_origin(const config_setting_t *s, bool elements, unsigned *line);
/* The override that made setting s (may be NULL), or one of its elements for an array
 * (nbep__scene_origin), NULL where none did; *rank its rank in the load's list
 * (nbep__scene_rank), NBEP_DIAG_UNRANKED where none: of several settings, a message about them
 * is blamed on the one with the least rank, the option typed first. In scene_text.c. */
const char *nbep__scene_set_by(const nbep__scene_ctx *c, const config_setting_t *s,
                               uint64_t *rank);
/* nbep__scene_error for a message whose origin was found already (nbep__scene_origin's answer:
 * the override's label, else NULL and the deck's line at, 1 where 0). In scene_text.c. */
void nbep__scene_error_from(nbep__scene_ctx *c, const char *label, unsigned at, const char *file,
                            int line, const char *fmt, ...) NBEP_PRINTF(6, 7);
#define NBEP__SCENE_ERR(c, s, ...) nbep__scene_error((c), (s), __FILE__, __LINE__, __VA_ARGS__)

/* ---- growable strings ----------------------------------------------------------------------- */

typedef struct nbep__strbuf {
    char *p;       /* owned, NUL-terminated once anything was added */
    size_t len, cap;
    bool oom;      /* an append failed; p holds what fitted before */
} nbep__strbuf;

void nbep__strbuf_add(nbep__strbuf *b, const char *fmt, ...) NBEP_PRINTF(2, 3);
void nbep__strbuf_addn(nbep__strbuf *b, const char *s, size_t n);
/* The text so far, "" when empty; valid until the next append or fini. */
const char *nbep__strbuf_str(const nbep__strbuf *b);
void nbep__strbuf_fini(nbep__strbuf *b);

/* ---- text (scene_text.c) -------------------------------------------------------------------- */

/* Copy of libconfig text rewritten so that libconfig 1.5 reads what the user meant (see the
 * definition): the deck's text (label NULL) or an override's value (label, one of c->labels).
 * Integers beyond 64 bits are reported as "DECK:LINE: ..." or "LABEL: ..." and counted in
 * *n_bad. In the deck's text, an `@include` directive (libconfig's: `@include "file"` at the
 * start of a line) is refused, "DECK:LINE: @include is not supported ...", and counted in
 * *n_bad and in *n_unread (the deck must not be parsed: libconfig would read the file); so is a
 * block comment never closed (libconfig would read it to the end, and what it then finds
 * missing is no mistake of the user's). NULL when out of memory. */
char *nbep__scene_widen(nbep__scene_ctx *c, const char *text, const char *label, size_t *n_bad,
                        size_t *n_unread);
/* Whether libconfig text leaves a group, list or array open at its end ({, ( or [ outside
 * strings and comments): then the line of the innermost one left open, and which it is. */
bool nbep__scene_unclosed(const char *text, size_t *line, char *opener);
/* Whether a list's or array's closer on `line` follows a comma (strings and comments aside):
 * `( a, b, )`, which libconfig calls a plain syntax error; *closer is it. */
bool nbep__scene_trailing_comma(const char *text, size_t line, char *closer);
/* Appends the libconfig text of a value: 0.9, 8192, 5000000000L, "text", [0.0, 1.0], (...),
 * { a = 1; }. Floats keep a '.' or an exponent so that they read back as floats. */
void nbep__scene_value_text(const config_setting_t *s, nbep__strbuf *b);
/* A short description of a value for "(got ...)": its text when short, else its kind. */
void nbep__scene_describe(const config_setting_t *s, nbep__strbuf *b);
/* Optimal-string-alignment edit distance (insert, delete, substitute, swap neighbours). */
size_t nbep__scene_edit_distance(const char *a, const char *b);

/* ---- schema queries (scene_schema.c) ------------------------------------------------------ */

typedef enum nbep__scene_kind {
    NBEP__K_GROUP,     /* { ... } */
    NBEP__K_LIST,      /* ( {...}, {...} ) */
    NBEP__K_STRING,
    NBEP__K_INT,       /* int or int64; a float is an error */
    NBEP__K_FLOAT,     /* float, int or int64; finite */
    NBEP__K_BOOL,
    NBEP__K_VEC3,      /* 3 finite numbers, array or list */
    NBEP__K_BOOL3,     /* 3 booleans, array or list */
    NBEP__K_STRINGS,   /* array or list of strings */
    NBEP__K_VALUES     /* non-empty array or list of any values */
} nbep__scene_kind;

/* Schema kind of a concrete path such as "spheres.[2].count" ("[N]" segments index lists). A
 * path that indexes into a list or array entry ("spheres.[0]", "physics.gravity.[2]") is
 * known, with *element set. Returns false for a path outside the schema. */
bool nbep__scene_schema_kind(const char *path, nbep__scene_kind *kind, bool *element);
/* Whether setting s has the type of a setting of kind k (an element of one when `element`:
 * a number of a [x, y, z], a group of a list, ...; any value of a sweep's values), and in
 * *words what that type is ("an integer", "3 numbers [x, y, z]", ...): the one rule of types
 * that the deck's getters (scene.c) and the check of what an override replaces (below) ask. */
bool nbep__scene_kind_holds(nbep__scene_kind k, bool element, const config_setting_t *s,
                            const char **words);
/* Writes "unknown setting PATH" plus " (did you mean P?)" when a close known path exists. */
void nbep__scene_unknown_text(const char *path, nbep__strbuf *b);
/* Reports each setting of the tree under root that the schema does not know, "DECK:LINE:
 * unknown setting PATH (did you mean P?)", walking every group and every group of a list. */
void nbep__scene_check_known(nbep__scene_ctx *c, const config_setting_t *root);
/* The deck's setting old (may be NULL), at concrete path canon, which the override `label`
 * replaces: it and everything under it must be known and of its kind's type (the deck, run
 * without the override, fails there otherwise), each fault reported at its deck line. */
void nbep__scene_check_replaced(nbep__scene_ctx *c, const config_setting_t *old,
                                const char *canon, const char *label);

/* ---- overrides (scene_override.c) ----------------------------------------------------------- */

/* Applies one "PATH=VALUE" override to the tree; problems go to the diag as "LABEL: ...",
 * label the option the user typed ("--set PATH=VALUE", "-n abc"). Settings it makes carry
 * the label as their hook (it must outlive the tree's messages). */
void nbep__scene_apply_override(nbep__scene_ctx *c, config_t *cfg, const char *ov,
                                const char *label);

/* path as an override names it (split_path: indices by number, "[02]" as "[2]", each after a
 * dot) into canon (len bytes); path itself, cut to fit, when it is no path. */
void nbep__scene_path_canon(const char *path, char *canon, size_t len);

/* Whether every list index of path (a schema path, "spheres.[5].radius") names an entry the
 * tree root has: false with the first list that lacks one (its path into list, list_len
 * bytes) and its length. An override there would append an entry instead (a sweep's axis:
 * the same in every run, so a deck error). A list missing on the way has no entries. */
bool nbep__scene_path_indices_exist(const config_setting_t *root, const char *path,
                                    char *list, size_t list_len, unsigned *len);

/* ---- placement (scene_place.c) -------------------------------------------------------------- */

typedef enum nbep__place {
    NBEP__PLACE_ONE,
    NBEP__PLACE_RANDOM,
    NBEP__PLACE_LATTICE, /* simple cubic */
    NBEP__PLACE_FCC      /* face-centred cubic */
} nbep__place;
/* Whether a group's places are a lattice's sites (which fill the region inside the box and
 * never look at other planes), not random ones. */
static inline bool nbep__place_is_lattice(nbep__place p)
{
    return p == NBEP__PLACE_LATTICE || p == NBEP__PLACE_FCC;
}

/* One validated `spheres` entry: a single sphere or a generated group. */
typedef struct nbep__scene_entry {
    const config_setting_t *setting;   /* borrowed: the entry's group, for messages */
    const config_setting_t *count_at;  /* borrowed: its count (groups), for fill messages */
    nbep__place place;
    uint64_t count;                    /* 1 for a single sphere */
    size_t first;                      /* id of its first sphere */
    double radius, mass, speed;
    nbep_vec3 position, velocity;      /* single sphere */
    nbep_vec3 acc;                     /* its own, or physics.gravity */
    nbep_vec3 lo, hi;                  /* group: the region */
} nbep__scene_entry;

/* Fills the spheres of s (allocated, planes set) from the entries in deck order: single
 * spheres as given, groups by random or lattice placement (deterministic for seed). Reports
 * each group that does not fit, blamed on the --set typed first of what places it, of what
 * placed the spheres its random tries met (another group's count, say) or of what bounds its
 * room (the box, the planes: plane_at, as nbep__scene_check_overlaps takes it). box_periodic
 * is NULL without a box, else the box's periodic axes: a random sphere keeps clear of the
 * others by the nearest image along them, across the faces of [box_lo, box_hi] too. Returns
 * NBEP_ENOMEM on allocation failure, NBEP_ESIGINT or NBEP_ESIGTERM (no message) when it found
 * c->stop raised, looking every PLACE_LOOK spheres of a group, else NBEP_OK (fill failures are
 * counted in the diag). Looking changes no place: they depend on (seed, group, sphere) only. */
NBEP_MUST_CHECK nbep_status nbep__scene_place(nbep__scene_ctx *c, nbep_state *s,
                                              const nbep__scene_entry *e, size_t n_entries,
                                              uint64_t seed, const bool *box_periodic,
                                              nbep_vec3 box_lo, nbep_vec3 box_hi,
                                              const config_setting_t *const *plane_at);
/* Reports every pair of spheres, and every sphere and plane, that overlap by more than
 * round-off (the first few in the load's order, nbep__scene_rank, by name, then how many
 * more, ranked with the last named). Each is blamed on what placed its spheres: a --set (or
 * sweep axis) of a member of their entry that decides where they go or how big they are, else
 * the deck's line of the position or entry. box_periodic is NULL without a box, else the
 * box's periodic axes: the box's walls (two per other axis) come first and are named
 * "box x-min" ..., the rest "planes.[k]"; pairs that overlap across a periodic face of the box
 * [lo, hi] are found too (spheres as placed, whose centres are inside the box), and blamed
 * on a --set of the box's min, max or periodic along the axes they meet across too, where
 * typed first (it moved or made those faces). An overlap with a plane is blamed on a --set
 * that moved or made the plane, where one did and was typed before whatever placed the
 * sphere: plane_at (2 s->n_planes, each may be NULL) holds what decides where each plane lies,
 * two a plane: a box wall's element of box.min or box.max and of box.periodic, a deck plane's
 * group (its point and normal) and NULL. O(n) expected time (a second or so per million
 * spheres): like nbep__scene_place it looks at c->stop every PLACE_LOOK spheres, and returns
 * NBEP_ESIGINT or NBEP_ESIGTERM (no message, nothing reported) when it found it raised. */
NBEP_MUST_CHECK nbep_status nbep__scene_check_overlaps(nbep__scene_ctx *c, const nbep_state *s,
                                                       const nbep__scene_entry *e,
                                                       size_t n_entries,
                                                       const bool *box_periodic, nbep_vec3 lo,
                                                       nbep_vec3 hi,
                                                       const config_setting_t *const *plane_at);

#endif
