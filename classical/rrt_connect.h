#pragma once

// The classical reference planner: RRT-Connect (Kuffner and LaValle, 2000) in
// joint space, every configuration and every motion judged by flowplan's one
// validity check (collision/checker.h, with the plan checker's settings,
// check.*), the path shortcut and its corners rounded, then timed to T states
// at the dataset's dt within the joints' speed limits
// (planning/time_parametrize.h). A plan is reported found only when the plan
// checker (validity/plan_check.h) passes it as it is returned, so every found
// plan is a valid one.
//
// Plain C++ on float64 configurations: no LibTorch operator runs inside a
// search.

#include <torch/torch.h>

#include <memory>

#include "collision/body_model.h"
#include "core/config.h"
#include "geometry/scene_rows.h"
#include "kinematics/robot.h"
#include "kinematics/trajectory_info.h"
#include "planning/planner.h"
#include "validity/plan_check.h"

namespace flowplan::classical {

/// The `rrt_connect` section of an experiment config. What a valid
/// configuration and motion are is the plan checker's (check.*).
struct RrtConnectConfig {
  int64_t max_iterations = 20000;  // RRT-Connect iterations per plan (a deterministic budget)
  double time_limit = 10.0;        // s per plan, a safety stop on top of max_iterations
  double range = 0.0;              // longest tree edge, joint-space units; 0: 20 % of the joint space's diagonal
  bool simplify = true;            // shortcut and tighten the found path, and round its corners
  int64_t attempts = 1;            // searches per plan until one passes the plan check, each with max_iterations

  template <class V>
  void Visit(V& v) {
    v.Field("max_iterations", max_iterations, "RRT-Connect iterations per plan (deterministic budget)",
            config::Positive());
    v.Field("time_limit", time_limit, "seconds per plan, a safety stop on top of max_iterations", config::Positive());
    v.Field("range", range, "longest tree edge in joint space (0: 20 % of the joint space's diagonal)",
            config::NonNegative());
    v.Field("simplify", simplify,
            "shortcut and tighten the found path and round its corners (Chaikin's corner cutting, kept only if valid)");
    v.Field("attempts", attempts,
            "searches per plan: when a search finds no path, or its path cannot be timed to pass the plan check, a "
            "fresh search with its own seed and max_iterations; time_limit is checked before each search (the "
            "hybrid's classical-first stage too runs up to this many searches of hybrid.classical_iterations)",
            config::Positive());
  }
};

/// RRT-Connect behind the Planner interface. Each of the B plans is its own
/// search, seeded from StreamSeed(request.seed, b), so plans do not depend on
/// batching or threads (a plan stopped by time_limit instead of max_iterations
/// is the exception). A plan holds T states: positions along the path and,
/// when D = 2J, the velocities of that timing. A start or goal past a joint
/// limit by more than check.limit_tolerance, or not valid, is refused
/// (PlanResult::refused, with the reason in failure); a plan not found is the
/// straight joint-space line, with found = false and the reason. With
/// config.attempts > 1, a search whose path is not found, or cannot be timed
/// to pass the plan check, is followed by a fresh unseeded one
/// (StreamSeed(seed, 2 + attempt)), up to `attempts` searches; attempts = 1
/// plans exactly as a single search.
class RrtConnectPlanner : public planning::Planner {
 public:
  /// Plans trajectories like `trajectory`'s (T states dt apart, D = J or 2J)
  /// for its robot, whose joint limits must be finite, valid by `check`.
  /// @throws flowplan::Error naming what does not fit.
  RrtConnectPlanner(const kinematics::TrajectoryInfo& trajectory, RrtConnectConfig config,
                    validity::CheckConfig check = {});

  planning::PlanResult Plan(const planning::PlanRequest& request) const override;

  /// Plan, seeded by a guide path per request: `guides` (B, T', D) states
  /// (T' ≥ 2; e.g. a learned planner's invalid proposal), positions first.
  /// The polyline start → guide states 1…T'−2 → goal keeps its longest valid
  /// stretch from the start and from the goal; RRT-Connect joins the last
  /// state of the first to the first state of the second (nothing to join
  /// when the whole polyline is valid), and the joined path is shortcut,
  /// smoothed and timed like an unseeded one. When nothing of the guide can be
  /// kept, or the join is not found, RRT-Connect searches from the start to
  /// the goal as Plan does (the join and that search each have max_iterations,
  /// and share the plan's time_limit). route[b] says which made plan b:
  /// "seeded" (the guide's stretches) or "unseeded". A guide that is not
  /// finite is not used. An undefined `guides` plans as Plan (route empty).
  /// `max_iterations` > 0 replaces the config's budget for this call.
  /// @throws flowplan::Error if guides are not (B, T', D).
  planning::PlanResult PlanAlong(const planning::PlanRequest& request, const torch::Tensor& guides,
                                 int64_t max_iterations = 0) const;

  int64_t horizon() const override { return horizon_; }
  int64_t state_dim() const override { return state_dim_; }
  const validity::PlanChecker& checker() const { return checker_; }

 private:
  std::shared_ptr<const collision::BodyModel> body_;
  int64_t horizon_, state_dim_;
  double dt_;
  RrtConnectConfig config_;
  validity::PlanChecker checker_;
  double range_;  // the longest edge in use
};

}  // namespace flowplan::classical
