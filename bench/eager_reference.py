#!/usr/bin/env python3
"""flowplan's flow planner and trainer written in plain PyTorch eager mode.

The speed reference that bench/speed_bench.cc sets beside the C++ planner and
trainer: the UNet1D (models/unet1d.cc) as torch.nn modules holding a
checkpoint's EMA weights, the min-max normalizer (models/normalizer.py), the
Franka's forward kinematics and collision spheres from the checkpoint's robot
description (kinematics/arm.py), signed distances to spheres, boxes,
cylinders and capsules (geometry/), the collision and smoothness guidance
costs (guidance/) with their gradient taken by autograd, the Euler sampler
with inpainting, guidance and midpoint splitting (planning/flow_sampler.py)
and a flow-matching training step with AdamW (objectives/flow_matching.cc,
objectives/trajectory_loss.cc). The files named are what each part
reimplements, not what it reads.
Nothing here is imported from flowplan or read from the exported planner's
code: the exported planner only serves as the reference the results are
checked against (and its ik() gives the checks' start and goal joints).

usage: eager_reference.py --checkpoint CKPT --export PLANNER.pt --threads THREADS
                          --json OUT.json [--repeats R] [--kernels LIB]
                          [--mpd-checkpoint CKPT --mpd-export PLANNER.pt] [--check-only]

Checks (max abs differences, written to the JSON under "checks"):
  network              the network's velocity at a fixed input against the export's velocity()
  unguided_plan        a 10-step unguided plan at B = 1 against the export's plan
  unguided_split_plan  the same with midpoint splitting
  guided_plan          guided around one sphere, without splitting
  guided_split_plan    guided around one sphere, with splitting
  guided_shapes_split_plan  guided around a box, a cylinder and a capsule, with splitting
  mpd_unguided_plan    with --mpd-*: MPD's DDPM plan at B = 1 against its export's plan()
  mpd_guided_plan      the same, guided around one sphere
The export computes a plan with the splitting it was exported with
(`splitting` attribute); the other variant is composed from the export's
normalize / denormalize methods and its sampler's integrate() as its plan()
composes them. The script exits with status 1 if `network`, `unguided_plan`,
`unguided_split_plan` or `mpd_unguided_plan` exceeds 1e-4, or a guided plan
1e-3. Guided plans take
the cost gradient by autograd here and by written-out formulas in the export,
so they agree to rounding, amplified by the sampler. --check-only skips the
timings (the test suite runs it so on a tiny network).

Timings (median ms over R repeats after warm-up, the same work as
bench/speed_bench.cc): forward_b1, forward_b64 (the network under
torch.inference_mode()), train_step_b256 and train_step_b256_bf16 (loss,
backward and AdamW step on a random normalized batch of 256 trajectories; the
second with the loss under bf16 autocast), plan_b1 (10 Euler steps,
unguided, under torch.inference_mode()), plan_guided_split_b1 (guided around
one sphere, with splitting; the network under torch.no_grad(), guidance with
autograd), plan_guided_split_b1_8 and plan_guided_split_b1_shelf (the same
around eight spheres, and among the two boxes and the cylinder of
configs/scenes/franka_shelf.yaml), plan_guided_split_b64 and
plan_guided_split_b64_8 (64 plans in one call around one and eight spheres),
with --mpd-*: mpd_guided_b64 and mpd_guided_b64_8 (MPD's 64 guided plans in
one call, the same scenes).
Every forward and plan timing is also taken with the network under bf16 CPU
autocast (key + "_bf16"): the network's convolutions and linear layers in
bfloat16, its GroupNorm and Mish in float32 (as under
train.precision=bf16), its velocity returned as float32; the sampler and
the guidance stay float32, as a user wrapping the network call in
torch.autocast would have them. flops_b1 is the multiply-add count x 2 of the
convolutions and linear layers in one forward pass at B = 1.

Shapes: B trajectories, T states per trajectory, D state dimensions, J joints,
L links, S collision spheres, K obstacles, W = 3 workspace dimensions.
"""
import argparse
import json
import math
import os
import statistics
import sys
import time

import torch
import torch.nn as nn
import torch.nn.functional as F
import yaml

TOLERANCE = 1e-4  # max abs difference allowed for the network and the unguided plans
GUIDED_TOLERANCE = 1e-3  # for guided plans: autograd here, written-out gradients there, amplified by the sampler
# The shapes of the B = 1 "shelf" timings (two boxes and a cylinder), as bench/speed_bench.cc plans among them.
SHELF_SCENE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "configs", "scenes", "franka_shelf.yaml")

# The C++ defaults (models/unet1d.h, guidance/guide.h) of keys a config may lack.
UNET_DEFAULTS = {"down_dims": [32, 64, 128, 256], "kernel_size": 5, "groups": 8, "time_embed_dim": 32,
                 "time_scale": 1.0}
DDPM_DEFAULTS = {"steps": 25, "schedule": "exponential", "beta_start": 1e-4, "beta_end": 1.0, "beta_max": 0.999}
DDPM_SAMPLER_DEFAULTS = {"guide_on": "posterior_mean", "guide_fraction": 0.25, "guide_iterations": 5, "extra_steps": 5,
                         "noise_scale": 1.0}
GUIDANCE_DEFAULTS = {"scale": 1.0, "schedule": "one_minus_t", "clip": 0.0, "collision_weight": 0.1,
                     "smoothness_weight": 1e-6, "margin": 0.05, "smoothness_sigma": 1.0}


# ----------------------------------------------------------------------------
# Network: the temporal UNet of models/unet1d.cc. Attribute names follow the
# C++ module names so that the checkpoint's "ema.*" tensors load by name.
# ----------------------------------------------------------------------------

