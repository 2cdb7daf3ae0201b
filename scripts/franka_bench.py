#!/usr/bin/env python3
"""The Franka benchmarks (SPEC section 4 and beyond), one resumable run.

usage: /usr/bin/python3 scripts/franka_bench.py [--quick] [--root DIR] [--only STAGE,...] [--rows ROW,...]
                                                [--threads N] [--flowplan BIN]
(Debian's python3-h5py and python3-yaml; build flowplan first: make build)

Stages, in order; each writes its output atomically and skips an output that
exists and was made by the current request (below), so a stopped run continues
where it stopped (a stopped training resumes from its newest checkpoint):

  data        ROOT/data/<set>.h5            `flowplan generate` of every data set
  train-reach ROOT/train/reach_*/done.json  `flowplan train` of FP, MPD, the VAE and the paper's MPD on franka_reach,
                                            and of FP and MPD with training seeds 1 and 2 (reach_fp_s1, ...)
  sweep       ROOT/sweep/<planner>_r<R>.*   the paper's scene, one sphere of radius R, every
                                            planner, plans executed in MuJoCo
  scales      ROOT/scales/s<S>_r<R>.*       FP + split at several guidance scales
  budget      ROOT/budget/<name>_r<R>.*     MPD at other guidance settings, every radius
  problems    ROOT/problems/...             random blocked scenes (`flowplan problems`), every planner
  examples    ROOT/results/example_*.png    a few plans of every planner, drawn
  train-cross ROOT/train/cross_*/done.json  `flowplan train` of every franka_cross row
  stitching   ROOT/stitching/<row>.json     `flowplan eval stitching` of every franka_cross row
  train-long  ROOT/train/long_*/done.json   FP on franka_cross for 10,000 steps (three seeds) and 20,000 (two),
                                            and the four-level UNet for 10,000; a checkpoint every 1,000 steps
                                            (the training-budget curve)
  curve       ROOT/curve/<row>_k<step>.*    each long run at the steps of the curve: stitching without and with
                                            splitting, and guided around the paper's sphere on the stitching pair
  select      ROOT/select/                  guidance chosen on validation problems (seed 101) and reported on
                                            held-out test problems (seed 303; spheres and boxes): guidance_select.py on FP,
                                            FP + split, MPD and the paper's MPD, exported from the reach rows;
                                            the test rows of FP, FP + split and MPD again with seeds 1 and 2
  train-joint ROOT/train/joint_*/done.json  `flowplan train` of FP, MPD and the VAE on franka_joint (configs/
                                            franka_joint.yaml: motions between random configurations)
  families    ROOT/families/                every planner on the scene families and the paper's sphere scene,
                                            checked and executed, guidance chosen on validation problems
                                            (scripts/bench_families.py)
  recount     ROOT/results/recount.json     scripts/recount_plans.py on every saved plan (always redone)
  results     ROOT/results/*.md|json|png    tables and plots (always redone from what exists)

Beside every output the driver records its request, written once the output
is finished (before, for a training's or a planner's folder of partial work):
the command that makes it (the output folder and the binary written as
placeholders), the YAML files that command names (parsed; a data set counts
only the generate section and the seed), and the requests of the outputs it
reads, so that a changed data set makes its models stale, and a changed model
its plans. An output of another request is made again: a data set, the random
problems, a planner's plans on them, a stitching report, a plan cell. A model
of another request (or of none) stops the driver with a message naming the
folder to delete: training takes hours and is never thrown away silently. The
results stage leaves out, and lists, every output of another request. Not
detected: a rebuilt flowplan binary and edited scripts (franka_problems.py,
plot.py); delete the outputs to redo them.

--rows limits the training, stitching and curve stages to the named rows, trained in
the order given (e.g. --rows cross_mpd,cross_fp_s0 --only train-cross,stitching).
--threads N sets the threads of the training and curve stages' flowplan calls
without entering any request (their results do not depend on it): two drivers
with --threads 1 and different --rows share a root on two cores. The select
stage plans on one thread always: it compares times per plan.
--adopt ROW=RUN makes the training stage take a run folder trained outside the driver as training row ROW instead of
training it, if its resolved config is the one the row's command makes (paths and threads aside) and it finished
its steps; done.json then names the folder, and the training time is summed from its logged rates.
--quick runs every stage at toy size (ROOT defaults to runs/franka_bench_quick).
The sizes of the full run and how they were chosen: docs/results.md.
"""
import argparse
import contextlib
import fcntl
import glob
import json
import os
import shlex
import shutil
import signal
import subprocess
import sys
import time

import bench_families

REACH_CONFIG = "configs/franka_reach.yaml"
PAPER_MPD_CONFIG = "configs/franka_reach_paper_mpd.yaml"
# franka_cross data sets: name, config, augmentation scheme as the paper names it.
CROSS_SETS = [("franka_cross", "configs/franka_cross.yaml", "per-joint noise"),
              ("franka_cross_same_noise", "configs/franka_cross_same_noise.yaml", "same noise"),
              ("franka_cross_no_noise", "configs/franka_cross_no_noise.yaml", "no noise"),
              ("franka_cross_random_pos", "configs/franka_cross_random_pos.yaml", "random positions"),
              ("franka_cross_random_forces", "configs/franka_cross_random_forces.yaml", "random forces")]
# Every data set: name, config.
DATA_SETS = [(name, config) for name, config, _ in CROSS_SETS] + [("franka_reach", REACH_CONFIG),
                                                                  ("franka_joint", bench_families.JOINT_CONFIG)]
SEEDS = [0, 1, 2]
# Table 1 on franka_cross: label, row name prefix, overrides, seeds.
TABLE1 = [("FP", "cross_fp", [], SEEDS),
          ("FP w/o inpainting", "cross_fp_direct", ["objective.conditioning=direct"], [0]),
          ("Transformer", "cross_transformer", ["model.name=transformer"], [0]),
          ("Transformer w/o inpainting", "cross_transformer_direct",
           ["model.name=transformer", "objective.conditioning=direct"], [0]),
          ("MPD", "cross_mpd", ["objective.name=ddpm"], [0])]
# The training-budget curve (stage curve): FP on franka_cross trained for longer budgets with its cosine schedule,
# evaluated at the checkpoints of curve_steps each run reaches; beside it, the 2,000-step rows of table 1, whose
# schedule ends there.
CURVE_EVERY = 1000


def long_train(steps):
    """Overrides of a long run of STEPS steps: a checkpoint (kept) and an evaluation every CURVE_EVERY steps."""
    return [f"train.steps={steps}", f"train.checkpoint_every={CURVE_EVERY}",
            f"train.keep_checkpoints={steps // CURVE_EVERY}", f"train.eval_every={CURVE_EVERY}"]


# The long runs: row name -> (overrides, training seeds); the row long_cross_fp<suffix>_s<seed>. Three seeds of
# 10,000 steps, two of 20,000 (their checkpoints up to 10,000 are mid-schedule too), and the paper's four-level UNet
# for 10,000 steps.
LONG_RUNS = {"": (long_train(10000), [0, 1, 2]),
             "_20k": (long_train(20000), [0, 1]),
             "_unet4": (long_train(10000) + ["model.unet.down_dims=[32,64,128,256]"], [0])}
REACH_SCALE = ["guidance.scale=1.75"]  # the reach rows' guidance scale (see train_rows)
REACH_SEEDS = [0, 1, 2]  # training seeds of the reach FP and MPD in the select stage's seed rows
CURVE_RADII = [0.1, 0.15]
# Guidance selection (stage select, scripts/guidance_select.py): validation and held-out test problems drawn with
# two seeds; the planners it compares, each exported from its training row with these settings (the flow planner
# with the paper's sampler, no end-game and the end-game's spread and hinge off, so that the grids' base setting is
# that and a grid row that adds end-game steps without a spread adds plain ones, whatever the preset's defaults).
# The test seed is 303: seed 202's set was reported at every round of the guidance work that led to the end-game
# (docs/results.md), so its figures were seen while the grid was designed; 303 was drawn for the final report only.
SELECT_SEEDS = {"val": 101, "test": 303}
# Both sets: 1-8 spheres (the first on the straight TCP path) and 1-3 boxes at random orientations near that path.
SELECT_PROBLEMS = ["problems.min_boxes=1", "problems.max_boxes=3"]
PAPER_SAMPLER = ["sampler.final_iterations=0", "sampler.final_spread=0", "sampler.final_joint_speed_weight=0"]
SELECT_PLANNERS = [("fp", "reach_fp", ["sampler.splitting=none", *PAPER_SAMPLER]),
                   ("fp_split", "reach_fp", ["sampler.splitting=midpoint", *PAPER_SAMPLER]),
                   ("mpd", "reach_mpd", []),
                   ("paper_mpd", "reach_paper_mpd", [])]
