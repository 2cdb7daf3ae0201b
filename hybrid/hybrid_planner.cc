#include "hybrid/hybrid_planner.h"

#include <chrono>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/random.h"
#include "planning/time_parametrize.h"
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

void HybridPlanner::RetimeTooFast(torch::Tensor& candidates, std::vector<validity::PlanVerdict>& verdicts,
                                  std::vector<bool>& retimed, const planning::PlanRequest& one,
                                  const collision::Checker& world) const {
  std::vector<int64_t> too_fast;
  for (size_t n = 0; n < verdicts.size(); ++n) {
    if (verdicts[n].failure == validity::Failure::kSpeedLimit) too_fast.push_back(static_cast<int64_t>(n));
  }
  if (too_fast.empty()) return;
  const int64_t T = horizon(), D = state_dim(), J = checker_.robot().num_joints();
  std::vector<torch::Tensor> timed;
  for (const int64_t n : too_fast) {
    // The proposal's states as a polyline: they passed the start, goal and joint-limit checks, and every state of
    // the re-timed plan lies on a segment between two of them (the motion between two states may cut a corner of
    // the polyline: the re-timed plan is checked again in full).
    timed.push_back(planning::TimedStates(candidates[n].slice(1, 0, J).to(torch::kFloat64), T, proposer_->info().dt, D,
                                          checker_.robot().description().velocity_limit)
                        .to(candidates.scalar_type()));
  }
  const torch::Tensor again = torch::stack(timed);  // (R, T, D)
  const std::vector<validity::PlanVerdict> second =
      checker_.CheckIn(world, again, one.start[0], one.goal[0]);
  candidates = candidates.clone();
  for (size_t r = 0; r < too_fast.size(); ++r) {
    if (!second[r].valid()) continue;  // the proposal keeps its own verdict, and its own states for a seed
    const int64_t n = too_fast[r];
    candidates[n] = again[static_cast<int64_t>(r)];
    verdicts[static_cast<size_t>(n)] = second[r];
    retimed[static_cast<size_t>(n)] = true;
  }
}

