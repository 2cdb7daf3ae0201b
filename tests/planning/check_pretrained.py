"""Checks the shipped Franka reach planner with nothing but torch, numpy and
yaml, and a forward kinematics written here (modified Denavit-Hartenberg
parameters; the collision spheres placed on its frames from the planner's
robot description), sharing no code with flowplan.

usage: check_pretrained.py PLANNER.pt
The paper's scene: TCP from (0.5, -0.3, 0.2) to (0.5, 0.3, 0.2), a sphere of
radius 0.10 at (0.5, 0, 0.2), 64 plans under torch.no_grad(). Unguided, the
TCP must pass through the sphere in at least 90 % of the plans; guided, at
least 90 % must keep the TCP and every collision sphere clear of it; every
plan's last TCP must be within 3 cm of the goal.
"""
import sys

import numpy as np
import torch
import yaml

DH = [(0, 0.333, 0), (0, 0, -np.pi / 2), (0, 0.316, np.pi / 2), (0.0825, 0, np.pi / 2),
      (-0.0825, 0.384, -np.pi / 2), (0, 0, np.pi / 2), (0.088, 0, np.pi / 2)]


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])


def move_z(d):
    m = np.eye(4)
    m[2, 3] = d
    return m


def frames(q):
    """q (7,) -> frames of link0..link7, hand, left finger, right finger (11, 4, 4)."""
    out = [np.eye(4)]
    for (a, d, alpha), theta in zip(DH, q):
        ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(theta), np.sin(theta)
        out.append(out[-1] @ np.array([[ct, -st, 0, a], [st * ca, ct * ca, -sa, -d * sa],
                                       [st * sa, ct * sa, ca, d * ca], [0, 0, 0, 1]]))
    hand = out[7] @ move_z(0.107) @ rot_z(-np.pi / 4)  # the flange, turned for the Franka Hand
    out += [hand, hand @ move_z(0.0584), hand @ move_z(0.0584) @ rot_z(np.pi)]
    return np.stack(out)


planner = torch.jit.load(sys.argv[1])
robot = yaml.safe_load(planner.robot_description)
links = np.array([s["link"] for s in robot["spheres"]])
local = np.array([s["centre"] + [1.0] for s in robot["spheres"]])  # (S, 4)
radii = np.array([s["radius"] for s in robot["spheres"]])
obstacle, radius = np.array([0.5, 0.0, 0.2]), 0.10
goal_tcp = np.array([0.5, 0.3, 0.2])


def geometry(plans):
    """plans (N, T, 14) -> TCP (N, T, 3), sphere centres (N, T, S, 3)."""
    N, T = plans.shape[:2]
    tcp, centres = np.zeros((N, T, 3)), np.zeros((N, T, len(radii), 3))
    for n in range(N):
        for t in range(T):
            f = frames(plans[n, t, :7])
            tcp[n, t] = (f[7] @ np.array([0, 0, 0.214, 1]))[:3]  # 0.107 to the flange, 0.107 more to the TCP
            centres[n, t] = np.einsum("sij,sj->si", f[links], local)[:, :3]
    return tcp, centres


start_q = planner.ik(torch.tensor([0.5, -0.3, 0.2], dtype=torch.float64)).float()
goal_q = planner.ik(torch.tensor([0.5, 0.3, 0.2], dtype=torch.float64)).float()
start, goal = torch.cat([start_q, torch.zeros(7)]), torch.cat([goal_q, torch.zeros(7)])
sphere = torch.tensor([[0.5, 0.0, 0.2, radius]])
torch.manual_seed(0)
# The executor's optimisations off, as flowplan plans: with them on, the first two calls of a freshly loaded file
# spend most of this check's time profiling (docs/export.md, "The first calls": about 24 s of its 29 here).
with torch.no_grad(), torch.jit.optimized_execution(False):
    unguided = planner.sample(start, goal, 64).double().numpy()
    guided = planner.sample(start, goal, 64, sphere).double().numpy()
    theirs = planner.collision_spheres(torch.from_numpy(guided[:2, :, :7]).float()).double().numpy()

results = {}
for name, plans in (("unguided", unguided), ("guided", guided)):
    tcp, centres = geometry(plans)
    tcp_clear = np.linalg.norm(tcp - obstacle, axis=-1).min(1) - radius                        # (N,)
    arm_clear = (np.linalg.norm(centres - obstacle, axis=-1) - radii).min((1, 2)) - radius     # (N,)
    goal_distance = np.linalg.norm(tcp[:, -1] - goal_tcp, axis=-1)
    results[name] = (tcp_clear, arm_clear, goal_distance)
    print(f"{name}: TCP clear {np.mean(tcp_clear >= 0):.0%}, whole arm clear {np.mean(arm_clear >= 0):.0%}, "
          f"largest last-state goal distance {goal_distance.max():.2e} m")
    if name == "guided":
        _, mine = tcp, centres
        assert np.abs(mine[:2] - theirs[..., :3]).max() < 1e-4, np.abs(mine[:2] - theirs[..., :3]).max()
        assert np.allclose(theirs[0, 0, :, 3], radii, atol=1e-6)

tcp_clear, arm_clear, goal_distance = results["unguided"]
assert np.mean(tcp_clear < 0) >= 0.9, "unguided plans should pass through the sphere"
tcp_clear, arm_clear, goal_distance = results["guided"]
assert np.mean((tcp_clear >= 0) & (arm_clear >= 0)) >= 0.9, np.mean((tcp_clear >= 0) & (arm_clear >= 0))
for plans in (unguided, guided):
    assert np.linalg.norm(geometry(plans[:, -1:])[0][:, 0] - goal_tcp, axis=-1).max() < 0.03
print("pretrained planner ok")
