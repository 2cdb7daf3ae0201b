#pragma once

// The one check every plan passes before anything calls it a success, for
// every planner: finite, within the joint limits, within the speed limits,
// starting at the start and ending at the goal, and valid by flowplan's one
// validity check (collision/checker.h) at every state and along the motion
// between consecutive states (the straight joint-space segment, certified by
// conservative advancement): every collision sphere clear of every obstacle
// of the scene and of the floor by `margin`, and no self-collision.
//
// Shapes: N plans, T states, D state dims, J joints, S collision spheres, K obstacles.

#include <torch/torch.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "collision/checker.h"
#include "core/config.h"
#include "geometry/scene_rows.h"
#include "kinematics/robot.h"

namespace flowplan::validity {

/// The `check` section of an experiment config: what a valid plan is. The
/// same settings make RRT-Connect's configurations and motions valid.
struct CheckConfig {
  double joint_tolerance = 0.01;  // rad (m for a point robot): largest |q − q_start| at the first state, |q − q_goal| at the last
  double max_speed_ratio = 1.0;   // joint speeds |Δq| / dt between consecutive states, over each joint's limit
  double margin = 0.0;            // world units every collision sphere keeps from every obstacle and the floor
  double resolution = 0.001;      // world units: motion checks stop halving a segment whose spheres move less than this
  double limit_tolerance = 1e-6;  // rad (m): how far past a joint limit a state may lie (float32 rounding of a value at it)
  double floor_height = -INFINITY;  // the floor's height (z; y in 2-D), -.inf for none; a problem may set its own

  template <class V>
  void Visit(V& v) {
    v.Field("joint_tolerance", joint_tolerance,
            "largest joint error of a valid plan's first state from the start and last state from the goal (rad)",
            config::Positive());
    v.Field("max_speed_ratio", max_speed_ratio,
            "a valid plan's joint speeds between consecutive states stay within this many times the limits",
            config::Positive());
    v.Field("margin", margin, "clearance every collision sphere keeps from every obstacle and the floor (world units)",
            config::NonNegative());
    v.Field("resolution", resolution,
            "motion checks: a segment whose spheres move less than this is not halved further (world units; it may "
            "come closer than the margin by at most half of it)",
            config::Positive());
    v.Field("limit_tolerance", limit_tolerance,
            "how far past a joint limit a state may lie and still count as at it (rad or m)", config::NonNegative());
    v.Field("floor_height", floor_height, "height of the floor (z), -.inf for no floor",
            config::Bounds{-INFINITY, INFINITY, false, false, "a number or -.inf", true});
  }
};

/// Why a plan is not valid; the first that applies, in this order.
enum class Failure {
  kNone,        // valid
  kNotFound,    // the planner reported that it found no plan
  kNotFinite,   // a state holds NaN or an infinity
  kStart,       // the first state is not the start
  kGoal,        // the last state is not the goal
  kJointLimit,  // a state outside the joint limits
  kSpeedLimit,  // a joint faster than max_speed_ratio × its limit between two states
  kSelf,        // two spheres of the robot overlap at a state
  kFloor,       // a sphere closer than the margin to the floor at a state
  kCollision,   // a sphere closer than the margin to an obstacle at a state
  kMotion,      // the motion between two valid states is not valid
};

inline const config::EnumNames<Failure>& EnumEntries(Failure) {
  static const config::EnumNames<Failure> names = {
      {Failure::kNone, "none"},           {Failure::kNotFound, "not_found"},     {Failure::kNotFinite, "not_finite"},
      {Failure::kStart, "start"},         {Failure::kGoal, "goal"},              {Failure::kJointLimit, "joint_limit"},
      {Failure::kSpeedLimit, "speed_limit"}, {Failure::kSelf, "self_collision"}, {Failure::kFloor, "floor"},
      {Failure::kCollision, "collision"}, {Failure::kMotion, "motion"}};
  return names;
}

/// The verdict on one plan.
struct PlanVerdict {
  Failure failure = Failure::kNone;
  std::string reason;               // one line naming the state, joint, sphere or obstacle at fault; empty if valid
  double clearance = 0.0;           // smallest clearance of any sphere at any state (+inf without obstacles)
  int64_t motion_checks = 0;        // configurations checked between the states
  bool valid() const { return failure == Failure::kNone; }
};

/// Checks plans of one robot at one sample spacing. Immutable; safe to share.
class PlanChecker {
 public:
  /// `dt`: seconds between a plan's states. @throws flowplan::Error naming a bad setting.
  PlanChecker(std::shared_ptr<const kinematics::Robot> robot, double dt, CheckConfig config);

  /// Checks plans (N, T, D) raw (positions first) against the start and goal
  /// (D,) or (N, D) raw states, `found` (N,) bool (undefined: all found), in
  /// `scene`, with the floor and held joints of `world` (what it leaves unset:
  /// config().floor_height and the robot's own). Without `measure_clearance`
  /// the verdicts' clearance is NaN (the verdict itself is the same, sooner).
  std::vector<PlanVerdict> Check(const torch::Tensor& plans, const torch::Tensor& start, const torch::Tensor& goal,
                                 const geometry::SceneRows& scene, const torch::Tensor& found = torch::Tensor(),
                                 const collision::WorldOptions& world = {}, bool measure_clearance = true) const;

  /// As Check, with the scene and world options already prepared: `checker`
  /// is what ConfigurationChecker(scene, world) of this PlanChecker returned.
  /// A planner that checks plans in one scene more than once builds that
  /// checker once and passes it to each call; the verdicts equal Check's.
  std::vector<PlanVerdict> CheckIn(const collision::Checker& checker, const torch::Tensor& plans,
                                   const torch::Tensor& start, const torch::Tensor& goal,
                                   const torch::Tensor& found = torch::Tensor(), bool measure_clearance = true) const;

  /// The validity check of configurations and motions in `scene` and `world`
  /// (as in Check), with this checker's settings: what RRT-Connect and the
  /// start and goal checks use. `names` (K) name the obstacles in reasons.
  /// @throws flowplan::Error for a held joint the robot does not have.
  collision::Checker ConfigurationChecker(const geometry::SceneRows& scene, const collision::WorldOptions& world = {},
                                          std::vector<std::string> names = {}) const;

  /// Why the configuration q (J values) cannot be planned from or to, or
  /// empty: a joint past its limit by more than limit_tolerance, or not valid
  /// in `checker`'s world. `what` ("start", "goal") begins the reason.
  std::string Refusal(const std::string& what, const std::vector<double>& q, const collision::Checker& checker) const;

  const CheckConfig& config() const { return config_; }
  const kinematics::Robot& robot() const { return *robot_; }
  const std::shared_ptr<const collision::BodyModel>& body() const { return body_; }
  double dt() const { return dt_; }

 private:
  std::shared_ptr<const kinematics::Robot> robot_;
  std::shared_ptr<const collision::BodyModel> body_;
  double dt_;
  CheckConfig config_;
};

}  // namespace flowplan::validity