class ConvBlock(nn.Module):
    """Conv1d(k) -> GroupNorm -> Mish; (B, in, T) -> (B, out, T)."""

    def __init__(self, channels_in, channels_out, kernel, groups):
        super().__init__()
        self.conv = nn.Conv1d(channels_in, channels_out, kernel, padding=kernel // 2)
        self.norm = nn.GroupNorm(groups, channels_out)

    def forward(self, x):
        return F.mish(self.norm(self.conv(x).float()))   # float(): see WidenBfloat16 in models/precision.h


class ResidualBlock(nn.Module):
    """Two ConvBlocks with FiLM from the condition between them, plus a 1x1
    residual convolution when the width changes.
    x (B, in, T), cond (B, C) -> (B, out, T)."""

    def __init__(self, channels_in, channels_out, cond_dim, kernel, groups):
        super().__init__()
        self.out = channels_out
        self.block0 = ConvBlock(channels_in, channels_out, kernel, groups)
        self.block1 = ConvBlock(channels_out, channels_out, kernel, groups)
        self.film = nn.Linear(cond_dim, 2 * channels_out)
        self.residual = nn.Conv1d(channels_in, channels_out, 1) if channels_in != channels_out else None

    def forward(self, x, cond):
        h = self.block0(x)                              # (B, out, T)
        film = self.film(F.mish(cond.float())).unsqueeze(-1)    # (B, 2 out, 1): scale, then shift
        h = film[:, 0:self.out] * h + film[:, self.out:2 * self.out]
        h = self.block1(h)
        return h + (self.residual(x) if self.residual is not None else x)


class UNet1D(nn.Module):
    """Velocity network: x (B, T, D) normalized, t (B,) flow time, cond (B, C)
    or None -> (B, T, D).

    Levels i = 0 .. len(down_dims) - 1 of widths down_dims[i]; T halves after every level but
    the last. The up path has len(down_dims) - 1 levels, each concatenating the skip of the
    matching down level (deepest first; the shallowest skip is not used) and
    doubling T with a transposed convolution."""

    def __init__(self, state_dim, cond_dim, down_dims, kernel_size, groups, time_embed_dim, time_scale):
        super().__init__()
        self.levels = len(down_dims)
        self.cond_dim = cond_dim
        self.time_scale = time_scale
        e, half = time_embed_dim, time_embed_dim // 2
        # Sinusoidal frequencies exp(-k ln(10000) / (half - 1)), k = 0 .. half-1; (half,)
        self.register_buffer(
            "frequencies", torch.exp(torch.arange(half, dtype=torch.float32) * (-math.log(10000.0) / (half - 1))))
        self.time_in = nn.Linear(e, 4 * e)
        self.time_out = nn.Linear(4 * e, e)
        cond = e + cond_dim
        k, g = kernel_size, groups
        dims = [state_dim] + list(down_dims)
        for i in range(self.levels):
            setattr(self, f"down{i}_block0", ResidualBlock(dims[i], dims[i + 1], cond, k, g))
            setattr(self, f"down{i}_block1", ResidualBlock(dims[i + 1], dims[i + 1], cond, k, g))
            if i + 1 < self.levels:
                setattr(self, f"down{i}_down", nn.Conv1d(dims[i + 1], dims[i + 1], 3, stride=2, padding=1))
        self.mid0 = ResidualBlock(dims[-1], dims[-1], cond, k, g)
        self.mid1 = ResidualBlock(dims[-1], dims[-1], cond, k, g)
        for u, i in enumerate(range(self.levels - 1, 0, -1)):  # up level u maps dims[i+1] (x2) -> dims[i]
            setattr(self, f"up{u}_block0", ResidualBlock(2 * dims[i + 1], dims[i], cond, k, g))
            setattr(self, f"up{u}_block1", ResidualBlock(dims[i], dims[i], cond, k, g))
            setattr(self, f"up{u}_up", nn.ConvTranspose1d(dims[i], dims[i], 4, stride=2, padding=1))
        self.final_block = ConvBlock(dims[1], dims[1], k, g)
        self.final_conv = nn.Conv1d(dims[1], state_dim, 1)

    def time_feature(self, t):
        """t (B,) -> (B, e)."""
        angles = (t * self.time_scale).unsqueeze(-1) * self.frequencies.unsqueeze(0)  # (B, half)
        embedding = torch.cat([torch.sin(angles), torch.cos(angles)], -1)            # (B, e)
        return self.time_out(F.mish(self.time_in(embedding).float()))

    def forward(self, x, t, cond=None):
        feature = self.time_feature(t)                                   # (B, e)
        if self.cond_dim > 0:
            feature = torch.cat([feature, cond], -1)                     # (B, e + C)
        h = x.transpose(1, 2)                                            # (B, D, T)
        skips = []
        for i in range(self.levels):
            h = getattr(self, f"down{i}_block0")(h, feature)
            h = getattr(self, f"down{i}_block1")(h, feature)
            skips.append(h)
            if i + 1 < self.levels:
                h = getattr(self, f"down{i}_down")(h)                    # T -> T/2
        h = self.mid0(h, feature)
        h = self.mid1(h, feature)
        for u in range(self.levels - 1):
            h = torch.cat([h, skips.pop()], 1)
            h = getattr(self, f"up{u}_block0")(h, feature)
            h = getattr(self, f"up{u}_block1")(h, feature)
            h = getattr(self, f"up{u}_up")(h)                            # T -> 2T
        h = self.final_conv(self.final_block(h)).float()                 # (B, D, T)
        return h.transpose(1, 2)                                         # (B, T, D)


class Bf16Autocast(nn.Module):
    """net under bf16 CPU autocast: the same call, its output float32."""

    def __init__(self, net):
        super().__init__()
        self.net = net

    def forward(self, x, t, cond=None):
        with torch.autocast("cpu", dtype=torch.bfloat16):
            return self.net(x, t, cond).float()


def count_flops(net, x, t, cond=None):
    """Multiply-adds x 2 of every convolution and linear layer in net(x, t, cond)."""
    total = 0

    def hook(module, inputs, output):
        nonlocal total
        if isinstance(module, nn.Linear):
            total += 2 * output.numel() * module.in_features
        elif isinstance(module, nn.ConvTranspose1d):  # every input element meets out_channels x kernel weights
            total += 2 * inputs[0].numel() * module.out_channels * module.kernel_size[0] // module.groups
        elif isinstance(module, nn.Conv1d):
            total += 2 * output.numel() * module.in_channels * module.kernel_size[0] // module.groups

    handles = [m.register_forward_hook(hook) for m in net.modules()
               if isinstance(m, (nn.Linear, nn.Conv1d, nn.ConvTranspose1d))]
    with torch.inference_mode():
        net(x, t, cond)
    for handle in handles:
        handle.remove()
    return total


# ----------------------------------------------------------------------------
# Normalizer and conditioning
# ----------------------------------------------------------------------------

class Normalizer:
    """Per-dimension min-max map of raw states to [-1, 1]; lo, hi (D,)."""

    def __init__(self, lo, hi):
        self.lo = lo.float().contiguous()
        self.hi = hi.float().contiguous()

    def normalize(self, x):                       # (..., D) -> (..., D)
        return (x - self.lo) / (self.hi - self.lo) * 2.0 - 1.0

    def denormalize_unclamped(self, x):           # (..., D) -> (..., D)
        return (x + 1.0) * 0.5 * (self.hi - self.lo) + self.lo

    def denormalize(self, x):                     # clamps to [-1, 1] first
        return self.denormalize_unclamped(torch.clamp(x, -1.0, 1.0))


def inpaint(x, start, goal):
    """x (B, T, D) with state 0 := start (B, D) and state T-1 := goal (B, D), out of place."""
    return torch.cat([start.unsqueeze(1), x[:, 1:-1], goal.unsqueeze(1)], 1)


# ----------------------------------------------------------------------------
# Robot: forward kinematics of a tree of hinge joints and its collision spheres
# ----------------------------------------------------------------------------

def pose(pos, quat):
    """4x4 float64 pose from a position (3,) and a quaternion (w, x, y, z)."""
    n = math.sqrt(sum(v * v for v in quat))
    w, x, y, z = (v / n for v in quat)
    return torch.tensor([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y), pos[0]],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x), pos[1]],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y), pos[2]],
                         [0.0, 0.0, 0.0, 1.0]], dtype=torch.float64)


def cross_matrix(axis):
    """[axis]x of the unit axis, padded to 4x4, float64."""
    n = math.sqrt(sum(v * v for v in axis))
    x, y, z = (v / n for v in axis)
    return torch.tensor([[0.0, -z, y, 0.0], [z, 0.0, -x, 0.0], [-y, x, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]],
                        dtype=torch.float64)


