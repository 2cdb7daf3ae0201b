#include "planning/planner.h"

#include <chrono>

#include "core/error.h"
#include "core/format.h"
#include "core/interrupt.h"
#include "core/parallel.h"
#include "core/random.h"

namespace flowplan::planning {

void CheckEnds(const torch::Tensor& start, const torch::Tensor& goal, int64_t state_dim, const std::string& where) {
  const std::string want = "(B, " + std::to_string(state_dim) + ")";
  auto shape = [](const torch::Tensor& t) { return t.defined() ? ShapeText(t.sizes().vec()) : "(undefined)"; };
  if (!start.defined() || start.dim() != 2 || start.size(1) != state_dim) {
    throw Error(where + ": start: expected " + want + ", got " + shape(start));
  }
  if (!goal.defined() || goal.sizes() != start.sizes()) {
    throw Error(where + ": goal: expected " + shape(start) + ", got " + shape(goal));
  }
}

PlanResult PlanInChunks(const Planner& planner, const PlanRequest& request, int threads, int64_t chunk) {
  CheckEnds(request.start, request.goal, planner.state_dim(), "plan");
  at::globalContext().setFlushDenormal(true);  // as in training; worker threads inherit it
  const int64_t N = request.start.size(0);
  const int chunks = static_cast<int>((N + chunk - 1) / chunk);
  std::vector<PlanResult> parts(static_cast<size_t>(chunks));
  ParallelFor(chunks, threads, [&](int, int c) {
    ThrowIfInterrupted();
    const int64_t begin = c * chunk, end = std::min(N, begin + chunk);
    PlanRequest part = request;
    part.start = request.start.slice(0, begin, end);
    part.goal = request.goal.slice(0, begin, end);
    part.seed = StreamSeed(request.seed, static_cast<uint64_t>(c));
    parts[c] = planner.Plan(part);
  });
  PlanResult result;
  std::vector<torch::Tensor> plans, found;
  for (const PlanResult& part : parts) {
    plans.push_back(part.plans);
    found.push_back(part.found);
    result.call_seconds.insert(result.call_seconds.end(), part.call_seconds.begin(), part.call_seconds.end());
    result.call_plans.insert(result.call_plans.end(), part.call_plans.begin(), part.call_plans.end());
    result.route.insert(result.route.end(), part.route.begin(), part.route.end());
    result.refused.insert(result.refused.end(), part.refused.begin(), part.refused.end());
    result.failure.insert(result.failure.end(), part.failure.begin(), part.failure.end());
  }
  // Every part says it, or none.
  if (result.route.size() != static_cast<size_t>(N)) result.route.clear();
  if (result.refused.size() != static_cast<size_t>(N)) result.refused.clear();
  if (result.failure.size() != static_cast<size_t>(N)) result.failure.clear();
  result.plans = chunks > 0 ? torch::cat(plans, 0) : torch::empty({0, planner.horizon(), planner.state_dim()});
  result.found = chunks > 0 ? torch::cat(found, 0) : torch::empty({0}, torch::kBool);
  return result;
}

}  // namespace flowplan::planning
