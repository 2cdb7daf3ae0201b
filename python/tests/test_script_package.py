"""flowplan.script: the TorchScript files flowplan compiles into every planner, imported as Python modules and run
eagerly by PyTorch, against closed forms, against PyTorch's own TorchScript compiler, against the copies compiled
into a shipped planner, and the hand-written collision gradient against autograd.

Run by ctest (Python.package.<function without test_>, Python.script_package) with PYTHONPATH=BUILD/python; by hand:
    PYTHONPATH=build/python /usr/bin/python3 -m pytest -q python/tests/test_script_package.py
"""
import builtins
import dis
import importlib
import inspect
import os
import pkgutil

import pytest
import torch

import flowplan.script
from flowplan.script.geometry.box import box_distance, box_prepared
from flowplan.script.geometry.scene import prepared_scene, scene_distance
from flowplan.script.guidance.collision import CollisionCost
from flowplan.script.kinematics.arm import Arm

SOURCE = os.environ.get("FLOWPLAN_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
REACH = os.path.join(SOURCE, "pretrained", "franka_reach_planner.pt")

torch.set_num_threads(2)


def modules():
    """Every module of flowplan.script, by name."""
    names = []
    for info in pkgutil.walk_packages(flowplan.script.__path__, "flowplan.script."):
        if not info.ispkg:
            names.append(info.name)
    return sorted(names)


def test_every_file_of_the_binary_is_a_module():
    # The files the binary embeds (jit/library.h) are those of the package: each folder's *.py beside its C++.
    names = modules()
    assert "flowplan.script.geometry.box" in names and "flowplan.script.planning.planner" in names
    for name in names:
        path = os.path.join(SOURCE, *name.split(".")[2:]) + ".py"
        assert os.path.isfile(path), name + " has no file in the repository"
        with open(path) as source, open(importlib.import_module(name).__file__) as packaged:
            assert source.read() == packaged.read(), name + " differs from " + path
    # And every TorchScript file of those folders is in the package (a file left out of flowplan_add_scripts is not).
    folders = {name.split(".")[2] for name in names}
    for folder in folders:
        for file in os.listdir(os.path.join(SOURCE, folder)):
            if file.endswith(".py"):
                with open(os.path.join(SOURCE, folder, file)) as f:
                    if f.readline().startswith("# TorchScript"):
                        assert "flowplan.script.%s.%s" % (folder, file[:-3]) in names, folder + "/" + file


def global_names(code):
    """The global names a function's code reads (its nested code too)."""
    names = {i.argval for i in dis.get_instructions(code) if i.opname == "LOAD_GLOBAL"}
    for const in code.co_consts:
        if inspect.iscode(const):
            names |= global_names(const)
    return names


@pytest.mark.parametrize("name", modules())
def test_every_module_imports_and_defines_what_it_uses(name):
    module = importlib.import_module(name)
    functions = [f for _, f in inspect.getmembers(module, inspect.isfunction) if f.__module__ == name]
    classes = [c for _, c in inspect.getmembers(module, inspect.isclass) if c.__module__ == name]
    # A function file holds functions, a class file one class of methods (jit/library.h).
    assert (len(functions) > 0 and not classes) or (not functions and len(classes) == 1), name
    for cls in classes:
        functions += [f for _, f in inspect.getmembers(cls, inspect.isfunction)]
    # Every global name a function reads is imported or defined: Python resolves them only when it runs.
    for function in functions:
        missing = {n for n in global_names(function.__code__) if n not in vars(module) and not hasattr(builtins, n)}
        assert not missing, "%s.%s reads undefined %s" % (name, function.__name__, sorted(missing))


def test_box_distance_is_the_closed_form():
    # An axis-aligned box centred at c with half sides h: outside, the length of max(|p - c| - h, 0); inside, the
    # largest |p - c| - h (negative).
    generator = torch.Generator().manual_seed(0)
    box = torch.tensor([[0.3, -0.2, 0.5, 0.4, 0.2, 0.6, 1.0, 0.0, 0.0, 0.0]], dtype=torch.float64)
    points = torch.rand(4000, 3, generator=generator, dtype=torch.float64) * 1.6 - 0.8 + box[:, :3]
    distance, normal = box_distance(points, box_prepared(box, 3))
    gap = (points - box[:, :3]).abs() - box[:, 3:6] / 2
    outside = gap.clamp(min=0).norm(dim=1)
    expected = torch.where(outside > 0, outside, gap.max(dim=1).values)
    assert torch.allclose(distance[:, 0], expected, atol=1e-12)
    assert torch.allclose(normal[:, 0].norm(dim=1), torch.ones(4000, dtype=torch.float64), atol=1e-9)


def test_pytorch_compiles_the_same_source():
    # PyTorch's own TorchScript frontend compiles scene_distance and every function it calls from the package.
    scripted = torch.jit.script(scene_distance)
    generator = torch.Generator().manual_seed(1)
    scene = prepared_scene({"spheres": torch.tensor([[0.5, 0.0, 0.2, 0.1]], dtype=torch.float64),
                            "boxes": torch.tensor([[0.2, 0.3, 0.4, 0.1, 0.2, 0.3, 0.9, 0.1, 0.3, 0.2]],
                                                  dtype=torch.float64),
                            "capsules": torch.tensor([[0.0, 0.0, 0.0, 0.3, 0.3, 0.3, 0.05]], dtype=torch.float64)}, 3)
    points = torch.rand(500, 3, generator=generator, dtype=torch.float64)
    eager, eager_normal = scene_distance(points, scene)
    compiled, compiled_normal = scripted(points, scene)
    assert torch.equal(eager, compiled) and torch.equal(eager_normal, compiled_normal)


@pytest.fixture(scope="module")
def planner():
    return torch.jit.load(REACH)


def test_the_arm_source_runs_on_a_planners_weights_as_its_compiled_copy(planner):
    # kinematics/arm.py run eagerly with the shipped planner's robot as `self` against the method compiled into it.
    robot = planner.robot
    generator = torch.Generator().manual_seed(2)
    q = (torch.rand(16, 7, generator=generator, dtype=torch.float64) - 0.5) * 3
    with torch.no_grad():
        assert torch.allclose(Arm.tcp(robot, q), robot.tcp(q), atol=1e-12)
        for eager, compiled in zip(Arm.spheres(robot, q), robot.spheres(q)):
            assert torch.allclose(eager, compiled, atol=1e-12)


def test_the_collision_gradient_written_out_is_autograds(planner):
    # guidance/collision.py's value_and_gradient writes its gradient out through the robot's vector-Jacobian
    # product; autograd through the same source's value says what it must be.
    term = planner.sampler.guide.costs.term
    assert term.original_name == "CollisionCost"
    scene = prepared_scene({"spheres": torch.tensor([[0.5, 0.0, 0.2, 0.1], [0.3, 0.3, 0.5, 0.15]],
                                                    dtype=torch.float64)}, 3)
    opts = {"guidance.margin": 0.05, term.weight_key: 1.0}
    generator = torch.Generator().manual_seed(3)
    # Plans that pass through the spheres: the arm reaching around the first one.
    q = torch.tensor([0.0, 0.3, 0.0, -2.0, 0.0, 2.3, 0.8], dtype=torch.float64)
    q = (q + 0.3 * torch.randn(2, 8, 7, generator=generator, dtype=torch.float64)).requires_grad_(True)
    qd = torch.zeros_like(q)
    value, grad_q, grad_qd = CollisionCost.value_and_gradient(term, q, qd, scene, opts)
    assert (value > 0).all(), "the test's plans must touch the spheres"
    compiled_value, compiled_grad_q, _ = term.value_and_gradient(q.detach(), qd, scene, opts)
    assert torch.allclose(value, compiled_value, atol=1e-12) and torch.allclose(grad_q, compiled_grad_q, atol=1e-12)
    # The value as a function of q, by autograd through the arm's kinematics.
    robot_centres = planner.robot.sphere_centres(q.reshape(16, 7))
    distance = scene_distance(robot_centres.reshape(-1, 3), scene)[0].view(16, -1, 2)
    reach = opts["guidance.margin"] + planner.robot.sphere_radii.to(q.dtype).view(1, -1, 1)
    autograd_value = torch.relu(reach - distance).sum([1, 2]).view(2, 8).sum(1)
    assert torch.allclose(autograd_value, value, atol=1e-9)
    (expected,) = torch.autograd.grad(autograd_value.sum(), [q])
    assert torch.allclose(grad_q, expected, atol=1e-8)
    assert torch.equal(grad_qd, torch.zeros_like(qd))
