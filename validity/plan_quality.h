#pragma once

// Plan quality, measured the same way for every planner: path length in joint
// space and at the TCP, the largest joint-speed ratio, mean squared jerk and
// the motion's duration.
//
// Shapes: N plans, T states, D state dims (positions first), J joints.

#include <torch/torch.h>

#include <vector>

#include "kinematics/robot.h"

namespace flowplan::validity {

struct PlanQuality {
  double joint_path_length = 0.0;  // rad (m for a point robot): Σ_t ‖q_{t+1} − q_t‖₂
  double tcp_path_length = 0.0;    // world units: Σ_t ‖tcp_{t+1} − tcp_t‖₂
  double max_speed_ratio = 0.0;    // largest |q_{t+1,j} − q_{t,j}| / dt over joint j's speed limit (0 without limits)
  double mean_squared_jerk = 0.0;  // (rad/s³)²: mean over t and j of ((q_{t+3} − 3q_{t+2} + 3q_{t+1} − q_t) / dt³)²
  double duration = 0.0;           // s: arrival, one state after the last one farther than `at_rest` from the final state
};

/// Measures plans (N, T, D) raw of `robot`, states `dt` s apart. A motion
/// ends at the last state whose largest joint difference from the plan's
/// final state exceeds `at_rest` (rad; m for a point robot).
std::vector<PlanQuality> MeasurePlans(const torch::Tensor& plans, const kinematics::Robot& robot, double dt,
                                      double at_rest);

}  // namespace flowplan::validity
