#include "eval/stitching.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"
#include "models/trajectory_net.h"

namespace flowplan::eval {

torch::Tensor StitchingErrors(const torch::Tensor& plans, const torch::Tensor& start, const torch::Tensor& goal) {
  if (plans.dim() != 3 || plans.size(1) < 3) {
    throw Error("stitching error: plans: expected (N, T, D) with T >= 3, got " + models::ShapeString(plans));
  }
  for (const auto& [name, ends] : {std::pair{"start", &start}, std::pair{"goal", &goal}}) {
    if (ends->dim() != 2 || ends->size(0) != plans.size(0) || ends->size(1) != plans.size(2)) {
      throw Error(std::string("stitching error: ") + name + ": expected (" + std::to_string(plans.size(0)) + ", " +
                  std::to_string(plans.size(2)) + "), got " + models::ShapeString(*ends));
    }
  }
  const int64_t T = plans.size(1), positions = plans.size(2) / 2;
  const torch::Tensor first = plans.select(1, 1).slice(1, 0, positions);
  const torch::Tensor last = plans.select(1, T - 2).slice(1, 0, positions);
  return 0.5 * ((first - start.slice(1, 0, positions)).norm(2, 1) + (last - goal.slice(1, 0, positions)).norm(2, 1));
}

StitchingResult EvaluateStitching(const planning::Planner& planner, const datasets::EvalPairTensors& pairs,
                                  const std::string& label, const EvalConfig& config, int threads) {
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
  const torch::Tensor errors = StitchingErrors(result.plans, start, goal).to(torch::kFloat64);
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
