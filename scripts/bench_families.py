"""The scene-family stage of scripts/franka_bench.py: every planner on the procedural scene families and on the
paper's sphere scene, each plan checked by `flowplan`'s plan checker and executed in MuJoCo with the real shapes.

  ROOT/families/problems/{val,test}_<family>.yaml   `flowplan problems --family` (validation seed 101, test seed 303)
  ROOT/families/problems/test_sphere.yaml           the paper's scene: one sphere of each radius of SPHERE_RADII
                                                    between the TCP points (0.5, -0.3, 0.2) and (0.5, 0.3, 0.2)
  ROOT/families/val/<planner>_<k>_<family>.*        `flowplan plan --problems` of setting k of the planner's grid
  ROOT/families/test/<planner>_<set>.*              the setting chosen on validation, on the test sets, executed

Every learned planner chooses its guidance (the grid below) on the validation problems of all families pooled:
the most valid plans, then the shorter median time per plan. The hybrid, with the flow planner's chosen setting as
its proposer, chooses the setting of shortest median time among those with at least as many valid plans as
RRT-Connect on the same validation problems (the goal the hybrid is held to), and the most valid plans when none
has. Test problems are never looked at before the choice. Every
plan is made by its own call on one thread (`--batch 1`, `threads=1`; the hybrid's call proposes its N plans in one
batch), so that the time per plan is the wall time of the call that made it, for every planner alike.
"""
import json
import os
import random

FAMILIES = ["table", "shelf", "box", "cage", "under_table"]
# Test seed 303: the sets of seed 202 were reported at every round of the work on these planners (docs/results.md),
# so their figures were seen while the grids and defaults were designed; 303 had drawn no family problems before (the
# select stage draws other problems, of its own generator, with it).
FAMILY_SEEDS = {"val": 101, "test": 303}
SPHERE_RADII = [0.05, 0.1, 0.15]
SPHERE_START_TCP, SPHERE_GOAL_TCP = "0.5,-0.3,0.2", "0.5,0.3,0.2"
JOINT_CONFIG = "configs/franka_joint.yaml"
# The family whose test problems are also planned as read from MoveIt files (moveit_set), and that set's name.
MOVEIT_FAMILY = "table"
MOVEIT_SET = "table_moveit"
# Guidance scales of the grid: the reach preset's 1.75 moves the joints of this planner too far (its data spans the
# whole joint range, so a normalized step is several times larger in radians), see docs/results.md.
SCALES = [0.05, 0.1, 0.2, 0.4]
# The flow planner's grid: the paper's sampler and 10 plain end-game steps at each scale, then the covariant
# end-game (20 steps spread over 4 states, the joint-speed hinge in them at weight 0.1 or 1; docs/planning.md). Every
# row names its end-game in full: the preset's defaults are the covariant one.
FP_GRID = ([[f"guidance.scale={s}", f"sampler.final_iterations={g}", "sampler.final_spread=0",
             "sampler.final_joint_speed_weight=0"] for s in SCALES for g in (0, 10)] +
           [[f"guidance.scale={s}", "sampler.final_iterations=20", "sampler.final_spread=4",
             f"sampler.final_joint_speed_weight={w}"] for s in SCALES for w in (0.1, 1)])
# Learned planners: name, label, training row, fixed overrides, validation grid (a list of override lists).
LEARNED = [("fp", "FP", "joint_fp", ["sampler.splitting=none"], FP_GRID),
           ("fp_split", "FP + split", "joint_fp", ["sampler.splitting=midpoint"], FP_GRID),
           ("mpd", "MPD", "joint_mpd", [], [[f"guidance.scale={s}"] for s in SCALES]),
           ("vae", "VAE planner", "joint_vae", ["sampler.latent.lr=0.02"], [[f"guidance.scale={s}"] for s in SCALES])]
