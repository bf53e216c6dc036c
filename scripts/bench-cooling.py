#!/usr/bin/python3
"""A freely cooling granular gas: nbep's cells mode on one thread and on a team, and Haff's law.

    scripts/bench-cooling.py            (make bench-cooling)

The scene is inputs/hard-sphere-fluid.deck (N spheres of diameter 1, mass 1, kT = 1 in a
periodic cube at packing fraction phi), melted elastically to T1 = 1 from its lattice start,
then resumed with restitution E < 1 (a resume may change the restitution): the homogeneous
cooling state, every collision taking (1 - E^2) / 4 m (v_n)^2 of the pair's energy, nothing
accelerating. Such a scene runs on the cells mode's team loop (reactions in free flight change
their own two spheres only), so threads pay off on it as on an elastic fluid.

Speed: each repeat resumes a copy of the melt for S time units on every thread count in turn
(the outer loop is the repeat, so background load hits all alike); the rate is the run's
collisions / wall_seconds (its stepping loop), the table gives medians and each thread count's
ratio to one thread's median, and every run's last frame must equal one thread's bit for bit
(else the script fails). NBEP_TEAM is left unset: the run picks its way (one thread, the team)
by measuring both (src/pred_ways.c), as users get it.

Physics: Haff's law. With each collision taking (1 - E^2) T on average (Maxwellian velocities:
the normal speed of colliding pairs has mean square 4 T / m) and N omega / 2 collisions per time
unit, omega = omega_E sqrt(T / T0) the Enskog collision frequency (4 n sigma^2 chi
sqrt(pi T / m), chi Carnahan-Starling's contact value), the temperature falls as
T(t) / T0 = 1 / (1 + t / t0)^2 with 1 / t0 = (1 - E^2) omega_E / 6. The table compares the
kinetic energy per step (/stats/kinetic_energy of one thread's first repeat) with it; the
velocity distribution's departure from a Maxwellian (a2, about -0.015 at E = 0.9) moves 1 / t0
by under 0.3 %. A gas this size stays homogeneous over a few t0 (clusters need a box larger
than the instability's length, which grows as E goes to 1).

Beside each run on more than one thread, the time a cache line takes to pass between two
cores (scripts/handover.c, as scripts/bench-dense.sh measures it, before the run): the team
loop passes a few lines between its threads for each event, so its gain follows that figure
(about 28 ns with the two virtual CPUs of this project's machine close, 150 to 170 ns apart);
the table lists each repeat's ratio to one thread's run of the same repeat with it.

Environment: NS (default "32000"), PHI (0.30), E (0.9), THREADS ("1 2"), REPS (3), S (1.0
time units; 0.25 at N >= 100000 unless set), NBEP (bin/nbep), OUT (build/bench-cooling).
"""
import json
import math
import os
import shutil
import statistics
import subprocess
import sys

import h5py
import numpy as np

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
DECK = os.path.join(ROOT, "inputs", "hard-sphere-fluid.deck")
DT = 0.1  # the deck's step
MELT_STEPS = 10  # T1 = 1: the lattice has melted (bench-dense.sh)


def env(name, default):
    return os.environ.get(name, default)


def run(nbep, args):
    e = dict(os.environ)
    e.pop("NBEP_TEAM", None)  # the run chooses its way, as users get it
    r = subprocess.run([nbep] + args, env=e, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"bench-cooling: {' '.join([nbep] + args)} failed ({r.returncode}): {r.stderr.strip()}")


def scene(n, phi):
    side = (n * math.pi / (6.0 * phi)) ** (1.0 / 3.0)
    return ["--set", f"spheres.[0].count={n}", "--set", f"box.max=[{side:.10f}, {side:.10f}, {side:.10f}]"]


def build_probe(out):
    """scripts/handover.c built in out; None without a compiler."""
    exe = os.path.join(out, "handover")
    r = subprocess.run(["cc", "-std=c11", "-O2", "-pthread", os.path.join(ROOT, "scripts", "handover.c"),
                        "-o", exe], capture_output=True)
    return exe if r.returncode == 0 else None


