/* The deck's schema, shared by the scene module's files (scene_impl.h lists them): one table
 * (SCENE_SCHEMA) gives every setting's path, type, default and meaning. scene_schema.c holds
 * the table and what only reads it (path queries, "did you mean", the --help-deck reference);
 * scene.c (parsing) and scene_override.c (--set) use it; it uses only scene_text.c. */
#ifndef NBEP_SCENE_SCHEMA_H
#define NBEP_SCENE_SCHEMA_H

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "scene_impl.h"

/* A macro's value as a string literal (NBEP_JAM_HOLD in the help text) */
#define NBEP_SCHEMA_STR(x) #x
#define NBEP_SCHEMA_XSTR(x) NBEP_SCHEMA_STR(x)

enum {
    F_REQUIRED = 1 << 0,   /* must be given when its group is */
    F_GT0 = 1 << 1,        /* > 0 */
    F_GE0 = 1 << 2,        /* >= 0 */
    F_GE1 = 1 << 3,        /* >= 1 */
    F_IN01 = 1 << 4,       /* in [0, 1] */
    F_ONE = 1 << 5,        /* only in a single-sphere entry (one with position) */
    F_GROUP = 1 << 6,      /* only in a generated group (one with count) */
    F_SCALE = 1 << 7       /* a quantity with units: 0, or its magnitude (a vector's length) in
                            * [NBEP_DECK_SCALE_MIN, NBEP_DECK_SCALE_MAX] */
};

/* The window of F_SCALE as text, as scene.h writes its bounds */
#define SCALE_RANGE                                                                                \
    NBEP_SCHEMA_XSTR(NBEP_DECK_SCALE_MIN) " to " NBEP_SCHEMA_XSTR(NBEP_DECK_SCALE_MAX)

/* X(id, path, kind, flags, default as libconfig text or NULL, default as shown when there is
 * no literal one, meaning). "[]" in a path stands for any index of that list. */
