#pragma once

// The hybrid planner: valid or nothing. A learned planner proposes N plans for
// a request in one call; the plan checker (validity/plan_check.h) keeps the
// valid ones and the best of them by guidance cost, then by joint-space path
// length, is returned. A proposal refused first for moving a joint too fast is
// timed again along its own path (planning/time_parametrize.h: the same states
// as a polyline, rest to rest over the plan's duration) and checked again in
// full. With
// unguided_first, N proposals without guidance come first and the guided ones
// only when none of those is valid. When no proposal is valid, RRT-Connect
// plans the request (with seeded_fallback, seeded by the guided proposal of
// least cost: it keeps that proposal's valid stretches from the start and to
// the goal and joins them, classical::RrtConnectPlanner::PlanAlong; if that
// plan is not valid, it plans again unseeded), and its plan is checked too.
// Every plan says which way it was made (PlanResult::route): "proposal k of N"
// (followed by " unguided" and/or " retimed"), "rrt_connect", "rrt_connect
// seeded by proposal k of N", or "none" when neither gave a valid plan (the
// plan returned is then RRT-Connect's, with its found: a path the checker
// refuses, which the report's check names the reason of, or the straight line
// it falls back to, found = false). With order = classical_first, RRT-Connect
// plans first within classical_iterations (a cheap plan where one is easy to
// find) and the learned planner, then the fallback as above, only when it
// fails. A start or goal the checker refuses is not planned: the result is
// refused, with the checker's reason (PlanResult::refused, ::failure).

#include <memory>

#include "classical/rrt_connect.h"
#include "core/config.h"
#include "planning/learned_planner.h"
#include "planning/planner.h"
#include "validity/plan_check.h"

namespace flowplan::hybrid {

/// Which planner of the hybrid goes first.
enum class HybridOrder {
  kLearnedFirst,    // the learned planner proposes; RRT-Connect when no proposal is valid
  kClassicalFirst,  // RRT-Connect within classical_iterations first; then as learned_first
};

inline const config::EnumNames<HybridOrder>& EnumEntries(HybridOrder) {
  static const config::EnumNames<HybridOrder> names = {{HybridOrder::kLearnedFirst, "learned_first"},
                                                       {HybridOrder::kClassicalFirst, "classical_first"}};
  return names;
}

/// The `hybrid` section of an experiment config.
struct HybridConfig {
  // The defaults (one guided proposal, RRT-Connect seeded by it when it is not valid) are those the scene families'
  // validation problems chose (docs/results.md, "Scene families: every planner").
  int64_t proposals = 1;         // N: plans the learned planner proposes per request, in one call
  bool seeded_fallback = true;   // RRT-Connect starts from the proposal of least guidance cost (PlanAlong)
  bool unguided_first = false;  // propose without guidance first; the guided proposals only when none is valid
  HybridOrder order = HybridOrder::kLearnedFirst;
  int64_t classical_iterations = 300;  // classical_first: RRT-Connect's iterations before the learned planner
  template <class V>
  void Visit(V& v) {
    v.Field("proposals", proposals, "plans the learned planner proposes per request, in one call",
            config::Positive());
    v.Field("seeded_fallback", seeded_fallback,
            "when no proposal is valid, RRT-Connect keeps the valid ends of the proposal of least guidance cost and "
            "joins them");
    v.Field("unguided_first", unguided_first,
            "propose without guidance first (guidance.scale = 0), and guided only when no unguided proposal is valid");
    v.Field("order", order, "which planner goes first");
    v.Field("classical_iterations", classical_iterations,
            "classical_first: RRT-Connect's iterations before the learned planner proposes", config::Positive());
  }
};

class HybridPlanner : public planning::Planner {
 public:
  /// @throws flowplan::Error if the proposer's and RRT-Connect's trajectories differ.
  HybridPlanner(std::unique_ptr<planning::LearnedPlanner> proposer,
                std::unique_ptr<classical::RrtConnectPlanner> fallback, validity::PlanChecker checker,
                HybridConfig config);

  /// Each of the B requests on its own: N proposals (one call, seeded from
  /// StreamSeed(request.seed, b)), checked; RRT-Connect (the same seed) when
  /// none is valid. call_seconds[b] is the wall time of request b, all of it
  /// (proposals, checks, fallback), and call_plans[b] = 1.
  planning::PlanResult Plan(const planning::PlanRequest& request) const override;

  int64_t horizon() const override { return proposer_->horizon(); }
  int64_t state_dim() const override { return proposer_->state_dim(); }

 private:
  /// N proposals for one request, checked (and re-timed where only too fast).
  struct Proposals {
    torch::Tensor plans;                          // (N, T, D): as proposed, or re-timed where that made them valid
    std::vector<validity::PlanVerdict> verdicts;  // (N)
    std::vector<bool> retimed;                    // (N)
    bool any_valid = false;
    int64_t best = -1;  // the valid one of least guidance cost, then path length; with none valid and
                        // seeded_fallback, the finite proposal chosen so; -1 otherwise
  };

  /// Proposes for `one` (a request of one plan) with the proposer's `settings`; costs are weighed with
  /// `cost_settings`. With none valid, a proposal to seed RRT-Connect is chosen only when `for_seed`. The
  /// proposals are checked in `world`: checker_.ConfigurationChecker(one.scene, one.world).
  Proposals Propose(const planning::PlanRequest& one, const planning::PlanSettings& settings,
                    const planning::PlanSettings& cost_settings, bool for_seed,
                    const collision::Checker& world) const;

  /// Proposals whose first failure is a joint moving too fast (their ends and joint limits passed; the collision
  /// checks, which come later, were not run) are timed again along their own path (planning::TimeAlongPath) and
  /// checked again in full; those that then pass replace their proposal in `candidates` (N, T, D), with their
  /// verdicts, and are marked in `retimed` (N). Checked in `world`, as in Propose.
  void RetimeTooFast(torch::Tensor& candidates, std::vector<validity::PlanVerdict>& verdicts,
                     std::vector<bool>& retimed, const planning::PlanRequest& one,
                     const collision::Checker& world) const;

  std::unique_ptr<planning::LearnedPlanner> proposer_;
  std::unique_ptr<classical::RrtConnectPlanner> fallback_;
  validity::PlanChecker checker_;
  HybridConfig config_;
};

}  // namespace flowplan::hybrid
