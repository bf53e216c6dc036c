#!/usr/bin/python3
"""Figures, tables and headline ratios from the runs scripts/bench.sh measured.

    /usr/bin/python3 scripts/plot_bench.py --results bench/results --figdir docs/figures

Reads RESULTS/runs.csv (one row per `nbep run`), meta.txt (machine and build) and the
micro-benchmark outputs (barrier.csv, bvh.csv, predict.txt). Writes, in FIGDIR, one PNG per
group of the paper's Section 6 figures; in RESULTS, tables.md (markdown tables of medians) and
headline.txt (also printed). Exit status 1 when a check fails: a run that failed, counters that
differ between thread counts or repeats of the same run (the algorithms are deterministic and
thread-invariant by contract), or a predictive run whose energy or overlap is off.

Medians over repeats throughout (a repeat of a short configuration holds several runs: their
median is that repeat's value); a speedup is the median over repeats of the ratio measured in
the same repeat (the runs of one repeat ran side by side, so they share the machine's load).
Beside it, the best-of-repeats speedup, fastest 1-thread time over fastest t-thread time: on a
shared machine a t-thread run that lost a core to another process is slowed far more than a
1-thread run (its threads wait for each other at every barrier), and the fastest run is the
one that was least disturbed.
"""
import argparse
import collections
import csv
import math
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

# predictive-grid: the predictive algorithm with run.neighbors = "grid" (beyond the paper: a
# re-prediction tests only nearby spheres); drawn when the runs hold it.
ALGORITHMS = ("naive", "seminaive", "predictive", "predictive-grid")
COLORS = {"naive": "tab:red", "seminaive": "tab:green", "predictive": "tab:blue",
          "predictive-grid": "tab:purple"}
PREDICTIVE = ("predictive", "predictive-grid")
MAIN_L = 10.0  # the paper-box deck's box edge: the volume of the headline comparisons
PLANES = 6  # the box's planes in every run

# Accuracy a correct predictive run meets with e = 1 (SPEC: exact contact times, elastic
# response): energy drifts by round-off only, about 1e-16 per collision relative, so 1e-12
# leaves room for millions of collisions; overlaps are round-off of the contact time, about
# 1e-13 of a radius, so 1e-9 still says "none". Naive and seminaive detect after the fact and
# overlap by up to a step's travel, so they are reported, not checked.
PRED_ENERGY_RTOL = 1e-12
PRED_OVERLAP_RTOL = 1e-9

# The counters that must not depend on the thread count or the repeat.
INVARIANT = ("checks", "predictions", "collisions", "sphere_collisions", "plane_collisions",
             "quiet_steps", "energy_rel_drift", "max_overlap_rel")


def read_meta(path):
    meta = {}
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                key, _, value = line.rstrip("\n").partition("=")
                meta[key] = value
    return meta


def read_runs(path):
    ints = ("n", "threads", "threads_requested", "repeat", "inner", "steps", "checks",
            "predictions", "collisions", "sphere_collisions", "plane_collisions", "quiet_steps",
            "peak_rss_bytes", "exit_status")
    runs = []
    with open(path) as f:
        for row in csv.DictReader(f):
            r = {}
            for k, v in row.items():
                if v == "":
                    r[k] = None
                elif k == "algorithm":
                    r[k] = v
                elif k in ints:
                    r[k] = int(float(v))
                else:
                    r[k] = float(v)
            runs.append(r)
    return runs


def read_barrier(path):
    """Rows of bench_barrier's CSV: threads, crossings, nbep_ns, omp_ns, nbep_over_omp."""
    rows = []
    if not os.path.exists(path):
        return rows
    with open(path) as f:
        lines = [ln for ln in f if not ln.startswith("#") and ln.strip()]
    for row in csv.DictReader(lines):
        rows.append({k: float(v) for k, v in row.items()})
    return rows


def median(xs):
    xs = [x for x in xs if x is not None and not math.isnan(x)]
    return statistics.median(xs) if xs else float("nan")


