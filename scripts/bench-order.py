#!/usr/bin/python3
"""make bench-order: the paper's step (run.order = "step", approximate) against the exact time
order (run.order = "time", the default) of the predictive algorithm's rounds, on crowded scenes,
with the exact cells mode beside them for reference. README "Algorithms", docs/accuracy.md.

    scripts/bench-order.py [--reps 3] [--scale 1.0] [--threads 1] [--only NAME,...]

The scenes (inputs/hard-sphere-fluid.deck and inputs/pile.deck cut down):
  fluid-0.30-all, fluid-0.50-all   4096 spheres (16^3 lattice, kT = 1, e = 1) in a periodic box
                                   at packing fraction 0.30 / 0.50, the paper's all-pairs rounds
                                   (grid mode has no periodic boxes)
  fluid-0.30-grid, fluid-0.50-grid the same spheres in a closed box whose centres can reach a
                                   cube of that packing fraction (side 1 + (N pi / (6 phi))^1/3),
                                   grid rounds
  pile                             inputs/pile.deck with 1000 spheres (grid rounds, gravity,
                                   e = 0.5, resting and held contacts), its 450 steps
Each scene runs its rounds in time order ("time") and step order ("step"), and in cells mode
("cells", exact, one event at a time: the fastest exact engine for comparison). Repeats are the
outer loop and every engine of every scene runs once per repeat, so that background load hits
all alike; the table gives medians. Time is the summary's wall_seconds: the stepping loop
alone (the first predictions, O(n^2) in all-pairs mode, are set-up). Accuracy columns: the
step order's largest overlap and its collision count against time order's (the same run).
Simulated times are short (the fluids start from a lattice); --scale multiplies them.
"""
import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
N = 4096


def fluid(phi, periodic):
    if periodic:
        side = (N * math.pi / (6.0 * phi)) ** (1.0 / 3.0)
    else:
        side = 1.0 + (N * math.pi / (6.0 * phi)) ** (1.0 / 3.0)
    per = "true" if periodic else "false"
    return [f"spheres.[0].count={N}", f"box.max=[{side!r},{side!r},{side!r}]",
            f"box.periodic=[{per},{per},{per}]",
            'run.neighbors="all"' if periodic else 'run.neighbors="grid"']


# name: (deck, overrides, dt, simulated time)
SCENES = {
    "fluid-0.30-all": ("inputs/hard-sphere-fluid.deck", fluid(0.30, True), 0.1, 0.5),
    "fluid-0.50-all": ("inputs/hard-sphere-fluid.deck", fluid(0.50, True), 0.05, 0.1),
    "fluid-0.30-grid": ("inputs/hard-sphere-fluid.deck", fluid(0.30, False), 0.1, 1.0),
    "fluid-0.50-grid": ("inputs/hard-sphere-fluid.deck", fluid(0.50, False), 0.1, 0.5),
    "pile": ("inputs/pile.deck", ["spheres.[0].count=1000", 'run.neighbors="grid"'], 1e-3, 0.45),
}
ENGINES = {"time": ['run.order="time"'], "step": ['run.order="step"'],
           "cells": ['run.neighbors="cells"']}


def run(nbep, scene, engine, threads, scale, work):
    deck, sets, dt, t_sim = SCENES[scene]
    steps = max(1, round(t_sim * scale / dt))
    out = os.path.join(work, "run.h5")
    summary = os.path.join(work, "run.json")
    cmd = [nbep, "run", os.path.join(ROOT, deck), "-t", str(threads), "--dt", repr(dt),
           "-n", str(steps), "-o", out, "--summary", summary, "--quiet",
           "--set", f"output.every={steps}", "--set", "output.fields=[]",
           "--set", "output.stats=false"]
    for s in sets + ENGINES[engine]:
        cmd += ["--set", s]
    res = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    if res.returncode != 0:
        sys.exit(f"bench-order: nbep failed ({res.returncode}): {' '.join(cmd)}\n{res.stderr}")
    with open(summary) as fh:
        data = json.load(fh)
    os.remove(summary)
    os.remove(out)
    data["steps"] = steps
    return data


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--scale", type=float, default=1.0, help="multiplies every simulated time")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--only", default="", help="comma-separated scene names")
    ap.add_argument("--nbep", default=os.path.join(ROOT, "bin/nbep"))
    a = ap.parse_args()
    scenes = a.only.split(",") if a.only else list(SCENES)
    for s in scenes:
        if s not in SCENES:
            sys.exit(f"bench-order: no scene named {s} (have {', '.join(SCENES)})")
    work = tempfile.mkdtemp(prefix="nbep-bench-order.")
    res = {}
    try:
        # one private copy of the binary: every run uses the same build, even if bin/nbep is
        # rebuilt meanwhile
        shutil.copy2(a.nbep, os.path.join(work, "nbep"))
        a.nbep = os.path.join(work, "nbep")
        for rep in range(a.reps):
            for s in scenes:
                for e in ENGINES:
                    res.setdefault((s, e), []).append(run(a.nbep, s, e, a.threads, a.scale,
                                                          work))
            print(f"bench-order: repeat {rep + 1}/{a.reps} done", file=sys.stderr, flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"threads {a.threads}, medians of {a.reps} (interleaved), load average "
          f"{os.getloadavg()[0]:.1f} at the end\n")
    print("| scene | dt | steps | engine | wall s | collisions | collisions/s | max overlap "
          "| collisions vs time |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    ratios = []
    for s in scenes:
        base = res[(s, "time")][0]["collisions"]
        med = {}
        for e in ENGINES:
            rs = res[(s, e)]
            wall = statistics.median(r["wall_seconds"] for r in rs)
            med[e] = wall
            r = rs[0]
            # against the time order's count; none when it had no collision (a cut-down run)
            off = f"{(r['collisions'] - base) / base:+.2%}" if base else "n/a"
            print(f"| {s} | {SCENES[s][2]:g} | {r['steps']} | {e} | {wall:.3g} "
                  f"| {r['collisions']} | {r['collisions'] / wall:.3g} "
                  f"| {r['max_overlap_rel']:.2g} | {off} |")
        ratios.append(f"{s}: step is {med['time'] / med['step']:.2f}x time order's speed; "
                      f"cells (exact) {med['time'] / med['cells']:.1f}x")
    print("\n" + "\n".join(ratios))
    return 0


if __name__ == "__main__":
    sys.exit(main())
