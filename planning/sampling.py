# TorchScript (compiled by flowplan at run time, jit/library.h): helpers of
# the trajectory samplers. Shapes: B plans, T states, D state dims.

from typing import Dict, List

import torch
from torch import Tensor

from flowplan.script.models.conditioning import inpaint


def conditioned(x: Tensor, start: Tensor, goal: Tensor, inpainting: bool) -> Tensor:
    """x (B, T, D) with its ends overwritten under inpainting, unchanged otherwise."""
    if inpainting:
        return inpaint(x, start, goal)
    return x


def setting_int(opts: Dict[str, float], key: str) -> int:
    value = opts[key]
    assert value == float(int(value)), key + ": expected a whole number, got " + str(value)
    return int(value)


def ceil_int(value: float) -> int:
    """The smallest whole number >= value."""
    whole = int(value)
    return whole + 1 if float(whole) < value else whole


def split_steps(steps: int, split_time: float) -> int:
    """Euler steps of splitting's second stage (split_time -> 1): the first
    stage's steps over the same stretch of flow time, at least one."""
    return max(1, int(steps * (1.0 - split_time) + 1e-9))


def guide_targets() -> List[str]:
    """Where the flow planner may guide (sampler.guide_at)."""
    return ["state", "velocity", "prediction"]


def spread_matrix(T: int, length: float, like: Tensor) -> Tensor:
    """(T, T) M such that M g spreads each state's push g (B, T, D) over its
    neighbours, the two end states fixed: on the interior states M is
    (I + l² KᵀK)⁻¹ (K the differences of successive states, the ends held, so
    KᵀK = tridiag(-1, 2, -1)), the covariant step of the metric that charges a
    push for the speed it adds, scaled so that its largest diagonal entry is 1
    (a push on the middle state alone moves it as far as a plain step would;
    the same push on every state adds up to about 2l times a plain step where
    l is short against the plan: 8.1 for l = 4 and T = 64, 24 for l = 16,
    7.7 and 14 in a split half of 32 states); l (states) the
    length over which a push decays, l = 0 the identity on the interior, l -> oo
    the tent min(i, j)(n + 1 - max(i, j)) of CHOMP's velocity metric. Rows and
    columns of the end states are 0. Closed form in float64:
    M_ij ∝ e^{-mu |i - j|} (1 - e^{-2 mu min(i, j)}) (1 - e^{-2 mu (n + 1 - max(i, j))})
    over interior indices 1..n = T - 2, cosh mu = 1 + 1 / (2 l²); returned in
    the dtype and on the device of `like`."""
    assert length == 0.0 or (length >= 1e-3 and length <= 1e6), "plan: settings: sampler.final_spread: expected 0 or a length in states from 0.001 to 1e6, got " + str(length)
    M = torch.zeros([T, T], dtype=like.dtype, device=like.device).double()
    n = T - 2
    if n <= 0:
        return M.to(like.dtype)
    if length == 0.0:
        M[1:T - 1, 1:T - 1] = torch.eye(n, dtype=like.dtype, device=like.device).double()
        return M.to(like.dtype)
    i = torch.arange(1, n + 1, device=like.device).double()
    a = i.new_full([1], 0.5 / (length * length))
    mu = torch.log1p(a + torch.sqrt(a * (2.0 + a)))  # acosh(1 + a), accurate for small a
    lo = torch.minimum(i.view(n, 1), i.view(1, n))
    hi = torch.maximum(i.view(n, 1), i.view(1, n))
    G = torch.exp(-mu * (hi - lo)) * torch.expm1(-2.0 * mu * lo) * torch.expm1(-2.0 * mu * (n + 1 - hi))
    M[1:T - 1, 1:T - 1] = G / G.diagonal().max()
    return M.to(like.dtype)
