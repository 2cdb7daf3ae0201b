# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# Planner, what `flowplan export` saves and what flowplan plans with
# in-process (docs/export.md). Submodules normalizer, robot and sampler (a
# FlowSampler, DdpmSampler or LatentSampler). Attributes: settings
# (Dict[str, float], every numeric setting a call may change, by its config
# name), schedule and guide_at (the choices a call may change), noise_shape and renoise_shape (per plan; renoise_shape empty:
# no renoise), state_dim (D), horizon (T), num_joints (J), workspace_dim (W),
# and the descriptive planner, conditioning, splitting, dt, env, state_labels,
# robot_description (YAML), config, format_version.
#
# Obstacles come as one tensor argument per shape (geometry/*.py give the
# columns): spheres (K, W + 1), boxes (K, 10) (2-D: (K, 5)), cylinders (K, 9)
# (2-D: (K, 5)), capsules (K, 2W + 1); `obstacles` is an older name of spheres.
#
# Best of N: with the setting guidance.candidates = N > 1, each request draws
# N plans (noise (B, N, *noise_shape)) and returns the one of least guidance
# cost (the weighted sum of the cost terms, whatever the scale).

from typing import Dict, List, Optional

import torch
from torch import Tensor

from flowplan.script.geometry.scene import add_obstacles, ordered_scene, prepared_scene, scene_size
from flowplan.script.kinematics.kinematics import sphere_clearance
from flowplan.script.guidance.guidance import guidance_schedules
from flowplan.script.planning.sampling import setting_int