# The hybrid: 1 or 4 proposals, guided only or unguided first, seeded fallback; one unguided first, unseeded; then
# cheaper proposers (fewer end-game steps, or 5 sampler steps instead of 10) than the flow planner's chosen one: a
# valid proposal's time is most of a hybrid plan's where the learned planner succeeds.
HYBRID_GRID = [[f"hybrid.proposals={n}", "hybrid.seeded_fallback=true", f"hybrid.unguided_first={u}"]
               for u in ("false", "true") for n in (1, 4)]
HYBRID_GRID.append(["hybrid.proposals=1", "hybrid.seeded_fallback=false", "hybrid.unguided_first=true"])
HYBRID_GRID += [["hybrid.proposals=1", "hybrid.seeded_fallback=true", "hybrid.unguided_first=false",
                 "sampler.final_iterations=10"],
                ["hybrid.proposals=1", "hybrid.seeded_fallback=false", "hybrid.unguided_first=true",
                 "sampler.final_iterations=10"]]
HYBRID_GRID += [["hybrid.proposals=1", "hybrid.seeded_fallback=true", "hybrid.unguided_first=false", *cheaper]
                for cheaper in (["sampler.final_iterations=5"], ["sampler.steps=5", "sampler.final_iterations=10"],
                                ["sampler.steps=5", "sampler.final_iterations=5"])]
LABELS = {name: label for name, label, *_ in LEARNED} | {"rrt_connect": "RRT-Connect", "hybrid": "hybrid (FP, RRT-Connect)"}
PLANNERS = [name for name, *_ in LEARNED] + ["rrt_connect", "hybrid"]
# Published anchors (docs/results.md says where they come from and how they differ from ours).
CUROBO = "cuRobo: 99.85 % of 2,600 MotionBenchMaker problems, 31 ms median (GPU)"
VAMP = "VAMP RRT-Connect: all 699 valid MotionBenchMaker problems, 35 µs median (one desktop CPU core)"


def choose(rows, bar=None):
    """The setting of validation ROWS [(setting, success, median time, plans)] with the most valid plans, then the
    shorter median time; with a BAR (a success rate), the shortest median time among the rows at least that
    successful (then the more successful), and the most valid when none is."""
    if bar is not None:
        level = [row for row in rows if row[1] >= bar]
        if level:
            return min(level, key=lambda row: (row[2], -row[1]))[0]
    return max(rows, key=lambda row: (row[1], -row[2]))[0]


def quantile(values, q):
    """The q-quantile of VALUES by linear interpolation between order statistics: numpy's default, and the
    definition of every `flowplan plan` report's median and p95 (experiment/plan_report.cc)."""
    ordered = sorted(values)
    if not ordered:
        return float("inf")
    at = q * (len(ordered) - 1)
    below = int(at)
    above = min(below + 1, len(ordered) - 1)
    return ordered[below] + (at - below) * (ordered[above] - ordered[below])


def pooled(reports):
    """Success over every plan asked of REPORTS (`flowplan plan` reports), and the median and p95 time per plan
    of their plans: {"success", "median_time_s", "p95_time_s", "plans"}."""
    samples = [s for r in reports for p in r["problems"] for s in p["samples"]]
    asked = sum(r["num_problems"] * r["num_samples"] for r in reports)
    times = [s["planning_time_s"] for s in samples]
    return {"success": sum(s["success"] for s in samples) / max(asked, 1), "median_time_s": quantile(times, 0.5),
            "p95_time_s": quantile(times, 0.95), "plans": asked}


