"""flowplan from Python: plan with an exported planner at the speed of flowplan's native kernels.

    import torch, flowplan
    planner = flowplan.load_planner("pretrained/franka_reach_planner.pt")
    start = torch.cat([planner.ik(torch.tensor([0.5, -0.3, 0.2])), torch.zeros(7)])  # (14,) at rest
    goal = torch.cat([planner.ik(torch.tensor([0.5, 0.3, 0.2])), torch.zeros(7)])
    sphere = torch.tensor([[0.5, 0.0, 0.2, 0.1]])                                    # (K, 4) centre, radius (m)
    plans = planner.sample(start, goal, 16, spheres=sphere)                          # (16, 64, 14)

`make_planner` makes any planner `flowplan plan` runs (the learned planner, RRT-Connect, the hybrid) in-process,
with the plan checker beside it:

    rrt = flowplan.make_planner("rrt_connect", config="configs/franka_joint.yaml")
    result = rrt.plan(start, goal, 4, spheres=sphere)                  # result.plans (4, 64, 14), result.found (4,)
    verdicts = rrt.check(result.plans, start, goal, spheres=sphere)    # [Verdict(valid=True, ...), ...]

`import_robot` is `flowplan robot import` (a robot folder from a URDF or an MJCF, for make_planner's robot=);
`import_scenes` and `load_problems` are MoveIt and problem files. `generate` and `train` are `flowplan generate`
and `flowplan train`:

    data = flowplan.generate("configs/franka_joint.yaml", ["generate.episodes=2000"])
    run = flowplan.train("configs/franka_joint.yaml", ["train.steps=1000"])   # logs its progress; Ctrl-C checkpoints
    learned = flowplan.make_planner("learned", ckpt=run)

`load_planner` returns a `Planner` with the exported module's interface (docs/export.md: `sample`, `plan`,
`tcp`, `ik`, `clearance`, `collision_spheres`, `settings`, `state_dim`, ...). With the package's C++ part
(`flowplan._flowplan`, built with flowplan) it runs the file's weights with flowplan's native kernels; with
PyTorch alone it runs the file's own portable code. Either way every call runs without gradients and with
TorchScript's graph executor optimisations off, so the first plan costs about what the later ones do.
"""
import dataclasses
import io
import warnings
from typing import List

import torch

try:
    from . import _flowplan
except ImportError as missing:  # PyTorch alone: the portable code of the files
    _flowplan = None
    _why_portable = f"flowplan's C++ module is not importable ({missing})"
else:
    _why_portable = ""

__all__ = ["Error", "InProcessPlanner", "Planner", "PlanResult", "Problem", "RobotFolder", "Verdict",
           "evaluate_stitching", "generate", "import_robot", "import_scenes", "load_planner", "load_problems",
           "load_scene", "make_planner", "make_problems", "native_kernels", "render", "set_log_level", "train"]

#: What flowplan raises for bad input (a file that is not a planner, a planner that cannot take the kernels);
#: a RuntimeError. The message names the file.
Error = _flowplan.Error if _flowplan is not None else RuntimeError


def native_kernels():
    """Whether flowplan's native kernels are loaded in this process (the package's C++ module imports)."""
    return _flowplan is not None


class Planner:
    """An exported flowplan planner: the TorchScript module's methods and attributes, each method called
    under `torch.no_grad()` with the graph executor's optimisations off.

    Attributes:
        module: the TorchScript module itself (torch.jit.ScriptModule), for calls of your own.
        native: whether it runs flowplan's native kernels.
        source: the file it was loaded from.
    """

    def __init__(self, module, native, source):
        self.module = module
        self.native = native
        self.source = source

    def __getattr__(self, name):
        if name.startswith("__") or name in ("module", "native", "source"):  # copy, pickle: not the module's
            raise AttributeError(name)
        value = getattr(self.module, name)
        if not callable(value) or isinstance(value, torch.nn.Module):
            return value

        def call(*args, **kwargs):
            with torch.no_grad(), torch.jit.optimized_execution(False):
                return value(*args, **kwargs)

        call.__name__ = name
        call.__doc__ = f"The exported planner's {name} (docs/export.md), without gradients."
        return call

    def __dir__(self):
        methods = [name for name in ("plan", "sample", "clearance", "tcp", "collision_spheres", "ik", "normalize",
                                     "denormalize", "call_settings") if hasattr(self.module, name)]
        return sorted(set(super().__dir__()) | set(methods))

    def __repr__(self):
        kernels = "native kernels" if self.native else "portable code"
        return (f"<flowplan.Planner {self.source}: {self.module.planner}, states ({self.module.horizon}, "
                f"{self.module.state_dim}), {kernels}>")


