/* What ends the scheduled loop's windows on slabs (NBEP_SCHEDULED=1 with NBEP_SLABS): bin/nbep
 * itself (src/main.c), with its own copy of the loop (src/evloop_warp.c) whose hooks count the
 * windows opened, and which at the run's end (the loop's, made once a run) prints to stderr
 * one line: the windows, the meetings (a list expiry near a face held for a window's end and done
 * there), how many of those moved their sphere to another slab, the expiries that waited for
 * room in their slab's arena of the lists' pool, and the scheduler's own tallies summed over
 * the slabs (events handled, messages acted on, events and messages undone, rollbacks).
 * docs/optimistic-design.md, *What ends the windows, counted*, reads these: a meeting whose
 * expiry stays in its slab is one the next step would do without one.
 *
 *   make build/bench/bench_windows
 *   NBEP_SCHEDULED=1 NBEP_SLABS=2 build/bench/bench_windows run DECK --resume MELT.h5 -t 2 ...
 *
 * Counting costs an increment a window; the run's results are bin/nbep's. Not for production. */
#include <stdint.h>
#include <stdio.h>

struct evl_sched;
static void windows_open(void);
static void windows_report(const struct evl_sched *x);
#define NBEP_SCHED_OPEN_HOOK(x) windows_open()
#define NBEP_SCHED_DESTROY_HOOK(x) windows_report(x)
#include "../../src/evloop_warp.c"
#include "../../src/main.c"

static uint64_t opened; /* windows opened since the last report (the lead alone opens them) */

static void windows_open(void)
{
    opened++;
}

static void windows_report(const struct evl_sched *x)
{
    nbep_warp_tally t = {0};
    uint64_t cramps = 0;
    for (int k = 0; k < x->slabs; k++) {
        nbep_warp_tally_add(&t, nbep_warp_tally_of(x->warp, k));
        cramps += x->side[k].cramps;
    }
    fprintf(stderr,
            "bench_windows: %d slabs: %llu windows, %llu meetings, %llu of them moving their "
            "sphere to another slab, %llu expiries waiting for room; %llu events handled, "
            "%llu messages acted on (%llu of them late, without a rollback), %llu undone, "
            "%llu rollbacks\n",
            x->slabs, (unsigned long long)opened, (unsigned long long)x->meetings,
            (unsigned long long)x->moves, (unsigned long long)cramps,
            (unsigned long long)t.handled, (unsigned long long)t.applied, (unsigned long long)t.late,
            (unsigned long long)t.undone, (unsigned long long)t.rollbacks);
    opened = 0;
}