def paired_bootstrap(first, second, draws=2000, seed=0):
    """The test problems drawn again with replacement (DRAWS times, a fixed SEED): FIRST's and SECOND's pooled
    median times per plan on each draw (the same problems for both; FIRST, SECOND: per family, `flowplan plan`
    reports of the same problem files). -> {"low", "high"}: the 2.5 and 97.5 percentiles of FIRST's median minus
    SECOND's (s); "faster": the share of draws where FIRST's median is the lower; "as_often": where FIRST is valid
    at least as often."""
    problems = []  # (first's plans, second's plans) per problem
    for a, b in zip(first, second):
        assert len(a["problems"]) == len(b["problems"]), "paired_bootstrap: the reports hold other problems"
        problems += list(zip(a["problems"], b["problems"]))
    rng = random.Random(seed)
    differences, faster, as_often = [], 0, 0
    for _ in range(draws):
        drawn = [problems[rng.randrange(len(problems))] for _ in problems]
        times = [[s["planning_time_s"] for pair in drawn for s in pair[k]["samples"]] for k in (0, 1)]
        valid = [sum(s["success"] for pair in drawn for s in pair[k]["samples"]) for k in (0, 1)]
        difference = quantile(times[0], 0.5) - quantile(times[1], 0.5)
        differences.append(difference)
        faster += difference < 0
        as_often += valid[0] >= valid[1]
    return {"low": quantile(differences, 0.025), "high": quantile(differences, 0.975), "faster": faster / draws,
            "as_often": as_often / draws}


