# TorchScript (compiled by flowplan at run time, jit/library.h): cylinders,
# their axis the local z axis, centred at the centre. Row layout, 3-D (K, 9):
# centre (3), radius, height, orientation quaternion (w, x, y, z). In 2-D a
# cylinder is seen from the side, a rectangle 2·radius wide (local x) and
# `height` long along its axis (local y): (K, 5) centre (2), radius, height,
# angle (rad). The distances also take prepared rows, those columns followed
# by the rotation matrix row by row (cylinder_prepared).

from typing import Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.frames import (
    check_non_negative, check_quaternions, lengths, shape_rotations, sign_of, to_local, to_world, unit_or,
    with_rotation_matrices,
)


def cylinder_columns(W: int) -> int:
    return 9 if W == 3 else 5


def cylinder_problem(params: Tensor, W: int) -> str:
    problem = check_non_negative(params[:, W], "radius")
    if problem != "":
        return problem
    problem = check_non_negative(params[:, W + 1], "height")
    if problem != "":
        return problem
    if W == 3:
        return check_quaternions(params[:, 5:9])
    return ""


def cylinder_prepared(params: Tensor, W: int) -> Tensor:
    """Cylinders (K, cylinder_columns(W)) with their rotation matrices appended (K, cylinder_columns(W) + W W)."""
    return with_rotation_matrices(params, W + 2, W)


def cylinder_parts(points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor, Tensor, Tensor, Tensor, Tensor, Tensor, Tensor, Tensor]:
    """What cylinder_distance computes from points (M, W) and cylinders (K,
    cylinder_columns(W)), distance first: the signed distance (M, K); the
    points' local coordinates across the axis (M, K, W - 1) and along it (M,
    K); their radial distance from the axis (M, K); how far they lie outside
    the mantle (side) and beyond a cap (cap), each > 0 outside (M, K); the
    length of the part outside (M, K); the rotations (K, W, W); and the part
    of side outside (M, K)."""
    W = points.size(1)
    rotations = shape_rotations(params, W + 2, W)
    local = to_local(points, params[:, 0:W], rotations)               # (M, K, W)
    across = local[:, :, 0:W - 1]                                     # (M, K, W - 1)
    along = local[:, :, W - 1]                                        # (M, K)
    radial = lengths(across)                                          # (M, K)
    side = radial - params[:, W].unsqueeze(0)                         # > 0 outside the mantle
    cap = along.abs() - 0.5 * params[:, W + 1].unsqueeze(0)          # > 0 beyond a cap
    outside_side = torch.relu(side)
    outside_cap = torch.relu(cap)
    outside_length = torch.sqrt(outside_side * outside_side + outside_cap * outside_cap)
    distance = outside_length + torch.clamp(torch.max(side, cap), max=0.0)
    return distance, across, along, radial, side, cap, outside_length, rotations, outside_side


def cylinder_distance(points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor]:
    """Signed distance from points (M, W) to cylinders (K, cylinder_columns(W))
    (negative inside): (M, K), and its gradient with respect to the points
    (M, K, W). On the axis the radial direction is taken along local x."""
    W = points.size(1)
    distance, across, along, radial, side, cap, outside_length, rotations, outside_side = cylinder_parts(points, params)
    outside_cap = torch.relu(cap)
    x_axis = torch.zeros([W - 1], dtype=points.dtype, device=points.device)
    x_axis[0] = 1.0
    radial_direction = unit_or(across, radial, x_axis)                # (M, K, W - 1)
    axial_direction = sign_of(along)                                  # (M, K)
    safe_length = torch.where(outside_length > 0.0, outside_length, torch.ones_like(outside_length))
    radial_weight = torch.where(outside_length > 0.0, outside_side / safe_length, (side >= cap).to(points.dtype))
    axial_weight = torch.where(outside_length > 0.0, outside_cap / safe_length, (side < cap).to(points.dtype))
    direction = torch.cat([radial_direction * radial_weight.unsqueeze(-1),
                           (axial_direction * axial_weight).unsqueeze(-1)], -1)
    return distance, to_world(direction, rotations)


def cylinder_distance_only(points: Tensor, params: Tensor) -> Tensor:
    """cylinder_distance's distances (M, K) alone, the same numbers."""
    return cylinder_parts(points, params)[0]