class ArmKinematics(nn.Module):
    """Differentiable forward kinematics of an arm described by flowplan's
    robot YAML: X_link = X_parent . Trans(pos) Rot(quat) . Rot(axis, q[joint]),
    the hinge rotation by Rodrigues' formula. Constants are built in float64
    and stored in float32."""

    def __init__(self, robot):
        super().__init__()
        if robot["kind"] != "arm":
            raise ValueError(f"robot {robot['name']!r} is not an arm")
        links = robot["links"]
        self.num_joints = robot["num_joints"]
        self.parents = [link["parent"] for link in links]
        self.joints = [link["joint"] for link in links]
        cross = [cross_matrix(link["axis"]) for link in links]
        self.register_buffer("fixed", torch.stack([pose(l["pos"], l["quat"]) for l in links]).float())  # (links, 4, 4)
        self.register_buffer("cross", torch.stack(cross).float())                                       # (links, 4, 4)
        self.register_buffer("cross_sq", torch.stack([k @ k for k in cross]).float())                   # (links, 4, 4)
        self.register_buffer("sphere_links", torch.tensor([s["link"] for s in robot["spheres"]]))        # (S,)
        self.register_buffer("sphere_local", torch.tensor([s["centre"] for s in robot["spheres"]],
                                                          dtype=torch.float64).float())                  # (S, 3)
        self.register_buffer("sphere_radii", torch.tensor([s["radius"] for s in robot["spheres"]],
                                                          dtype=torch.float64).float())                  # (S,)

    def link_frames(self, q):
        """q (M, J) rad -> link poses in the world (M, links, 4, 4)."""
        identity = torch.eye(4, dtype=q.dtype)
        sin_q = torch.sin(q).unsqueeze(-1).unsqueeze(-1)             # (M, J, 1, 1)
        one_minus_cos = (1.0 - torch.cos(q)).unsqueeze(-1).unsqueeze(-1)
        frames = []
        for l, (parent, j) in enumerate(zip(self.parents, self.joints)):
            if j >= 0:
                rotation = identity + sin_q[:, j] * self.cross[l] + one_minus_cos[:, j] * self.cross_sq[l]  # (M, 4, 4)
                local = torch.matmul(self.fixed[l], rotation)
            else:
                local = self.fixed[l].expand(q.size(0), 4, 4)
            frames.append(torch.matmul(frames[parent], local) if parent >= 0 else local)
        return torch.stack(frames, 1)

    def sphere_centres(self, q):
        """q (M, J) -> collision sphere centres (M, S, 3) in the world."""
        carriers = self.link_frames(q).index_select(1, self.sphere_links)  # (M, S, 4, 4)
        return torch.matmul(carriers[:, :, 0:3, 0:3], self.sphere_local.unsqueeze(-1)).squeeze(-1) + carriers[:, :, 0:3, 3]


# ----------------------------------------------------------------------------
# Guidance costs (values; their gradients come from autograd)
# ----------------------------------------------------------------------------

def quaternion_rotation(quaternion):
    """(K, 4) quaternions (w, x, y, z), any norm -> (K, 3, 3): R = (w^2 - |v|^2) I + 2 v v^T + 2 w [v]x."""
    q = quaternion / torch.linalg.vector_norm(quaternion, dim=-1, keepdim=True)
    w, v = q[:, 0], q[:, 1:]
    cross = torch.zeros(len(q), 3, 3, dtype=q.dtype)
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    cross = cross - cross.transpose(1, 2)
    eye = torch.eye(3, dtype=q.dtype).expand(len(q), 3, 3)
    return ((w * w - (v * v).sum(-1)).view(-1, 1, 1) * eye + 2.0 * v.unsqueeze(2) * v.unsqueeze(1)
            + 2.0 * w.view(-1, 1, 1) * cross)


def in_frame(points, centres, rotations):
    """points (M, 3) in the frames of K shapes: (M, K, 3) = R_k^T (p - c_k)."""
    return torch.einsum("kji,nkj->nki", rotations, points.unsqueeze(1) - centres.unsqueeze(0))


def rectangle_distance(p, half):
    """Signed distance of points p (..., n) to the axis-aligned box [-half, half] (..., n):
    to the closest point outside; minus the distance to the nearest face inside."""
    closest = torch.maximum(torch.minimum(p, half), -half)
    outside = torch.linalg.vector_norm(p - closest, dim=-1)
    inside = (half - p.abs()).min(-1).values
    return torch.where(outside > 0, outside, -inside)


def scene_distance(points, scene):
    """Signed distance (M, K) of points (M, 3) to every obstacle of a scene {kind: rows}."""
    columns = []
    for kind, rows in scene.items():
        rows = rows.to(points.dtype)
        if kind == "spheres":
            columns.append(torch.cdist(points, rows[:, 0:3]) - rows[:, 3])
        elif kind == "boxes":
            local = in_frame(points, rows[:, 0:3], quaternion_rotation(rows[:, 6:10]))
            columns.append(rectangle_distance(local, 0.5 * rows[:, 3:6].unsqueeze(0)))
        elif kind == "cylinders":
            local = in_frame(points, rows[:, 0:3], quaternion_rotation(rows[:, 5:9]))
            side = torch.stack([torch.linalg.vector_norm(local[..., 0:2], dim=-1), local[..., 2]], -1)
            half = torch.stack([rows[:, 3], 0.5 * rows[:, 4]], -1).unsqueeze(0)
            columns.append(rectangle_distance(side, half))
        elif kind == "capsules":
            a, b = rows[:, 0:3], rows[:, 3:6]
            ab = b - a
            t = (((points.unsqueeze(1) - a) * ab).sum(-1) / (ab * ab).sum(-1).clamp_min(1e-300)).clamp(0, 1)
            nearest = a + t.unsqueeze(-1) * ab
            columns.append(torch.linalg.vector_norm(points.unsqueeze(1) - nearest, dim=-1) - rows[:, 6])
        else:
            raise ValueError(f"unknown obstacle kind {kind}")
    return torch.cat(columns, 1) if columns else torch.zeros(len(points), 0, dtype=points.dtype)


class CollisionCost:
    """Sum over states, spheres s and obstacles k of relu(margin + r_s - d_k(c_s)),
    d_k the signed distance to obstacle k. x (B, T, D) raw, scene {kind: rows} -> (B,)."""

    def __init__(self, kinematics, margin):
        self.kinematics = kinematics
        self.margin = margin

    def __call__(self, x, scene):
        B, T = x.shape[:2]
        J = self.kinematics.num_joints
        q = x[:, :, 0:J].reshape(B * T, J)                                    # (M, J), M = B T
        centres = self.kinematics.sphere_centres(q)                           # (M, S, 3)
        M, S = centres.shape[:2]
        distance = scene_distance(centres.reshape(M * S, 3), scene).view(M, S, -1)  # (M, S, K)
        penetration = torch.relu(self.margin + self.kinematics.sphere_radii.view(1, -1, 1) - distance)
        return penetration.sum([1, 2]).view(B, T).sum(1)


