# TorchScript (compiled by flowplan at run time, jit/library.h): capsules
# (stadiums in 2-D), the points within `radius` of the segment a-b. Row layout
# (K, 2W + 1): a (W), b (W), radius.

from typing import Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.frames import check_non_negative, lengths


def capsule_columns(W: int) -> int:
    return 2 * W + 1


def capsule_problem(params: Tensor, W: int) -> str:
    return check_non_negative(params[:, 2 * W], "radius")


def capsule_distance(points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor]:
    """Signed distance from points (M, W) to capsules (K, 2W + 1) (negative
    inside): (M, K), and its gradient with respect to the points (M, K, W). On
    the segment the gradient is 0."""
    W = points.size(1)
    a = params[:, 0:W]
    segment = params[:, W:2 * W] - a                                  # (K, W)
    offset = points.unsqueeze(1) - a.unsqueeze(0)                     # (M, K, W)
    length2 = (segment * segment).sum(-1)                             # (K,)
    along = (offset * segment.unsqueeze(0)).sum(-1) / torch.where(length2 > 0.0, length2, torch.ones_like(length2)).unsqueeze(0)
    along = torch.clamp(along, 0.0, 1.0)                              # (M, K), 0 for a point capsule
    away = offset - along.unsqueeze(-1) * segment.unsqueeze(0)        # from the nearest point of the segment
    length = lengths(away)
    # On the segment away is 0 and so is the quotient.
    return length - params[:, 2 * W].unsqueeze(0), away / length.clamp_min(1e-30).unsqueeze(-1)
