#pragma once

// A robot's collision body as plain arrays: its links, the collision spheres
// they carry, a bounding sphere per link, which link pairs are checked against
// each other and against a floor, and how far each sphere can move along a
// joint-space segment. Built once from a RobotDescription; immutable and safe
// to share between threads. What the one validity check of flowplan
// (collision/checker.h) runs on: no LibTorch, no MuJoCo, no allocation per call.
//
// An arm's link poses follow RobotDescription:
//   X_link = X_parent · Trans(pos) · Rot(quat) · Motion(axis, v)
// (kinematics/robot_description.h); a point robot is one sphere whose centre
// is the state's first W entries.
//
// Shapes: J joints, L links, S collision spheres, W workspace dimensions (2 or 3).

#include <array>
#include <map>
#include <string>
#include <vector>

#include "kinematics/robot_description.h"

namespace flowplan::collision {

/// `robot` with the joints of `held` (by RobotLink::joint_name; links that are
/// not planned) held at the values given.
/// @throws flowplan::Error naming a joint the robot does not have or plans.
kinematics::RobotDescription WithHeld(const kinematics::RobotDescription& robot,
                                      const std::map<std::string, double>& held);

/// A rigid transform: x -> R x + p, R row-major.
struct Frame {
  double R[9];
  double p[3];
};

class BodyModel {
 public:
  /// @throws flowplan::Error, prefixed by `where`, if the description is inconsistent.
  explicit BodyModel(const kinematics::RobotDescription& robot, const std::string& where = "robot");

  const kinematics::RobotDescription& description() const { return robot_; }
  int num_joints() const { return J_; }      // J
  int num_links() const { return L_; }       // L (1 for a point robot)
  int num_spheres() const { return S_; }     // S
  int workspace_dim() const { return W_; }   // W
  bool is_point() const { return point_; }

  /// Link frames (L) and sphere centres (S × W) of configuration q (J). `frames`
  /// may be null for a point robot.
  void Place(const double* q, Frame* frames, double* centres) const;

  /// The link frames (L) of configuration q alone (nothing for a point robot).
  void PlaceFrames(const double* q, Frame* frames) const;

  /// The centres of cluster c's spheres, into their rows of centres (S × W), from PlaceFrames' frames.
  void PlaceSpheres(const double* q, const Frame* frames, int c, double* centres) const;

  /// The tool centre point (W) of configuration q (J): an arm's TCP, a point robot's centre.
  void Tcp(const double* q, double* tcp) const;

  /// The centres of the links' bounding spheres (L × W) and of the clusters' (num_clusters() × W) of
  /// configuration q, from PlaceFrames' frames.
  void PlaceBounds(const double* q, const Frame* frames, double* bound_centres, double* cluster_centres) const;

  /// A link's spheres are grouped in clusters of at most kClusterSize spheres near each other, each with a
  /// bounding sphere: clusters first_cluster(l) .. first_cluster(l + 1) - 1 are link l's; cluster c holds
  /// spheres first_in_cluster(c) .. first_in_cluster(c + 1) - 1.
  static constexpr int kClusterSize = 8;
  int num_clusters() const { return static_cast<int>(cluster_radius_.size()); }
  int first_cluster(int l) const { return first_cluster_[static_cast<size_t>(l)]; }
  int first_in_cluster(int c) const { return first_in_cluster_[static_cast<size_t>(c)]; }
  double cluster_radius(int c) const { return cluster_radius_[static_cast<size_t>(c)]; }

  double sphere_radius(int s) const { return radius_[s]; }
  int sphere_link(int s) const { return sphere_link_[s]; }
  /// Spheres first_sphere(l) .. first_sphere(l + 1) - 1 ride on link l.
  int first_sphere(int l) const { return first_sphere_[l]; }
  double bound_radius(int l) const { return bound_radius_[l]; }
  /// A name for sphere s in messages: "sphere 12 (link5_c0)".
  const std::string& sphere_name(int s) const { return sphere_name_[s]; }
  const std::string& link_name(int l) const { return link_name_[l]; }
  /// Index of the description's sphere at position s of the link-sorted order.
  int description_sphere(int s) const { return original_[s]; }

