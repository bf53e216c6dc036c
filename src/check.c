/* `nbep check`'s two reports (check.h), from one nbep_check_facts. The JSON on jansson, as the
 * summary's (summary.c), with its reals written by the same rule. */
#include "nbep/check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "build_info.h"
#include "nbep/nblist.h"
#include "nbep/output.h"
#include "nbep/output_xdmf.h"
#include "nbep/run.h"
#include "nbep/sim.h"
#include "nbep/summary.h"

#define CHECK_FORMAT_NAME "nbep-check-1"

/* The mean count of spheres within cut of a sphere's centre, the box's density times the
 * ball's volume, and no more than the other spheres (a small box's ball can hold it all); NaN
 * without lists, a box or spheres. */
static double partners_within(const nbep_scene *sc, double cut, bool lists)
{
    if (!lists || !sc->has_box || sc->state.n == 0)
        return NAN;
    const nbep_vec3 b = nbep_vec3_sub(sc->box_max, sc->box_min);
    const double density = (double)sc->state.n / (b.x * b.y * b.z);
    const double ball = 4.0 / 3.0 * 3.14159265358979323846 * cut * cut * cut;
    return fmin((double)(sc->state.n - 1), density * ball);
}

void nbep_check_gather(const nbep_scene *sc, nbep_check_facts *f)
{
    memset(f, 0, sizeof *f);
    f->threads = nbep_sim_resolve_threads(sc->threads);
    nbep_sim_threads_use(sc, f->threads, f->threads_use, sizeof f->threads_use);
    nbep_scene_count_pairs(&sc->state, &f->pairs_quadratic, &f->pairs_quartic);
    f->packing = nbep_scene_packing_fraction(sc, &sc->state);
    f->lists = nbep_scene_cells_engine(sc);
    if (f->lists) {
        f->skin_asked = nbep_scene_list_skin(sc, &sc->state);
        f->skin_taken = nbep_scene_list_skin_taken(sc, &sc->state);
    }
    f->radius_max = nbep_state_max_radius(&sc->state);
    f->radius_min = f->radius_max;
    for (size_t i = 0; i < sc->state.n; i++)
        f->radius_min = fmin(f->radius_min, sc->state.radius[i]);
    /* a list reaches its pair's contact and the skin (evloop.c), the skin a fraction of the
     * largest diameter; the cells are as wide as the largest pair's reach, and a smallest
     * sphere's new list is looked for as far as the largest could be listed */
    const double skin = 2.0 * f->radius_max * f->skin_taken;
    f->partners = partners_within(sc, 2.0 * f->radius_min + skin, f->lists);
    f->walk_reads = partners_within(sc, f->radius_min + f->radius_max + skin, f->lists);
    f->settles = nbep_sim_settle_speeds(sc, &f->settle_lo, &f->settle_hi, &f->settle_steps);
    f->memory_bytes = (double)nbep_sim_memory_estimate(sc, f->threads);
    f->frames = nbep_output_frames(sc);
    /* what the run writes: its file and, beside it, the XDMF sidecar */
    f->sidecar_bytes = nbep_output_sidecar_bytes(sc, sc->output_file);
    f->output_bytes =
        nbep_output_bytes(sc, nbep_sim_keeps_events(sc), nbep_sim_keeps_contacts(sc)) +
        f->sidecar_bytes;
}

/* Whether x prints as "1" under %.0f: one partner, not "1 partners". */
static bool prints_as_one(double x)
{
    char text[32];
    snprintf(text, sizeof text, "%.0f", x);
    return strcmp(text, "1") == 0;
}

