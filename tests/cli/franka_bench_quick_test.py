#!/usr/bin/env python3
"""scripts/franka_bench.py --quick end to end, then what a stopped or repeated run does.

usage: franka_bench_quick_test.py FLOWPLAN_BINARY SCRATCH_DIR

1. The quick run fills every table (both stitching tables, the radius sweep of
   all five planners, the guidance-scale sweep, the random scenes, the scene
   families with guidance chosen on validation problems) and the independent
   recount agrees with flowplan's counts.
2. Run again, it redoes nothing but the recount and the tables, also with the
   output folder moved; an output made by another request (a changed command,
   config or model) is made again; a row trained by another request stops every
   stage that trains or uses it with a message naming it, and the tables leave
   out what it made. A request counts what a YAML file says, not its comments.
3. Stitching rows evaluated again from their checkpoints give the same
   figures; --rows limits a stage to the rows it names and refuses an unknown one.
4. A training row stopped after its first checkpoint resumes from it (not from
   scratch) and ends at the full step count.
5. The recount is not blind: a report with one success flag flipped, or plans
   changed under their report, are caught.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys

import h5py
import numpy
import yaml

flowplan, scratch = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
repo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
root = os.path.join(scratch, "bench")
shutil.rmtree(root, ignore_errors=True)


def bench(*extra):
    done = subprocess.run([sys.executable, os.path.join(repo, "scripts", "franka_bench.py"), "--quick", "--root", root,
                           "--flowplan", flowplan, *extra], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done.stdout


def log_commands():
    with open(os.path.join(root, "bench.log")) as f:
        return [line for line in f if line.startswith("$ ")]


# 1. Every table filled; the recount agrees.
bench()
summary = json.load(open(os.path.join(root, "results", "summary.json")))
for table in ("table1", "table2"):
    assert len(summary[table]) == 5 and all(v is not None for v in summary[table].values()), summary[table]
for label, value in summary["table2"].items():
    assert len(value["seeds"]) == 3, (label, value)
planners = ["mpd", "vae", "fp", "fp_split", "rrt_connect"]
cells = {(c["planner"], c["radius"]) for c in summary["sweep"]}
assert cells == {(p, r) for p in planners for r in (0.0, 0.1, 0.2, 0.3)}, sorted(cells)
assert len(summary["scales"]) == 2, summary["scales"]
assert {(c["planner"], c["radius"]) for c in summary["budget"]} == {
    (name, r) for name in ("mpd_g10", "mpd_paper_weights") for r in (0.0, 0.1, 0.2, 0.3)}, summary["budget"]
# The paper's count (TCP clear and at the goal, any joint speed) from the per-plan flags of each report: never
# below the TCP count with the speed limit, and equal to it where no plan breaks the limit.
for c in summary["sweep"]:
    if c["refused"]:
        continue
    report = json.load(open(os.path.join(root, "sweep", f"{c['planner']}_r{c['radius']:g}.json")))
    plans = report["samples"]
    clear = [not p["tcp_collision"] and p["goal_distance"] <= report["goal_tolerance"] for p in plans]
    assert c["tcp_clear_rate_any_speed"] == sum(clear) / len(plans), c
    assert c["tcp_clear_rate_any_speed"] >= c["tcp_clear_rate"], c
    if all(p["feasible"] for p in plans):
        assert c["tcp_clear_rate_any_speed"] == c["tcp_clear_rate"], c
assert all(f"{p}/TCP, any speed" in summary["largest_radius_90"] for p in planners), summary["largest_radius_90"]
# The tables' aggregates, recomputed here: a seeded row is the mean of its seeds' report means ± their sample
# standard deviation; the largest radius is the last of the radii from 0 up that all reach 90 %.
for label, value in list(summary["table1"].items()) + list(summary["table2"].items()):
    if "seeds" not in value:
        continue
    means = [json.load(open(os.path.join(root, "stitching", f"{row}.json")))["test"]["mean"] for row in value["seeds"]]
    assert abs(value["mean_of_seeds"] - statistics.mean(means)) < 1e-9, (label, value, means)
    assert abs(value["std_of_seed_means"] - statistics.stdev(means)) < 1e-9, (label, value, means)
for p in planners:
    for key, way in [("tcp_clear_rate", "TCP"), ("arm_clear_rate", "whole arm"),
                     ("success_rate_executed", "executed"), ("tcp_clear_rate_any_speed", "TCP, any speed")]:
        rates = {c["radius"]: (0.0 if c["refused"] else c[key]) for c in summary["sweep"] if c["planner"] == p}
        reached = [r for r in sorted(rates) if all(rates[q] >= 0.9 for q in sorted(rates) if q <= r)]
        assert summary["largest_radius_90"][f"{p}/{way}"] == (reached[-1] if reached else None), (p, way, rates)
assert sorted(summary["problems"]["planners"]) == sorted(planners), summary["problems"]
assert summary["recount"]["differ"] == 0 and summary["recount"]["plans"] > 0, summary["recount"]
# RRT-Connect checks the whole arm itself: at 0.1 m every plan it returns is clear.
rrt = next(c for c in summary["sweep"] if c["planner"] == "rrt_connect" and c["radius"] == 0.1)
assert rrt["arm_clear_rate"] == 1.0, rrt
# The training table carries each cross row's test- and training-pair stitching error from its own report.
cross = [row for row in summary["train"] if row.startswith("cross_")]
assert len(cross) == 19 and sorted(summary["stitching"]) == sorted(cross), summary["stitching"]
for row in cross:
    report = json.load(open(os.path.join(root, "stitching", f"{row}.json")))
    for pairs in ("test", "train"):
        assert summary["stitching"][row][pairs]["mean"] == report[pairs]["mean"], (row, pairs)
    # 4 plans for each of the two test pairs
    with h5py.File(os.path.join(root, "stitching", f"{row}.json.plans.h5"), "r") as f:
        assert sorted(f["test/pair_index"][...].tolist()) == [0] * 4 + [1] * 4, row
# The training-budget curve: each long row at each checkpoint. Its last checkpoint is the row's own model, so the
# curve's stitching error there is what `flowplan eval stitching` of the run folder gives (same plans and noise);
# the first checkpoint's differs.
assert sorted(summary["curve"]) == ["long_cross_fp_20k_s0", "long_cross_fp_s0"], summary["curve"]
for row, points in summary["curve"].items():
    assert sorted(int(k) for k in points) == [10, 20], (row, points)
    for point in points.values():
        assert sorted(point) == ["r0.1", "r0.15", "stitching", "stitching_split", "val_loss"], point
    own = os.path.join(scratch, f"{row}_stitching.json")
    done = subprocess.run([flowplan, "eval", "stitching", "--ckpt", os.path.join(root, "train", row), "--out", own,
                           "data.path=" + os.path.join(root, "data", "franka_cross.h5"), "eval.num_plans=8",
                           "--log-level", "warn"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    final = json.load(open(own))["test"]
    assert points["20"]["stitching"] == {"mean": final["mean"], "stddev": final["stddev"]}, (row, points["20"], final)
    assert points["10"]["stitching"] != points["20"]["stitching"], (row, points)
    losses = [json.loads(line) for line in open(os.path.join(root, "train", row, "metrics.jsonl"))]
    assert points["20"]["val_loss"] == next(r["val_loss"] for r in losses if r.get("step") == 20 and "val_loss" in r)
    plans = json.load(open(os.path.join(root, "curve", f"{row}_k10_r0.1.json")))
    assert points["10"]["r0.1"]["arm"] == sum(p["arm_clear"] for p in plans["samples"]) / len(plans["samples"])
# The families stage: every learned planner's guidance chosen from its validation rows alone (most valid, then
# faster); the hybrid's the fastest of those at least as often valid as RRT-Connect on the same validation problems
# (the most valid when none is); every planner's test reports, checked by the independent plan-file script; the
# validation and test problems differ (two seeds).
families = summary["families"]
assert sorted(families["chosen"]) == ["fp", "fp_split", "hybrid", "mpd", "vae"], families["chosen"]
bar = families["validation"]["rrt_connect"]
assert len(bar) == 1 and bar[0]["setting"] == [] and bar[0]["plans"] > 0, bar
for planner, rows in families["validation"].items():
    if planner == "rrt_connect":
        continue
    best = max(rows, key=lambda r: (r["success"], -r["median_time_s"]))
    level = [r for r in rows if r["success"] >= bar[0]["success"]]
    if planner == "hybrid" and level:
        best = min(level, key=lambda r: (r["median_time_s"], -r["success"]))
    assert rows and families["chosen"][planner] == best["setting"], (planner, rows)
fp_grid = [r["setting"] for r in families["validation"]["fp"]]
assert len(fp_grid) == 2 and fp_grid[0] != fp_grid[1], fp_grid
# The rule itself, on made-up rows (the quick grid has one hybrid setting): the bar keeps out the fast row below it,
# picks the fastest above it, and falls back to the most valid when no row reaches it.
sys.path.insert(0, os.path.join(repo, "scripts"))
import bench_families  # noqa: E402
made_up = [(["slow"], 0.98, 0.020, 200), (["fast"], 0.965, 0.013, 200), (["below"], 0.955, 0.010, 200)]
assert bench_families.choose(made_up, 0.96) == ["fast"]
assert bench_families.choose(made_up, 0.99) == ["slow"] == bench_families.choose(made_up)
test_cells = {f"{p}/{s}" for p in ("fp", "fp_split", "mpd", "vae", "rrt_connect", "hybrid")
              for s in ("table", "shelf", "sphere", "table_moveit")}
assert sorted(families["test"]) == sorted(test_cells), sorted(families["test"])
for cell in test_cells:
    prefix = os.path.join(root, "families", "test", cell.replace("/", "_"))
    checked = subprocess.run([sys.executable, os.path.join(repo, "tests", "cli", "check_plan.py"), prefix + ".h5",
                              prefix + ".json"], capture_output=True, text=True)
    assert checked.returncode == 0, (cell, checked.stdout + checked.stderr)
    report = json.load(open(prefix + ".json"))
    assert report["planning_time_s"]["per"] == "plan, the wall time of the call that made it", cell
    assert families["test"][cell]["success"] == report["success_rate"], cell
# The pooled times are quantiles of the same definition as each report's (numpy's linear interpolation, which
# statistics.median agrees with): pooled over a report's own plans they are its median.
for planner in ("fp", "fp_split", "mpd", "vae", "rrt_connect", "hybrid"):
    times = []
    for family in ("table", "shelf"):
        report = json.load(open(os.path.join(root, "families", "test", f"{planner}_{family}.json")))
        own = [s["planning_time_s"] for p in report["problems"] for s in p["samples"]]
        assert abs(report["planning_time_s"]["median"] - statistics.median(own)) < 1e-9, (planner, family)
        times += own
    assert abs(families["pooled"][planner]["median_time_s"] - statistics.median(times)) < 1e-12, planner
hybrid = json.load(open(os.path.join(root, "families", "test", "hybrid_sphere.json")))
assert all(s["route"].startswith(("rrt_connect", "proposal")) for p in hybrid["problems"]
           for s in p["samples"] if s["success"]), hybrid
assert "--hybrid" in open(os.path.join(root, "families", "test", "hybrid_sphere.request")).read()
for family in ("table", "shelf"):
    val = open(os.path.join(root, "families", "problems", f"val_{family}.yaml")).read()
    test = open(os.path.join(root, "families", "problems", f"test_{family}.yaml")).read()
    assert "seed: 101" in val and "seed: 303" in test and val.split("problems:")[1] != test.split("problems:")[1]
# The table's test problems written as MoveIt files by the driver and imported by `flowplan scenes import` plan as
# the originals do: the same problems, so every planner's plans are the same bytes.
for planner in ("fp", "fp_split", "mpd", "vae", "rrt_connect", "hybrid"):
    prefixes = [os.path.join(root, "families", "test", f"{planner}_{s}") for s in ("table", "table_moveit")]
    reports = [json.load(open(prefix + ".json")) for prefix in prefixes]
    assert len(reports[0]["problems"]) == len(reports[1]["problems"]) > 0, planner
    with h5py.File(prefixes[0] + ".h5", "r") as native, h5py.File(prefixes[1] + ".h5", "r") as imported:
        for a, b in zip(reports[0]["problems"], reports[1]["problems"]):
            assert a["status"] == b["status"] == "planned", (planner, a, b)
            for key in ("start", "goal", "plans"):
                assert numpy.array_equal(native[a["group"]][key][()], imported[b["group"]][key][()]), \
                    (planner, a["name"], key)
assert os.path.exists(os.path.join(root, "results", "families_success_vs_time.png"))
# The select stage's sets: validation seed 101, the held-out test set seed 303.
select_val = open(os.path.join(root, "select", "val.yaml")).read()
select_test = open(os.path.join(root, "select", "test.yaml")).read()
assert "seed: 101" in select_val and "seed: 303" in select_test, (select_val[:300], select_test[:300])

# The select stage: FP and FP + split exported with the paper's sampler (the grids' base row), as the driver's sweep
# rows plan; every planner's grid on the validation problems; FP's best setting chosen from validation alone, then
# reported on the test problems beside every other planner's default.
import torch  # noqa: E402

for name, splitting in (("fp", "none"), ("fp_split", "midpoint")):
    exported = torch.jit.load(os.path.join(root, "select", f"{name}.pt"))
    assert exported.settings["sampler.final_iterations"] == 0.0 and exported.splitting == splitting, name
    assert exported.settings["sampler.final_spread"] == exported.settings["sampler.final_joint_speed_weight"] == 0.0
assert "sampler.final_iterations=0" in open(os.path.join(root, "sweep", "fp_r0.1.request")).read()
validation = json.load(open(os.path.join(root, "select", "validation.json")))
assert sorted(validation["planners"]) == ["fp", "fp_split", "mpd", "paper_mpd"], sorted(validation["planners"])
fp_rows = [(n, r) for n in ("fp", "fp_split") for r in validation["planners"][n]]
best = max(fp_rows, key=lambda nr: (nr[1]["arm_clear"], -nr[1]["seconds_per_plan"]))
assert summary["select"]["chosen"]["fp_best"] == {"planner": best[0], "label": best[1]["label"]}, summary["select"]
roles = {r["role"] for r in summary["select"]["test"]}
assert {"mpd_default", "paper_mpd_default"} <= roles, roles
assert all(len(r["per_problem"]) == 2 for r in summary["select"]["test"]), summary["select"]["test"]
summary_md = open(os.path.join(root, "results", "summary.md")).read()
assert "### Guidance chosen on validation problems" in summary_md and "Test (held out)" in summary_md
# ... and every test row of FP, FP + split and MPD again with the models of training seeds 1 and 2 (exported as seed
# 0's, with other weights); the report gives each row's mean ± sample std over the three models.
for row in ("reach_fp", "reach_mpd"):
    for seed in (1, 2):
        assert yaml.safe_load(open(os.path.join(root, "train", f"{row}_s{seed}", "config.yaml")))["seed"] == seed
tested = {r["planner"] for r in summary["select"]["test"]}
assert {"fp", "fp_split", "mpd"} <= tested, tested
# Each planner's budgets (its success-versus-time curve) are planned on test, with the first model only.
test_rows = {(r["planner"], r["label"]) for r in summary["select"]["test"]}
for name, labels in {"fp": ["base: x_t, rising, s 1.75", "base + end-game G 20, spread 4, end joint speed 0.1"],
                     "fp_split": ["split + end-game G 5, spread 4, end joint speed 0.1"],
                     "mpd": ["10 gradient steps", "default", "best of 2", "best of 4"],
                     "paper_mpd": ["default", "best of 4"]}.items():
    assert all((name, label) in test_rows for label in labels), (name, sorted(test_rows))
assert "Test, each planner's budgets" in open(os.path.join(root, "select", "selection.md")).read()
assert not any(x["role"] == "budget" for x in summary["select"]["test_other_seeds"])
for name in {"fp", "fp_split", "mpd"} & tested:
    for r in [r for r in summary["select"]["test"] if r["planner"] == name and r["role"] != "budget"]:
        models = sorted((x for x in summary["select"]["test_other_seeds"]
                         if (x["planner"], x["role"], x["label"]) == (name, r["role"], r["label"])),
                        key=lambda x: x["model"])
        assert [x["model"] for x in models] == [2, 3], (name, r["role"], models)
        rates = [r["arm_clear"]] + [x["arm_clear"] for x in models]
        line = next(line for line in summary_md.split("Test over models")[1].split("\n")
                    if line.startswith(f"| {r['role']} | {name} | {r['label']} | "))
        cells = [c.strip() for c in line.split("|")[4:-1]]
        assert cells[:3] == [f"{x['arm_clear']:.1%}, {1e3 * x['seconds_per_plan']:.1f}" for x in [r] + models], line
        assert cells[3].startswith(f"{statistics.mean(rates):.1%} ± {statistics.stdev(rates):.1%}, "), line
# Every test row but the budgets is counted by the plan checker too, for every model of its planner, from a report of
# `flowplan plan --problems` that the row's file names.
checked = summary["select"]["test_checked"]
for r in [r for r in summary["select"]["test"] if r["role"] != "budget"]:
    models = sorted(x["model"] for x in checked if (x["planner"], x["role"], x["label"]) ==
                    (r["planner"], r["role"], r["label"]))
    assert models == ([1, 2, 3] if r["planner"] in tested & {"fp", "fp_split", "mpd"} else [1]), (r, models)
for x in checked:
    # a checked success has its states clear, at the goal and within the speed limit: the state count holds it
    assert 0.0 <= x["success"] <= x["arm_clear"] + 1e-9 and x["plans"] > 0 and x["seconds_per_plan"] > 0, x
    # every plan of every test problem counts, refused problems' plans as failures
    assert x["plans"] == summary["select"]["test_problems"] * summary["select"]["plans_per_problem"], x
assert "counted by the plan checker" in summary_md
# guidance_select.py refuses an FP file exported with the preset's end-game defaults (its grids add to them).
unfit = os.path.join(root, "select_unfit_fp.pt")
subprocess.run([flowplan, "export", "--ckpt", os.path.join(root, "train", "reach_fp"), "--out", unfit], check=True,
               capture_output=True)
refused = subprocess.run([sys.executable, os.path.join(repo, "scripts", "guidance_select.py"), "--planner",
                          f"fp={unfit}", "--val", os.path.join(root, "select", "val.yaml"), "--test",
                          os.path.join(root, "select", "test.yaml"), "--out", os.path.join(root, "select_unfit")],
                         capture_output=True, text=True)
assert refused.returncode != 0 and "export the flow planner with the paper's sampler" in refused.stderr, refused.stderr
assert "sampler.final_iterations=10" in refused.stderr and not os.path.exists(os.path.join(root, "select_unfit"))
os.remove(unfit)
weights = [dict(torch.jit.load(os.path.join(root, "select", f"{name}.pt")).named_buffers())
           ["sampler.network.p_final_conv_weight"] for name in ("fp", "fp_s1")]
assert weights[0].shape == weights[1].shape and not torch.equal(*weights)
times = next(line for line in summary_md.split("\n") if line.startswith("| FP + split | "))
assert len([t for t in times.split("|")[2:-1] if float(t) > 0]) == 5, times  # 4 radii and their median
for name in (["success_vs_radius.png", "training_budget.png", "success_vs_time.png", "summary.md"] +
             [f"example_{p}_r0.1.png" for p in planners]):
    assert os.path.getsize(os.path.join(root, "results", name)) > 0, name

# 2. A second run redoes nothing but the recount.
before = len(log_commands())
bench()
again = log_commands()[before:]
assert len(again) == 1 and "recount_plans.py" in again[0], again
# ... as when the output folder has moved (requests name it by a placeholder).
moved = root + "_moved"
os.rename(root, moved)
try:
    out = subprocess.run([sys.executable, os.path.join(repo, "scripts", "franka_bench.py"), "--quick", "--root", moved,
                          "--flowplan", flowplan], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-3000:]
    with open(os.path.join(moved, "bench.log")) as f:
        again = [line for line in f if line.startswith("$ ")][before + 1:]
    assert len(again) == 1 and "recount_plans.py" in again[0], again
finally:
    os.rename(moved, root)

# A request is what the YAML files say, not how: a comment does not count, a value does.
sys.path.insert(0, os.path.join(repo, "scripts"))
import franka_bench  # noqa: E402

maker = franka_bench.Bench(argparse.Namespace(root="some/root", quick=True, flowplan="bin/flowplan", rows=None,
                                              threads=None))
# The full run's long rows are evaluated at the checkpoints they reach: 10,000 steps and 20,000.
full = franka_bench.Bench(argparse.Namespace(root="some/root", quick=False, flowplan="bin/flowplan", rows=None,
                                             threads=None))
assert full.curve_steps("long_cross_fp_s2") == [2000, 5000, 10000], full.curve_steps("long_cross_fp_s2")
assert full.curve_steps("long_cross_fp_20k_s1") == [2000, 5000, 10000, 20000]
assert full.curve_steps("long_cross_fp_unet4_s0") == [2000, 5000, 10000]
assert full.long_rows() == ["long_cross_fp_s0", "long_cross_fp_s1", "long_cross_fp_s2", "long_cross_fp_20k_s0",
                            "long_cross_fp_20k_s1", "long_cross_fp_unet4_s0"], full.long_rows()
# The rows' overrides are part of their training requests: runs trained before must stay theirs.
rows = franka_bench.train_rows()
assert rows["long_cross_fp_s2"][2] == ["train.steps=10000", "train.checkpoint_every=1000", "train.keep_checkpoints=10",
                                       "train.eval_every=1000"], rows["long_cross_fp_s2"]
assert rows["long_cross_fp_20k_s1"][2] == ["train.steps=20000", "train.checkpoint_every=1000",
                                           "train.keep_checkpoints=20", "train.eval_every=1000"], rows["long_cross_fp_20k_s1"]
assert rows["long_cross_fp_unet4_s0"][2] == rows["long_cross_fp_s0"][2] + ["model.unet.down_dims=[32,64,128,256]"]
config = os.path.join(scratch, "request.yaml")
requests = []
for text in ("train:\n  steps: 20\n", "# sized for the test\ntrain: {steps: 20}  # steps\n", "train:\n  steps: 21\n"):
    open(config, "w").write(text)
    requests.append(maker.request(["bin/flowplan", "train", "--config", config, "run_dir=some/root/train/x"]))
assert requests[0] == requests[1] != requests[2], requests
assert requests[0].startswith("{flowplan} train --config ") and "run_dir={root}/train/x" in requests[0], requests[0]

# ... but a cell whose recorded request is not the driver's (another command, scene or model made it) is made again,
with open(os.path.join(root, "sweep", "mpd_r0.1.request"), "a") as f:
    f.write("guidance.scale=9\n")
before = len(log_commands())
out = bench("--only", "sweep")
again = log_commands()[before:]
assert len(again) == 1 and " plan " in again[0] and again[0].rstrip().endswith("/sweep/mpd_r0.1"), again
assert "stale" in out and "mpd_r0.1.json" in out, out
# and a row trained by another request stops the driver, naming the folder to delete, and keeps the model.
done_path = os.path.join(root, "train", "cross_mpd", "done.json")
done = json.load(open(done_path))
checkpoints_of_mpd = sorted(os.listdir(os.path.join(root, "train", "cross_mpd", "checkpoints")))
json.dump(done | {"request": done["request"].replace("objective.name=ddpm", "objective.name=flow_matching")},
          open(done_path, "w"))
stopped = subprocess.run([sys.executable, os.path.join(repo, "scripts", "franka_bench.py"), "--quick", "--root", root,
                          "--flowplan", flowplan, "--only", "train-cross"], capture_output=True, text=True)
assert stopped.returncode != 0 and "train/cross_mpd: trained by another request" in stopped.stderr, stopped.stderr
assert "Delete" in stopped.stderr, stopped.stderr
assert sorted(os.listdir(os.path.join(root, "train", "cross_mpd", "checkpoints"))) == checkpoints_of_mpd
# The stage that evaluates it stops too, and the tables leave out (and list) what it made.
stopped = subprocess.run([sys.executable, os.path.join(repo, "scripts", "franka_bench.py"), "--quick", "--root", root,
                          "--flowplan", flowplan, "--only", "stitching"], capture_output=True, text=True)
assert stopped.returncode != 0 and "train/cross_mpd: trained by another request" in stopped.stderr, stopped.stderr
bench("--only", "results")
summary = json.load(open(os.path.join(root, "results", "summary.json")))
assert summary["table1"]["MPD"] is None and "cross_mpd" not in summary["train"], summary["table1"]
assert any(path.endswith("stitching/cross_mpd.json") for path in summary["left_out"]), summary["left_out"]
json.dump(done, open(done_path, "w"))
bench("--only", "results")
assert json.load(open(os.path.join(root, "results", "summary.json")))["left_out"] == []

# 3. Re-evaluated from their checkpoints, stitching rows give the same figures; --rows picks the rows.
rows = {name: os.path.join(root, "stitching", f"{name}.json") for name in ("cross_fp_s1", "cross_fp_s2")}
first = {name: json.load(open(path))["test"] for name, path in rows.items()}
for path in rows.values():
    os.remove(path)
before = len(log_commands())
bench("--only", "stitching", "--rows", "cross_fp_s1")
again = log_commands()[before:]
assert len(again) == 1 and "/cross_fp_s1 " in again[0], again
assert not os.path.exists(rows["cross_fp_s2"])
bench("--only", "stitching")
for name, path in rows.items():
    second = json.load(open(path))["test"]
    assert (first[name]["mean"], first[name]["stddev"]) == (second["mean"], second["stddev"]), (name, first, second)
unknown = subprocess.run([sys.executable, os.path.join(repo, "scripts", "franka_bench.py"), "--quick", "--root", root, "--rows", "cross_fp_s9"],
                         capture_output=True, text=True)
assert unknown.returncode != 0 and "--rows: unknown row 'cross_fp_s9'" in unknown.stderr, unknown.stderr

# 4. A row stopped after its first checkpoint resumes from it.
run = os.path.join(root, "train", "reach_vae")
os.remove(os.path.join(run, "done.json"))
checkpoints = sorted(os.listdir(os.path.join(run, "checkpoints")))
assert len(checkpoints) >= 2, checkpoints
for name in checkpoints[1:]:
    os.remove(os.path.join(run, "checkpoints", name))
# Checkpoints begun by another request stop the driver rather than being resumed or thrown away,
marker = os.path.join(run, "request.txt")
request = open(marker).read()
open(marker, "w").write(request.replace("train.steps=20", "train.steps=30"))
stopped = subprocess.run([sys.executable, os.path.join(repo, "scripts", "franka_bench.py"), "--quick", "--root", root,
                          "--flowplan", flowplan, "--only", "train-reach"], capture_output=True, text=True)
assert stopped.returncode != 0 and "train/reach_vae: trained by another request" in stopped.stderr, stopped.stderr
assert sorted(os.listdir(os.path.join(run, "checkpoints"))) == checkpoints[:1]
open(marker, "w").write(request)  # those of this request resume
before = len(log_commands())
bench("--only", "train-reach")
again = log_commands()[before:]
assert len(again) == 1 and "train --resume" in again[0] and again[0].rstrip().endswith("reach_vae"), again
assert json.load(open(os.path.join(run, "done.json")))["steps"] == 20

# 5. A report whose counts do not match its plans is caught.
cell = os.path.join(root, "sweep", "fp_r0")
tampered = os.path.join(scratch, "tampered")
shutil.copy(cell + ".h5", tampered + ".h5")
report = json.load(open(cell + ".json"))
report["samples"][0]["tcp_clear"] = not report["samples"][0]["tcp_clear"]
json.dump(report, open(tampered + ".json", "w"))


def recount(prefix):
    return subprocess.run([sys.executable, os.path.join(repo, "scripts", "recount_plans.py"), prefix],
                          capture_output=True, text=True)


done = recount(tampered)
assert done.returncode == 1 and "differs" in done.stdout, done.stdout + done.stderr
# ... and so are plans that are not those the report scored (the geometry is recomputed).
cell = os.path.join(root, "sweep", "rrt_connect_r0.1")
shutil.copy(cell + ".json", tampered + ".json")
shutil.copy(cell + ".h5", tampered + ".h5")
assert recount(tampered).returncode == 0, recount(tampered).stdout
with h5py.File(tampered + ".h5", "r+") as f:
    plans = f["plans"][...]
    plans[0, :, 1] += 0.2  # shoulder joint of plan 0: its whole arm moves
    f["plans"][...] = plans
done = recount(tampered)
assert done.returncode == 1 and "differs" in done.stdout, done.stdout + done.stderr
print("franka_bench --quick: every table, resume, re-evaluation and recount ok")
