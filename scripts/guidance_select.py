#!/usr/bin/python3
"""Chooses guidance settings on validation problems and reports them on held-out
test problems, success against time per plan (docs/results.md, "Choosing
guidance on validation problems").

usage: /usr/bin/python3 scripts/guidance_select.py --planner NAME=FILE.pt ... --val VAL.yaml --test TEST.yaml
                                                   --out DIR [--plans 8] [--threads 1] [--warmup 3] [--rows K]
                                                   [--replicate NAME=FILE ...] [--flowplan BINARY]

--planner names an exported planner (`flowplan export`): `fp` (the flow planner
whose settings are chosen), `fp_split` (the same network exported with
splitting) and any others (e.g. `mpd`, `paper_mpd`), which run at their own
settings and the few variants of GRIDS[name]. Every grid changes the exported
file's defaults; its base row is those defaults, so export the flow planner
with the paper's sampler (`sampler.final_iterations=0
sampler.final_spread=0 sampler.final_joint_speed_weight=0`, and
`sampler.splitting=none` or `midpoint`), as scripts/franka_bench.py's select
stage does; an fp or fp_split file with other defaults is refused. VAL and TEST are
`flowplan problems` files drawn with different seeds. Stages:

  1. validation: every setting of every planner's grid on every validation
     problem, `--plans` plans per problem in one call, the same noise for every
     setting of a planner (paired comparisons; best of N draws N times as much); per setting the share of plans
     that succeed and the time per plan (wall time of the call / plans);
  2. selection, on validation only: for each other planner's default setting,
     the FP setting of highest success whose time per plan is at most that
     planner's (FP "at equal time"), and FP's best setting at any time;
  3. test: the chosen settings and every other planner's default on the test
     problems, with other noise, and each planner's budgets (BUDGETS: its
     success-versus-time curve, cheapest first; reported, never chosen from);
  4. other training seeds (`--replicate NAME=FILE`, e.g. the same preset
     trained with seed=1 and exported as NAME's file was): every test row of
     planner NAME planned again with that file, with the same problems and
     noise, nothing chosen again; the report gives each model's success and
     the mean ± sample standard deviation over the models (the --planner file
     first, then the --replicate files of NAME in the order given);
  5. the plan checker (`--flowplan BINARY`): every test row of stages 3 and 4
     but the budgets planned again by `flowplan plan --planner FILE --problems
     TEST -n PLANS --batch PLANS` with the row's settings (other noise: seed 3),
     whose report counts a success as the one plan checker does (docs/planning.md,
     "Valid or nothing": the motion between states too, self-collision and
     floor, joint limits, speeds within 1.0 × the limits); the report gives its
     success and failure kinds beside the state count.

A plan succeeds (whole arm) when every collision sphere of every state stays
outside every obstacle (the planner's own `clearance`, the flowplan kinematics),
the TCP of its last state is within 3 cm of the goal's and the joint speeds its
positions imply stay within 1.5 times the velocity limits (the state count
`arm_clear` of `flowplan plan`'s reports, not the plan checker's success:
stage 5 gives that). Each setting's result is kept in DIR/rows/ and not made again (delete
the folder after changing a planner file); then DIR/validation.json,
DIR/test.json, DIR/selection.md and DIR/success_vs_time.png are written from them.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time

import torch
import yaml

# Settings grids: name -> (label, settings, guide_at, schedule). The first entry is the planner's default.
FP_GRID = [
    ("base: x_t, rising, s 1.75", {}, None, None),
    ("x_t, 1 - t, s 1.75", {}, None, "one_minus_t"),
    ("x_t, 1 - t, s 5", {"guidance.scale": 5.0}, None, "one_minus_t"),
    ("x_t, rising, s 3", {"guidance.scale": 3.0}, None, None),
    ("velocity, 1 - t, s 10", {"guidance.scale": 10.0}, "velocity", "one_minus_t"),
    ("velocity, 1 - t, s 30", {"guidance.scale": 30.0}, "velocity", "one_minus_t"),
    ("velocity, constant, s 10", {"guidance.scale": 10.0}, "velocity", "constant"),
    ("prediction, 1 - t, s 1.75", {}, "prediction", "one_minus_t"),
    ("prediction, 1 - t, s 1.75, G 3", {"sampler.prediction_iterations": 3.0}, "prediction", "one_minus_t"),
    ("prediction, constant, s 1.75, G 3", {"sampler.prediction_iterations": 3.0}, "prediction", "constant"),
    ("prediction, constant from 0.5, s 1.75, G 5",
     {"sampler.prediction_iterations": 5.0, "sampler.guide_from": 0.5}, "prediction", "constant"),
    ("base + end-game G 5", {"sampler.final_iterations": 5.0}, None, None),
    ("base + end-game G 10", {"sampler.final_iterations": 10.0}, None, None),
    ("base + end-game G 5, re-denoise 0.98",
     {"sampler.final_iterations": 5.0, "sampler.final_denoise_time": 0.98}, None, None),
    ("base, 20 steps", {"sampler.steps": 20.0}, None, None),
    ("base, best of 4", {"guidance.candidates": 4.0}, None, None),
    ("base + end-game G 5, best of 4", {"sampler.final_iterations": 5.0, "guidance.candidates": 4.0}, None, None),
    ("prediction, constant, G 3, best of 4",
     {"sampler.prediction_iterations": 3.0, "guidance.candidates": 4.0}, "prediction", "constant"),
    ("base + end-game G 10, re-denoise 0.9",
     {"sampler.final_iterations": 10.0, "sampler.final_denoise_time": 0.9}, None, None),
    ("base + end-game G 10, smoothness 0.2",
     {"sampler.final_iterations": 10.0, "guidance.smoothness_weight": 0.2}, None, None),
    ("prediction, constant from 0.5, G 5 + end-game G 10",
     {"sampler.prediction_iterations": 5.0, "sampler.guide_from": 0.5, "sampler.final_iterations": 10.0},
     "prediction", "constant"),
    ("base + end-game G 10, joint speed 0.1", {"sampler.final_iterations": 10.0, "guidance.joint_speed_weight": 0.1},
     None, None),
    ("base + end-game G 10, joint speed 1", {"sampler.final_iterations": 10.0, "guidance.joint_speed_weight": 1.0},
     None, None),
] + [(f"base + end-game G {g}, spread {l:g}" + (f", end joint speed {w:g}" if w else ""),
      {"sampler.final_iterations": float(g), "sampler.final_spread": float(l), "sampler.final_joint_speed_weight": w},
      None, None)
     for g, l, w in ((10, 4, 0.0), (10, 1, 0.1), (10, 4, 0.1), (10, 16, 0.1), (10, 4, 0.3), (5, 4, 0.1), (20, 4, 0.1))] + [
    # The covariant end-game at other guidance scales and with fewer Euler steps (the scale of the rows above is the
    # preset's 1.75).
    (f"base + end-game G 10, spread {l:g}, end joint speed 0.1, {what}",
     {"sampler.final_iterations": 10.0, "sampler.final_spread": float(l), "sampler.final_joint_speed_weight": 0.1,
      **extra}, None, None)
    for l in (4, 16)
    for what, extra in (("s 1", {"guidance.scale": 1.0}), ("s 2.5", {"guidance.scale": 2.5}),
                        ("5 steps", {"sampler.steps": 5.0}))] + [
    # Below the scale of 1 that the rows above found best, at the spread of 4 that works with splitting too.
    (f"base + end-game G 10, spread 4, end joint speed 0.1, s {scale:g}",
     {"sampler.final_iterations": 10.0, "sampler.final_spread": 4.0, "sampler.final_joint_speed_weight": 0.1,
      "guidance.scale": scale}, None, None)
    for scale in (0.5, 0.75)]
# FP + split: the same planner exported with splitting; its grid adds the re-noise time and midpoint steps.
FP_SPLIT_GRID = [
    ("split base", {}, None, None),
    ("split, re-noise 0.7", {"sampler.split_time": 0.7}, None, None),
    ("split, midpoint G 5", {"sampler.midpoint_iterations": 5.0}, None, None),
    ("split + end-game G 5", {"sampler.final_iterations": 5.0}, None, None),
    ("split, prediction, constant, G 3", {"sampler.prediction_iterations": 3.0}, "prediction", "constant"),
    ("split + end-game G 5, best of 4", {"sampler.final_iterations": 5.0, "guidance.candidates": 4.0}, None, None),
    ("split + end-game G 10", {"sampler.final_iterations": 10.0}, None, None),
    ("split + end-game G 10, re-denoise 0.9",
     {"sampler.final_iterations": 10.0, "sampler.final_denoise_time": 0.9}, None, None),
    ("split + end-game G 10, joint speed 0.1",
     {"sampler.final_iterations": 10.0, "guidance.joint_speed_weight": 0.1}, None, None),
    ("split + end-game G 10, joint speed 1",
     {"sampler.final_iterations": 10.0, "guidance.joint_speed_weight": 1.0}, None, None),
] + [(f"split + end-game G {g}, spread {l:g}, end joint speed {w:g}",
      {"sampler.final_iterations": float(g), "sampler.final_spread": float(l), "sampler.final_joint_speed_weight": w},
      None, None)
     for g, l, w in ((10, 4, 0.1), (5, 4, 0.1), (10, 16, 0.1))] + [
    (f"split + end-game G 10, spread 4, end joint speed 0.1, s {scale:g}",
     {"sampler.final_iterations": 10.0, "sampler.final_spread": 4.0, "sampler.final_joint_speed_weight": 0.1,
      "guidance.scale": scale}, None, None)
    for scale in (0.5, 1.0)]
OTHER_GRID = [
    ("default", {}, None, None),
    ("best of 4", {"guidance.candidates": 4.0}, None, None),
]
MPD_GRID = OTHER_GRID + [("halved noise", {"sampler.ddpm.noise_scale": 0.5}, None, None),
                         # Fewer gradient steps than the default's 60 (5 in each of the last 7 denoising steps and
                         # of 5 noise-free steps after them): 10, one per guided step and 3 noise-free steps.
                         ("10 gradient steps", {"sampler.ddpm.guide_iterations": 1.0, "sampler.ddpm.extra_steps": 3.0},
                          None, None),
                         ("best of 2", {"guidance.candidates": 2.0}, None, None)]
GRIDS = {"fp": FP_GRID, "fp_split": FP_SPLIT_GRID, "mpd": MPD_GRID}
# Each planner's budgets, cheapest first: the settings of its success-versus-time curve on the test problems (role
# "budget"; reported, never chosen from). Labels of its grid.
BUDGETS = {"fp": ["base: x_t, rising, s 1.75"] + [f"base + end-game G {g}, spread 4, end joint speed 0.1"
                                                   for g in (5, 10, 20)],
           "fp_split": ["split base"] + [f"split + end-game G {g}, spread 4, end joint speed 0.1" for g in (5, 10)],
           "mpd": ["10 gradient steps", "default", "best of 2", "best of 4"],
           "paper_mpd": ["default", "best of 4"]}
for _name, _labels in BUDGETS.items():
    assert set(_labels) <= {e[0] for e in GRIDS.get(_name, OTHER_GRID)}, f"BUDGETS[{_name!r}]: not a grid label"
BASE_SCALE = 1.75  # the guidance scale of the FP files, which every FP row without a scale of its own plans at
GOAL_TOLERANCE = 0.03
MAX_SPEED_RATIO = 1.5


def load_problems(path):
    """The problems of a `flowplan problems` file: start and goal states, the goal's TCP, and the scene's spheres
    and boxes as the planner's keyword arguments."""
    problems = yaml.safe_load(open(path))["problems"]
    out = []
    for p in problems:
        scene = p["scene"]
        spheres = [list(s["centre"]) + [s["radius"]] for s in scene.get("spheres", [])]
        # Boxes (K, 10): centre, full side lengths, quaternion (w, x, y, z) (docs/export.md, "Obstacles").
        boxes = [list(b["centre"]) + list(b["size"]) + list(b.get("quaternion", [1.0, 0.0, 0.0, 0.0]))
                 for b in scene.get("boxes", [])]
        unknown = sorted(kind for kind, rows in scene.items() if rows and kind not in ("spheres", "boxes"))
        if unknown:
            sys.exit(f"{path}: problem {p['name']}: scene: {unknown[0]}: only spheres and boxes are read here")
        # States are [q, q̇]: at rest at both ends (as `flowplan plan --start/--goal` makes them).
        out.append({"start": torch.tensor(p["start_q"] + [0.0] * len(p["start_q"]), dtype=torch.float32),
                    "goal": torch.tensor(p["goal_q"] + [0.0] * len(p["goal_q"]), dtype=torch.float32),
                    "goal_tcp": torch.tensor(p["goal_tcp"], dtype=torch.float32),
                    "scene": {"spheres": torch.tensor(spheres, dtype=torch.float32).view(-1, 4),
                              "boxes": torch.tensor(boxes, dtype=torch.float32).view(-1, 10)}})
    return out


