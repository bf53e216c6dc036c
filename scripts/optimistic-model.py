#!/usr/bin/env python3
"""What an optimistic parallel event loop could gain on a dense fluid (README, *Why the team
stops near two times one thread*): a model driven by a real run's events, not nbep.

The scheme modelled is the one issue 8 still needs: the box cut into P slabs across x, one
thread each; every slab handles its own events (those whose sphere's list centre lies in it)
in time order, from its own calendar, without waiting for the others; the threads meet at a
barrier every W of simulated time (a window), where what crossed a slab's faces is settled.
An event that read what an event of another slab writes earlier in simulated time, but later
in wall time, read too soon: its slab rolls back to it and handles it and everything after it
in the window again (an optimistic scheme, as parallel discrete-event simulation's Time Warp,
keeping old versions of what it writes). The results stay those of one thread, bit for bit,
since every event finally reads what it reads in one thread's order.

Input: the trace of `build/bench/bench_parallelism` (NBEP_PAR_TRACE=FILE): each event's
time, its list centre's place across x (0 to 1), how far across x its footprint reaches, its
kind and the events whose writes it reads or overwrites. With `--expiries wait` a list expiry
whose footprint reaches into another slab is not handled ahead: it waits until every slab it
reaches has handled its events before it (the first step of docs/optimistic-design.md, which
keeps versions of motion only). With `--expiries meet` such an expiry ends the window, as the
scheduled loop's slabs do (`NBEP_SCHEDULED=1 NBEP_SLABS`): every slab ends its events before
it, the barrier, the expiry alone on one thread, and the next window; with `--meet-every K`
only every K-th such expiry does, the others going ahead (docs/optimistic-design.md, *What ends
the windows*: 94 % of them stay in their slab and could go ahead as messages, K = 16).

Costs, in units of one event handled: each event 1; each event undone `--undo` (default
0.3); each window's barrier `--barrier` (default 0.2). The events are replayed in the trace's
order (model(): each event's kept handling starts when its slab has ended the one before
and, where it depends on another slab's event of the same window that ends later, after
that one, plus the undo of what its slab handled meanwhile); so rollbacks that follow from
rollbacks are in. A window lasts as long as its slowest slab, plus the barrier; the speed-up
printed is events / (sum over windows of the window's length). Left out, so that the
figures are an upper bound: the bookkeeping an optimistic event does beyond one thread's
(versions, messages), and cache effects.

    build/bench/bench_parallelism run DECK --resume MELT.h5 -t 1 -n N  (NBEP_PAR_TRACE=FILE)
    scripts/optimistic-model.py FILE [--slabs 2,4,8,16] [--windows ...] [--undo U] [--barrier B]
                                     [--expiries ahead|wait|meet] [--meet-every K]
"""
import argparse
import struct
import sys


EXPIRY = 1  # an event's kind in the trace: 1 a list expiry, 2 a reaction, 0 a stale slot


def read_trace(path):
    """Each event's time, place across x, footprint's reach (down, up), kind and dependences
    (event numbers), as lists."""
    times, places, reach, kinds, deps = [], [], [], [], []
    with open(path, "rb") as f:
        data = f.read()
    off, head = 0, struct.Struct("<ddddII")
    while off < len(data):
        t, x, lo, hi, kind, n = head.unpack_from(data, off)
        off += head.size
        times.append(t)
        places.append(x)
        reach.append((lo, hi))
        kinds.append(kind)
        deps.append(struct.unpack_from(f"<{n}I", data, off) if n else ())
        off += 4 * n
    return times, places, reach, kinds, deps


def slab_of(x, slabs):
    """The slab of place x (0 to 1; a place past either end wraps round, as a periodic x
    does, and a footprint's reach may)."""
    return int((x % 1.0) * slabs) % slabs


def reached(places, reach, e, slabs):
    """The slabs event e's footprint reaches, first to last (round a periodic x), its own
    among them (its reach runs from lo <= 0 to hi >= 0)."""
    lo, hi = reach[e]
    return slab_of(places[e] + lo, slabs), slab_of(places[e] + hi, slabs)


def reaches_across(places, reach, e, slabs):
    """Whether event e's footprint reaches a slab other than its own."""
    first, last = reached(places, reach, e, slabs)
    return first != last


