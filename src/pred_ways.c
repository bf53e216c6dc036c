/* How many threads run a step's events: cells mode's team loop (one thread, a pair, or the
 * whole team) and grid mode's crews, chosen step by step by measuring each way. */
#include "pred_impl.h"

#include <stdlib.h>
#include <string.h>

/* The team loop pays where other cores are close (it passes a few cache lines per event
 * between them), and loses where they are not or are busy with other work: the same fluid on
 * this project's 2-core virtual machine ran 1.5 times as fast as one thread in some runs and
 * 0.8 times in others. Results are the same bit for bit whatever the way, so the run measures
 * each (one thread, a pair, and the whole team where it has more than two threads) and takes
 * the fastest. In cells mode a probe of another way runs only the first part of a step (its
 * events before T0 + PRED_WAYS_PART dt; the rest of the step runs the way taken): every way
 * is measured once, the largest first (the first step the whole team, the next two the
 * others' parts), then every TEAM_PROBE-th step has a probe (with three ways, the other two in
 * turn). Before 584504d (2026-11-29) a probe was a whole step: on a 16-core node the run's
 * own choice ran the large fluid (N = 256000, phi = 0.30, 10 steps) 1.63 times as fast as one
 * thread, the whole team at every step 2.11, as its first three steps ran the team, the pair
 * and one thread (one alone costs two team steps). Grid mode's probes are still whole steps
 * (nbep__pred_ways_choose_crew). The way taken keeps its seconds per event as a running mean
 * of its steps (half the last step, half what it was); a probe's figure replaces the probed
 * way's, which would otherwise carry a probe from many steps before (the first, at the second
 * step, runs while a lattice start melts, on events a quarter cheaper than later: its figure
 * kept the run probing every TEAM_PROBE-th step, 5 probes in 80 steps of a fluid at N =
 * 256000, phi = 0.30). A probe costs what the slower way loses in its part: with the team 1.6
 * times as fast, an eighth of every 8th step run alone adds about 1 % to the run's time (a
 * whole step added 7 %). Where the fastest way is at least TEAM_CLEAR times as fast as every
 * other, they are probed every TEAM_PROBE_FAR-th step only; the way taken is measured at every
 * step, so a change that makes it slower is seen at once. NBEP_TEAM in the environment, read
 * as the run is made, fixes the choice (tests, benchmarks): "always" the whole team, "never"
 * (or 1) one thread, a count k >= 2 a team of k threads (at most the run's and
 * NBEP_EVLOOP_TEAM_MAX), "cycle" the ways in turn, step by step, the whole team first, and in
 * cells mode each step's first part the way after its own (every change of way, for the
 * tests). */
#define TEAM_PROBE 8
#define TEAM_PROBE_FAR 64
#define TEAM_CLEAR 1.25

int nbep__pred_ways_forced(const char *v)
{
    if (!v)
        return PRED_WAYS_FREE;
    if (strcmp(v, "always") == 0)
        return PRED_WAYS_ALWAYS;
    if (strcmp(v, "never") == 0)
        return PRED_WAYS_NEVER;
    if (strcmp(v, "cycle") == 0)
        return PRED_WAYS_CYCLE;
    char *end;
    const long k = strtol(v, &end, 10);
    if (end == v || *end != '\0' || k < 1)
        return PRED_WAYS_FREE;
    /* a team of one is one thread; a team is at most NBEP_EVLOOP_TEAM_MAX */
    return k == 1 ? PRED_WAYS_NEVER : k < NBEP_EVLOOP_TEAM_MAX ? (int)k : NBEP_EVLOOP_TEAM_MAX;
}

_Static_assert(PRED_WAYS_MAX == 3, "the ways: one thread, a pair and the whole team");

void nbep__pred_ways_init(pred_ways *w, int size, int force)
{
    const int n = size < 1 ? 0 : size < PRED_WAYS_MAX ? size : PRED_WAYS_MAX;
    *w = (pred_ways){.n = n, .crew = {1, 2, size}, .probe = {-1, -1}, .force = force,
                     .last = -1};
    /* the first step: the whole team */
    w->way[0] = w->way[1] = force == PRED_WAYS_NEVER || n < 1 ? 0 : n - 1;
}

