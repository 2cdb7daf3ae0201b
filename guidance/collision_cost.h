#pragma once

#include <memory>

#include "guidance/cost.h"
#include "kinematics/robot.h"

namespace flowplan::guidance {

/// Whole-robot collision cost (SPEC section 2): for every state, every robot
/// collision sphere s (from the robot's kinematics) and every obstacle k,
///   relu(margin + r_s + r_k − ‖c_s − o_k‖),
/// summed over spheres, obstacles and states. The state's first J entries are
/// the robot's positions (joint angles, or a point's coordinates); the rest
/// (velocities) do not enter. Zero far from every obstacle and with K = 0.
class CollisionCost : public Cost {
 public:
  /// @param margin  clearance (world units) below which the hinge starts to count
  CollisionCost(std::shared_ptr<const kinematics::Robot> robot, double margin);

  torch::Tensor Value(const torch::Tensor& x, const torch::Tensor& obstacles) const override;
  CostAndGradient ValueAndGradient(const torch::Tensor& x, const torch::Tensor& obstacles) const override;
  /// Needs the robot's script methods (kinematics::Robot::WriteScript) in the same module.
  void WriteScript(jit::ScriptModule& module, const std::string& name) const override;

 private:
  void Check(const torch::Tensor& x, const torch::Tensor& obstacles) const;

  std::shared_ptr<const kinematics::Robot> robot_;
  double margin_;
};

/// The smallest clearance of each state: min over spheres and obstacles of
/// ‖c_s − o_k‖ − r_s − r_k (negative inside). x: (B, T, D) raw; obstacles
/// (K, W+1), K >= 1 -> (B, T, K) per obstacle.
torch::Tensor SphereClearance(const kinematics::Robot& robot, const torch::Tensor& x, const torch::Tensor& obstacles);

}  // namespace flowplan::guidance