def criteria(planner, plans, problem, limits):
    """(clear, at goal, within speed), each (plans,) bool, of raw plans (P, T, D)."""
    J = planner.num_joints
    q = plans[:, :, :J]
    clear = planner.clearance(q, **problem["scene"]).flatten(1).min(1).values > 0.0
    goal = (planner.tcp(q[:, -1]) - problem["goal_tcp"]).norm(dim=-1) <= GOAL_TOLERANCE
    speed = ((q[:, 1:] - q[:, :-1]).abs() / planner.dt / limits).flatten(1).max(1).values <= MAX_SPEED_RATIO
    return clear, goal, speed


def run(planner, grid_entry, problems, plans, seed, limits, warmup=3):
    label, settings, guide_at, schedule = grid_entry
    N = int(settings.get("guidance.candidates", planner.settings["guidance.candidates"]))
    ok, seconds = 0, 0.0
    per_problem = []
    failing = {"collision": 0, "goal": 0, "speed": 0}  # plans failing each criterion (a plan may fail several)
    # Untimed calls first (3 by default). The plans run with the graph executor's optimisations off, as flowplan plans:
    # a freshly loaded file's first calls would otherwise profile and specialise its graphs for seconds, for no gain
    # later (docs/export.md, "The first calls").
    for i, problem in [(-1, problems[0])] * warmup + list(enumerate(problems)):
        generator = torch.Generator().manual_seed(seed * 100003 + i)
        shape = [plans] if N == 1 else [plans, N]
        noise = torch.randn(shape + list(planner.noise_shape), generator=generator)
        renoise = (torch.randn(shape + list(planner.renoise_shape), generator=generator)
                   if len(planner.renoise_shape) > 0 else None)
        start = problem["start"].expand(plans, -1)
        goal = problem["goal"].expand(plans, -1)
        with torch.inference_mode(), torch.jit.optimized_execution(False):
            begin = time.perf_counter()
            out = planner.plan(start, goal, noise, renoise, **problem["scene"], settings=settings,
                               schedule=schedule, guide_at=guide_at)
            seconds += time.perf_counter() - begin
            clear, at_goal, slow = criteria(planner, out, problem, limits)
            good = clear & at_goal & slow
        if i < 0:
            seconds = 0.0
            continue
        for key, passed in (("collision", clear), ("goal", at_goal), ("speed", slow)):
            failing[key] += int((~passed).sum())
        ok += int(good.sum())
        per_problem.append(int(good.sum()))
    total = plans * len(problems)
    return {"label": label, "settings": settings, "guide_at": guide_at, "schedule": schedule,
            "arm_clear": ok / total, "problems_solved": sum(1 for c in per_problem if c > 0) / len(problems),
            "seconds_per_plan": seconds / total, "per_problem": per_problem, "failing": failing}


