#pragma once

// A plain-data description of a robot for planning: which state dimensions
// are its joint positions, its kinematic tree, its tool centre point (TCP) and
// its collision spheres. No MuJoCo and no LibTorch types: datasets, checkpoints
// and exported planners carry it as YAML text (RobotToYaml), the LibTorch
// kinematics (kinematics/robot.h) are built from it, and sim/ extracts the
// Franka's from its MJCF model (sim::DescribeKinematics), the one geometry
// source, which tests tie back to MuJoCo.
//
// Two kinds of robot:
//  - kArm: a tree of links moved by revolute and prismatic joints; the state's
//    first J entries are the joint values (rad or m); the TCP and the spheres
//    ride on links.
//  - kPoint: a ball (or disc, W = 2) of radius `point_radius` whose centre is the
//    state's first J = W entries (m); its TCP is that centre.

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "core/config.h"

namespace flowplan::kinematics {

enum class RobotKind { kArm, kPoint };

inline const config::EnumNames<RobotKind>& EnumEntries(RobotKind) {
  static const config::EnumNames<RobotKind> names = {{RobotKind::kArm, "arm"}, {RobotKind::kPoint, "point"}};
  return names;
}

/// How a link moves in its parent: turning about its axis (rad) or sliding along it (m).
enum class JointType { kRevolute, kPrismatic };

inline const config::EnumNames<JointType>& EnumEntries(JointType) {
  static const config::EnumNames<JointType> names = {{JointType::kRevolute, "revolute"},
                                                     {JointType::kPrismatic, "prismatic"}};
  return names;
}

/// One rigid body of the tree. Its pose in the world is
///   X_link = X_parent · Trans(pos) · Rot(quat) · Motion(axis, v),
/// where Motion turns about the axis through the link origin by v (revolute)
/// or slides along it by v (prismatic), and v is q[joint] for a planned joint
/// and `offset` for a link that is not planned (joint == -1): welded where
/// offset is 0, held at a value otherwise (a gripper's fingers held open).
struct RobotLink {
  std::string name;
  int parent = -1;                                 // index into RobotDescription::links; -1: world
  std::array<double, 3> pos{0.0, 0.0, 0.0};        // m, origin in the parent frame at q = 0
  std::array<double, 4> quat{1.0, 0.0, 0.0, 0.0};  // (w, x, y, z), orientation in the parent frame
  int joint = -1;                                  // index into q of the joint moving this link; -1: not planned
  std::array<double, 3> axis{0.0, 0.0, 1.0};       // joint axis through the link origin, link frame
  JointType type = JointType::kRevolute;           // how the joint moves the link
  double offset = 0.0;                             // joint == -1: the value the link is held at (rad or m)
  std::string joint_name;                          // the joint's name in the robot's files (MoveIt, URDF); may be empty

  template <class V>
  void Visit(V& v) {
    v.Field("name", name, "link name");
    v.Field("parent", parent, "index of the parent link, -1 for the world", config::AtLeast(-1));
    v.Field("pos", pos, "origin in the parent frame at q = 0 (m)");
    v.Field("quat", quat, "orientation in the parent frame (w, x, y, z)");
    v.Field("joint", joint, "index of the planned joint moving the link, -1 if not planned", config::AtLeast(-1));
    v.Field("axis", axis, "joint axis in the link frame");
    v.Field("type", type, "how the joint moves the link");
    v.Field("offset", offset, "a link that is not planned: the joint value it is held at (0: welded)");
    v.Field("joint_name", joint_name, "the joint's name in the robot's own files");
  }

  /// Whether the link moves against its parent at all (planned, or held away from 0).
  bool moves() const { return joint >= 0 || offset != 0.0; }
};

/// A collision sphere fixed to one link of an arm.
struct RobotSphere {
  int link = -1;                                // index into RobotDescription::links
  std::array<double, 3> centre{0.0, 0.0, 0.0};  // m, in the link frame
  double radius = 0.0;                          // m
  std::string geom;                             // the collision geometry it was made from

  template <class V>
  void Visit(V& v) {
    v.Field("link", link, "index of the link carrying the sphere", config::NonNegative());
    v.Field("centre", centre, "centre in the link frame (m)");
    v.Field("radius", radius, "radius (m)", config::NonNegative());
    v.Field("geom", geom, "collision geometry it was made from");
  }
};

/// Links L (parents before children), joints J, collision spheres S, workspace dimension W.
struct RobotDescription {
  std::string name;                       // e.g. "franka_panda", "particle_disc"
  RobotKind kind = RobotKind::kArm;
  int workspace_dim = 3;                  // W: 3 for an arm, 2 or 3 for a point
  int num_joints = 0;                     // J: the state's first J entries are the positions
  std::vector<double> joint_lower;        // (J,) rad (arm) or m (point)
  std::vector<double> joint_upper;        // (J,)
  std::vector<double> velocity_limit;     // (J,) rad/s (arm) or m/s (point); empty: none
  std::vector<double> home;               // (J,) arm: the posture inverse kinematics starts from and keeps
                                          // to; a TCP target is reached with the TCP orientation of home
  std::vector<RobotLink> links;           // (L,), arm only
  int tcp_link = -1;                      // arm: link that carries the TCP
  std::array<double, 3> tcp_pos{0.0, 0.0, 0.0};        // m, TCP origin in that link's frame
  std::array<double, 4> tcp_quat{1.0, 0.0, 0.0, 0.0};  // (w, x, y, z), TCP orientation there
  std::vector<RobotSphere> spheres;       // (S,), arm only
  double point_radius = 0.0;              // point only: radius of the ball or disc (m)
  bool self_collision = false;            // arm: whether spheres of different links may not overlap
  std::vector<std::array<std::string, 2>> self_collision_ignore;  // arm: link pairs never checked against each other
  std::vector<std::string> floor_exempt;  // arm: links not checked against a floor (they stand on it)

