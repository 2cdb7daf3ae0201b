# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# UserCost, a cost a user writes as the method
#   def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor
# (q, qd (B, T, J) raw joint positions and velocities, scene the obstacles
# as the call gave them (given_scene: a prepared scene's rows without their
# appended columns),
# returning (B,)), in the file named by guidance.user_cost, compiled onto this
# module. Its gradient is taken by autograd, also under a caller's
# torch.no_grad(). Submodule robot (self.robot.tcp(q) and the rest of
# kinematics/arm.py); attributes dt, source (the file), weight_key.

from typing import Dict, Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.scene import given_scene


class UserCost:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return opts[self.weight_key] != 0.0

    def autograd_source(self, opts: Dict[str, float]) -> str:
        """The file of this cost when it takes part (its gradient needs autograd), else ''."""
        return self.source if opts[self.weight_key] != 0.0 else ""

    def value_and_gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tuple[Tensor, Tensor, Tensor]:
        """q, qd (B, T, J) raw -> C (B,), dC/dq, dC/dqd (B, T, J), by autograd."""
        assert not q.is_inference(), self.source + ": a user cost takes its gradient by autograd, which cannot run under torch.inference_mode(); plan under torch.no_grad() instead"
        enabled = torch.is_grad_enabled()
        torch.set_grad_enabled(True)
        q_leaf = q.detach().requires_grad_(True)
        qd_leaf = qd.detach().requires_grad_(True)
        value = self.cost(q_leaf, qd_leaf, given_scene(scene, self.robot.workspace_dim))
        assert value.dim() == 1 and value.size(0) == q.size(0), self.source + ": cost: expected a value per trajectory (" + str(q.size(0)) + ",), got " + str(value.shape)
        gradients = torch.autograd.grad([value.sum()], [q_leaf, qd_leaf], allow_unused=True)
        torch.set_grad_enabled(enabled)
        grad_q = gradients[0]
        grad_qd = gradients[1]
        if grad_q is None:
            grad_q = torch.zeros_like(q)
        if grad_qd is None:
            grad_qd = torch.zeros_like(qd)
        return value.detach(), grad_q, grad_qd