def cached(path, entry, make, source=None):
    """make()'s JSON, kept in `path`: a row that exists is not made again if it was made with ENTRY's settings
    (grid rows are kept by index; a grid edited since makes the row again, a renamed row takes the new label) and,
    given SOURCE (a --replicate file's identity), from that file."""
    label, settings, guide_at, schedule = entry
    if os.path.exists(path):
        row = json.load(open(path))
        if (row["settings"], row["guide_at"], row["schedule"], row.get("source")) == (settings, guide_at, schedule,
                                                                                     source):
            return row | {"label": label}
    result = make() | ({} if source is None else {"source": source})
    with open(path + ".tmp", "w") as f:
        json.dump(result, f, indent=1)
    os.replace(path + ".tmp", path)
    return result


def identity(path):
    """A file's identity for the row cache: its real path, size and modification time."""
    stat = os.stat(path)
    return f"{os.path.realpath(path)} {stat.st_size} {stat.st_mtime_ns}"


def checked(flowplan, path, grid_entry, problems_file, plans, limit, prefix):
    """The plan checker's count of a setting on a problem file: `flowplan plan --planner PATH --problems FILE` with
    the setting's overrides, one thread, PLANS plans per problem in one call; its report's success rate, state count
    (`arm_clear`), failures by kind and mean time per plan."""
    label, settings, guide_at, schedule = grid_entry
    command = [flowplan, "plan", "--planner", path, "--problems", problems_file, "-n", str(plans), "--batch", str(plans),
               "--seed", "3", "--no-plot", "--out", prefix, "--log-level", "warn", "threads=1",
               *[f"{key}={value:g}" for key, value in settings.items()]]
    command += [f"sampler.guide_at={guide_at}"] if guide_at else []
    command += [f"guidance.schedule={schedule}"] if schedule else []
    command += ["--limit", str(limit)] if limit > 0 else []
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"failed: {' '.join(command)}\n{done.stderr[-2000:]}")
    report = json.load(open(prefix + ".json"))
    samples = [sample for problem in report["problems"] for sample in problem.get("samples", [])]
    total = report["num_problems"] * report["num_samples"]  # a refused problem's plans count as failures
    failures = {"refused": total - len(samples)} if total > len(samples) else {}
    for sample in samples:
        if not sample["success"]:
            failures[sample["failure"]] = failures.get(sample["failure"], 0) + 1
    return {"label": label, "settings": settings, "guide_at": guide_at, "schedule": schedule,
            "success": sum(sample["success"] for sample in samples) / total,
            "arm_clear": sum(sample["arm_clear"] for sample in samples) / total,
            "plans": total, "failures": failures, "refused": report["refused"],
            "seconds_per_plan": statistics.mean(sample["planning_time_s"] for sample in samples) if samples else 0.0}


