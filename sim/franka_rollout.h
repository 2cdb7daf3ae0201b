#pragma once

// Rollouts of the Franka under the operational-space controller, with the
// augmentation schemes of the data sets, recorded at a fixed rate.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/random.h"
#include "sim/franka_controller.h"
#include "sim/franka_joint_motion.h"
#include "sim/franka_model.h"
#include "sim/joint_rollout.h"

namespace flowplan::sim {

/// How episodes are made to differ from each other.
enum class Augmentation {
  kPerJointNoise,   // Gaussian torque noise drawn independently per joint and physics step
  kSameNoise,       // one standard-normal draw per physics step shared by all joints (× σ_j)
  kNone,            // no randomness: every episode of a family is the same
  kRandomPosition,  // no torque noise; start and goal jittered around the commanded points
  kRandomForce,     // external force on the hand, random direction and magnitude, re-drawn at random intervals
};

inline const config::EnumNames<Augmentation>& EnumEntries(Augmentation) {
  static const config::EnumNames<Augmentation> names = {
      {Augmentation::kPerJointNoise, "per_joint_noise"}, {Augmentation::kSameNoise, "same_noise"},
      {Augmentation::kNone, "none"},                     {Augmentation::kRandomPosition, "random_position"},
      {Augmentation::kRandomForce, "random_force"}};
  return names;
}

struct AugmentationConfig {
  Augmentation scheme = Augmentation::kPerJointNoise;
  std::array<double, kFrankaJoints> torque_noise_sigma = {1.0, 1.0, 1.0, 1.0, 0.1, 0.1, 0.1};  // N·m
  double noise_scale = 1.0;                        // multiplies torque_noise_sigma
  double position_jitter = 0.05;                   // m, std per axis of start/goal jitter
  std::array<double, 2> force_range = {15.0, 20.0};  // N, [min, max] force magnitude
  std::array<double, 2> force_interval = {0.3, 0.5};  // s, [min, max] time between re-draws

  template <class V>
  void Visit(V& v) {
    v.Field("scheme", scheme, "augmentation scheme");
    v.Field("torque_noise_sigma", torque_noise_sigma,
            "per-joint std of the torque noise (N m), per_joint_noise and same_noise",
            config::NonNegative());
    v.Field("noise_scale", noise_scale, "global factor on torque_noise_sigma", config::NonNegative());
    v.Field("position_jitter", position_jitter, "std of the start/goal jitter per axis (m), random_position",
            config::NonNegative());
    v.Field("force_range", force_range, "[min, max] external force magnitude (N), random_force",
            config::NonNegative());
    v.Field("force_interval", force_interval, "[min, max] seconds between force re-draws, random_force",
            config::Positive());
  }
};

/// The Franka's rollout: the timing and rejection rule of every rollout
/// (RolloutTiming, sim/joint_rollout.h), its controller and its augmentation.
struct FrankaRolloutConfig : RolloutTiming {
  OscConfig controller;
  AugmentationConfig augmentation;

  template <class V>
  void Visit(V& v) {
    RolloutTiming::Visit(v);
    v.Field("controller", controller, "operational-space controller");
    v.Field("augmentation", augmentation, "how episodes are randomized");
  }

  /// Checks relations between fields; `where` is the config key of this struct.
  /// @throws flowplan::Error, e.g. "generate.franka.augmentation.force_range:
  ///   expected min <= max, got [20, 15]".
  void Validate(const std::string& where, const FrankaLimits& limits) const;
};

/// One recorded episode; arrays are row-major.
struct FrankaEpisode {
  std::vector<double> states;          // (T, 14): q (rad), q̇ (rad/s)
  std::vector<double> tcp;             // (T, 3), m, TCP position
  std::vector<double> torques;         // (T, 7), N·m, applied in the physics step after each state
  std::vector<double> external_force;  // (T, 3), N, on the hand after each state (zero unless random_force)
  int64_t warnings = 0;                // MuJoCo warnings during the episode
  int64_t physics_steps = 0;
  bool rejected = false;
  std::string reject_reason;
};

/// A per-thread simulator: owns its mjData, controller and buffers. The model
/// must have been configured with SetPhysics(config.physics_timestep(), config.integrator).
class FrankaSimulator {
 public:
  FrankaSimulator(const FrankaModel& model, const FrankaRolloutConfig& config);

  /// Rolls out from `q0` at rest, commanding the TCP to `goal` (m) with the
  /// gripper pointing down. `scheme` picks the disturbances simulated here
  /// (torque noise, external force; kNone and kRandomPosition add none), drawn
  /// from `rng`. Unstable episodes (MuJoCo instability warnings, non-finite
  /// states, joint speeds beyond reject_velocity_factor × limit) stop early
  /// with rejected = true and a reason.
  void Rollout(const JointVector& q0, const Eigen::Vector3d& goal, Augmentation scheme, Rng& rng,
               FrankaEpisode* episode);

  /// Why a configuration q (rad) may not be part of an episode; empty if it may.
  using StateCheck = std::function<std::string(const JointVector& q)>;

  /// Rolls out from `motion`'s start at rest, tracking `motion` with the
  /// computed-torque controller of `joint_motion` (the torque noise, force and
  /// rejection rules of Rollout apply). `check` is asked at every control step;
  /// its first objection rejects the episode with that reason.
  void RolloutJoints(const MinimumJerkMotion& motion, const JointMotionConfig& joint_motion, const StateCheck& check,
                     Augmentation scheme, Rng& rng, FrankaEpisode* episode);

  /// Sizes `episode`'s arrays for config.horizon states and zeroes them.
  void Clear(FrankaEpisode* episode) const;

 private:
  void Reject(FrankaEpisode* episode, const std::string& reason);
  void CheckState(FrankaEpisode* episode);
  // The rollout loop: `control_law(d)` gives the torques at each control step
  // (after mj_step1), `check(q)` may object to its configuration.
  template <class Control>
  void Simulate(const JointVector& q0, Control control_law, const StateCheck& check, Augmentation scheme, Rng& rng,
                FrankaEpisode* episode);

  const FrankaModel& model_;
  FrankaRolloutConfig config_;
  MjDataPtr data_;
  OperationalSpaceController controller_;
  JointVector sigma_;
};

}  // namespace flowplan::sim
