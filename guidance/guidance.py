# TorchScript (compiled by flowplan at run time, jit/library.h): helpers of
# guidance (SPEC section 2). Settings travel as a Dict[str, float] `opts`
# keyed by their config names ("guidance.scale", "guidance.clip", ...).

from typing import List

import torch
from torch import Tensor


def guidance_schedules() -> List[str]:
    return ["one_minus_t", "ratio", "rising", "constant"]


def schedule_factor(schedule: str, t: float) -> float:
    """b_t, the factor on the cost gradient after the step that reached flow time t (0 noise, 1 data)."""
    if schedule == "one_minus_t":
        return 1.0 - t
    if schedule == "ratio":
        return (1.0 - t) / max(t, 1e-3)
    if schedule == "rising":
        return t
    if schedule == "constant":
        return 1.0
    raise Exception("guidance.schedule: unknown schedule " + schedule + " (expected one_minus_t, ratio, rising or constant)")


def clip_states(gradient: Tensor, clip: float) -> Tensor:
    """Caps the norm of each state's gradient (B, T, D) at `clip` (raw units); 0: no cap."""
    if clip <= 0.0:
        return gradient
    return gradient / (torch.norm(gradient, 2, -1, True).clamp_min(clip) / clip)
