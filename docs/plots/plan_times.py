#!/usr/bin/env python3
"""Box plots of planning times per family and planner from `hearth bench plan --json` files.

Usage: python3 docs/plots/plan_times.py OUT.png RESULTS.json [RESULTS.json ...]
Each JSON file holds the results of one planner (rows name their robot); the figure has one panel per
robot, one box per (family, planner), successful plans only, log time axis.
Needs matplotlib (a documentation tool, not a build dependency).
"""
import json
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(paths):
    data = defaultdict(lambda: defaultdict(list))  # robot -> (family, planner) -> times ms
    for p in paths:
        # Rows name their robot; files written before they did are told apart by name.
        fallback = "fetch" if "fetch" in p else "panda"
        for r in json.load(open(p))["results"]:
            if r.get("success"):
                robot = r.get("robot", fallback)
                data[robot][(r["family"], r["planner"])].append(1e3 * r["plan_time_s"])
    return data


def main():
    out, paths = sys.argv[1], sys.argv[2:]
    data = load(paths)
    fig, axes = plt.subplots(len(data), 1, figsize=(12, 4.4 * len(data)), squeeze=False)
    for ax, (robot, groups) in zip(axes[:, 0], sorted(data.items())):
        keys = sorted(groups)
        ax.boxplot([groups[k] for k in keys], whis=(5, 95), showfliers=True, flierprops={"markersize": 2})
        ax.set_xticks(range(1, len(keys) + 1))
        ax.set_xticklabels([f"{f} {p}" for f, p in keys], fontsize=8, rotation=40, ha="right")
        ax.set_yscale("log")
        ax.set_ylabel("planning time (ms)")
        ax.set_title(f"{robot}: MotionBenchMaker, successful plans (box: quartiles, whiskers: p5-p95)")
        ax.grid(True, axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
