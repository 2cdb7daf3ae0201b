"""Plans motions of an exported Franka planner around a sphere from Python, with flowplan's package, and keeps
the plans whose whole arm stays clear.

    PYTHONPATH=build/python /usr/bin/python3 examples/plan_around_sphere.py [PLANNER.pt]

(default: the shipped reach planner, pretrained/franka_reach_planner.pt). With the package's C++ module the
planner runs flowplan's native kernels; with PyTorch alone, the file's own code (slower, the same plans to
within 1e-2).
"""
import os
import sys

import torch

import flowplan

here = os.path.dirname(os.path.abspath(__file__))
path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "pretrained", "franka_reach_planner.pt")
torch.set_num_threads(2)
planner = flowplan.load_planner(path)                 # every call: no gradients, no profiling runs

start_q = planner.ik(torch.tensor([0.5, -0.3, 0.2]))  # (7,) joints that put the TCP there, gripper down
goal_q = planner.ik(torch.tensor([0.5, 0.3, 0.2]))
start = torch.cat([start_q, torch.zeros(7)])          # (14,) state: positions, then velocities (at rest)
goal = torch.cat([goal_q, torch.zeros(7)])
sphere = torch.tensor([[0.5, 0.0, 0.2, 0.1]])         # (K, 4): centre, radius (m)

torch.manual_seed(0)
plans = planner.sample(start, goal, 16, spheres=sphere)                 # (16, 64, 14)
clearance = planner.clearance(plans[..., :7], spheres=sphere)           # (16, 64, 1) m, whole arm
reached = (planner.tcp(plans[:, -1, :7]) - torch.tensor([0.5, 0.3, 0.2])).norm(dim=-1)  # (16,) m
clear = clearance.amin(dim=(1, 2)) >= 0
print(f"{planner}: {len(plans)} plans of {plans.shape[1]} states, {int(clear.sum())} keep the whole arm clear of "
      f"the sphere; largest distance of the last TCP to the goal {reached.max().item():.2g} m")
sys.exit(0 if clear.sum() >= len(plans) - 2 and reached.max() < 0.03 else 1)
