#pragma once

#include <torch/torch.h>

#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/trajectory_loader.h"
#include "planning/planner.h"

namespace flowplan::eval {

/// The `eval` section of an experiment config.
struct EvalConfig {
  int num_plans = 64;     // plans per pair set; plan i goes to pair i mod P
  int64_t seed = 1234;    // noise of the evaluation plans (fixed, so evaluations are comparable)

  template <class V>
  void Visit(V& v) {
    v.Field("num_plans", num_plans, "plans per evaluation (plan i targets pair i mod P)", config::Positive());
    v.Field("seed", seed, "seed of the evaluation noise", config::NonNegative());
  }
};

/// Stitching error of one start/goal pair set (SPEC section 4): per plan,
/// 0.5 * (|x_1 - start| + |x_{T-2} - goal|) over the position dimensions of the
/// state (PositionDims of its labels: x, y for the particle, q1…q7 for the Franka).
struct StitchingResult {
  std::string pairs;                  // "test" or "train"
  double mean = 0.0;
  double stddev = 0.0;
  std::vector<std::string> pair_names;  // (P,)
  std::vector<double> pair_means;       // (P,)
  torch::Tensor plans;                  // (num_plans, T, D) raw
  torch::Tensor pair_index;             // (num_plans,) which pair each plan targets
};

/// The position dimensions of a state, from its labels (D,): every label but
/// the time derivatives, which are named by "v" or "d" before the label of
/// their position ("vx" of "x", "dq3" of "q3").
/// @throws flowplan::Error if no label is a position.
std::vector<int64_t> PositionDims(const std::vector<std::string>& state_labels);

/// Per-plan stitching errors. plans: (N, T, D); start, goal: (N, D) raw;
/// positions: indices into D -> (N,).
torch::Tensor StitchingErrors(const torch::Tensor& plans, const torch::Tensor& start, const torch::Tensor& goal,
                              const std::vector<int64_t>& positions);

/// Plans `config.num_plans` times between the pairs (without obstacles) and
/// scores them on the positions among `state_labels`. `threads` workers plan fixed chunks of the plans, each seeded
/// from `config.seed` and its index (planning::PlanInChunks), so the result
/// does not depend on the thread count (call with LibTorch's intra-op threads
/// set to 1).
/// @throws flowplan::Error if there are no pairs.
StitchingResult EvaluateStitching(const planning::Planner& planner, const datasets::EvalPairTensors& pairs,
                                  const std::vector<std::string>& state_labels, const std::string& label,
                                  const EvalConfig& config, int threads = 1);

/// {"pairs": "test", "mean": …, "stddev": …, "num_plans": …, "per_pair": {"name": mean, …}};
/// NaN (no plans) is written as null.
std::string ToJson(const StitchingResult& result);

}  // namespace flowplan::eval