def wilson(p, n):
    """95 % Wilson interval of a rate p over n trials."""
    z = 1.96
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--planner", action="append", required=True, metavar="NAME=FILE")
    parser.add_argument("--val", required=True)
    parser.add_argument("--test", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--plans", type=int, default=8)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rows", type=int, default=0,
                        help="K > 0: only each grid's first row (the planner's default) and its last K - 1 rows (quick "
                             "runs); 0: every row")
    parser.add_argument("--warmup", type=int, default=3,
                        help="untimed calls before each setting's timed ones (fewer only where times do not matter)")
    parser.add_argument("--limit", type=int, default=0, help="first K problems of each set (0: all)")
    parser.add_argument("--replicate", action="append", default=[], metavar="NAME=FILE",
                        help="another model of planner NAME (another training seed, exported alike): the test rows of "
                             "NAME are planned with it too and reported over the models")
    parser.add_argument("--test-also", action="append", default=[], metavar="NAME:LABEL",
                        help="a grid setting to report on the test problems besides the chosen ones (role \"also\"; "
                             "it takes no part in the choice), e.g. 'fp:base + end-game G 10'")
    parser.add_argument("--flowplan", help="the flowplan binary: stage 5 counts the test rows by its plan checker")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    planners, paths = {}, {}
    for spec in args.planner:
        name, _, path = spec.partition("=")
        if not path or not os.path.isfile(path):
            sys.exit(f"--planner {spec}: expected NAME=FILE of an exported planner")
        planners[name] = torch.jit.load(path)
        paths[name] = path
    if "fp" not in planners:
        sys.exit("--planner: expected fp=FILE, the flow planner whose settings are chosen")
    paper_sampler = ("sampler.final_iterations", "sampler.final_spread", "sampler.final_joint_speed_weight")
    replicates = {}  # name -> [(planner, identity: path, size, time) of each --replicate file of it, in order]
    for spec in args.replicate:
        name, _, path = spec.partition("=")
        if name not in planners or not os.path.isfile(path):
            sys.exit(f"--replicate {spec}: expected NAME=FILE, NAME one of the --planner names "
                     f"({', '.join(planners)}) and FILE an exported planner")
        replicates.setdefault(name, []).append((torch.jit.load(path), identity(path)))  # a row is kept for its file
        paths.setdefault(f"{name} replicates", []).append(path)
    # The FP grids add end-game steps to the file's defaults: a file whose defaults already hold an end-game, a
    # spread or its hinge would turn their rows into other settings than their labels say.
    loaded = [(f"--planner {n}", n, planners[n]) for n in planners] + [
        (f"--replicate {n} (model {m})", n, p) for n, ps in replicates.items() for m, (p, _) in enumerate(ps, start=2)]
    for where, name, planner in loaded:
        if name in ("fp", "fp_split"):
            # the grids' rows without a scale of their own are labelled and chosen at the file's 1.75
            if planner.settings["guidance.scale"] != BASE_SCALE:
                sys.exit(f"{where}: exported with guidance.scale={planner.settings['guidance.scale']:g}; the FP grids "
                         f"take {BASE_SCALE:g} as their base (export with guidance.scale={BASE_SCALE:g})")
            other = [f"{key}={planner.settings[key]:g}" for key in paper_sampler if planner.settings[key] != 0.0]
            if other:
                sys.exit(f"{where}: exported with {', '.join(other)}; export the flow planner with the paper's "
                         f"sampler ({' '.join(key + '=0' for key in paper_sampler)}), the FP grids' base")
    test_also = []
    for spec in args.test_also:
        name, _, label = spec.partition(":")
        if name not in planners or label not in [e[0] for e in GRIDS.get(name, OTHER_GRID)]:
            sys.exit(f"--test-also {spec}: expected PLANNER:LABEL of a grid setting of a given planner")
        test_also.append((name, label))
    os.makedirs(args.out, exist_ok=True)
    val, test = load_problems(args.val), load_problems(args.test)
    if args.limit > 0:
        val, test = val[:args.limit], test[:args.limit]
    limits = {name: torch.tensor(yaml.safe_load(p.robot_description)["velocity_limit"], dtype=torch.float32)
              for name, p in planners.items()}

    def validate():
        out = {"problems": len(val), "plans_per_problem": args.plans, "threads": args.threads, "planners": {}}
        for name, planner in planners.items():
            rows = []
            grid = GRIDS.get(name, OTHER_GRID)
            for k, entry in enumerate(grid):
                if args.rows > 0 and 0 < k < len(grid) - (args.rows - 1):
                    continue  # the rows run keep their indices (their files are named by them)
                rows.append(cached(os.path.join(args.out, "rows", f"validation_{name}_{k}.json"), entry,
                                   lambda: run(planner, entry, val, args.plans, 1, limits[name], args.warmup)))
                r = rows[-1]
                print(f"validation {name} | {r['label']}: {r['arm_clear']:.1%} of plans, "
                      f"{r['problems_solved']:.0%} of problems, {1e3 * r['seconds_per_plan']:.1f} ms/plan", flush=True)
            out["planners"][name] = rows
        return out

    os.makedirs(os.path.join(args.out, "rows"), exist_ok=True)
    validation = validate()
    fp_names = [n for n in planners if n.startswith("fp")]
    others = [n for n in planners if not n.startswith("fp")]
    fp_rows = [(n, r) for n in fp_names for r in validation["planners"][n]]
    best_any = max(fp_rows, key=lambda nr: (nr[1]["arm_clear"], -nr[1]["seconds_per_plan"]))
    chosen = {"fp_best": {"planner": best_any[0], "label": best_any[1]["label"]}}
    for other in others:
        budget = validation["planners"][other][0]["seconds_per_plan"]
        within = [nr for nr in fp_rows if nr[1]["seconds_per_plan"] <= budget]
        if within:
            pick = max(within, key=lambda nr: (nr[1]["arm_clear"], -nr[1]["seconds_per_plan"]))
            chosen[f"fp_within_{other}_time"] = {"planner": pick[0], "label": pick[1]["label"]}

    def held_out():
        out = {"problems": len(test), "plans_per_problem": args.plans, "threads": args.threads, "chosen": chosen,
               "rows": []}
        runs = {}
        for key, pick in chosen.items():
            runs[(pick["planner"], pick["label"])] = key
        for other in others:
            runs[(other, GRIDS.get(other, OTHER_GRID)[0][0])] = f"{other}_default"
        runs.setdefault((fp_names[0], GRIDS[fp_names[0]][0][0]), "fp_default")
        for name, label in test_also:  # reported on test, never chosen from it
            runs.setdefault((name, label), "also")
        for name in planners:  # each planner's curve over its budgets, on test; never chosen from
            for label in BUDGETS.get(name, []):
                runs.setdefault((name, label), "budget")
        # Each run's grid entry and its index in the grid (rows are kept by it).
        entries = [(name, label, key) + next((k, e) for k, e in enumerate(GRIDS.get(name, OTHER_GRID)) if e[0] == label)
                   for (name, label), key in runs.items()]
        for name, label, key, k, entry in entries:
            row = dict(cached(os.path.join(args.out, "rows", f"test_{name}_{k}.json"), entry,
                              lambda: run(planners[name], entry, test, args.plans, 2, limits[name], args.warmup)))
            row |= {"planner": name, "role": key}
            out["rows"].append(row)
            print(f"test {key} ({name} | {label}): {row['arm_clear']:.1%} of plans, {row['problems_solved']:.0%} "
                  f"of problems, {1e3 * row['seconds_per_plan']:.1f} ms/plan", flush=True)
        # Stage 4: the same rows with the other models of a planner (model 2, 3, ...; model 1 is the row above).
        out["replicate_rows"] = []
        for name, label, key, k, entry in entries:
            if key == "budget":
                continue  # the curves are of model 1 only
            for m, (planner, source) in enumerate(replicates.get(name, []), start=2):
                row = dict(cached(os.path.join(args.out, "rows", f"test_{name}_model{m}_{k}.json"), entry,
                                  lambda: run(planner, entry, test, args.plans, 2, limits[name], args.warmup), source))
                row |= {"planner": name, "role": key, "model": m}
                out["replicate_rows"].append(row)
                print(f"test {key} ({name} | {label}), model {m}: {row['arm_clear']:.1%} of plans, "
                      f"{1e3 * row['seconds_per_plan']:.1f} ms/plan", flush=True)
        # Stage 5: the same rows (not the budgets) counted by the plan checker, through `flowplan plan --problems`.
        out["checked_rows"] = []
        for name, label, key, k, entry in entries if args.flowplan else []:
            if key == "budget":
                continue
            files = [(1, paths[name])] + [(m, path) for m, path in enumerate(paths.get(f"{name} replicates", []),
                                                                              start=2)]
            for m, path in files:
                stem = os.path.join(args.out, "rows", f"checked_{name}_model{m}_{k}")
                # kept for the same planner file, problem file, checker binary and plan count
                source = " ".join([identity(path), identity(args.test), identity(args.flowplan),
                                   f"plans {args.plans} limit {args.limit}"])
                row = dict(cached(stem + ".json", entry, lambda: checked(args.flowplan, path, entry, args.test,
                                                                          args.plans, args.limit, stem + "_plans"),
                                  source))
                row |= {"planner": name, "role": key, "model": m}
                out["checked_rows"].append(row)
                print(f"test {key} ({name} | {label}), model {m}, plan checker: {row['success']:.1%} of plans "
                      f"(state count {row['arm_clear']:.1%}), {1e3 * row['seconds_per_plan']:.1f} ms/plan", flush=True)
        return out

    test_result = held_out()
    for name, content in (("validation.json", validation), ("test.json", test_result)):
        with open(os.path.join(args.out, name + ".tmp"), "w") as f:
            json.dump(content, f, indent=1)
        os.replace(os.path.join(args.out, name + ".tmp"), os.path.join(args.out, name))
    write_report(args.out, validation, test_result)