#define SCENE_SCHEMA(X)                                                                            \
    X(RUN, "run", GROUP, 0, NULL, "-", "how to run")                                               \
    X(RUN_ALGORITHM, "run.algorithm", STRING, 0, "\"predictive\"", NULL,                           \
      "\"naive\", \"seminaive\" or \"predictive\"")                                                \
    X(RUN_STEPS, "run.steps", INT, F_GE0, "1000", NULL,                                            \
      "time steps after t0; frames t0..t_steps")                                                   \
    X(RUN_DT, "run.dt", FLOAT, F_GT0 | F_SCALE,                                                    \
      "1.0e-3", NULL, "the constant time step")                                                    \
    X(RUN_THREADS, "run.threads", INT, F_GE0, "0", NULL,                                           \
      "threads; 0: OMP_NUM_THREADS, else all cores (\"cells\" with no gravity: the event loop "    \
      "runs as a team of up to 16, any others share the rebuilds and update only); at most "     \
      NBEP_SCHEMA_XSTR(NBEP_THREADS_MAX))                                                         \
    X(RUN_SEED, "run.seed", INT, F_GE0, "1", NULL, "every random choice derives from it")          \
    X(RUN_NEIGHBORS, "run.neighbors", STRING, 0, "\"all\"", NULL,                                  \
      "predictive: whom a re-prediction tests: \"all\" spheres (the paper), \"grid\" (nearby "  \
      "cells within a time horizon) or \"cells\" (event loop: cell lists and a calendar over "   \
      "the box, or without one over the spheres' extent)")                                         \
    X(RUN_ORDER, "run.order", STRING, 0, "\"time\"", NULL,                                         \
      "predictive \"all\" or \"grid\": how a step's events are reacted to: \"time\" (earliest "    \
      "first, re-predicting in between: exact) or \"step\" (the paper's step: every event "        \
      "found before the step's end that is the earliest of both its spheres reacts in one "        \
      "round, then re-predict; faster on crowded scenes, approximate: spheres may overlap)")       \
    X(RUN_MAX_REACTIONS, "run.max_reactions", INT, F_GE1, "1000000", NULL,                         \
      "predictive: a sphere that reacts more than this many times in one step is jammed "         \
      "(pressed between walls and neighbours that nbep cannot hold still, README: granular "      \
      "scenes): the run stops with exit 1, its frames kept, instead of never ending the step "    \
      "(with e < 1 and gravity a sphere is first held where it is after "                        \
      NBEP_SCHEMA_XSTR(NBEP_JAM_HOLD) " reactions in a "                                          \
      "step, at its next meeting with a held sphere or, carried by planes, any sphere; such "  \
      "a sphere that meets one with " NBEP_SCHEMA_XSTR(NBEP_JAM_JOIN) " reactions in the step "  \
      "moves on as one body with it and every such sphere touching them)")                       \
    X(PHYSICS, "physics", GROUP, 0, NULL, "-", "physics")                                          \
    X(PHYSICS_GRAVITY, "physics.gravity", VEC3, F_SCALE,                                           \
      "[0.0, 0.0, 0.0]", NULL,                                                                     \
      "uniform acceleration of every sphere without its own")                                      \
    X(PHYSICS_RESTITUTION, "physics.restitution", FLOAT, F_IN01, "1.0", NULL,                      \
      "coefficient of restitution e, sphere-sphere and sphere-plane")                              \
    X(PHYSICS_TC, "physics.tc", FLOAT, F_GE0 | F_SCALE,                                            \
      "1.0e-6", NULL,                                                                              \
      "TC model: a collision within tc seconds of the sphere's previous one is elastic (stops "  \
      "inelastic collapse); 0: off; the default is a time for grains in SI units (dt about "       \
      "1e-3): run and check warn when it is over a tenth of run.dt, as in other units")            \
    X(PHYSICS_CARRY_DROP, "physics.carry_drop", FLOAT, F_GE0, NBEP_SCHEMA_XSTR(NBEP_CARRY_DROP),   \
      NULL, "a held sphere (e < 1, accelerated) struck no faster than a fall from carry_drop of "  \
      "its radius (sqrt(2 a carry_drop r), a its acceleration) stays held when the faces that "    \
      "hold it take the push, and the striker bounces off it as off a wall, so a settling pile "  \
      "does not wake at every touch; a faster impact wakes it and what it carries; 0: off")        \
    X(PHYSICS_ZERO_MOMENTUM, "physics.zero_momentum", BOOL, 0, "false", NULL,                      \
      "after placing, take the centre of mass's velocity off every sphere's and scale them all "  \
      "to keep the kinetic energy the speeds gave: the total momentum is zero (random "            \
      "directions leave about sqrt(N) m speed, whose kinetic energy counts in kT and pressure)")   \
    X(BOX, "box", GROUP, 0, NULL, "none",                                                          \
      "optional: inward planes bounding [min, max], two per axis that is not periodic")          \
    X(BOX_MIN, "box.min", VEC3, F_REQUIRED, NULL, "required", "lower corner")                      \
    X(BOX_MAX, "box.max", VEC3, F_REQUIRED, NULL, "required",                                      \
      "upper corner, above min on every axis by " SCALE_RANGE)                                     \
    X(BOX_PERIODIC, "box.periodic", BOOL3, 0, "[false, false, false]", NULL,                       \
      "per axis: the box repeats along it (no walls there; contacts by the minimum image; "    \
      "positions wrapped, /frames/image counts the periods); a periodic side must exceed "      \
      "twice the largest diameter (\"cells\": 6.75 largest radii, three cells across); "       \
      "planes must lie along a periodic axis; every algorithm, predictive \"grid\" mode excepted")          \
    X(PLANES, "planes", LIST, 0, NULL, "none", "extra static planes, after the box's walls")       \
    X(PLANE_NORMAL, "planes.[].normal", VEC3, F_REQUIRED, NULL, "required",                        \
      "points to where spheres live; normalized; not zero; no part along a periodic axis")      \
    X(PLANE_POINT, "planes.[].point", VEC3, F_REQUIRED, NULL, "required",                          \
      "a point of the plane")                                                                      \
    X(SPHERES, "spheres", LIST, 0, NULL, "required",                                               \
      "single spheres (with position) and generated groups (with count); ids in this order; "      \
      "`spheres = ();` for a scene without spheres (a deck without the list is an error)")         \
    X(SPH_POSITION, "spheres.[].position", VEC3, F_ONE, NULL, "none",                              \
      "a single sphere's centre")                                                                  \
    X(SPH_VELOCITY, "spheres.[].velocity", VEC3, F_ONE | F_SCALE,                                  \
      "[0.0, 0.0, 0.0]", NULL,                                                                     \
      "a single sphere's velocity")                                                                \
    X(SPH_COUNT, "spheres.[].count", INT, F_GE0 | F_GROUP, NULL, "none",                           \
      "a group's number of spheres")                                                               \
    X(SPH_RADIUS, "spheres.[].radius", FLOAT, F_REQUIRED | F_GT0 | F_SCALE,                        \
      NULL, "required", "radius")                                                                  \
    X(SPH_MASS, "spheres.[].mass", FLOAT, F_REQUIRED | F_GT0 | F_SCALE,                            \
      NULL, "required", "mass")                                                                    \
    X(SPH_ACCELERATION, "spheres.[].acceleration", VEC3, F_SCALE,                                  \
      NULL, "physics.gravity",                                                                     \
      "own uniform acceleration, replacing physics.gravity")                                       \
    X(SPH_PLACE, "spheres.[].place", STRING, F_GROUP, "\"random\"", NULL,                          \
      "\"random\" (uniform, non-overlapping), \"lattice\" (simple cubic) or \"fcc\" "              \
      "(face-centred cubic, packing fractions up to 0.74)")                                       \
    X(SPH_SPEED, "spheres.[].speed", FLOAT, F_GE0 | F_GROUP | F_SCALE,                             \
      "0.0", NULL,                                                                                 \
      "each sphere of a group moves at this speed in a random direction")                          \
    X(SPH_REGION, "spheres.[].region", GROUP, F_GROUP, NULL, "the box",                            \
      "where a group is placed")                                                                   \
    X(SPH_REGION_MIN, "spheres.[].region.min", VEC3, 0, NULL, "box.min",                           \
      "lower corner")                                                                              \
    X(SPH_REGION_MAX, "spheres.[].region.max", VEC3, 0, NULL, "box.max",                           \
      "upper corner, above min on every axis by " SCALE_RANGE)                                     \
    X(OUTPUT, "output", GROUP, 0, NULL, "-", "output")                                             \
    X(OUTPUT_FILE, "output.file", STRING, 0, NULL, "the deck's name with .h5",                     \
      "HDF5 file (nbep-1 format)")                                                                 \
    X(OUTPUT_EVERY, "output.every", INT, F_GE1, "10", NULL,                                        \
      "a frame at step 0, every `every` steps, and the last step (run.neighbors = \"cells\": "        \
      "each brings every sphere to the frame's time, rebuilds the cells and lists and predicts "    \
      "afresh, so that a run resumes from it bit for bit; another `every` changes the "            \
      "round-off, and a chaotic scene's trajectory with it)")                                     \
    X(OUTPUT_FIELDS, "output.fields", STRINGS, 0, "[\"position\", \"velocity\"]", NULL,            \
      "per-sphere fields of each frame: \"position\", \"velocity\"")                               \
    X(OUTPUT_STATS, "output.stats", BOOL, 0, "true", NULL, "per-step counters in /stats")          \
    X(SWEEP, "sweep", GROUP, 0, NULL, "none",                                                      \
      "parameter study for `nbep sweep`; run and check validate it, each axis value with the "     \
      "deck, then take the deck as one run without it")                                            \
    X(SWEEP_REPLICAS, "sweep.replicas", INT, F_GE1, "1", NULL,                                     \
      "runs of every combination of values")                                                       \
    X(SWEEP_VARY, "sweep.vary", LIST, 0, NULL, "none", "the axes of the study")                    \
    X(SWEEP_KEY, "sweep.vary.[].key", STRING, F_REQUIRED, NULL, "required",                        \
      "a deck path, as --set takes it")                                                            \
    X(SWEEP_VALUES, "sweep.vary.[].values", VALUES, F_REQUIRED, NULL, "required",                  \
      "the values it takes (array or list); each must pass with the deck as a --set of it")

