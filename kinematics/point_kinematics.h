#pragma once

#include "kinematics/robot.h"

namespace flowplan::kinematics {

/// A ball or disc whose centre is the configuration itself: TCP = q, one
/// collision sphere of radius point_radius at q (W = J).
class PointKinematics : public Robot {
 public:
  explicit PointKinematics(const RobotDescription& description) : Robot(description) {}

  torch::Tensor Tcp(const torch::Tensor& q) const override;
  torch::Tensor TcpVjp(const torch::Tensor& q, const torch::Tensor& g) const override;
  SpherePoses Spheres(const torch::Tensor& q) const override;
  torch::Tensor SpheresVjp(const SpherePoses& poses, const torch::Tensor& grad_centres) const override;
  void WriteScript(jit::ScriptModule& module) const override;
};

}  // namespace flowplan::kinematics
