"""Plans motions of an exported Franka planner around a sphere from Python,
with nothing but PyTorch, and keeps the plans whose whole arm stays clear.

    /usr/bin/python3 examples/plan_around_sphere.py [PLANNER.pt]

(default: the shipped reach planner, pretrained/franka_reach_planner.pt)
"""
import os
import sys

import torch

here = os.path.dirname(os.path.abspath(__file__))
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "pretrained", "franka_reach_planner.pt")
torch.set_num_threads(2)
planner = torch.jit.load(path)

start_q = planner.ik(torch.tensor([0.5, -0.3, 0.2]))  # (7,) joints that put the TCP there, gripper down
goal_q = planner.ik(torch.tensor([0.5, 0.3, 0.2]))
start = torch.cat([start_q, torch.zeros(7)])          # (14,) state: positions, then velocities (at rest)
goal = torch.cat([goal_q, torch.zeros(7)])
sphere = torch.tensor([[0.5, 0.0, 0.2, 0.1]])         # (K, 4): centre, radius (m)

torch.manual_seed(0)
# With the graph executor's optimisations off the first plan is as fast as the next (no profiling runs).
with torch.no_grad(), torch.jit.optimized_execution(False):
    plans = planner.sample(start, goal, 16, spheres=sphere)                # (16, 64, 14)
    clearance = planner.clearance(plans[..., :7], spheres=sphere)           # (16, 64, 1) m, whole arm
    reached = (planner.tcp(plans[:, -1, :7]) - torch.tensor([0.5, 0.3, 0.2])).norm(dim=-1)  # (16,) m
clear = clearance.amin(dim=(1, 2)) >= 0
print(f"{len(plans)} plans of {plans.shape[1]} states: {int(clear.sum())} keep the whole arm clear of the sphere; "
      f"largest distance of the last TCP to the goal {reached.max().item():.2g} m")
sys.exit(0 if clear.any() else 1)
