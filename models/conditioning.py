# TorchScript (compiled by flowplan at run time, jit/library.h): how start and
# goal reach a trajectory network (SPEC section 2).

from typing import Optional

import torch
from torch import Tensor


def inpaint(x: Tensor, start: Tensor, goal: Tensor) -> Tensor:
    """x (B, T, D) with state 0 replaced by start (B, D) and state T - 1 by goal
    (B, D), out of place (gradients flow to the interior states)."""
    return torch.cat([start.unsqueeze(1), x[:, 1:-1], goal.unsqueeze(1)], 1)


def condition_vector(start: Tensor, goal: Tensor, inpainting: bool) -> Optional[Tensor]:
    """The network's global condition (B, 2D) = [start, goal] under direct
    conditioning, None under inpainting."""
    if inpainting:
        return None
    return torch.cat([start, goal], -1)
