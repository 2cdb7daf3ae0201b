#pragma once

// An arm's collision against a scene's obstacles as native loops: the hinge
// of guidance, and the nearest obstacles of the plan checker and RRT-Connect.
//
// The whole-arm collision hinge of guidance (guidance/collision.py) for an
// arm of hinge joints (kinematics/arm.py), as one native loop over a plan's
// configurations: the link frames, the collision spheres' centres, every
// sphere's signed distance to every obstacle, the hinge
//   C(q) = sum over spheres s and obstacles k of relu(reach_s - d_k(c_s(q)))
// and its gradient with respect to the joint angles, written out as the
// script writes it (Arm.spheres_vjp). A guidance step on LibTorch's
// operators runs some two hundred of them, most of their time the
// interpreter's and the operators' fixed cost (docs/performance.md, "The
// native collision cost"). Registered as the TorchScript operator
// `flowplan::arm_collision` (kernels/arm_collision_op.cc); the cost class of
// guidance/arm_collision.py calls it. Tested against the scripts
// (tests/guidance/arm_collision_test.cc, tests/kinematics/robot_test.cc).

#include <torch/torch.h>

#include <string>
#include <tuple>
#include <vector>

namespace flowplan::kernels {

/// The kinematic tables of an arm, the buffers of kinematics/arm.py's class
/// Arm (that file documents them): L links, J joints, S collision spheres.
struct ArmTables {
  torch::Tensor fixed;           // (L, 4, 4) each link's pose in its parent at q = 0
  torch::Tensor fixed_cross;     // (L, 4, 4) fixed times [a]x of the link's hinge axis
  torch::Tensor fixed_cross_sq;  // (L, 4, 4) fixed times [a]x^2
  torch::Tensor link_joint;      // (L,) int64 the joint turning each link
  torch::Tensor link_turns;      // (L,) 1 for a turned link, 0 for a welded one
  std::vector<int64_t> parents;  // (L) each link's parent, -1 for the root
  torch::Tensor frame_points;    // (4 L, S + 2 J) points fixed in the links: sphere centres, hinge axes, hinge points
  torch::Tensor ancestors;       // (J, S) 1 where joint j moves sphere s
};

/// The shape kinds ArmCollision knows (geometry/scene.py's names);
/// callers send scenes with any other kind to the scripts.
const std::vector<std::string>& ArmCollisionKinds();

/// The hinge C (M,) of configurations q (M, J) (float32 or float64, CPU) with
/// the spheres' reach (S,) (the guidance margin plus each radius) against
/// the obstacles of `kinds` (geometry/scene.py's names, each at most once)
/// with their `rows` (K_i, columns) (boxes and cylinders prepared, as
/// prepared_scene leaves them; converted to q's dtype); and, if
/// `with_gradient`, dC/dq (M, J), else an empty tensor. Each obstacle's
/// distances to a chunk of configurations' sphere centres are one vectorised
/// loop; the gradients are taken at the active pairs alone; a NaN
/// configuration's C is NaN, as the script's. Chunks of configurations run in
/// parallel on LibTorch's intra-op threads, and each configuration's numbers
/// depend on it alone, so the result does not depend on the thread count. No
/// autograd. Throws std::runtime_error naming what is wrong (a
/// shape, a dtype, a kind, rows of the wrong width).
std::tuple<torch::Tensor, torch::Tensor> ArmCollision(const torch::Tensor& q, const ArmTables& arm,
                                                      const torch::Tensor& reach,
                                                      const std::vector<std::string>& kinds,
                                                      const std::vector<torch::Tensor>& rows, bool with_gradient);

}  // namespace flowplan::kernels
