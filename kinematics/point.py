# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# Point, a ball (or disc, W = 2) whose centre is the configuration itself:
# J = W, the TCP is q, one collision sphere of radius sphere_radii[0] at q.
# The same methods as the class Arm (kinematics/arm.py).

from typing import Optional, Tuple

import torch
from torch import Tensor


class Point:
    def tcp(self, q: Tensor) -> Tensor:
        assert q.dim() >= 1 and q.size(-1) == self.num_joints, "tcp: q: expected (..., " + str(self.num_joints) + "), got " + str(q.shape)
        return q

    def spheres(self, q: Tensor) -> Tuple[Tensor, Tensor, Tensor]:
        none = torch.zeros([0], dtype=q.dtype, device=q.device)
        return q.unsqueeze(1), none, none

    def spheres_vjp(self, centres: Tensor, axes: Tensor, origins: Tensor, rows: Tensor, g: Tensor) -> Tensor:
        return torch.zeros_like(centres.squeeze(1)).index_add_(0, rows, g)

    def tcp_vjp(self, q: Tensor, g: Tensor) -> Tensor:
        return g

    def sphere_centres(self, q: Tensor) -> Tensor:
        assert q.dim() >= 1 and q.size(-1) == self.num_joints, "sphere_centres: q: expected (..., " + str(self.num_joints) + "), got " + str(q.shape)
        return q.unsqueeze(-2)

    def collision_spheres(self, q: Tensor) -> Tensor:
        centres = self.sphere_centres(q)
        radii = self.sphere_radii.to(centres.dtype).expand(centres.shape[:-1]).unsqueeze(-1)
        return torch.cat([centres, radii], -1)

    def ik_solve(self, targets: Tensor, seed: Tensor) -> Tuple[Tensor, Tensor, Tensor, Tensor]:
        zero = torch.zeros([targets.size(0)], dtype=targets.dtype).double()
        return targets.double(), zero, zero, zero == 0.0

    def ik(self, tcp: Tensor, seed: Optional[Tensor] = None) -> Tensor:
        assert tcp.dim() >= 1 and tcp.size(-1) == self.num_joints, "ik: tcp: expected (..., " + str(self.num_joints) + "), got " + str(tcp.shape)
        return tcp
