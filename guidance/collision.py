# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# CollisionCost, the whole-robot collision hinge (SPEC section 2) against every
# obstacle shape:
#   C = sum over states, collision spheres s and obstacles k of
#       relu(margin + r_s - d_k(c_s)),
# d_k the signed distance of the sphere centre c_s to obstacle k. Submodule
# robot and distances (geometry/distances.py or native_distances.py); attribute
# weight_key. Shapes: B trajectories, T states, J joints,
# S spheres, K obstacles.

from typing import Dict, Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.scene import scene_size


class CollisionCost:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return opts[self.weight_key] != 0.0 and scene_size(scene) > 0

    def autograd_source(self, opts: Dict[str, float]) -> str:
        return ""

    def value_and_gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tuple[Tensor, Tensor, Tensor]:
        """q, qd (B, T, J) raw -> C (B,), dC/dq (B, T, J), dC/dqd (B, T, J), the
        gradient written out (through the robot's vector-Jacobian product)."""
        B = q.size(0)
        T = q.size(1)
        J = q.size(2)
        if scene_size(scene) == 0:
            return torch.zeros([B], dtype=q.dtype, device=q.device), torch.zeros_like(q), torch.zeros_like(qd)
        centres, axes, origins = self.robot.spheres(q.reshape(B * T, J))
        M = centres.size(0)
        S = centres.size(1)
        W = centres.size(2)
        points = centres.reshape(M * S, W)
        distance = self.distances.distance_only(points, scene)
        K = distance.size(1)
        reach = opts["guidance.margin"] + self.robot.sphere_radii.to(q.dtype).view(1, S, 1)
        penetration = torch.relu(reach - distance.view(M, S, K))
        # d/dc_s of sum_k relu(reach - d_k(c_s)) = -sum_k [active] grad d_k(c_s). Only the sphere centres within
        # reach of some obstacle have a gradient, usually a few of the M S: the obstacles' gradients are taken
        # at those alone, summed as one batched product, and carried to q from those rows alone.
        active = (penetration > 0).view(M * S, K)
        near = active.any(1).nonzero().squeeze(1)
        grad_near = torch.zeros([0, W], dtype=q.dtype, device=q.device)
        if near.size(0) > 0:
            near_distance, normal = self.distances.distance(points.index_select(0, near), scene)
            weights = active.index_select(0, near).to(q.dtype).unsqueeze(1)
            grad_near = -torch.bmm(weights, normal).squeeze(1)
        grad_q = self.robot.spheres_vjp(centres, axes, origins, near, grad_near).view(B, T, J)
        return penetration.sum([1, 2]).view(B, T).sum(1), grad_q, torch.zeros_like(qd)