# The select stage's other models: each planner above whose row has seeds REACH_SEEDS[1:] is exported from those rows
# alike and passed as --replicate, so that the held-out rows give their spread over training seeds.
SELECT_REPLICATED = ["fp", "fp_split", "mpd"]
# The cross planner guided around the paper's sphere on the stitching pair (its start and goal TCP are those of the
# pair (-0.3, 0.2) -> (0.3, 0.2)): the reach preset's guidance, split, with the plain end-game of 10 steps chosen on
# validation problems before the covariant end-game existed (docs/results.md, "Training budget").
CURVE_GUIDANCE = ["guidance.scale=1.75", "guidance.schedule=rising", "guidance.clip=1", "guidance.collision_weight=0.1",
                  "guidance.smoothness_weight=0.02", "guidance.margin=0.05", "sampler.splitting=midpoint",
                  "sampler.final_iterations=10"]
PAPER_TABLE1 = {"FP": "0.16 ± 0.07", "FP w/o inpainting": "0.71 ± 0.24", "Transformer": "0.30 ± 0.09",
                "Transformer w/o inpainting": "1.73 ± 0.49", "MPD": "1.00 ± 0.97"}
PAPER_TABLE2 = {"per-joint noise": "0.16 ± 0.07", "same noise": "1.62 ± 0.25", "no noise": "0.81 ± 0.05",
                "random positions": "0.54 ± 0.06", "random forces": "0.85 ± 0.23"}
# Obstacle planners: name, label, `flowplan plan` source (train row or RRT-Connect), extra overrides.
PLANNERS = [("mpd", "MPD", "reach_mpd", []),
            # Adam's step on the latent: at the default 0.05 the VAE planner's plans reach the goal but move
            # at 1.9-2.7x the joint speed limits, with no sphere (docs/results.md); 0.02 keeps them within.
            ("vae", "VAE planner", "reach_vae", ["sampler.latent.lr=0.02"]),
            # The paper's sampler (no end-game), whatever the preset's defaults; the select stage chooses among the
            # guidance variants on validation problems.
            ("fp", "FP", "reach_fp", ["sampler.splitting=none", "sampler.final_iterations=0"]),
            ("fp_split", "FP + split", "reach_fp", ["sampler.splitting=midpoint", "sampler.final_iterations=0"]),
            ("rrt_connect", "RRT-Connect", None, [])]
# MPD with other guidance settings than the sweep's (FP's cost weights, 60 gradient steps: MPD guides the last 7
# of its 25 denoising steps and 5 noise-free steps after them, 5 gradient steps each): FP's budget of gradient
# steps (one per Euler step: 10), and MPD's published cost weights. Name, label, overrides.
MPD_BUDGETS = [("mpd_g10", "MPD, 10 gradient steps (1 per guided step, 3 noise-free steps)",
                ["sampler.ddpm.guide_iterations=1", "sampler.ddpm.extra_steps=3"]),
               ("mpd_paper_weights", "MPD, MPD's cost weights (collision 1e-2, GP prior 1e-7)",
                ["guidance.collision_weight=0.01", "guidance.smoothness_weight=1e-7"])]
PAPER_RADIUS = {"mpd": 0.03, "vae": 0.05, "fp": 0.15, "fp_split": 0.20}
WAYS = [("tcp_clear_rate", "TCP"), ("arm_clear_rate", "whole arm"), ("success_rate_executed", "executed")]
# The paper's count: the TCP clear of the sphere and the last TCP at the goal, whatever the joint speeds.
ANY_SPEED = ("tcp_clear_rate_any_speed", "TCP, any speed")
SCENE = "configs/scenes/franka_sphere.yaml"
START_TCP, GOAL_TCP = "0.5,-0.3,0.2", "0.5,0.3,0.2"

FULL = {"episodes": None, "train": [], "plans_per_pair": 64, "radii": [round(0.025 * i, 3) for i in range(14)],
        "sweep_plans": 64, "scales": [0.5, 1.0, 1.75, 2.5, 3.5, 5.0],
        "scale_radii": [0.1, 0.125, 0.15, 0.175, 0.2, 0.225, 0.25],
        "problems": 100, "problem_plans": 8, "example_radii": [0.1, 0.2], "example_plans": 8,
        "curve_steps": [2000, 5000, 10000, 20000], "long_rows": None, "select_problems": 100, "select_plans": 8,
        "select_warmup": 3, "select_rows": 0,
        "family_val_problems": 20, "family_val_plans": 2, "family_test_problems": 20, "family_test_plans": 4}
QUICK = {"episodes": 256,
         "train": ["train.steps=20", "train.batch_size=16", "train.eval_every=0", "train.checkpoint_every=10",
                   "train.log_every=10", "train.val_batch_size=16"],
         "plans_per_pair": 4, "radii": [0.0, 0.1, 0.2, 0.3], "sweep_plans": 4, "scales": [1.0, 2.5],
         "scale_radii": [0.15], "problems": 2, "problem_plans": 2, "example_radii": [0.1], "example_plans": 2,
         "curve_steps": [10, 20], "long_rows": ["long_cross_fp_s0", "long_cross_fp_20k_s0"], "select_problems": 2,
         "select_plans": 2, "select_warmup": 1, "select_rows": 3,
         "family_val_problems": 1, "family_val_plans": 1, "family_test_problems": 1, "family_test_plans": 1}


def train_rows():
    """Every training row: name -> (config, data set, overrides, seed)."""
    rows = {}
    for _, prefix, overrides, seeds in TABLE1:
        for seed in seeds:
            rows[f"{prefix}_s{seed}" if len(seeds) > 1 else prefix] = (CROSS_SETS[0][1], "franka_cross", overrides, seed)
    for seed in SEEDS:  # seed by seed, so that a partial run has every scheme
        for name, config, _ in CROSS_SETS[1:]:
            rows[f"{name[len('franka_'):]}_fp_s{seed}"] = (config, name, [], seed)
    for suffix, (overrides, seeds) in LONG_RUNS.items():  # the training-budget curve
        for seed in seeds:
            rows[f"long_cross_fp{suffix}_s{seed}"] = (CROSS_SETS[0][1], "franka_cross", overrides, seed)
    # The reach rows keep guidance scale 1.75, the scale every figure of the sweeps, the select stage's grids and MPD
    # were measured at; the preset's 0.75 is the select stage's choice for FP with its end-game (a grid row).
    rows["reach_fp"] = (REACH_CONFIG, "franka_reach", [*REACH_SCALE], 0)
    rows["reach_mpd"] = (REACH_CONFIG, "franka_reach", ["objective.name=ddpm", *REACH_SCALE], 0)
    # Two more training seeds of FP and MPD for the spread of the held-out comparison (the select stage's seed rows;
    # seed 0 is the row above). The seed draws the initial weights, the batches and the validation episodes; the
    # data set is the same.
    for seed in REACH_SEEDS[1:]:
        rows[f"reach_fp_s{seed}"] = (REACH_CONFIG, "franka_reach", [*REACH_SCALE], seed)
        rows[f"reach_mpd_s{seed}"] = (REACH_CONFIG, "franka_reach", ["objective.name=ddpm", *REACH_SCALE], seed)
    # The VAE learns single states: 16 trajectories are 1,024 states per step (as in the particle zoo), and
    # 128 would make its 10,000 steps take 95 minutes here.
    rows["reach_vae"] = (REACH_CONFIG, "franka_reach",
                         ["model.name=state_vae", "objective.name=vae", "train.batch_size=16", *REACH_SCALE], 0)
    # The Flow Planner paper's MPD baseline as its code runs it (docs/results.md, "Two MPDs").
    rows["reach_paper_mpd"] = (PAPER_MPD_CONFIG, "franka_reach", [], 0)
    # The general planners of the scene families (configs/franka_joint.yaml).
    joint = bench_families.JOINT_CONFIG
    rows["joint_fp"] = (joint, "franka_joint", [], 0)
    rows["joint_mpd"] = (joint, "franka_joint", ["objective.name=ddpm"], 0)
    rows["joint_vae"] = (joint, "franka_joint", ["model.name=state_vae", "objective.name=vae", "train.batch_size=16"], 0)
    return rows


