/* The input deck (libconfig) resolved into a scene: run settings, physics, output settings and
 * the initial spheres and planes. The only user of libconfig. A schema table drives parsing,
 * --set overrides and unknown-setting errors. */
#ifndef NBEP_SCENE_H
#define NBEP_SCENE_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "nbep/compiler.h"
#include "nbep/state.h"
#include "nbep/status.h"
#include "nbep/vec3.h"

#define NBEP_ALGO_NAME_MAX 16

/* The most threads a run takes (run.threads): more than any node's cores, where OpenMP's pool
 * fails (40000 threads: libgomp could not create them; 100000: a crash inside it) and every
 * thread's workspaces cost memory for nothing. */
#define NBEP_THREADS_MAX 1024

/* The magnitudes a deck's quantities with units may take when not 0 (a radius, a mass, a time
 * step, tc, a box's side, a speed, a velocity's, an acceleration's length): within
 * [NBEP_DECK_SCALE_MIN, NBEP_DECK_SCALE_MAX] in any one system of units. The contact kernels
 * square products of a length and a speed (the quadratic's b^2 and |dv|^2 sigma^2), which
 * underflowed past about 1e-75 and overflowed past 1e75 in (length x speed): a fluid scaled
 * by 2^-300 in length and speed lost its collisions (overlaps of 1.9 radii) without a word.
 * Within 1e+-40 every quantity nbep forms stays a normal double with room to spare: a product
 * of a length and a speed differing in the last bit, squared, 1e-192 at least; a pressure
 * m v^2 / L^3, 1e+-240; sums over 1e12 collisions, 1e+-252; a fall's speed after 1e9 steps,
 * squared with a length, 1e258 (tests/test_extremes.c runs scenes scaled to the window's
 * corners and gets the same frames, scaled). It holds every physical system of units: SI from
 * below the electron's mass (9e-31 kg) and the Planck length (1.6e-35 m) to 1e40 kg. */
#define NBEP_DECK_SCALE_MIN 1e-40
#define NBEP_DECK_SCALE_MAX 1e40

/* How far from the origin a deck's coordinates (sphere positions, box and region corners,
 * plane points) may lie, in units of the smallest radius: 2^40 (1.1e12). A position carries
 * 16 digits, so its rounding is 2^-52 of its size: at 2^40 radii from the origin that is 2^-12
 * of a radius, and contacts there are placed to a few of those. Farther out a review found
 * overlaps of 129 radii (a box of 1e17 around spheres of radius 1) and a plane 1e300 away
 * that stopped a falling sphere dead at t = 0 (its contact time's discriminant overflowed):
 * deck errors now. The window of magnitudes alone bounds each quantity, not their ratio. */
#define NBEP_DECK_SPAN_MAX 0x1p40

/* One `vary` entry of the sweep group: a deck path and the values it takes, each kept as the
 * libconfig text of the value so that it can be applied as "key=value" like --set. */
typedef struct nbep_sweep_axis {
    char *key;          /* owned, e.g. "physics.restitution" */
    size_t n_values;
    char **values;      /* owned, e.g. "0.9", "[0.0, 0.0, -1.0]", "\"naive\"" */
    unsigned line;      /* the deck's line of its values; 0 where a --set gave them */
} nbep_sweep_axis;

/* The most runs a sweep takes (replicas times the product of the axes' lengths): more is a
 * mistake in the deck (a product of long axes), not a study. The deck check refuses it, so
 * that nbep sweep's plan (sweep.c) can count its runs without overflow. */
#define NBEP_SWEEP_RUNS_MAX ((uint64_t)10000000)

/* The jam hold (algo_predictive.c, JAM_HOLD): with e < 1 and accelerations, a sphere that has
 * reacted this many times in one step is held where it is at its next meeting with a held
 * sphere (any speed) or, carried by planes, any sphere. Here because --help-deck names it. */
#define NBEP_JAM_HOLD 10000
/* A sphere in the jam (pred_react.c, in_jam): this many reactions in the step; a jammed
 * sphere that meets one moves on as one body with it (jam_lock). Here for --help-deck. */
#define NBEP_JAM_JOIN 1000

/* physics.carry_drop's default (algo_predictive.c, carried): a held sphere struck no faster
 * than a fall from this fraction of its radius stays held when its faces take the push. Here
 * because --help-deck and the tests' hand-built scenes use it. */
#define NBEP_CARRY_DROP 0.01

