# TorchScript (compiled by flowplan at run time, jit/library.h): kinematic
# helpers shared by every robot class.

from typing import Dict

import torch
from torch import Tensor

from flowplan.script.geometry.scene import scene_distance_only


def rotation_vector(m: Tensor) -> Tensor:
    """Rotation vectors (M, 3), axis times angle, of rotations m (M, 3, 3)."""
    v = 0.5 * torch.stack([m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]], 1)
    cosine = 0.5 * (torch.diagonal(m, 0, 1, 2).sum(1) - 1.0)
    sine = torch.norm(v, 2, 1)
    angle = torch.atan2(sine, cosine)
    return v * (angle / sine.clamp_min(1e-12)).unsqueeze(1)


def sphere_clearance(centres: Tensor, radii: Tensor, scene: Dict[str, Tensor]) -> Tensor:
    """Clearance (M, K) of M configurations' collision spheres, centres
    (M, S, W) and radii (S,), from every obstacle of `scene`: the smallest
    signed distance of a sphere's surface to the obstacle (negative: they
    overlap)."""
    M = centres.size(0)
    S = centres.size(1)
    distance = scene_distance_only(centres.reshape(M * S, -1), scene)
    clearance = distance.view(M, S, -1) - radii.to(distance.dtype).view(1, S, 1)
    return clearance.min(1)[0]