def over_models(test_result):
    """The test rows of the planners given other models (--replicate): each model's success and time, then the
    mean ± sample standard deviation of success over the models; [] without replicates."""
    extra = test_result.get("replicate_rows", [])
    if not extra:
        return []
    models = max(r["model"] for r in extra)
    lines = ["", f"Test over models (model 1 is the --planner file, models 2–{models} the --replicate files, e.g. "
             "other training seeds; the same problems and noise): success (whole arm), time per plan in ms.", "",
             "| role | planner | setting | " + " | ".join(f"model {m}" for m in range(1, models + 1)) +
             " | mean ± std over models |", "|---|---|---|" + "---|" * (models + 1)]
    for r in test_result["rows"]:
        rows = [r] + sorted((x for x in extra if (x["planner"], x["role"], x["label"]) ==
                             (r["planner"], r["role"], r["label"])), key=lambda x: x["model"])
        if len(rows) == 1:
            continue
        rates = [x["arm_clear"] for x in rows]
        spread = (f"{statistics.mean(rates):.1%} ± {statistics.stdev(rates):.1%}, "
                  f"{1e3 * statistics.mean(x['seconds_per_plan'] for x in rows):.1f}")
        cells = [f"{x['arm_clear']:.1%}, {1e3 * x['seconds_per_plan']:.1f}" for x in rows]
        cells += [""] * (models - len(rows))  # a planner given fewer models
        lines.append(f"| {r['role']} | {r['planner']} | {r['label']} | " + " | ".join(cells) + f" | {spread} |")
    return lines


