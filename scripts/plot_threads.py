#!/usr/bin/env python3
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


def paper_series(path):
    by = {}
    for r in csv.DictReader(open(path)):
        key = f"paper box, {'all pairs' if r['mode'] == 'all' else r['mode']}, n = {r['n']}"
        by.setdefault(key, {}).setdefault(int(r["threads"]), []).append(float(r["wall_seconds"]))
    out = {}
    for key, ts in by.items():
        med = {t: statistics.median(v) for t, v in ts.items()}
        if 1 in med:
            out[key] = {t: med[1] / m for t, m in sorted(med.items())}
    return out


def dense_series(path):
    by = {}
    for r in csv.DictReader(open(path)):
        if r["engine"] != "nbep" or float(r["seconds"] or 0) <= 0:
            continue
        key = f"fluid, N = {r['n']}, phi = {r['phi']}"
        rate = int(r["collisions"]) / float(r["seconds"])
        by.setdefault(key, {}).setdefault(int(r["threads"]), []).append(rate)
    out = {}
    for key, ts in by.items():
        med = {t: statistics.median(v) for t, v in ts.items()}
        if 1 in med:
            out[key] = {t: m / med[1] for t, m in sorted(med.items())}
    return out


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
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
        style = "--" if key.startswith("fluid") else "-"
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
