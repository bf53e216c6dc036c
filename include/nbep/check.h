/* `nbep check` (README "The deck", "Parameter studies"): what a scene needs, gathered once and
 * shown two ways, as the human report on stdout and as the JSON report that `--summary FILE`
 * writes for job scripts ("format": "nbep-check-1": the memory and output a run will need,
 * read by a script to size its job, without parsing the human lines). */
#ifndef NBEP_CHECK_H
#define NBEP_CHECK_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "nbep/scene.h"
#include "nbep/sweep.h"

/* What a check finds out about one scene (nbep_check_gather), the one source of both reports. */
typedef struct nbep_check_facts {
    int threads;                /* nbep_sim_resolve_threads of the scene's run.threads */
    char threads_use[256];      /* nbep_sim_threads_use's words */
    uint64_t pairs_quadratic;   /* pairs whose contact time is a quadratic's root ... */
    uint64_t pairs_quartic;     /* ... and a quartic's (different accelerations) */
    double packing;             /* of the box volume; NaN without a box */
    bool lists;                 /* the cells engine's neighbour lists are used: */
    double skin_asked;          /* the skin the packing asks for (of the largest diameter) */
    double skin_taken;          /* the skin taken (smaller where a small periodic box cuts it) */
    double radius_min;          /* the smallest and largest radius (0 without spheres) */
    double radius_max;
    double partners;            /* with lists in a box: the mean partners a smallest
                                 * sphere's list holds (its own kind's cutoff's ball times
                                 * the spheres' density), else NaN */
    double walk_reads;          /* ... and the spheres its list's rebuild reads at least:
                                 * those within its cutoff with the largest sphere */
    double memory_bytes;        /* nbep_sim_memory_estimate */
    uint64_t frames;            /* frames the output file will hold */
    double sidecar_bytes;       /* the XDMF sidecar's (0: none is written) */
    double output_bytes;        /* what the run writes: nbep_output_bytes and the sidecar's */
    bool settles;               /* nbep_sim_settle_speeds: the run holds slow spheres still, */
    double settle_lo, settle_hi; /* at or below these speeds (least and largest of the
                                  * spheres') */
    unsigned settle_steps;      /* for this many whole steps */
} nbep_check_facts;

void nbep_check_gather(const nbep_scene *sc, nbep_check_facts *f);

/* The human report, one "key: value" line each (scripts/slurm-scaling.sbatch reads `box:`). */
void nbep_check_print(FILE *out, const nbep_scene *sc, const nbep_check_facts *f);

/* The JSON report, one line ending in a newline (malloc'd; NULL when out of memory): the
 * scene's settings and f's figures, and under "study" (null for a deck without a sweep group)
 * what nbep_sweep_check found of its runs. README "nbep check --summary" lists the keys. */
char *nbep_check_to_json(const nbep_scene *sc, const nbep_check_facts *f,
                         const nbep_sweep_check_report *study);

#endif
