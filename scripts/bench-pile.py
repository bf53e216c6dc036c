#!/usr/bin/python3
"""The pile over its whole run (issue 9): inputs/pile.deck poured and settled, e = 0.5 against
e = 1, on 1 and 2 threads: collisions per step, spheres held and wall time over the run.

    scripts/bench-pile.py [--threads 1,2] [--restitution 0.5,1] [--steps N] [--count N]
                          [--jobs J] [--out DIR] [--plot FILE] [--nbep BIN] [--replot]

Every configuration (restitution x threads) runs the deck once, as set but for the overrides
given (--steps, --count: fewer spheres on a proportionally smaller floor, so the pile is as
deep, as scripts/bench-granular.sh does). Wall time over the run comes from nbep's progress
lines (one every 10 s when stderr is not a terminal), each stamped when it arrives; the
collisions per step and the held spheres (velocity exactly zero) from /stats and /frames. With
--jobs 2 two configurations run at the same time (on a 2-core machine: one core each; the
cells mode's event loop is one thread, so a 2-thread run's second thread mostly sleeps). One
run per configuration (the deck's e = 0.5 run takes 25 to 80 minutes of one core), so the times are one sample
each on whatever load the machine has.

Prints one table row per configuration, checks that the thread counts of one restitution give
the same frames bit for bit (exit 1 if not), keeps the runs in --out (default: a temporary
folder, removed) and draws --plot (default: none): collisions per step, held spheres and wall
time against simulated time, one line per configuration. --replot reads the runs kept in --out
instead of running them (to redraw the table and the figure).

Needs h5py, numpy and (for --plot) matplotlib (Debian: python3-h5py python3-matplotlib)."""
import argparse
import concurrent.futures
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DECK = os.path.join(ROOT, "inputs", "pile.deck")
PROGRESS = re.compile(r"^step (\d+)/(\d+)")


def run(cfg, a, work):
    """Runs one configuration; returns its summary, stamped progress and file name."""
    e, t = cfg
    name = os.path.join(work, f"pile-e{e}-t{t}")
    cmd = [a.nbep, "run", DECK, "-t", str(t), "--set", f"physics.restitution={e}",
           "-o", name + ".h5", "--summary", name + ".json"]
    if a.steps:
        cmd += ["-n", str(a.steps)]
    if a.count:  # the deck's 2000 spheres on a 1 m floor: the floor shrinks with the count
        side = math.sqrt(a.count / 2000.0)
        cmd += ["--set", f"spheres.[0].count={a.count}",
                "--set", f"box.max=[{side!r}, {side!r}, 1.2]"]
    t0 = time.monotonic()
    stamps = [(0, 0.0)]
    with subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True) as p:
        tail = []
        for line in p.stderr:
            m = PROGRESS.match(line)
            if m:
                stamps.append((int(m.group(1)), time.monotonic() - t0))
            else:
                tail.append(line)
        rc = p.wait()
    if rc != 0:
        sys.exit(f"bench-pile: nbep failed ({rc}): {' '.join(cmd)}\n{''.join(tail[-5:])}")
    with open(name + ".json") as fh:
        summary = json.load(fh)
    stamps.append((summary["steps"], time.monotonic() - t0))  # the process, as the stamps
    with open(name + ".wall", "w") as fh:  # step, wall seconds: kept with the runs
        fh.writelines(f"{s} {w:.3f}\n" for s, w in stamps)
    return summary, stamps, name + ".h5"


def kept(cfg, work):
    """A run kept in work by an earlier call: its summary, stamped progress and file name."""
    name = os.path.join(work, f"pile-e{cfg[0]}-t{cfg[1]}")
    if not os.path.exists(name + ".json") or not os.path.exists(name + ".wall"):
        sys.exit(f"bench-pile: --replot: no run {name}.json and .wall (restitution and threads "
                 f"as given when it ran)")
    with open(name + ".json") as fh:
        summary = json.load(fh)
    with open(name + ".wall") as fh:
        stamps = [(int(a), float(b)) for a, b in (line.split() for line in fh)]
    return summary, stamps, name + ".h5"


def held_per_frame(path):
    with h5py.File(path, "r") as f:
        vel = f["/frames/velocity"]
        times = f["/frames/time"][:]
        held = [int((np.abs(vel[k]).sum(axis=1) == 0.0).sum()) for k in range(vel.shape[0])]
        coll = f["/stats/collisions"][:]
    return times, np.array(held), coll