def load_planner(path, native=None):
    """Loads an exported planner file (`flowplan export`, or one of pretrained/).

    Args:
        path: the file.
        native: None (default): flowplan's native kernels when they are loaded, else the file's portable code,
            with a warning saying why; True: native kernels or an error; False: the file as written.

    Returns:
        a Planner.

    Raises:
        flowplan.Error: the file is not a flowplan planner, or native=True and the kernels cannot run it.
        FileNotFoundError: there is no such file.
    """
    path = str(path)
    with open(path, "rb"):  # FileNotFoundError naming the path, before anything else
        pass
    if native is not False:
        if _flowplan is None:
            if native:
                raise Error(f"{path}: native kernels asked for, but {_why_portable}")
            warnings.warn(f"{path}: planning with the file's portable code: {_why_portable}", stacklevel=2)
        else:
            try:
                module = torch.jit.load(io.BytesIO(_flowplan.native_planner(path)))
                return Planner(module, True, path)
            except Error as error:
                if native or "not a flowplan planner" in str(error) or "not a TorchScript module" in str(error):
                    raise
                warnings.warn(f"{path}: planning with the file's portable code: {error}", stacklevel=2)
    try:
        module = torch.jit.load(path)
    except RuntimeError as error:
        raise Error(f"{path}: not a TorchScript module: {str(error).splitlines()[0]}") from None
    if not hasattr(module, "format_version"):
        raise Error(f"{path}: not a flowplan planner (a TorchScript module without format_version)")
    return Planner(module, False, path)


@dataclasses.dataclass
class PlanResult:
    """What InProcessPlanner.plan returns. B plans of T states of D values."""
    plans: torch.Tensor    # (B, T, D) float32 raw states: positions, then velocities
    found: torch.Tensor    # (B,) bool: a plan was found (a learned planner always finds one; check it)
    refused: List[bool]    # (B) the start or goal cannot be planned from or to (RRT-Connect, the hybrid)
    failure: List[str]     # (B) why a plan was not found or was refused; "" when found
    route: List[str]       # (B) how the hybrid made each plan ("proposal 2 of 8", "rrt_connect"); else empty
    seconds: List[float]   # (B) wall time per plan (a batch's time shared among its plans)


@dataclasses.dataclass
class Verdict:
    """The plan checker's verdict on one plan (docs/planning.md, "The plan checker")."""
    valid: bool
    failure: str      # "none", "not_found", "start", "goal", "joint_limit", "speed_limit", "self_collision",
                      # "floor", "collision" or "motion": the first that applies
    reason: str       # one line naming the state, joint, sphere or obstacle at fault; "" when valid
    clearance: float  # the smallest clearance of any collision sphere at any state (world units; inf: no obstacles)


def _scene(spheres, boxes, cylinders, capsules):
    """The obstacles as (K, columns) tensors (lists and arrays of rows too)."""
    scene = {"spheres": spheres, "boxes": boxes, "cylinders": cylinders, "capsules": capsules}
    return {kind: rows if rows is None or isinstance(rows, torch.Tensor) else torch.as_tensor(rows, dtype=torch.float64)
            for kind, rows in scene.items()}