class SmoothnessCost:
    """The constant-velocity GP prior on [q, q_dot]: with e_q = q_{i+1} - q_i - dt v_i
    and e_v = v_{i+1} - v_i, C = sum a e_q^2 + 2 b e_q e_v + c e_v^2 with
    a = 12/(dt^3 s^2), b = -6/(dt^2 s^2), c = 4/(dt s^2). x (B, T, D) raw -> (B,)."""

    def __init__(self, num_joints, dt, sigma):
        s2 = sigma * sigma
        self.J, self.dt = num_joints, dt
        self.a, self.b, self.c = 12.0 / (dt * dt * dt * s2), -6.0 / (dt * dt * s2), 4.0 / (dt * s2)

    def __call__(self, x, scene):
        J = self.J
        q, v = x[:, :, 0:J], x[:, :, J:2 * J]                     # (B, T, J) each
        e_q = q[:, 1:] - q[:, :-1] - self.dt * v[:, :-1]           # (B, T-1, J)
        e_v = v[:, 1:] - v[:, :-1]
        return (self.a * e_q * e_q + 2.0 * self.b * e_q * e_v + self.c * e_v * e_v).sum([1, 2])


class JointSpeedCost:
    """The joint-speed hinge: sum over steps and joints of relu(|q_{i+1} - q_i| / (dt v_j) - ratio)^2, v_j the
    joint's velocity limit. x (B, T, D) raw -> (B,)."""

    def __init__(self, velocity_limit, num_joints, dt, ratio):
        self.step_limit = torch.tensor(velocity_limit, dtype=torch.float64).float() * dt  # (J,)
        self.J, self.ratio = num_joints, ratio

    def __call__(self, x, scene):
        q = x[:, :, 0:self.J]
        excess = torch.relu((q[:, 1:] - q[:, :-1]).abs() / self.step_limit - self.ratio)  # (B, T-1, J)
        return (excess * excess).sum([1, 2])


def spread_by_inversion(T, length):
    """(T, T): (I + l^2 L)^-1 on the T - 2 interior states (L = tridiag(-1, 2, -1)), scaled to a largest diagonal
    entry of 1, zero on the end states; the end-game's covariant step, by matrix inversion."""
    n = T - 2
    eye = torch.eye(n, dtype=torch.float64)
    laplacian = 2.0 * eye - torch.diag(torch.ones(n - 1, dtype=torch.float64), 1) \
        - torch.diag(torch.ones(n - 1, dtype=torch.float64), -1)
    inverse = torch.linalg.inv(eye + length * length * laplacian)
    spread = torch.zeros(T, T, dtype=torch.float64)
    spread[1:T - 1, 1:T - 1] = inverse / inverse.diagonal().max()
    return spread.float()


SCHEDULES = {
    "one_minus_t": lambda t: 1.0 - t,
    "ratio": lambda t: (1.0 - t) / max(t, 1e-3),
    "rising": lambda t: t,
}


class Guide:
    """One guidance step on normalized trajectories x (B, T, D):
    x - scale b_t sum_k w_k clip(grad C_k(denormalize_unclamped(x))) (hi - lo)/2,
    clip() capping each term's raw gradient at each state to norm `clip`."""

    def __init__(self, settings, kinematics, dt, normalizer, velocity_limit):
        self.normalizer = normalizer
        self.schedule = SCHEDULES[settings["schedule"]]
        self.clip = float(settings["clip"])
        self.terms = [(float(settings["collision_weight"]), CollisionCost(kinematics, float(settings["margin"]))),
                      (float(settings["smoothness_weight"]),
                       SmoothnessCost(kinematics.num_joints, dt, float(settings["smoothness_sigma"])))]
        self.speed = JointSpeedCost(velocity_limit, kinematics.num_joints, dt,
                                    float(settings.get("joint_speed_ratio", 1.0)))
        self.speed_weight = float(settings.get("joint_speed_weight", 0.0))

    def gradient(self, x_n, scene, extra_speed_weight=0.0):
        """(B, T, D) normalized -> (B, T, D), the weighted clipped gradient in normalized units; the joint-speed
        hinge's weight raised by extra_speed_weight (the end-game's)."""
        with torch.enable_grad():
            raw = self.normalizer.denormalize_unclamped(x_n.detach()).requires_grad_(True)  # (B, T, D)
            gradient = torch.zeros_like(x_n)
            for weight, cost in self.terms + [(self.speed_weight + extra_speed_weight, self.speed)]:
                if weight == 0.0:
                    continue
                part, = torch.autograd.grad(cost(raw, scene).sum(), raw)  # (B, T, D) raw units
                if self.clip > 0.0:
                    part = part / (torch.linalg.vector_norm(part, dim=-1, keepdim=True).clamp_min(self.clip) / self.clip)
                gradient = gradient + weight * part
        return gradient * (0.5 * (self.normalizer.hi - self.normalizer.lo))

    def step(self, x_n, t, scene, scale):
        return x_n - (scale * self.schedule(t)) * self.gradient(x_n, scene)


# ----------------------------------------------------------------------------
# Planner: Euler steps with inpainting, guidance and midpoint splitting
# ----------------------------------------------------------------------------