HybridPlanner::Proposals HybridPlanner::Propose(const planning::PlanRequest& one,
                                                const planning::PlanSettings& settings,
                                                const planning::PlanSettings& cost_settings, bool for_seed,
                                                const collision::Checker& world) const {
  const int64_t N = config_.proposals, D = state_dim();
  planning::PlanRequest request = one;
  request.start = one.start.expand({N, D}).contiguous();
  request.goal = one.goal.expand({N, D}).contiguous();
  request.settings = settings;
  const planning::PlanResult planned = proposer_->Plan(request);
  Proposals p;
  p.plans = planned.plans;
  p.verdicts = checker_.CheckIn(world, p.plans, one.start[0], one.goal[0], planned.found);
  p.retimed.assign(static_cast<size_t>(N), false);
  RetimeTooFast(p.plans, p.verdicts, p.retimed, one, world);
  for (const auto& v : p.verdicts) p.any_valid = p.any_valid || v.valid();
  // The best candidate by guidance cost, then joint-space path length: among the valid ones, or among all the
  // finite proposals when none is valid and one seeds RRT-Connect. With one such candidate there is no choice.
  if (!p.any_valid && !(config_.seeded_fallback && for_seed)) return p;
  std::vector<int64_t> eligible;
  for (int64_t n = 0; n < N; ++n) {
    const bool ok = p.any_valid ? p.verdicts[static_cast<size_t>(n)].valid()
                                : torch::isfinite(p.plans[n]).all().item<bool>();  // a NaN proposal seeds nothing
    if (ok) eligible.push_back(n);
  }
  if (eligible.size() == 1) {
    p.best = eligible[0];
    return p;
  }
  if (eligible.empty()) return p;
  const torch::Tensor cost = proposer_->GuidanceCost(p.plans, one.scene, cost_settings);
  const std::vector<validity::PlanQuality> quality =
      validity::MeasurePlans(p.plans, checker_.robot(), proposer_->info().dt, checker_.config().joint_tolerance);
  double best_cost = std::numeric_limits<double>::infinity(), best_length = best_cost;
  for (const int64_t n : eligible) {
    const double c = cost[n].item<double>(), length = quality[static_cast<size_t>(n)].joint_path_length;
    // A seed needs a finite cost and length; a valid plan is chosen whatever its cost (the first of the valid ones
    // when no cost is finite).
    if (!p.any_valid && (!std::isfinite(c) || !std::isfinite(length))) continue;
    if (p.best < 0 || c < best_cost || (c == best_cost && length < best_length)) {
      p.best = n;
      best_cost = c;
      best_length = length;
    }
  }
  return p;
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
  result.refused.assign(static_cast<size_t>(B), false);
  result.failure.assign(static_cast<size_t>(B), "");
  for (int64_t b = 0; b < B; ++b) {
    const auto began = std::chrono::steady_clock::now();
    planning::PlanRequest one = request;
    one.start = request.start.slice(0, b, b + 1);
    one.goal = request.goal.slice(0, b, b + 1);
    one.seed = StreamSeed(request.seed, static_cast<uint64_t>(b));
    planning::PlanRequest classical = one;
    classical.settings = {};  // RRT-Connect takes its settings from its config
    if (config_.order == HybridOrder::kClassicalFirst) {
      // RRT-Connect on a small budget first: the easy problems end here, as fast as RRT-Connect alone; a start or
      // goal it refuses ends the request.
      const planning::PlanResult first = fallback_->PlanAlong(classical, torch::Tensor(), config_.classical_iterations);
      if (first.found[0].item<bool>() || first.refused[0]) {
        result.plans[b] = first.plans[0];
        result.found[b] = first.found[0];
        result.refused[static_cast<size_t>(b)] = first.refused[0];
        result.failure[static_cast<size_t>(b)] = first.failure[0];
        result.route[static_cast<size_t>(b)] = first.found[0].item<bool>() ? "rrt_connect" : "none";
        result.call_seconds[static_cast<size_t>(b)] =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
        continue;
      }
    }
    // Every check from here on is in the request's scene: its collision world is built once.
    const collision::Checker world = checker_.ConfigurationChecker(one.scene, one.world);
    // The unguided proposals first when asked (no cost gradients: a fraction of a guided plan's time), then the
    // guided ones when none of those is valid.
    Proposals proposed;
    bool unguided = config_.unguided_first;
    if (unguided) {
      planning::PlanSettings free = request.settings;
      free.values["guidance.scale"] = 0.0;
      proposed = Propose(one, free, request.settings, /*for_seed=*/false, world);
    }
    if (!proposed.any_valid) {
      unguided = false;
      proposed = Propose(one, request.settings, request.settings, /*for_seed=*/true, world);
    }
    FLOWPLAN_DEMAND(!proposed.any_valid || proposed.best >= 0);
    const bool any_valid = proposed.any_valid;
    const int64_t best = proposed.best;
    const torch::Tensor& candidates = proposed.plans;
    const std::string of_n = std::to_string(best + 1) + " of " + std::to_string(N);
    if (any_valid) {
      result.plans[b] = candidates[best];
      result.found[b] = true;
      result.route[static_cast<size_t>(b)] = "proposal " + of_n + (unguided ? " unguided" : "") +
                                               (proposed.retimed[static_cast<size_t>(best)] ? " retimed" : "");
    } else {
      planning::PlanResult fallback =
          best >= 0 ? fallback_->PlanAlong(classical, candidates.slice(0, best, best + 1)) : fallback_->Plan(classical);
      bool seeded = !fallback.route.empty() && fallback.route[0] == "seeded";
      validity::PlanVerdict verdict =
          checker_.CheckIn(world, fallback.plans, one.start[0], one.goal[0], fallback.found)[0];
      if (seeded && !verdict.valid()) {
        // A path along the proposal can be too long to keep within the speed limits: search without it (a search
        // of its own, with RRT-Connect's whole budget). A refused seeded plan is kept if that finds nothing.
        planning::PlanResult unseeded = fallback_->Plan(classical);
        const validity::PlanVerdict second =
            checker_.CheckIn(world, unseeded.plans, one.start[0], one.goal[0], unseeded.found)[0];
        if (second.valid() || unseeded.found[0].item<bool>()) {
          seeded = false;
          fallback = std::move(unseeded);
          verdict = second;
        }
      }
      result.plans[b] = fallback.plans[0];
      result.found[b] = fallback.found[0];  // a path RRT-Connect found but the checker refuses fails with its reason
      if (!fallback.refused.empty()) {
        result.refused[static_cast<size_t>(b)] = fallback.refused[0];
        result.failure[static_cast<size_t>(b)] = fallback.failure[0];
      }
      result.route[static_cast<size_t>(b)] =
          !verdict.valid() ? "none" : seeded ? "rrt_connect seeded by proposal " + of_n : "rrt_connect";
    }
    result.call_seconds[static_cast<size_t>(b)] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  }
  return result;
}

}  // namespace flowplan::hybrid