class Families:
    def __init__(self, bench, helpers):
        """BENCH: the driver (its paths, requests, calls, sizes); HELPERS: its module (write_text, recorded, stale,
        Unavailable)."""
        self.bench = bench
        self.write_text, self.recorded, self.stale = helpers.write_text, helpers.recorded, helpers.stale
        self.Unavailable = helpers.Unavailable
        size = bench.size
        # Quick: two families, and grids of two settings for the flow planner and one for the others.
        self.families = FAMILIES[:2] if bench.quick else FAMILIES
        self.grids = {name: (grid[:2 if name == "fp" else 1] if bench.quick else grid) for name, *_, grid in LEARNED}
        self.grids["hybrid"] = HYBRID_GRID[:1] if bench.quick else HYBRID_GRID
        self.grids["rrt_connect"] = [[]]  # no setting to choose: its validation cells are the hybrid's bar
        self.counts = {"val": size["family_val_problems"], "test": size["family_test_problems"]}
        self.plans = {"val": size["family_val_plans"], "test": size["family_test_plans"]}

    def path(self, *parts):
        return self.bench.path("families", *parts)

    # -- problem files ----------------------------------------------------------
    def problems_command(self, split, family):
        out = self.path("problems", f"{split}_{family}.yaml")
        command = [self.bench.flowplan, "problems", "--family", family, "--out", out, f"seed={FAMILY_SEEDS[split]}",
                   f"problems.count={self.counts[split]}"]
        return out, command, self.bench.request(command)

    def sphere_command(self):
        """The paper's start and goal as joint configurations: RRT-Connect's report of one plan between them holds
        the IK of both TCP points; the problem file is written from it."""
        out = self.path("problems", "test_sphere.yaml")
        report = self.path("problems", "sphere_ends")
        command = [self.bench.flowplan, "plan", "--rrt-connect", "--config", JOINT_CONFIG,
                   f"data.path={self.bench.path('data', 'franka_joint.h5')}", "--start-tcp", SPHERE_START_TCP,
                   "--goal-tcp", SPHERE_GOAL_TCP, "scene.spheres=[]", "-n", "1", "--no-plot", "--log-level", "warn",
                   "--out", report]
        return out, report, command, self.bench.request(command, " ".join(map(str, SPHERE_RADII)))

    def problem_sets(self):
        sets = [(split, family) for split in ("val", "test") for family in self.families]
        for split, family in sets:
            out, command, request = self.problems_command(split, family)
            with self.stale(lambda: self.recorded(out + ".request", request), out + ".lock",
                            [out, out + ".request"]) as ours:
                if ours:
                    print(f"families: {split} problems of {family}", flush=True)
                    self.bench.call(command + ["threads=2"])
                    self.write_text(out + ".request", request)
        out, report, command, request = self.sphere_command()
        with self.stale(lambda: self.recorded(out + ".request", request), out + ".lock",
                        [out, out + ".request", report + ".json", report + ".h5"]) as ours:
            if ours:
                import yaml
                self.bench.call(command)
                ends = json.load(open(report + ".json"))
                problems = [{"name": f"sphere_r{r:g}", "start_q": ends["start"][:7], "goal_q": ends["goal"][:7],
                             "scene": {"spheres": [{"centre": [0.5, 0.0, 0.2], "radius": r}]}} for r in SPHERE_RADII]
                self.write_text(out, yaml.safe_dump({"source": "the paper's sphere scene", "problems": problems},
                                                    default_flow_style=None, sort_keys=False))
                self.write_text(out + ".request", request)

    # -- the MoveIt copy of a test set ---------------------------------------------
    def moveit_command(self):
        """MOVEIT_FAMILY's test problems written as MoveIt scene and request files (write_moveit) and read back by
        `flowplan scenes import`, every obstacle kept (--grasped none), so that the imported set must equal the
        original: (problem file, folder of MoveIt files, command, request)."""
        source, source_request = self.set_request("test", MOVEIT_FAMILY)
        out = self.path("problems", f"test_{MOVEIT_SET}.yaml")
        folder = self.path("problems", f"test_{MOVEIT_SET}_files")
        command = [self.bench.flowplan, "scenes", "import", "--dir", folder, "--grasped", "none", "--out", out]
        return out, source, folder, command, self.bench.request(command, source_request)

    def moveit_set(self):
        out, source, folder, command, request = self.moveit_command()
        with self.stale(lambda: self.recorded(out + ".request", request), out + ".lock",
                        [out, out + ".request"]) as ours:
            if ours:
                import shutil
                import yaml
                shutil.rmtree(folder, ignore_errors=True)
                write_moveit(yaml.safe_load(open(source)), folder)
                self.bench.call(command)
                compare_imported(yaml.safe_load(open(source)), yaml.safe_load(open(out)), out)
                print(f"families: {MOVEIT_SET}: {source} through MoveIt files equals the original", flush=True)
                self.write_text(out + ".request", request)

    def set_request(self, split, family):
        if family == MOVEIT_SET:
            out, _, _, _, request = self.moveit_command()
        elif family == "sphere":
            out, _, _, request = self.sphere_command()
        else:
            out, _, request = self.problems_command(split, family)
        if not self.recorded(out + ".request", request):
            raise self.Unavailable(f"{out}: not made by the current request; run the families stage")
        return out, request

    # -- planning ---------------------------------------------------------------
    def source(self, planner, setting):
        """(`flowplan plan` arguments, the request of what they read) of PLANNER with SETTING (overrides)."""
        bench = self.bench
        if planner == "rrt_connect":
            return (["--rrt-connect", "--config", JOINT_CONFIG, f"data.path={bench.path('data', 'franka_joint.h5')}"],
                    bench.data_request("franka_joint"))
        if planner == "hybrid":
            proposer = self.chosen("fp")
            if proposer is None:
                return None
            arguments, model = self.source("fp", proposer)
            return arguments + ["--hybrid", *setting], model
        _, _, row, fixed, _ = next(p for p in LEARNED if p[0] == planner)
        return ["--ckpt", bench.path("train", row), *fixed, *setting], bench.model_request(row)

    def cell_command(self, prefix, planner, setting, split, family, execute):
        found = self.source(planner, setting)
        if found is None:
            return None
        arguments, model = found
        problems, problems_request = self.set_request(split, family)
        command = [self.bench.flowplan, "plan", *arguments, "--problems", problems, "-n", str(self.plans[split]),
                   "--batch", "1", "--seed", "1", "threads=1", *(["--execute"] if execute else []),
                   "--log-level", "warn", "--out", prefix]
        return command, self.bench.request(command, model, problems_request)

    def cell(self, prefix, planner, setting, split, family, execute):
        made = self.cell_command(prefix, planner, setting, split, family, execute)
        if made is None:
            return
        command, request = made
        with self.stale(lambda: self.recorded(prefix + ".request", request), prefix + ".lock",
                        [prefix + ext for ext in (".json", ".h5", ".request")]) as ours:
            if ours:
                self.bench.call(command)
                self.write_text(prefix + ".request", request)

    def report(self, prefix, planner, setting, split, family, execute):
        """The cell's report, if made by the current request, else None."""
        try:
            made = self.cell_command(prefix, planner, setting, split, family, execute)
        except self.Unavailable:
            return None
        if made is None or not self.recorded(prefix + ".request", made[1]):
            return None
        return json.load(open(prefix + ".json"))

    def val_prefix(self, planner, k, family):
        return self.path("val", f"{planner}_{k}_{family}")

    def validation(self, planner):
        """[(setting, pooled success, median time, plans)] of PLANNER's grid on the validation problems made so far."""
        rows = []
        for k, setting in enumerate(self.grids[planner]):
            reports = [self.report(self.val_prefix(planner, k, f), planner, setting, "val", f, False)
                       for f in self.families]
            if any(r is None for r in reports):
                continue
            row = pooled(reports)
            rows.append((setting, row["success"], row["median_time_s"], row["plans"]))
        return rows

    def chosen(self, planner):
        """The setting of PLANNER's grid with the most valid validation plans, then the shorter median time; for
        the hybrid, the shortest median time among the settings with at least RRT-Connect's validation success
        (the most valid plans when none has). None until every setting (and RRT-Connect's) has been planned."""
        rows = self.validation(planner)
        if len(rows) < len(self.grids[planner]):
            return None
        if planner == "rrt_connect":
            return []
        if planner == "hybrid":
            bar = self.validation("rrt_connect")
            if not bar:
                return None
            return choose(rows, bar[0][1])
        return choose(rows)

    def run(self):
        self.problem_sets()
        self.moveit_set()
        # The VAE planner last: the other planners' cells do not wait for its training.
        for planner in [name for name in PLANNERS if name != "vae"] + ["vae"]:
            for k, setting in enumerate(self.grids[planner]):
                for family in self.families:
                    self.cell(self.val_prefix(planner, k, family), planner, setting, "val", family, False)
            setting = self.chosen(planner)
            if planner != "rrt_connect" and setting is not None:
                print(f"families: {planner} chose {setting} on validation", flush=True)
            if setting is None:  # another driver is still planning its validation cells
                print(f"families: {planner} has not chosen yet; its test problems wait for the next run", flush=True)
                continue
            for family in self.test_sets():
                self.cell(self.path("test", f"{planner}_{family}"), planner, setting, "test", family, True)
            print(f"families: {planner} planned the test problems", flush=True)

    def test_sets(self):
        """The test problem sets: every family, the paper's sphere scene, and MOVEIT_FAMILY's set as imported from
        MoveIt files."""
        return self.families + ["sphere", MOVEIT_SET]

    # -- results ----------------------------------------------------------------
    def results(self, summary):
        text = ["### Scene families: every planner, checked and executed\n",
                f"Validation: {self.counts['val']} problems per family (seed {FAMILY_SEEDS['val']}), "
                f"{self.plans['val']} plans each; test: {self.counts['test']} problems per family (seed "
                f"{FAMILY_SEEDS['test']}) and the paper's sphere scene (radii {', '.join(f'{r:g}' for r in SPHERE_RADII)} "
                f"m), {self.plans['test']} plans each. A success passed `flowplan`'s plan checker (whole arm, motion "
                "between states, joint position and speed limits, ends); executed: and then tracked in MuJoCo "
                "without contact to within 3 cm of the goal. Time: per plan, the wall time of the call that made it "
                "(one plan per call, one thread).\n", "Chosen on validation (pooled success, median time per plan):\n"]
        summary["families"] = {"chosen": {}, "validation": {}, "test": {}, "pooled": {}}
        for planner in [name for name, *_ in LEARNED] + ["hybrid"]:
            rows = self.validation(planner)
            choice = self.chosen(planner)
            summary["families"]["chosen"][planner] = choice
            summary["families"]["validation"][planner] = [
                {"setting": s, "success": v, "median_time_s": t, "plans": n} for s, v, t, n in rows]
            grid = "; ".join(f"{' '.join(s)}: {v:.1%}, {t:.3f} s" for s, v, t, _ in rows)
            text.append(f"- {LABELS[planner]}: **{' '.join(choice) if choice else 'not chosen yet'}** ({grid})")
        bar = self.validation("rrt_connect")
        summary["families"]["validation"]["rrt_connect"] = [
            {"setting": s, "success": v, "median_time_s": t, "plans": n} for s, v, t, n in bar]
        text.append("- RRT-Connect (no setting; the hybrid's bar): " +
                    (f"{bar[0][1]:.1%}, {bar[0][2]:.3f} s" if bar else "not planned yet"))
        text.append("")
        header = ("| planner | success | executed | median time (s) | p95 time (s) | joint path (rad) | TCP path (m) "
                  "| max speed ratio | mean squared jerk (rad²/s⁶) | duration (s) | routes |")
        points = {}
        for family in self.test_sets():
            text += [f"**{family}**\n", header, "|---" * 11 + "|"]
            for planner in PLANNERS:
                setting = [] if planner == "rrt_connect" else self.chosen(planner)
                report = None if setting is None else self.report(self.path("test", f"{planner}_{family}"), planner,
                                                                  setting, "test", family, True)
                if report is None:
                    text.append(f"| {LABELS[planner]} | not run |" + " |" * 9)
                    continue
                row = summarize(report)
                summary["families"]["test"][f"{planner}/{family}"] = row
                points[(planner, family)] = (row["median_time_s"], row["success"])
                text.append(f"| {LABELS[planner]} | {row['success']:.0%} | {row['executed']:.0%} | "
                            f"{row['median_time_s']:.3f} | {row['p95_time_s']:.3f} | {row['joint_path']:.2f} | "
                            f"{row['tcp_path']:.2f} | {row['speed_ratio']:.2f} | {row['jerk']:.3g} | "
                            f"{row['duration_s']:.2f} | {row['routes']} |")
            text.append("")
        text += [f"**the {len(self.families)} families pooled** (every test plan of them)\n",
                 "| planner | success | median time (s) | p95 time (s) |", "|---|---|---|---|"]
        tested = {}  # planner -> its test reports, one per family, where every family's was planned
        for planner in PLANNERS:
            setting = [] if planner == "rrt_connect" else self.chosen(planner)
            reports = [None if setting is None else self.report(self.path("test", f"{planner}_{family}"), planner,
                                                                setting, "test", family, True)
                       for family in self.families]
            if any(r is None for r in reports):
                text.append(f"| {LABELS[planner]} | not run | | |")
                continue
            tested[planner] = reports
            row = pooled(reports)
            summary["families"]["pooled"][planner] = {key: row[key] for key in ("success", "median_time_s", "p95_time_s")}
            text.append(f"| {LABELS[planner]} | {row['success']:.1%} | {row['median_time_s']:.3f} | "
                        f"{row['p95_time_s']:.2f} |")
        text.append("")
        if "hybrid" in tested and "rrt_connect" in tested:
            spread = paired_bootstrap(tested["hybrid"], tested["rrt_connect"])
            summary["families"]["hybrid_vs_rrt_connect"] = spread
            text += [f"The hybrid's pooled median minus RRT-Connect's, over the test problems drawn again with "
                     f"replacement (2,000 draws, paired): 95 % interval {spread['low'] * 1e3:+.2f} to "
                     f"{spread['high'] * 1e3:+.2f} ms; the hybrid's median the lower in {spread['faster']:.0%} of "
                     f"draws, the hybrid valid at least as often in {spread['as_often']:.0%}.\n"]
        text += ["Path length, speed ratio, jerk and duration: medians over the valid plans (over all plans when none is "
                 "valid). Routes: how the hybrid made its plans. Published anchors, not measured here: "
                 f"{CUROBO}; {VAMP}.\n"]
        plot_families(points, self.test_sets(), self.bench.path("results", "families_success_vs_time.png"))
        return text


