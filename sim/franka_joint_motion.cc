#include "sim/franka_joint_motion.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace flowplan::sim {
namespace {

// Peak speed of s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ over the mean speed: s'(1/2) = 15/8.
constexpr double kPeakOverMean = 15.0 / 8.0;

}  // namespace

MinimumJerkMotion::MinimumJerkMotion(const JointVector& from, const JointVector& to, double duration)
    : from_(from), to_(to), duration_(duration) {
  FLOWPLAN_DEMAND(duration > 0.0);
}

double MinimumJerkMotion::Duration(const JointVector& from, const JointVector& to, const JointVector& velocity_limit,
                                   const JointMotionConfig& config) {
  double duration = config.min_duration;
  for (int j = 0; j < kFrankaJoints; ++j) {
    duration = std::max(duration, kPeakOverMean * std::abs(to[j] - from[j]) / (config.speed_share * velocity_limit[j]));
  }
  return duration;
}

void MinimumJerkMotion::Sample(double t, JointVector* position, JointVector* velocity,
                               JointVector* acceleration) const {
  const double tau = std::clamp(t / duration_, 0.0, 1.0);
  const double tau2 = tau * tau, tau3 = tau2 * tau;
  const double s = tau3 * (10.0 - 15.0 * tau + 6.0 * tau2);
  const bool moving = t > 0.0 && t < duration_;
  const double ds = moving ? 30.0 * tau2 * (1.0 - tau) * (1.0 - tau) / duration_ : 0.0;
  const double dds = moving ? 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (duration_ * duration_) : 0.0;
  const JointVector delta = to_ - from_;
  *position = from_ + s * delta;
  *velocity = ds * delta;
  *acceleration = dds * delta;
}

JointTrackingController::JointTrackingController(const FrankaModel& model, const JointMotionConfig& config)
    : model_(model), kp_(config.stiffness), kd_(2.0 * config.damping_ratio * std::sqrt(config.stiffness)) {}

JointVector JointTrackingController::Compute(const mjData& d, const MinimumJerkMotion& motion, double t) {
  const mjModel& m = model_.mj();
  JointVector position, velocity, acceleration;
  motion.Sample(t, &position, &velocity, &acceleration);
  const Eigen::Map<const JointVector> q(d.qpos), qdot(d.qvel);
  mj_fullM(&m, mass_.data(), d.qM);
  const JointVector command = acceleration + kp_ * (position - q) + kd_ * (velocity - qdot);
  JointVector torque = mass_ * command + Eigen::Map<const JointVector>(d.qfrc_bias) -
                       Eigen::Map<const JointVector>(d.qfrc_passive);
  const JointVector& limit = model_.limits().torque;
  return torque.cwiseMax(-limit).cwiseMin(limit);
}

}  // namespace flowplan::sim