def table2_rows():
    """label -> row names (3 seeds) of FP trained on each augmentation scheme."""
    out = {CROSS_SETS[0][2]: [f"cross_fp_s{s}" for s in SEEDS]}
    for name, _, label in CROSS_SETS[1:]:
        out[label] = [f"{name[len('franka_'):]}_fp_s{s}" for s in SEEDS]
    return out


class Unavailable(Exception):
    """An input of an output is missing, or was made by another request; the message names it and what to do."""


class Bench:
    def __init__(self, args):
        self.root = args.root
        self.size = QUICK if args.quick else FULL
        self.flowplan = args.flowplan
        self.python = sys.executable
        self.quick = args.quick
        self.child = None  # the running command
        self.rows = args.rows  # None: every row
        self.adoptions = {}  # row -> a run folder trained outside the driver (--adopt), taken by the train stages
        # threads=N on every training and evaluation (not part of any request: results do not depend on it)
        self.threads = [] if args.threads is None else [f"threads={args.threads}"]

    def selected(self, rows):
        """The rows among `rows` that --rows selects, in --rows order (all of them without --rows)."""
        return list(rows) if self.rows is None else [row for row in self.rows if row in rows]

    def path(self, *parts):
        return os.path.join(self.root, *parts)

    def call(self, command, accept_refusal=False, accept_failure=False):
        """Runs a command, its output appended to ROOT/bench.log; returns (ok, output)."""
        started = time.time()
        self.child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        stdout = stderr = ""
        try:
            stdout, stderr = self.child.communicate()
        except KeyboardInterrupt:  # the command got the signal too (main forwards SIGTERM): let it stop cleanly
            stdout, stderr = self.child.communicate()
            raise
        finally:
            with open(self.path("bench.log"), "a") as log:
                log.write(f"$ {shlex.join(command)}\n{stdout}{stderr}[exit {self.child.returncode}, "
                          f"{time.time() - started:.1f} s]\n")
        done = subprocess.CompletedProcess(command, self.child.returncode, stdout, stderr)
        self.child = None
        refused = accept_refusal and "inside obstacle" in done.stdout + done.stderr
        if done.returncode != 0 and not refused and not accept_failure:
            sys.exit(f"failed: {' '.join(command)}\n{done.stderr[-3000:]}{done.stdout[-2000:]}")
        return done.returncode == 0, done.stdout + done.stderr

    # -- requests: what makes each output ---------------------------------------
    def request(self, command, *inputs, sections=None):
        """The text that identifies an output: COMMAND with ROOT and the binary as placeholders (so a moved folder
        stays valid), the YAML files it names (parsed, so that comments do not count; only the top-level SECTIONS
        if given), then the requests of the outputs it reads (INPUTS), so that a changed data set makes its models
        stale, and a changed model its plans."""
        import yaml
        text = [shlex.join(command).replace(self.flowplan, "{flowplan}").replace(self.root + os.sep, "{root}/")]
        for argument in command:
            value = argument.partition("=")[2] if "=" in argument else argument
            if value.endswith(".yaml") and os.path.isfile(value) and not value.startswith(self.root + os.sep):
                content = yaml.safe_load(open(value))
                if sections is not None:
                    content = {k: v for k, v in content.items() if k in sections}
                text.append(f"--- {value}: " + json.dumps(content, sort_keys=True))
        return "\n".join(text + list(inputs)) + "\n"

    def data_command(self, name):
        """(output, command, request) of data set NAME."""
        config = next(c for n, c in DATA_SETS if n == name)
        out = self.path("data", f"{name}.h5")
        episodes = [f"generate.episodes={self.size['episodes']}"] if self.size["episodes"] else []
        command = [self.flowplan, "generate", "--config", config, f"generate.out={out}", *episodes]
        return out, command, self.request(command, sections=("generate", "seed"))  # all that generation reads

    def data_request(self, name):
        """The request of data set NAME, which must have been made by it."""
        out, _, request = self.data_command(name)
        if not (os.path.exists(out) and recorded(out + ".request", request)):
            raise Unavailable(f"{out}: not made by the current request; run the data stage first")
        return request

    def train_command(self, row):
        """(command, request) that trains ROW from scratch."""
        config, data, overrides, seed = train_rows()[row]
        command = [self.flowplan, "train", "--config", config, f"seed={seed}", f"run_dir={self.path('train', row)}",
                   f"data.path={self.path('data', data + '.h5')}", *overrides, *self.size["train"]]
        # The whole config counts: the checkpoint carries it, and `flowplan plan --ckpt` plans with its guidance.
        return command, self.request(command, self.data_request(data))

    def check_training_request(self, row, before, request):
        """Raises Unavailable if ROW was trained (or began training) by another request than REQUEST."""
        if before != request:
            run = self.path("train", row)
            raise Unavailable(
                f"{run}: trained by another request than the driver's now (a changed config, override or data set, "
                f"or none recorded).\n--- recorded:\n{before}\n--- now:\n{request}"
                f"Delete {run} to train it again, or move it aside to keep it.")

    def model_request(self, row):
        """The training request of ROW, whose training must have finished (done.json) by the current request."""
        run = self.path("train", row)
        done = os.path.join(run, "done.json")
        if not os.path.exists(done):
            raise Unavailable(f"{run}: not trained to the end (no done.json); run the train-reach / train-cross "
                              "stage first")
        _, request = self.train_command(row)
        self.check_training_request(row, json.load(open(done)).get("request"), request)
        return request

    def stitching_command(self, row):
        """(output, command, request, plans) of ROW's stitching report."""
        import h5py
        data = train_rows()[row][1]
        model = self.model_request(row)
        out = self.path("stitching", f"{row}.json")
        # plans_per_pair plans for each test pair (plan i targets pair i mod P in `flowplan eval stitching`)
        with h5py.File(self.path("data", data + ".h5"), "r") as f:
            pairs = f["eval/test_pairs/start"].shape[0]
        plans = self.size["plans_per_pair"] * pairs
        command = [self.flowplan, "eval", "stitching", "--ckpt", self.path("train", row), "--out", out + ".tmp",
                   f"data.path={self.path('data', data + '.h5')}", f"eval.num_plans={plans}"]
        return out, command, self.request(command, model), plans

    def planner_source(self, planner):
        """(`flowplan plan` arguments choosing PLANNER, the request of the model or robot they read)."""
        _, _, row, overrides = next(p for p in PLANNERS if p[0] == planner)
        if row is None:
            return (["--rrt-connect", "--config", REACH_CONFIG, f"data.path={self.path('data', 'franka_reach.h5')}"],
                    self.data_request("franka_reach"))
        return ["--ckpt", self.path("train", row), *overrides], self.model_request(row)

    def plan_command(self, prefix, planner, radius, plans, extra=(), plot=False):
        """(command, request) of one `flowplan plan` call on the paper's scene, writing PREFIX.*."""
        source, model = self.planner_source(planner)
        scene = ["--scene", SCENE, "--radius", str(radius)] if radius > 0 else ["--scene", self.empty_scene()]
        command = [self.flowplan, "plan", *source, *extra, "--start-tcp", START_TCP, "--goal-tcp", GOAL_TCP, *scene,
                   "-n", str(plans), "--seed", "1", "--execute", *([] if plot else ["--no-plot"]),
                   "--log-level", "warn", "--out", prefix]
        return command, self.request(command, model)

    def problems_command(self):
        out = self.path("problems.yaml")
        command = [self.flowplan, "problems", "--out", out, f"problems.count={self.size['problems']}"]
        return out, command, self.request(command)

    def problem_planner_request(self, planner, problems_request):
        source, model = self.planner_source(planner)
        return source, self.request(source + ["--samples", str(self.size["problem_plans"])], model, problems_request)

    # -- data -----------------------------------------------------------------
    def data(self):
        for name, _ in DATA_SETS:
            out, command, request = self.data_command(name)
            with stale(lambda: os.path.exists(out) and recorded(out + ".request", request), out + ".lock",
                       [out, out + ".request"]) as ours:
                if ours:
                    print(f"data: {name}", flush=True)
                    self.call(command)
                    write_text(out + ".request", request)  # last: a request marks a finished output

    # -- train ----------------------------------------------------------------
    def train_reach(self):
        self.train([row for row in train_rows() if row.startswith("reach_")])

    def train_cross(self):
        self.train([row for row in train_rows() if row.startswith("cross_")])

    def train_long(self):
        self.train(self.long_rows())

    def train_joint(self):
        self.train([row for row in train_rows() if row.startswith("joint_")])

    def families(self):
        bench_families.Families(self, sys.modules[__name__]).run()

    def adopt(self, row, run):
        """Takes RUN, trained outside the driver, as training ROW: its resolved config must be the one ROW's command
        makes (run_dir, data.path and threads aside), and it must have trained all its steps."""
        import yaml
        if row not in train_rows():
            sys.exit(f"--adopt: unknown row {row!r}")
        target = self.path("train", row)
        if os.path.exists(os.path.join(target, "done.json")):
            return
        command, request = self.train_command(row)
        probe = self.path("adopt", row)
        shutil.rmtree(probe, ignore_errors=True)
        # The config the row's command resolves to, from `flowplan config show` of the same arguments.
        shown = subprocess.run([self.flowplan, "config", "show", *command[2:]], capture_output=True, text=True)
        if shown.returncode != 0:
            sys.exit(f"--adopt {row}: {shown.stderr.strip()}")
        ignore = lambda c: {k: v for k, v in c.items() if k not in ("run_dir", "threads")} | {
            "data": {k: v for k, v in c["data"].items() if k != "path"}}
        # The run's config resolved by this flowplan too (sections newer than the run get their defaults).
        resolved = subprocess.run([self.flowplan, "config", "show", "--config", os.path.join(run, "config.yaml")],
                                  capture_output=True, text=True)
        if resolved.returncode != 0:
            sys.exit(f"--adopt {row}: {resolved.stderr.strip()}")
        wanted, theirs = yaml.safe_load(shown.stdout), yaml.safe_load(resolved.stdout)
        if ignore(wanted) != ignore(theirs):
            different = sorted(k for k in set(wanted) | set(theirs) if ignore(wanted).get(k) != ignore(theirs).get(k))
            sys.exit(f"--adopt {row}: {run}/config.yaml differs from the row's config in {', '.join(different)}")
        metrics = [json.loads(line) for line in open(os.path.join(run, "metrics.jsonl"))]
        steps = max(m.get("step", 0) for m in metrics)
        # Its training time from the logged rates: each logged row covers the steps since the one before.
        seconds, before = 0.0, 0
        for m in metrics:
            if "steps_per_s" in m:
                seconds += (m["step"] - before) / m["steps_per_s"]
                before = m["step"]
        if steps != wanted["train"]["steps"]:
            sys.exit(f"--adopt {row}: {run} trained {steps} of {wanted['train']['steps']} steps")
        shutil.copytree(run, target)
        write_text(os.path.join(target, "request.txt"), request)
        config, data, overrides, seed = train_rows()[row]
        write_json(os.path.join(target, "done.json"), {"row": row, "config": config, "data": data, "overrides": overrides,
                                                       "seed": seed, "steps": steps, "adopted_from": run,
                                                       "train_seconds": round(seconds, 1), "request": request})
        print(f"adopted {run} as {row}", flush=True)

    def train(self, rows):
        for row in self.selected(rows):
            config, data, overrides, seed = train_rows()[row]
            run = self.path("train", row)
            done = os.path.join(run, "done.json")
            marker = os.path.join(run, "request.txt")  # written first: the checkpoints beside it are its
            command, request = self.train_command(row)
            if os.path.exists(done):
                self.check_training_request(row, json.load(open(done)).get("request"), request)
                continue
            if row in self.adoptions:
                self.adopt(row, self.adoptions[row])
                continue
            lock = claim(self.path("train", f"{row}.lock"))
            if lock is None:
                print(f"train: {row} is being trained by another driver, skipped", flush=True)
                continue
            if os.path.exists(done):  # finished by another driver since
                lock.close()
                continue
            print(f"train: {row}", flush=True)
            started = time.time()
            partial = os.path.join(run, "train_seconds.txt")  # seconds of this row's stopped invocations
            try:
                if glob.glob(os.path.join(run, "checkpoints", "step_*.pt")):
                    self.check_training_request(row, open(marker).read() if os.path.exists(marker) else None, request)
                    self.call([self.flowplan, "train", "--resume", run, *self.threads])
                else:
                    shutil.rmtree(run, ignore_errors=True)  # nothing worth keeping: no checkpoint
                    write_text(marker, request)
                    self.call(command + self.threads)
            finally:  # also when stopped: the next invocation adds its own time
                earlier = float(open(partial).read()) if os.path.exists(partial) else 0.0
                if os.path.isdir(run):
                    write_text(partial, f"{earlier + time.time() - started:.1f}\n")
            seconds = float(open(partial).read())
            steps = max(json.loads(line).get("step", 0) for line in open(os.path.join(run, "metrics.jsonl")))
            write_json(done, {"row": row, "config": config, "data": data, "overrides": overrides, "seed": seed,
                              "steps": steps, "train_seconds": round(seconds, 1), "request": request})
            lock.close()

    # -- stitching ------------------------------------------------------------
    def stitching(self):
        for row in self.selected(train_rows()):
            if not train_rows()[row][1].startswith("franka_cross") or row.startswith("long_"):
                continue  # the long rows are evaluated at each checkpoint by the curve stage
            if not os.path.exists(self.path("train", row, "done.json")):
                print(f"stitching: {row} not trained yet, skipped", flush=True)
                continue
            out, command, request, plans = self.stitching_command(row)
            # `flowplan eval stitching --out X.json.tmp` writes its plans to X.json.plans.h5
            with stale(lambda: os.path.exists(out) and recorded(out + ".request", request), out + ".lock",
                       [out, out + ".plans.h5", out + ".request"]) as ours:
                if ours:
                    print(f"stitching: {row}", flush=True)
                    self.call(command)
                    report = json.load(open(out + ".tmp"))
                    if report["test"]["num_plans"] != plans:
                        sys.exit(f"{out}.tmp: {report['test']['num_plans']} test plans, expected {plans}")
                    os.replace(out + ".tmp", out)
                    write_text(out + ".request", request)

    # -- planning around spheres ---------------------------------------------
    def plan_cell(self, prefix, planner, radius, plans, extra=(), plot=False):
        """One `flowplan plan` call on the paper's scene. Its request, written last, marks PREFIX.json (or
        PREFIX.refused: the start or goal lies inside the sphere) and PREFIX.png, if drawn, as finished."""
        command, request = self.plan_command(prefix, planner, radius, plans, extra, plot)
        with stale(lambda: recorded(prefix + ".request", request), prefix + ".lock",
                   [prefix + ext for ext in (".json", ".h5", ".png", ".refused", ".request")]) as ours:
            if ours:
                ok, output = self.call(command, accept_refusal=True)
                if not ok:
                    write_text(prefix + ".refused", output)
                write_text(prefix + ".request", request)

    def empty_scene(self):
        path = self.path("scenes", "empty.yaml")
        if not os.path.exists(path):
            write_text(path, "spheres: []\n")
        return path

    def sweep(self):
        for radius in self.size["radii"]:
            for planner, *_ in PLANNERS:
                self.plan_cell(self.path("sweep", f"{planner}_r{radius:g}"), planner, radius, self.size["sweep_plans"])
            print(f"sweep: radius {radius:g} done", flush=True)

    def scales(self):
        for radius in self.size["scale_radii"]:
            for scale in self.size["scales"]:
                self.plan_cell(self.path("scales", f"s{scale:g}_r{radius:g}"), "fp_split", radius,
                               self.size["sweep_plans"], extra=[f"guidance.scale={scale}"])
            print(f"scales: radius {radius:g} done", flush=True)

    def budget(self):
        for radius in self.size["radii"]:
            for name, _, overrides in MPD_BUDGETS:
                self.plan_cell(self.path("budget", f"{name}_r{radius:g}"), "mpd", radius, self.size["sweep_plans"],
                               extra=overrides)
            print(f"budget: radius {radius:g} done", flush=True)

    def problems(self):
        lock = claim(self.path("problems.lock"))
        if lock is None:
            print("problems: another driver is on them, skipped", flush=True)
            return
        problems, command, made = self.problems_command()
        if not (os.path.exists(problems) and recorded(problems + ".request", made)):
            discard([problems, problems + ".request", self.path("problems")])
            self.call(command)
            write_text(problems + ".request", made)
        # One request per planner, written before its first plan: franka_problems.py resumes per problem, and the
        # reports in problems/<planner>/ are that request's. A planner whose model or arguments changed plans again.
        summary = self.path("problems", "summary.json")
        specs = []
        for planner, *_ in PLANNERS:
            source, request = self.problem_planner_request(planner, made)
            specs += ["--planner", f"{planner}={shlex.join(source)}"]
            marker = self.path("problems", f"{planner}.request")
            if not recorded(marker, request):
                discard([summary, self.path("problems", planner), marker])
                write_text(marker, request)
        if os.path.exists(summary):
            return
        print("problems: every planner on every problem", flush=True)
        self.call([self.python, "scripts/franka_problems.py", problems, "--out", self.path("problems"),
                   "--samples", str(self.size["problem_plans"]), "--flowplan", self.flowplan, *specs])

    def examples(self):
        for radius in self.size["example_radii"]:
            for planner, *_ in PLANNERS:
                self.plan_cell(self.path("results", f"example_{planner}_r{radius:g}"), planner, radius,
                               self.size["example_plans"], plot=True)

    def recount(self):
        plans = [self.path(d) for d in ("sweep", "scales", "budget") if os.path.isdir(self.path(d))]
        plans += [self.path("problems", p) for p, *_ in PLANNERS if os.path.isdir(self.path("problems", p))]
        plans += [self.path("families", "test")] if os.path.isdir(self.path("families", "test")) else []
        ok, _ = self.call([self.python, "scripts/recount_plans.py", "--out", self.path("results", "recount.json"), *plans],
                          accept_failure=True)
        if not ok:
            print("recount: some files differ (ROOT/results/recount.json, ROOT/bench.log)", flush=True)

    # -- guidance selection ---------------------------------------------------
    def select_commands(self):
        """(commands, request) of the select stage: the two problem sets, the exports, then the selection."""
        commands, inputs = [], []
        for name, seed in SELECT_SEEDS.items():
            commands.append([self.flowplan, "problems", "--out", self.path("select", f"{name}.yaml"), f"seed={seed}",
                             f"problems.count={self.size['select_problems']}", *SELECT_PROBLEMS])
        selection = [self.python, "scripts/guidance_select.py"]
        for name, row, overrides in SELECT_PLANNERS:
            out = self.path("select", f"{name}.pt")
            commands.append([self.flowplan, "export", "--ckpt", self.path("train", row), "--out", out, *overrides])
            inputs.append(self.model_request(row))
            selection += ["--planner", f"{name}={out}"]
        for name, row, overrides in SELECT_PLANNERS:
            if name not in SELECT_REPLICATED:
                continue
            for seed in REACH_SEEDS[1:]:
                out = self.path("select", f"{name}_s{seed}.pt")
                commands.append([self.flowplan, "export", "--ckpt", self.path("train", f"{row}_s{seed}"), "--out", out,
                                 *overrides])
                inputs.append(self.model_request(f"{row}_s{seed}"))
                selection += ["--replicate", f"{name}={out}"]
        commands.append(selection + ["--flowplan", self.flowplan,
                                     "--val", self.path("select", "val.yaml"), "--test", self.path("select", "test.yaml"),
                                     "--out", self.path("select"), "--plans", str(self.size["select_plans"]),
                                     "--warmup", str(self.size["select_warmup"]), "--rows", str(self.size["select_rows"])])
        request = "".join(self.request(c) for c in commands)
        return commands, self.request([], request, *inputs)

    def select(self):
        commands, request = self.select_commands()
        marker = self.path("select.request")
        done = self.path("select", "success_vs_time.png")  # guidance_select.py writes it last
        lock = claim(self.path("select.lock"))
        if lock is None:
            print("select: another driver is on it, skipped", flush=True)
            return
        try:
            if recorded(marker, request) and os.path.exists(done):
                return
            if not recorded(marker, request):  # the cached rows are of another request
                discard([self.path("select")])
                write_text(marker, request)
            print("select: guidance settings chosen on validation problems, reported on test problems", flush=True)
            for command in commands[:-1]:
                self.call(command)
            # the selection keeps each setting's result in select/rows/, so a stopped run continues; it plans on one
            # thread whatever --threads says, since its choices compare times per plan
            self.call(commands[-1])
        finally:
            lock.close()

    # -- training budget ------------------------------------------------------
    def long_rows(self):
        """The long rows of this size: every one in the full run; in the quick one, one of each length."""
        rows = [row for row in train_rows() if row.startswith("long_")]
        if self.size["long_rows"] is None:
            return rows
        assert set(self.size["long_rows"]) <= set(rows), self.size["long_rows"]
        return self.size["long_rows"]

    def curve_steps(self, row):
        """The steps of curve_steps at which long row ROW has a checkpoint (those up to its last step)."""
        _, _, overrides, _ = train_rows()[row]
        last = [int(o.split("=", 1)[1]) for o in [*overrides, *self.size["train"]] if o.startswith("train.steps=")][-1]
        return [step for step in self.size["curve_steps"] if step <= last]

    def curve_commands(self, row, step):
        """[(prefix, command, request, outputs)] of the evaluations of ROW's checkpoint at STEP: stitching without
        and with splitting, then the sphere of each radius in CURVE_RADII."""
        data = train_rows()[row][1]
        model = self.model_request(row)
        checkpoint = self.path("train", row, "checkpoints", f"step_{step:08d}.pt")
        prefix = self.path("curve", f"{row}_k{step}")
        _, _, _, plans = self.stitching_command(row)
        cells = []
        for name, extra in (("", []), ("_split", ["sampler.splitting=midpoint"])):
            out = prefix + name + ".json"
            command = [self.flowplan, "eval", "stitching", "--ckpt", checkpoint, "--out", out + ".tmp",
                       f"data.path={self.path('data', data + '.h5')}", f"eval.num_plans={plans}", *extra]
            cells.append((out, command, self.request(command, model), [out, out + ".plans.h5"]))
        for radius in CURVE_RADII:
            out = f"{prefix}_r{radius:g}"
            command = [self.flowplan, "plan", "--ckpt", checkpoint, *CURVE_GUIDANCE, "--start-tcp", START_TCP,
                       "--goal-tcp", GOAL_TCP, "--scene", SCENE, "--radius", str(radius), "-n",
                       str(self.size["sweep_plans"]), "--seed", "1", "--no-plot", "--log-level", "warn", "--out", out]
            cells.append((out + ".json", command, self.request(command, model), [out + ".json", out + ".h5"]))
        return cells

    def curve(self):
        for row in self.selected(self.long_rows()):
            if not os.path.exists(self.path("train", row, "done.json")):
                print(f"curve: {row} not trained yet, skipped", flush=True)
                continue
            for step in self.curve_steps(row):
                for out, command, request, outputs in self.curve_commands(row, step):
                    with stale(lambda: os.path.exists(out) and recorded(out + ".request", request), out + ".lock",
                               outputs + [out + ".request"]) as ours:
                        if ours:
                            self.call(command + self.threads)
                            if os.path.exists(out + ".tmp"):  # `eval stitching --out X.tmp`
                                plans = self.stitching_command(row)[3]
                                if json.load(open(out + ".tmp"))["test"]["num_plans"] != plans:
                                    sys.exit(f"{out}.tmp: expected {plans} test plans")
                                os.replace(out + ".tmp", out)
                            write_text(out + ".request", request)
                print(f"curve: {row} at step {step} done", flush=True)

    # -- results: only outputs of the current requests --------------------------
    def current(self, make_request, marker):
        """Whether the output whose request MARKER holds is that of the current request (make_request() ->
        request); an output whose inputs are missing or stale is not current. Others are counted in self.left_out."""
        if not os.path.exists(marker):
            return False
        try:
            request = make_request()
        except Unavailable:
            request = None
        if recorded(marker, request or ""):
            return True
        self.left_out.append(marker[:-len(".request")])
        return False

    def stitching_report(self, row):
        """ROW's stitching report, if made by the current request."""
        out = self.path("stitching", f"{row}.json")
        return json.load(open(out)) if self.current(lambda: self.stitching_command(row)[2], out + ".request") else None

    def plan_report(self, prefix, *cell):
        """{'refused': True}, PREFIX.json's report, or None (not made by the current request)."""
        if not self.current(lambda: self.plan_command(prefix, *cell)[1], prefix + ".request"):
            return None
        return {"refused": True} if os.path.exists(prefix + ".refused") else json.load(open(prefix + ".json")) | {
            "refused": False}

    def problem_summary(self):
        """problems/summary.json, if every planner's reports are those of the current requests."""
        summary = self.path("problems", "summary.json")
        if not os.path.exists(summary):
            return None
        _, _, made = self.problems_command()
        if not self.current(lambda: made, self.path("problems.yaml.request")):
            return None
        for planner, *_ in PLANNERS:
            if not self.current(lambda: self.problem_planner_request(planner, made)[1],
                                self.path("problems", f"{planner}.request")):
                return None
        return json.load(open(summary))

    def trained_row(self, row):
        """ROW's done.json, if trained by the current request."""
        done = self.path("train", row, "done.json")
        if not os.path.exists(done):
            return None
        try:
            self.model_request(row)
        except Unavailable:
            self.left_out.append(done)
            return None
        return json.load(open(done))

    def results(self):
        os.makedirs(self.path("results"), exist_ok=True)
        self.left_out = []
        summary = {"root": self.root, "quick": self.quick, "sizes": self.size}
        text = [f"Made by `scripts/franka_bench.py{' --quick' if self.quick else ''} --root {self.root}`.\n"]
        text += stitching_tables(self, summary)
        text += obstacle_tables(self, summary)
        text += problem_table(self, summary)
        recount = self.path("results", "recount.json")
        if os.path.exists(recount):
            r = json.load(open(recount))
            summary["recount"] = {k: r[k] for k in ("files", "plans", "differ")}
            text.append(f"Independent recount (scripts/recount_plans.py, its own kinematics) of {r['plans']} saved plans "
                        f"in {r['files']} files: {r['differ']} files with a different TCP or whole-arm count.\n")
        text += select_table(self, summary)
        text += bench_families.Families(self, sys.modules[__name__]).results(summary)
        text += curve_table(self, summary)
        text.append(training_table(self, summary))
        summary["left_out"] = sorted(set(self.left_out))
        if self.left_out:
            text.append("Left out, made by another request than the driver's now (run their stages again): " +
                        ", ".join(summary["left_out"]) + "\n")
            print(f"results: {len(summary['left_out'])} outputs of another request left out", flush=True)
        write_text(self.path("results", "summary.md"), "\n".join(text))
        write_json(self.path("results", "summary.json"), summary)
        print("\n".join(text))