class InProcessPlanner:
    """A planner as `flowplan plan` makes it, planning in this process, with its plan checker (check.* of its
    config). Made by make_planner.

    Obstacles are keyword arguments of (K, columns) tensors, as the exported planner takes them (docs/export.md,
    "Obstacles"); start and goal are (D,) or (B, D) raw states, or J joint positions (at rest).
    """

    def __init__(self, core):
        self._core = core

    kind = property(lambda self: self._core.kind, doc="learned, rrt_connect or hybrid")
    native = property(lambda self: self._core.native, doc="whether its network runs flowplan's native kernels")
    horizon = property(lambda self: self._core.horizon, doc="T: states per plan")
    state_dim = property(lambda self: self._core.state_dim, doc="D: values per state")
    num_joints = property(lambda self: self._core.num_joints, doc="J: planned joints")
    dt = property(lambda self: self._core.dt, doc="seconds between states")
    source = property(lambda self: self._core.source, doc="what it was made from")
    config = property(lambda self: self._core.config, doc="its resolved config (YAML)")

    def _states(self, x, n, what):
        x = torch.as_tensor(x, dtype=torch.float32)
        if x.shape[-1] == self.num_joints and self.state_dim == 2 * self.num_joints:
            x = torch.cat([x, torch.zeros_like(x)], dim=-1)  # positions at rest
        if x.dim() == 1 and n != 0:
            x = x.unsqueeze(0).expand(n or 1, -1)
        elif n and x.shape[0] != n:
            raise Error(f"plan: {what}: {x.shape[0]} states for n = {n} plans")
        return x.contiguous()

    def plan(self, start, goal, n=None, *, spheres=None, boxes=None, cylinders=None, capsules=None, seed=0,
             floor_height=None, held=None):
        """Plans from start to goal (n plans of one pair, or one plan per row of (B, D) starts and goals).

        floor_height: the floor's height (z) for this call, -inf for none; None: the config's check.floor_height.
        held: joints that are not planned, by name, held at these values (a gripper's fingers); None: the robot's.
        Returns a PlanResult. Raises flowplan.Error for bad shapes or obstacles.
        """
        start, goal = self._states(start, n, "start"), self._states(goal, n, "goal")
        return PlanResult(**self._core.plan(start, goal, _scene(spheres, boxes, cylinders, capsules), int(seed),
                                            floor_height, dict(held or {})))

    def check(self, plans, start, goal, *, spheres=None, boxes=None, cylinders=None, capsules=None, found=None,
              floor_height=None, held=None):
        """The plan checker's verdicts on plans (N, T, D) from start to goal ((D,) or (N, D)) among the obstacles:
        a list of N Verdicts."""
        start, goal = self._states(start, 0, "start"), self._states(goal, 0, "goal")  # (D,) stays (D,)
        return [Verdict(**v) for v in self._core.check(torch.as_tensor(plans), start, goal,
                                                       _scene(spheres, boxes, cylinders, capsules), found,
                                                       floor_height, dict(held or {}))]

    def __repr__(self):
        return f"<flowplan.InProcessPlanner {self.kind} from {self.source}: ({self.horizon}, {self.state_dim}) plans>"


def make_planner(kind="learned", *, planner=None, ckpt=None, config=None, robot=None, overrides=()):
    """A planner of `flowplan plan`, in-process: what `flowplan plan --planner-kind KIND` makes of the same
    arguments (docs/planning.md).

    Args:
        kind: "learned", "rrt_connect" or "hybrid".
        planner: an exported planner file (learned, hybrid); it runs flowplan's native kernels.
        ckpt: a run folder or checkpoint instead of planner.
        config: a config file (RRT-Connect: its robot, trajectories and check.*; else applied over the planner's).
        robot: a robot folder (`flowplan robot import`) for RRT-Connect.
        overrides: "key=value" strings, e.g. ["rrt_connect.range=1.0", "check.margin=0.01"].

    Raises:
        flowplan.Error naming what is wrong; RuntimeError if the package's C++ module is not importable.
    """
    made = InProcessPlanner(_cpp("make_planner").InProcessPlanner(kind, str(planner or ""), str(ckpt or ""), str(config or ""),
                                                       str(robot or ""), [str(o) for o in overrides]))
    asked_portable = any("kernels=portable" in str(o) for o in overrides)
    if made.kind != "rrt_connect" and not made._core.native and not asked_portable:
        warnings.warn(f"{made.source}: planning with the network's portable code (the log says why)", stacklevel=2)
    return made


def _cpp(what):
    if _flowplan is None:
        raise RuntimeError(f"{what} needs {_why_portable.replace('is not importable', 'importable')}")
    return _flowplan


def generate(config, overrides=()):
    """`flowplan generate --config CONFIG OVERRIDES...`: rolls out the config's data set (generate.*; threads from
    `threads`) and returns the path of the HDF5 file written (generate.out). Progress goes to the log.

    Raises flowplan.Error naming the file or key at fault; KeyboardInterrupt on Ctrl-C (nothing is left written).
    """
    return _cpp("generate").generate(str(config), [str(o) for o in overrides])


def train(config=None, overrides=(), *, resume=None, until_step=0):
    """`flowplan train --config CONFIG OVERRIDES...`, or with resume=RUN_DIR `flowplan train --resume RUN_DIR
    OVERRIDES...`; until_step > 0 stops with a checkpoint at that step. Returns the run folder (config.yaml,
    metrics.jsonl, checkpoints/; docs/getting_started.md). The loss and validation loss go to the log as it trains.

    Raises flowplan.Error naming what is wrong; KeyboardInterrupt on Ctrl-C, after a checkpoint of the step reached
    (resume=RUN_DIR continues the run exactly).
    """
    return _cpp("train").train(str(config or ""), [str(o) for o in overrides], str(resume or ""), int(until_step))


def set_log_level(level):
    """What flowplan logs (to the console, as the command line does): "debug", "info" (default), "warn", "error"."""
    _cpp("set_log_level").set_log_level(str(level))


