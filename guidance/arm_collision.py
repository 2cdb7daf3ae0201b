# TorchScript (compiled by flowplan at run time, jit/library.h): the class
# ArmCollisionCost, guidance/collision.py's whole-robot collision hinge for an
# arm of hinge joints (kinematics/arm.py), its value and gradient for a whole
# plan in one call of the native operator flowplan::arm_collision
# (kernels/arm_collision_kernel.h) instead of some two hundred LibTorch
# operators. What the operator does not take (a kind of shape not in
# native_kinds, tensors off the CPU, of another dtype or needing autograd)
# goes to the script. Submodules robot (an Arm) and scripted (the
# CollisionCost it stands for); attributes native_kinds, weight_key. A planner
# saved with it loads where libflowplan_kernels is loaded (docs/export.md).
# Shapes: B trajectories, T states, J joints, S spheres.

from typing import Dict, List, Tuple

import torch
from torch import Tensor
from torch import ops

from flowplan.script.geometry.scene import scene_size, shape_prepared


class ArmCollisionCost:
    def active(self, scene: Dict[str, Tensor], opts: Dict[str, float]) -> bool:
        return self.scripted.active(scene, opts)

    def autograd_source(self, opts: Dict[str, float]) -> str:
        return ""

    def native(self, q: Tensor, scene: Dict[str, Tensor]) -> bool:
        """Whether the operator takes these tensors: float32 or float64 q on the
        CPU, nothing that needs autograd, only kinds it knows, an arm of hinges only."""
        if q.get_device() >= 0 or not q.is_floating_point() or q.element_size() < 4 or q.requires_grad:
            return False
        if self.robot.has_slides:  # the operator turns hinges only
            return False
        for kind, params in scene.items():
            if kind not in self.native_kinds or params.requires_grad:
                return False
        return True

    def value_and_gradient(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor], opts: Dict[str, float]) -> Tuple[Tensor, Tensor, Tensor]:
        """q, qd (B, T, J) raw -> C (B,), dC/dq (B, T, J), dC/dqd (B, T, J)."""
        if scene_size(scene) == 0 or not self.native(q, scene):
            return self.scripted.value_and_gradient(q, qd, scene, opts)
        B = q.size(0)
        T = q.size(1)
        J = q.size(2)
        kinds: List[str] = []
        rows: List[Tensor] = []
        for kind, params in scene.items():
            kinds.append(kind)
            rows.append(shape_prepared(kind, params, 3))
        robot = self.robot
        reach = opts["guidance.margin"] + robot.sphere_radii.to(q.dtype)
        value, grad_q = ops.flowplan.arm_collision(q.reshape(B * T, J), robot.fixed, robot.fixed_cross, robot.fixed_cross_sq,
                                                   robot.link_joint, robot.link_turns, robot.parents, robot.frame_points,
                                                   robot.ancestors, reach, kinds, rows, True)
        return value.view(B, T).sum(1), grad_q.view(B, T, J), torch.zeros_like(qd)
