# TorchScript (compiled by flowplan at run time, jit/library.h): the Guide's
# native_gradient (guidance/guide.py) for an arm whose cost chain holds the
# built-in terms only (no user cost): the whole guidance gradient in one call
# of the native operator flowplan::arm_guidance (kernels/arm_guidance_kernel.h)
# instead of some hundred LibTorch operators through the chain. What the
# operator does not take (x off the CPU, of another dtype or needing autograd,
# normalizer statistics wider than x, a kind of shape not in native_kinds)
# goes to the chain. Submodule robot (an
# Arm); attributes native_kinds, dt (s between states). A planner saved with
# it loads where libflowplan_kernels is loaded (docs/export.md).

from typing import Dict, List, Optional

import torch
from torch import Tensor
from torch import ops

from flowplan.script.geometry.scene import shape_prepared


class ArmGuide:
    def native_gradient(self, x: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Optional[Tensor]:
        """The guidance gradient (B, T, D) of normalized plans x (B, T, D) in one
        native call, or None where the operator does not take them."""
        normalizer = self.normalizer
        if self.robot.has_slides:  # the operator turns hinges only
            return None
        if x.get_device() >= 0 or not x.is_floating_point() or x.element_size() < 4 or x.requires_grad:
            return None
        # Statistics on another device, or wider than x (float64 with float32 x: the chain's result is float64).
        if normalizer.lo.get_device() >= 0 or normalizer.hi.get_device() >= 0 or normalizer.lo.element_size() > x.element_size():
            return None
        kinds: List[str] = []
        rows: List[Tensor] = []
        for kind, params in scene.items():
            if kind not in self.native_kinds or params.requires_grad:
                return None
            kinds.append(kind)
            rows.append(shape_prepared(kind, params, 3))
        robot = self.robot
        return ops.flowplan.arm_guidance(x, normalizer.lo, normalizer.hi, robot.fixed, robot.fixed_cross,
                                         robot.fixed_cross_sq, robot.link_joint, robot.link_turns, robot.parents,
                                         robot.frame_points, robot.ancestors, robot.sphere_radii, robot.lower,
                                         robot.upper, robot.velocity_limit, self.dt, kinds, rows, opts)