def handover(probe):
    """The probe's nanoseconds now, as text ("-" without a probe)."""
    if not probe:
        return "-"
    r = subprocess.run([probe], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else "-"


def enskog_rate(phi):
    n = 6.0 * phi / math.pi
    chi = (1.0 - phi / 2.0) / (1.0 - phi) ** 3
    return 4.0 * n * chi * math.sqrt(math.pi)


def main():
    # settings come from the environment; --help prints them, and any argument else is refused
    # before a run (until 2026-11-30 every argument, --help too, was ignored and the benchmark
    # ran: minutes at the default N = 32000)
    if sys.argv[1:] in (["-h"], ["--help"]):
        print(__doc__)
        return
    if len(sys.argv) > 1:
        print(f"bench-cooling: takes no arguments (got {' '.join(sys.argv[1:])}): its settings are "
              "environment variables, NS, PHI, E, THREADS, REPS, S, NBEP and OUT; --help",
              file=sys.stderr)
        sys.exit(2)
    nbep = env("NBEP", os.path.join(ROOT, "bin", "nbep"))
    ns = [int(x) for x in env("NS", "32000").split()]
    phi = float(env("PHI", "0.30"))
    e = float(env("E", "0.9"))
    threads = [int(x) for x in env("THREADS", "1 2").split()]
    reps = int(env("REPS", "3"))
    out = env("OUT", os.path.join(ROOT, "build", "bench-cooling"))
    os.makedirs(out, exist_ok=True)
    probe = build_probe(out)
    print(f"# freely cooling gas: phi = {phi}, e = {e}, {reps} repeats, nbep = {nbep}")
    for n in ns:
        s_time = float(env("S", "0.25" if n >= 100000 else "1.0"))
        steps = MELT_STEPS + max(1, round(s_time / DT))
        base = ["--quiet", "--set", "output.stats=true"] + scene(n, phi)
        melt = os.path.join(out, f"melt-{n}.h5")
        if os.path.exists(melt):
            os.remove(melt)
        run(nbep, ["run", DECK, "-t", "1", "-o", melt, "--set", f"run.steps={MELT_STEPS}",
                   "--set", f"output.every={MELT_STEPS}"] + base)
        with h5py.File(melt, "r") as h:
            melt_collisions = json.loads(h["summary"].attrs["json"])["collisions"]
        rates = {t: [] for t in threads}
        pairs = []  # per repeat and thread count > 1: (t, ratio to one thread's, handover ns)
        ref_last = None
        energy = None
        for rep in range(reps):
            for t in threads:
                f = os.path.join(out, f"cool-{n}-{t}-{rep}.h5")
                shutil.copyfile(melt, f)
                ho = handover(probe) if t > 1 else None
                sj = f + ".json"
                run(nbep, ["run", DECK, "-t", str(t), "--resume", f, "--summary", sj,
                           "--set", f"run.steps={steps}", "--set", f"output.every={MELT_STEPS}",
                           "--set", f"physics.restitution={e}"] + base)
                with open(sj) as fh:
                    sm = json.load(fh)
                # the collisions since the melt (a resumed run's summary counts from step 0)
                rates[t].append((sm["collisions"] - melt_collisions) / sm["wall_seconds"])
                if t > 1 and threads[0] == 1:
                    pairs.append((t, rates[t][-1] / rates[1][-1], ho))
                with h5py.File(f, "r") as h:
                    last = (h["frames/position"][-1], h["frames/velocity"][-1], h["frames/image"][-1])
                    if energy is None:
                        energy = (h["stats/step"][:], h["stats/kinetic_energy"][:])
                if ref_last is None:
                    ref_last = last
                elif not all(np.array_equal(a, b) for a, b in zip(ref_last, last)):
                    sys.exit(f"bench-cooling: N = {n}, {t} threads, repeat {rep}: the last frame "
                             "differs from one thread's")
                for x in (f, sj, f[:-3] + ".xmf"):  # the run, its summary, its sidecar
                    if os.path.exists(x):
                        os.remove(x)
        m1 = statistics.median(rates[threads[0]])
        print(f"\n## N = {n}, {s_time:g} time units from the melt at t = 1 (frames equal on every thread count)\n")
        print("| threads | collisions / s, median (min-max) | over one thread |")
        print("| --- | --- | --- |")
        for t in threads:
            r = rates[t]
            print(f"| {t} | {statistics.median(r) / 1e3:.1f} k ({min(r) / 1e3:.0f}-{max(r) / 1e3:.0f}) "
                  f"| {statistics.median(r) / m1:.2f} |")
        if pairs:
            print("\nper repeat, threads: rate over the same repeat's one thread (hand-over ns):",
                  "; ".join(f"{t}: {r:.2f} ({h})" for t, r, h in pairs))
        step, ke = energy
        t0_inv = (1.0 - e * e) * enskog_rate(phi) / 6.0
        k0 = 1.5 * n  # kT = 1 at the melt: the deck's speed sqrt(3)
        print(f"\nHaff's law, 1 / t0 = (1 - e^2) omega_E / 6 = {t0_inv:.4f} (omega_E = {enskog_rate(phi):.3f}):\n")
        print("| t - 1 | T / T0 measured | Haff | measured / Haff - 1 |")
        print("| --- | --- | --- | --- |")
        worst = 0.0
        for s, k in zip(step, ke):
            tt = (s - MELT_STEPS) * DT
            if tt <= 0:
                continue
            haff = 1.0 / (1.0 + tt * t0_inv) ** 2
            dev = (k / k0) / haff - 1.0
            worst = max(worst, abs(dev))
            if abs(tt * 4 - round(tt * 4)) < 1e-9 or s == step[-1]:
                print(f"| {tt:.2f} | {k / k0:.4f} | {haff:.4f} | {dev:+.4f} |")
        print(f"\nlargest |measured / Haff - 1| over the steps: {worst:.4f}")


if __name__ == "__main__":
    main()