@dataclasses.dataclass
class Problem:
    """One problem of a problem file (`flowplan problems`, `flowplan scenes import`; docs/planning.md)."""
    name: str
    start: torch.Tensor        # (J,) float64 joint positions
    goal: torch.Tensor         # (J,)
    scene: dict                # kind -> (K, columns) float64 rows: spheres=, boxes=, ... of plan() and check()
    obstacle_names: List[str]  # (K) in the scene's numbering (spheres, boxes, cylinders, capsules), or empty
    floor_height: float        # None: no floor
    held: dict                 # joint name -> value held (a gripper's fingers)
    status: str                # "ok", or "refused" (no plan can start or end there)
    reason: str                # why it was refused
    notes: List[str]           # what the import changed

    def world(self):
        """The keyword arguments of InProcessPlanner.plan and check for this problem: obstacles, floor, held joints."""
        return dict(self.scene, floor_height=-float("inf") if self.floor_height is None else self.floor_height,
                    held=self.held)


def load_scene(path, workspace_dim=3):
    """A scene file's obstacles (docs/planning.md, "Scenes") as the keyword arguments of plan() and check():
    {"spheres": (K, 4), "boxes": (K, 10), ...} float64 rows, kinds without obstacles left out."""
    return dict(_cpp("load_scene").load_scene(str(path), int(workspace_dim)))


def load_problems(path):
    """A problem file's problems: a list of Problem.

        for problem in flowplan.load_problems("mbm/table_pick_val.yaml"):
            if problem.status == "ok":
                result = rrt.plan(problem.start, problem.goal, 1, **problem.world())
    """
    return [Problem(**entry) for entry in _cpp("load_problems").load_problems(str(path))]


def import_scenes(out, pairs=(), *, folder=None, robot=None, frames=(), grasped="touching-tcp", grasp_margin=0.01,
                  limit_tolerance=0.002, force=False):
    """`flowplan scenes import`: MoveIt planning scenes and motion-plan requests (MotionBenchMaker's format) into
    the problem file `out`, whose problems it returns (load_problems).

    Args:
        out: the problem file to write.
        pairs: (scene.yaml, request.yaml) pairs; or folder: a folder of sceneNNNN.yaml / requestNNNN.yaml pairs.
        robot: a robot folder whose joints the requests set by name (default: the built-in Franka).
        frames, grasped, grasp_margin, limit_tolerance: as the command's --frame, --grasped, --grasp-margin and
            --limit-tolerance (docs/planning.md).
        force: replace `out` if it exists (otherwise flowplan.Error names it and nothing is written).

    A pair that cannot be planned is a problem with status "refused" and its reason; a file that is not a MoveIt
    file raises flowplan.Error naming it, and nothing is written.
    """
    files = [str(f) for pair in pairs for f in pair]
    _cpp("import_scenes").import_scenes(files, str(folder or ""), str(out), str(robot or ""),
                                        [str(f) for f in frames], str(grasped), float(grasp_margin),
                                        float(limit_tolerance), bool(force))
    return load_problems(out)


@dataclasses.dataclass
class RobotFolder:
    """A robot folder `import_robot` wrote (docs/robots.md): pass `path` as robot= to make_planner, or to the
    commands' --robot."""
    path: str                     # the folder: robot.yaml, meshes/
    name: str                     # the robot's name
    joints: List[str]             # (J) the planned joints, in order
    lower: torch.Tensor           # (J,) float64 position limits (rad, or m for a prismatic joint)
    upper: torch.Tensor           # (J,)
    velocity_limit: torch.Tensor  # (J,) rad/s or m/s
    effort_limit: torch.Tensor    # (J,) N·m or N
    spheres: int                  # collision spheres, all links
    ignored_pairs: List[tuple]    # (link, link, reason): pairs never checked against each other
    cover: List[dict]             # per link: spheres, samples, largest_uncovered and largest_outside (m), overshoot_ratio
    notes: List[str]              # what the import decided, one line each