  template <class V>
  void Visit(V& v) {
    v.Field("name", name, "robot name");
    v.Field("kind", kind, "kind of robot");
    v.Field("workspace_dim", workspace_dim, "dimension of the workspace (2 or 3)", config::InRange(2, 3));
    v.Field("num_joints", num_joints, "number of position entries at the start of the state", config::Positive());
    const config::Bounds any{-INFINITY, INFINITY, false, false, "a number or -.inf / .inf", true};
    v.Field("joint_lower", joint_lower, "lower position limits (-.inf: none)", any);
    v.Field("joint_upper", joint_upper, "upper position limits (.inf: none)", any);
    v.Field("velocity_limit", velocity_limit, "speed limit per joint, empty for none", config::Positive());
    v.Field("home", home, "arm: posture that inverse kinematics starts from and keeps to (rad)");
    v.Field("links", links, "arm: kinematic tree, parents first");
    v.Field("tcp_link", tcp_link, "arm: index of the link carrying the tool centre point", config::AtLeast(-1));
    v.Field("tcp_pos", tcp_pos, "arm: TCP origin in its link frame (m)");
    v.Field("tcp_quat", tcp_quat, "arm: TCP orientation in its link frame (w, x, y, z)");
    v.Field("spheres", spheres, "arm: collision spheres");
    v.Field("point_radius", point_radius, "point: radius of the ball or disc (m)", config::NonNegative());
    v.Field("self_collision", self_collision, "arm: spheres of different links must not overlap");
    v.Field("self_collision_ignore", self_collision_ignore,
            "arm: pairs of link names never checked against each other (neighbours, and pairs that touch anyway)");
    v.Field("floor_exempt", floor_exempt, "arm: links not checked against a floor (the base that stands on it)");
  }

  /// Number of collision spheres S (1 for a point robot).
  int num_spheres() const { return kind == RobotKind::kPoint ? 1 : static_cast<int>(spheres.size()); }

  /// Index of the link called `name`, or -1.
  int FindLink(const std::string& name) const;

  /// Index of the planned joint called `name` (RobotLink::joint_name), or -1.
  int FindJoint(const std::string& name) const;

  /// The name of planned joint j: its link's joint_name, or "joint j+1" when it has none.
  std::string JointName(int j) const;

  /// @throws flowplan::Error, prefixed by `where`, if the description is
  ///   inconsistent: a parent after its child, a joint index outside [0, J) or
  ///   used twice, a sphere or the TCP on no link, limits of the wrong size, a
  ///   point robot whose J is not W.
  void Validate(const std::string& where) const;
};

/// The pose in its parent of a link that is not planned (joint == -1), with
/// the motion it is held at folded in: Trans(pos) · Rot(quat) · Motion(axis,
/// offset) as a position and a (w, x, y, z) quaternion. A planned link's pos and quat.
void FixedPose(const RobotLink& link, std::array<double, 3>& pos, std::array<double, 4>& quat);

/// A collision sphere of a robot file, on a link named by its name.
struct NamedSphere {
  std::string link;
  std::array<double, 3> centre{0.0, 0.0, 0.0};  // m, in the link frame
  double radius = 0.0;                          // m

  template <class V>
  void Visit(V& v) {
    v.Field("link", link, "name of the link carrying the sphere");
    v.Field("centre", centre, "centre in the link frame (m)");
    v.Field("radius", radius, "radius (m)", config::Positive());
  }
};

/// A link pair never checked against each other, and why (adjacent, default,
/// always, never: collision/self_pairs.h; or by hand).
struct IgnoredLinkPair {
  std::array<std::string, 2> links;
  std::string reason;

  template <class V>
  void Visit(V& v) {
    v.Field("links", links, "the two links' names");
    v.Field("reason", reason, "why they are not checked");
  }
};

/// A robot's collision body as a file gives it, by link names: what a robot
/// folder's robot.yaml holds under `collision` (hand-editable; docs/robots.md).
struct CollisionBody {
  std::vector<NamedSphere> spheres;
  bool self_collision = true;
  std::vector<IgnoredLinkPair> self_collision_ignore;
  std::vector<std::string> floor_exempt;

  template <class V>
  void Visit(V& v) {
    v.Field("spheres", spheres, "collision spheres: [{link, centre, radius}]");
    v.Field("self_collision", self_collision, "spheres of different links must not overlap");
    v.Field("self_collision_ignore", self_collision_ignore, "link pairs never checked: [{links: [a, b], reason}]");
    v.Field("floor_exempt", floor_exempt, "links not checked against a floor");
  }
};

/// Replaces the spheres, self-collision settings and floor exemptions of
/// `robot` by those of `body`. `source` names the file in errors.
/// @throws flowplan::Error naming a link the robot does not have.
void ApplyCollisionBody(const CollisionBody& body, RobotDescription& robot, const std::string& source);

/// The collision body of `robot`, by link names.
CollisionBody CollisionBodyOf(const RobotDescription& robot);

/// The description as YAML text (reads back to the same values, bit for bit).
std::string RobotToYaml(const RobotDescription& robot);

/// Parses and validates RobotToYaml() text; `source` names it in errors.
/// @throws flowplan::Error naming the source and the key at fault.
RobotDescription RobotFromYaml(const std::string& yaml, const std::string& source);

/// A ball (W = 3) or disc (W = 2) of radius `radius` whose centre is the
/// state's first W entries, within [lower, upper] per axis.
RobotDescription PointRobot(const std::string& name, int workspace_dim, double radius, double lower, double upper);

}  // namespace flowplan::kinematics