def claim(path):
    """An exclusive lock on PATH (an open file; close it to release), or None if another process holds it.
    Several drivers may share a root (e.g. two on a four-core machine): each row is trained and evaluated
    by whichever locks it first."""
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    lock = open(path, "w")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        lock.close()
        return None
    return lock


@contextlib.contextmanager
def stale(is_current, lock_path, outputs):
    """Yields True to the one driver that is to make an output: is_current() is false, before and after it locks
    LOCK_PATH (another driver may have made it meanwhile); the OUTPUTS of another request are removed first.
    Yields False when the output is current or another driver holds the lock."""
    if is_current():
        yield False
        return
    lock = claim(lock_path)
    if lock is None:
        yield False
        return
    try:
        ours = not is_current()
        if ours:
            discard(outputs)
        yield ours
    finally:
        lock.close()


def recorded(marker, request):
    """Whether MARKER holds REQUEST (the output beside it was made by this request)."""
    return os.path.exists(marker) and open(marker).read() == request


def discard(paths):
    """Removes the outputs of another request (files or folders), before the new request is written beside them,
    so that a new request never sits beside an older output."""
    present = [p for p in paths if os.path.exists(p)]
    if present:
        print(f"stale (made by another request), made again: {', '.join(present)}", flush=True)
    for path in present:
        shutil.rmtree(path) if os.path.isdir(path) else os.remove(path)


