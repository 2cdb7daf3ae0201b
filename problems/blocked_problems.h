#pragma once

// Random planning problems whose straight path is blocked: reach start/goal
// pairs for an arm, with 1 to K spheres of which the first sits on the
// straight TCP segment between them (beyond the paper's single sphere), and
// optionally boxes at any orientation near that segment.

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "geometry/scene.h"
#include "kinematics/robot.h"
#include "problems/problem.h"

namespace flowplan::problems {

/// How the problems are drawn.
struct BlockedProblemsConfig {
  int count = 100;                                     // problems
  int min_spheres = 1;                                 // spheres per problem, uniform in [min, max]
  int max_spheres = 8;
  double min_radius = 0.05;                            // m, uniform in [min, max]
  double max_radius = 0.12;
  std::vector<double> lower = {0.35, -0.5, 0.15};      // (3,) m: start and goal TCP uniform in this box
  std::vector<double> upper = {0.75, 0.5, 0.75};       // (the reach data set's box)
  double min_length = 0.3;                             // m between start and goal TCP
  double clearance = 0.02;                             // m between the start/goal arm's spheres and every obstacle
  int min_boxes = 0;                                   // boxes per problem, uniform in [min, max], drawn after the
  int max_boxes = 0;                                   // spheres (0: the problems of a set without boxes)
  double min_box_side = 0.04;                          // m, each side length uniform in [min, max]
  double max_box_side = 0.25;

  template <class V>
  void Visit(V& v) {
    v.Field("count", count, "number of problems", config::Positive());
    v.Field("min_spheres", min_spheres, "fewest spheres per problem", config::Positive());
    v.Field("max_spheres", max_spheres, "most spheres per problem", config::Positive());
    v.Field("min_radius", min_radius, "smallest sphere radius (m)", config::Positive());
    v.Field("max_radius", max_radius, "largest sphere radius (m)", config::Positive());
    v.Field("lower", lower, "lower corner of the box start and goal TCP are drawn in (m)");
    v.Field("upper", upper, "upper corner of that box (m)");
    v.Field("min_length", min_length, "shortest start-goal TCP distance (m)", config::NonNegative());
    v.Field("clearance", clearance, "gap between the start/goal arm and every obstacle (m)", config::NonNegative());
    v.Field("min_boxes", min_boxes, "fewest boxes per problem", config::NonNegative());
    v.Field("max_boxes", max_boxes, "most boxes per problem", config::NonNegative());
    v.Field("min_box_side", min_box_side, "shortest side of a box (m)", config::Positive());
    v.Field("max_box_side", max_box_side, "longest side of a box (m)", config::Positive());
  }
};

/// Draws `config.count` problems ("blocked/0", …; problem.h's format, its
/// `source` saying how they were drawn); problem i depends only on (seed, i).
/// Every start and goal is the IK of a TCP point (the home posture's TCP
/// orientation), at least `min_length` apart, and its arm (all collision
/// spheres) is `clearance` clear of every obstacle; the first sphere is
/// centred on the straight TCP segment between them, the other spheres and
/// the boxes (uniformly random orientations) near it. The boxes are drawn
/// after the spheres, so a set without boxes is what it was before they existed.
/// @throws flowplan::Error naming the key for an inconsistent config, or if a
///   problem cannot be drawn in 10,000 attempts (the box is unreachable).
ProblemSet MakeBlockedProblems(const kinematics::Robot& arm, const BlockedProblemsConfig& config, uint64_t seed);

}  // namespace flowplan::problems
