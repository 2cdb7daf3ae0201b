#pragma once

// The one check every plan passes before anything calls it a success, for
// every planner: finite, within the joint limits, within the speed limits,
// starting at the start and ending at the goal, allowed by a configuration
// check (the Franka's self-collision and floor), and clear of every obstacle of the scene
// with every collision sphere — at every state and along the motion between
// consecutive states (the straight joint-space segment), checked by
// conservative advancement so that no obstacle can be stepped over:
//
// along a segment from q_a to q_b, sphere s's centre moves at most
// Δ_s = Σ_j bound[j, s] |q_b,j − q_a,j| (kinematics::Robot::MotionBound), and a
// signed distance changes no faster than the point it is measured from, so
// the sphere keeps at least (d_a + d_b − Δ_s) / 2 from every obstacle when its
// clearances at the ends are d_a and d_b. A segment for which that bound is
// below the margin for some sphere is halved, and its halves are checked the
// same way, until every piece is certified clear, a state inside an obstacle
// is found, or a piece is shorter than `resolution` (its ends clear: it can
// overlap an obstacle by at most resolution / 2, which is accepted).
//
// Shapes: N plans, T states, D state dims, J joints, S collision spheres, K obstacles.

#include <torch/torch.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "geometry/scene_rows.h"
#include "kinematics/robot.h"

namespace flowplan::validity {

/// The `check` section of an experiment config: what a valid plan is.
struct CheckConfig {
  double joint_tolerance = 0.01;  // rad (m for a point robot): largest |q − q_start| at the first state, |q − q_goal| at the last
  double max_speed_ratio = 1.0;   // joint speeds |Δq| / dt between consecutive states, over each joint's limit
  double margin = 0.0;            // world units every collision sphere keeps from every obstacle
  double resolution = 0.001;      // world units: motion checks stop halving a segment whose spheres move less than this
  double self_resolution = 0.02;  // rad: the self check (below) samples each segment at most this far apart in every joint

  template <class V>
  void Visit(V& v) {
    v.Field("joint_tolerance", joint_tolerance,
            "largest joint error of a valid plan's first state from the start and last state from the goal (rad)",
            config::Positive());
    v.Field("max_speed_ratio", max_speed_ratio,
            "a valid plan's joint speeds between consecutive states stay within this many times the limits",
            config::Positive());
    v.Field("margin", margin, "clearance every collision sphere keeps from every obstacle (world units)",
            config::NonNegative());
    v.Field("resolution", resolution,
            "motion checks: a segment whose spheres move less than this is not halved further (world units; it may "
            "overlap an obstacle by at most half of it)",
            config::Positive());
    v.Field("self_resolution", self_resolution,
            "self-collision and floor check (the Franka): configurations sampled along each segment at most this far "
            "apart in every joint (rad)",
            config::Positive());
  }
};

/// A check of single configurations beyond the scene's obstacles (for the
/// Franka: self-collision and the floor, by MuJoCo; sim/franka_self_collision.h):
/// given the J joint positions, why the configuration is not allowed, or empty.
/// Called from several threads at once.
using ConfigurationCheck = std::function<std::string(const std::vector<double>& q)>;

/// Why a plan is not valid; the first that applies, in this order.
enum class Failure {
  kNone,        // valid
  kNotFound,    // the planner reported that it found no plan
  kNotFinite,   // a state holds NaN or an infinity
  kStart,       // the first state is not the start
  kGoal,        // the last state is not the goal
  kJointLimit,  // a state outside the joint limits
  kSpeedLimit,  // a joint faster than max_speed_ratio × its limit between two states
  kSelf,        // the configuration check objects at a state or at a sample between two states
  kCollision,   // a state inside an obstacle
  kMotion,      // the motion between two clear states passes through an obstacle
};

inline const config::EnumNames<Failure>& EnumEntries(Failure) {
  static const config::EnumNames<Failure> names = {
      {Failure::kNone, "none"},           {Failure::kNotFound, "not_found"},     {Failure::kNotFinite, "not_finite"},
      {Failure::kStart, "start"},         {Failure::kGoal, "goal"},              {Failure::kJointLimit, "joint_limit"},
      {Failure::kSpeedLimit, "speed_limit"}, {Failure::kSelf, "self_collision"}, {Failure::kCollision, "collision"},
      {Failure::kMotion, "motion"}};
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
  /// `dt`: seconds between a plan's states; `self_check` (may be empty) is
  /// asked about every state and about samples along every segment, at most
  /// config.self_resolution apart in every joint (a sampled check, unlike the
  /// obstacles'). @throws flowplan::Error naming a bad setting.
  PlanChecker(std::shared_ptr<const kinematics::Robot> robot, double dt, CheckConfig config,
              ConfigurationCheck self_check = {});

  /// Checks plans (N, T, D) raw (positions first) against the start and goal
  /// (D,) or (N, D) raw states, `found` (N,) bool (undefined: all found), in `scene`.
  std::vector<PlanVerdict> Check(const torch::Tensor& plans, const torch::Tensor& start, const torch::Tensor& goal,
                                 const geometry::SceneRows& scene, const torch::Tensor& found = torch::Tensor()) const;

  const CheckConfig& config() const { return config_; }
  const kinematics::Robot& robot() const { return *robot_; }

 private:
  std::shared_ptr<const kinematics::Robot> robot_;
  double dt_;
  CheckConfig config_;
  ConfigurationCheck self_check_;
  torch::Tensor motion_bound_;  // (J, S)
};

}  // namespace flowplan::validity
