# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# Distances, the distance passes of guidance (guidance/collision.py) with
# LibTorch's operators only: geometry/scene.py's scene_distance and
# scene_distance_only. A planner saved with it needs nothing but PyTorch.
# geometry/native_distances.py computes the same with native kernels.

from typing import Dict, Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.scene import scene_distance, scene_distance_only


class Distances:
    def distance(self, points: Tensor, scene: Dict[str, Tensor]) -> Tuple[Tensor, Tensor]:
        """Signed distances (M, K) from points (M, W) to every obstacle of the
        scene, and their gradients with respect to the points (M, K, W)."""
        return scene_distance(points, scene)

    def distance_only(self, points: Tensor, scene: Dict[str, Tensor]) -> Tensor:
        """The signed distances (M, K) of distance() alone."""
        return scene_distance_only(points, scene)