class FlowPlanner:
    def __init__(self, net, normalizer, conditioning, steps, guide, final_iterations=0, final_spread=0.0,
                 final_speed_weight=0.0):
        self.net = net
        self.normalizer = normalizer
        self.inpaint = conditioning == "inpaint"
        self.steps = steps
        self.split_steps = max(1, steps // 2)
        self.guide = guide
        self.final_iterations = final_iterations  # the end-game: gradient steps on each stage's finished plan
        self.final_spread = final_spread  # > 0: each step's push spread over the neighbours (covariant step)
        self.final_speed_weight = final_speed_weight  # added to the joint-speed hinge's weight in the end-game

    def integrate(self, x, s, g, t0, steps, scene, scale):
        """Euler from flow time t0 to 1: x (B, T', D) normalized, boundaries s, g (B, D);
        guided after every step when a scene {kind: rows} is given."""
        cond = None if self.inpaint else torch.cat([s, g], -1)  # (B, 2D) under direct conditioning
        if self.inpaint:
            x = inpaint(x, s, g)
        h = (1.0 - t0) / steps
        for i in range(steps):
            t = torch.full([x.size(0)], t0 + i * h, dtype=x.dtype)
            x = x + h * self.net(inpaint(x, s, g) if self.inpaint else x, t, cond)
            if scene is not None:
                x = self.guide.step(x, t0 + (i + 1) * h, scene, scale)
            if self.inpaint:
                x = inpaint(x, s, g)
        spread = spread_by_inversion(x.size(1), self.final_spread) if self.final_spread > 0.0 else None
        for _ in range(self.final_iterations if scene is not None else 0):
            push = self.guide.gradient(x, scene, self.final_speed_weight)  # (B, T', D)
            if spread is not None:
                push = torch.einsum("ij,bjd->bid", spread, push)
            x = x - scale * push  # x <- x - s M g(x), no schedule factor
            if self.inpaint:
                x = inpaint(x, s, g)
        return x

    def plan(self, start, goal, noise, renoise=None, scene=None, scale=0.0, split=False):
        """start, goal (B, D) raw; noise, renoise (B, T, D) standard normal; scene {kind: (K, columns)}
        -> (B, T, D) raw plans. Unguided without obstacles or at scale 0."""
        guided = ({kind: rows.float() for kind, rows in scene.items()}
                  if scene and scale != 0.0 and sum(len(r) for r in scene.values()) > 0 else None)
        start, goal = start.float(), goal.float()
        s, g = self.normalizer.normalize(start), self.normalizer.normalize(goal)
        x = self.integrate(noise.float(), s, g, 0.0, self.steps, guided, scale)
        if split:
            # Re-noise to t = 0.5, cut into halves that take the states beside the
            # middle as their missing boundaries, refine both from t = 0.5 to 1.
            B, T = x.shape[:2]
            half = T // 2
            before_mid, after_mid = x[:, half - 1], x[:, half]                   # (B, D) each
            x = 0.5 * renoise.float() + 0.5 * x
            halves = torch.cat([x[:, 0:half], x[:, half:T]], 0)                  # (2B, T/2, D)
            refined = self.integrate(halves, torch.cat([s, after_mid], 0), torch.cat([before_mid, g], 0),
                                     0.5, self.split_steps, guided, scale)
            x = torch.cat([refined[0:B], refined[B:2 * B]], 1)                   # (B, T, D)
        plan = self.normalizer.denormalize(x)
        return inpaint(plan, start, goal) if self.inpaint else plan


class DdpmPlanner:
    """Motion Planning Diffusion's sampler: `steps` ancestral DDPM steps k = N-1 .. 0 of an epsilon-predicting
    network, guided in the last ceil(guide_fraction N) steps by guide_iterations gradient steps on the posterior
    mean before the step's noise, then extra_steps noise-free guided steps at k = 0. The schedule (objective.ddpm):
    beta_k exponential, beta_start exp(a x_k) with x = linspace(0, N, N) and a = ln(beta_end / beta_start) / N, or
    linear, linspace(beta_start, beta_end, N); clipped at beta_max; alpha_bar_k = prod_{i <= k} (1 - beta_i)."""

    def __init__(self, net, normalizer, conditioning, schedule, sampler, guide):
        self.net = net
        self.normalizer = normalizer
        self.inpaint = conditioning == "inpaint"
        self.guide = guide
        n = int(schedule["steps"])
        x = torch.linspace(0.0, float(n), n, dtype=torch.float64)
        if schedule["schedule"] == "exponential":
            a = math.log(schedule["beta_end"] / schedule["beta_start"]) / n
            betas = schedule["beta_start"] * torch.exp(a * x)
        elif schedule["schedule"] == "linear":
            betas = torch.linspace(schedule["beta_start"], schedule["beta_end"], n, dtype=torch.float64)
        else:
            raise ValueError(f"objective.ddpm.schedule {schedule['schedule']!r}: expected exponential or linear")
        betas = betas.clamp(max=schedule["beta_max"])                         # (N,) float64
        alpha_bars = torch.cumprod(1.0 - betas, 0)
        before = torch.cat([torch.ones(1, dtype=torch.float64), alpha_bars[:-1]])
        # The posterior q(x_{k-1} | x_k, x0): mean = mean_x0 x0 + mean_x x_k, std noise_std; x0 from x_k and eps.
        self.x0_from_x = (1.0 / alpha_bars.sqrt()).tolist()
        self.x0_from_eps = (1.0 / alpha_bars - 1.0).sqrt().tolist()
        self.mean_x0 = (betas * before.sqrt() / (1.0 - alpha_bars)).tolist()
        self.mean_x = ((1.0 - before) * (1.0 - betas).sqrt() / (1.0 - alpha_bars)).tolist()
        self.noise_std = (betas * (1.0 - before) / (1.0 - alpha_bars)).sqrt().tolist()
        self.steps = n
        if sampler["guide_on"] != "posterior_mean":
            raise ValueError(f"sampler.ddpm.guide_on {sampler['guide_on']!r}: only posterior_mean is written here")
        self.guided_steps = math.ceil(float(sampler["guide_fraction"]) * n - 1e-9)
        self.iterations = int(sampler["guide_iterations"])
        self.extra_steps = int(sampler["extra_steps"])
        self.noise_scale = float(sampler["noise_scale"])

    def conditioned(self, x, s, g):
        return inpaint(x, s, g) if self.inpaint else x

    def denoise(self, x, k, s, g, scene, scale):
        """The posterior mean (B, T, D) of step k from x (B, T, D) normalized, guided when a scene is given."""
        t = torch.full([x.size(0)], float(k), dtype=x.dtype)
        eps = self.net(x, t, None if self.inpaint else torch.cat([s, g], -1))
        x0 = torch.clamp(self.x0_from_x[k] * x - self.x0_from_eps[k] * eps, -1.0, 1.0)
        mean = self.mean_x0[k] * x0 + self.mean_x[k] * x
        for _ in range(self.iterations if scene is not None else 0):
            mean = self.conditioned(mean - scale * self.guide.gradient(mean, scene), s, g)
        return mean

    def plan(self, start, goal, noise, renoise, scene=None, scale=0.0):
        """start, goal (B, D) raw; noise (B, T, D), renoise (B, N - 1, T, D) standard normal; scene {kind: rows}
        -> (B, T, D) raw plans. Unguided without obstacles or at scale 0."""
        guided = ({kind: rows.float() for kind, rows in scene.items()}
                  if scene and scale != 0.0 and sum(len(r) for r in scene.values()) > 0 else None)
        start, goal = start.float(), goal.float()
        s, g = self.normalizer.normalize(start), self.normalizer.normalize(goal)
        x = self.conditioned(noise.float(), s, g)
        for j in range(self.steps):
            k = self.steps - 1 - j
            x = self.denoise(x, k, s, g, guided if k < self.guided_steps else None, scale)
            if k > 0:
                x = x + (self.noise_scale * self.noise_std[k]) * renoise[:, j].float()
            x = self.conditioned(x, s, g)
        for _ in range(self.extra_steps):
            x = self.conditioned(self.denoise(x, 0, s, g, guided, scale), s, g)
        plan = self.normalizer.denormalize(x)
        return inpaint(plan, start, goal) if self.inpaint else plan


# ----------------------------------------------------------------------------
# Training step: conditional flow matching on the OT path, AdamW
# ----------------------------------------------------------------------------

def flow_matching_loss(net, x1, conditioning):
    """x1 (B, T, D) normalized data -> scalar loss. x0 ~ N(0, I), t ~ U[0, 1),
    x_t = t x1 + (1 - t) x0, target x1 - x0; under inpainting x_t's ends are
    x1's and the loss covers the interior states only."""
    x0 = torch.randn_like(x1)
    t = torch.rand(x1.size(0))
    tb = t.view(-1, 1, 1)
    xt = tb * x1 + (1.0 - tb) * x0
    target = x1 - x0
    start, goal = x1[:, 0], x1[:, -1]
    if conditioning == "inpaint":
        output = net(inpaint(xt, start, goal), t)
        return F.mse_loss(output[:, 1:-1], target[:, 1:-1])
    return F.mse_loss(net(xt, t, torch.cat([start, goal], -1)), target)


def train_step(net, optimizer, x1, conditioning):
    optimizer.zero_grad(set_to_none=True)
    loss = flow_matching_loss(net, x1, conditioning)
    loss.backward()
    optimizer.step()
    return loss


# ----------------------------------------------------------------------------
# Loading, checks, timings
# ----------------------------------------------------------------------------

def load_network(checkpoint, prefix, config, state_dim, cond_dim):
    """The UNet1D of the checkpoint's config with the tensors named prefix + '.*'."""
    unet = dict(UNET_DEFAULTS, **config["model"].get("unet", {}))
    net = UNet1D(state_dim, cond_dim, unet["down_dims"], unet["kernel_size"], unet["groups"],
                 unet["time_embed_dim"], unet["time_scale"])
    tensors = dict(checkpoint.named_parameters())
    tensors.update(dict(checkpoint.named_buffers()))
    state = {name[len(prefix) + 1:]: value.detach().clone() for name, value in tensors.items()
             if name.startswith(prefix + ".")}
    net.load_state_dict(state, strict=True)
    return net


def load_scene(path):
    """A flowplan scene YAML (spheres, boxes, cylinders, capsules) -> {kind: rows} in this file's layout: spheres
    (K, 4) centre, radius; boxes (K, 10) centre, size, quaternion (w, x, y, z); cylinders (K, 9) centre, radius,
    height, quaternion; capsules (K, 7) ends a, b, radius. A shape without a quaternion is unrotated."""
    with open(path) as f:
        entries = yaml.safe_load(f) or {}
    unrotated = [1.0, 0.0, 0.0, 0.0]
    layouts = {"spheres": lambda e: e["centre"] + [e["radius"]],
               "boxes": lambda e: e["centre"] + e["size"] + e.get("quaternion", unrotated),
               "cylinders": lambda e: e["centre"] + [e["radius"], e["height"]] + e.get("quaternion", unrotated),
               "capsules": lambda e: e["a"] + e["b"] + [e["radius"]]}
    unknown = sorted(set(entries) - set(layouts))
    if unknown:
        raise ValueError(f"{path}: unknown obstacle kinds {unknown}")
    return {kind: torch.tensor([layouts[kind](e) for e in rows], dtype=torch.float64).float()
            for kind, rows in entries.items() if rows}


def median_ms(body, repeats, warmup=3):
    for _ in range(warmup):
        body()
    times = []
    for _ in range(repeats):
        begin = time.perf_counter()
        body()
        times.append((time.perf_counter() - begin) * 1e3)
    return statistics.median(times)


class ExportReference:
    """Plans of the exported planner: its own plan() for the splitting it was
    exported with, otherwise its sampler's integrate() composed as its plan()
    composes it."""

    def __init__(self, module):
        self.m = module
        self.splits = module.splitting == "midpoint"

    def plan(self, start, goal, noise, renoise, scene, scale, split):
        m = self.m
        scene = dict(scene or {})
        if split == self.splits:
            return m.plan(start, goal, noise, renoise if split else None, scale=scale, **scene), "export.plan"
        sampler = m.sampler
        opts = dict(m.settings)
        opts["guidance.scale"] = scale
        guided = sampler.guide.active(scene, opts)
        s, g = m.normalize(start), m.normalize(goal)
        steps = int(opts["sampler.steps"])
        choices = {"guidance.schedule": m.schedule, "sampler.guide_at": m.guide_at}
        x = sampler.integrate(noise, s, g, 0.0, steps, scene, opts, choices, guided)
        if split:
            B, half = x.size(0), m.horizon // 2
            t_s = opts["sampler.split_time"]
            if guided:
                x = sampler.descend(x, scale, int(opts["sampler.midpoint_iterations"]), s, g, scene, opts)
            before_mid, after_mid = x[:, half - 1], x[:, half]
            x = (1.0 - t_s) * renoise + t_s * x
            halves = torch.cat([x[:, 0:half], x[:, half:m.horizon]], 0)
            refined = sampler.integrate(halves, torch.cat([s, after_mid], 0), torch.cat([before_mid, g], 0), t_s,
                                        max(1, int(steps * (1.0 - t_s) + 1e-9)), scene, opts, choices, guided)
            x = torch.cat([refined[0:B], refined[B:2 * B]], 1)
        return inpaint(m.denormalize(x), start, goal), "export.sampler.integrate"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--checkpoint", required=True, help="flowplan checkpoint (.pt)")
    parser.add_argument("--export", required=True, help="the exported planner of the same weights (.pt)")
    parser.add_argument("--threads", type=int, required=True, help="torch intra-op threads")
    parser.add_argument("--json", required=True, help="output JSON file")
    parser.add_argument("--repeats", type=int, default=20, help="timed repeats per measurement (median)")
    parser.add_argument("--kernels", help="libflowplan_kernels.so, loaded first when --export uses native kernels")
    parser.add_argument("--mpd-checkpoint", help="a DDPM (MPD) checkpoint of the same network: its plans are checked "
                                                 "against --mpd-export and timed too")
    parser.add_argument("--mpd-export", help="the exported planner of --mpd-checkpoint's weights (.pt)")
    parser.add_argument("--check-only", action="store_true", help="the checks without the timings")
    args = parser.parse_args()
    if (args.mpd_checkpoint is None) != (args.mpd_export is None):
        parser.error("--mpd-checkpoint and --mpd-export go together")

    torch.set_num_threads(args.threads)
    if args.check_only:
        # The graph executor's optimisations off, as flowplan itself plans: with them on, the first calls of the
        # exported file's methods profile their graphs for seconds each, which the checks need not wait for.
        torch._C._set_graph_executor_optimize(False)
    torch.set_flush_denormal(True)  # as bench/speed_bench.cc does for the C++ side

    checkpoint = torch.jit.load(args.checkpoint, map_location="cpu")
    config = yaml.safe_load(checkpoint.config)
    robot = yaml.safe_load(checkpoint.robot)
    # Configs written before model.architecture became model.name use the old key.
    model_name = config["model"].get("name", config["model"].get("architecture", "unet1d"))
    objective = config.get("objective", {})
    if model_name != "unet1d" or objective.get("name", "flow_matching") != "flow_matching":
        sys.exit(f"{args.checkpoint}: expected model.name unet1d and objective.name flow_matching, got "
                 f"{model_name} and {objective.get('name')}")
    conditioning = objective.get("conditioning", "inpaint")
    normalizer = Normalizer(checkpoint.normalizer_lo, checkpoint.normalizer_hi)
    D, T = normalizer.lo.numel(), int(checkpoint.horizon)
    C = 2 * D if conditioning == "direct" else 0
    steps = int(config.get("sampler", {}).get("steps", 10))
    settings = dict(GUIDANCE_DEFAULTS, **config.get("guidance", {}))
    scale = float(settings["scale"])

    net = load_network(checkpoint, "ema", config, D, C).eval()
    kinematics = ArmKinematics(robot)
    guide = Guide(settings, kinematics, float(checkpoint.dt), normalizer, robot["velocity_limit"])
    if args.kernels:
        torch.ops.load_library(args.kernels)
    export = torch.jit.load(args.export, map_location="cpu")
    # The end-game as the exported file says (plain or covariant, with its joint-speed weight; the speed benchmark
    # exports without it, the preset has it); the other guidance variants are not written here, so a file that uses one
    # is refused rather than misjudged.
    variants = {"sampler.midpoint_iterations": 0.0, "sampler.guide_from": 0.0,
                "sampler.split_time": 0.5, "guidance.candidates": 1.0}
    if export.settings.get("sampler.final_iterations", 0.0) != 0.0:  # the end-game's own variant matters only with it
        variants["sampler.final_denoise_time"] = 0.0
    other = {k: export.settings[k] for k, v in variants.items() if export.settings.get(k, v) != v}
    if other or getattr(export, "guide_at", "state") != "state":
        sys.exit(f"{args.export}: guidance variants this reference does not implement: {other}, "
                 f"guide_at {getattr(export, 'guide_at', 'state')}")
    planner = FlowPlanner(net, normalizer, conditioning, steps, guide,
                          int(export.settings.get("sampler.final_iterations", 0.0)),
                          float(export.settings.get("sampler.final_spread", 0.0)),
                          float(export.settings.get("sampler.final_joint_speed_weight", 0.0)))
    reference = ExportReference(export)
    compiled = {key[len("guidance."):]: value for key, value in export.settings.items() if key.startswith("guidance.")}
    compiled["schedule"] = export.schedule
    mismatched = sorted(k for k in compiled if k in settings and compiled[k] != settings[k])
    if mismatched:
        print(f"warning: the export's compiled guidance differs from the checkpoint's in {mismatched}; "
              f"the guided checks compare different settings", file=sys.stderr)

    # ---- checks ------------------------------------------------------------
    checks, references = {}, {}
    torch.manual_seed(0)
    x = torch.randn(2, T, D)                                   # (2, T, D) normalized
    t = torch.tensor([0.3, 0.8])                               # (2,)
    cond = torch.randn(2, C) if C > 0 else None
    with torch.inference_mode():
        checks["network"] = (net(x, t, cond) - export.sampler.network.forward(x, t, cond)).abs().max().item()

    start_q = export.ik(torch.tensor([[0.5, -0.3, 0.2], [0.5, 0.3, 0.2]], dtype=torch.float64)).float()  # (2, J)
    start = torch.cat([start_q[0:1], torch.zeros(1, D - start_q.size(1))], 1)   # (1, D): q, then q_dot at rest
    goal = torch.cat([start_q[1:2], torch.zeros(1, D - start_q.size(1))], 1)
    noise, renoise = torch.randn(1, T, D), torch.randn(1, T, D)                  # (1, T, D)
    sphere = {"spheres": torch.tensor([[0.5, 0.0, 0.2, 0.1]])}                  # (K = 1, 4)
    shapes = {"boxes": torch.tensor([[0.5, 0.0, 0.1, 0.1, 0.2, 0.2, 0.97, 0.0, 0.0, 0.24]]),   # (1, 10)
              "cylinders": torch.tensor([[0.45, 0.05, 0.3, 0.04, 0.2, 0.7, 0.7, 0.0, 0.0]]),   # (1, 9)
              "capsules": torch.tensor([[0.55, -0.1, 0.25, 0.55, 0.1, 0.25, 0.03]])}         # (1, 7)
    cases = [("unguided_plan", None, 0.0, False), ("unguided_split_plan", None, 0.0, True),
             ("guided_plan", sphere, scale, False), ("guided_split_plan", sphere, scale, True),
             ("guided_shapes_split_plan", shapes, scale, True)]
    plans = {}
    for name, scene, s, split in cases:
        with torch.no_grad():
            ours = planner.plan(start, goal, noise, renoise, scene, s, split)
            theirs, references[name] = reference.plan(start, goal, noise, renoise, scene, s, split)
        checks[name] = (ours - theirs).abs().max().item()
        plans[name] = ours
    # Guidance must have moved the plans for its checks to mean anything.
    moved = {name: (plans[name] - plans["unguided_split_plan" if "split" in name else "unguided_plan"]).abs().max().item()
             for name in plans if name.startswith("guided")}
    # MPD: its plans against its export's plan() with the same noise, unguided and around the sphere.
    mpd = mpd_bf16 = None
    if args.mpd_checkpoint:
        mpd_checkpoint = torch.jit.load(args.mpd_checkpoint, map_location="cpu")
        mpd_config = yaml.safe_load(mpd_checkpoint.config)
        mpd_objective = mpd_config.get("objective", {})
        if (mpd_config["model"].get("name", mpd_config["model"].get("architecture", "unet1d")) != "unet1d"
                or mpd_objective.get("name") != "ddpm"):
            sys.exit(f"{args.mpd_checkpoint}: expected model.name unet1d and objective.name ddpm")
        mpd_normalizer = Normalizer(mpd_checkpoint.normalizer_lo, mpd_checkpoint.normalizer_hi)
        if (mpd_normalizer.lo.numel(), int(mpd_checkpoint.horizon)) != (D, T):
            sys.exit(f"{args.mpd_checkpoint}: expected states of {D} dimensions and a horizon of {T}, as "
                     f"{args.checkpoint}'s")
        mpd_conditioning = mpd_objective.get("conditioning", "inpaint")
        mpd_net = load_network(mpd_checkpoint, "ema", mpd_config, D, 2 * D if mpd_conditioning == "direct" else 0).eval()
        # The guidance and sampler settings the exported file plans with (its defaults, which export overrides set),
        # and the noise schedule of the checkpoint (compiled into the file).
        mpd_export = torch.jit.load(args.mpd_export, map_location="cpu")
        mpd_settings = dict(GUIDANCE_DEFAULTS, **mpd_config.get("guidance", {}))
        mpd_settings.update({key[len("guidance."):]: value for key, value in mpd_export.settings.items()
                             if key.startswith("guidance.")})
        sampler_ddpm = dict(DDPM_SAMPLER_DEFAULTS, **{key[len("sampler.ddpm."):]: value for key, value
                                                      in mpd_export.settings.items() if key.startswith("sampler.ddpm.")})
        sampler_ddpm["guide_on"] = mpd_export.sampler.guide_on
        if mpd_settings.get("candidates", 1.0) != 1.0:
            sys.exit(f"{args.mpd_export}: guidance.candidates > 1 is not written here")
        mpd_guide = Guide(mpd_settings, kinematics, float(mpd_checkpoint.dt), mpd_normalizer, robot["velocity_limit"])
        schedule = dict(DDPM_DEFAULTS, **mpd_objective.get("ddpm", {}))
        mpd, mpd_bf16 = (DdpmPlanner(network, mpd_normalizer, mpd_conditioning, schedule, sampler_ddpm, mpd_guide)
                         for network in (mpd_net, Bf16Autocast(mpd_net)))
        mpd_scale = float(mpd_settings["scale"])
        mpd_renoise = torch.randn(1, mpd.steps - 1, T, D)                         # (1, N - 1, T, D)
        mpd_plans = {}
        for name, scene, s_ in (("mpd_unguided_plan", None, 0.0), ("mpd_guided_plan", sphere, mpd_scale)):
            with torch.no_grad():
                ours = mpd.plan(start, goal, noise, mpd_renoise, scene, s_)
                theirs = mpd_export.plan(start, goal, noise, mpd_renoise, scale=s_, **dict(scene or {}))
            checks[name], references[name] = (ours - theirs).abs().max().item(), "mpd_export.plan"
            mpd_plans[name] = ours
        moved["mpd_guided_plan"] = (mpd_plans["mpd_guided_plan"] - mpd_plans["mpd_unguided_plan"]).abs().max().item()
    failed = [k for k in ("network", "unguided_plan", "unguided_split_plan", "mpd_unguided_plan")
              if k in checks and not checks[k] <= TOLERANCE]
    failed += [k for k in checks if "guided" in k and "unguided" not in k and not checks[k] <= GUIDED_TOLERANCE]
    failed += [f"{k} (guidance moved the plan by {v:.1e} only)" for k, v in moved.items() if not v > 1e-4]
    if args.check_only:
        for key, value in checks.items():
            print(f"  {key:<26} {value:10.3e}  ({references.get(key, 'export.sampler.network')})")
        if failed:
            print(f"FAILED: {', '.join(failed)}", file=sys.stderr)
        return 1 if failed else 0

    # ---- timings (the inputs of bench/speed_bench.cc) ------------------------
    # Each forward and plan timing twice: the network in float32, then under bf16 autocast (key + "_bf16").
    net_bf16 = Bf16Autocast(net)
    precisions = (("", net), ("_bf16", net_bf16))
    ms = {}
    for B in (1, 64):
        xb, tb = torch.randn(B, T, D), torch.full([B], 0.5)
        cb = torch.zeros(B, C) if C > 0 else None
        for suffix, network in precisions:
            with torch.inference_mode():
                ms[f"forward_b{B}{suffix}"] = median_ms(lambda: network(xb, tb, cb), args.repeats)
    flops_b1 = count_flops(net, torch.randn(1, T, D), torch.full([1], 0.5), torch.zeros(1, C) if C > 0 else None)

    # A copy of the EMA weights trained with AdamW(1e-4, weight decay 0.01), as bench/speed_bench.cc does.
    trainee = load_network(checkpoint, "ema", config, D, C).train()
    optimizer = torch.optim.AdamW(trainee.parameters(), lr=1e-4, weight_decay=0.01)
    x1 = torch.rand(256, T, D) * 2 - 1                         # (256, T, D) normalized
    ms["train_step_b256"] = median_ms(lambda: train_step(trainee, optimizer, x1, conditioning),
                                      max(5, args.repeats // 4), warmup=1)

    def train_step_bf16():
        with torch.autocast("cpu", dtype=torch.bfloat16):  # the loss; backward and AdamW outside, as PyTorch advises
            optimizer.zero_grad(set_to_none=True)
            loss = flow_matching_loss(trainee, x1, conditioning)
        loss.backward()
        optimizer.step()
    ms["train_step_b256_bf16"] = median_ms(train_step_bf16, max(5, args.repeats // 4), warmup=1)

    # Plans at B = 1 between two fixed states (40 % and 60 % of the normalizer range): unguided, then guided and
    # split around the sphere, the eight spheres of bench/speed_bench.cc (EightSpheres) and the shelf scene's shapes.
    eight = {"spheres": torch.tensor([[0.5, 0.0, 0.2, 0.1], [0.3, -0.5, 0.6, 0.05], [0.3, 0.5, 0.6, 0.05],
                                      [0.7, -0.4, 0.5, 0.05], [0.7, 0.4, 0.5, 0.05], [0.6, 0.0, 0.8, 0.05],
                                      [0.2, -0.3, 0.1, 0.05], [0.2, 0.3, 0.1, 0.05]])}           # (K = 8, 4)
    shelf = load_scene(SHELF_SCENE)
    plan_start = (normalizer.lo * 0.6 + normalizer.hi * 0.4).unsqueeze(0)   # (1, D) raw
    plan_goal = (normalizer.lo * 0.4 + normalizer.hi * 0.6).unsqueeze(0)
    torch.manual_seed(1)
    plan_noise, plan_renoise = torch.randn(1, T, D), torch.randn(1, T, D)
    planners = [(suffix, FlowPlanner(network, normalizer, conditioning, steps, guide, planner.final_iterations,
                                     planner.final_spread, planner.final_speed_weight))
                for suffix, network in precisions]
    for suffix, flow in planners:
        with torch.inference_mode():
            ms["plan_b1" + suffix] = median_ms(lambda: flow.plan(plan_start, plan_goal, plan_noise), args.repeats)
        for scene_suffix, scene in (("", sphere), ("_8", eight), ("_shelf", shelf)):
            with torch.no_grad():
                ms["plan_guided_split_b1" + scene_suffix + suffix] = median_ms(
                    lambda: flow.plan(plan_start, plan_goal, plan_noise, plan_renoise, scene, scale, split=True),
                    args.repeats)

    # Throughput: 64 guided, split plans in one call between the postures of the TCPs (0.5, -/+0.3, 0.2), around
    # the sphere and around the eight spheres.
    start64, goal64 = start.expand(64, D), goal.expand(64, D)                                   # (64, D) raw
    noise64, renoise64 = torch.randn(64, T, D), torch.randn(64, T, D)                           # (64, T, D)
    for suffix, flow in planners:
        for scene_suffix, scene in (("", sphere), ("_8", eight)):
            with torch.no_grad():
                ms["plan_guided_split_b64" + scene_suffix + suffix] = median_ms(
                    lambda: flow.plan(start64, goal64, noise64, renoise64, scene, scale, split=True),
                    max(3, args.repeats // 10), warmup=1)

    if mpd is not None:  # MPD's 64 guided plans in one call, around the sphere and the eight spheres
        mpd_renoise64 = torch.randn(64, mpd.steps - 1, T, D)                    # (64, N - 1, T, D)
        for suffix, planner_ in (("", mpd), ("_bf16", mpd_bf16)):
            for scene_suffix, scene in (("", sphere), ("_8", eight)):
                with torch.no_grad():
                    ms["mpd_guided_b64" + scene_suffix + suffix] = median_ms(
                        lambda: planner_.plan(start64, goal64, noise64, mpd_renoise64, scene, mpd_scale),
                        max(3, args.repeats // 10), warmup=1)

    result = dict(ms)
    result.update({
        "flops_b1": flops_b1,
        "torch_version": torch.__version__,
        "threads": torch.get_num_threads(),
        "repeats": args.repeats,
        "checkpoint": args.checkpoint,
        "export": args.export,
        "mpd_checkpoint": args.mpd_checkpoint,
        "mpd_export": args.mpd_export,
        "export_splitting": export.splitting,
        "guidance_scale": scale,
        "checks": {f"{k}_max_abs_diff": v for k, v in checks.items()},
        "check_references": references,
        "check_tolerance": TOLERANCE,
        "checks_passed": not failed,
    })
    with open(args.json, "w") as f:
        json.dump(result, f, indent=2)
        f.write("\n")

    print(f"PyTorch {torch.__version__} eager, {torch.get_num_threads()} threads, median of {args.repeats}")
    for key, value in ms.items():
        print(f"  {key:<34} {value:10.3f} ms")
    print(f"  {'flops_b1':<34} {flops_b1 / 1e6:10.1f} MFLOP")
    print("max abs difference to the export")
    for key, value in checks.items():
        print(f"  {key:<22} {value:10.3e}  ({references.get(key, 'export.sampler.network')})")
    if failed:
        print(f"FAILED: {', '.join(failed)} above {TOLERANCE:g} (guided {GUIDED_TOLERANCE:g})", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
