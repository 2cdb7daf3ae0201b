#pragma once

// Joint-space motions of the Franka for the general (franka_joint) data set: a
// minimum-jerk reference from one configuration to another, timed so that no
// joint exceeds a share of its velocity limit, tracked by a computed-torque
// controller:
//
//   τ = M (q̈_r + kp (q_r − q) + kd (q̇_r − q̇)) + c(q, q̇) − τ_passive(q̇),
//
// clamped to the motor limits, with c = qfrc_bias (gravity, Coriolis) and the
// model's joint damping τ_passive = qfrc_passive.

#include <mujoco/mujoco.h>

#include <Eigen/Core>

#include "core/config.h"
#include "sim/franka_model.h"

namespace flowplan::sim {

/// The `generate.franka.joint_motion` config section.
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
class MinimumJerkMotion {
 public:
  MinimumJerkMotion(const JointVector& from, const JointVector& to, double duration);

  /// The shortest duration (s) with which no joint's peak speed exceeds
  /// speed_share × its limit `velocity_limit` (rad/s), and at least min_duration.
  static double Duration(const JointVector& from, const JointVector& to, const JointVector& velocity_limit,
                         const JointMotionConfig& config);

  /// Position (rad), velocity (rad/s) and acceleration (rad/s²) at time t (s).
  void Sample(double t, JointVector* position, JointVector* velocity, JointVector* acceleration) const;

  double duration() const { return duration_; }
  const JointVector& to() const { return to_; }

 private:
  JointVector from_, to_;
  double duration_;
};

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