typedef struct nbep_scene {
    /* provenance */
    char *deck_path;          /* owned: as given on the command line */
    char *deck_text;          /* owned: the deck file's full text */
    char *overrides;          /* owned: one "PATH=VALUE" per line, "" when none */
    /* run */
    char algorithm[NBEP_ALGO_NAME_MAX];   /* "naive" | "seminaive" | "predictive" */
    uint64_t steps;
    double dt;
    int threads;              /* as given; 0 = OMP_NUM_THREADS or all cores */
    uint64_t seed;
    bool neighbors_grid;      /* predictive: re-predict against nearby cells, not all spheres */
    bool neighbors_cells;     /* predictive: the in-step event loop (evloop.c) over cell lists */
    uint64_t max_reactions;   /* predictive: more reactions of one sphere in a step: jammed,
                               * the run stops (0: no limit) */
    bool order_step;          /* predictive "all"/"grid": run.order = "step", the paper's step
                               * (a step's events react at once; approximate) */
    /* physics */
    nbep_vec3 gravity;
    double restitution;
    double tc;                /* TC model: collisions within tc of the last are elastic */
    bool tc_given;            /* physics.tc was set (deck or override), not its default */
    double carry_drop;        /* held spheres carry impacts no faster than a fall from
                               * carry_drop of their radius (0: off) */
    bool zero_momentum;       /* placed spheres' total momentum taken off, kinetic energy kept
                               * (nbep_physics_zero_momentum) */
    double span;              /* the deck's farthest coordinate from the origin (sphere
                               * positions, box and region corners, plane points) in smallest
                               * radii, at most NBEP_DECK_SPAN_MAX: a position's rounding there
                               * is span * 2^-53 of a radius (0: no coordinate, or no sphere) */
    /* box (optional) */
    bool has_box;
    nbep_vec3 box_min, box_max;
    bool periodic[3];         /* box.periodic: the box repeats along that axis (no walls) */
    /* output */
    char *output_file;        /* owned: resolved (default: deck name with .h5) */
    char *output_file_origin; /* owned: the command line's option that set output.file (-o
                               * FILE, --set ..., as typed), NULL where the deck did or the
                               * default holds (a resumed run refuses another file) */
    unsigned output_file_line; /* the deck's line that set output.file, 0 where none did */
    uint64_t output_every;    /* >= 1 */
    bool out_position, out_velocity;
    bool out_stats;
    /* the initial condition, planes included (box planes first, then `planes`) */
    nbep_state state;
    /* sweep (optional group, used by `nbep sweep`): replicas x cartesian product of axes */
    uint64_t sweep_replicas;              /* >= 1; 1 when the deck has no sweep group */
    size_t sweep_n_axes;
    struct nbep_sweep_axis *sweep_axes;   /* owned */
} nbep_scene;

/* Reads and validates the deck at deck_path, applies the overrides (each "PATH=VALUE", as
 * --set takes them; n_overrides may be 0), places generated groups and fills *out.
 * Reports every problem it finds, one line each as "deck:line: message", then returns
 * NBEP_EDECK (NBEP_ENOMEM for counts that cannot be allocated, NBEP_EIO when the deck cannot
 * be read). A sweep group's axis values are each checked on their own against the deck and
 * the overrides, as a --set of the value (scene.c, check_axis_values). *out is written only on
 * success; release it with nbep_scene_fini. */
NBEP_MUST_CHECK nbep_status nbep_scene_load(const char *deck_path,
                                            const char *const *overrides, size_t n_overrides,
                                            nbep_scene *out, nbep_diag *d);
/* The same, with what the user typed for each override, for its messages: origins[k] (say
 * "-n abc" for `-n abc`, which gives the override "run.steps=abc"), or, where origins or
 * origins[k] is NULL, "--set PATH=VALUE". stop (borrowed, may be NULL) is main.c's signal
 * flag: the placement of the spheres and the overlap check, a second or so per million
 * spheres each, look at it every PLACE_LOOK spheres (scene_place.c), and one raised ends the
 * load there with NBEP_ESIGINT or NBEP_ESIGTERM (nbep_status_of_stop) and no message of its
 * own (the caller says what stopped; the deck's problems found before stay in d). */
NBEP_MUST_CHECK nbep_status nbep_scene_load_from(const char *deck_path,
                                                 const char *const *overrides,
                                                 const char *const *origins, size_t n_overrides,
                                                 const atomic_int *stop, nbep_scene *out,
                                                 nbep_diag *d);
/* nbep_scene_load_from for one run of a sweep (sweep.c): the same checks but one, that of
 * each sweep axis value on its own against the base deck, which the sweep's plan made once
 * for all its runs (it parses the deck once per value). */
