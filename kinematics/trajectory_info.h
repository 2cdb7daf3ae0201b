#pragma once

// What a trajectory is, wherever one is stored or planned: data sets,
// checkpoints, planners, plan reports. The one description of it.

#include <cstdint>
#include <string>
#include <vector>

#include "kinematics/robot_description.h"

namespace flowplan::kinematics {

struct TrajectoryInfo {
  std::string env;                        // the environment that made the data, e.g. "particle", "franka"
  double dt = 0.0;                        // s between states
  int64_t horizon = 0;                    // T
  std::vector<std::string> state_labels;  // (D,) e.g. "x", "y", "vx", "vy"; "q1" … "q7", "dq1" … "dq7"
  RobotDescription robot;                 // what moves: its J joint positions are the first J state entries

  int64_t state_dim() const { return static_cast<int64_t>(state_labels.size()); }  // D
};

}  // namespace flowplan::kinematics
