#pragma once

// Batched, differentiable forward kinematics in LibTorch, built from the
// plain kinematic description that sim/ extracts from the MJCF model (one
// geometry source). Only tensor operations: no MuJoCo at run time, usable in
// guidance costs and expressible in TorchScript.
//
// Shapes follow the glossary of docs/architecture.md: B batch, J joints,
// L links, S collision spheres.

#include <torch/torch.h>

#include <string>
#include <vector>

#include "sim/kinematic_description.h"

namespace flowplan::kinematics {

/// Everything one forward pass computes; the dtype and device are q's.
struct FkResult {
  torch::Tensor link_frames;     // (B, L, 4, 4), link poses in the world (homogeneous, m)
  torch::Tensor tcp_position;    // (B, 3), m
  torch::Tensor sphere_centres;  // (B, S, 3), m
};

/// Forward kinematics of a tree of hinge joints. Immutable after construction
/// and safe to share between threads.
class ForwardKinematics {
 public:
  /// @throws flowplan::Error if the description is inconsistent (a parent after
  ///   its child, a joint index outside [0, J), a sphere on no link).
  explicit ForwardKinematics(const sim::KinematicDescription& description);

  /// Link frames, TCP position and sphere centres for joint angles `q`
  /// (B, J) in rad, float32 or float64 on any device; gradients flow to q.
  /// @throws flowplan::Error "kinematics: q: expected (B, 7), got (3, 6)" for a
  ///   wrong shape, and for a non-floating dtype.
  FkResult Forward(const torch::Tensor& q) const;

  /// TCP position (B, 3), m, for q (B, J).
  torch::Tensor TcpPosition(const torch::Tensor& q) const;

  /// Collision sphere centres (B, S, 3), m, for q (B, J).
  torch::Tensor SphereCentres(const torch::Tensor& q) const;

  /// Sphere radii (S,), m, in `dtype`.
  torch::Tensor SphereRadii(torch::ScalarType dtype = torch::kFloat64) const;

  /// Link index of every sphere (S,), int64.
  const torch::Tensor& sphere_links() const { return sphere_links_; }

  int64_t num_joints() const { return num_joints_; }
  int64_t num_links() const { return static_cast<int64_t>(parents_.size()); }
  int64_t num_spheres() const { return sphere_radii_.size(0); }
  const std::vector<std::string>& link_names() const { return link_names_; }

 private:
  /// The link frames as a list of L tensors (B, 4, 4).
  std::vector<torch::Tensor> LinkFrames(const torch::Tensor& q) const;
  void CheckJoints(const torch::Tensor& q) const;

  int64_t num_joints_ = 0;
  std::vector<std::string> link_names_;
  std::vector<int64_t> parents_;       // (L,), -1: world
  std::vector<int64_t> joints_;        // (L,), -1: welded
  int64_t tcp_link_ = -1;
  // Constants in float64 on the CPU; converted to q's dtype and device per call.
  torch::Tensor fixed_;           // (L, 4, 4), pose in the parent at q = 0
  torch::Tensor axis_cross_;      // (L, 4, 4), [axis]× padded to 4×4
  torch::Tensor axis_cross_sq_;   // (L, 4, 4), ([axis]×)² padded to 4×4
  torch::Tensor tcp_;             // (4, 4), TCP pose in its link
  torch::Tensor sphere_links_;    // (S,), int64
  torch::Tensor sphere_local_;    // (S, 3), m, centres in their link frames
  torch::Tensor sphere_radii_;    // (S,), m
};

}  // namespace flowplan::kinematics