def write_moveit(problem_set, folder):
    """Writes every problem of PROBLEM_SET (a parsed flowplan problem file) as MotionBenchMaker does: FOLDER/
    sceneNNNN.yaml, a MoveIt planning scene (world.collision_objects, one primitive each, named as the problem names
    its obstacles; quaternions as x, y, z, w), and requestNNNN.yaml, a motion-plan request (start_state by joint
    name, the fingers included; the goal as joint constraints). Written here from the problem file alone, with
    nothing of flowplan's importer."""
    import yaml
    os.makedirs(folder, exist_ok=True)
    joints = [f"panda_joint{j + 1}" for j in range(7)]
    for i, problem in enumerate(problem_set["problems"], start=1):
        scene, names = problem["scene"], problem["obstacle_names"]
        objects = []

        def add(primitive, centre, quaternion=(1.0, 0.0, 0.0, 0.0)):
            w, x, y, z = quaternion
            objects.append({"header": {"frame_id": "panda_link0"}, "id": names[len(objects)],
                            "primitives": [primitive],
                            "primitive_poses": [{"position": list(centre), "orientation": [x, y, z, w]}],
                            "operation": 0})
        for sphere in scene.get("spheres", []):  # the scene's numbering: spheres, boxes, cylinders
            add({"type": "sphere", "dimensions": [sphere["radius"]]}, sphere["centre"])
        for box in scene.get("boxes", []):
            add({"type": "box", "dimensions": list(box["size"])}, box["centre"], box["quaternion"])
        for cylinder in scene.get("cylinders", []):
            add({"type": "cylinder", "dimensions": [cylinder["height"], cylinder["radius"]]}, cylinder["centre"],
                cylinder["quaternion"])
        if scene.get("capsules"):
            raise ValueError(f"{problem['name']}: MoveIt has no capsule primitive")
        planning_scene = {"name": problem["name"], "robot_model_name": "panda", "is_diff": True,
                          "world": {"collision_objects": objects}}
        request = {"group_name": "panda_arm", "num_planning_attempts": 1, "allowed_planning_time": 10.0,
                   "start_state": {"joint_state": {"name": joints + ["panda_finger_joint1", "panda_finger_joint2"],
                                                   "position": list(problem["start_q"]) + [0.035, 0.035]}},
                   "goal_constraints": [{"joint_constraints": [
                       {"joint_name": name, "position": q, "tolerance_above": 0.001, "tolerance_below": 0.001,
                        "weight": 1.0} for name, q in zip(joints, problem["goal_q"])]}]}
        for stem, content in ((f"scene{i:04d}", planning_scene), (f"request{i:04d}", request)):
            with open(os.path.join(folder, stem + ".yaml"), "w") as f:
                yaml.safe_dump(content, f, default_flow_style=None, sort_keys=False)


