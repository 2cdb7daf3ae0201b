# TorchScript (compiled by flowplan at run time, jit/library.h): boxes (rotated
# rectangles in 2-D). Row layout, 3-D (K, 10): centre (3), full side lengths
# (3), orientation quaternion (w, x, y, z); 2-D (K, 5): centre (2), side
# lengths (2), angle (rad). The distances also take prepared rows, those
# columns followed by the rotation matrix row by row (box_prepared).

from typing import Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.frames import (
    check_non_negative, check_quaternions, largest, lengths, shape_rotations, sign_of, to_local, to_world,
    with_rotation_matrices,
)


def box_columns(W: int) -> int:
    return 10 if W == 3 else 5


def box_problem(params: Tensor, W: int) -> str:
    for i in range(W):
        problem = check_non_negative(params[:, W + i], "size")
        if problem != "":
            return problem
    if W == 3:
        return check_quaternions(params[:, 6:10])
    return ""


def box_prepared(params: Tensor, W: int) -> Tensor:
    """Boxes (K, box_columns(W)) with their rotation matrices appended (K, box_columns(W) + W W)."""
    return with_rotation_matrices(params, 2 * W, W)


def box_frame(points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor, Tensor]:
    """Points (M, W) in the frames of boxes (K, box_columns(W)): (M, K, W); the
    per-axis gap beyond the half side lengths, > 0 outside that slab: (M, K, W);
    and the rotations, local to world (K, W, W)."""
    W = points.size(1)
    rotations = shape_rotations(params, 2 * W, W)
    local = to_local(points, params[:, 0:W], rotations)
    gap = local.abs() - 0.5 * params[:, W:2 * W].unsqueeze(0)
    return local, gap, rotations


def box_outside(gap: Tensor) -> Tuple[Tensor, Tensor, Tensor]:
    """From box_frame's gap (M, K, W): the signed distance (M, K), the gap's
    part outside the box (M, K, W) and its length (M, K)."""
    outside = torch.relu(gap)
    outside_length = lengths(outside)
    return outside_length + torch.clamp(largest(gap), max=0.0), outside, outside_length


def box_distance(points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor]:
    """Signed distance from points (M, W) to boxes (K, box_columns(W)) (negative
    inside): (M, K), and its gradient with respect to the points (M, K, W):
    outside, the direction from the nearest surface point; inside, the normal of
    the nearest face."""
    local, gap, rotations = box_frame(points, params)
    distance, outside, outside_length = box_outside(gap)
    face = torch.argmax(gap, -1)                                        # the axis of the deepest gap, the nearest face's
    towards_outside = outside / torch.where(outside_length > 0.0, outside_length, torch.ones_like(outside_length)).unsqueeze(-1)
    face_normal = torch.zeros_like(gap).scatter_(-1, face.unsqueeze(-1), 1.0)
    direction = torch.where((outside_length > 0.0).unsqueeze(-1), towards_outside, face_normal) * sign_of(local)
    return distance, to_world(direction, rotations)


def box_distance_only(points: Tensor, params: Tensor) -> Tensor:
    """box_distance's distances (M, K) alone, the same numbers."""
    return box_outside(box_frame(points, params)[1])[0]
