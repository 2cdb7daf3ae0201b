# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# NativeDistances, what geometry/distances.py computes, each kind of shape in
# one call of the native operator flowplan::shape_distance
# (kernels/shape_distance_kernel.h) instead of some twenty LibTorch operators.
# The kinds the operator knows are the attribute native_kinds; any other kind,
# and tensors the CPU operator does not take (on a GPU, of another dtype, or
# needing autograd), go to the kind's script (geometry/scene.py).
# A planner saved with it loads where libflowplan_kernels is loaded
# (docs/export.md).

from typing import Dict, List, Tuple

import torch
from torch import Tensor
from torch import ops

from flowplan.script.geometry.scene import shape_distance, shape_distance_only, shape_prepared


class NativeDistances:
    def native(self, kind: str, points: Tensor, params: Tensor) -> bool:
        """Whether the operator takes this kind and these tensors: a known kind,
        float32 or float64 points on the CPU, nothing that needs autograd."""
        return (kind in self.native_kinds and points.get_device() < 0
                and points.is_floating_point() and points.element_size() >= 4
                and not points.requires_grad and not params.requires_grad)

    def distance(self, points: Tensor, scene: Dict[str, Tensor]) -> Tuple[Tensor, Tensor]:
        """Signed distances (M, K) from points (M, W) to every obstacle of the
        scene, and their gradients with respect to the points (M, K, W)."""
        W = points.size(1)
        distances: List[Tensor] = []
        gradients: List[Tensor] = []
        for kind, params in scene.items():
            if self.native(kind, points, params):
                distance, gradient = ops.flowplan.shape_distance(kind, points, shape_prepared(kind, params, W), True)
            else:
                distance, gradient = shape_distance(kind, points, params.to(points.dtype))
            distances.append(distance)
            gradients.append(gradient)
        if len(distances) == 1:
            return distances[0], gradients[0]
        if len(distances) == 0:
            M = points.size(0)
            return torch.zeros([M, 0], dtype=points.dtype, device=points.device), torch.zeros([M, 0, W], dtype=points.dtype, device=points.device)
        return torch.cat(distances, 1), torch.cat(gradients, 1)

    def distance_only(self, points: Tensor, scene: Dict[str, Tensor]) -> Tensor:
        """The signed distances (M, K) of distance() alone."""
        W = points.size(1)
        distances: List[Tensor] = []
        for kind, params in scene.items():
            if self.native(kind, points, params):
                distances.append(ops.flowplan.shape_distance(kind, points, shape_prepared(kind, params, W), False)[0])
            else:
                distances.append(shape_distance_only(kind, points, params.to(points.dtype)))
        if len(distances) == 0:
            return torch.zeros([points.size(0), 0], dtype=points.dtype, device=points.device)
        return distances[0] if len(distances) == 1 else torch.cat(distances, 1)
