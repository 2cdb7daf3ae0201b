# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# JointLimitCost, a hinge on the distance to the joint position limits:
#   C = sum over states and joints of relu(lower + m - q) + relu(q - upper + m),
# m = guidance.joint_limit_margin. Submodule robot (its lower and upper limits);
# attribute weight_key.
# kernels/arm_guidance_kernel.cc computes this term too, for an arm with native
# kernels (guidance/arm_guide.py): a change here is a change there.

from typing import Dict, Tuple

import torch
from torch import Tensor


class JointLimitCost:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return opts[self.weight_key] != 0.0

    def autograd_source(self, opts: Dict[str, float]) -> str:
        return ""

    def value_and_gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tuple[Tensor, Tensor, Tensor]:
        """q, qd (B, T, J) raw -> C (B,), dC/dq, dC/dqd (B, T, J), written out."""
        margin = opts["guidance.joint_limit_margin"]
        below = torch.relu(self.robot.lower.to(q.dtype) + margin - q)
        above = torch.relu(q - self.robot.upper.to(q.dtype) + margin)
        gradient = (above > 0).to(q.dtype) - (below > 0).to(q.dtype)
        return (below + above).sum([1, 2]), gradient, torch.zeros_like(qd)
