#pragma once

// Executing planned joint trajectories of any arm in MuJoCo among obstacles
// that are real collision bodies: a controller tracks the plan (optionally
// smoothed first, as the paper did on hardware), and every arm–obstacle
// contact and the smallest arm–obstacle distance are recorded. The Franka
// (sim/franka_execution.h) and robot folders (robotfiles/robot_model.h) make
// their scene models and drives; this is the one tracking loop.
//
// Shapes: J planned joints, T planned states, K obstacles.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/config.h"
#include "sim/mujoco_util.h"

namespace flowplan::sim {

/// Distances up to this (m) between the arm's collision geoms and the obstacles
/// are measured; farther ones are reported as this or more.
inline constexpr double kMeasuredDistance = 0.5;

/// How a plan is smoothed before it is tracked.
enum class PlanSmoothing {
  kNone,
  kMovingAverage,  // centred moving average of q and q̇ over `smoothing_window` states
  kSavitzkyGolay,  // centred quadratic Savitzky–Golay filter of q and q̇ over `smoothing_window` states
};

inline const config::EnumNames<PlanSmoothing>& EnumEntries(PlanSmoothing) {
  static const config::EnumNames<PlanSmoothing> names = {{PlanSmoothing::kNone, "none"},
                                                         {PlanSmoothing::kMovingAverage, "moving_average"},
                                                         {PlanSmoothing::kSavitzkyGolay, "savitzky_golay"}};
  return names;
}

/// Which law tracks a plan.
enum class TrackingLaw {
  kDefault,         // the built-in Franka: joint PD; a robot folder's arm: computed torque
  kJointPd,         // joint PD with gravity compensation, execute.kp and execute.kd (the Franka's 7 joints)
  kComputedTorque,  // the computed-torque law on the simulated arm's own inertia, execute.stiffness and .damping_ratio
};

inline const config::EnumNames<TrackingLaw>& EnumEntries(TrackingLaw) {
  static const config::EnumNames<TrackingLaw> names = {{TrackingLaw::kDefault, "default"},
                                                       {TrackingLaw::kJointPd, "joint_pd"},
                                                       {TrackingLaw::kComputedTorque, "computed_torque"}};
  return names;
}

/// The `execute` section of an experiment config.
struct ExecutionConfig {
  TrackingLaw controller = TrackingLaw::kDefault;
  // The Franka: joint PD with gravity compensation, libfranka's joint impedance example gains.
  std::array<double, 7> kp = {600.0, 600.0, 600.0, 600.0, 250.0, 150.0, 50.0};  // N·m/rad
  std::array<double, 7> kd = {50.0, 50.0, 50.0, 50.0, 30.0, 25.0, 15.0};       // N·m·s/rad
  // The computed-torque law on the arm's own inertia, the same for every joint (a robot folder's arm, or the Franka
  // with controller: computed_torque).
  double stiffness = 400.0;    // 1/s², kp of the tracking error dynamics
  double damping_ratio = 1.0;  // kd = 2 · ratio · sqrt(stiffness)
  int control_hz = 1000;       // control and physics rate
  double settle_time = 1.0;    // s the last planned state is held after the plan ends
  PlanSmoothing smoothing = PlanSmoothing::kNone;
  int smoothing_window = 5;  // states, odd

  template <class V>
  void Visit(V& v) {
    v.Field("controller", controller,
            "tracking law: default (the Franka: joint_pd; a robot folder: computed_torque), joint_pd (the Franka "
            "only) or computed_torque");
    v.Field("kp", kp, "the Franka's joint PD stiffness (N m/rad)", config::NonNegative());
    v.Field("kd", kd, "the Franka's joint PD damping (N m s/rad)", config::NonNegative());
    v.Field("stiffness", stiffness,
            "computed-torque tracking stiffness, the same for every joint (1/s^2)",
            config::Positive());
    v.Field("damping_ratio", damping_ratio, "computed-torque damping ratio (1: critical)",
            config::NonNegative());
    v.Field("control_hz", control_hz, "control and physics rate (Hz)", config::Positive());
    v.Field("settle_time", settle_time, "seconds the last state is held after the plan", config::NonNegative());
    v.Field("smoothing", smoothing, "smoothing of the plan before tracking");
    v.Field("smoothing_window", smoothing_window, "smoothing window (states, odd)", config::Positive());
  }