def model(times, places, reach, kinds, deps, slabs, window, undo, barrier, wait,
          meet=False, meet_every=1):
    """(speed-up over one thread, events handled again / events, windows) for one setting.

    Each event's last (kept) handling, in the trace's order (a time order, so every event comes
    after those it depends on): its slab has gone ahead to it at `ahead` (the end of its
    previous event); a dependence on another slab's event of the same window that ends later,
    at `late`, means the slab handled it too soon: it rolls back when that news comes (undoing
    what it had handled since, about late - ahead events, at `undo` each) and handles it
    again from there. Rollbacks so follow from rollbacks (cascades are in). With `wait`, an
    expiry whose footprint reaches another slab starts only once each slab it reaches has
    ended its events before it (their clocks now, in the trace's time order). With `meet`,
    every `meet_every`-th such expiry ends the window instead: all slabs end what came before
    it, the barrier, then it alone, and a window opens after it (it depends on nothing of the
    new window, and nothing there on it as of another slab's late news)."""
    n = len(times)
    t0 = times[0]
    slab = [slab_of(x, slabs) for x in places]
    win = [int((t - t0) / window) for t in times]
    end = [0.0] * n                      # each event's end, from its window's start
    clock = [0.0] * slabs                # each slab's end of its last event in the window
    length, redone, w_cur, windows = 0.0, 0.0, win[0], 1
    wid = [0] * n                        # each event's window, counting the meetings' too
    cur, held = 0, 0
    for e in range(n):
        if win[e] != w_cur:              # the barrier: every slab starts the next window at 0
            length += max(clock) + barrier
            clock = [0.0] * slabs
            w_cur = win[e]
            windows += 1
            cur += 1
        if meet and kinds[e] == EXPIRY and reaches_across(places, reach, e, slabs):
            held += 1
            if (held - 1) % meet_every == 0:  # a meeting: it alone between two windows
                length += max(clock) + barrier + 1.0
                clock = [0.0] * slabs
                windows += 1
                cur += 1
                wid[e] = -1
                end[e] = 0.0
                continue
        wid[e] = cur
        b = slab[e]
        ahead = clock[b]
        late = ahead
        for s in deps[e]:
            if wid[s] == cur and slab[s] != b and end[s] > late:
                late = end[s]
        if late > ahead:                 # read too soon: undo what was handled since, again
            redone += late - ahead
            start = late + undo * (late - ahead)
        else:
            start = ahead
        if wait and kinds[e] == EXPIRY:  # held until the slabs it reaches are past it
            first, last = reached(places, reach, e, slabs)
            for j in range((last - first) % slabs + 1):
                start = max(start, clock[(first + j) % slabs])
        end[e] = start + 1.0
        clock[b] = end[e]
    length += max(clock) + barrier
    return n / length, redone / n, windows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("trace")
    ap.add_argument("--slabs", default="2,4,8,16")
    ap.add_argument("--windows", default="0.0003,0.001,0.003,0.01,0.03,0.1",
                    help="window widths W in units of simulated time")
    ap.add_argument("--undo", type=float, default=0.3)
    ap.add_argument("--barrier", type=float, default=0.2)
    ap.add_argument("--expiries", choices=("ahead", "wait", "meet"), default="ahead")
    ap.add_argument("--meet-every", type=int, default=1,
                    help="with --expiries meet: every K-th expiry reaching across meets")
    a = ap.parse_args()
    times, places, reach, kinds, deps = read_trace(a.trace)
    if not times:
        sys.exit("optimistic-model: the trace holds no events")
    span = times[-1] - times[0]
    expiries = sum(k == EXPIRY for k in kinds)
    print(f"{len(times)} events over {span:.4g} of simulated time ({expiries} list expiries, "
          f"{a.expiries}); undo {a.undo}, barrier {a.barrier} (units of one event)")
    print("| slabs | window W | events a window and slab | handled again | speed-up bound |")
    print("| --- | --- | --- | --- | --- |")
    for p in (int(s) for s in a.slabs.split(",")):
        for w in (float(s) for s in a.windows.split(",")):
            sp, again, nw = model(times, places, reach, kinds, deps, p, w, a.undo, a.barrier,
                                  a.expiries == "wait", a.expiries == "meet", a.meet_every)
            print(f"| {p} | {w:g} | {len(times) / nw / p:.0f} | {100 * again:.1f} % | "
                  f"{sp:.2f} |")


if __name__ == "__main__":
    main()
