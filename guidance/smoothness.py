# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# SmoothnessCost, the constant-velocity Gaussian-process prior of GPMP2 / MPD
# (SPEC section 2): with e_q = q_{i+1} - q_i - dt qd_i and e_v = qd_{i+1} - qd_i,
#   C = sum_i 12/(dt^3 s^2) e_q^2 - 12/(dt^2 s^2) e_q e_v + 4/(dt s^2) e_v^2,
# s = guidance.smoothness_sigma. Attributes: dt (s between states), weight_key.
# It smooths what the other terms push, and never makes guidance run alone.
# kernels/arm_guidance_kernel.cc computes this term too, for an arm with native
# kernels (guidance/arm_guide.py): a change here is a change there.

from typing import Dict, Tuple

import torch
from torch import Tensor


class SmoothnessCost:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return False

    def autograd_source(self, opts: Dict[str, float]) -> str:
        return ""

    def value_and_gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tuple[Tensor, Tensor, Tensor]:
        """q, qd (B, T, J) raw -> C (B,), dC/dq, dC/dqd (B, T, J), written out."""
        T = q.size(1)
        dt = self.dt
        s2 = opts["guidance.smoothness_sigma"] * opts["guidance.smoothness_sigma"]
        a = 12.0 / (dt * dt * dt * s2)
        b = -6.0 / (dt * dt * s2)
        c = 4.0 / (dt * s2)
        e_q = q[:, 1:T] - q[:, 0:T - 1] - dt * qd[:, 0:T - 1]
        e_v = qd[:, 1:T] - qd[:, 0:T - 1]
        value = (a * e_q * e_q + 2.0 * b * e_q * e_v + c * e_v * e_v).sum([1, 2])
        # dC/de_q = 2(a e_q + b e_v), dC/de_v = 2(b e_q + c e_v); e_q_i depends on q_{i+1} (+1),
        # q_i (-1), qd_i (-dt); e_v_i on qd_{i+1} (+1), qd_i (-1).
        g_q = 2.0 * (a * e_q + b * e_v)
        g_v = 2.0 * (b * e_q + c * e_v)
        zero = torch.zeros_like(q[:, 0:1])
        grad_q = torch.cat([zero, g_q], 1) - torch.cat([g_q, zero], 1)
        grad_qd = torch.cat([zero, g_v], 1) - torch.cat([dt * g_q + g_v, zero], 1)
        return value, grad_q, grad_qd
