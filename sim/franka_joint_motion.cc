#include "sim/franka_joint_motion.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace flowplan::sim {

JointTrackingController::JointTrackingController(const FrankaModel& model, const JointMotionConfig& config)
    : model_(model), kp_(config.stiffness), kd_(2.0 * config.damping_ratio * std::sqrt(config.stiffness)) {}

JointVector JointTrackingController::Compute(const mjData& d, const MinimumJerkMotion& motion, double t) {
  const mjModel& m = model_.mj();
  const Eigen::Map<const JointVector> q(d.qpos), qdot(d.qvel);
  mj_fullM(&m, mass_.data(), d.qM);
  const JointVector torque = TrackingTorque<JointVector>(motion, t, q, qdot, mass_, Eigen::Map<const JointVector>(d.qfrc_bias),
                                                         Eigen::Map<const JointVector>(d.qfrc_passive), kp_, kd_);
  const JointVector& limit = model_.limits().torque;
  return torque.cwiseMax(-limit).cwiseMin(limit);
}

}  // namespace flowplan::sim
