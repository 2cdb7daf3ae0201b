#!/usr/bin/env python3
"""Every planner on every problem of a problem file (`flowplan problems`, with or
without --family, or `flowplan scenes import`).

For each planner, one `flowplan plan --problems` call plans every problem in its
own scene (-n plans each, --execute) with the planner loaded once, and keeps its
report in OUT/<planner>/plans.json and .h5 (refused problems are a status in it);
a planner whose report exists is not planned again, so an interrupted run
continues with the next planner. Then writes OUT/summary.json and OUT/summary.md:
per planner, the states-only counts of `flowplan plan` over all plans (TCP, whole
arm; each also requiring the goal within 3 cm and speeds within 1.5 times the
limits), the plan checker's successes and those executed in MuJoCo, the share of
problems with at least one whole-arm clear plan, and the planning time.

usage: franka_problems.py PROBLEMS.yaml [--run RUN] [--config CONFIG] [--out OUT]
                          [--planners fp,fp_split,rrt_connect] [--samples N] [--limit K]
                          [--set KEY=VALUE ...]   (config overrides for every `flowplan plan` call)
                          [--planner NAME="ARGS" ...]
--planner names a planner and the `flowplan plan` arguments that choose it,
e.g. --planner mpd="--ckpt runs/reach_mpd"; given at least once, it replaces
--planners (whose fp, fp_split and rrt_connect come from --run and --config).
"""
import argparse
import json
import os
import shlex
import subprocess
import sys

LABELS = {"fp": "FP", "fp_split": "FP + split", "rrt_connect": "RRT-Connect", "mpd": "MPD", "vae": "VAE planner"}
WAYS = [("tcp_clear_rate", "TCP"), ("arm_clear_rate", "whole arm"), ("success_rate", "valid"),
        ("success_rate_executed", "executed")]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("problems")
    parser.add_argument("--run", default="runs/franka_reach")
    parser.add_argument("--config", default="configs/franka_reach.yaml")
    parser.add_argument("--out", default=None)
    parser.add_argument("--planners", default="fp,fp_split,rrt_connect")
    parser.add_argument("--samples", type=int, default=8)
    parser.add_argument("--limit", type=int, default=0, help="first K problems only (0: all)")
    parser.add_argument("--flowplan", default=os.environ.get("FLOWPLAN", "build/apps/flowplan/flowplan"))
    parser.add_argument("--planner", action="append", default=[], metavar='NAME="ARGS"',
                        help="a planner and its `flowplan plan` arguments (replaces --planners)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="config override for every planner call, e.g. data.path=... for RRT-Connect's robot")
    args = parser.parse_args()
    out = args.out or os.path.join(args.run, "problems")
    sources = {"fp": ["--ckpt", args.run],
               "fp_split": ["--ckpt", args.run, "sampler.splitting=midpoint"],
               "rrt_connect": ["--rrt-connect", "--config", args.config]}
    if args.planner:
        sources = {}
        for spec in args.planner:
            name, _, planner_args = spec.partition("=")
            if not name or not planner_args:
                sys.exit(f'--planner {spec!r}: expected NAME="ARGS"')
            sources[name] = shlex.split(planner_args)
        planners = list(sources)
    else:
        planners = args.planners.split(",")
    for planner in planners:
        if planner not in sources:
            sys.exit(f"--planners: unknown planner {planner} (known: {', '.join(sources)})")
    for planner in planners:
        prefix = os.path.join(out, planner, "plans")
        if os.path.exists(prefix + ".json"):
            continue
        os.makedirs(os.path.dirname(prefix), exist_ok=True)
        command = [args.flowplan, "plan", *sources[planner], "--problems", args.problems, "--limit", str(args.limit),
                   "-n", str(args.samples), "--seed", "1", "--execute", "--log-level", "warn", "--out", prefix,
                   *args.set]
        done = subprocess.run(command, capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"{planner}: {' '.join(command)}\n{done.stderr}{done.stdout}")
        print(f"{planner}: every problem planned", flush=True)
    summarize(out, planners)


def summarize(out, planners):
    summary = {"planners": {}}
    lines = ["| planner | problems | TCP | whole arm | valid | executed | problems solved (arm) | "
             "planning time (s, median) |", "|---|---|---|---|---|---|---|---|"]
    for planner in planners:
        report = json.load(open(os.path.join(out, planner, "plans.json")))
        summary["problems"] = report["num_problems"]
        solved = sum(1 for p in report["problems"] if any(s["arm_clear"] for s in p["samples"]))
        times = sorted(s["planning_time_s"] for p in report["problems"] for s in p["samples"])
        plans = report["planned"] * report["num_samples"]
        row = {key: report.get(key, 0.0) for key, _ in WAYS}
        row |= {"problems_solved_arm": solved / report["num_problems"], "refused": report["refused"],
                "planning_time_s_median": times[len(times) // 2] if times else None,
                # the planning wall time of every call (checks and execution excluded) over the plans it made
                "planning_time_s_per_plan": report["wall_time_s"] / plans if plans else None}
        summary["planners"][planner] = row
        lines.append(f"| {LABELS.get(planner, planner)} | {report['num_problems']} | " +
                     " | ".join(f"{row[key]:.0%}" for key, _ in WAYS) +
                     f" | {row['problems_solved_arm']:.0%} | {row['planning_time_s_median']:.3f} |")
    text = "\n".join(lines) + "\n"
    for name, content in (("summary.md", text), ("summary.json", json.dumps(summary, indent=1))):
        with open(os.path.join(out, name + ".tmp"), "w") as f:
            f.write(content)
        os.replace(os.path.join(out, name + ".tmp"), os.path.join(out, name))
    print(text)


if __name__ == "__main__":
    main()