def compare_imported(original, imported, path):
    """Raises ValueError naming the first difference between ORIGINAL's problems and IMPORTED's (parsed problem
    files): the same count, starts and goals exactly, the same obstacle names and kinds, every obstacle's keys and
    numbers (within 1e-12: the importer normalizes quaternions) and nothing else."""
    first, second = original["problems"], imported["problems"]
    if len(first) != len(second):
        raise ValueError(f"{path}: {len(second)} problems imported from {len(first)}")

    def same(a, b, where):
        if isinstance(a, dict) and isinstance(b, dict):
            if sorted(a) != sorted(b):
                raise ValueError(f"{path}: {where}: keys {sorted(b)} imported from {sorted(a)}")
            for key in a:
                same(a[key], b[key], f"{where}.{key}")
        elif isinstance(a, list) and isinstance(b, list):
            if len(a) != len(b):
                raise ValueError(f"{path}: {where}: {len(b)} entries imported from {len(a)}")
            for k, (x, y) in enumerate(zip(a, b)):
                same(x, y, f"{where}[{k}]")
        elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
            if abs(float(a) - float(b)) > 1e-12:
                raise ValueError(f"{path}: {where}: {b!r} imported from {a!r}")
        elif a != b:
            raise ValueError(f"{path}: {where}: {b!r} imported from {a!r}")
    for k, (a, b) in enumerate(zip(first, second)):
        for key in ("start_q", "goal_q", "obstacle_names", "left_out"):
            if list(a[key]) != list(b[key]):
                raise ValueError(f"{path}: problem {k}: {key} {b[key]} imported from {a[key]}")
        same(a["scene"], b["scene"], f"problem {k}: scene")


