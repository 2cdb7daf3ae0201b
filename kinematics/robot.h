#pragma once

// A robot's kinematics: a TorchScript module built from a RobotDescription
// (the class Arm of kinematics/arm.py for a tree of hinge joints, the class
// Point of kinematics/point.py for a ball or disc): the kinematics guidance,
// exported planners, inverse kinematics and the reports' scores use. (The
// validity of configurations and motions is collision/checker.h's, on the
// same description; tests hold the two placements to each other and to
// MuJoCo.) Every method is batched; gradients
// flow to q through autograd, and the module also writes out the
// vector–Jacobian products guidance uses (so that exported planners plan under
// torch.inference_mode(), where autograd cannot run).
//
// Shapes: M configurations, J joints, S collision spheres, W workspace dims, K obstacles.

#include <torch/script.h>
#include <torch/torch.h>

#include <memory>
#include <string>

#include "geometry/scene_rows.h"
#include "kinematics/robot_description.h"

namespace flowplan::kinematics {

/// Joint configurations that put the TCP at targets, with what was reached.
struct IkSolution {
  torch::Tensor q;                  // (M, J) rad, float64
  torch::Tensor position_error;     // (M,) m
  torch::Tensor orientation_error;  // (M,) rad
  torch::Tensor converged;          // (M,) bool: within kIkPositionTolerance and kIkOrientationTolerance
};

inline constexpr double kIkPositionTolerance = 1e-5;     // m
inline constexpr double kIkOrientationTolerance = 1e-4;  // rad

/// The damped-least-squares solver's settings (attributes of the module).
struct IkSettings {
  int64_t iterations = 300;
  double damping = 0.05;        // λ (m, rad)
  double max_step = 0.2;        // rad, largest joint change per iteration
  double limit_margin = 0.01;   // rad kept from every joint limit
  double posture_gain = 0.1;    // pull towards home in the task's null space
  double position_tolerance = kIkPositionTolerance;
  double orientation_tolerance = kIkOrientationTolerance;
};

/// Immutable after construction and safe to share between threads.
class Robot {
 public:
  /// @throws flowplan::Error, prefixed by `where`, if the description is inconsistent.
  explicit Robot(const RobotDescription& description, const std::string& where = "robot");

  const RobotDescription& description() const { return description_; }
  int64_t num_joints() const { return description_.num_joints; }        // J
  int64_t workspace_dim() const { return description_.workspace_dim; }  // W
  int64_t num_spheres() const { return description_.num_spheres(); }    // S
  bool is_arm() const { return description_.kind == RobotKind::kArm; }

  /// The TorchScript module (methods tcp, sphere_centres, collision_spheres,
  /// spheres, spheres_vjp, tcp_vjp, ik, ik_solve; see kinematics/arm.py).
  const torch::jit::Module& module() const { return module_; }

  /// Sphere radii (S,), float64.
  torch::Tensor SphereRadii() const;

  /// TCP positions (..., W) of q (..., J); dtype follows q.
  /// @throws flowplan::Error "tcp: q: expected (..., 7), got [3, 6]".
  torch::Tensor Tcp(const torch::Tensor& q) const;

  /// Collision sphere centres (..., S, W) of q (..., J).
  torch::Tensor SphereCentres(const torch::Tensor& q) const;

  /// Whole-robot clearance (M, K) of q (M, J) from every obstacle of `scene`:
  /// the smallest signed distance between a collision sphere and the obstacle
  /// (negative: they overlap). float64.
  torch::Tensor Clearance(const torch::Tensor& q, const geometry::SceneRows& scene) const;

  /// Signed distance (M, K) of points (M, W) to every obstacle of `scene`. float64.
  static torch::Tensor PointClearance(const torch::Tensor& points, const geometry::SceneRows& scene);

  /// Inverse kinematics of TCP positions `targets` (M, W), with the TCP
  /// orientation of the home posture, from `seed` (M, J) (default: home). A
  /// point robot's solution is the target itself. float64.
  /// @throws flowplan::Error if an arm has no home posture.
  IkSolution InverseTcp(const torch::Tensor& targets, const torch::Tensor& seed = torch::Tensor()) const;

 private:
  RobotDescription description_;
  torch::jit::Module module_;
};

/// The kinematics of `description` (an arm or a point).
/// @throws flowplan::Error, prefixed by `where`, if the description is inconsistent.
std::shared_ptr<const Robot> MakeRobot(const RobotDescription& description, const std::string& where = "robot");

}  // namespace flowplan::kinematics