def by_checker(test_result):
    """The test rows counted by the plan checker (stage 5): per row and model its success, the state count and the
    time per plan, then the mean ± sample standard deviation of success over the models; and the failures by kind,
    summed over the models. [] without --flowplan."""
    checked_rows = test_result.get("checked_rows", [])
    if not checked_rows:
        return []
    models = max(r["model"] for r in checked_rows)
    lines = ["", "Test, counted by the plan checker (`flowplan plan --problems`: states and the motion between them, "
             "self-collision and floor, joint limits, speeds within 1.0 × the limits; other noise than the rows "
             "above): success (state count), time per plan in ms; failures by kind over all models.", "",
             "| role | planner | setting | " + " | ".join(f"model {m}" for m in range(1, models + 1)) +
             " | mean ± std over models | failures |", "|---|---|---|" + "---|" * (models + 2)]
    for r in test_result["rows"]:
        rows = sorted((x for x in checked_rows if (x["planner"], x["role"], x["label"]) ==
                       (r["planner"], r["role"], r["label"])), key=lambda x: x["model"])
        if not rows:
            continue
        rates = [x["success"] for x in rows]
        spread = f"{statistics.mean(rates):.1%}" + (f" ± {statistics.stdev(rates):.1%}" if len(rates) > 1 else "")
        cells = [f"{x['success']:.1%} ({x['arm_clear']:.1%}), {1e3 * x['seconds_per_plan']:.1f}" for x in rows]
        cells += [""] * (models - len(rows))
        failures = {}
        for x in rows:
            for kind, count in x["failures"].items():
                failures[kind] = failures.get(kind, 0) + count
        kinds = ", ".join(f"{kind} {count}" for kind, count in sorted(failures.items(), key=lambda kc: -kc[1]))
        lines.append(f"| {r['role']} | {r['planner']} | {r['label']} | " + " | ".join(cells) +
                     f" | {spread} | {kinds or 'none'} |")
    return lines


