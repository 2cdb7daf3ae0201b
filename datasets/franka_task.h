#pragma once

// Franka Panda data sets (SPEC section 3): rollouts of the operational-space
// controller in MuJoCo from an IK start configuration to a commanded TCP goal
// (franka_cross, franka_reach), and joint-space motions between random
// configurations tracked by a computed-torque controller (franka_joint).

#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/episode_task.h"
#include "sim/franka_joint_motion.h"
#include "sim/franka_model.h"
#include "sim/franka_rollout.h"
#include "sim/franka_self_collision.h"

namespace flowplan::datasets {

/// The `generate.franka` config section: the rollout settings of
/// sim::FrankaRolloutConfig (physics, controller, augmentation) plus the
/// sampling box of franka_reach.
struct FrankaTaskConfig {
  sim::FrankaRolloutConfig rollout;
  // franka_cross: family i goes from cross_starts[i] to cross_goals[i] (TCP, m); by
  // default the two diagonals of the y-z plane at x = 0.5 (SPEC section 3).
  std::vector<std::array<double, 3>> cross_starts = {{0.5, -0.3, 0.2}, {0.5, -0.3, 0.6}};
  std::vector<std::array<double, 3>> cross_goals = {{0.5, 0.3, 0.6}, {0.5, 0.3, 0.2}};
  std::array<double, 3> reach_lower = {0.35, -0.5, 0.15};  // m, TCP box of franka_reach
  std::array<double, 3> reach_upper = {0.75, 0.5, 0.75};   // m
  int max_draws = 100;  // draws of random points before an episode is given up as unreachable
  // franka_joint: starts and goals uniform within the joint limits shrunk by
  // joint_margin, free of self-collision and above the floor at every control step.
  double joint_margin = 0.1;   // rad
  double floor_height = 0.0;   // m, z of the floor the arm stands on (-.inf: none)
  sim::JointMotionConfig joint_motion;

  template <class V>
  void Visit(V& v) {
    rollout.Visit(v);
    v.Field("cross_starts", cross_starts, "franka_cross: commanded TCP start of each family (m)");
    v.Field("cross_goals", cross_goals, "franka_cross: commanded TCP goal of each family (m), one per start");
    v.Field("reach_lower", reach_lower, "franka_reach: lower corner of the start/goal box (m)");
    v.Field("reach_upper", reach_upper, "franka_reach: upper corner of the start/goal box (m)");
    v.Field("max_draws", max_draws,
            "franka_reach and random_position: draws of a start/goal pair until both are reachable "
            "with the gripper down",
            config::Positive());
    v.Field("joint_margin", joint_margin, "franka_joint: starts and goals keep this far inside the joint limits (rad)",
            config::NonNegative());
    const config::Bounds height{-INFINITY, INFINITY, false, false, "a height in m, or -.inf for no floor", true};
    v.Field("floor_height", floor_height,
            "franka_joint: z of the floor no collision capsule may go below (m; -.inf: none)", height);
    v.Field("joint_motion", joint_motion, "franka_joint: the reference motion and its tracking controller");
  }
};

/// Where the starts and goals of a Franka data set come from.
enum class FrankaGoals {
  kCross,  // franka_cross: the two diagonals of the y-z plane at x = 0.5, episode i in family i mod 2
  kReach,  // franka_reach: start and goal uniform in the reach box (reachable part)
  kJoint,  // franka_joint: start and goal configurations uniform within the joint limits
};

/// Episodes of the Franka. Random start/goal pairs (franka_reach, and the
/// random_position scheme around the cross points) are drawn again until the
/// IK reaches both with the gripper pointing down, up to max_draws times.
/// franka_joint draws start and goal configurations until both, and the
/// noise-free reference between them, are free of self-collision and above
/// the floor and the motion (timed by joint_motion) leaves min_hold seconds at
/// the goal; a rollout that still collides is drawn again, up to max_draws
/// times in all. State [q (7, rad), q̇ (7, rad/s)] at 15 Hz by
/// default, P = 3 (commanded TCP start and goal, m; franka_joint: P = 7, the
/// start and goal configurations, rad), extras "tcp" (T, 3) m,
/// "torques" (T, 7) N·m applied in the physics step after each state and,
/// for the random_force scheme, "external_force" (T, 3) N on the hand.
class FrankaTask : public EpisodeTask {
 public:
  /// Loads the built-in model, checks `config` (`where` is its config key, for
  /// messages) and solves the IK of every family's start.
  /// @throws flowplan::Error naming the key of a bad value or the unreachable target.
  FrankaTask(FrankaGoals goals, const FrankaTaskConfig& config, const std::string& where = "generate.franka");

  EpisodeLayout Layout() const override;
  std::vector<Family> Families() const override;
  std::unique_ptr<EpisodeWorker> MakeWorker() const override;

  const sim::FrankaModel& model() const { return *model_; }

 private:
  FrankaGoals goals_;
  FrankaTaskConfig config_;
  std::shared_ptr<const sim::FrankaModel> model_;
  std::shared_ptr<const sim::FrankaCollisionModel> collision_model_;  // franka_joint only
  std::vector<Family> families_;
  std::vector<sim::JointVector> family_start_q_;  // IK of each family's start
  std::vector<sim::JointVector> family_goal_q_;   // IK of each family's goal
};

}  // namespace flowplan::datasets