class Results:
    """The successful runs, grouped by (algorithm, n, L, threads)."""

    def __init__(self, runs):
        self.runs = [r for r in runs if r["exit_status"] == 0 and r["time_per_step"] is not None]
        self.groups = collections.defaultdict(list)
        for r in self.runs:
            self.groups[(r["algorithm"], r["n"], r["box_L"], r["threads"])].append(r)
        self.volumes = sorted({r["box_L"] for r in self.runs})
        self.algorithms = [a for a in ALGORITHMS if any(r["algorithm"] == a for r in self.runs)]
        self.threads = sorted({r["threads"] for r in self.runs})

    def ns(self, a, L, t=None):
        return sorted({n for (aa, n, LL, tt) in self.groups
                       if aa == a and LL == L and (t is None or tt == t)})

    def by_repeat(self, a, n, L, t, field):
        """{repeat: median of the field over that repeat's runs} (the inner runs of a short
        configuration are one measurement)."""
        reps = collections.defaultdict(list)
        for r in self.groups.get((a, n, L, t), []):
            reps[r["repeat"]].append(r[field])
        return {k: median(v) for k, v in reps.items()}

    def get(self, a, n, L, t, field):
        """Median over repeats, nan if never run."""
        return median(list(self.by_repeat(a, n, L, t, field).values()))

    def per_step(self, a, n, L, t, field):
        return median([r[field] / r["steps"] for r in self.groups.get((a, n, L, t), [])])

    def step_predictions(self, r):
        """Predictions made while stepping: predictive counts its set-up's n(n-1) + n*P first
        predictions (every sphere against every other sphere and plane) in step 1. (The grid
        variant's set-up predictions, O(n), stay in.)"""
        p = r["predictions"]
        if r["algorithm"] == "predictive":
            p -= r["n"] * (r["n"] - 1) + r["n"] * PLANES
        return p

    def best_speedup(self, a, n, L, t):
        """Fastest 1-thread time over fastest t-thread time, over all repeats."""
        one = [r["time_per_step"] for r in self.groups.get((a, n, L, 1), [])]
        many = [r["time_per_step"] for r in self.groups.get((a, n, L, t), [])]
        return min(one) / min(many) if one and many else float("nan")

    def speedup(self, a, n, L, t):
        """Median over repeats of T(1 thread) / T(t threads), each pair from one repeat; and
        the smallest and largest of those ratios."""
        one = self.by_repeat(a, n, L, 1, "time_per_step")
        many = self.by_repeat(a, n, L, t, "time_per_step")
        ratios = [one[k] / many[k] for k in one if k in many and many[k] > 0]
        if not ratios:
            return float("nan"), float("nan"), float("nan")
        return median(ratios), min(ratios), max(ratios)


def check(all_runs, res):
    """Problems that make the numbers untrustworthy; each one line."""
    problems = []
    for r in all_runs:
        if r["exit_status"] != 0 or r["time_per_step"] is None:
            problems.append("run failed (exit %s): %s n=%d L=%g threads=%d repeat %d.%d"
                            % (r["exit_status"], r["algorithm"], r["n"], r["box_L"],
                               r["threads_requested"], r["repeat"], r["inner"]))
    same_run = collections.defaultdict(list)
    for r in res.runs:
        same_run[(r["algorithm"], r["n"], r["box_L"], r["steps"])].append(r)
    for (a, n, L, steps), rs in sorted(same_run.items()):
        for field in INVARIANT:
            values = {r[field] for r in rs}
            if len(values) > 1:
                problems.append("%s n=%d L=%g: %s differs between thread counts or repeats: %s"
                                % (a, n, L, field, sorted(values)))
    for r in res.runs:
        if r["algorithm"] not in PREDICTIVE:
            continue
        if (abs(r["energy_rel_drift"]) > PRED_ENERGY_RTOL
                or r["max_overlap_rel"] > PRED_OVERLAP_RTOL):
            problems.append("%s n=%d L=%g threads=%d: energy_rel_drift %.3g, "
                            "max_overlap_rel %.3g (limits %g, %g)"
                            % (r["algorithm"], r["n"], r["box_L"], r["threads"],
                               r["energy_rel_drift"],
                               r["max_overlap_rel"], PRED_ENERGY_RTOL, PRED_OVERLAP_RTOL))
    return problems


# ---- figures ---------------------------------------------------------------------------------

def corner(fig, meta):
    note = ("%s, tree %s | %s cores: %s | bench size %s, %s | paper-box deck, %s-step window, "
            "medians over repeats" % (meta.get("build", "?"), meta.get("tree", "?"),
                                      meta.get("nproc", "?"),
                                      meta.get("cpu", "?"), meta.get("size", "?"),
                                      meta.get("date", "?"), meta.get("window_steps", "?")))
    fig.text(0.995, 0.004, note, ha="right", va="bottom", fontsize=6.5, color="0.35")


def vol_label(L):
    return "L = %g (%g m$^3$)" % (L, L ** 3)


