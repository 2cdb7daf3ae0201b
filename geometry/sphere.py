# TorchScript (compiled by flowplan at run time, jit/library.h): spherical
# obstacles (discs in 2-D). Row layout (K, W + 1): centre (W), radius.

from typing import Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.frames import check_non_negative, lengths


def sphere_columns(W: int) -> int:
    return W + 1


def sphere_problem(params: Tensor, W: int) -> str:
    """'' if the rows (K, W + 1) describe spheres, else what is wrong with which row."""
    return check_non_negative(params[:, W], "radius")


def sphere_distance(points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor]:
    """Signed distance from points (M, W) to spheres (K, W + 1) (negative inside):
    (M, K), and its gradient with respect to the points (M, K, W). At a centre
    the gradient is 0."""
    W = points.size(1)
    offset = points.unsqueeze(1) - params[:, 0:W].unsqueeze(0)
    length = lengths(offset)
    # At a centre offset is 0 and so is the quotient.
    return length - params[:, W].unsqueeze(0), offset * torch.reciprocal(length.clamp_min(1e-30)).unsqueeze(-1)


def sphere_distance_only(points: Tensor, params: Tensor) -> Tensor:
    """The distances (M, K) of sphere_distance without their gradient, in one
    pass of torch.cdist over exact differences (mode 2: not the matrix-product
    expansion, which loses digits near a surface); no (M, K, W) intermediate."""
    W = points.size(1)
    return torch.cdist(points, params[:, 0:W], 2.0, 2) - params[:, W].unsqueeze(0)
