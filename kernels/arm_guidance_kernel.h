#pragma once

// The guide's gradient for an arm with the built-in cost terms, as one native
// call: what guidance/guide.py's Guide.gradient computes through its cost
// chain (guidance/cost_chain.py) when the chain holds the built-in terms only
// (no user cost) — the whole-arm collision hinge (ArmCollision,
// kernels/arm_collision_kernel.h), the GP smoothness prior
// (guidance/smoothness.py), the joint-limit hinge (guidance/joint_limit.py)
// and the joint-speed hinge (guidance/joint_speed.py), each term's gradient
// capped per state at guidance.clip and weighted, the sum taken through the
// normalizer. On LibTorch's operators a guidance step is some hundred small
// operators of the interpreter's and the operators' fixed cost, two thirds
// of its time once the collision hinge is native (docs/performance.md,
// "The native guidance step"). Registered as the TorchScript operator
// `flowplan::arm_guidance` (kernels/arm_guidance_op.cc); guidance/arm_guide.py
// calls it. Tested against the scripts (tests/guidance/arm_guidance_test.cc).

#include <torch/torch.h>

#include <string>
#include <vector>

#include "kernels/arm_collision_kernel.h"

namespace flowplan::kernels {

/// The weight keys of the terms ArmGuidance computes, in the order of the
/// guide's chain (guidance/guide.cc, kCostTerms). A guide whose chain holds
/// other terms keeps the chain (guide.cc compares the two lists).
const std::vector<std::string>& ArmGuidanceWeightKeys();

/// The settings of the terms, by their config names (guidance.*).
struct GuidanceTerms {
  double collision_weight = 0, margin = 0;                // guidance.collision_weight, guidance.margin
  double smoothness_weight = 0, smoothness_sigma = 1;     // guidance.smoothness_weight, guidance.smoothness_sigma
  double joint_limit_weight = 0, joint_limit_margin = 0;  // guidance.joint_limit_weight, guidance.joint_limit_margin
  double joint_speed_weight = 0, joint_speed_ratio = 1;   // guidance.joint_speed_weight, guidance.joint_speed_ratio
  double clip = 0;                                        // guidance.clip (0: no cap)
};

/// The robot's tables the terms read besides the kinematics: the collision
/// spheres' radii (S,), the joint limits lower, upper (J,) and the velocity
/// limits (J,) (infinite: none), float64 as kinematics/robot.cc keeps them.
struct ArmLimits {
  torch::Tensor sphere_radii, lower, upper, velocity_limit;
};

/// The guidance gradient (B, T, D) with respect to normalized plans x
/// (B, T, D) (float32 or float64, CPU; D = 2J: positions, then velocities),
/// the normalizer's lo, hi (D,), states dt seconds apart, among the obstacles
/// of `kinds` and `rows` (prepared, as ArmCollision takes them): the sum over
/// the terms of weight times the term's gradient [dC/dq, dC/dqd] capped per
/// state at `clip`, times (hi - lo) / 2: the scripts' order of terms and of
/// operations, each product and sum rounded in x's dtype as theirs are, but
/// for the cap's norm, summed in another order (the last bits of a capped
/// state can differ). A term of weight 0 is skipped, as the chain skips it.
/// Every setting of GuidanceTerms must be given (a planner's settings hold
/// them all). No autograd; the result does not depend on the thread count.
/// Throws std::runtime_error naming what is wrong.
torch::Tensor ArmGuidance(const torch::Tensor& x, const torch::Tensor& lo, const torch::Tensor& hi,
                          const ArmTables& arm, const ArmLimits& limits, double dt,
                          const std::vector<std::string>& kinds, const std::vector<torch::Tensor>& rows,
                          const GuidanceTerms& terms);

}  // namespace flowplan::kernels
