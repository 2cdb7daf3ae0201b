#!/usr/bin/env python3
"""What a guidance step and a guided plan at B = 1 cost, for exported planners
side by side on the same problems: for each problem of a `flowplan problems`
file (the scene families' YAML), one guidance gradient (`sampler.guide.gradient`
at a plan of the planner) and one whole plan (`plan`, the export's settings,
the problem's obstacles), timed round-robin between the planners (the median
of `--repeats` calls each, after warm-up) on `--threads` threads. Prints each
planner's median over the problems and the ratios to the first.

usage: /usr/bin/python3 bench/guidance_latency.py --problems FILE [--count N]
       [--repeats R] [--threads T] PLANNER.pt [PLANNER.pt ...]

Exports with native kernels need libflowplan_kernels (`--kernels LIB`, default
build/kernels/libflowplan_kernels.so). docs/performance.md ("The native
guidance step") has the figures.
"""
import argparse
import statistics
import time

import torch
import yaml


def scene_rows(scene, kind):
    """A family problem's obstacles of one kind as the planner's rows (K, columns), or None."""
    rows = []
    for shape in scene.get(kind, []):
        if kind == "boxes":
            rows.append(shape["centre"] + shape["size"] + shape["quaternion"])
        elif kind == "cylinders":
            rows.append(shape["centre"] + [shape["radius"], shape["height"]] + shape["quaternion"])
        elif kind == "spheres":
            rows.append(shape["centre"] + [shape["radius"]])
        else:
            rows.append(shape["a"] + shape["b"] + [shape["radius"]])
    return torch.tensor(rows, dtype=torch.float32) if rows else None


def median_time(call, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("planners", nargs="+")
    parser.add_argument("--problems", required=True)
    parser.add_argument("--count", type=int, default=10)
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--kernels", default="build/kernels/libflowplan_kernels.so")
    args = parser.parse_args()
    torch.ops.load_library(args.kernels)
    torch.set_num_threads(args.threads)
    planners = [torch.jit.load(path) for path in args.planners]
    problems = yaml.safe_load(open(args.problems))["problems"][:args.count]
    gradient = [[] for _ in planners]
    plan = [[] for _ in planners]
    generator = torch.Generator().manual_seed(0)
    with torch.no_grad():
        for problem in problems:
            J = len(problem["start_q"])
            start = torch.tensor(problem["start_q"] + [0.0] * J).view(1, 2 * J)
            goal = torch.tensor(problem["goal_q"] + [0.0] * J).view(1, 2 * J)
            noise = torch.randn(1, 64, 2 * J, generator=generator)
            kinds = {kind: scene_rows(problem["scene"], kind) for kind in ("spheres", "boxes", "cylinders", "capsules")}
            for _ in range(3):  # warm-up, every planner
                for planner in planners:
                    planner.plan(start, goal, noise, **kinds)
            for i, planner in enumerate(planners):
                scene = planner.call_scene(None, kinds["spheres"], kinds["boxes"], kinds["cylinders"], kinds["capsules"])
                scene = {kind: rows for kind, rows in scene.items()}
                opts = planner.call_settings(None, None)
                x = planner.normalize(planner.plan(start, goal, noise, **kinds))
                gradient[i].append(median_time(lambda: planner.sampler.guide.gradient(x, scene, opts), args.repeats))
            for i, planner in enumerate(planners):
                plan[i].append(median_time(lambda: planner.plan(start, goal, noise, **kinds), args.repeats))
    print(f"{len(problems)} problems of {args.problems}, {args.threads} thread(s), medians of {args.repeats} calls")
    first_gradient = statistics.median(gradient[0])
    first_plan = statistics.median(plan[0])
    for i, path in enumerate(args.planners):
        g = statistics.median(gradient[i])
        p = statistics.median(plan[i])
        print(f"{path}: guidance gradient {g * 1e3:.3f} ms (the first / this: {first_gradient / g:.2f}), "
              f"plan {p * 1e3:.2f} ms (the first / this: {first_plan / p:.2f})")


if __name__ == "__main__":
    main()