NBEP_MUST_CHECK nbep_status nbep_scene_load_run(const char *deck_path,
                                                const char *const *overrides,
                                                const char *const *origins, size_t n_overrides,
                                                const atomic_int *stop, nbep_scene *out,
                                                nbep_diag *d);
void nbep_scene_fini(nbep_scene *sc);

/* Whether two decks' texts make the same runs (a sweep's reuse of its folder's files: a file
 * made from another deck is not this study's run): the same settings, in the same order, with
 * the same values, comments and layout aside, but for those that say how far a run goes or
 * where it is written, which the sweep judges apart (run.steps, run.threads, output.file, and
 * the sweep group: a run's combination and seed are its own overrides). False when either
 * text cannot be read as a deck (libconfig's syntax) or memory runs out. */
bool nbep_scene_decks_alike(const char *a, const char *b);
/* run.neighbors as the deck spells it: "all", "grid" or "cells" (predictive's setting). */
const char *nbep_scene_neighbors_name(const nbep_scene *sc);
/* run.order as the deck spells it: "time" or "step". */
const char *nbep_scene_order_name(const nbep_scene *sc);
/* Whether a run of sc continues bit for bit from its frame at `step`: any frame, but in the
 * predictive cells mode only those at a multiple of output.every (its rebuild points,
 * algo_predictive.c cells_steps). */
bool nbep_scene_resume_point(const nbep_scene *sc, int64_t step);
/* Whether the TC model acts in sc's predictive runs: tc > 0 and e < 1 (its window makes a
 * collision elastic; at e = 1 every collision is). */
bool nbep_scene_tc_model(const nbep_scene *sc);
/* Whether the scene's box repeats along some axis (box.periodic): a frame's image counts, a
 * detection's minimum image. */
bool nbep_scene_any_periodic(const nbep_scene *sc);
/* Whether sc runs the paper's all-pairs mode: the predictive algorithm with run.neighbors =
 * "all", which predicts each sphere against every other (n^2 / 2 pair tests before the first
 * step, n - 1 at each event). */
bool nbep_scene_all_pairs(const nbep_scene *sc);
/* A warning's line (no newline) when sc's TC model runs with its default physics.tc, a time
 * in the deck's units, that is more than TC_DEFAULT_STEP_SHARE of run.dt, as in a deck in
 * other units than SI grains' (the default's); NULL when not (tc set, the model off, or the
 * default small against the step); the line is written into buf (len bytes). */
const char *nbep_scene_tc_warning(const nbep_scene *sc, char *buf, size_t len);
/* Whether sc runs on the cells engine (predictive, run.neighbors = "cells"): its lists are
 * rebuilt at the multiples of output.every, and their skin is nbep_scene_list_skin_taken's. */
bool nbep_scene_cells_engine(const nbep_scene *sc);
/* The fraction of sc's box that the spheres of st fill (the scene's own, or a run's, whose
 * radii are the same: `nbep check` prints it; the cells mode picks its lists' skin from it);
 * NAN without a box. */
double nbep_scene_packing_fraction(const nbep_scene *sc, const nbep_state *st);
/* The skin of the cells mode's neighbour lists for sc with the spheres of st, as a fraction
 * of the largest diameter (nbep_nblist_skin_for: from the packing fraction when nothing
 * accelerates), which the run asks its lists for. */
double nbep_scene_list_skin(const nbep_scene *sc, const nbep_state *st);
/* Whether that skin is by the rule of sparse elastic scenes (nbep_nblist_sparse). */
bool nbep_scene_list_sparse(const nbep_scene *sc, const nbep_state *st);
/* Whether sc asks a neighbour mode ("grid", "cells") of an algorithm that has none (naive,
 * seminaive: they find pairs their own way), which leaves it aside. */
bool nbep_scene_neighbors_aside(const nbep_scene *sc);
/* The skin the run's lists then take, as a fraction of the largest diameter: the same, unless
 * a small periodic box cuts it down (nbep check prints this one). */
double nbep_scene_list_skin_taken(const nbep_scene *sc, const nbep_state *st);

/* Pairs of spheres whose accelerations are equal (quadratic contact time) and differ
 * (quartic), counted in O(n log n) by grouping equal accelerations. */
void nbep_scene_count_pairs(const nbep_state *s, uint64_t *quadratic, uint64_t *quartic);

/* Writes the deck reference (every setting, type, default, meaning) generated from the schema
 * table, as Markdown. Used by `nbep --help-deck` and to keep README in step. */
void nbep_scene_print_reference(FILE *f);

#endif
