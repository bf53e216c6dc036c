/* Where the team loop's leader spends its time: bin/nbep itself (src/main.c), with its own
 * copy of the engine (src/evloop.c, src/evloop_team.c) whose phase hook reads the time-stamp
 * counter at each change of the leader's phase (PH_WAIT .. PH_START in src/evloop_team.c:
 * waiting for a place with none left to take, handling places itself, deciding whether the
 * window's first place stands, committing it, filling the window, undoing, starting an empty
 * window). At exit it prints to stderr, per
 * phase, the leader's seconds and their share of its time in the team loop. The leader can
 * commit no faster than its own work allows, so the phases other than waiting and handling
 * bound what any number of helpers can gain (README, Threads on dense scenes).
 *
 *   make build/bench/bench_leader
 *   NBEP_TEAM=always build/bench/bench_leader run DECK --resume MELT.h5 -t 16 ...
 *
 * Only the leader (thread 0) changes phase, so the tallies are its alone. The counter is read
 * about three times an event (about 25 cycles each; the rest of the hook a few more): on a
 * 16-core node the loop took 1.00 to 1.10 times the plain build's (median 1.05, README), so
 * the leader's shares come out a little high. Each change of phase counts an entry, a return to a phase after a nested one
 * (a wait inside deciding whether a place stands) included. Not for production. x86-64 only
 * (the counter); elsewhere it says so and nbep runs untimed. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#if defined(__x86_64__)
#include <x86intrin.h>
#endif

static int leader_phase(int p);
#define NBEP_EVLOOP_PHASE_HOOK(p) leader_phase(p)
#include "../../src/evloop.c"
#include "../../src/evloop_team.c"
#include "../../src/main.c"

static const char *const PHASE_NAME[PH_COUNT] = {"wait", "handle", "stand", "commit",
                                                 "fill", "undo", "start"};

static struct {
    bool started;
    int cur;                    /* PH_COUNT: outside the loop */
    uint64_t last, first_tsc;   /* counter readings: the last change, the first */
    struct timespec first_ns;   /* the clock at the first, to convert the counter */
    uint64_t ticks[PH_COUNT];
    uint64_t entries[PH_COUNT]; /* changes into each phase */
} lp = {.cur = PH_COUNT};

static uint64_t ticks_now(void)
{
#if defined(__x86_64__)
    return __rdtsc();
#else
    return 0;
#endif
}

static void leader_report(void)
{
    if (!lp.started) {
        fprintf(stderr, "bench_leader: the team loop never ran (cells mode, e = 1, no gravity, "
                        "2 threads or more; NBEP_TEAM=always)\n");
        return;
    }
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    const double secs = (double)(now.tv_sec - lp.first_ns.tv_sec) +
                        1e-9 * (double)(now.tv_nsec - lp.first_ns.tv_nsec);
    const uint64_t span = ticks_now() - lp.first_tsc;
    if (span == 0) {
        fprintf(stderr, "bench_leader: no time-stamp counter here (x86-64 only)\n");
        return;
    }
    const double per_tick = secs / (double)span; /* the counter's rate over the whole run */
    uint64_t total = 0;
    for (int k = 0; k < PH_COUNT; k++)
        total += lp.ticks[k];
    fprintf(stderr, "bench_leader: the leader's time in the team loop: %.3f s\n",
            (double)total * per_tick);
    for (int k = 0; k < PH_COUNT; k++)
        fprintf(stderr, "bench_leader: %-7s %8.3f s %6.1f %%  (%llu entries)\n", PHASE_NAME[k],
                (double)lp.ticks[k] * per_tick, 100.0 * (double)lp.ticks[k] / (double)total,
                (unsigned long long)lp.entries[k]);
}

/* The report at exit, whether or not the loop ran (registered before main). */
__attribute__((constructor)) static void leader_register(void)
{
    atexit(leader_report);
}

static int leader_phase(int p)
{
    const uint64_t t = ticks_now();
    if (!lp.started) {
        lp.started = true;
        lp.first_tsc = t;
        clock_gettime(CLOCK_MONOTONIC, &lp.first_ns);
    } else if (lp.cur < PH_COUNT) {
        lp.ticks[lp.cur] += t - lp.last;
    }
    const int was = lp.cur;
    lp.cur = p;
    lp.last = t;
    if (p < PH_COUNT)
        lp.entries[p]++;
    return was;
}