def import_robot(model, out, *, srdf=None, package_dir=None, base=None, tip=None, tcp_offset=None, joints=(),
                 hold=None, overshoot=0.01, max_spheres=64, pair_samples=10000, velocity_limit=None,
                 collision_group=None, force=False):
    """`flowplan robot import`: a robot folder `out` (robot.yaml and meshes/) from a URDF (.urdf) or an MJCF (.xml),
    with collision spheres fitted to the collision geometry. Returns a RobotFolder.

        arm = flowplan.import_robot("examples/lift_arm/lift_arm.urdf", "robots/lift_arm", package_dir="examples",
                                    tip="tool")
        rrt = flowplan.make_planner("rrt_connect", robot=arm.path, config="configs/robot_joint.yaml")

    Args (as the command's options, docs/robots.md):
        srdf: an SRDF whose disable_collisions are the link pairs not checked.
        package_dir: the folder package://NAME/... paths resolve in.
        base, tip: the link fixed to the world and the link carrying the TCP; tcp_offset: (x, y, z) in the tip (m).
        joints: the planned joints in order (default: from base to tip); hold: {joint: value} held joints.
        overshoot: how far a sphere may reach outside the geometry (m); max_spheres: most spheres per link.
        pair_samples: random configurations that decide which link pairs always touch (without srdf).
        velocity_limit, collision_group: for an MJCF, as --velocity-limit and --collision-group.
        force: replace an existing out/robot.yaml.

    Raises flowplan.Error naming the file and element at fault (a malformed URDF, a joint without limits, a tip that
    does not exist, a missing collision mesh) or an existing robot.yaml without force.
    """
    if isinstance(joints, str):  # "a,b,c", as the command takes them
        joints = [j for j in joints.split(",") if j]
    entry = _cpp("import_robot").import_robot(
        str(model), str(out), str(srdf or ""), str(package_dir or ""), str(base or ""), str(tip or ""),
        [float(v) for v in tcp_offset] if tcp_offset is not None else [], [str(j) for j in joints],
        {str(k): float(v) for k, v in (hold or {}).items()}, float(overshoot), int(max_spheres), int(pair_samples),
        [float(v) for v in velocity_limit] if velocity_limit is not None else [],
        -1 if collision_group is None else int(collision_group), bool(force))
    return RobotFolder(**entry)


def render(plans, out=None, *, problem=None, index=0, robot=None, config=None, overrides=()):
    """`flowplan render`: plan `index` of the plan file `plans` (PREFIX.h5 of `flowplan plan`, or of `--problems`
    with problem=NAME) drawn among its scene's shapes, as out.gif (a frame a state) and out.png (four states). The
    built-in Franka's plans, and given robot=FOLDER a robot folder's, are executed in MuJoCo first and the execution
    drawn. config and overrides set render.* (size, camera) and execute.* (docs/planning.md).

    Returns {"gif": path, "png": path, "frames": n, "shown": what the video shows (contacts, goal distance)}.
    Raises flowplan.Error naming the file, problem, index or setting at fault.
    """
    return _cpp("render").render(str(plans), str(out or ""), str(problem or ""), int(index), str(robot or ""),
                                 str(config or ""), [str(o) for o in overrides])


def make_problems(out, config=None, overrides=(), *, family=None, robot=None, force=False):
    """`flowplan problems`: random planning problems written to the problem file `out`, whose problems it returns
    (load_problems). Without family, spheres that block the straight TCP path (problems.* of the config: count,
    spheres, radii, clearance) for the built-in Franka or the robot folder `robot` (or the config's robot:); with
    family="shelf" (or another of the scene families, docs/planning.md) that family's problems for the same robot.
    The config's seed makes them; the same seed gives the same file.

        problems = flowplan.make_problems("shelf.yaml", family="shelf", overrides=["problems.count=20"])

    Raises flowplan.Error naming the setting or folder at fault, or `out` if it exists and force is not set;
    nothing is written then.
    """
    _cpp("make_problems").make_problems(str(out), str(config or ""), [str(o) for o in overrides], str(family or ""),
                                        str(robot or ""), bool(force))
    return load_problems(out)


def evaluate_stitching(ckpt, out=None, config=None, overrides=()):
    """`flowplan eval stitching`: the trained planner's stitching error, unguided, on its data set's test pairs (that
    no training episode connects) and training pairs: per plan 0.5 (|x_1 - start| + |x_{T-2} - goal|) over the
    positions, eval.num_plans plans per set (docs/getting_started.md). ckpt is a checkpoint or a run folder (its
    newest checkpoint); config and overrides apply over the checkpoint's config.

    Returns the report (written to out, default RUN/eval_stitching.json) as a dict: "test" and "train" each hold
    "mean", "stddev", "num_plans" and "per_pair"; "plans_file" is the HDF5 file of the plans beside it
    (/test/plans (N, T, D), /test/pair_index (N,), and /train/...).
    """
    import json
    path, plans = _cpp("evaluate_stitching").evaluate_stitching(str(ckpt), str(out or ""), str(config or ""),
                                                                [str(o) for o in overrides])
    with open(path) as report:
        result = json.load(report)
    result["report_file"] = path
    result["plans_file"] = plans
    return result
