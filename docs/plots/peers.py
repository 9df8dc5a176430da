#!/usr/bin/env python3
"""Per-problem planning times of our BiRRT, OMPL's RRTConnect and pybullet-planning's birrt on the
first ten valid MotionBenchMaker problems of each family (the 2026-11-30 runs in `peers_*.csv`).

Usage: python3 docs/plots/peers.py OUT.png docs/plots/peers_panda.csv docs/plots/peers_fetch.csv
A cell holds the time in ms, `fail` (not solved within the limit: drawn as a cross at the limit)
or `skip` (the start or goal collides in our model: not drawn). Needs matplotlib (a documentation
tool, not a build dependency).
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FAMILIES = ["table_pick", "table_under_pick", "box", "bookshelf_small", "bookshelf_tall", "bookshelf_thin", "cage"]
# (column, label, time limit in ms, colour)
SERIES = [
    ("hearth_birrt_seed0", "hearth BiRRT (1 s)", 1e3, "tab:blue"),
    ("ompl_rrtconnect_seed1", "OMPL 2.0.1 RRTConnect, VAMP's check from Python (1 s)", 1e3, "tab:orange"),
    ("pybullet_planning_birrt", "pybullet-planning 0.6.1 birrt (5 s)", 5e3, "tab:green"),
]


def main():
    out, paths = sys.argv[1], sys.argv[2:]
    fig, axes = plt.subplots(len(paths), 1, figsize=(12, 4.2 * len(paths)), squeeze=False)
    for ax, path in zip(axes[:, 0], paths):
        rows = list(csv.DictReader(open(path)))
        robot = os.path.basename(path).removeprefix("peers_").removesuffix(".csv")
        for s, (col, label, limit, colour) in enumerate(SERIES):
            xs, ys, fx, fy = [], [], [], []
            for f, family in enumerate(FAMILIES):
                cells = [r[col] for r in rows if r["family"] == family]
                for j, cell in enumerate(cells):
                    x = f + (s - 1) * 0.27 + (j - 4.5) * 0.018
                    if cell == "fail":
                        fx.append(x)
                        fy.append(limit)
                    elif cell not in ("skip", ""):
                        xs.append(x)
                        ys.append(float(cell))
            ax.scatter(xs, ys, s=10, color=colour, label=label)
            ax.scatter(fx, fy, s=18, color=colour, marker="x")
        ax.set_xticks(range(len(FAMILIES)))
        ax.set_xticklabels(FAMILIES, fontsize=9)
        ax.set_yscale("log")
        ax.set_ylabel("planning time (ms)")
        ax.set_title(f"{robot}: first ten valid problems per family; crosses: not solved within the limit")
        ax.grid(True, axis="y", which="both", alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=9)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(out, dpi=100)


if __name__ == "__main__":
    main()
