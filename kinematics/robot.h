#pragma once

// Batched kinematics of a robot in LibTorch: TCP position and collision
// spheres of joint configurations, and the vector–Jacobian product that turns
// a gradient on the sphere centres into a gradient on the joints, written out
// (not taken by autograd) so that guidance works in an exported planner even
// where autograd cannot run (a caller under torch.inference_mode()). Every
// implementation also writes the same functions as TorchScript.
//
// Shapes: N configurations, J joints, S collision spheres, W workspace dims.

#include <torch/torch.h>

#include <memory>

#include "jit/script_writer.h"
#include "kinematics/robot_description.h"

namespace flowplan::kinematics {

/// Sphere centres of a batch of configurations with what their gradient needs.
struct SpherePoses {
  torch::Tensor centres;        // (N, S, W), m
  torch::Tensor joint_axes;     // (N, J, 3), unit hinge axes in the world; arms only
  torch::Tensor joint_origins;  // (N, J, 3), m, a point on each hinge axis; arms only
};

/// A robot's kinematics. Immutable after construction and safe to share between threads.
///
/// WriteScript() adds these methods to an exported module (shapes as above;
/// dtype and device follow q):
///   tcp(q (..., J)) -> (..., W)
///   collision_spheres(q (..., J)) -> (..., S, W + 1): centre and radius of every sphere
///   robot_spheres(q (N, J)) -> (centres, joint_axes, joint_origins) as SpherePoses
///   robot_spheres_vjp(centres, joint_axes, joint_origins, g (N, S, W)) -> (N, J)
///   robot_tcp_vjp(q (N, J), g (N, W)) -> (N, J)
/// the buffer robot_sphere_radii (S,) and the attributes robot (the description
/// as YAML), num_joints and workspace_dim.
class Robot {
 public:
  explicit Robot(RobotDescription description);
  virtual ~Robot() = default;
  Robot(const Robot&) = delete;
  Robot& operator=(const Robot&) = delete;

  const RobotDescription& description() const { return description_; }
  int64_t num_joints() const { return description_.num_joints; }        // J
  int64_t workspace_dim() const { return description_.workspace_dim; }  // W
  int64_t num_spheres() const { return description_.num_spheres(); }    // S

  /// Sphere radii (S,), m.
  torch::Tensor SphereRadii(torch::ScalarType dtype = torch::kFloat64) const { return radii_.to(dtype); }

  /// TCP positions (N, W), m, of configurations q (N, J), float32 or float64.
  /// @throws flowplan::Error "kinematics: q: expected (N, 7), got (3, 6)".
  virtual torch::Tensor Tcp(const torch::Tensor& q) const = 0;

  /// ∂/∂q of Σ ⟨g, Tcp(q)⟩: q (N, J), g (N, W) -> (N, J), written out.
  virtual torch::Tensor TcpVjp(const torch::Tensor& q, const torch::Tensor& g) const = 0;

  /// Sphere centres of q (N, J), with what SpheresVjp needs.
  virtual SpherePoses Spheres(const torch::Tensor& q) const = 0;

  /// ∂/∂q of Σ ⟨grad_centres, centres(q)⟩ at the configurations of `poses`:
  /// grad_centres (N, S, W) -> (N, J).
  virtual torch::Tensor SpheresVjp(const SpherePoses& poses, const torch::Tensor& grad_centres) const = 0;

  /// Adds tcp, collision_spheres, robot_spheres, robot_spheres_vjp and robot_sphere_radii.
  virtual void WriteScript(jit::ScriptModule& module) const = 0;

 protected:
  /// @throws flowplan::Error unless q is (N, J) float32 or float64.
  void CheckJoints(const torch::Tensor& q) const;
  /// The public tcp() and collision_spheres() of the script, written from the
  /// private `robot_tcp(q (N, J)) -> (N, W)` and robot_spheres the subclass adds.
  void WritePublicScript(jit::ScriptModule& module) const;

 private:
  RobotDescription description_;
  torch::Tensor radii_;  // (S,) float64
};

/// The kinematics of `description` (an arm or a point).
/// @throws flowplan::Error, prefixed by `where`, if the description is inconsistent.
std::shared_ptr<const Robot> MakeRobot(const RobotDescription& description, const std::string& where = "robot");

}  // namespace flowplan::kinematics
