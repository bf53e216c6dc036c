#!/usr/bin/env python3
"""What a conservative parallel event loop could gain on a dense fluid (README, "Threads on
dense scenes"): a model, not nbep.

The scheme modelled is the exact one that keeps frames bitwise identical for any thread count
without rollback: the periodic box is cut into P slabs, one per thread; each thread takes its
slab's events from its own calendar in time order. An event whose footprint (the spheres and
lists it reads or writes) lies deep inside the slab is *local* and runs at once; any other is
*shared* and runs only when every other thread's next event is later (else a chain of events
in another slab could reach it first: hard spheres pass influence on at no speed limit, so
there is no time lookahead). Two threads' local events cannot touch; shared events run in
global time order. That reproduces the serial order of every pair of events that touch.

How deep is "deep": an event of sphere i reads i's list (centres within the cutoff c, the
contact distance plus the skin) and, for a collision, the partner's (within c plus the stray s
of i's centre); a shared event of the next slab can so reach D = 2c + s into this one, and a
local event spans c + s from its spheres, so a local event needs its spheres deeper than
Z = 3c + 2s from both faces of its slab. The fraction of shared events is then about
2 Z P / L for a box of side L.

The model: each thread gets a Poisson stream of events in simulated time (rate 1), a fraction
f of them shared, each costing one unit of wall time; a shared event waits while another
thread's next event is earlier. It prints the speed-up over one thread, an upper bound (no
cost for synchronisation, perfect balance), for the slab fractions of given scenes.

    scripts/conservative-model.py [--events N] [--seed S]
"""
import argparse
import math
import random


def speedup(threads, shared, events, seed):
    """Wall-time speed-up of `threads` threads over one, for a shared fraction `shared`."""
    rnd = random.Random(seed)
    seqs = []
    for _ in range(threads):
        t, seq = 0.0, []
        for _ in range(events // threads):
            t += rnd.expovariate(1.0)
            seq.append((t, rnd.random() < shared))
        seq.append((math.inf, False))
        seqs.append(seq)
    n = len(seqs[0]) - 1
    idx = [0] * threads
    busy = [False] * threads
    finish = [0.0] * threads
    now = 0.0

    def clock(q):
        return seqs[q][idx[q]][0]

    while any(idx[p] < n for p in range(threads)):
        started = True
        while started:  # start every idle thread whose next event may run now
            started = False
            for p in range(threads):
                if busy[p] or idx[p] >= n:
                    continue
                t, is_shared = seqs[p][idx[p]]
                if is_shared and not all(clock(q) > t for q in range(threads) if q != p):
                    continue
                busy[p], finish[p], started = True, now + 1.0, True
        q = min((p for p in range(threads) if busy[p]), key=lambda p: finish[p])
        now, busy[q] = finish[q], False
        idx[q] += 1
    return threads * n / now


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=100000)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    cut, stray = 1.4, 0.2  # skin 0.4 diameters: cutoff 1.4, stray 0.2 (diameter 1)
    zone = 3 * cut + 2 * stray
    print(f"zone of shared events: Z = 3c + 2s = {zone:.1f} diameters from each slab face")
    print("| N | phi | threads | shared fraction | speed-up bound |")
    print("| --- | --- | --- | --- | --- |")
    for n, phi in ((32000, 0.30), (256000, 0.30), (256000, 0.50)):
        side = (n * math.pi / (6 * phi)) ** (1 / 3)
        for p in (2, 4, 8):
            f = min(1.0, 2 * zone * p / side)
            print(f"| {n} | {phi:.2f} | {p} | {f:.2f} | "
                  f"{speedup(p, f, a.events, a.seed):.2f} |")


if __name__ == "__main__":
    main()
