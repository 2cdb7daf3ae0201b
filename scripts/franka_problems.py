#!/usr/bin/env python3
"""Every planner on every problem of a problem file (`flowplan problems`, with or
without --family, or `flowplan scenes import`).

For each problem and planner, runs `flowplan plan` (joint start and goal, the
problem's scene, --execute) and keeps its JSON report in
OUT/<planner>/<i>.json; a report that exists is not made again, so an
interrupted run continues where it stopped. Then writes OUT/summary.json and
OUT/summary.md: per planner, the success rate over all plans counted three
ways (TCP, whole arm, executed in MuJoCo; each also requiring the goal within
3 cm and feasible speeds, as in `flowplan plan`), the share of problems with
at least one successful plan (whole arm), and the median planning time.

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

import yaml

LABELS = {"fp": "FP", "fp_split": "FP + split", "rrt_connect": "RRT-Connect", "mpd": "MPD", "vae": "VAE planner"}
WAYS = [("tcp_clear_rate", "TCP"), ("arm_clear_rate", "whole arm"), ("success_rate_executed", "executed")]


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
    problems = yaml.safe_load(open(args.problems))["problems"]
    if args.limit > 0:
        problems = problems[: args.limit]
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
        os.makedirs(os.path.join(out, planner), exist_ok=True)
    os.makedirs(os.path.join(out, "scenes"), exist_ok=True)

    for i, problem in enumerate(problems):
        scene = os.path.join(out, "scenes", f"{i}.yaml")
        if not os.path.exists(scene):
            with open(scene + ".tmp", "w") as f:
                yaml.safe_dump({kind: shapes for kind, shapes in problem["scene"].items() if shapes}, f)
            os.replace(scene + ".tmp", scene)
        for planner in planners:
            prefix = os.path.join(out, planner, str(i))
            if os.path.exists(prefix + ".json") or os.path.exists(prefix + ".refused"):
                continue
            command = [args.flowplan, "plan", *sources[planner],
                       "--start", ",".join(repr(q) for q in problem["start_q"]),
                       "--goal", ",".join(repr(q) for q in problem["goal_q"]),
                       "--scene", scene, "-n", str(args.samples), "--seed", "1", "--execute", "--no-plot",
                       "--log-level", "warn", "--out", prefix, *args.set]
            done = subprocess.run(command, capture_output=True, text=True)
            if done.returncode != 0:
                if "inside obstacle" in done.stderr + done.stdout:
                    with open(prefix + ".refused.tmp", "w") as f:
                        f.write(done.stderr + done.stdout)
                    os.replace(prefix + ".refused.tmp", prefix + ".refused")
                else:
                    sys.exit(f"problem {i}, {planner}: {' '.join(command)}\n{done.stderr}{done.stdout}")
        print(f"problem {i + 1}/{len(problems)} done", flush=True)
    summarize(out, planners, len(problems))


def summarize(out, planners, count):
    summary = {"problems": count, "planners": {}}
    lines = ["| planner | problems | TCP | whole arm | executed | problems solved (arm) | planning time (s, median) |",
             "|---|---|---|---|---|---|---|"]
    for planner in planners:
        rates = {key: [] for key, _ in WAYS}
        solved, times, refused, wall, plans = 0, [], 0, 0.0, 0
        for i in range(count):
            prefix = os.path.join(out, planner, str(i))
            if os.path.exists(prefix + ".refused"):
                refused += 1
                for key, _ in WAYS:
                    rates[key].append(0.0)
                continue
            report = json.load(open(prefix + ".json"))
            for key, _ in WAYS:
                rates[key].append(report[key])
            solved += report["arm_clear_rate"] > 0
            times += [s["planning_time_s"] for s in report["samples"]]
            wall += report["wall_time_s"]
            plans += report["num_samples"]
        row = {key: sum(values) / len(values) for key, values in rates.items()}
        row |= {"problems_solved_arm": solved / count, "refused": refused,
                "planning_time_s_median": sorted(times)[len(times) // 2] if times else None,
                # the planning wall time of every call (execution excluded) over the plans it made
                "planning_time_s_per_plan": wall / plans if plans else None}
        summary["planners"][planner] = row
        lines.append(f"| {LABELS.get(planner, planner)} | {count} | " + " | ".join(f"{row[key]:.0%}" for key, _ in WAYS) +
                     f" | {row['problems_solved_arm']:.0%} | {row['planning_time_s_median']:.3f} |")
    text = "\n".join(lines) + "\n"
    for name, content in (("summary.md", text), ("summary.json", json.dumps(summary, indent=1))):
        with open(os.path.join(out, name + ".tmp"), "w") as f:
            f.write(content)
        os.replace(os.path.join(out, name + ".tmp"), os.path.join(out, name))
    print(text)


if __name__ == "__main__":
    main()
