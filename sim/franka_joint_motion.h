#pragma once

// Joint-space motions of the Franka for the general (franka_joint) data set:
// the minimum-jerk reference of sim/joint_motion.h tracked by its
// computed-torque law, clamped to the Franka's motor limits.

#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include "core/config.h"
#include "sim/franka_model.h"
#include "sim/joint_motion.h"

namespace flowplan::sim {

/// The Franka's joint-space reference.
using MinimumJerkMotion = BasicMinimumJerkMotion<JointVector>;

/// Computed-torque tracking of a joint trajectory; one per worker thread.
class JointTrackingController {
 public:
  JointTrackingController(const FrankaModel& model, const JointMotionConfig& config);

  /// Torques (N·m) tracking `motion` at time t (s). Reads from `d` the state and
  /// what mj_step1 (or mj_forward) computes: qM, qfrc_bias, qfrc_passive.
  /// Clamped to the torque limits.
  JointVector Compute(const mjData& d, const MinimumJerkMotion& motion, double t);

 private:
  const FrankaModel& model_;
  double kp_, kd_;
  Eigen::Matrix<double, kFrankaJoints, kFrankaJoints> mass_;
};

}  // namespace flowplan::sim