def write_text(path, text):
    os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
    with open(path + ".tmp", "w") as f:
        f.write(text)
    os.replace(path + ".tmp", path)


def write_json(path, value):
    write_text(path, json.dumps(value, indent=1) + "\n")


def mean_and_sample_std(values):
    """Mean and the sample standard deviation (n - 1; None for one value)."""
    n = len(values)
    mean = sum(values) / n
    return mean, (sum((v - mean) ** 2 for v in values) / (n - 1)) ** 0.5 if n > 1 else None


def stitching_cell(bench, rows):
    """(text, json) of one table cell: one row, or several seeds."""
    found = [(row, bench.stitching_report(row)) for row in rows]
    found = [(row, r["test"]) for row, r in found if r is not None]
    if not found:
        return "not run", None
    if len(rows) == 1:
        r = found[0][1]
        return f"{r['mean']:.2f} ± {r['stddev']:.2f}", {"mean": r["mean"], "stddev": r["stddev"]}
    means = [r["mean"] for _, r in found]
    mean, spread = mean_and_sample_std(means)
    seeds = ", ".join(f"{r['mean']:.2f} ± {r['stddev']:.2f}" for _, r in found)
    missing = "" if len(found) == len(rows) else f"; {len(rows) - len(found)} of {len(rows)} seeds not run"
    across = "" if spread is None else f" ± {spread:.2f}"
    return (f"{mean:.2f}{across} (seeds: {seeds}{missing})",
            {"mean_of_seeds": mean, "std_of_seed_means": spread,
             "seeds": {row: {"mean": r["mean"], "stddev": r["stddev"]} for row, r in found}})


