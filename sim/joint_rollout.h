#pragma once

// Rollouts of any arm tracking a joint-space motion (sim/joint_motion.h) in
// MuJoCo, with Gaussian torque noise drawn per joint and physics step, recorded
// at a fixed rate: the simulator of the robot_joint data set. The model is any
// MuJoCo model whose degrees of freedom are exactly the planned joints (a robot
// folder's, robotfiles/robot_model.h), told apart by index.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/random.h"
#include "sim/franka_model.h"
#include "sim/joint_motion.h"
#include "sim/mujoco_util.h"

namespace flowplan::sim {

/// Physics, control and recording of every rollout (the Franka's and any
/// arm's). The recorded rate is control_hz / record_every; an episode records
/// `horizon` states, the first at t = 0, so it simulates (horizon - 1) ·
/// record_every control steps.
struct RolloutTiming {
  int control_hz = 30;       // controller updates per second
  int physics_substeps = 2;  // physics steps per control step: timestep 1 / (control_hz · substeps)
  int record_every = 2;      // control steps between recorded states
  int horizon = 64;          // recorded states per episode, T
  Integrator integrator = Integrator::kEuler;
  // Reject an episode once |q̇_j| > factor · limit_j at a physics step: at 1, kept
  // data respects the arm's velocity limits (a real arm stops when it breaks one).
  double reject_velocity_factor = 1.0;

  double physics_timestep() const { return 1.0 / (control_hz * physics_substeps); }
  double record_dt() const { return static_cast<double>(record_every) / control_hz; }

  template <class V>
  void Visit(V& v) {
    v.Field("control_hz", control_hz, "controller rate (Hz)", config::Positive());
    v.Field("physics_substeps", physics_substeps, "physics steps per control step", config::Positive());
    v.Field("record_every", record_every, "control steps between recorded states", config::Positive());
    v.Field("horizon", horizon, "recorded states per episode", config::AtLeast(2));
    v.Field("integrator", integrator, "physics integrator");
    v.Field("reject_velocity_factor", reject_velocity_factor,
            "reject an episode once a joint speed exceeds this many times its limit (1: kept data obeys the "
            "limits)", config::Positive());
  }
};

/// A joint-space rollout: the timing of every rollout and its torque noise.
struct JointRolloutConfig : RolloutTiming {
  // σ_j = share × effort_limit_j: the std of the torque noise added to joint j at every physics step (0: none).
  // The Franka's data sets add 1 N·m to joints with an 87 N·m limit and 0.1 to those with 12 (shares 0.011, 0.008).
  double torque_noise_share = 0.01;

  template <class V>
  void Visit(V& v) {
    RolloutTiming::Visit(v);
    v.Field("torque_noise_share", torque_noise_share,
            "std of the per-joint torque noise as a share of the joint's effort limit (0: none)", config::NonNegative());
  }
};

/// Where the planned joints are in the model and what limits them.
struct JointDrives {
  std::vector<int> qpos;           // (J,) index into qpos of joint j
  std::vector<int> dof;            // (J,) index into qvel, qfrc_* and the mass matrix (nv = J); motor j
                                   // (ctrl[j]) drives joint j
  Eigen::VectorXd velocity_limit;  // (J,) rad/s or m/s
  Eigen::VectorXd effort_limit;    // (J,) N·m or N
  int tcp_site = -1;               // site recorded as the TCP
};

/// One recorded episode; arrays are row-major.
struct JointEpisode {
  std::vector<double> states;   // (T, 2J): q, q̇
  std::vector<double> tcp;      // (T, 3), m
  std::vector<double> torques;  // (T, J), applied in the physics step after each state
  int64_t warnings = 0;         // MuJoCo warnings during the episode
  int64_t physics_steps = 0;
  bool rejected = false;
  std::string reject_reason;
};

using JointMotion = BasicMinimumJerkMotion<Eigen::VectorXd>;

/// A per-thread simulator: owns its mjData and buffers. `model` must have
/// timestep config.physics_timestep() and the integrator of `config`, and
/// outlive the simulator.
class JointSimulator {
 public:
  JointSimulator(const mjModel& model, JointDrives drives, const JointRolloutConfig& config,
                 const JointMotionConfig& motion);

  /// Why a configuration q (J, in the joints' order) may not be part of an episode; empty if it may.
  using StateCheck = std::function<std::string(const Eigen::VectorXd& q)>;

  /// Rolls out from `motion`'s start at rest, tracking it with the
  /// computed-torque law (clamped to the effort limits) plus torque noise drawn
  /// from `rng` when `noise`. `check` is asked at every control step; its first
  /// objection rejects the episode with that reason. Unstable episodes (MuJoCo
  /// instability warnings, non-finite states, joint speeds beyond
  /// reject_velocity_factor × limit) stop early with rejected = true.
  void Rollout(const JointMotion& motion, const StateCheck& check, bool noise, Rng& rng, JointEpisode* episode);

  /// Sizes `episode`'s arrays for config.horizon states and zeroes them.
  void Clear(JointEpisode* episode) const;

  int num_joints() const { return J_; }

 private:
  void Reject(JointEpisode* episode, const std::string& reason) const;

  const mjModel& model_;
  JointDrives drives_;
  JointRolloutConfig config_;
  double kp_, kd_;
  int J_;
  MjDataPtr data_;
  Eigen::MatrixXd full_mass_, mass_;                           // (nv, nv) MuJoCo's order, (J, J) the joints'
  Eigen::VectorXd q_, qdot_, bias_, passive_, control_, sigma_;  // (J,) the joints' order
};

}  // namespace flowplan::sim
