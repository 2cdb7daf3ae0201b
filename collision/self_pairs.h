#pragma once

// Which link pairs of a robot need no self-collision check, found the way
// MoveIt's setup assistant finds the `disable_collisions` of an SRDF:
//
//   adjacent  a link and its parent (links welded together count as one body)
//   default   the pair's spheres overlap at the home configuration
//   always    they overlap at more than `always_share` of random configurations
//   never     they overlap at none of the random configurations
//
// "never" is a sampled judgement: a pair that touches in a small corner of
// the joint space may be missed (MoveIt takes the same risk); it is left out
// of the list unless asked for.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "kinematics/robot_description.h"

namespace flowplan::collision {

struct IgnoredPair {
  std::array<std::string, 2> links;
  std::string reason;       // adjacent, default, always or never
  int64_t overlapping = 0;  // random configurations at which the pair's spheres overlap
};

struct SelfPairStudy {
  std::vector<IgnoredPair> ignored;
  int64_t samples = 0;  // random configurations drawn
  int64_t pairs = 0;    // link pairs with spheres on both links
};

struct SelfPairSettings {
  int64_t samples = 10000;     // random configurations, uniform within the joint limits
  uint64_t seed = 0;
  double always_share = 0.95;  // a pair overlapping at more than this share of them is always in contact
  bool ignore_never = false;   // also ignore pairs that never overlap in the samples
};

/// The pairs of `robot` (its spheres; its own ignore list is not read) to
/// ignore, by the categories above, in link order.
SelfPairStudy StudySelfPairs(const kinematics::RobotDescription& robot, const SelfPairSettings& settings);

}  // namespace flowplan::collision