def stitching_tables(bench, summary):
    size = bench.size
    text = ["### Stitching, table 1 (franka_cross, per-joint torque noise)\n",
            f"Stitching error on the two test pairs, {size['plans_per_pair']} plans per pair (mean ± std over the plans "
            "of both pairs; a row of "
            "several seeds: the mean of the seeds' means ± their sample standard deviation, then every seed's "
            "mean ± std over its plans).\n", "| model | ours | paper |", "|---|---|---|"]
    summary["table1"] = {}
    for label, prefix, _, seeds in TABLE1:
        rows = [f"{prefix}_s{s}" for s in seeds] if len(seeds) > 1 else [prefix]
        cell, value = stitching_cell(bench, rows)
        summary["table1"][label] = value
        text.append(f"| {label} | {cell} | {PAPER_TABLE1[label]} |")
    text += ["", "### Stitching, table 2 (FP trained on each augmentation scheme)\n",
             "| augmentation | ours | paper |", "|---|---|---|"]
    summary["table2"] = {}
    for label, rows in table2_rows().items():
        cell, value = stitching_cell(bench, rows)
        summary["table2"][label] = value
        text.append(f"| {label} | {cell} | {PAPER_TABLE2[label]} |")
    return text + [""]


def read_cells(bench, cells_to_read):
    """{key: report summary or {'refused': True}} of the plan cells (key, prefix, planner, radius, plans, extra)
    made by the current request."""
    cells = {}
    for key, prefix, *cell in cells_to_read:
        report = bench.plan_report(prefix, *cell)
        if report is None:
            continue
        if report["refused"]:
            cells[key] = {"refused": True}
        else:
            cells[key] = {k: report.get(k) for k, _ in WAYS} | {
                "refused": False, "num_samples": report["num_samples"], ANY_SPEED[0]: tcp_any_speed(report),
                "wall_time_s": report["wall_time_s"], "planning_time_s_per_plan": report["wall_time_s"] /
                report["num_samples"]}
    return cells


def tcp_any_speed(report):
    """The fraction of a plan report's plans whose TCP stays clear and ends within the goal tolerance, without the
    joint-speed limit of its success counts (None for a report without plans)."""
    samples = report.get("samples") or []
    if not samples:
        return None
    return sum(not s["tcp_collision"] and s["goal_distance"] <= report["goal_tolerance"] for s in samples) / len(samples)


def rate_text(cell, key):
    if cell is None:
        return ""
    if cell["refused"]:
        return "refused"
    return "–" if cell[key] is None else f"{cell[key]:.0%}"


