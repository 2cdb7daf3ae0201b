#include "eval/stitching.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/format.h"
#include "models/trajectory_net.h"

namespace flowplan::eval {

std::vector<int64_t> PositionDims(const std::vector<std::string>& state_labels) {
  auto is_derivative = [&](const std::string& label) {
    if (label.size() < 2 || (label[0] != 'v' && label[0] != 'd')) return false;
    return std::find(state_labels.begin(), state_labels.end(), label.substr(1)) != state_labels.end();
  };
  std::vector<int64_t> positions;
  for (size_t i = 0; i < state_labels.size(); ++i) {
    if (!is_derivative(state_labels[i])) positions.push_back(static_cast<int64_t>(i));
  }
  if (positions.empty()) throw Error("stitching error: no position among the state labels");
  return positions;
}

torch::Tensor StitchingErrors(const torch::Tensor& plans, const torch::Tensor& start, const torch::Tensor& goal,
                              const std::vector<int64_t>& positions) {
  if (plans.dim() != 3 || plans.size(1) < 3) {
    throw Error("stitching error: plans: expected (N, T, D) with T >= 3, got " + models::ShapeString(plans));
  }
  for (const auto& [name, ends] : {std::pair{"start", &start}, std::pair{"goal", &goal}}) {
    if (ends->dim() != 2 || ends->size(0) != plans.size(0) || ends->size(1) != plans.size(2)) {
      throw Error(std::string("stitching error: ") + name + ": expected (" + std::to_string(plans.size(0)) + ", " +
                  std::to_string(plans.size(2)) + "), got " + models::ShapeString(*ends));
    }
  }
  for (const int64_t i : positions) {
    if (i < 0 || i >= plans.size(2)) {
      throw Error("stitching error: position dimension " + std::to_string(i) + " is not among the state's " +
                  std::to_string(plans.size(2)));
    }
  }
  const int64_t T = plans.size(1);
  const torch::Tensor index = torch::tensor(positions, torch::kInt64);
  auto pick = [&](const torch::Tensor& states) { return states.index_select(1, index); };
  return 0.5 * ((pick(plans.select(1, 1)) - pick(start)).norm(2, 1) +
                (pick(plans.select(1, T - 2)) - pick(goal)).norm(2, 1));
}

StitchingResult EvaluateStitching(const planning::Planner& planner, const datasets::EvalPairTensors& pairs,
                                  const std::vector<std::string>& state_labels, const std::string& label,
                                  const EvalConfig& config, int threads) {
  if (static_cast<int64_t>(state_labels.size()) != planner.state_dim()) {
    throw Error("stitching evaluation: " + std::to_string(state_labels.size()) + " state labels for a planner of " +
                std::to_string(planner.state_dim()) + " state dimensions");
  }
  const std::vector<int64_t> positions = PositionDims(state_labels);
  const int64_t P = pairs.start.defined() ? pairs.start.size(0) : 0;
  if (P == 0) throw Error("stitching evaluation: the dataset defines no " + label + " pairs");
  const torch::Tensor pair_index = torch::arange(config.num_plans, torch::kInt64) % P;
  const torch::Tensor start = pairs.start.index_select(0, pair_index);
  const torch::Tensor goal = pairs.goal.index_select(0, pair_index);
  StitchingResult result;
  result.pairs = label;
  planning::PlanRequest request;
  request.start = start;
  request.goal = goal;
  request.seed = static_cast<uint64_t>(config.seed);
  result.plans = planning::PlanInChunks(planner, request, threads).plans;
  result.pair_index = pair_index;
  const torch::Tensor errors = StitchingErrors(result.plans, start, goal, positions).to(torch::kFloat64);
  result.mean = errors.mean().item<double>();
  result.stddev = config.num_plans > 1 ? errors.std(/*unbiased=*/false).item<double>() : 0.0;
  for (int64_t p = 0; p < P; ++p) {
    result.pair_names.push_back(p < static_cast<int64_t>(pairs.names.size()) ? pairs.names[p] : std::to_string(p));
    const torch::Tensor mask = pair_index == p;
    result.pair_means.push_back(mask.any().item<bool>() ? errors.index({mask}).mean().item<double>() : NAN);
  }
  return result;
}

std::string ToJson(const StitchingResult& result) {
  std::string out = "{\"pairs\": " + JsonString(result.pairs) + ", \"mean\": " + JsonNumber(result.mean) +
                    ", \"stddev\": " + JsonNumber(result.stddev) +
                    ", \"num_plans\": " + std::to_string(result.plans.defined() ? result.plans.size(0) : 0) +
                    ", \"per_pair\": {";
  for (size_t i = 0; i < result.pair_names.size(); ++i) {
    out += (i ? ", " : "") + JsonString(result.pair_names[i]) + ": " + JsonNumber(result.pair_means[i]);
  }
  return out + "}}";
}

}  // namespace flowplan::eval
