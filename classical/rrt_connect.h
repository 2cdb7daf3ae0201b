#pragma once

// The classical reference planner: OMPL's RRT-Connect in joint space, with
// whole-arm validity from the robot's collision spheres and the scene, path
// shortcutting and corner rounding, time-parametrized to T states at the
// dataset's dt so that its plans compare with the learned planners'.

#include <torch/torch.h>

#include <memory>

#include "core/config.h"
#include "geometry/scene_rows.h"
#include "kinematics/robot.h"
#include "kinematics/trajectory_info.h"
#include "planning/planner.h"
#include "validity/plan_check.h"

namespace flowplan::classical {

/// The `rrt_connect` section of an experiment config.
struct RrtConnectConfig {
  int64_t max_iterations = 20000;  // calls of the termination check per plan (a deterministic budget)
  double time_limit = 10.0;        // s per plan, a safety stop on top of max_iterations
  double range = 0.0;              // maximum tree edge, joint-space units; 0: OMPL's default (20 % of the extent)
  double resolution = 0.005;       // motion checks every resolution × the space's extent
  double margin = 0.01;            // world units: a state is valid when every sphere is this far from every obstacle
  bool simplify = true;            // shortcut and tighten the path, and round its corners

  template <class V>
  void Visit(V& v) {
    v.Field("max_iterations", max_iterations, "RRT-Connect iterations per plan (deterministic budget)",
            config::Positive());
    v.Field("time_limit", time_limit, "seconds per plan, a safety stop on top of max_iterations", config::Positive());
    v.Field("range", range, "longest tree edge in joint space (0: OMPL's default)", config::NonNegative());
    v.Field("resolution", resolution, "motion check resolution as a fraction of the joint space's extent",
            config::Positive());
    v.Field("margin", margin, "clearance every collision sphere keeps from every obstacle (world units)",
            config::NonNegative());
    v.Field("simplify", simplify, "shortcut and tighten the found path and round its corners (Chaikin's corner cutting, kept only if valid)");
  }
};

/// RRT-Connect behind the Planner interface. Each of the B plans is its own
/// search, seeded from StreamSeed(request.seed, b), so plans do not depend on
/// batching or threads (a plan stopped by time_limit instead of max_iterations
/// is the exception). A plan holds T states: positions along the path with a
/// smooth start and stop (s(τ) = 3τ² − 2τ³ of the path length over
/// (T − 1)·dt) and, when D = 2J, the velocities of that timing. Plans not found
/// are the straight joint-space line, with found = false.
class RrtConnectPlanner : public planning::Planner {
 public:
  /// Plans trajectories like `trajectory`'s (T states dt apart, D = J or 2J)
  /// for its robot, whose joint limits must be finite. A configuration is
  /// valid when `configuration_check` (may be empty; the Franka's self-collision
  /// and floor) does not object either.
  /// @throws flowplan::Error naming what does not fit.
  RrtConnectPlanner(const kinematics::TrajectoryInfo& trajectory, RrtConnectConfig config,
                    validity::ConfigurationCheck configuration_check = {});

  planning::PlanResult Plan(const planning::PlanRequest& request) const override;

  /// Plan, seeded by a guide path per request: `guides` (B, T', D) states
  /// (T' ≥ 2; e.g. a learned planner's invalid proposal), positions first.
  /// The polyline start → guide states 1…T'−2 → goal keeps its longest valid
  /// stretch from the start and from the goal (each state and the motion
  /// between them checked as RRT-Connect's tree edges are); RRT-Connect joins
  /// the last state of the first to the first state of the second (nothing to
  /// join when the whole polyline is valid), and the joined path is shortcut,
  /// smoothed and timed like an unseeded one. When nothing of the guide can be
  /// kept, or the join is not found, RRT-Connect searches from the start to
  /// the goal as Plan does (the join and that search each have max_iterations,
  /// and share the plan's time_limit). route[b] says which made plan b:
  /// "seeded" (the guide's stretches) or "unseeded". A guide that is not
  /// finite is not used. An undefined `guides` plans as Plan (route empty).
  /// @throws flowplan::Error if guides are not (B, T', D).
  planning::PlanResult PlanAlong(const planning::PlanRequest& request, const torch::Tensor& guides) const;

  /// Whether configurations q (M, J) keep every sphere `margin` away from every obstacle of `scene`
  /// (the robot's clearance, kinematics::Robot::Clearance) and pass the configuration check: (M,) bool.
  torch::Tensor Valid(const torch::Tensor& q, const geometry::SceneRows& scene) const;

  int64_t horizon() const override { return horizon_; }
  int64_t state_dim() const override { return state_dim_; }

 private:
  std::shared_ptr<const kinematics::Robot> robot_;
  int64_t horizon_, state_dim_;
  double dt_;
  RrtConnectConfig config_;
  validity::ConfigurationCheck configuration_check_;
};

}  // namespace flowplan::classical