def obstacle_tables(bench, summary):
    size, radii = bench.size, bench.size["radii"]
    cells = read_cells(bench, [((p, r), bench.path("sweep", f"{p}_r{r:g}"), p, r, size["sweep_plans"])
                               for p, *_ in PLANNERS for r in radii])
    summary["sweep"] = [{"planner": p, "radius": r, **c} for (p, r), c in sorted(cells.items())]
    summary["largest_radius_90"] = {}
    text = ["### Obstacle avoidance (franka_reach models, the paper's scene)\n",
            f"Success over {size['sweep_plans']} plans per radius, counted three ways (each also needs the last TCP "
            "within 3 cm of the goal and joint speeds within 1.5 times the limits) and, as the paper counts, by the "
            "TCP at any joint speed; radius 0 is the empty scene; "
            "\"refused\": the start or goal TCP lies inside the sphere (counted as no success); \"largest radius\": the "
            "largest r such that every radius from 0 to r reaches 90 %.\n",
            "| planner, counted by | " + " | ".join(f"{r:g}" for r in radii) + " | largest radius ≥ 90 % | paper |",
            "|---|" + "---|" * (len(radii) + 2)]
    for planner, label, *_ in PLANNERS:
        for key, way in WAYS + [ANY_SPEED]:
            contiguous = largest_radius(cells, planner, key, radii)
            summary["largest_radius_90"][f"{planner}/{way}"] = contiguous
            paper = PAPER_RADIUS.get(planner) if key == ANY_SPEED[0] else None
            text.append(f"| {label}, {way} | " + " | ".join(rate_text(cells.get((planner, r)), key) for r in radii) +
                        f" | {'–' if contiguous is None else f'{contiguous:g}'} | {'' if paper is None else paper} |")
    text += ["\nPlanning time per plan (s) at each radius: the wall time of the `flowplan plan` call's planning (both "
             "cores, execution excluded) divided by its plans; the last column is the median over the radii.\n",
             "| planner | " + " | ".join(f"{r:g}" for r in radii) + " | median |", "|---|" + "---|" * (len(radii) + 1)]
    for planner, label, *_ in PLANNERS:
        times = [cells.get((planner, r)) for r in radii]
        median = median_time(cells, planner, radii)
        text.append(f"| {label} | " + " | ".join(
            "" if c is None else "refused" if c["refused"] else f"{c['planning_time_s_per_plan']:.3f}" for c in times) +
            f" | {'' if median is None else f'{median:.3f}'} |")
    text.append("")
    plot_sweep(cells, radii, bench.path("results", "success_vs_radius.png"))
    scale_cells = read_cells(bench, [((s, r), bench.path("scales", f"s{s:g}_r{r:g}"), "fp_split", r, size["sweep_plans"],
                                      [f"guidance.scale={s}"]) for s in size["scales"] for r in size["scale_radii"]])
    summary["scales"] = [{"scale": s, "radius": r, **c} for (s, r), c in sorted(scale_cells.items())]
    text += ["### Guidance scale, FP + split\n", "| scale | " + " | ".join(
        f"r {r:g}: TCP / arm / executed" for r in size["scale_radii"]) + " |",
        "|---|" + "---|" * len(size["scale_radii"])]
    for s in size["scales"]:
        text.append(f"| {s:g} | " + " | ".join(
            " / ".join(rate_text(scale_cells.get((s, r)), k) for k, _ in WAYS) for r in size["scale_radii"]) + " |")
    return text + [""] + budget_table(bench, summary, cells)


def largest_radius(cells, planner, key, radii):
    """The largest r with every radius from 0 up to r at >= 90 % success counted by KEY (None: not even 0)."""
    contiguous = None
    for r in radii:
        c = cells.get((planner, r))
        if not c or c["refused"] or c[key] is None or c[key] < 0.9:
            break
        contiguous = r
    return contiguous


def budget_table(bench, summary, sweep_cells):
    """MPD as in the sweep (FP's costs, 60 gradient steps) beside MPD with each of MPD_BUDGETS' settings."""
    size, radii = bench.size, bench.size["radii"]
    cells = {("mpd", r): c for (p, r), c in sweep_cells.items() if p == "mpd"}
    cells |= read_cells(bench, [((name, r), bench.path("budget", f"{name}_r{r:g}"), "mpd", r, size["sweep_plans"],
                                 overrides) for name, _, overrides in MPD_BUDGETS for r in radii])
    summary["budget"] = [{"planner": p, "radius": r, **c} for (p, r), c in sorted(cells.items()) if p != "mpd"]
    text = ["### MPD's guidance settings\n",
            f"The paper's scene, {size['sweep_plans']} plans per radius; MPD as in the sweep (FP's cost weights, 60 "
            "gradient steps per plan), at FP's budget of gradient steps, and with MPD's published cost weights.\n",
            "| planner, counted by | " + " | ".join(f"{r:g}" for r in radii) + " | largest radius ≥ 90 % |",
            "|---|" + "---|" * (len(radii) + 1)]
    for name, label in [("mpd", "MPD, 60 gradient steps")] + [(n, l) for n, l, _ in MPD_BUDGETS]:
        for key, way in WAYS + [ANY_SPEED]:
            contiguous = largest_radius(cells, name, key, radii)
            summary.setdefault("budget_largest_radius_90", {})[f"{name}/{way}"] = contiguous
            text.append(f"| {label}, {way} | " + " | ".join(rate_text(cells.get((name, r)), key) for r in radii) +
                        f" | {'–' if contiguous is None else f'{contiguous:g}'} |")
    return text + [""]


def select_table(bench, summary):
    """The select stage's tables (select/selection.md) and plot, if made by the current request."""
    marker, report = bench.path("select.request"), bench.path("select", "selection.md")
    made = [report, bench.path("select", "test.json"), bench.path("select", "success_vs_time.png")]
    if not all(os.path.exists(p) for p in made) or not bench.current(lambda: bench.select_commands()[1], marker):
        return ["### Guidance chosen on validation problems\n", "Not run.\n"]
    test = json.load(open(bench.path("select", "test.json")))
    summary["select"] = {"chosen": test["chosen"], "test": test["rows"], "test_other_seeds": test["replicate_rows"],
                         "test_checked": test.get("checked_rows", []), "test_problems": test["problems"],
                         "plans_per_problem": test["plans_per_problem"]}
    shutil.copyfile(bench.path("select", "success_vs_time.png"), bench.path("results", "success_vs_time.png"))
    seeds = ", ".join(f"{name} seed {seed}" for name, seed in SELECT_SEEDS.items())
    return ["### Guidance chosen on validation problems\n",
            f"Problems: {seeds}; every setting on validation, the chosen ones and the defaults on test "
            "(scripts/guidance_select.py; plot: success_vs_time.png). The test rows of "
            f"{', '.join(SELECT_REPLICATED)} are planned again with the models of training seeds "
            f"{', '.join(map(str, REACH_SEEDS[1:]))} (models 2–{len(REACH_SEEDS)}; model 1 is seed {REACH_SEEDS[0]}).\n",
            open(report).read()]


def curve_table(bench, summary):
    """The training-budget curve: each long row's stitching error, validation loss and success around the paper's
    sphere at each checkpoint of curve_steps, beside the table-1 rows whose schedule ends at 2,000 steps."""
    summary["curve"] = {}
    text = ["### Training budget (FP on franka_cross)\n",
            "Each run trained for its steps with its cosine schedule, evaluated (EMA weights) at the "
            "checkpoints below: a checkpoint before the end is mid-schedule, not a run of that length. Stitching: "
            "mean ± std over the test-pair plans; sphere: the cross planner guided around the paper's sphere on the "
            f"stitching pair ({' '.join(CURVE_GUIDANCE)}), {bench.size['sweep_plans']} plans, TCP / whole arm.\n",
            "| run | step | validation loss | stitching | stitching, split | " +
            " | ".join(f"sphere {r:g} m" for r in CURVE_RADII) + " |", "|---|---|---|---|---|" + "---|" * len(CURVE_RADII)]
    for row in bench.long_rows():
        if bench.trained_row(row) is None:
            text.append(f"| {row} | not run | | | |" + " |" * len(CURVE_RADII))
            continue
        losses = {}
        for line in open(bench.path("train", row, "metrics.jsonl")):
            record = json.loads(line)
            if "val_loss" in record:
                losses[record["step"]] = record["val_loss"]
        for step in bench.curve_steps(row):
            cells, point = [], {"val_loss": losses.get(step)}
            for out, _, request, _ in bench.curve_commands(row, step):
                if not bench.current(lambda: request, out + ".request"):
                    cells.append("")
                    continue
                report = json.load(open(out))
                if "test" in report:
                    key = "stitching_split" if out.endswith("_split.json") else "stitching"
                    point[key] = {"mean": report["test"]["mean"], "stddev": report["test"]["stddev"]}
                    cells.append(f"{report['test']['mean']:.2f} ± {report['test']['stddev']:.2f}")
                else:
                    point[os.path.basename(out)[:-len(".json")].rsplit("_", 1)[1]] = {
                        "tcp": report["tcp_clear_rate"], "arm": report["arm_clear_rate"]}
                    cells.append(f"{report['tcp_clear_rate']:.0%} / {report['arm_clear_rate']:.0%}")
            summary["curve"].setdefault(row, {})[step] = point
            loss = "" if point["val_loss"] is None else f"{point['val_loss']:.4f}"
            text.append(f"| {row} | {step} | {loss} | " + " | ".join(cells) + " |")
    for seed in LONG_RUNS[""][1]:
        report = bench.stitching_report(f"cross_fp_s{seed}")
        if report is not None:
            text.append(f"| cross_fp_s{seed} (schedule ends at its steps) | {bench.trained_row(f'cross_fp_s{seed}')['steps']}"
                        f" | | {report['test']['mean']:.2f} ± {report['test']['stddev']:.2f} | |" + " |" * len(CURVE_RADII))
    if summary["curve"]:
        plot_curve(summary["curve"], bench.path("results", "training_budget.png"))
        text.append("\nPlot: training_budget.png. The paper's FP: 0.16 ± 0.07.")
    return text + [""]


