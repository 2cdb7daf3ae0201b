"""Runs an exported flowplan planner with nothing but torch.

usage: run_exported_planner.py PLANNER.pt DIR B
Reads DIR/start.bin, DIR/goal.bin (B, D), DIR/noise.bin and DIR/renoise.bin (B, T, D) as float32,
writes DIR/plan.bin, and checks the planner's documented attributes and methods.
"""
import sys

import torch

planner = torch.jit.load(sys.argv[1])
folder, batch = sys.argv[2], int(sys.argv[3])
T, D = planner.horizon, planner.state_dim
assert len(planner.state_labels) == D, planner.state_labels
assert planner.dt > 0 and planner.steps > 0 and planner.format_version == 2


def read(name, shape):
    return torch.from_file(f"{folder}/{name}", size=int(torch.Size(shape).numel()), dtype=torch.float32).view(shape)


start, goal, noise = read("start.bin", (batch, D)), read("goal.bin", (batch, D)), read("noise.bin", (batch, T, D))
renoise = read("renoise.bin", (batch, T, D)) if planner.splitting != "none" else None
plan = planner.plan(start, goal, noise, renoise)
assert plan.shape == (batch, T, D), plan.shape
if planner.conditioning == "inpaint":
    assert torch.equal(plan[:, 0], start) and torch.equal(plan[:, -1], goal)
samples = planner.sample(start[0], goal[0], 4)
assert samples.shape == (4, T, D)
plan.contiguous().numpy().tofile(f"{folder}/plan.bin")
