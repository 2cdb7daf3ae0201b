#include "datasets/trajectory_loader.h"

#include <cmath>
#include <numeric>

#include "core/error.h"
#include "core/random.h"

namespace flowplan::datasets {
namespace {
// Stream index reserved for the train/validation permutation.
constexpr uint64_t kSplitStream = 0x5350'4c49'54ULL;
}  // namespace

EvalPairTensors ToTensors(const EvalPairs& pairs, int64_t state_dim) {
  EvalPairTensors out;
  const int64_t p = pairs.count();
  out.start = torch::tensor(pairs.start.empty() ? std::vector<float>{} : pairs.start,
                            torch::kFloat32).reshape({p, state_dim});
  out.goal = torch::tensor(pairs.goal.empty() ? std::vector<float>{} : pairs.goal,
                           torch::kFloat32).reshape({p, state_dim});
  out.names = pairs.names;
  return out;
}

TrajectorySplits SplitTrajectories(const TrajectoryDataset& dataset, double val_fraction,
                                   uint64_t seed, const std::string& where) {
  const int64_t n = dataset.num_episodes;
  const int64_t n_val = static_cast<int64_t>(std::floor(val_fraction * static_cast<double>(n)));
  if (n - n_val < 1) {
    throw Error(where + ": " + std::to_string(n) + " episodes leave none for training");
  }
  std::vector<int64_t> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  Rng rng(StreamSeed(seed, kSplitStream));
  for (int64_t i = n - 1; i > 0; --i) {
    std::swap(order[i], order[rng.Below(static_cast<uint64_t>(i + 1))]);
  }
  const torch::Tensor all =
      torch::from_blob(const_cast<float*>(dataset.states.data()),
                       {n, dataset.horizon, dataset.state_dim}, torch::kFloat32);
  const torch::Tensor index = torch::tensor(order, torch::kInt64);
  TrajectorySplits splits;
  // Validation episodes first in the permutation; sorted so the split is easy to audit.
  splits.val = all.index_select(0, std::get<0>(index.slice(0, 0, n_val).sort())).clone();
  splits.train = all.index_select(0, std::get<0>(index.slice(0, n_val, n).sort())).clone();
  splits.train_pairs = ToTensors(dataset.train_pairs, dataset.state_dim);
  splits.test_pairs = ToTensors(dataset.test_pairs, dataset.state_dim);
  splits.env = dataset.env;
  splits.dt = dataset.dt;
  splits.state_labels = dataset.state_labels;
  splits.robot = dataset.robot;
  splits.fingerprint = DatasetFingerprint(dataset);
  return splits;
}

TrajectorySplits LoadTrajectorySplits(const DataConfig& config, uint64_t seed) {
  return SplitTrajectories(ReadDataset(config.path), config.val_fraction, seed, config.path);
}

}  // namespace flowplan::datasets