void nbep_check_print(FILE *out, const nbep_scene *sc, const nbep_check_facts *f)
{
    const int threads = f->threads;
    fprintf(out, "deck:            %s\n", sc->deck_path);
    if (strcmp(sc->algorithm, "predictive") == 0) /* run.neighbors and run.order act there */
        fprintf(out, "algorithm:       predictive (neighbors %s, order %s), %d thread%s\n",
                nbep_scene_neighbors_name(sc), nbep_scene_order_name(sc), threads,
                threads == 1 ? "" : "s");
    else { /* a neighbour mode the deck asks of naive or seminaive, said left aside (a new
            * user's review: run.neighbors = "cells" under seminaive passed without a word) */
        char aside[96] = "";
        if (nbep_scene_neighbors_aside(sc))
            snprintf(aside, sizeof aside,
                     " (run.neighbors = \"%s\" is the predictive algorithm's: left aside)",
                     nbep_scene_neighbors_name(sc));
        fprintf(out, "algorithm:       %s, %d thread%s%s\n", sc->algorithm, threads,
                threads == 1 ? "" : "s", aside);
    }
    fprintf(out, "threads:         %s\n", f->threads_use);
    fprintf(out, "steps:           %llu of dt = %g (t = 0 .. %g), seed %llu\n",
            (unsigned long long)sc->steps, sc->dt, (double)sc->steps * sc->dt,
            (unsigned long long)sc->seed);
    fprintf(out, "physics:         restitution %g, gravity [%g, %g, %g]", sc->restitution,
            sc->gravity.x, sc->gravity.y, sc->gravity.z);
    /* the TC model and the carry rule act on the predictive algorithm's dissipative scenes;
     * naive and seminaive apply SPEC's law alone (a new user read "tc 0.5" for naive as taken) */
    if (sc->restitution < 1.0 && strcmp(sc->algorithm, "predictive") == 0)
        fprintf(out, ", tc %g, carry_drop %g", sc->tc, sc->carry_drop);
    else if (sc->restitution < 1.0)
        fprintf(out, " (physics.tc and carry_drop: predictive only, unused by %s)",
                sc->algorithm);
    if (sc->zero_momentum)
        fprintf(out, ", total momentum zeroed");
    fprintf(out, "\n");
    /* a sphere stopped with no collision surprised a review's user (one sliding on a floor
     * at 1.5 mm/s, e = 0.5, held from step 10): said before the run */
    if (f->settles) {
        char range[48];
        if (f->settle_lo == f->settle_hi)
            snprintf(range, sizeof range, "%.3g", f->settle_hi);
        else
            snprintf(range, sizeof range, "%.3g to %.3g", f->settle_lo, f->settle_hi);
        fprintf(out, "settling:        a sphere on what carries it that stays at or below a speed "
                "of %s for %u whole steps is held still, its speed taken (e < 1 under an "
                "acceleration: README, Held spheres)\n", range, f->settle_steps);
    }
    if (sc->has_box)
        fprintf(out, "box:             [%g, %g, %g] .. [%g, %g, %g]\n", sc->box_min.x,
                sc->box_min.y, sc->box_min.z, sc->box_max.x, sc->box_max.y, sc->box_max.z);
    else
        fprintf(out, "box:             none\n");
    fprintf(out, "spheres:         %zu\n", sc->state.n);
    const int walls = 2 * (!sc->periodic[0] + !sc->periodic[1] + !sc->periodic[2]);
    if (sc->has_box)
        fprintf(out, "planes:          %zu (%d from the box)\n", sc->state.n_planes, walls);
    else
        fprintf(out, "planes:          %zu\n", sc->state.n_planes);
    if (sc->periodic[0] || sc->periodic[1] || sc->periodic[2])
        fprintf(out, "periodic:        %s%s%s\n", sc->periodic[0] ? "x" : "",
                sc->periodic[1] ? "y" : "", sc->periodic[2] ? "z" : "");
    fprintf(out, "pairs:           %llu need a quadratic (equal accelerations), %llu the quartic\n",
            (unsigned long long)f->pairs_quadratic, (unsigned long long)f->pairs_quartic);
    /* the paper's all-pairs mode predicts each sphere against every other: a new user ran a
     * 150-sphere pile 20 to 50 times slower so, with no word of the cells mode (2026-12-01).
     * (A periodic box may be too small for cells: no hint there.) */
    if (nbep_scene_all_pairs(sc) && sc->state.n >= 100 && !nbep_scene_any_periodic(sc))
        fprintf(out,
                "hint:            run.neighbors = \"cells\" predicts each sphere against its "
                "neighbours only, the fast mode for crowded scenes (\"all\" is the paper's)\n");
    if (isnan(f->packing))
        fprintf(out, "packing:         n/a (no box)\n");
    else
        fprintf(out, "packing:         %.4g of the box volume\n", f->packing);
    if (f->lists) {
        if (f->skin_taken < f->skin_asked)
            fprintf(out,
                    "lists:           skin %.3g of the largest diameter (%.3g by the packing, "
                    "cut down so that three cells fit across the periodic box)\n",
                    f->skin_taken, f->skin_asked);
        else if (nbep_scene_list_sparse(sc, &sc->state)) /* accelerating or not */
            fprintf(out,
                    "lists:           skin %.3g of the largest diameter (sparse and elastic, by "
                    "the packing: %g at packing %g or below, the denser scenes' rules from "
                    "%g)\n",
                    f->skin_taken, NBEP_NBLIST_SKIN_SPARSE, NBEP_NBLIST_PHI_SPARSE,
                    NBEP_NBLIST_PHI_SPARSE_END);
        else /* why this skin (nbep_nblist_skin_for): until 2026-11-30 the line gave the
              * rule of free flight alone, "(when nothing accelerates, ...)", also for a pile,
              * whose skin it does not set */
            fprintf(out,
                    "lists:           skin %.3g of the largest diameter (%s: %g at packing %g "
                    "or below, %g from %g)\n",
                    f->skin_taken,
                    !nbep_state_free_flight(&sc->state)
                        ? "something accelerates; only free flight goes by the packing"
                    : isnan(f->packing) ? "no box to take the packing from; in a box"
                                        : "by the packing",
                    NBEP_NBLIST_SKIN_DILUTE, NBEP_NBLIST_PHI_DILUTE, NBEP_NBLIST_SKIN_DENSE,
                    NBEP_NBLIST_PHI_DENSE);
    }
    /* a mixture twice as wide as its smallest spheres or wider: its cells, sized by the
     * largest pair, make a small sphere's new list read (ratio)^3 the spheres it keeps (a
     * new user's colloids: 3000 of radius 0.25 and 2 of radius 2 ran 3.4 times the small ones'
     * alone, 50 times until each pair's list had its own reach) */
    if (f->lists && f->radius_min > 0.0 && f->radius_max >= 2.0 * f->radius_min &&
        isfinite(f->partners))
        fprintf(out,
                "mixture:         radii %g to %g: a list reaches its pair's contact and the "
                "skin, about %.0f partner%s for the smallest spheres, but the cells are sized "
                "by the largest pair: each new list of a smallest sphere reads about %.0f "
                "spheres or more; an event's cost grows with them (README, Algorithms: What "
                "it costs)\n",
                f->radius_min, f->radius_max, f->partners,
                prints_as_one(f->partners) ? "" : "s", f->walk_reads);
    char size[NBEP_BYTES_TEXT_MAX];
    fprintf(out, "memory:          about %s\n", nbep_format_bytes(f->memory_bytes, size));
    char every[48] = "every step";
    if (sc->output_every > 1)
        snprintf(every, sizeof every, "every %llu steps", (unsigned long long)sc->output_every);
    /* a study's deck: the file is what `nbep run` of it writes; a sweep writes each run into
     * its folder, said on the sweep lines after (a new user looked for this file after a
     * sweep) */
    const bool study = sc->sweep_n_axes > 0 || sc->sweep_replicas > 1;
    /* and where nbep run of it could not make that file (its folder missing, say), why: a
     * study's deck passes, as nbep sweep makes its folder, but nbep run of it would fail */
    const char *fault = study ? nbep_run_output_fault(sc->output_file) : NULL;
    /* no sidecar beside a file that cannot be made (`-o results/` named `results/.xmf`) */
    char *xmf = f->sidecar_bytes > 0.0 && !fault ? nbep_xdmf_path(sc->output_file) : NULL;
    char whose[256] = "";
    if (study)
        snprintf(whose, sizeof whose, " (nbep run's%s%s; nbep sweep's runs: below)",
                 fault ? ", which it cannot create: " : "", fault ? fault : "");
    fprintf(out, "output:          %s%s%s: %llu frame%s (%s), about %s%s\n", sc->output_file,
            xmf ? " and " : "", xmf ? xmf : "", (unsigned long long)f->frames,
            f->frames == 1 ? "" : "s", every, nbep_format_bytes(f->output_bytes, size), whose);
    free(xmf);
}