  /// An upper bound, at every configuration, on how far sphere s's centre
  /// moves per unit of joint j: Σ_j sphere_travel(s)[j] |Δq_j| bounds its
  /// motion along a joint-space segment Δq. Likewise for link l's bounding sphere.
  const double* sphere_travel(int s) const { return &sphere_travel_[static_cast<size_t>(s) * J_]; }
  const double* bound_travel(int l) const { return &bound_travel_[static_cast<size_t>(l) * J_]; }

  /// The planned joints that move link l against the world, as a bit mask (bit j: joint j; J <= 64). Joints
  /// that move two links alike do not change the distance between them: a pair's relative motion is bounded by
  /// the joints of one mask and not the other.
  uint64_t ancestor_joints(int l) const { return ancestors_[static_cast<size_t>(l)]; }

  /// The world axes and points on the axes (J × 3 each) of the planned joints, from PlaceFrames' frames.
  void JointAxes(const Frame* frames, double* axes, double* points) const;

  /// A bound on how far any point within link l's bounding sphere (centred at `centre` in the world) moves along
  /// a joint-space segment of |Δq| = dq (J) starting where the joints' axes are `axes` and `points`, counting
  /// only the joints of the bit mask `joints`: each turning joint moves the point at most |Δq_j| times its
  /// distance from the axis, which the joints below it can lengthen by their own motion along the segment. At
  /// most the static bound Σ_j travel_j |Δq_j| of bound_travel.
  double Travel(int l, uint64_t joints, const double* dq, const double* axes, const double* points,
                const double* centre) const;
  /// The same bound for the sphere centres of link l that lie within `radius` of `centre` (a cluster's
  /// bounding sphere; the static part holds for centres within the link's bounding sphere, as every sphere
  /// centre of the link is): tighter than the link's for a part of the link near the joints' axes.
  double Travel(int l, uint64_t joints, const double* dq, const double* axes, const double* points,
                const double* centre, double radius) const;

  /// The static part of Travel alone, Σ_j reach_j |Δq_j| over the joints of `joints` that move link l: never
  /// below Travel, and cheaper (no axes), so a screen before it.
  double StaticTravel(int l, uint64_t joints, const double* dq) const;

  /// Whether planned joint j turns (revolute) rather than slides.
  bool revolute(int j) const { return joint_revolute_[static_cast<size_t>(j)] != 0; }

  /// Link pairs (a, b), a < b, whose spheres must not overlap (none unless self_collision).
  const std::vector<std::array<int, 2>>& self_pairs() const { return self_pairs_; }
  /// Whether link l is checked against a floor.
  bool floor_checked(int l) const { return floor_checked_[l] != 0; }

 private:
  kinematics::RobotDescription robot_;
  int J_ = 0, L_ = 0, S_ = 0, W_ = 3;
  bool point_ = false;
  // Links: fixed pose in the parent at v = 0 (a held link's offset folded in), parent, joint, axis, type.
  std::vector<Frame> fixed_;
  std::vector<int> parent_, joint_;
  std::vector<std::array<double, 3>> axis_;
  std::vector<uint8_t> prismatic_;
  // Spheres sorted by link.
  std::vector<double> local_;  // (S, 3) centres in their link frame
  std::vector<double> radius_;
  std::vector<int> sphere_link_, first_sphere_, original_;
  std::vector<std::string> sphere_name_, link_name_;
  std::vector<int> first_cluster_, first_in_cluster_;
  std::vector<double> cluster_local_, cluster_radius_;  // (C, 3), (C)
  std::vector<double> bound_local_;  // (L, 3)
  std::vector<double> bound_radius_;
  std::vector<double> sphere_travel_, bound_travel_;  // (S, J), (L, J)
  std::vector<std::array<int, 2>> self_pairs_;
  std::vector<uint8_t> floor_checked_;
  std::vector<uint64_t> ancestors_;  // (L)
  std::vector<uint8_t> joint_revolute_;  // (J)
  std::vector<int> joint_link_;          // (J) the link each planned joint moves
  // Per link, its planned ancestor joints, deepest first, with the static reach of its bounding sphere's points
  // from each (bound_travel plus the radius for a turning joint, 1 for a sliding one).
  std::vector<std::vector<std::pair<int, double>>> chain_;
  Frame tcp_{};  // the TCP in its link
};

}  // namespace flowplan::collision
