"""Plans with an exported flowplan planner and nothing but PyTorch, and compares.

usage: check_exported_planner.py PLANNER.pt DIR B SCHEDULE KINDS MODE [KERNELS.so]
Reads DIR/start.bin, DIR/goal.bin (B, D), DIR/noise.bin (B, *noise_shape),
DIR/renoise.bin (B, *renoise_shape) if the planner takes renoise, DIR/<kind>.bin
for every obstacle kind of KINDS (comma-separated, "-" for none; rows of the
documented columns) and DIR/plan.bin, the in-process plan (B, T, D), all float32.
Plans with the same inputs and the guidance schedule SCHEDULE under
torch.no_grad() and, with MODE "inference", under torch.inference_mode(); with
MODE "no_grad" (a user cost, which needs autograd) checks that
torch.inference_mode() ends in the user cost's clear error instead. Requires
every plan within 1e-5 of the in-process one, and checks the documented
attributes and methods. Then, for the flow planner, each guide_at variant
plans alike under both modes (MODE "inference"), and best of 3 returns, per
request, the candidate of least guidance cost as the planner's own guide
scores the candidates planned one by one. A planner saved with flowplan's
native kernels (network, obstacle distances) needs KERNELS.so (libflowplan_kernels) loaded first.
"""
import sys

import torch

COLUMNS = {"spheres": lambda W: W + 1, "boxes": lambda W: 10 if W == 3 else 5,
           "cylinders": lambda W: 9 if W == 3 else 5, "capsules": lambda W: 2 * W + 1}

# The graph executor's optimisations off, as flowplan itself plans and docs/export.md advises: with them on,
# the first calls of every method and setting below profile their graphs, seconds each.
torch._C._set_graph_executor_optimize(False)

path, folder, batch, schedule, kinds, mode = sys.argv[1:7]
batch = int(batch)
if len(sys.argv) > 7:
    torch.ops.load_library(sys.argv[7])
planner = torch.jit.load(path)
T, D, W = planner.horizon, planner.state_dim, planner.workspace_dim
assert len(planner.state_labels) == D, planner.state_labels
assert planner.dt > 0 and planner.format_version == 5, planner.format_version
assert "kind:" in planner.robot_description
assert planner.schedule in ("one_minus_t", "ratio", "rising", "constant")
assert planner.guide_at in ("state", "velocity", "prediction")
assert "guidance.scale" in planner.settings, planner.settings


def read(name, shape):
    return torch.from_file(f"{folder}/{name}", size=int(torch.Size(shape).numel()), dtype=torch.float32).view(shape)


start, goal = read("start.bin", (batch, D)), read("goal.bin", (batch, D))
noise = read("noise.bin", (batch, *planner.noise_shape))
renoise = read("renoise.bin", (batch, *planner.renoise_shape)) if len(planner.renoise_shape) > 0 else None
scene = {}
if kinds != "-":
    for kind in kinds.split(","):
        scene[kind] = read(f"{kind}.bin", (1, COLUMNS[kind](W)))
expected = read("plan.bin", (batch, T, D))


def plan():
    return planner.plan(start, goal, noise, renoise, schedule=schedule, **scene)


with torch.no_grad():
    plans = plan()
difference = (plans - expected).abs().max().item()
assert difference <= 1e-5, f"no_grad: plans differ from the in-process planner by {difference}"
if mode == "inference":
    with torch.inference_mode():
        again = plan()
    assert torch.equal(again, plans), "inference_mode and no_grad plans differ"
else:
    try:
        with torch.inference_mode():
            plan()
        raise SystemExit("a user cost under torch.inference_mode() should fail")
    except torch.jit.Error as error:
        assert "cannot run under torch.inference_mode(); plan under torch.no_grad() instead" in str(error), error
assert plans.shape == (batch, T, D), plans.shape
if planner.conditioning == "inpaint":
    assert torch.equal(plans[:, 0], start) and torch.equal(plans[:, -1], goal)
# The documented helpers.
with torch.no_grad():
    samples = planner.sample(start[0], goal[0], 2, schedule=schedule, **scene)
    assert samples.shape == (2, T, D), samples.shape
    J = planner.num_joints
    spheres = planner.collision_spheres(plans[0, :, :J])
    assert spheres.shape[0] == T and spheres.shape[2] == W + 1, spheres.shape
    assert planner.tcp(plans[:, :, :J]).shape == (batch, T, W)
    clearance = planner.clearance(plans[:, :, :J], **scene)
    assert clearance.shape == (batch, T, sum(len(rows) for rows in scene.values())), clearance.shape

if planner.planner == "flow_matching":
    variants = {"sampler.final_iterations": 2.0, "sampler.final_denoise_time": 0.95, "sampler.prediction_iterations": 2.0,
                "sampler.final_spread": 4.0, "sampler.final_joint_speed_weight": 0.1, "sampler.guide_from": 0.2,
                "sampler.midpoint_iterations": 2.0, "sampler.split_time": 0.6}
    for at in ("state", "velocity", "prediction"):
        with torch.no_grad():
            guided = planner.plan(start, goal, noise, renoise, schedule=schedule, guide_at=at, settings=variants, **scene)
        if mode == "inference":
            with torch.inference_mode():
                again = planner.plan(start, goal, noise, renoise, schedule=schedule, guide_at=at, settings=variants, **scene)
            assert torch.equal(again, guided), f"guide_at {at}: inference_mode and no_grad plans differ"
    N = 3
    generator = torch.Generator().manual_seed(5)
    noises = torch.randn((batch, N, *planner.noise_shape), generator=generator)
    renoises = torch.randn((batch, N, *planner.renoise_shape), generator=generator) if renoise is not None else None
    with torch.no_grad():
        best = planner.plan(start, goal, noises, renoises, schedule=schedule, settings={"guidance.candidates": float(N)}, **scene)
        alone = [planner.plan(start, goal, noises[:, j], None if renoises is None else renoises[:, j], schedule=schedule,
                              **scene) for j in range(N)]
        settings = dict(planner.settings)
        costs = torch.stack([planner.sampler.guide.value(p, scene, settings) for p in alone], 1)
    choice = costs.argmin(1)
    for b in range(batch):
        gap = (best[b] - alone[int(choice[b])][b]).abs().max().item()
        assert gap <= 1e-5, f"best of {N}: request {b} is not its least-cost candidate ({gap})"
print("exported planner ok:", path)
