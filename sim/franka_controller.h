#pragma once

// Operational-space (task-space inverse-dynamics) control of the Franka TCP:
//
//   τ = Jᵀ Λ (a − J̇ q̇) + (I − Jᵀ J̄ᵀ) M (kp_n (q_posture − q) − kd_n q̇)
//       + c(q, q̇) − τ_passive(q̇) + M b
//
// with the 6×7 TCP Jacobian J (position and orientation), the joint-space
// inertia M, the task-space inertia Λ = (J M⁻¹ Jᵀ)⁻¹ (inertial decoupling), the
// dynamically consistent inverse J̄ = M⁻¹ Jᵀ Λ, the gravity and Coriolis forces
// c = qfrc_bias, the model's joint damping τ_passive = qfrc_passive, and the
// torques clamped to the motor limits. The task acceleration a is a PD law on
// the TCP position and orientation errors, a = Kp e − Kd ė, whose position part
// is written as a = Kd (v_des − ė) with v_des = (Kp / Kd) e, and v_des is
// capped at max_speed (Khatib's velocity saturation): far from the target the
// TCP cruises at max_speed, near it the error obeys ë = −Kp e − Kd ė. With the
// J̇ q̇ term the TCP moves along a straight line to the target. J̇ q̇ is the
// derivative of J q̇ along q̇, by a forward difference. b brakes joints that
// move faster than speed_guard × their velocity limit: b_j = −rate (|q̇_j| −
// guard · limit_j) sign(q̇_j) with rate = control_hz, which removes the excess
// within about one control period; unlike MuJoCo, the reference simulator
// enforces joint velocity limits, and external pushes would otherwise spin
// the arm far beyond them.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <array>

#include "core/config.h"
#include "sim/franka_model.h"
#include "sim/mujoco_util.h"

namespace flowplan::sim {

struct OscConfig {
  // The reference controller uses Kp = 2.5 for position and orientation and no
  // speed cap; with SPEC's torque noise that leaves about half of the episodes
  // more than 2 cm from the goal at the last state. Kp = 8 with the TCP speed
  // capped at 0.3 m/s keeps the motion spread over the episode, the joints
  // within their velocity limits, and ends 99 % of episodes within 2 cm.
  double stiffness = 8.0;              // 1/s², task-space position stiffness Kp
  double damping_ratio = 1.0;          // Kd = 2 · ratio · sqrt(Kp)
  double max_speed = 0.3;              // m/s, cap on the commanded TCP speed (.inf: none)
  double orientation_stiffness = 2.5;  // 1/s², task-space orientation stiffness
  double speed_guard = 0.9;            // brake joints beyond this fraction of their velocity limit
  double nullspace_stiffness = 10.0;   // 1/s², joint-space posture stiffness in the null space
  double nullspace_damping_ratio = 1.0;
  std::array<double, kFrankaJoints> posture = {0.0, -0.7853981633974483, 0.0, -2.356194490192345,
                                               0.0, 1.5707963267948966, 0.7853981633974483};  // ready pose, rad

  template <class V>
  void Visit(V& v) {
    v.Field("stiffness", stiffness, "task-space position stiffness (1/s^2)", config::Positive());
    v.Field("damping_ratio", damping_ratio, "task-space damping ratio (1: critical)",
            config::NonNegative());
    v.Field("max_speed", max_speed, "cap on the commanded TCP speed (m/s; .inf: none)",
            config::PositiveOrInfinite());
    v.Field("orientation_stiffness", orientation_stiffness, "task-space orientation stiffness (1/s^2)",
            config::Positive());
    v.Field("speed_guard", speed_guard,
            "brake a joint once its speed exceeds this fraction of its velocity limit (.inf: never)",
            config::PositiveOrInfinite());
    v.Field("nullspace_stiffness", nullspace_stiffness, "null-space posture stiffness (1/s^2)",
            config::NonNegative());
    v.Field("nullspace_damping_ratio", nullspace_damping_ratio, "null-space damping ratio",
            config::NonNegative());
    v.Field("posture", posture, "null-space posture, 7 joint angles (rad)", config::InRange(-4.0, 4.0));
  }
};

/// The controller with its scratch buffers; one per worker thread.
class OperationalSpaceController {
 public:
  /// `control_hz` is the rate at which Compute() is called (Hz).
  OperationalSpaceController(const FrankaModel& model, const OscConfig& config, double control_hz);

  /// Torques (N·m) driving the TCP to `target` (m, world) with orientation
  /// `target_rotation`. Reads from `d` the state and the quantities mj_step1
  /// (or mj_forward) computes: kinematics, com positions, qM, qfrc_bias.
  /// The result is clamped to the torque limits.
  JointVector Compute(const mjData& d, const Eigen::Vector3d& target, const Eigen::Matrix3d& target_rotation);

 private:
  const FrankaModel& model_;
  double kp_, kd_, max_speed_, kp_rot_, kd_rot_, kp_null_, kd_null_, speed_guard_, brake_rate_;
  JointVector posture_;
  MjDataPtr probe_;  // kinematics at q + ε q̇ for J̇ q̇
  Eigen::Matrix<double, 3, kFrankaJoints, Eigen::RowMajor> jacp_, jacr_;
  Eigen::Matrix<double, kFrankaJoints, kFrankaJoints> mass_;  // symmetric: storage order is moot
};

}  // namespace flowplan::sim
