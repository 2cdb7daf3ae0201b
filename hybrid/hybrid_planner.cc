#include "hybrid/hybrid_planner.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/random.h"
#include "validity/plan_quality.h"

namespace flowplan::hybrid {

HybridPlanner::HybridPlanner(std::unique_ptr<planning::LearnedPlanner> proposer,
                             std::unique_ptr<classical::RrtConnectPlanner> fallback, validity::PlanChecker checker,
                             HybridConfig config)
    : proposer_(std::move(proposer)), fallback_(std::move(fallback)), checker_(std::move(checker)), config_(config) {
  if (proposer_->horizon() != fallback_->horizon() || proposer_->state_dim() != fallback_->state_dim()) {
    throw Error("hybrid: the learned planner plans (" + std::to_string(proposer_->horizon()) + ", " +
                std::to_string(proposer_->state_dim()) + ") trajectories and RRT-Connect (" +
                std::to_string(fallback_->horizon()) + ", " + std::to_string(fallback_->state_dim()) + ")");
  }
  if (config_.proposals < 1) throw Error("hybrid.proposals: expected at least one proposal");
}

planning::PlanResult HybridPlanner::Plan(const planning::PlanRequest& request) const {
  planning::CheckEnds(request.start, request.goal, state_dim(), "plan");
  const int64_t B = request.start.size(0), N = config_.proposals, D = state_dim();
  planning::PlanResult result;
  result.plans = torch::empty({B, horizon(), D}, torch::kFloat32);
  result.found = torch::zeros({B}, torch::kBool);
  result.call_seconds.assign(static_cast<size_t>(B), 0.0);
  result.call_plans.assign(static_cast<size_t>(B), 1);
  result.route.assign(static_cast<size_t>(B), "none");
  for (int64_t b = 0; b < B; ++b) {
    const auto began = std::chrono::steady_clock::now();
    planning::PlanRequest one = request;
    one.start = request.start.slice(0, b, b + 1);
    one.goal = request.goal.slice(0, b, b + 1);
    one.seed = StreamSeed(request.seed, static_cast<uint64_t>(b));
    planning::PlanRequest proposals = one;
    proposals.start = one.start.expand({N, D}).contiguous();
    proposals.goal = one.goal.expand({N, D}).contiguous();
    const planning::PlanResult proposed = proposer_->Plan(proposals);
    const std::vector<validity::PlanVerdict> verdicts =
        checker_.Check(proposed.plans, one.start[0], one.goal[0], request.scene, proposed.found);
    bool any_valid = false;
    for (const auto& v : verdicts) any_valid = any_valid || v.valid();
    // The best proposal by guidance cost, then joint-space path length: among the valid ones, or among all of them
    // when none is valid and it seeds RRT-Connect.
    int64_t best = -1;
    if (any_valid || config_.seeded_fallback) {
      const torch::Tensor cost = proposer_->GuidanceCost(proposed.plans, request.scene, request.settings);
      const std::vector<validity::PlanQuality> quality =
          validity::MeasurePlans(proposed.plans, checker_.robot(), proposer_->info().dt, checker_.config().joint_tolerance);
      double best_cost = std::numeric_limits<double>::infinity(), best_length = best_cost;
      for (int64_t n = 0; n < N; ++n) {
        if (any_valid && !verdicts[static_cast<size_t>(n)].valid()) continue;
        const double c = cost[n].item<double>(), length = quality[static_cast<size_t>(n)].joint_path_length;
        if (!any_valid && (!std::isfinite(c) || !std::isfinite(length))) continue;  // a NaN proposal seeds nothing
        if (best < 0 || c < best_cost || (c == best_cost && length < best_length)) {
          best = n;
          best_cost = c;
          best_length = length;
        }
      }
    }
    const std::string of_n = std::to_string(best + 1) + " of " + std::to_string(N);
    if (any_valid) {
      result.plans[b] = proposed.plans[best];
      result.found[b] = true;
      result.route[static_cast<size_t>(b)] = "proposal " + of_n;
    } else {
      planning::PlanRequest classical = one;
      classical.settings = {};  // RRT-Connect takes its settings from its config
      planning::PlanResult fallback =
          best >= 0 ? fallback_->PlanAlong(classical, proposed.plans.slice(0, best, best + 1)) : fallback_->Plan(classical);
      bool seeded = !fallback.route.empty() && fallback.route[0] == "seeded";
      validity::PlanVerdict verdict =
          checker_.Check(fallback.plans, one.start[0], one.goal[0], request.scene, fallback.found)[0];
      if (seeded && !verdict.valid()) {
        // A path along the proposal can be too long to keep within the speed limits: search without it (a search
        // of its own, with RRT-Connect's whole budget). A refused seeded plan is kept if that finds nothing.
        planning::PlanResult unseeded = fallback_->Plan(classical);
        const validity::PlanVerdict second =
            checker_.Check(unseeded.plans, one.start[0], one.goal[0], request.scene, unseeded.found)[0];
        if (second.valid() || unseeded.found[0].item<bool>()) {
          seeded = false;
          fallback = std::move(unseeded);
          verdict = second;
        }
      }
      result.plans[b] = fallback.plans[0];
      result.found[b] = fallback.found[0];  // a path RRT-Connect found but the checker refuses fails with its reason
      result.route[static_cast<size_t>(b)] =
          !verdict.valid() ? "none" : seeded ? "rrt_connect seeded by proposal " + of_n : "rrt_connect";
    }
    result.call_seconds[static_cast<size_t>(b)] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  }
  return result;
}

}  // namespace flowplan::hybrid
