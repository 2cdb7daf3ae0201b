#!/usr/bin/env python3
"""Table (markdown) and plot of scripts/franka_obstacle_sweep.sh's reports.

usage: summarize_sweep.py OUT  ->  OUT/summary.md, OUT/summary.json, OUT/success_vs_radius.png
Success is counted three ways, each also requiring the last state within the
goal tolerance and feasible joint speeds: the TCP never inside the sphere (the
paper's count), every collision sphere of the arm outside it, and the plan
executed in MuJoCo without contact and reaching the goal. A refused radius
(start or goal inside the sphere) counts as no success.
"""
import glob
import json
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1]
PLANNERS = [("fp", "FP"), ("fp_split", "FP + split"), ("rrt_connect", "RRT-Connect")]
WAYS = [("success_rate_tcp", "TCP"), ("success_rate_arm", "whole arm"), ("success_rate_executed", "executed")]

cells = {}
for path in glob.glob(os.path.join(out, "*_r*.json")) + glob.glob(os.path.join(out, "*_r*.refused")):
    match = re.match(r"(.+)_r([0-9]*\.?[0-9]+)\.(json|refused)$", os.path.basename(path))
    if match is None:
        continue
    planner, radius, kind = match.group(1), float(match.group(2)), match.group(3)
    if kind == "refused":
        cells[(planner, radius)] = {"refused": True}
        continue
    report = json.load(open(path))
    times = [s["planning_time_s"] for s in report["samples"]]
    cells[(planner, radius)] = {key: report.get(key) for key, _ in WAYS} | {
        "refused": False, "planning_time_s_median": sorted(times)[len(times) // 2], "num_samples": report["num_samples"]}

radii = sorted({r for _, r in cells})
summary = {"cells": [{"planner": p, "radius": r, **c} for (p, r), c in sorted(cells.items())], "largest_radius_90": {}}
lines = ["| planner | " + " | ".join(f"{r:g}" for r in radii) + " | largest radius ≥ 90 % |",
         "|---|" + "---|" * (len(radii) + 1)]
for planner, label in PLANNERS:
    for key, way in WAYS:
        row, best = [], None
        for r in radii:
            cell = cells.get((planner, r))
            if cell is None:
                row.append("")
            elif cell["refused"]:
                row.append("refused")
            elif cell[key] is None:
                row.append("–")
            else:
                row.append(f"{cell[key]:.0%}")
                if cell[key] >= 0.9 and (best is None or r > best):
                    best = r
        summary["largest_radius_90"][f"{planner}/{way}"] = best
        lines.append(f"| {label}, {way} | " + " | ".join(row) + f" | {best if best is not None else '–'} |")
times = [f"{label}: " + ", ".join(f"{cells[(p, r)]['planning_time_s_median']:.3f}" for r in radii
                                   if (p, r) in cells and not cells[(p, r)]["refused"])
         for p, label in PLANNERS]
text = ("\n".join(lines) + "\n\nplanning time (s, median over the plans, by radius; a learned planner's is the "
        "wall time of the batched call of up to 16 plans that made the plan, RRT-Connect's that plan's own search): " +
        "; ".join(times) + "\n")
open(os.path.join(out, "summary.md"), "w").write(text)
json.dump(summary, open(os.path.join(out, "summary.json"), "w"), indent=1)
print(text)

figure, axes = plt.subplots(1, 3, figsize=(13, 3.8), sharey=True)
for axis, (key, way) in zip(axes, WAYS):
    for planner, label in PLANNERS:
        xs = [r for r in radii if (planner, r) in cells]
        xs = [r for r in xs if cells[(planner, r)]["refused"] or cells[(planner, r)][key] is not None]
        ys = [0.0 if cells[(planner, r)]["refused"] else cells[(planner, r)][key] for r in xs]
        axis.plot(xs, ys, marker="o", label=label)
    axis.axhline(0.9, color="grey", lw=0.8, ls="--")
    axis.set_title(f"success: {way}")
    axis.set_xlabel("sphere radius (m)")
axes[0].set_ylabel("success rate (64 plans)")
axes[0].legend()
figure.tight_layout()
figure.savefig(os.path.join(out, "success_vs_radius.png"), dpi=60)