enum schema_id {
#define X_ENUM(id, path, kind, flags, def, def_doc, meaning) S_##id,
    SCENE_SCHEMA(X_ENUM)
#undef X_ENUM
    S_COUNT
};

typedef struct schema_entry {
    const char *path;
    nbep__scene_kind kind;
    unsigned flags;
    const char *def;       /* libconfig text of the default, NULL when none is literal */
    const char *def_doc;   /* the default as documented when def is NULL */
    const char *meaning;
} schema_entry;

extern const schema_entry nbep__scene_schema[S_COUNT];
/* The id of a schema path ("spheres.[].radius"), -1 when there is none. */
int nbep__scene_schema_find(const char *abstract);

/* Concrete paths are short ("sweep.vary.[12].values"); longer user names are cut in messages. */
enum { PATH_LEN = 256 };

/* snprintf into a path buffer. Paths longer than PATH_LEN only come from long misspelt names
 * and are cut; the format-truncation warning is therefore not wanted here. */
NBEP_PRINTF(3, 4)
static inline void cut_printf(char *out, size_t len, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(out, len, fmt, ap);
    va_end(ap);
}

/* The last name of a path: "spheres.[].radius" -> "radius". */
static inline const char *leaf_of(const char *path)
{
    const char *dot = strrchr(path, '.');
    return dot ? dot + 1 : path;
}

#endif