def log2_axis(ax, which="x"):
    axis = ax.xaxis if which == "x" else ax.yaxis
    (ax.set_xscale if which == "x" else ax.set_yscale)("log", base=2)
    def label(v, _):
        if v >= 2 ** 16:  # long integers crowd the axis: powers of two as such
            return "$2^{%d}$" % round(math.log2(v))
        return "%d" % v if v >= 1 and v == int(v) else "%g" % v
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(label))


def vol_styles(volumes):
    markers = "os^Dv"
    lines = ["-", "--", ":", "-."]
    return {L: (markers[i % len(markers)], lines[i % len(lines)]) for i, L in enumerate(volumes)}


def panels(k):
    """k side-by-side panels of the usual size."""
    fig, axes = plt.subplots(1, k, figsize=(5 * k, 4.8), squeeze=False)
    return fig, axes[0]


def save(fig, figdir, name, meta):
    corner(fig, meta)
    fig.tight_layout(rect=(0, 0.02, 1, 1))
    path = os.path.join(figdir, name)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def fig_runtime_volumes(res, meta, figdir):
    """Paper Figs 1 and 3 (and seminaive between them): time per step against sphere count for
    each volume, one thread."""
    fig, axes = panels(len(res.algorithms))
    styles = vol_styles(res.volumes)
    titles = {"naive": "Fig 1: naive, runtime is volume-invariant",
              "seminaive": "seminaive (BVH filter), for comparison",
              "predictive": "Fig 3: predictive, runtime grows with density",
              "predictive-grid": "predictive, neighbors = grid (beyond the paper)"}
    for ax, a in zip(axes, res.algorithms):
        for L in res.volumes:
            ns = res.ns(a, L, 1)
            if not ns:
                continue
            ys = [1e3 * res.get(a, n, L, 1, "time_per_step") for n in ns]
            m, ls = styles[L]
            ax.plot(ns, ys, marker=m, ls=ls, color=COLORS[a], label=vol_label(L))
        log2_axis(ax)
        ax.set_yscale("log")
        ax.set_xlabel("spheres n")
        ax.set_ylabel("time per step (ms), 1 thread")
        ax.set_title(titles[a], fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, title="box edge (volume)", title_fontsize=8)
    fig.suptitle("Runtime vs spheres for three volumes (paper Figs 1, 3)")
    return save(fig, figdir, "bench_runtime_volumes.png", meta)


def fig_checks(res, meta, figdir):
    """Paper Fig 4 (predictive checks per step, linear in n) and Fig 11 (log-log checks of all
    algorithms); between them the predictive's real work, its predictions per step."""
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    styles = vol_styles(res.volumes)
    ax = axes[0]
    for i, L in enumerate(res.volumes):
        ns = res.ns("predictive", L, 1)
        m, ls = styles[L]
        ax.plot(ns, [res.per_step("predictive", n, L, 1, "checks") for n in ns], marker=m,
                ms=9 - 2.5 * i, mfc="none", ls=ls, color=COLORS["predictive"],
                label="predictive, " + vol_label(L))
    if res.ns("predictive", MAIN_L, 1):
        nmax = max(res.ns("predictive", MAIN_L, 1))
        ax.plot([0, nmax], [0, nmax], color="0.5", lw=0.8, label="n (one slot per sphere)")
    ax.set_xlabel("spheres n")
    ax.set_ylabel("checks per step")
    ax.set_title("Fig 4: predictive checks per step are linear in n", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)

    ax = axes[1]
    for a in [x for x in res.algorithms if x in PREDICTIVE]:
        for L in res.volumes:
            ns = res.ns(a, L, 1)
            ys = [median([res.step_predictions(r) / r["steps"]
                          for r in res.groups[(a, n, L, 1)]]) for n in ns]
            pts = [(n, y) for n, y in zip(ns, ys) if y > 0]
            m, ls = styles[L]
            if pts:
                ax.plot(*zip(*pts), marker=m, ls=ls, color=COLORS[a],
                        label="%s, %s" % (a, vol_label(L)))
    log2_axis(ax, "x")
    ax.set_yscale("log")
    ax.set_xlabel("spheres n")
    ax.set_ylabel("contact-time predictions per step")
    ax.set_title("predictions per step: all pairs ~ collisions x n, collisions ~ n$^2$/L$^3$\n"
                 "(all pairs: set-up's excluded; grid: its O(n) set-up's included)",
                 fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)

    ax = axes[2]
    for a in res.algorithms:
        ns = res.ns(a, MAIN_L, 1)
        ax.plot(ns, [res.per_step(a, n, MAIN_L, 1, "checks") for n in ns], marker="o",
                color=COLORS[a], label=a)
    ns = res.ns("naive", MAIN_L, 1) or res.ns("predictive", MAIN_L, 1)
    if ns:
        ax.plot(ns, [n * (n - 1) / 2 + PLANES * n for n in ns], color="0.5", lw=0.8, ls="--",
                label="n(n-1)/2 + 6n (all pairs)")
    log2_axis(ax, "x")
    log2_axis(ax, "y")
    ax.set_xlabel("spheres n (log2)")
    ax.set_ylabel("checks per step (log2)")
    ax.set_title("Fig 11: checks per step, log-log, L = %g, 1 thread" % MAIN_L, fontsize=10)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle("Checks vs spheres (paper Figs 4, 11)")
    return save(fig, figdir, "bench_checks.png", meta)


