"""The Python package: flowplan.load_planner runs the shipped planners' weights with flowplan's native kernels,
plans what the files plan, and says what is wrong with bad files in one line.

Run by ctest (Python.package.<function without test_>, Python.script_package) with PYTHONPATH=BUILD/python; by hand:
    PYTHONPATH=build/python /usr/bin/python3 -m pytest -q python/tests
"""
import os
import shutil
import subprocess
import sys
import textwrap

import pytest
import torch

import flowplan

SOURCE = os.environ.get("FLOWPLAN_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
BINARY = os.environ.get("FLOWPLAN_BINARY_DIR", os.path.join(SOURCE, "build"))
REACH = os.path.join(SOURCE, "pretrained", "franka_reach_planner.pt")
SPLIT = os.path.join(SOURCE, "pretrained", "franka_joint_split_planner.pt")
UR5 = os.path.join(SOURCE, "pretrained", "ur5_joint_planner.pt")
SPHERE = torch.tensor([[0.5, 0.0, 0.2, 0.1]])  # the paper's: centre, radius (m)

torch.set_num_threads(2)


def paper_problem(planner):
    """Start and goal (14,) at rest, TCP from (0.5, -0.3, 0.2) to (0.5, 0.3, 0.2)."""
    start = torch.cat([planner.ik(torch.tensor([0.5, -0.3, 0.2])), torch.zeros(7)])
    goal = torch.cat([planner.ik(torch.tensor([0.5, 0.3, 0.2])), torch.zeros(7)])
    return start, goal


def noises(planner, batch, seed=0):
    generator = torch.Generator().manual_seed(seed)
    noise = torch.randn([batch] + list(planner.noise_shape), generator=generator)
    renoise = torch.randn([batch] + list(planner.renoise_shape), generator=generator) if planner.renoise_shape else None
    return noise, renoise


def test_the_cpp_module_is_there():
    assert flowplan.native_kernels()


@pytest.mark.parametrize("path", [REACH, SPLIT])
def test_native_planner_plans_what_the_file_plans(path):
    native = flowplan.load_planner(path)
    portable = flowplan.load_planner(path, native=False)
    assert native.native and not portable.native
    # The native planner's network and guidance are flowplan's operators; the file's are LibTorch's.
    assert "ops.flowplan.unet1d" in native.module.sampler.network.code
    assert "ops.flowplan" not in portable.module.sampler.network.code
    start, goal = paper_problem(portable)
    noise, renoise = noises(portable, 8)
    starts, goals = start.expand(8, -1), goal.expand(8, -1)
    extra = {} if renoise is None else {"renoise": renoise}
    ours = native.plan(starts, goals, noise, spheres=SPHERE, **extra)
    theirs = portable.plan(starts, goals, noise, spheres=SPHERE, **extra)
    by_torch = torch.jit.load(path)
    with torch.no_grad():
        direct = by_torch.plan(starts, goals, noise, spheres=SPHERE, **extra)
    assert torch.equal(theirs, direct)  # native=False is the file as written
    assert ours.shape == (8, portable.horizon, 14)
    # Summed in another order, iterated over the sampler's guided steps: close, not the same bytes
    # (docs/export.md); rad and rad/s.
    assert (ours - theirs).abs().max().item() < 2e-2
    assert (ours - theirs).abs().mean().item() < 2e-4


def test_guided_native_plans_clear_the_sphere():
    planner = flowplan.load_planner(REACH)
    start, goal = paper_problem(planner)
    torch.manual_seed(0)
    plans = planner.sample(start, goal, 16, spheres=SPHERE)
    assert plans.shape == (16, 64, 14) and not plans.requires_grad
    # Judged by the file's own scripts (LibTorch's operators), not by the native kernels that planned.
    judge = torch.jit.load(REACH)
    with torch.no_grad():
        clear = judge.clearance(plans[..., :7], spheres=SPHERE).amin(dim=(1, 2)) >= 0
        unguided = planner.sample(start, goal, 16, spheres=SPHERE, settings={"guidance.scale": 0.0})
        unguided_clear = judge.clearance(unguided[..., :7], spheres=SPHERE).amin(dim=(1, 2)) >= 0
        reached = (judge.tcp(plans[:, -1, :7]) - torch.tensor([0.5, 0.3, 0.2])).norm(dim=-1)
    assert clear.sum().item() >= 14
    assert unguided_clear.sum().item() <= 2  # the guidance, not luck, clears it
    assert reached.max().item() < 0.03


def test_any_arm_planner_loads_native():
    planner = flowplan.load_planner(UR5)
    assert planner.native and planner.state_dim == 12
    noise, _ = noises(planner, 2)
    start = torch.zeros(2, 12)
    goal = torch.cat([torch.full((2, 6), 0.5), torch.zeros(2, 6)], dim=1)
    plans = planner.plan(start, goal, noise)
    assert plans.shape == (2, planner.horizon, 12)
    assert torch.allclose(plans[:, 0], start, atol=1e-5) and torch.allclose(plans[:, -1], goal, atol=1e-5)
    with torch.no_grad():  # the file alone, with PyTorch's operators: the same plans to the kernels' rounding
        plain = torch.jit.load(UR5).plan(start, goal, noise)
    assert (plans - plain).abs().max().item() < 2e-2 and (plans - plain).abs().mean().item() < 2e-4


def test_a_planner_is_a_python_object_like_any_other():
    import copy
    planner = flowplan.load_planner(REACH)
    assert "sample" in dir(planner) and "ik" in dir(planner)
    shallow = copy.copy(planner)
    assert shallow.module is planner.module and shallow.native
    with pytest.raises(AttributeError):
        planner.no_such_method


def test_bad_files_are_one_clear_error(tmp_path):
    with pytest.raises(FileNotFoundError):
        flowplan.load_planner(tmp_path / "missing.pt")
    text = tmp_path / "notes.pt"
    text.write_text("not a planner\n")
    with pytest.raises(flowplan.Error, match="notes.pt: not a TorchScript module"):
        flowplan.load_planner(text)

    class Tiny(torch.nn.Module):
        def forward(self, x):
            return x + 1

    tiny = tmp_path / "tiny.pt"
    torch.jit.script(Tiny()).save(str(tiny))
    for native in (None, False):
        with pytest.raises(flowplan.Error, match="tiny.pt: not a flowplan planner"):
            flowplan.load_planner(tiny, native=native)


def export(*args):
    subprocess.run([os.path.join(BINARY, "apps", "flowplan", "flowplan"), "export", *map(str, args)], check=True,
                   capture_output=True)


def test_export_planner_reads_back_every_weight(tmp_path):
    # The file's weights read back from its script (models::ReadScriptedWeights) and written again with the
    # same portable code: the same planner, bit for bit.
    out = tmp_path / "split_again.pt"
    export("--planner", SPLIT, "--kernels", "portable", "--out", out)
    original, again = torch.jit.load(SPLIT), torch.jit.load(str(out))
    assert "ops.flowplan" not in again.sampler.network.code
    written = dict(again.sampler.network.named_buffers())
    for name, weight in original.sampler.network.named_buffers():
        assert torch.equal(weight, written.pop(name)), name
    assert not written
    start, goal = paper_problem(original)
    noise, renoise = noises(original, 4)
    with torch.no_grad():
        assert torch.equal(original.plan(start.expand(4, -1), goal.expand(4, -1), noise, renoise, spheres=SPHERE),
                           again.plan(start.expand(4, -1), goal.expand(4, -1), noise, renoise, spheres=SPHERE))


def test_export_planner_writes_a_native_file(tmp_path):
    out = tmp_path / "reach_native.pt"
    export("--planner", REACH, "--kernels", "native", "--out", out)
    # flowplan's C++ module loaded the kernels into this process: the native file loads with torch.jit.load.
    loaded = torch.jit.load(str(out))
    assert "ops.flowplan.unet1d" in loaded.sampler.network.code
    planner = flowplan.load_planner(out)
    start, goal = paper_problem(planner)
    noise, _ = noises(planner, 4)
    with torch.no_grad():
        assert torch.equal(loaded.plan(start.expand(4, -1), goal.expand(4, -1), noise, spheres=SPHERE),
                           planner.plan(start.expand(4, -1), goal.expand(4, -1), noise, spheres=SPHERE))


def test_without_the_cpp_module_the_files_own_code_plans(tmp_path):
    shutil.copytree(os.path.dirname(flowplan.__file__), tmp_path / "flowplan",
                    ignore=shutil.ignore_patterns("_flowplan*", "__pycache__"))
    script = textwrap.dedent(f"""
        import warnings, torch, flowplan
        assert not flowplan.native_kernels()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            planner = flowplan.load_planner({REACH!r})
        assert not planner.native
        assert "portable code" in str(caught[0].message), caught
        start = torch.cat([planner.ik(torch.tensor([0.5, -0.3, 0.2])), torch.zeros(7)])
        goal = torch.cat([planner.ik(torch.tensor([0.5, 0.3, 0.2])), torch.zeros(7)])
        assert planner.sample(start, goal, 2).shape == (2, 64, 14)
        try:
            flowplan.load_planner({REACH!r}, native=True)
        except RuntimeError as error:
            assert "not importable" in str(error), error
        else:
            raise AssertionError("native=True without the C++ module must fail")
    """)
    environment = dict(os.environ, PYTHONPATH=str(tmp_path))
    subprocess.run([sys.executable, "-c", script], check=True, env=environment, cwd=tmp_path)


# The shelf scene of configs/scenes/franka_shelf.yaml as tensors: a table top, an upright board across the
# base joint's path, a bottle.
SHELF = {
    "boxes": torch.tensor([[0.6, 0.0, 0.0, 0.5, 1.0, 0.04, 1.0, 0.0, 0.0, 0.0],
                           [0.447, 0.176, 0.42, 0.2, 0.03, 0.22, 0.9825, 0.0, 0.0, 0.1864]]),
    "cylinders": torch.tensor([[0.55, -0.2, 0.12, 0.04, 0.2, 1.0, 0.0, 0.0, 0.0]]),
}
SHELF_START = torch.tensor([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
SHELF_GOAL = torch.tensor([0.75, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])


def straight_line(start, goal, horizon):
    """(1, T, 14): the joint-space line at rest at both ends, velocities zero."""
    s = torch.linspace(0, 1, horizon).unsqueeze(1)
    return torch.cat([start + s * (goal - start), torch.zeros(horizon, 7)], dim=1).unsqueeze(0)


def test_rrt_connect_in_process_plans_around_the_board_and_the_checker_says_why_a_line_does_not():
    rrt = flowplan.make_planner("rrt_connect", config=os.path.join(SOURCE, "configs", "franka_joint.yaml"))
    assert rrt.kind == "rrt_connect" and (rrt.state_dim, rrt.num_joints) == (14, 7)
    line = straight_line(SHELF_START, SHELF_GOAL, rrt.horizon)
    verdict, = rrt.check(line, SHELF_START, SHELF_GOAL, **SHELF)
    assert not verdict.valid and verdict.failure in ("collision", "motion") and "boxes[1]" in verdict.reason
    result = rrt.plan(SHELF_START, SHELF_GOAL, 3, seed=1, **SHELF)
    assert result.plans.shape == (3, rrt.horizon, 14) and result.found.all() and not any(result.refused)
    verdicts = rrt.check(result.plans, SHELF_START, SHELF_GOAL, found=result.found, **SHELF)
    assert all(v.valid for v in verdicts), verdicts
    assert all(v.clearance >= 0 for v in verdicts)
    again = rrt.plan(SHELF_START, SHELF_GOAL, 3, seed=1, **SHELF)
    assert torch.equal(again.plans, result.plans)  # same seed, same bytes
    # Without the board the line is valid, and RRT-Connect's plans stay near it.
    free = {"boxes": SHELF["boxes"][:1], "cylinders": SHELF["cylinders"]}
    assert rrt.check(line, SHELF_START, SHELF_GOAL, **free)[0].valid
    # A goal past a joint limit is refused, with its reason, not searched for.
    past = SHELF_GOAL.clone()
    past[3] = 0.5  # joint 4 stays below -0.0698 rad
    refused = rrt.plan(SHELF_START, past, 1, **SHELF)
    assert refused.refused == [True] and "goal" in refused.failure[0] and not refused.found.any()


def test_hybrid_and_learned_in_process_with_the_shipped_planner():
    hybrid = flowplan.make_planner("hybrid", planner=SPLIT, overrides=["hybrid.order=classical_first"])
    result = hybrid.plan(SHELF_START, SHELF_GOAL, 2, **SHELF)
    assert result.found.all() and len(result.route) == 2
    assert all(v.valid for v in hybrid.check(result.plans, SHELF_START, SHELF_GOAL, **SHELF))
    learned = flowplan.make_planner("learned", planner=REACH)
    assert learned.native and not flowplan.make_planner("learned", planner=REACH, overrides=[
        "sampler.network_kernels=portable", "guidance.distance_kernels=portable"]).native
    start, goal = paper_problem(flowplan.load_planner(REACH, native=False))
    result = learned.plan(start, goal, 8, spheres=SPHERE, seed=3)
    verdicts = learned.check(result.plans, start, goal, spheres=SPHERE)
    assert sum(v.valid for v in verdicts) >= 6, verdicts
    unguided = flowplan.make_planner("learned", planner=REACH, overrides=["guidance.scale=0"])
    result = unguided.plan(start, goal, 8, spheres=SPHERE, seed=3)
    assert sum(v.failure in ("collision", "motion") for v in unguided.check(result.plans, start, goal,
                                                                              spheres=SPHERE)) >= 6


def test_in_process_planners_say_what_is_wrong():
    with pytest.raises(flowplan.Error, match="--planner-kind: expected one of"):
        flowplan.make_planner("astar", config=os.path.join(SOURCE, "configs", "franka_joint.yaml"))
    with pytest.raises(flowplan.Error, match="missing.pt"):
        flowplan.make_planner("learned", planner="missing.pt")
    rrt = flowplan.make_planner("rrt_connect", config=os.path.join(SOURCE, "configs", "franka_joint.yaml"))
    with pytest.raises(flowplan.Error, match="boxes: .*row 0"):
        rrt.plan(SHELF_START, SHELF_GOAL, 1, boxes=torch.tensor([[0.5, 0, 0, 0.1, 0.1, -0.1, 1, 0, 0, 0]]))
    with pytest.raises(flowplan.Error, match="plan: start"):
        rrt.plan(torch.zeros(5), SHELF_GOAL, 1)


def test_generate_train_resume_and_plan_from_python(tmp_path):
    tiny = os.path.join(SOURCE, "tests", "cli", "tiny.yaml")
    paths = [f"generate.out={tmp_path}/data.h5", f"data.path={tmp_path}/data.h5", f"run_dir={tmp_path}/run"]
    assert flowplan.generate(tiny, paths) == f"{tmp_path}/data.h5"
    run = flowplan.train(tiny, paths, until_step=3)
    assert run == f"{tmp_path}/run"
    # Training flushes denormals to zero on its thread and sets LibTorch's thread count from its config; the caller's
    # floating-point mode and thread count come back with the call.
    assert (torch.tensor([1e-40]) * 1.0).item() != 0 and torch.get_num_threads() == 2
    assert sorted(os.listdir(os.path.join(run, "checkpoints"))) == ["step_00000003.pt"]
    assert flowplan.train(resume=run) == run
    assert "step_00000006.pt" in os.listdir(os.path.join(run, "checkpoints"))
    # The stitching error of the run, recomputed from the plans and the data set's pairs read by h5py.
    import h5py
    report = flowplan.evaluate_stitching(run, tmp_path / "stitching.json")
    assert report["report_file"] == str(tmp_path / "stitching.json") and report["step"] == 6
    with h5py.File(report["plans_file"], "r") as plans, h5py.File(tmp_path / "data.h5", "r") as data:
        for pairs in ("test", "train"):
            x = torch.from_numpy(plans[pairs]["plans"][()]).double()               # (N, T, D)
            which = torch.from_numpy(plans[pairs]["pair_index"][()]).long()        # (N,)
            start = torch.from_numpy(data["eval"][f"{pairs}_pairs"]["start"][()]).double()[which]
            goal = torch.from_numpy(data["eval"][f"{pairs}_pairs"]["goal"][()]).double()[which]
            positions = slice(0, 2)  # the particle's x, y (then vx, vy)
            errors = 0.5 * ((x[:, 1, positions] - start[:, positions]).norm(dim=1) +
                            (x[:, -2, positions] - goal[:, positions]).norm(dim=1))
            assert report[pairs]["num_plans"] == x.shape[0]
            assert report[pairs]["mean"] == pytest.approx(errors.mean().item(), rel=1e-5)
    learned = flowplan.make_planner("learned", ckpt=run)
    result = learned.plan(torch.tensor([0.0, 0.0, 0.0, 0.0]), torch.tensor([1.0, 0.0, 0.0, 0.0]), 3,
                          spheres=[[0.5, 0.3, 0.1]])  # rows as a list: the same as a tensor
    assert result.plans.shape == (3, 16, 4)
    # A user cost is compiled into an exported file: the file plans with it even after its source changed
    # (assembling the planner again would read the source as it is now).
    cost = tmp_path / "above.py"
    cost.write_text("def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                    "    return torch.relu(0.2 - self.robot.tcp(q)[:, :, 1]).sum(1)\n")
    export("--ckpt", run, "--out", tmp_path / "costly.pt", f"guidance.user_cost={cost}",
           "guidance.user_cost_weight=1", "guidance.scale=2")
    ends = torch.tensor([0.0, 0.0, 0.0, 0.0]), torch.tensor([1.0, 0.0, 0.0, 0.0])
    with pytest.warns(UserWarning, match="portable code"):
        costly = flowplan.make_planner("learned", planner=tmp_path / "costly.pt")
    assert not costly.native
    before = costly.plan(*ends, 3, seed=2).plans
    cost.write_text("def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                    "    return torch.relu(self.robot.tcp(q)[:, :, 1] + 5.0).sum(1)\n")
    with pytest.warns(UserWarning, match="portable code"):
        after = flowplan.make_planner("learned", planner=tmp_path / "costly.pt").plan(*ends, 3, seed=2).plans
    assert torch.equal(before, after)
    with pytest.warns(UserWarning, match="user cost .* is compiled into it"):
        assert not flowplan.load_planner(tmp_path / "costly.pt").native
    with pytest.raises(flowplan.Error, match="train: give either a config or a run folder to resume, not both"):
        flowplan.train(tiny, resume=run)
    with pytest.raises(flowplan.Error, match="model.unet.down_dims"):
        flowplan.train(resume=run, overrides=["model.unet.down_dims=[8,32]"])
    with pytest.raises(flowplan.Error, match="loud"):
        flowplan.set_log_level("loud")
    flowplan.set_log_level("info")


def test_ctrl_c_while_training_checkpoints_and_raises_keyboard_interrupt(tmp_path):
    tiny = os.path.join(SOURCE, "tests", "cli", "tiny.yaml")
    script = textwrap.dedent(f"""
        import flowplan
        paths = ["generate.out={tmp_path}/data.h5", "data.path={tmp_path}/data.h5", "run_dir={tmp_path}/run"]
        flowplan.generate({tiny!r}, paths)
        print("training", flush=True)
        try:
            flowplan.train({tiny!r}, paths + ["train.steps=1000000", "train.checkpoint_every=1000000",
                                               "train.eval_every=1000000", "train.log_every=100"])
        except KeyboardInterrupt as interrupt:
            print("KeyboardInterrupt:", interrupt, flush=True)
        print("after", flowplan.train(resume="{tmp_path}/run", overrides=["train.steps=3"]), flush=True)
    """)
    process = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                               text=True, cwd=tmp_path)
    lines = []
    for line in process.stdout:
        lines.append(line)
        if "step 200" in line or "step=200" in line or ("step" in line and "loss" in line and len(lines) > 8):
            process.send_signal(2)  # SIGINT
            break
    output = "".join(lines) + process.communicate(timeout=120)[0]
    assert process.returncode == 0, output
    assert "KeyboardInterrupt: interrupted at step" in output, output
    assert "continue with: flowplan train --resume" in output
    # The interrupted run resumes (here to a shorter end: nothing left to train), and Python went on.
    assert f"after {tmp_path}/run" in output
    assert any(name.startswith("step_") for name in os.listdir(tmp_path / "run" / "checkpoints"))


def test_problem_files_and_scenes_plan_from_python(tmp_path):
    import yaml
    problems_file = tmp_path / "shelf.yaml"
    subprocess.run([os.path.join(BINARY, "apps", "flowplan", "flowplan"), "problems", "--family", "shelf",
                    "problems.count=2", "seed=3", "--out", str(problems_file), "--log-level", "warn"], check=True)
    problems = flowplan.load_problems(problems_file)
    written = yaml.safe_load(problems_file.read_text())["problems"]  # read by another YAML reader
    assert [p.name for p in problems] == [w["name"] for w in written]
    for problem, entry in zip(problems, written):
        assert problem.start.tolist() == pytest.approx(entry["start_q"], abs=1e-12)
        assert problem.goal.tolist() == pytest.approx(entry["goal_q"], abs=1e-12)
        assert problem.scene["boxes"].shape == (len(entry["scene"]["boxes"]), 10)
        assert problem.scene["boxes"][0, :3].tolist() == pytest.approx(entry["scene"]["boxes"][0]["centre"])
    rrt = flowplan.make_planner("rrt_connect", config=os.path.join(SOURCE, "configs", "franka_joint.yaml"))
    for problem in problems:
        result = rrt.plan(problem.start, problem.goal, 1, **problem.world())
        assert result.found.all(), result.failure
        assert rrt.check(result.plans, problem.start, problem.goal, **problem.world())[0].valid
    scene = flowplan.load_scene(os.path.join(SOURCE, "configs", "scenes", "franka_shelf.yaml"))
    assert sorted(scene) == ["boxes", "cylinders"]
    assert torch.allclose(scene["boxes"][:, :6].float(), SHELF["boxes"][:, :6])
    with pytest.raises(flowplan.Error, match="nothing.yaml"):
        flowplan.load_problems(tmp_path / "nothing.yaml")
    # flowplan.make_problems is `flowplan problems`: the same settings write the same file.
    again = flowplan.make_problems(tmp_path / "again.yaml", overrides=["problems.count=2", "seed=3"], family="shelf")
    assert (tmp_path / "again.yaml").read_bytes() == problems_file.read_bytes()
    assert torch.get_num_threads() == 2  # as this file set it: the call's own thread count is not left behind
    assert [p.name for p in again] == [p.name for p in problems]
    # An existing file is replaced only with force=True; without it, one error naming the file and the bytes kept.
    with pytest.raises(flowplan.Error, match="again.yaml: exists; give --force"):
        flowplan.make_problems(tmp_path / "again.yaml", overrides=["problems.count=1", "seed=4"], family="table")
    assert (tmp_path / "again.yaml").read_bytes() == problems_file.read_bytes()
    assert len(flowplan.make_problems(tmp_path / "again.yaml", overrides=["problems.count=1", "seed=4"],
                                      family="table", force=True)) == 1
    blocked = flowplan.make_problems(tmp_path / "ur5.yaml", overrides=["problems.count=3"],
                                     robot=os.path.join(SOURCE, "robots", "ur5"))
    assert len(blocked) == 3 and all(p.start.shape == (6,) and p.scene["spheres"].shape[0] >= 1 for p in blocked)
    # A family for the robot folder, planned by its RRT-Connect.
    shelf = flowplan.make_problems(tmp_path / "ur5_shelf.yaml", overrides=["problems.count=2"], family="shelf",
                                   robot=os.path.join(SOURCE, "robots", "ur5"))
    ur5 = flowplan.make_planner("rrt_connect", config=os.path.join(SOURCE, "configs", "robot_joint.yaml"),
                                robot=os.path.join(SOURCE, "robots", "ur5"))
    for problem in shelf:
        assert problem.start.shape == (6,) and problem.scene["boxes"].shape[0] >= 5
        result = ur5.plan(problem.start, problem.goal, 1, **problem.world())
        assert result.found.all(), result.failure
        assert ur5.check(result.plans, problem.start, problem.goal, **problem.world())[0].valid
    with pytest.raises(flowplan.Error, match="kitchen"):
        flowplan.make_problems(tmp_path / "bad.yaml", family="kitchen", robot=os.path.join(SOURCE, "robots", "ur5"))
    assert not (tmp_path / "bad.yaml").exists()


def test_rrt_connect_for_a_robot_folder():
    rrt = flowplan.make_planner("rrt_connect", config=os.path.join(SOURCE, "configs", "robot_joint.yaml"),
                                robot=os.path.join(SOURCE, "robots", "ur5"))
    assert (rrt.num_joints, rrt.state_dim) == (6, 12) and not rrt.native
    start, goal = torch.zeros(6), torch.tensor([1.0, -1.0, 1.0, 0.5, 0.5, 0.5])
    ball = [[0.4, 0.2, 0.4, 0.1]]
    result = rrt.plan(start, goal, 2, spheres=ball)
    assert result.found.all() and all(v.valid for v in rrt.check(result.plans, start, goal, spheres=ball))


def test_a_robot_imported_from_python_plans_and_its_limits_are_the_urdfs(tmp_path):
    import xml.etree.ElementTree as ElementTree
    urdf = os.path.join(SOURCE, "examples", "lift_arm", "lift_arm.urdf")
    arm = flowplan.import_robot(urdf, tmp_path / "lift_arm", package_dir=os.path.join(SOURCE, "examples"), tip="tool",
                                pair_samples=2000)
    assert (tmp_path / "lift_arm" / "robot.yaml").exists() and arm.path == str(tmp_path / "lift_arm")
    # The planned joints, limits and efforts as the URDF states them, read by another reader.
    limits = {j.get("name"): j.find("limit") for j in ElementTree.parse(urdf).getroot().iter("joint")
              if j.get("type") != "fixed"}
    assert arm.joints == ["lift", "shoulder", "elbow", "wrist"]
    for key, values in (("lower", arm.lower), ("upper", arm.upper), ("velocity", arm.velocity_limit),
                        ("effort", arm.effort_limit)):
        assert values.tolist() == pytest.approx([float(limits[j].get(key)) for j in arm.joints], abs=1e-12)
    # Adjacent links are never checked against each other; every link's surface is covered.
    ignored = {frozenset(pair[:2]) for pair in arm.ignored_pairs}
    assert {frozenset(("base", "column")), frozenset(("column", "upper")), frozenset(("upper", "fore"))} <= ignored
    assert arm.spheres == sum(c["spheres"] for c in arm.cover) and all(c["largest_uncovered"] == 0 for c in arm.cover)
    assert 0 < max(c["largest_outside"] for c in arm.cover) < 0.02  # about the overshoot asked for (0.01)
    rrt = flowplan.make_planner("rrt_connect", config=os.path.join(SOURCE, "configs", "robot_joint.yaml"),
                                robot=arm.path)
    start, goal = torch.tensor([0.0, -1.0, 0.5, 0.0]), torch.tensor([0.25, 1.5, -0.5, 1.0])
    ball = [[0.0, 0.45, 0.6, 0.1]]
    result = rrt.plan(start, goal, 1, spheres=ball)
    assert result.found.all() and rrt.check(result.plans, start, goal, spheres=ball)[0].valid
    # Again without force: one error naming the file; a URDF that is not there: one error naming it.
    with pytest.raises(flowplan.Error, match="robot.yaml exists"):
        flowplan.import_robot(urdf, tmp_path / "lift_arm", package_dir=os.path.join(SOURCE, "examples"), tip="tool")
    with pytest.raises(flowplan.Error, match="missing.urdf"):
        flowplan.import_robot(tmp_path / "missing.urdf", tmp_path / "other")
    assert not (tmp_path / "other" / "robot.yaml").exists()


def test_render_executes_a_robot_folders_plan_and_draws_it(tmp_path):
    from PIL import Image
    flowplan_binary = os.path.join(BINARY, "apps", "flowplan", "flowplan")
    ur5 = os.path.join(SOURCE, "robots", "ur5")
    subprocess.run([flowplan_binary, "plan", "--rrt-connect", "--robot", ur5, "--config",
                    os.path.join(SOURCE, "configs", "robot_joint.yaml"), "--start", "0,-1,1,0,0,0",
                    "--goal", "1,-1,1,0.5,0.5,0.5", "--sphere", "0.4,0.2,0.4,0.1", "-n", "2", "--no-plot",
                    "--out", str(tmp_path / "ur5")], check=True, capture_output=True)
    drawn = flowplan.render(tmp_path / "ur5.h5", tmp_path / "ur5_1", index=1, robot=ur5,
                            overrides=["render.width=160", "render.height=120"])
    assert drawn["gif"] == str(tmp_path / "ur5_1.gif") and "executed in MuJoCo: 0 contacts" in drawn["shown"]
    with Image.open(drawn["gif"]) as gif:
        assert gif.size == (160, 120) and gif.n_frames == drawn["frames"] > 64  # the plan's states and the settling
    with Image.open(drawn["png"]) as png:
        assert png.size == (320, 240)  # four states, two to a row
    # Without the folder the plan is drawn as planned, a frame a state.
    assert flowplan.render(tmp_path / "ur5.h5", tmp_path / "planned", overrides=["render.width=160",
                                                                                  "render.height=120"])["frames"] == 64
    with pytest.raises(flowplan.Error, match="--index"):
        flowplan.render(tmp_path / "ur5.h5", tmp_path / "bad", index=2)
    assert not (tmp_path / "bad.gif").exists()


def test_motionbenchmaker_files_are_imported_and_planned_from_python(tmp_path):
    import tarfile
    import yaml
    tarball = os.path.join(SOURCE, "bench", "motionbenchmaker", "panda_problems.tar.bz2")
    with tarfile.open(tarball) as archive:
        members = [m for m in archive.getmembers()
                   if "/box_panda/" in m.name and m.name.endswith(("scene0001.yaml", "request0001.yaml",
                                                                  "scene0002.yaml", "request0002.yaml"))]
        archive.extractall(tmp_path, members)
    folder = next(p.parent for p in tmp_path.rglob("scene0001.yaml"))
    problems = flowplan.import_scenes(tmp_path / "box.yaml", folder=folder)
    assert [p.name for p in problems] == ["scene0001", "scene0002"] and (tmp_path / "box.yaml").exists()
    request = yaml.safe_load((folder / "request0001.yaml").read_text())  # the published file, by another reader
    joints = request["start_state"]["joint_state"]
    published = dict(zip(joints["name"], joints["position"]))
    assert problems[0].start.tolist() == pytest.approx([published[f"panda_joint{j}"] for j in range(1, 8)], abs=1e-9)
    assert problems[0].floor_height is None  # MotionBenchMaker's world has no floor
    rrt = flowplan.make_planner("rrt_connect", config=os.path.join(SOURCE, "configs", "franka_joint.yaml"),
                                overrides=["rrt_connect.range=1.0"])
    for problem in problems:
        result = rrt.plan(problem.start, problem.goal, 1, **problem.world())
        assert rrt.check(result.plans, problem.start, problem.goal, found=result.found, **problem.world())[0].valid
    again = flowplan.import_scenes(tmp_path / "pairs.yaml", [(folder / "scene0002.yaml", folder / "request0002.yaml")])
    assert again[0].start.tolist() == problems[1].start.tolist()
    with pytest.raises(flowplan.Error, match="request0001.yaml"):
        flowplan.import_scenes(tmp_path / "bad.yaml", [(folder / "scene0001.yaml", folder / "request0001.yaml"),
                                                       (folder / "request0001.yaml", folder / "request0001.yaml")])
    assert not (tmp_path / "bad.yaml").exists()