/* The fastest way measured (ties: the one with more threads); the largest when none is. */
static int best_way(const pred_ways *w)
{
    int best = w->n - 1;
    for (int k = best - 1; k >= 0; k--)
        if (w->cost[k] > 0.0 && (w->cost[k] < w->cost[best] || w->cost[best] == 0.0))
            best = k;
    return best;
}

void nbep__pred_ways_note(pred_ways *w, int way, bool probe, uint64_t events, double seconds)
{
    if (events > 0) {
        const double per = seconds / (double)events;
        double *m = &w->cost[way];
        *m = *m > 0.0 && !probe ? 0.5 * (*m + per) : per;
    }
}

/* The ways of step + 1 (after step `step` ran `way`): its way and, where `parts` (cells mode),
 * the way of its first part (probe; -1 none). Without parts a probe is a whole step. */
static void decide(pred_ways *w, uint64_t step, int way, bool parts)
{
    int *next = &w->way[(step + 1) & 1], *probe = &w->probe[(step + 1) & 1];
    *probe = -1;
    if (w->force == PRED_WAYS_CYCLE) { /* down, in turn; the first part the way after */
        *next = way > 0 ? way - 1 : w->n - 1;
        if (parts && w->n > 1)
            *probe = *next > 0 ? *next - 1 : w->n - 1;
        return;
    }
    if (w->force) {
        *next = w->force > 0 ? w->n - 1 : 0;
        return;
    }
    const int best = best_way(w);
    for (int k = w->n - 1; k >= 0; k--)
        if (w->cost[k] == 0.0) { /* each way measured once, the largest first */
            *next = k; /* (none measured yet: the largest, throughout) */
            if (parts && k != best) { /* on a first part, the rest the fastest measured */
                *next = best;
                *probe = k;
            }
            return;
        }
    bool clear = true;
    for (int k = 0; k < w->n; k++)
        clear &= k == best || w->cost[k] >= TEAM_CLEAR * w->cost[best];
    const uint64_t period = clear ? TEAM_PROBE_FAR : TEAM_PROBE;
    *next = best;
    if ((step + 1) % period != 0)
        return;
    /* the probes take the other ways in turn */
    const int k = (int)((step + 1) / period % (uint64_t)(w->n - 1));
    const int other = (best + 1 + k) % w->n;
    if (parts)
        *probe = other;
    else
        *next = other;
}

void nbep__pred_ways_choose(pred_ways *w, uint64_t step, int way, uint64_t events,
                            double seconds)
{
    nbep__pred_ways_note(w, way, false, events, seconds);
    decide(w, step, way, true);
}

/* Thread 0, after step `step` of grid mode ran way `way` in `seconds` (from its start to the
 * barrier after the update: a crew smaller than the run's leaves the others waiting, asleep
 * after a while, and they take their share of the update late; timed on its rounds alone, the
 * paper's box on a 16-core node took 1.17 times as long as with every thread): the way of the
 * next step, chosen as nbep__pred_ways_choose does, timed per step. Two differences, both
 * from the same node, where the box of 32768 spheres ran 1.19, 1.40 and 1.61 ms a step on 16,
 * 2 and 1 threads and the run's own choice took 1.4 times as long as 16 threads throughout:
 * - per step, not per event (round): much of a step does not depend on its rounds (the first
 *   round's look at every slot, the update), and the box has 20 to 40 rounds a step;
 * - a step whose way differs from the step before's is not timed, and the next runs the same
 *   way: after a change the sphere states, slots and candidate lists that the other crew
 *   wrote are still in its cores' caches, so a probe timed on its first step pays for the
 *   change, which a way kept for many steps pays once (our reading of why the box's run kept
 *   to the smaller crews). */
void nbep__pred_ways_choose_crew(pred_ways *w, uint64_t step, int way, double seconds)
{
    if (way != w->last && w->force != PRED_WAYS_CYCLE) {
        w->last = way;
        w->way[(step + 1) & 1] = way;
        return;
    }
    w->last = way;
    nbep__pred_ways_note(w, way, way != best_way(w), 1, seconds); /* a slower way's: a probe */
    decide(w, step, way, false);
}
