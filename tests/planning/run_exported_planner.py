"""Runs an exported flowplan planner with nothing but torch.

usage: run_exported_planner.py PLANNER.pt DIR B K
Reads DIR/start.bin, DIR/goal.bin (B, D), DIR/noise.bin, DIR/renoise.bin (B, T, D) and
DIR/obstacles.bin (K, W+1) as float32. Plans around the obstacles under
torch.inference_mode() (where autograd cannot run) and under torch.no_grad(),
checks that the two agree and that guidance changed the plan, writes the guided
plan to DIR/plan.bin, and checks the planner's documented attributes and methods.
"""
import sys

import torch

planner = torch.jit.load(sys.argv[1])
folder, batch, num_obstacles = sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
T, D, W = planner.horizon, planner.state_dim, planner.workspace_dim
assert len(planner.state_labels) == D, planner.state_labels
assert planner.dt > 0 and planner.steps > 0 and planner.format_version == 3
assert "kind:" in planner.robot


def read(name, shape):
    return torch.from_file(f"{folder}/{name}", size=int(torch.Size(shape).numel()), dtype=torch.float32).view(shape)


start, goal = read("start.bin", (batch, D)), read("goal.bin", (batch, D))
noise = read("noise.bin", (batch, *planner.noise_shape))
renoise = read("renoise.bin", (batch, *planner.renoise_shape)) if len(planner.renoise_shape) > 0 else None
obstacles = read("obstacles.bin", (num_obstacles, W + 1))
with torch.inference_mode():
    guided = planner.plan(start, goal, noise, renoise, obstacles)
with torch.no_grad():
    again = planner.plan(start, goal, noise, renoise, obstacles)
    unguided = planner.plan(start, goal, noise, renoise)
assert torch.equal(guided, again), "inference_mode and no_grad plans differ"
assert (guided - unguided).abs().max() > 1e-3, "guidance changed nothing"
assert guided.shape == (batch, T, D), guided.shape
if planner.conditioning == "inpaint":
    assert torch.equal(guided[:, 0], start) and torch.equal(guided[:, -1], goal)
samples = planner.sample(start[0], goal[0], 4, obstacles)
assert samples.shape == (4, T, D)
spheres = planner.collision_spheres(guided[0, :, : planner.num_joints])
assert spheres.shape[0] == T and spheres.shape[2] == W + 1
assert planner.tcp(guided[:, :, : planner.num_joints]).shape == (batch, T, W)
guided.contiguous().numpy().tofile(f"{folder}/plan.bin")