  /// @throws flowplan::Error naming the `execute.*` key at fault.
  void Validate() const;
};

/// Contact between one arm geom and one obstacle, over the steps it lasted.
struct ContactEvent {
  std::string arm_geom;   // e.g. "hand_c0"
  int obstacle = -1;      // index into the obstacles
  double first_time = 0;  // s
  double last_time = 0;   // s
  double max_depth = 0;   // m, deepest penetration
  int64_t steps = 0;      // physics steps in contact
};

struct ExecutionResult {
  int64_t num_states = 0;              // T_exec = T + settle_time / dt
  std::vector<double> states;          // (T_exec, 2J): q, q̇ at the plan's dt
  std::vector<double> tcp;             // (T_exec, 3), m
  double goal_distance = 0.0;          // m, TCP at the end to the goal TCP
  std::vector<double> min_distance;    // (K,) m, smallest distance of the arm's collision geoms to each obstacle, by
                                       // MuJoCo's collision detection (< 0: overlap; kMeasuredDistance or more: farther)
  std::vector<ContactEvent> contacts;  // every arm–obstacle contact
  double max_tracking_error = 0.0;     // rad (m for a sliding joint), largest |q_ref − q| over joints and time
  int64_t warnings = 0;                // MuJoCo warnings
};

/// Smooths a plan (T, D) as `smoothing` says, every column alike (the first and last states are kept).
std::vector<double> SmoothPlan(const std::vector<double>& plan, int64_t T, int64_t D, PlanSmoothing smoothing,
                               int window);

/// Where the planned joints are in a scene model and how the controller drives them.
struct ExecutionDrives {
  std::vector<int> qpos;              // (J,) index into qpos of joint j
  std::vector<int> dof;               // (J,) index into qvel, qfrc_*, the mass matrix of joint j; ctrl[j] drives it
  std::vector<double> effort_limit;   // (J,) N·m or N: the motors' torque or force limits
  int tcp_site = -1;                  // the site whose position is the TCP
  // The control law, clamped to the effort limits:
  //  - joint PD with gravity compensation: τ = kp_j (q_r − q) + kd_j (q̇_r − q̇) + c(q, q̇), gains per joint;
  //  - computed torque (sim/joint_motion.h's ComputedTorque, q̈_r the reference spline's): the same stiffness and
  //    damping for every joint.
  enum class Law { kJointPd, kComputedTorque };
  Law law = Law::kJointPd;
  std::vector<double> kp, kd;  // kJointPd: (J,) N·m/rad and N·m·s/rad
  double stiffness = 0.0;      // kComputedTorque: 1/s²
  double damping = 0.0;        // kComputedTorque: 1/s

  /// The computed-torque law with `config`'s stiffness and damping ratio.
  void UseComputedTorque(const ExecutionConfig& config);
};

/// Tracks plans in one scene; owns its mjData (one per worker thread).
class ArmExecutor {
 public:
  /// `scene` with physics at 1 / config.control_hz and the obstacles as geoms "obstacle0", … ("obstacle<k>", K of
  /// them), every arm collision geom colliding with them, must outlive the executor.
  ArmExecutor(const mjModel& scene, ExecutionDrives drives, int num_obstacles, const ExecutionConfig& config);

  /// Starts at plan state 0 and tracks the plan (T, 2J) = [q, q̇], states `dt` s
  /// apart, interpolated by cubic Hermite splines, then holds the last state
  /// for settle_time. Deterministic.
  ExecutionResult Execute(const std::vector<double>& plan, int64_t T, double dt, const Eigen::Vector3d& goal_tcp);

  int num_joints() const { return static_cast<int>(drives_.qpos.size()); }

 private:
  const mjModel& scene_;
  ExecutionDrives drives_;
  int num_obstacles_;
  ExecutionConfig config_;
  MjDataPtr data_;
  std::vector<int> obstacle_geoms_;  // (K,)
};

}  // namespace flowplan::sim