def write_report(out, validation, test_result):
    lines = [f"Validation: {validation['problems']} problems x {validation['plans_per_problem']} plans, "
             f"{validation['threads']} thread(s).", "",
             "| planner | setting | success (whole arm) | 95 % interval | problems solved | time per plan (ms) "
             "| plans failing: collision / goal / speed |",
             "|---|---|---|---|---|---|---|"]
    n = validation["problems"] * validation["plans_per_problem"]

    def failing(r):  # rows made before the counts were kept have none
        return " / ".join(str(r["failing"][k]) for k in ("collision", "goal", "speed")) if "failing" in r else ""

    for name, rows in validation["planners"].items():
        for r in rows:
            lo, hi = wilson(r["arm_clear"], n)
            lines.append(f"| {name} | {r['label']} | {r['arm_clear']:.1%} | {lo:.1%}–{hi:.1%} | "
                         f"{r['problems_solved']:.0%} | {1e3 * r['seconds_per_plan']:.1f} | {failing(r)} |")
    n = test_result["problems"] * test_result["plans_per_problem"]
    lines += ["", f"Test (held out): {test_result['problems']} problems x {test_result['plans_per_problem']} plans.", "",
              "| role | planner | setting | success (whole arm) | 95 % interval | problems solved | time per plan (ms) "
              "| plans failing: collision / goal / speed |",
              "|---|---|---|---|---|---|---|---|"]
    for r in test_result["rows"]:
        lo, hi = wilson(r["arm_clear"], n)
        lines.append(f"| {r['role']} | {r['planner']} | {r['label']} | {r['arm_clear']:.1%} | {lo:.1%}–{hi:.1%} | "
                     f"{r['problems_solved']:.0%} | {1e3 * r['seconds_per_plan']:.1f} | {failing(r)} |")
    curves = [(name, label) for name, labels in BUDGETS.items() for label in labels]
    by_key = {(r["planner"], r["label"]): r for r in test_result["rows"]}
    if any(key in by_key for key in curves):
        lines += ["", "Test, each planner's budgets (its success-versus-time curve; cheapest first):", "",
                  "| planner | budget | success (whole arm) | time per plan (ms) |", "|---|---|---|---|"]
        for key in curves:
            if key in by_key:
                r = by_key[key]
                lines.append(f"| {key[0]} | {key[1]} | {r['arm_clear']:.1%} | {1e3 * r['seconds_per_plan']:.1f} |")
    lines += over_models(test_result)
    lines += by_checker(test_result)
    with open(os.path.join(out, "selection.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5), sharey=True)
    colours = {name: f"C{i}" for i, name in enumerate(validation["planners"])}
    for name, rows in validation["planners"].items():
        points = sorted((1e3 * r["seconds_per_plan"], 100 * r["arm_clear"]) for r in rows)
        axes[0].scatter([x for x, _ in points], [y for _, y in points], s=16, color=colours[name], alpha=0.5)
        # The planner's curve: its best success at each time per plan or less (one point per budget).
        front, best = [], -1.0
        for x, y in points:
            if y > best:
                front.append((x, y))
                best = y
        axes[0].step([x for x, _ in front], [y for _, y in front], where="post", color=colours[name], label=name)
    # Test points are numbered, and the numbers explained below the panel (labels beside close points overlap).
    for k, r in enumerate(test_result["rows"]):
        axes[1].scatter([1e3 * r["seconds_per_plan"]], [100 * r["arm_clear"]], color=colours[r["planner"]], s=24)
        axes[1].annotate(str(k + 1), (1e3 * r["seconds_per_plan"], 100 * r["arm_clear"]), fontsize=8,
                         xytext=(3, 3), textcoords="offset points")
    for name in validation["planners"]:  # each planner's budgets, cheapest first, as a line
        by_label = {r["label"]: r for r in test_result["rows"] if r["planner"] == name}
        curve = [by_label[label] for label in BUDGETS.get(name, []) if label in by_label]
        if len(curve) > 1:
            axes[1].plot([1e3 * r["seconds_per_plan"] for r in curve], [100 * r["arm_clear"] for r in curve],
                         color=colours[name], linewidth=1, label=f"{name}: its budgets")
    for r in test_result.get("replicate_rows", []):  # other training seeds: crosses
        axes[1].scatter([1e3 * r["seconds_per_plan"]], [100 * r["arm_clear"]], color=colours[r["planner"]], s=24,
                        marker="x")
    axes[1].text(0.02, 0.02, "\n".join(f"{k + 1}: {r['planner']}: {r['label']}" for k, r in enumerate(test_result["rows"])),
                 transform=axes[1].transAxes, fontsize=7, va="bottom")
    axes[0].set_title("validation: every setting; line: best within a time", fontsize=10)
    axes[1].set_title("held-out test: chosen settings, defaults; lines: each planner's budgets", fontsize=10)
    axes[1].legend(fontsize=7, loc="lower right")
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("time per plan (ms, log; 1 thread)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8, loc="lower right")
    axes[0].set_ylabel("plans that succeed, whole arm (%)")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "success_vs_time.png"), dpi=110)


if __name__ == "__main__":
    main()
