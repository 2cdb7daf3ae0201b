#pragma once

// A plain-data description of a robot's kinematic tree and its collision
// spheres, extracted once from a compiled MuJoCo model (see
// DescribeKinematics in sim/franka_model.h). It has no MuJoCo types, so
// code that must not call MuJoCo at run time (the LibTorch kinematics in
// kinematics/) builds from it: the MJCF stays the one geometry source.

#include <array>
#include <string>
#include <vector>

namespace flowplan::sim {

/// One rigid body of the tree. Its pose in the world is
///   X_body = X_parent · Trans(pos) · Rot(quat) · Rot(axis, q[joint]),
/// with q[joint] omitted for a welded body (joint == -1).
struct KinematicLink {
  std::string name;
  int parent = -1;                            // index into KinematicDescription::links; -1: world
  std::array<double, 3> pos{0.0, 0.0, 0.0};   // m, origin in the parent frame at q = 0
  std::array<double, 4> quat{1.0, 0.0, 0.0, 0.0};  // (w, x, y, z), orientation in the parent frame
  int joint = -1;                             // index into q of the hinge turning this body; -1: welded
  std::array<double, 3> axis{0.0, 0.0, 1.0};  // unit hinge axis through the body origin, body frame
};

/// A sphere fixed to one link.
struct CollisionSphere {
  int link = -1;                                 // index into KinematicDescription::links
  std::array<double, 3> centre{0.0, 0.0, 0.0};   // m, in the link frame
  double radius = 0.0;                           // m
  std::string geom;                              // the collision geom it was made from
};

/// Links L (parents before children), joints J, collision spheres S.
struct KinematicDescription {
  std::vector<KinematicLink> links;     // (L,)
  int num_joints = 0;                   // J; links with joint >= 0 use each index once
  std::vector<double> joint_lower;      // (J,) rad
  std::vector<double> joint_upper;      // (J,) rad
  int tcp_link = -1;                    // link that carries the tool centre point
  std::array<double, 3> tcp_pos{0.0, 0.0, 0.0};        // m, TCP origin in that link's frame
  std::array<double, 4> tcp_quat{1.0, 0.0, 0.0, 0.0};  // (w, x, y, z), TCP orientation there
  std::vector<CollisionSphere> spheres;  // (S,)

  /// Index of the link called `name`, or -1.
  int FindLink(const std::string& name) const {
    for (size_t i = 0; i < links.size(); ++i) {
      if (links[i].name == name) return static_cast<int>(i);
    }
    return -1;
  }
};

}  // namespace flowplan::sim