class Planner:
    def call_settings(self, scale: Optional[float], settings: Optional[Dict[str, float]]) -> Dict[str, float]:
        """The exported settings, overridden by this call's."""
        opts: Dict[str, float] = {}
        for key, value in self.settings.items():
            opts[key] = value
        if settings is not None:
            for key, value in settings.items():
                assert key in self.settings, "plan: settings: unknown key " + key + " (this planner takes " + ", ".join(list(self.settings.keys())) + ")"
                assert value >= 0.0, "plan: settings: " + key + ": expected a non-negative value, got " + str(value)
                opts[key] = value
        if scale is not None:
            assert scale >= 0.0, "plan: scale: expected a non-negative guidance scale, got " + str(scale)
            opts["guidance.scale"] = scale
        return opts

    def call_scene(self, obstacles: Optional[Tensor], spheres: Optional[Tensor], boxes: Optional[Tensor],
                   cylinders: Optional[Tensor], capsules: Optional[Tensor]) -> Dict[str, Tensor]:
        """The obstacles of a call as a scene, checked."""
        W = self.workspace_dim
        scene: Dict[str, Tensor] = {}
        add_obstacles(scene, "spheres", obstacles, W, "plan: obstacles")
        add_obstacles(scene, "spheres", spheres, W, "plan: spheres")
        add_obstacles(scene, "boxes", boxes, W, "plan: boxes")
        add_obstacles(scene, "cylinders", cylinders, W, "plan: cylinders")
        add_obstacles(scene, "capsules", capsules, W, "plan: capsules")
        return ordered_scene(scene)

    def plan(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor] = None,
             obstacles: Optional[Tensor] = None, scale: Optional[float] = None, spheres: Optional[Tensor] = None,
             boxes: Optional[Tensor] = None, cylinders: Optional[Tensor] = None, capsules: Optional[Tensor] = None,
             settings: Optional[Dict[str, float]] = None, schedule: Optional[str] = None,
             guide_at: Optional[str] = None) -> Tensor:
        """Plans from start to goal (B, D) raw states with the given noise (B,
        *noise_shape) and renoise (B, *renoise_shape) — (B, N, *noise_shape) and
        (B, N, *renoise_shape) with N = guidance.candidates > 1 — around the
        obstacles, -> (B, T, D) raw float32 plans."""
        D = self.state_dim
        assert start.dim() == 2 and start.size(1) == D, "plan: start: expected (B, " + str(D) + "), got " + str(start.shape)
        assert goal.shape == start.shape, "plan: goal: expected the shape of start " + str(start.shape) + ", got " + str(goal.shape)
        B = start.size(0)
        opts = self.call_settings(scale, settings)
        N = setting_int(opts, "guidance.candidates")
        assert N >= 1, "plan: settings: guidance.candidates: expected at least one plan per request, got " + str(N)
        per_request: List[int] = [B] if N == 1 else [B, N]
        because = "" if N == 1 else " (guidance.candidates = " + str(N) + ")"
        hint = ""
        if N == 1 and noise.dim() == len(self.noise_shape) + 2 and noise.shape[2:] == self.noise_shape:
            hint = " (for N candidates per plan, set guidance.candidates = N)"
        assert noise.shape == per_request + self.noise_shape, "plan: noise: expected " + str(per_request + self.noise_shape) + because + ", got " + str(noise.shape) + hint
        if len(self.renoise_shape) > 0:
            assert renoise is not None, "plan: renoise: this planner needs renoise " + str(per_request + self.renoise_shape) + because
            assert renoise.shape == per_request + self.renoise_shape, "plan: renoise: expected " + str(per_request + self.renoise_shape) + because + ", got " + str(renoise.shape)
        chosen = self.schedule if schedule is None else schedule
        assert chosen in guidance_schedules(), "plan: schedule: expected one of " + ", ".join(guidance_schedules()) + ", got " + chosen
        at = self.guide_at if guide_at is None else guide_at
        assert self.planner == "flow_matching" or at == self.guide_at, "plan: guide_at: only the flow planner takes it (this is a " + self.planner + " planner, which guides as it was built to)"
        choices: Dict[str, str] = {"guidance.schedule": chosen, "sampler.guide_at": at}
        scene = self.call_scene(obstacles, spheres, boxes, cylinders, capsules)
        self.sampler.guide.check_grad_mode(start, scene, opts)
        device = self.normalizer.lo.device
        for kind, params in scene.items():
            scene[kind] = params.to(device)
        scene = prepared_scene(scene, self.workspace_dim)
        start_f = start.to(device).float()
        goal_f = goal.to(device).float()
        noise_f = noise.to(device).float()
        renoise_f: Optional[Tensor] = None
        if len(self.renoise_shape) > 0 and renoise is not None:
            renoise_f = renoise.to(device).float()
        if N == 1:
            return self.sampler.sample(start_f, goal_f, noise_f, renoise_f, scene, opts, choices)
        if renoise_f is not None:
            renoise_f = renoise_f.flatten(0, 1)
        plans = self.sampler.sample(start_f.repeat_interleave(N, 0), goal_f.repeat_interleave(N, 0), noise_f.flatten(0, 1),
                                    renoise_f, scene, opts, choices)
        return self.least_cost(plans.view([B, N] + plans.shape[1:]), scene, opts)

    def least_cost(self, plans: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tensor:
        """The plan (B, T, D) of least guidance cost among each request's
        candidates (B, N, T, D) raw; the first of equal costs."""
        B = plans.size(0)
        N = plans.size(1)
        cost = self.sampler.guide.value(plans.flatten(0, 1), scene, opts).view(B, N)
        best = torch.argmin(cost, 1)
        return plans[torch.arange(B, device=plans.device), best]

    def sample(self, start: Tensor, goal: Tensor, num_samples: int, obstacles: Optional[Tensor] = None,
               scale: Optional[float] = None, spheres: Optional[Tensor] = None, boxes: Optional[Tensor] = None,
               cylinders: Optional[Tensor] = None, capsules: Optional[Tensor] = None,
               settings: Optional[Dict[str, float]] = None, schedule: Optional[str] = None,
               guide_at: Optional[str] = None) -> Tensor:
        """num_samples plans from start to goal (D,), noise from the caller's
        global generator (torch.manual_seed) -> (num_samples, T, D)."""
        assert start.dim() == 1 and goal.dim() == 1, "sample: expected start and goal of shape (D,)"
        N = setting_int(self.call_settings(scale, settings), "guidance.candidates")
        per_request: List[int] = [num_samples] if N == 1 else [num_samples, N]
        noise = torch.randn(per_request + self.noise_shape, dtype=self.normalizer.lo.dtype, device=self.normalizer.lo.device)
        renoise: Optional[Tensor] = None
        if len(self.renoise_shape) > 0:
            renoise = torch.randn(per_request + self.renoise_shape, dtype=self.normalizer.lo.dtype, device=self.normalizer.lo.device)
        return self.plan(start.unsqueeze(0).expand(num_samples, -1), goal.unsqueeze(0).expand(num_samples, -1), noise,
                         renoise, obstacles, scale, spheres, boxes, cylinders, capsules, settings, schedule, guide_at)

    def clearance(self, q: Tensor, obstacles: Optional[Tensor] = None, spheres: Optional[Tensor] = None,
                  boxes: Optional[Tensor] = None, cylinders: Optional[Tensor] = None,
                  capsules: Optional[Tensor] = None) -> Tensor:
        """Whole-robot clearance (..., K) of joint positions q (..., J) from every
        obstacle: the smallest signed distance between a collision sphere and the
        obstacle (negative: they overlap)."""
        scene = self.call_scene(obstacles, spheres, boxes, cylinders, capsules)
        shape = list(q.shape[:-1])
        centres = self.robot.sphere_centres(q).reshape(-1, self.robot.num_spheres, self.workspace_dim)
        return sphere_clearance(centres, self.robot.sphere_radii, scene).reshape(shape + [scene_size(scene)])

    def tcp(self, q: Tensor) -> Tensor:
        """TCP positions (..., W) of joint positions q (..., J)."""
        return self.robot.tcp(q)

    def collision_spheres(self, q: Tensor) -> Tensor:
        """Centre and radius (..., S, W + 1) of the robot's collision spheres at q (..., J)."""
        return self.robot.collision_spheres(q)

    def ik(self, tcp: Tensor, seed: Optional[Tensor] = None) -> Tensor:
        """Joint positions (..., J) that put the TCP at tcp (..., W) (arms: with the
        TCP orientation of the home posture), from seed (..., J) or home."""
        return self.robot.ik(tcp, seed)

    def normalize(self, x: Tensor) -> Tensor:
        return self.normalizer.normalize(x)

    def denormalize(self, x: Tensor) -> Tensor:
        return self.normalizer.denormalize(x)
