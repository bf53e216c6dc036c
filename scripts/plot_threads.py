#!/usr/bin/python3
"""Speed-up over one thread against threads, from what scripts/bench-threads.sh leaves in OUT:
the paper's box in its three predictive modes (paper.csv) and the dense fluids (dense-*/rows.csv),
medians of the repeats (the paper box's ms per step; the fluids' collisions per second).

    scripts/plot_threads.py OUT [FIGURE.png] [TITLE]
"""
import csv
import glob
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def medians(rows, key, value):
    """{key(r): {threads: median of value(r)}} over the rows."""
    by = {}
    for r in rows:
        by.setdefault(key(r), {}).setdefault(int(r["threads"]), []).append(value(r))
    return {k: {t: statistics.median(v) for t, v in sorted(ts.items())} for k, ts in by.items()}


def paper_series(path):
    """The paper box's speed-ups (a time: one thread's over t threads'), its table printed."""
    rows = list(csv.DictReader(open(path)))
    key = lambda r: f"paper box, {'all pairs' if r['mode'] == 'all' else r['mode']}, n = {r['n']}"
    ms = medians(rows, key, lambda r: float(r["wall_seconds"]) * 10)  # 100 steps
    setup = medians(rows, key, lambda r: float(r["setup_seconds"]))
    print("The paper's box, 100 steps: ms per step, median of the repeats (set-up, s)")
    for k, m in ms.items():
        print(f"  {k}: " + ", ".join(f"{t} threads {v:.2f} ({setup[k][t]:.3f})" for t, v in m.items()))
    return {k: {t: m[1] / v for t, v in m.items()} for k, m in ms.items() if 1 in m}


def dense_series(path):
    """A dense fluid's speed-ups (a rate: t threads' over one thread's). Rows may name the run's
    NBEP_TEAM in a column "team" (absent or "auto": the chooser); each value past one thread
    makes a series of its own, over the same one-thread rows."""
    rows = [r for r in csv.DictReader(open(path))
            if r["engine"] == "nbep" and float(r["seconds"] or 0) > 0]
    team = lambda r: "" if r.get("team") in (None, "", "auto") else r["team"]
    series = {}
    for name in sorted({team(r) for r in rows if int(r["threads"]) > 1}):
        label = f", NBEP_TEAM={name}" if name else ""
        rate = medians([r for r in rows if int(r["threads"]) == 1 or team(r) == name],
                       lambda r: f"fluid, N = {r['n']}, phi = {r['phi']}{label}",
                       lambda r: int(r["collisions"]) / float(r["seconds"]))
        series.update({k: {t: v / m[1] for t, v in m.items()} for k, m in rate.items() if 1 in m})
    return series


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    if sys.argv[1] in ("-h", "--help"):  # (it took --help for a folder, 2026-12-01)
        print(__doc__)
        return
    out = sys.argv[1]
    fig_path = sys.argv[2] if len(sys.argv) > 2 else os.path.join(out, "threads.png")
    title = sys.argv[3] if len(sys.argv) > 3 else "nbep: speed-up over one thread"
    series = {}
    if os.path.exists(os.path.join(out, "paper.csv")):
        series.update(paper_series(os.path.join(out, "paper.csv")))
    for rows in sorted(glob.glob(os.path.join(out, "dense-*", "rows.csv"))):
        series.update(dense_series(rows))
    if not series:
        sys.exit(f"plot_threads: nothing to plot in {out}")
    fig, ax = plt.subplots(figsize=(7, 4.5))
    tmax = max(max(s) for s in series.values())
    ax.plot([1, tmax], [1, tmax], color="0.8", lw=1, label="ideal")
    for key, s in series.items():
        style = (":" if "NBEP_TEAM" in key else "--") if key.startswith("fluid") else "-"
        ax.plot(list(s), list(s.values()), style, marker="o", label=key)
        print(f"{key}: " + ", ".join(f"{t} threads x{v:.2f}" for t, v in s.items()))
    ax.set_xscale("log", base=2)
    ax.set_yscale("log", base=2)
    ax.set_xlabel("threads")
    ax.set_ylabel("speed-up over 1 thread (medians)")
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(fig_path, dpi=110)
    print(f"plot_threads: {fig_path}")


if __name__ == "__main__":
    main()
