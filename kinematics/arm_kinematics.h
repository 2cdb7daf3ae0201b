#pragma once

// Batched, differentiable forward kinematics of a tree of hinge joints (the
// Franka), from a RobotDescription. Only tensor operations: no MuJoCo at run
// time; gradients flow to q through autograd, and SpheresVjp gives the same
// gradient by the formula ∂c/∂q_j = a_j × (c − p_j) without autograd.
//
// Shapes: B (or N) configurations, J joints, L links, S collision spheres.

#include <torch/torch.h>

#include <string>
#include <vector>

#include "kinematics/robot.h"

namespace flowplan::kinematics {

/// Everything one forward pass computes; the dtype and device are q's.
struct FkResult {
  torch::Tensor link_frames;     // (B, L, 4, 4), link poses in the world (homogeneous, m)
  torch::Tensor tcp_position;    // (B, 3), m
  torch::Tensor sphere_centres;  // (B, S, 3), m
  torch::Tensor joint_axes;      // (B, J, 3), unit hinge axes in the world
  torch::Tensor joint_origins;   // (B, J, 3), m, origins of the links the hinges turn
};

/// Joint configurations that put the TCP at targets, with what was reached.
struct IkSolution {
  torch::Tensor q;                  // (N, J) rad
  torch::Tensor position_error;     // (N,) m
  torch::Tensor orientation_error;  // (N,) rad
  torch::Tensor converged;          // (N,) bool: within kIkPositionTolerance and kIkOrientationTolerance
};

inline constexpr double kIkPositionTolerance = 1e-5;     // m
inline constexpr double kIkOrientationTolerance = 1e-4;  // rad

class ArmKinematics : public Robot {
 public:
  /// @throws flowplan::Error if the description is not a consistent arm.
  explicit ArmKinematics(const RobotDescription& description);

  /// Link frames, TCP position, sphere centres and hinge axes for joint angles
  /// `q` (B, J) in rad, float32 or float64 on any device; gradients flow to q.
  /// @throws flowplan::Error "kinematics: q: expected (N, 7), got (3, 6)" for a
  ///   wrong shape, and for a non-floating dtype.
  FkResult Forward(const torch::Tensor& q) const;

  torch::Tensor Tcp(const torch::Tensor& q) const override;
  torch::Tensor TcpVjp(const torch::Tensor& q, const torch::Tensor& g) const override;
  SpherePoses Spheres(const torch::Tensor& q) const override;
  torch::Tensor SpheresVjp(const SpherePoses& poses, const torch::Tensor& grad_centres) const override;
  void WriteScript(jit::ScriptModule& module) const override;

  /// Inverse kinematics of TCP positions `targets` (N, 3), m, with the TCP
  /// orientation it has at the description's home posture (the Franka's: the
  /// gripper pointing down), by damped least squares (λ 0.05, steps of at most
  /// 0.2 rad, joints 0.01 rad inside their limits) from home with a pull
  /// towards home in the task's null space: the solver of sim/franka_ik.h, in
  /// LibTorch and in the exported script (`ik`). float64.
  /// @throws flowplan::Error if the description has no home posture.
  IkSolution InverseTcp(const torch::Tensor& targets) const;

  /// Link index of every sphere (S,), int64.
  const torch::Tensor& sphere_links() const { return sphere_links_; }
  int64_t num_links() const { return static_cast<int64_t>(parents_.size()); }
  const std::vector<std::string>& link_names() const { return link_names_; }

 private:
  /// The link frames as a list of L tensors (B, 4, 4).
  std::vector<torch::Tensor> LinkFrames(const torch::Tensor& q) const;
  torch::Tensor TcpFrom(const std::vector<torch::Tensor>& frames, const torch::Tensor& q) const;
  torch::Tensor TcpFrame(const std::vector<torch::Tensor>& frames, const torch::Tensor& q) const;  // (B, 4, 4)

  std::vector<std::string> link_names_;
  std::vector<int64_t> parents_;  // (L,), -1: world
  std::vector<int64_t> joints_;   // (L,), -1: welded
  int64_t tcp_link_ = -1;
  // Constants in float64 on the CPU; converted to q's dtype and device per call.
  torch::Tensor fixed_;          // (L, 4, 4), pose in the parent at q = 0
  torch::Tensor axis_cross_;     // (L, 4, 4), [axis]× padded to 4×4
  torch::Tensor axis_cross_sq_;  // (L, 4, 4), ([axis]×)² padded to 4×4
  torch::Tensor tcp_;            // (4, 4), TCP pose in its link
  torch::Tensor sphere_links_;   // (S,), int64
  torch::Tensor sphere_local_;   // (S, 3), m, centres in their link frames
  torch::Tensor joint_links_;    // (J,), int64, the link each joint turns
  torch::Tensor joint_axes_;     // (J, 3), unit hinge axes in their link frames
  torch::Tensor ancestors_;      // (J, S), 1 where joint j moves sphere s
  torch::Tensor tcp_ancestors_;  // (J,), 1 where joint j moves the TCP
};

}  // namespace flowplan::kinematics