def summarize(report):
    """Success rates, time quantiles and the medians of the quality metrics of one `--problems` report."""
    samples = [s for p in report["problems"] for s in p["samples"]]
    asked = report["num_problems"] * report["num_samples"]
    valid = [s for s in samples if s["success"]]
    pool = valid or samples

    def median(values):
        values = sorted(values)
        return values[len(values) // 2] if values else float("nan")

    routes = {}
    for s in samples:
        route = s.get("route")
        if route is not None:
            # "proposal k of N[ unguided][ retimed]": the proposal kind, without k and N
            key = ("proposal" + (" unguided" if " unguided" in route else "") + (" retimed" if " retimed" in route else "")
                   if route.startswith("proposal") else
                   "rrt_connect seeded" if route.startswith("rrt_connect seeded") else route)
            routes[key] = routes.get(key, 0) + 1
    return {"success": report["success_rate"], "executed": report.get("success_rate_executed", 0.0),
            "problems_solved": report["problems_solved_rate"] if "problems_solved_rate" in report else report["problems_solved"], "refused": report["refused"], "plans": asked,
            "median_time_s": report["planning_time_s"]["median"], "p95_time_s": report["planning_time_s"]["p95"],
            "joint_path": median(s["quality"]["joint_path_length"] for s in pool),
            "tcp_path": median(s["quality"]["tcp_path_length"] for s in pool),
            "speed_ratio": median(s["quality"]["max_speed_ratio"] for s in pool),
            "jerk": median(s["quality"]["mean_squared_jerk"] for s in pool),
            "duration_s": median(s["quality"]["duration_s"] for s in pool),
            "routes": ", ".join(f"{k} {v}" for k, v in sorted(routes.items())) or ""}


def plot_families(points, sets, path):
    """Success against median time per plan, one panel per scene set, one point per planner."""
    if not points:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker
    figure, axes = plt.subplots(1, len(sets), figsize=(3.2 * len(sets), 3.3), sharey=True)
    for axis, family in zip(axes, sets):
        for planner in PLANNERS:
            if (planner, family) in points:
                t, s = points[(planner, family)]
                axis.scatter([max(t, 1e-4)], [100 * s], label=LABELS[planner], s=28)
        axis.set_xscale("log")
        axis.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())  # minor labels overlap on short ranges
        axis.set_title(family)
        axis.set_xlabel("median time per plan (s)")
        axis.set_ylim(-5, 105)
    axes[0].set_ylabel("valid plans (%)")
    axes[-1].legend(fontsize=7, loc="lower right")
    figure.tight_layout()
    os.makedirs(os.path.dirname(path), exist_ok=True)
    figure.savefig(path + ".tmp.png", dpi=80)
    os.replace(path + ".tmp.png", path)
    plt.close(figure)