def fig_prediction_rate(res, meta, figdir):
    """Paper Figs 2 and 5: prediction rate = collisions / checks."""
    fig, axes = panels(len(res.algorithms))
    styles = vol_styles(res.volumes)
    titles = {"naive": "Fig 2: naive", "seminaive": "seminaive (checks after the BVH filter)",
              "predictive": "Fig 5: predictive",
              "predictive-grid": "predictive, neighbors = grid"}
    for ax, a in zip(axes, res.algorithms):
        for L in res.volumes:
            ns = res.ns(a, L, 1)
            m, ls = styles[L]
            ys = [100 * res.get(a, n, L, 1, "prediction_rate") for n in ns]
            pts = [(n, y) for n, y in zip(ns, ys) if y > 0]
            if pts:
                ax.plot(*zip(*pts), marker=m, ls=ls, color=COLORS[a], label=vol_label(L))
        log2_axis(ax)
        ax.set_yscale("log")
        ax.set_xlabel("spheres n")
        ax.set_ylabel("prediction rate = collisions / checks (%)")
        ax.set_title(titles[a], fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Prediction rates (paper Figs 2, 5)")
    return save(fig, figdir, "bench_prediction_rate.png", meta)


def thread_styles(threads):
    return {t: ("os^Dv<>"[i % 7], ["-", "--", ":", "-."][i % 4]) for i, t in enumerate(threads)}


def fig_threads(res, meta, figdir):
    """Paper Figs 6-9: naive and predictive runs per thread count; runtime (6, 8), and the
    thread-invariant collisions and checks (7, 9)."""
    cols = [("naive", 6, 7), ("predictive", 8, 9)]
    if "predictive-grid" in res.algorithms:
        cols.append(("predictive-grid", None, None))
    fig, axes = plt.subplots(2, len(cols), figsize=(6.5 * len(cols), 9), squeeze=False)
    styles = thread_styles(res.threads)
    for col, (a, fr, fc) in enumerate(cols):
        ax = axes[0][col]
        for t in res.threads:
            ns = res.ns(a, MAIN_L, t)
            m, ls = styles[t]
            ax.plot(ns, [1e3 * res.get(a, n, MAIN_L, t, "time_per_step") for n in ns],
                    marker=m, ls=ls, color=COLORS[a], label="%d thread%s" % (t, "s" * (t > 1)))
        log2_axis(ax)
        ax.set_yscale("log")
        ax.set_xlabel("spheres n")
        ax.set_ylabel("time per step (ms)")
        ax.set_title("%s%s runtime by thread count, L = %g"
                     % ("Fig %d: " % fr if fr else "", a, MAIN_L), fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)

        ax = axes[1][col]
        for t in res.threads:
            ns = res.ns(a, MAIN_L, t)
            m, _ = styles[t]
            size = 9 - 3 * res.threads.index(t)  # later thread counts drawn smaller, inside
            ax.plot(ns, [res.per_step(a, n, MAIN_L, t, "checks") for n in ns], marker=m,
                    ms=size, ls="-", color="0.3", mfc="none",
                    label="checks, %d thread%s" % (t, "s" * (t > 1)))
            ax.plot(ns, [res.per_step(a, n, MAIN_L, t, "collisions") for n in ns], marker=m,
                    ms=size, ls="--", color=COLORS[a], mfc="none",
                    label="collisions, %d thread%s" % (t, "s" * (t > 1)))
        log2_axis(ax)
        ax.set_yscale("log")
        ax.set_xlabel("spheres n")
        ax.set_ylabel("per step")
        ax.set_title("%s%s checks and collisions per step are thread-invariant"
                     % ("Fig %d: " % fc if fc else "", a), fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Thread runs (paper Figs 6-9)")
    return save(fig, figdir, "bench_threads.png", meta)


def crossover(res, n0, t, L=MAIN_L, a="predictive"):
    """How many times n0 spheres predictive handles in the time naive takes for n0: the
    largest measured k (a power of two) with T_pred(k n0) <= T_naive(n0), and k found on the
    log-log line through the measured predictive times: between the two sizes that bracket
    naive's time ("interpolated"), or past the largest size along the last segment's slope
    ("extrapolated", when even the largest predictive run is faster; at most to twice the
    largest size, beyond which a slope from two noisy points says little: then k is a lower
    bound, ">="). Returns (k_measured, k, how)."""
    tn = res.get("naive", n0, L, t, "time_per_step")
    ns = [n for n in res.ns(a, L, t) if n >= n0]
    ts = [res.get(a, n, L, t, "time_per_step") for n in ns]
    if math.isnan(tn) or not ns:
        return float("nan"), float("nan"), "-"
    k_meas = max([n / n0 for n, tp in zip(ns, ts) if tp <= tn], default=float("nan"))

    def on_line(na, ta, nb, tb):
        f = (math.log(tn) - math.log(ta)) / (math.log(tb) - math.log(ta))
        return math.exp(math.log(na) + f * (math.log(nb) - math.log(na))) / n0

    for (na, ta), (nb, tb) in zip(zip(ns, ts), zip(ns[1:], ts[1:])):
        if ta <= tn < tb:
            return k_meas, on_line(na, ta, nb, tb), "interpolated"
    if ts[-1] <= tn:
        if len(ns) >= 2 and ts[-1] > ts[-2]:
            k = on_line(ns[-2], ts[-2], ns[-1], ts[-1])
            if k <= 2 * ns[-1] / n0:
                return k_meas, k, "extrapolated"
        return k_meas, ns[-1] / n0, "lower bound"
    return k_meas, float("nan"), "-"


def fmt_k(k, how):
    if math.isnan(k):
        return "-"
    return (">= %.0f" if how == "lower bound" else "%.1f") % k


def fig_pred_vs_naive(res, meta, figdir):
    """Paper Fig 10: predictive against naive, all thread counts."""
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
    styles = thread_styles(res.threads)
    ax = axes[0]
    for a in res.algorithms:
        for t in res.threads:
            ns = res.ns(a, MAIN_L, t)
            m, ls = styles[t]
            ax.plot(ns, [1e3 * res.get(a, n, MAIN_L, t, "time_per_step") for n in ns],
                    marker=m, ls=ls, color=COLORS[a], label="%s, %d thr" % (a, t),
                    alpha=0.45 if a == "seminaive" else 1.0)
    # the headline: naive at its largest n against predictive at 4n, one thread
    naive_ns = res.ns("naive", MAIN_L, 1)
    for n0 in naive_ns[::-1]:
        tn = res.get("naive", n0, MAIN_L, 1, "time_per_step")
        tp = res.get("predictive", 4 * n0, MAIN_L, 1, "time_per_step")
        if not math.isnan(tp):
            ax.annotate("", xy=(4 * n0, 1e3 * tp), xytext=(n0, 1e3 * tn),
                        arrowprops=dict(arrowstyle="->", color="k", lw=1))
            ax.text(0.02, 0.97, "arrow: naive n=%d -> predictive n=%d (1 thread),\n"
                    "%.2fx the time per step" % (n0, 4 * n0, tp / tn), transform=ax.transAxes,
                    fontsize=8, ha="left", va="top", bbox=dict(fc="white", ec="0.7", alpha=0.85))
            break
    log2_axis(ax)
    ax.set_yscale("log")
    ax.set_xlabel("spheres n")
    ax.set_ylabel("time per step (ms)")
    ax.set_title("time per step vs spheres, L = %g" % MAIN_L, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=3)

    ax = axes[1]
    lo, hi = float("inf"), 0.0
    for a in [x for x in res.algorithms if x in PREDICTIVE]:
        for t in res.threads:
            ns = [n for n in res.ns("naive", MAIN_L, t) if n in res.ns(a, MAIN_L, t)]
            xs = [1e3 * res.get("naive", n, MAIN_L, t, "time_per_step") for n in ns]
            ys = [1e3 * res.get(a, n, MAIN_L, t, "time_per_step") for n in ns]
            if not ns:
                continue
            m, ls = styles[t]
            ax.plot(xs, ys, marker=m, ls=ls, color=COLORS[a],
                    label="%s, %d thread%s" % (a, t, "s" * (t > 1)))
            for n, x, y in zip(ns, xs, ys):
                if t == res.threads[0] and a == "predictive":
                    ax.annotate("n=%d" % n, (x, y), fontsize=7, xytext=(3, -9),
                                textcoords="offset points")
            lo, hi = min(lo, *xs, *ys), max(hi, *xs, *ys)
    if hi > 0:
        ax.plot([lo, hi], [lo, hi], color="0.5", lw=0.8, ls="--", label="equal time")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("naive time per step (ms)")
    ax.set_ylabel("predictive time per step (ms)")
    ax.set_title("predictive vs naive runtime at the same n", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.suptitle("Predictive vs naive runtime, all thread counts (paper Fig 10)")
    return save(fig, figdir, "bench_predictive_vs_naive.png", meta)


def fig_speedup(res, meta, figdir):
    """Paper Figs 12 and 13: speedup of t threads over one."""
    many = [t for t in res.threads if t > 1]
    fig, axes = panels(len(res.algorithms))
    styles = vol_styles(res.volumes)
    titles = {"naive": "Fig 12: naive", "seminaive": "seminaive",
              "predictive": "Fig 13: predictive", "predictive-grid": "predictive, grid"}
    for ax, a in zip(axes, res.algorithms):
        for t in many:
            for L in res.volumes:
                ns = [n for n in res.ns(a, L, t) if n in res.ns(a, L, 1)]
                if not ns:
                    continue
                s = [res.speedup(a, n, L, t) for n in ns]
                m, ls = styles[L]
                main = L == MAIN_L
                ax.errorbar(ns, [x[0] for x in s],
                            yerr=[[x[0] - x[1] for x in s], [x[2] - x[0] for x in s]],
                            marker=m, ls=ls, capsize=2, lw=1.6 if main else 0.9,
                            alpha=1.0 if main else 0.6,
                            label="%d threads, %s" % (t, vol_label(L)))
                if main:
                    ax.plot(ns, [res.best_speedup(a, n, L, t) for n in ns], marker=m, ls="none",
                            mfc="none", ms=9, color="k",
                            label="%d threads, %s, best of repeats" % (t, vol_label(L)))
            ax.axhline(t, color="0.6", lw=0.6, ls=":")
        ax.axhline(1, color="0.3", lw=0.8)
        log2_axis(ax)
        ax.set_xlabel("spheres n")
        ax.set_ylabel("speedup T(1 thread) / T(t threads)")
        ax.set_title(titles[a] + "; median, bars min..max over repeats", fontsize=10)
        ax.set_ylim(bottom=0)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best", framealpha=0.7)
    fig.suptitle("Thread speedup over one thread (paper Figs 12, 13)")
    return save(fig, figdir, "bench_speedup.png", meta)


# ---- tables and headline ---------------------------------------------------------------------

def fmt_ms(x):
    if math.isnan(x):
        return "-"
    x *= 1e3
    return "%.3g" % x if x < 1000 else "%.0f" % x


def fmt(x, spec="%.3g"):
    return "-" if x is None or (isinstance(x, float) and math.isnan(x)) else spec % x


def md_table(header, rows):
    out = ["| " + " | ".join(header) + " |", "| " + " | ".join("---" for _ in header) + " |"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def tables(res, barrier, meta):
    parts = []
    L = MAIN_L
    ns = sorted({n for (a, n, LL, t) in res.groups if LL == L})
    setups = [a for a in res.algorithms if a in PREDICTIVE]
    header = ["n"] + ["%s %dt" % (a, t) for a in res.algorithms for t in res.threads] + [
        "%s set-up (s), 1t" % a for a in setups]
    rows = []
    for n in ns:
        row = [n] + [fmt_ms(res.get(a, n, L, t, "time_per_step"))
                     for a in res.algorithms for t in res.threads]
        row += [fmt(res.get(a, n, L, 1, "setup_seconds"), "%.3g") for a in setups]
        rows.append(row)
    parts.append("### Time per step (ms), L = %g, median of repeats\n\n%s"
                 % (L, md_table(header, rows)))

    header = ["n"] + ["%s L=%g" % (a, LL) for a in res.algorithms for LL in res.volumes]
    rows = []
    for n in sorted({n for (a, n, LL, t) in res.groups}):
        rows.append([n] + [fmt_ms(res.get(a, n, LL, 1, "time_per_step"))
                           for a in res.algorithms for LL in res.volumes])
    parts.append("### Time per step (ms) by volume, 1 thread\n\n" + md_table(header, rows))

    header = ["algorithm", "L", "n", "steps", "checks/step", "predictions/step",
              "collisions/step", "prediction rate (%)", "quiet steps (%)", "peak RSS (MB)"]
    rows = []
    for a in res.algorithms:
        for LL in res.volumes:
            for n in res.ns(a, LL, 1):
                g = res.groups[(a, n, LL, 1)][0]
                rows.append([a, "%g" % LL, n, g["steps"], fmt(g["checks"] / g["steps"]),
                             fmt(res.step_predictions(g) / g["steps"]),
                             fmt(g["collisions"] / g["steps"]),
                             fmt(100 * g["prediction_rate"] if g["prediction_rate"] else 0.0),
                             fmt(100 * g["quiet_fraction"], "%.0f"),
                             fmt(g["peak_rss_bytes"] / 2 ** 20, "%.0f")])
    parts.append("### Counters per step (1 thread; identical for every thread count)\n\n"
                 + md_table(header, rows))

    many = [t for t in res.threads if t > 1]
    header = ["n"] + ["%s %dt" % (a, t) for a in res.algorithms for t in many]
    rows = []
    for n in ns:
        rows.append([n] + ["%s (%s)" % (fmt(res.speedup(a, n, L, t)[0], "%.2f"),
                                        fmt(res.best_speedup(a, n, L, t), "%.2f"))
                           for a in res.algorithms for t in many])
    parts.append("### Speedup over 1 thread, L = %g: median of per-repeat ratios (best of "
                 "repeats)\n\n%s" % (L, md_table(header, rows)))

    if barrier:
        rows = [[int(b["threads"]), int(b["crossings"]), "%.1f" % b["nbep_ns"],
                 "%.1f" % b["omp_ns"], "%.3f" % b["nbep_over_omp"]] for b in barrier]
        parts.append("### One barrier crossing (bench_barrier), ns, median of repeats\n\n"
                     + md_table(["threads", "crossings", "nbep_barrier", "omp barrier",
                                 "nbep / omp"], rows))
    return "\n\n".join(parts) + "\n"


def headline(res, barrier, problems):
    lines = []
    L = MAIN_L
    for t in res.threads:
        for n0 in res.ns("naive", L, t):
            tn = res.get("naive", n0, L, t, "time_per_step")
            tp = res.get("predictive", 4 * n0, L, t, "time_per_step")
            k_meas, k, how = crossover(res, n0, t)
            if math.isnan(tp):
                continue
            lines.append("4x: %d thread%s, naive n=%d %s ms/step vs predictive n=%d %s ms/step "
                         "(ratio %s); predictive handles k = %s x n in naive's time (%s; "
                         "largest measured: %s)"
                         % (t, "s" * (t > 1), n0, fmt_ms(tn), 4 * n0, fmt_ms(tp),
                            fmt(tp / tn, "%.2f"), fmt_k(k, how), how, fmt(k_meas, "%.0f")))
    nmax = max(res.ns("predictive", L, 1) or [0])
    for t in res.threads:
        if t > 1 and nmax:
            for a in res.algorithms:
                s, lo, hi = res.speedup(a, nmax if a != "naive" else max(res.ns(a, L, 1) or [0]),
                                        L, t)
                if not math.isnan(s):
                    na = nmax if a != "naive" else max(res.ns(a, L, 1))
                    lines.append("speedup: %s n=%d, %d threads over 1: median %.2f (repeats "
                                 "%.2f..%.2f), best of repeats %.2f"
                                 % (a, na, t, s, lo, hi, res.best_speedup(a, na, L, t)))
    if nmax:
        tp = res.get("predictive", nmax, L, 1, "time_per_step")
        ts = res.get("seminaive", nmax, L, 1, "time_per_step")
        lines.append("seminaive vs predictive: n=%d, 1 thread: %s vs %s ms/step (predictive "
                     "%.2gx the seminaive time); predictive set-up %.3g s"
                     % (nmax, fmt_ms(ts), fmt_ms(tp), tp / ts,
                        res.get("predictive", nmax, L, 1, "setup_seconds")))
    if nmax and "predictive-grid" in res.algorithms:
        tg = res.get("predictive-grid", nmax, L, 1, "time_per_step")
        lines.append("grid: n=%d, 1 thread: predictive-grid %s ms/step; time of predictive "
                     "(all pairs) / grid = %.3g, seminaive / grid = %.3g; set-up %.3g s vs %.3g s"
                     % (nmax, fmt_ms(tg), tp / tg, ts / tg,
                        res.get("predictive-grid", nmax, L, 1, "setup_seconds"),
                        res.get("predictive", nmax, L, 1, "setup_seconds")))
        for t in res.threads:
            naive_ns = res.ns("naive", L, t)
            if naive_ns:
                n0 = max(naive_ns)
                k_meas, k, how = crossover(res, n0, t, a="predictive-grid")
                lines.append("grid: %d thread%s, naive n=%d %s ms/step; predictive-grid n=%d "
                             "%s ms/step; k = %s (%s)"
                             % (t, "s" * (t > 1), n0,
                                fmt_ms(res.get("naive", n0, L, t, "time_per_step")), nmax,
                                fmt_ms(res.get("predictive-grid", nmax, L, t, "time_per_step")),
                                fmt_k(k, how), how))
    for a in res.algorithms:
        rates = [r["prediction_rate"] for r in res.runs if r["algorithm"] == a
                 and r["prediction_rate"]]
        quiet = [r["quiet_fraction"] for r in res.runs if r["algorithm"] == a
                 and r["box_L"] == L]
        if rates:
            lines.append("prediction rate %s: %.2g%% .. %.2g%% (all n and volumes); quiet steps "
                         "at L = %g: %.0f%% .. %.0f%%"
                         % (a, 100 * min(rates), 100 * max(rates), L, 100 * min(quiet),
                            100 * max(quiet)))
    for a in PREDICTIVE:
        pred = [r for r in res.runs if r["algorithm"] == a]
        if pred:
            lines.append("%s accuracy (e = 1): max |energy_rel_drift| %.2g, "
                         "max max_overlap_rel %.2g over %d runs"
                         % (a, max(abs(r["energy_rel_drift"]) for r in pred),
                            max(r["max_overlap_rel"] for r in pred), len(pred)))
    for a in ("naive", "seminaive"):
        rs = [r for r in res.runs if r["algorithm"] == a]
        if rs:
            lines.append("%s (detects after overlap): max max_overlap_rel %.2g"
                         % (a, max(r["max_overlap_rel"] for r in rs)))
    for b in barrier:
        lines.append("barrier: %d threads, nbep_barrier %.1f ns vs omp barrier %.1f ns per "
                     "crossing (ratio %.3f)%s" % (b["threads"], b["nbep_ns"], b["omp_ns"],
                                                  b["nbep_over_omp"],
                                                  " [oversubscribed]" if b["crossings"] < 10000
                                                  else ""))
    lines.append("checks: %s" % ("all passed" if not problems else "%d PROBLEMS" % len(problems)))
    lines += ["  " + p for p in problems]
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default="bench/results")
    ap.add_argument("--figdir", default="docs/figures")
    args = ap.parse_args()

    if not os.path.isfile(os.path.join(args.results, "runs.csv")):
        sys.stderr.write("plot_bench.py: %s has no runs.csv: run `make bench` first "
                         "(or pass --results DIR)\n" % args.results)
        sys.exit(2)
    all_runs = read_runs(os.path.join(args.results, "runs.csv"))
    meta = read_meta(os.path.join(args.results, "meta.txt"))
    barrier = read_barrier(os.path.join(args.results, "barrier.csv"))
    res = Results(all_runs)
    problems = check(all_runs, res)
    if not res.runs:
        print("plot_bench: no successful runs in %s" % args.results, file=sys.stderr)
        return 1

    os.makedirs(args.figdir, exist_ok=True)
    figs = [fig_runtime_volumes(res, meta, args.figdir), fig_checks(res, meta, args.figdir),
            fig_prediction_rate(res, meta, args.figdir), fig_threads(res, meta, args.figdir),
            fig_pred_vs_naive(res, meta, args.figdir), fig_speedup(res, meta, args.figdir)]

    with open(os.path.join(args.results, "tables.md"), "w") as f:
        f.write("<!-- %s, tree %s; %s cores (%s); bench size %s, %s -->\n\n"
                % (meta.get("build", "?"), meta.get("tree", "?"), meta.get("nproc", "?"),
                   meta.get("cpu", "?"), meta.get("size", "?"), meta.get("date", "?")))
        f.write(tables(res, barrier, meta))
    text = headline(res, barrier, problems)
    with open(os.path.join(args.results, "headline.txt"), "w") as f:
        f.write(text)
    print("plot_bench: figures %s" % " ".join(figs))
    print("plot_bench: tables %s" % os.path.join(args.results, "tables.md"))
    print(text, end="")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
