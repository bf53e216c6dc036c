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
 * the fastest: every TEAM_PROBE-th step runs another way (a probe; with three ways, the other
 * two in turn). The way taken keeps its seconds per event as a running mean of its steps (half
 * the last step, half what it was); a probe's figure replaces the probed way's, which would
 * otherwise carry a probe from many steps before (the first, at the second step, runs while a
 * lattice start melts, on events a quarter cheaper than later: its figure kept the run probing
 * every TEAM_PROBE-th step, 5 probes in 80 steps of a fluid at N = 256000, phi = 0.30, each
 * costing 0.75 of a team step). A probe costs what the slower way loses: with the team 1.6
 * times as fast, one step in 8 run alone adds 7 % to the run's time. Where the fastest way is
 * at least TEAM_CLEAR times as fast as every other, they are probed every TEAM_PROBE_FAR-th
 * step only; the way taken is measured at every step, so a change that makes it slower is
 * seen at once. NBEP_TEAM in the environment, read as the run is made, fixes the choice
 * (tests, benchmarks): "always" the whole team, "never" (or 1) one thread, a count k >= 2 a
 * team of k threads (at most the run's and NBEP_EVLOOP_TEAM_MAX), "cycle" the ways in turn,
 * step by step, the whole team first (every change of way, for the tests). */
#define TEAM_PROBE 8
#define TEAM_PROBE_FAR 64
#define TEAM_CLEAR 1.25

#define TEAM_CYCLE (-2)

/* NBEP_TEAM: 1 always, -1 never, k >= 2 always with a team of k, TEAM_CYCLE, 0 (unset or
 * anything else) the fastest way. */
int nbep__pred_team_forced(void)
{
    const char *v = getenv("NBEP_TEAM");
    if (!v)
        return 0;
    if (strcmp(v, "always") == 0)
        return 1;
    if (strcmp(v, "never") == 0)
        return -1;
    if (strcmp(v, "cycle") == 0)
        return TEAM_CYCLE;
    char *end;
    const long k = strtol(v, &end, 10);
    if (end == v || *end != '\0' || k < 1)
        return 0;
    /* a team of one is one thread; a team is at most NBEP_EVLOOP_TEAM_MAX */
    return k == 1 ? -1 : k < NBEP_EVLOOP_TEAM_MAX ? (int)k : NBEP_EVLOOP_TEAM_MAX;
}

/* The fastest way measured (ties: the one with more threads). */
static int team_best(const pred_ctx *c)
{
    int best = c->team_ways - 1;
    for (int w = best - 1; w >= 0; w--)
        if (c->team_cost[w] < c->team_cost[best])
            best = w;
    return best;
}

/* Thread 0, after step `step` ran its events (`events` of them in `seconds`) way `way`: the
 * way of the next step. */
void nbep__pred_team_choose(pred_ctx *c, uint64_t step, int way, uint64_t events, double seconds)
{
    if (events > 0) {
        const double per = seconds / (double)events;
        const bool probed = way != team_best(c); /* a slower way */
        double *m = &c->team_cost[way];
        *m = *m > 0.0 && !probed ? 0.5 * (*m + per) : per;
    }
    int *next = &c->team_way[(step + 1) & 1];
    if (c->team_force == TEAM_CYCLE) {
        *next = way > 0 ? way - 1 : c->team_ways - 1;
        return;
    }
    if (c->team_force) {
        *next = c->team_force > 0 ? c->team_ways - 1 : 0;
        return;
    }
    for (int w = c->team_ways - 1; w >= 0; w--)
        if (c->team_cost[w] == 0.0) { /* each way measured once, the largest first */
            *next = w;
            return;
        }
    const int best = team_best(c);
    bool clear = true;
    for (int w = 0; w < c->team_ways; w++)
        clear &= w == best || c->team_cost[w] >= TEAM_CLEAR * c->team_cost[best];
    const uint64_t probe = clear ? TEAM_PROBE_FAR : TEAM_PROBE;
    if ((step + 1) % probe != 0) {
        *next = best;
        return;
    }
    /* the probes take the other ways in turn */
    const int k = (int)((step + 1) / probe % (uint64_t)(c->team_ways - 1));
    *next = (best + 1 + k) % c->team_ways;
}

/* Thread 0, after step `step` of grid mode ran way `way` in `seconds` (from its start to the
 * barrier after the update: a crew smaller than the run's leaves the others waiting, asleep
 * after a while, and they take their share of the update late; timed on its rounds alone, the
 * paper's box on a 16-core node took 1.17 times as long as with every thread): the way of the
 * next step, team_choose's, timed per step. Two differences, both from the same node, where
 * the box of 32768 spheres ran 1.19, 1.40 and 1.61 ms a step on 16, 2 and 1 threads and the
 * run's own choice took 1.4 times as long as 16 threads throughout:
 * - per step, not per event (round): much of a step does not depend on its rounds (the first
 *   round's look at every slot, the update), and the box has 20 to 40 rounds a step;
 * - a step whose way differs from the step before's is not timed, and the next runs the same
 *   way: after a change the sphere states, slots and candidate lists that the other crew
 *   wrote are still in its cores' caches, so a probe timed on its first step pays for the
 *   change, which a way kept for many steps pays once (our reading of why the box's run kept
 *   to the smaller crews). */
void nbep__pred_crew_choose(pred_ctx *c, uint64_t step, int way, double seconds)
{
    if (way != c->crew_last && c->team_force != TEAM_CYCLE) {
        c->crew_last = way;
        c->team_way[(step + 1) & 1] = way;
        return;
    }
    c->crew_last = way;
    nbep__pred_team_choose(c, step, way, 1, seconds);
}
