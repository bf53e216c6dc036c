/* What ends the scheduled loop's windows on slabs (NBEP_SCHEDULED=1 with NBEP_SLABS): bin/nbep
 * itself (src/main.c), with its own copy of the loop (src/evloop_warp.c) whose hooks count the
 * windows opened, and which at the run's end (the loop's, made once a run) prints to stderr
 * one line: the windows, the meetings (a list expiry near a face held for a window's end and done
 * there), how many of those moved their sphere to another slab, the expiries that waited for
 * room in their slab's arena of the lists' pool, and the scheduler's own tallies summed over
 * the slabs (events handled, messages acted on and of them those acted on late without a
 * rollback, events and messages undone, rollbacks), and what the meetings' cuts undid of those
 * (the rest the stragglers' rollbacks undid).
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
static void windows_cut(const struct evl_sched *x, int after);
#define NBEP_SCHED_OPEN_HOOK(x) windows_open()
#define NBEP_SCHED_CUT_HOOK(x, after) windows_cut(x, after)
#define NBEP_SCHED_DESTROY_HOOK(x) windows_report(x)
#include "../../src/evloop_warp.c"
#include "../../src/main.c"

static uint64_t opened; /* windows opened since the last report (the lead alone opens them) */
/* what the meetings' cuts undid (events and messages) and how many cuts undid any, since the
 * last report; the undone count as it was before the cut under way */
static uint64_t cut_undone, cuts, undone_before;

static void windows_open(void)
{
    opened++;
}

/* (the lead's, at the meeting: every slab idle) */
static uint64_t undone_now(const struct evl_sched *x)
{
    nbep_warp_tally t = {0};
    for (int k = 0; k < x->slabs; k++)
        nbep_warp_tally_add(&t, nbep_warp_tally_of(x->warp, k));
    return t.undone;
}

static void windows_cut(const struct evl_sched *x, int after)
{
    if (!after) {
        undone_before = undone_now(x);
        return;
    }
    const uint64_t u = undone_now(x) - undone_before;
    cut_undone += u;
    cuts += u > 0;
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
            "%llu rollbacks; the meetings' cuts undid %llu in %llu cuts\n",
            x->slabs, (unsigned long long)opened, (unsigned long long)x->meetings,
            (unsigned long long)x->moves, (unsigned long long)cramps,
            (unsigned long long)t.handled, (unsigned long long)t.applied,
            (unsigned long long)t.late,
            (unsigned long long)t.undone, (unsigned long long)t.rollbacks,
            (unsigned long long)cut_undone, (unsigned long long)cuts);
    opened = cut_undone = cuts = 0;
}