def same_frames(p, q):
    with h5py.File(p, "r") as f, h5py.File(q, "r") as g:
        return all(np.array_equal(f["/frames/" + k][:], g["/frames/" + k][:])
                   for k in ("position", "velocity")) and \
            np.array_equal(f["/stats/collisions"][:], g["/stats/collisions"][:])


def main():
    # the docstring's first sentence (its first line alone stopped at "e = 0.5 against")
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0].replace("\n", " "))
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--restitution", default="0.5,1")
    ap.add_argument("--steps", type=int, default=0, help="default: the deck's")
    ap.add_argument("--count", type=int, default=0, help="default: the deck's 2000")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default="")
    ap.add_argument("--plot", default="")
    ap.add_argument("--nbep", default=os.path.join(ROOT, "bin", "nbep"))
    ap.add_argument("--replot", action="store_true", help="use the runs kept in --out")
    a = ap.parse_args()
    if a.replot and not a.out:
        sys.exit("bench-pile: --replot needs --out (the folder of the kept runs)")
    threads = [int(x) for x in a.threads.split(",")]
    rests = [x.strip() for x in a.restitution.split(",")]
    cfgs = [(e, t) for e in rests for t in threads]
    work = a.out or tempfile.mkdtemp(prefix="nbep-bench-pile.")
    os.makedirs(work, exist_ok=True)
    try:
        if a.replot:
            res = {c: kept(c, work) for c in cfgs}
        else:
            # one private copy of the binary: every run uses the same build even if bin/nbep
            # changes meanwhile
            binary = os.path.join(work, "nbep")
            shutil.copy2(a.nbep, binary)
            a.nbep = binary
            with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as ex:
                futs = [ex.submit(run, c, a, work) for c in cfgs]
                try:
                    res = {c: f.result() for c, f in zip(cfgs, futs)}
                except BaseException:  # a failed run: start no more (running ones finish)
                    ex.shutdown(wait=False, cancel_futures=True)
                    raise
        rows, curves, failed = [], {}, False
        print("| e | threads | steps | collisions | per sphere/step | "
              "last tenth, per sphere/step | held at end | last collision step | wall s | "
              "energy drift |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
        for (e, t), (s, stamps, h5) in res.items():
            times, held, coll = held_per_frame(h5)
            n, steps = s["spheres"], s["steps"]
            hit = np.nonzero(coll)[0]
            last = int(hit[-1]) + 1 if len(hit) else 0
            tail = coll[-max(1, len(coll) // 10):].mean() / n
            print(f"| {e} | {t} | {steps} | {s['collisions']} | "
                  f"{s['collisions'] / steps / n:.3f} | {tail:.3f} | {held[-1]} | {last} | "
                  f"{s['wall_seconds']:.1f} | {s['energy_rel_drift']:.3g} |")
            curves[(e, t)] = (times, held, coll, stamps, s["dt"])
        for e in rests:
            for t in threads[1:]:
                same = same_frames(res[(e, threads[0])][2], res[(e, t)][2])
                failed |= not same
                print(f"e = {e}: frames and collisions of {t} threads "
                      f"{'identical to' if same else 'DIFFER from'} {threads[0]} thread(s)")
        if a.plot:
            plot(curves, a.plot)
        return 1 if failed else 0
    finally:
        if not a.out:
            shutil.rmtree(work, ignore_errors=True)


def plot(curves, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(3, 1, figsize=(7, 8), sharex=True)
    for (e, t), (times, held, coll, stamps, dt) in curves.items():
        lab = f"e = {e}, {t} thread{'s' if t > 1 else ''}"
        steps = np.arange(1, len(coll) + 1)
        w = min(50, len(coll))  # collisions per step, mean of 50 (zeros kept: a settled pile)
        avg = np.convolve(coll, np.ones(w) / w, mode="valid")
        style = dict(label=lab, ls="-" if t == 1 else "--", lw=2.5 if t == 1 else 1.2)
        ax[0].plot(steps[w - 1:] * dt, np.maximum(avg, 0.1), **style)
        # frame 0 left out: the spheres start at rest, velocity zero but falling, not held
        ax[1].plot(times[1:], held[1:], **style)
        st = np.array(stamps, dtype=float)
        ax[2].plot(st[:, 0] * dt, st[:, 1] / 60.0, **style)
    ax[0].set_yscale("log")
    ax[0].set_ylabel("collisions per step\n(mean of 50; 0.1 = none)")
    ax[1].set_ylabel("spheres held")
    ax[2].set_ylabel("wall time (min)")
    ax[2].set_xlabel("simulated time (s)")
    for x in ax:
        x.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
