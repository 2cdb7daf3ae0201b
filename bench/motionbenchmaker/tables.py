#!/usr/bin/env python3
"""The MotionBenchMaker benchmark's tables and plot, from the test reports.

usage: tables.py --root ROOT --planners a,b,... --families x,y,...

Reads ROOT/test/<planner>/<family>.json (`flowplan plan --problems` reports, one plan per problem, executed),
ROOT/val/<planner>/chosen.json and ROOT/problems/<family>_test.yaml; writes ROOT/results/summary.md,
summary.json and success_vs_time.png. Per planner, per family and pooled: plans valid by the plan checker,
valid and executed in MuJoCo without contact to the goal, problems refused (their start or goal cannot be
planned), the reasons of the other failures, the median and 95th-percentile time per plan (one thread), and
the median joint-space path length and mean squared jerk of the valid plans.
"""
import argparse
import collections
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def quantile(values, q):
    return float(np.quantile(values, q)) if values else float("nan")


def summarise(reports):
    """One row of counts and figures from the reports of some families."""
    row = {"problems": 0, "refused": 0, "valid": 0, "executed": 0, "failures": collections.Counter(), "times": [],
           "lengths": [], "jerks": []}
    for report in reports:
        for problem in report["problems"]:
            row["problems"] += 1
            if problem["status"] == "refused":
                row["refused"] += 1
                row["failures"]["refused"] += 1
                continue
            for sample in problem["samples"]:
                row["times"].append(sample["planning_time_s"])
                if sample["success"]:
                    row["valid"] += 1
                    row["lengths"].append(sample["quality"]["joint_path_length"])
                    row["jerks"].append(sample["quality"]["mean_squared_jerk"])
                    executed = sample.get("executed")
                    if executed is not None and executed["success"]:
                        row["executed"] += 1
                    elif executed is not None:
                        row["failures"]["execution"] += 1
                else:
                    row["failures"][sample["failure"]] += 1
    return row


def figures(row):
    n = max(row["problems"], 1)
    return {
        "problems": row["problems"],
        "valid": row["valid"],
        "valid_share": row["valid"] / n,
        "executed": row["executed"],
        "executed_share": row["executed"] / n,
        "refused": row["refused"],
        "failures": dict(row["failures"]),
        "median_time_ms": 1e3 * quantile(row["times"], 0.5),
        "p95_time_ms": 1e3 * quantile(row["times"], 0.95),
        "median_joint_path_length": quantile(row["lengths"], 0.5),
        "median_mean_squared_jerk": quantile(row["jerks"], 0.5),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", required=True)
    parser.add_argument("--planners", required=True)
    parser.add_argument("--families", required=True)
    args = parser.parse_args()
    planners = args.planners.split(",")
    families = args.families.split(",")
    reports = {}
    for planner in planners:
        for family in families:
            with open(os.path.join(args.root, "test", planner, family + ".json")) as f:
                reports[planner, family] = json.load(f)
    chosen = {}
    for planner in planners:
        with open(os.path.join(args.root, "val", planner, "chosen.json")) as f:
            chosen[planner] = json.load(f)
    summary = {"pooled": {}, "families": {}, "chosen": {p: chosen[p]["variant"] for p in planners}}
    for planner in planners:
        summary["pooled"][planner] = figures(summarise([reports[planner, f] for f in families]))
        summary["families"][planner] = {f: figures(summarise([reports[planner, f]])) for f in families}

    lines = ["# MotionBenchMaker (published Panda problems), test split: problems 21-100 of each family", ""]
    lines.append("Settings chosen on problems 1-20 of each family: " +
                 ", ".join(f"{p} `{chosen[p]['variant']}` ({chosen[p]['arguments']})" for p in planners) + ".")
    lines.append("")
    lines.append("| planner | valid (checker) | valid and executed | refused | other failures | median ms | p95 ms "
                 "| path length (rad) | jerk |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for planner in planners:
        s = summary["pooled"][planner]
        other = ", ".join(f"{k} {v}" for k, v in sorted(s["failures"].items()) if k != "refused") or "none"
        lines.append(f"| {planner} | {s['valid']}/{s['problems']} ({100 * s['valid_share']:.1f} %) | "
                     f"{s['executed']}/{s['problems']} ({100 * s['executed_share']:.1f} %) | {s['refused']} | {other} | "
                     f"{s['median_time_ms']:.3g} | {s['p95_time_ms']:.3g} | {s['median_joint_path_length']:.3g} | "
                     f"{s['median_mean_squared_jerk']:.3g} |")
    lines.append("")
    lines.append("Valid plans per family (of 80 problems each), and median time per plan (ms):")
    lines.append("")
    lines.append("| family | " + " | ".join(planners) + " |")
    lines.append("|---|" + "---|" * len(planners))
    for family in families:
        cells = []
        for planner in planners:
            s = summary["families"][planner][family]
            cells.append(f"{s['valid']}/{s['problems']}, {s['median_time_ms']:.3g} ms")
        lines.append(f"| {family} | " + " | ".join(cells) + " |")
    os.makedirs(os.path.join(args.root, "results"), exist_ok=True)
    out = os.path.join(args.root, "results", "summary.md")
    with open(out + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(out + ".tmp", out)
    out = os.path.join(args.root, "results", "summary.json")
    with open(out + ".tmp", "w") as f:
        json.dump(summary, f, indent=1)
    os.replace(out + ".tmp", out)

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for planner in planners:
        s = summary["pooled"][planner]
        ax.scatter([s["median_time_ms"]], [100 * s["valid_share"]], s=40, label=planner)
        ax.annotate(planner, (s["median_time_ms"], 100 * s["valid_share"]), textcoords="offset points",
                    xytext=(5, 4), fontsize=8)
    ax.set_xscale("log")
    ax.set_xlabel("median time per plan (ms, one thread, log scale)")
    ax.set_ylabel("valid plans (% of test problems)")
    ax.set_title("MotionBenchMaker, Panda, test problems 21-100 of 7 families")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    out = os.path.join(args.root, "results", "success_vs_time.png")
    fig.savefig(out + ".tmp.png", dpi=120)
    os.replace(out + ".tmp.png", out)


if __name__ == "__main__":
    main()
