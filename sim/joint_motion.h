#pragma once

// Joint-space motions for the joint-space data sets (franka_joint,
// robot_joint): a minimum-jerk reference from one configuration to another,
// timed so that no joint exceeds a share of its velocity limit, tracked by a
// computed-torque controller. One implementation for any joint count.

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "core/config.h"
#include "core/error.h"

namespace flowplan::sim {

// Peak speed of s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ over the mean speed: s'(1/2) = 15/8.
inline constexpr double kMinimumJerkPeakOverMean = 15.0 / 8.0;

/// The `joint_motion` config section of the joint-space data sets.
struct JointMotionConfig {
  // The reference's peak speed 15 |Δq_j| / (8 τ) (minimum jerk) stays within
  // this share of joint j's limit; a longer motion is slower, never faster.
  double speed_share = 0.75;
  double min_duration = 1.0;  // s: short motions take at least this long
  // s the arm holds the goal at the end of an episode at least: a pair whose
  // motion would not leave it is drawn again.
  double min_hold = 0.4;
  double stiffness = 100.0;    // 1/s², kp of the tracking error dynamics
  double damping_ratio = 1.0;  // kd = 2 · ratio · sqrt(kp)

  template <class V>
  void Visit(V& v) {
    v.Field("speed_share", speed_share,
            "share of each joint's velocity limit the reference's peak speed may reach", config::InRange(0.01, 1.0));
    v.Field("min_duration", min_duration, "shortest motion (s)", config::Positive());
    v.Field("min_hold", min_hold, "seconds the goal is held at least at the end of an episode",
            config::NonNegative());
    v.Field("stiffness", stiffness, "tracking stiffness kp (1/s^2)", config::Positive());
    v.Field("damping_ratio", damping_ratio, "tracking damping ratio (1: critical)", config::NonNegative());
  }
};

/// A minimum-jerk (quintic, rest to rest) joint trajectory from `from` to `to`
/// over `duration` s; before 0 it is at `from`, after `duration` at `to`.
/// `Vector` is an Eigen column vector of the joint values (fixed or dynamic size).
template <class Vector>
class BasicMinimumJerkMotion {
 public:
  BasicMinimumJerkMotion(const Vector& from, const Vector& to, double duration)
      : from_(from), to_(to), duration_(duration) {
    FLOWPLAN_DEMAND(duration > 0.0 && from.size() == to.size());
  }

  /// The shortest duration (s) with which no joint's peak speed exceeds
  /// speed_share × its limit `velocity_limit` (rad/s), and at least min_duration.
  static double Duration(const Vector& from, const Vector& to, const Vector& velocity_limit,
                         const JointMotionConfig& config) {
    double duration = config.min_duration;
    for (Eigen::Index j = 0; j < from.size(); ++j) {
      duration = std::max(duration, kMinimumJerkPeakOverMean * std::abs(to[j] - from[j]) /
                                        (config.speed_share * velocity_limit[j]));
    }
    return duration;
  }

  /// Position (rad), velocity (rad/s) and acceleration (rad/s²) at time t (s).
  void Sample(double t, Vector* position, Vector* velocity, Vector* acceleration) const {
    const double tau = std::clamp(t / duration_, 0.0, 1.0);
    const double tau2 = tau * tau, tau3 = tau2 * tau;
    const double s = tau3 * (10.0 - 15.0 * tau + 6.0 * tau2);
    const bool moving = t > 0.0 && t < duration_;
    const double ds = moving ? 30.0 * tau2 * (1.0 - tau) * (1.0 - tau) / duration_ : 0.0;
    const double dds = moving ? 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (duration_ * duration_) : 0.0;
    const Vector delta = to_ - from_;
    *position = from_ + s * delta;
    *velocity = ds * delta;
    *acceleration = dds * delta;
  }

  double duration() const { return duration_; }
  const Vector& to() const { return to_; }

 private:
  Vector from_, to_;
  double duration_;
};

/// The computed-torque law tracking a reference (q_r, q̇_r, q̈_r), before clamping:
///   τ = M (q̈_r + kp (q_r − q) + kd (q̇_r − q̇)) + c(q, q̇) − τ_passive(q̇),
/// with the joint-space inertia `mass` (J, J), `bias` = c (gravity, Coriolis:
/// MuJoCo's qfrc_bias) and `passive` = the joints' damping (qfrc_passive), all
/// in the joints' order.
template <class Vector, class Matrix>
Vector ComputedTorque(const Vector& position, const Vector& velocity, const Vector& acceleration, const Vector& q,
                      const Vector& qdot, const Matrix& mass, const Vector& bias, const Vector& passive, double kp,
                      double kd) {
  const Vector command = acceleration + kp * (position - q) + kd * (velocity - qdot);
  return mass * command + bias - passive;
}

/// ComputedTorque of `motion`'s reference at time t (s).
template <class Vector, class Matrix>
Vector TrackingTorque(const BasicMinimumJerkMotion<Vector>& motion, double t, const Vector& q, const Vector& qdot,
                      const Matrix& mass, const Vector& bias, const Vector& passive, double kp, double kd) {
  Vector position, velocity, acceleration;
  motion.Sample(t, &position, &velocity, &acceleration);
  return ComputedTorque(position, velocity, acceleration, q, qdot, mass, bias, passive, kp, kd);
}

}  // namespace flowplan::sim