/* ---- the JSON report ------------------------------------------------------------------------ */

/* Each returns a new reference, or NULL when out of memory. */
static json_t *vec3_array(nbep_vec3 v)
{
    return json_pack("[fff]", v.x, v.y, v.z);
}

/* A figure that may be NaN (no box): JSON has no NaN, so null. */
static json_t *real_or_null(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

/* A size in bytes (an estimate, held as a double) as a whole number: what a job script passes
 * on (`--mem`), and jq and Python read it as an integer. */
static json_t *bytes(double v)
{
    return isfinite(v) && v >= 0.0 && v < 9e18 ? json_integer((json_int_t)llround(v))
                                               : json_null();
}

/* A count as a JSON integer, or as a number where it passes the integers' range (a deck of
 * 2^63 - 1 steps plans 2^63 frames: it read -9223372036854775808 until 2026-12-01). */
static json_t *count(uint64_t v)
{
    return v <= (uint64_t)INT64_MAX ? json_integer((json_int_t)v) : json_real((double)v);
}

static json_t *study_object(const nbep_sweep_check_report *r)
{
    /* output_bytes as the human line's `sweep output`: the runs' files and sidecars and the
     * sweep's tables, which tables_bytes gives apart */
    return json_pack("{s:I, s:I, s:I, s:o, s:I, s:b, s:o, s:o, s:o, s:I, s:I, s:I, s:I}",
                     "runs", (json_int_t)r->n_runs, "combinations", (json_int_t)r->n_combos,
                     "replicas", (json_int_t)r->replicas, "dir", nbep_summary_json_text(r->dir),
                     "runs_checked",
                     (json_int_t)r->checked, "out_of_time", r->out_of_time,
                     "memory_bytes_max", bytes(r->memory_max), "output_bytes",
                     bytes(r->output_bytes + r->tables_bytes), "tables_bytes",
                     bytes(r->tables_bytes), "files_reused", (json_int_t)r->files_complete,
                     "files_resumed", (json_int_t)r->files_partial, "files_replaced",
                     (json_int_t)r->files_other, "files_kept", (json_int_t)r->files_kept);
}

/* jansson's json_pack builds the object in one call (keys in this order with
 * JSON_PRESERVE_ORDER); "o" steals each nested reference, also on failure. */
static json_t *check_object(const nbep_scene *sc, const nbep_check_facts *f,
                            const nbep_sweep_check_report *study)
{
    const bool predictive = strcmp(sc->algorithm, "predictive") == 0;
    char *xmf = f->sidecar_bytes > 0.0 ? nbep_xdmf_path(sc->output_file) : NULL;
    json_t *o = json_pack(
        "{s:s, s:s, s:o, s:s, s:o, s:o, s:i, s:I, s:I, s:I, s:f, s:I, s:f, s:f, s:f, s:b, s:o, "
        "s:o, s:o, s:o, s:o, s:I, s:I, s:o, s:o}",
        "format", CHECK_FORMAT_NAME, "version", NBEP_VERSION, "deck",
        nbep_summary_json_text(sc->deck_path),
        "algorithm", sc->algorithm, "neighbors",
        predictive ? json_string(nbep_scene_neighbors_name(sc)) : json_null(), "order",
        predictive ? json_string(nbep_scene_order_name(sc)) : json_null(), "threads",
        f->threads, "spheres", (json_int_t)sc->state.n, "planes", (json_int_t)sc->state.n_planes,
        "steps", (json_int_t)sc->steps, "dt", sc->dt, "seed", (json_int_t)sc->seed,
        "restitution", sc->restitution, "tc", sc->tc, "carry_drop", sc->carry_drop,
        "zero_momentum", (int)sc->zero_momentum, "gravity",
        vec3_array(sc->gravity), "settling",
        f->settles ? json_pack("{s:f, s:f, s:I}", "speed_min", f->settle_lo, "speed_max",
                               f->settle_hi, "steps", (json_int_t)f->settle_steps)
                : json_null(),
        "box",
        sc->has_box ? json_pack("{s:o, s:o, s:[bbb]}", "min", vec3_array(sc->box_min), "max",
                                vec3_array(sc->box_max), "periodic", sc->periodic[0],
                                sc->periodic[1], sc->periodic[2])
                    : json_null(),
        "packing_fraction", real_or_null(f->packing), "skin",
        f->lists ? json_real(f->skin_taken) : json_null(), "pairs_quadratic",
        (json_int_t)f->pairs_quadratic, "pairs_quartic", (json_int_t)f->pairs_quartic,
        "memory_bytes", bytes(f->memory_bytes), "output",
        json_pack("{s:o, s:o, s:o, s:I, s:o}", "file", nbep_summary_json_text(sc->output_file),
                  "sidecar", xmf ? nbep_summary_json_text(xmf) : json_null(), "frames",
                  count(f->frames),
                  "every", (json_int_t)sc->output_every, "bytes", bytes(f->output_bytes)));
    free(xmf);
    if (o && json_object_set_new(o, "study", study ? study_object(study) : json_null()) != 0) {
        json_decref(o);
        return NULL;
    }
    return o;
}

char *nbep_check_to_json(const nbep_scene *sc, const nbep_check_facts *f,
                         const nbep_sweep_check_report *study)
{
    json_t *o = check_object(sc, f, study);
    char *line = o ? nbep_summary_dump_line(o) : NULL;
    json_decref(o);
    return line;
}
