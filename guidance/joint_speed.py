# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# JointSpeedCost, a squared hinge on the joint speeds a plan's positions imply:
#   r_ij = |q_{i+1,j} - q_{i,j}| / (dt v_j),   C = sum over i, j of relu(r_ij - rho)^2,
# v_j the joint's velocity limit, rho = guidance.joint_speed_ratio (the speed,
# as a share of the limit, above which the hinge acts). It keeps what the other
# terms push within speeds the arm can follow, and never makes guidance run
# alone. A robot without velocity limits (infinite) has no cost. Submodule
# robot (its velocity_limit); attributes dt (s between states), weight_key.
# kernels/arm_guidance_kernel.cc computes this term too, for an arm with native
# kernels (guidance/arm_guide.py): a change here is a change there.

from typing import Dict, Tuple

import torch
from torch import Tensor


class JointSpeedCost:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return False

    def autograd_source(self, opts: Dict[str, float]) -> str:
        return ""

    def value_and_gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tuple[Tensor, Tensor, Tensor]:
        """q, qd (B, T, J) raw -> C (B,), dC/dq, dC/dqd (B, T, J), written out."""
        T = q.size(1)
        step_limit = self.robot.velocity_limit.to(q.dtype) * self.dt  # (J,) the largest |q_{i+1} - q_i|
        step = q[:, 1:T] - q[:, 0:T - 1]  # (B, T - 1, J)
        excess = torch.relu(step.abs() / step_limit - opts["guidance.joint_speed_ratio"])
        # dC/dstep = 2 excess sign(step) / step_limit; step_i depends on q_{i+1} (+1) and q_i (-1).
        g = 2.0 * excess * torch.sign(step) / step_limit
        zero = torch.zeros_like(q[:, 0:1])
        return (excess * excess).sum([1, 2]), torch.cat([zero, g], 1) - torch.cat([g, zero], 1), torch.zeros_like(qd)