def plot_curve(curve, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for row, points in curve.items():
        steps = sorted(points)
        for key, style in (("stitching", "-"), ("stitching_split", ":")):
            xs = [k for k in steps if key in points[k]]
            axes[0].plot(xs, [points[k][key]["mean"] for k in xs], style, marker="o", ms=3, label=f"{row} {key}")
        radii = sorted({r for k in steps for r in points[k] if r.startswith("r")})
        for radius in radii:
            xs = [k for k in steps if radius in points[k]]
            axes[1].plot(xs, [points[k][radius]["arm"] for k in xs], marker="o", ms=3, label=f"{row} {radius[1:]} m")
    axes[0].axhline(0.16, color="grey", lw=0.8, ls="--", label="paper FP")
    axes[0].set_ylabel("stitching error, test pairs")
    axes[1].set_ylabel("whole arm clear, goal reached")
    axes[1].set_ylim(0.0, 1.02)
    for axis in axes:
        axis.set_xscale("log")
        axis.set_xlabel("training step")
        axis.legend(fontsize=6)
    figure.tight_layout()
    os.makedirs(os.path.dirname(path), exist_ok=True)
    figure.savefig(path + ".tmp.png", dpi=70)
    os.replace(path + ".tmp.png", path)
    plt.close(figure)


def median_time(cells, planner, radii):
    """Median over the cells of a planner of the planning time per plan (the call's wall time / its plans)."""
    times = []
    for r in radii:
        c = cells.get((planner, r))
        if c and not c["refused"]:
            times.append(c["planning_time_s_per_plan"])
    if not times:
        return None
    times.sort()
    return (times[(len(times) - 1) // 2] + times[len(times) // 2]) / 2


def plot_sweep(cells, radii, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ways = WAYS + [ANY_SPEED]  # the last panel counts as the paper does
    figure, axes = plt.subplots(1, len(ways), figsize=(4.3 * len(ways), 3.8), sharey=True)
    for axis, (key, way) in zip(axes, ways):
        for planner, label, *_ in PLANNERS:
            xs = [r for r in radii if (planner, r) in cells and
                  (cells[(planner, r)]["refused"] or cells[(planner, r)][key] is not None)]
            ys = [0.0 if cells[(planner, r)]["refused"] else cells[(planner, r)][key] for r in xs]
            axis.plot(xs, ys, marker="o", ms=3, label=label)
        axis.axhline(0.9, color="grey", lw=0.8, ls="--")
        axis.set_title(f"success: {way}")
        axis.set_xlabel("sphere radius (m)")
    axes[0].set_ylabel("success rate")
    axes[0].legend(fontsize=8)
    figure.tight_layout()
    os.makedirs(os.path.dirname(path), exist_ok=True)
    figure.savefig(path + ".tmp.png", dpi=70)
    os.replace(path + ".tmp.png", path)
    plt.close(figure)


def problem_table(bench, summary):
    problems = bench.problem_summary()
    if problems is None:
        return ["### Random blocked scenes: not run\n"]
    summary["problems"] = problems
    text = [f"### Random blocked scenes ({problems['problems']} problems of `flowplan problems`, 1–8 spheres)\n",
            "| planner | TCP | whole arm | executed | problems solved (arm) | planning time per plan (s) |",
            "|---|---|---|---|---|---|"]
    for planner, label, *_ in PLANNERS:
        row = problems["planners"].get(planner)
        if row:
            text.append(f"| {label} | " + " | ".join(f"{row[k]:.0%}" for k, _ in WAYS) +
                        f" | {row['problems_solved_arm']:.0%} | {row['planning_time_s_per_plan']:.3f} |")
    return text + [""]


def training_table(bench, summary):
    """Every row's training (steps, seconds) and, for a franka_cross row, its stitching error on the test pairs
    beside the error on the training pairs (how well the model reproduces the data it saw)."""
    text = ["### Training runs\n", "| row | steps | seconds | stitching error, test pairs | training pairs |",
            "|---|---|---|---|---|"]
    summary["train"] = {}
    summary["stitching"] = {}
    for row in train_rows():
        done = bench.trained_row(row)
        if done is None:
            text.append(f"| {row} | not run | | | |")
            continue
        summary["train"][row] = {k: v for k, v in done.items() if k != "request"}
        cells = ["", ""]
        report = bench.stitching_report(row) if row.startswith("cross_") else None
        if report is not None:
            summary["stitching"][row] = {k: {"mean": report[k]["mean"], "stddev": report[k]["stddev"]}
                                         for k in ("test", "train")}
            cells = [f"{report[k]['mean']:.2f} ± {report[k]['stddev']:.2f}" for k in ("test", "train")]
        text.append(f"| {row} | {done['steps']} | {done['train_seconds']:.0f} | {cells[0]} | {cells[1]} |")
    return "\n".join(text) + "\n"


STAGES = ["data", "train-reach", "sweep", "scales", "budget", "problems", "examples", "train-cross", "stitching",
          "train-long", "curve", "select", "train-joint", "families", "recount", "results"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="every stage at toy size")
    parser.add_argument("--root", help="output folder (default, in the repository: runs/franka_bench, quick: "
                        "runs/franka_bench_quick)")
    parser.add_argument("--only", help=f"comma-separated stages to run ({', '.join(STAGES)})")
    parser.add_argument("--rows", help="comma-separated training rows to train and evaluate, in this order")
    parser.add_argument("--adopt", action="append", default=[], metavar="ROW=RUN",
                        help="take a finished run folder as training row ROW (its config must be the row's)")
    parser.add_argument("--threads", type=int, help="threads of the training and curve stages (default: the configs' "
                        "threads, all cores); results do not depend on it, e.g. two drivers with --threads 1 each")
    parser.add_argument("--flowplan", default=os.environ.get("FLOWPLAN"),
                        help="the flowplan binary (default: $FLOWPLAN, else the repository's build/apps/flowplan/flowplan)")
    args = parser.parse_args()
    repo = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    # Defaults are in the repository, from whatever folder the driver runs; given paths are from that folder.
    args.root = args.root or os.path.join(repo, "runs", "franka_bench_quick" if args.quick else "franka_bench")
    args.flowplan = args.flowplan or os.path.join(repo, "build", "apps", "flowplan", "flowplan")
    stages = STAGES if not args.only else args.only.split(",")
    for stage in stages:
        if stage not in STAGES:
            sys.exit(f"--only: unknown stage {stage!r} (stages: {', '.join(STAGES)})")
    if args.rows is not None:
        args.rows = args.rows.split(",")
        unknown = [row for row in args.rows if row not in train_rows()]
        if unknown:
            sys.exit(f"--rows: unknown row {unknown[0]!r} (rows: {', '.join(train_rows())})")
    if not os.access(args.flowplan, os.X_OK):
        sys.exit(f"--flowplan: {os.path.abspath(args.flowplan)} is not an executable (build first: make build)")
    adoptions = [(row, os.path.abspath(run)) for row, _, run in (a.partition("=") for a in args.adopt)]
    args.root = os.path.relpath(os.path.abspath(args.root), repo)
    args.flowplan = os.path.relpath(os.path.abspath(args.flowplan), repo)
    os.chdir(repo)
    os.makedirs(args.root, exist_ok=True)
    bench = Bench(args)

    def stop(signum, frame):  # SIGTERM: the running command gets it once, then stops like Ctrl-C
        if bench.child is not None and bench.child.poll() is None:
            bench.child.send_signal(signal.SIGTERM)
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, stop)
    bench.adoptions = dict(adoptions)
    try:
        for stage in stages:
            started = time.time()
            getattr(bench, stage.replace("-", "_"))()
            print(f"== {stage}: {time.time() - started:.0f} s", flush=True)
    except KeyboardInterrupt:
        sys.exit(f"stopped during {stage}; run the same command again to continue")
    except Unavailable as missing:
        sys.exit(f"{stage}: {missing}")


if __name__ == "__main__":
    main()
