#pragma once

// Executing planned joint trajectories on the simulated Franka among obstacles
// that are real collision bodies: a joint-space PD controller with gravity
// compensation tracks the plan (optionally smoothed first, as the paper did on
// hardware), and every arm–obstacle contact and the smallest arm–obstacle
// distance are recorded.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/config.h"
#include "geometry/scene.h"
#include "sim/franka_model.h"
#include "sim/mujoco_util.h"

namespace flowplan::sim {

/// Distances up to this (m) between the arm's collision geoms and the obstacles
/// are measured; farther ones are reported as this or more.
inline constexpr double kMeasuredDistance = 0.5;

/// The Franka of FrankaModelXml() with the obstacles of `scene` (3-D) as
/// static geoms of their own shape ("obstacle0", … in the scene's numbering:
/// spheres, boxes, cylinders, capsules) that the arm's collision capsules
/// collide with (the arm does not collide with itself), contacts enabled,
/// physics at `timestep` s. MuJoCo reports every arm–obstacle pair closer than
/// kMeasuredDistance (margin) but exerts contact forces only on overlaps (gap).
/// @throws flowplan::Error if MuJoCo rejects the model.
FrankaModel MakeFrankaScene(const geometry::Scene& scene, double timestep);

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

/// The `execute` section of an experiment config.
struct ExecutionConfig {
  // libfranka's joint impedance example gains.
  std::array<double, kFrankaJoints> kp = {600.0, 600.0, 600.0, 600.0, 250.0, 150.0, 50.0};  // N·m/rad
  std::array<double, kFrankaJoints> kd = {50.0, 50.0, 50.0, 50.0, 30.0, 25.0, 15.0};       // N·m·s/rad
  int control_hz = 1000;     // control and physics rate
  double settle_time = 1.0;  // s the last planned state is held after the plan ends
  PlanSmoothing smoothing = PlanSmoothing::kNone;
  int smoothing_window = 5;  // states, odd

  template <class V>
  void Visit(V& v) {
    v.Field("kp", kp, "joint PD stiffness (N m/rad)", config::NonNegative());
    v.Field("kd", kd, "joint PD damping (N m s/rad)", config::NonNegative());
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
  std::vector<double> states;          // (T_exec, 14): q (rad), q̇ (rad/s) at the plan's dt
  std::vector<double> tcp;             // (T_exec, 3), m
  double goal_distance = 0.0;          // m, TCP at the end to the goal TCP
  std::vector<double> min_distance;    // (K,) m, smallest distance of the arm's capsules to each obstacle, by MuJoCo's
                                       // collision detection (< 0: overlap; kMeasuredDistance or more: farther)
  std::vector<ContactEvent> contacts;  // every arm–obstacle contact
  double max_tracking_error = 0.0;     // rad, largest |q_ref − q| over joints and time
  int64_t warnings = 0;                // MuJoCo warnings
};

/// Smooths a plan (T, 14) as `config` says (the first and last states are kept).
std::vector<double> SmoothPlan(const std::vector<double>& plan, int64_t T, PlanSmoothing smoothing, int window);

/// Tracks plans in one scene; owns its mjData (one per worker thread).
class FrankaExecutor {
 public:
  /// `scene` from MakeFrankaScene(obstacles, 1 / config.control_hz) with `num_obstacles` obstacles.
  FrankaExecutor(const FrankaModel& scene, int num_obstacles, const ExecutionConfig& config);

  /// Starts at plan state 0 and tracks the plan (T, 14) = [q, q̇], states `dt` s
  /// apart, interpolated by cubic Hermite splines, then holds the last state
  /// for settle_time. Deterministic.
  ExecutionResult Execute(const std::vector<double>& plan, int64_t T, double dt, const Eigen::Vector3d& goal_tcp);

 private:
  const FrankaModel& scene_;
  int num_obstacles_;
  ExecutionConfig config_;
  MjDataPtr data_;
  std::vector<int> obstacle_geoms_;  // (K,)
};

}  // namespace flowplan::sim
