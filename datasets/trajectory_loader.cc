#include "datasets/trajectory_loader.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "core/random.h"
#include "datasets/h5.h"

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

namespace {

/// The episode permutation of the split: validation episodes first.
std::vector<int64_t> SplitOrder(int64_t n, uint64_t seed) {
  std::vector<int64_t> order(static_cast<size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  Rng rng(StreamSeed(seed, kSplitStream));
  for (int64_t i = n - 1; i > 0; --i) {
    std::swap(order[i], order[rng.Below(static_cast<uint64_t>(i + 1))]);
  }
  return order;
}

/// What the splits carry of the dataset besides its episodes.
void CopyDescription(const TrajectoryDataset& dataset, TrajectorySplits& splits) {
  splits.train_pairs = ToTensors(dataset.train_pairs, dataset.info.state_dim());
  splits.test_pairs = ToTensors(dataset.test_pairs, dataset.info.state_dim());
  splits.info = dataset.info;
}

int64_t ValidationCount(int64_t n, double val_fraction, const std::string& where) {
  const int64_t n_val = static_cast<int64_t>(std::floor(val_fraction * static_cast<double>(n)));
  if (n - n_val < 1) {
    throw Error(where + ": " + std::to_string(n) + " episodes leave none for training");
  }
  return n_val;
}

}  // namespace

TrajectorySplits SplitTrajectories(const TrajectoryDataset& dataset, double val_fraction,
                                   uint64_t seed, const std::string& where) {
  const int64_t n = dataset.num_episodes;
  const int64_t n_val = ValidationCount(n, val_fraction, where);
  const std::vector<int64_t> order = SplitOrder(n, seed);
  const torch::Tensor all =
      torch::from_blob(const_cast<float*>(dataset.states.data()),
                       {n, dataset.info.horizon, dataset.info.state_dim()}, torch::kFloat32);
  const torch::Tensor index = torch::tensor(order, torch::kInt64);
  TrajectorySplits splits;
  // Validation episodes first in the permutation; sorted so the split is easy to audit.
  splits.val = all.index_select(0, std::get<0>(index.slice(0, 0, n_val).sort())).clone();
  splits.train = all.index_select(0, std::get<0>(index.slice(0, n_val, n).sort())).clone();
  CopyDescription(dataset, splits);
  splits.fingerprint = DatasetFingerprint(dataset);
  splits.num_train = splits.train.size(0);
  return splits;
}

TrajectorySplits LoadTrajectorySplits(const DataConfig& config, uint64_t seed) {
  return SplitTrajectories(ReadDataset(config.path), config.val_fraction, seed, config.path);
}

}  // namespace flowplan::datasets

namespace flowplan::datasets {

TrajectorySplits LoadTrajectorySplits(const DataConfig& config, uint64_t seed, const PartSelection& parts) {
  FLOWPLAN_DEMAND(parts.count >= 1);
  for (const int p : parts.mine) FLOWPLAN_DEMAND(p >= 0 && p < parts.count);
  TrajectorySplits splits;
  std::vector<int64_t> train_episodes;  // file rows of the training split, ascending (the split order)
  if (parts.everything) {
    splits = LoadTrajectorySplits(config, seed);
  } else {
    const int64_t n = h5::File::OpenReadOnly(config.path).Shape("/states").at(0);
    const int64_t n_val = ValidationCount(n, config.val_fraction, config.path);
    const std::vector<int64_t> order = SplitOrder(n, seed);
    train_episodes.assign(order.begin() + n_val, order.end());
    std::sort(train_episodes.begin(), train_episodes.end());
    splits.num_train = static_cast<int64_t>(train_episodes.size());
  }
  if (splits.num_train < parts.count) {
    throw Error("train.data_parts=" + std::to_string(parts.count) + ": " + config.path + " has only " +
                std::to_string(splits.num_train) + " training episodes");
  }
  if (parts.everything) {
    for (const int p : parts.mine) {
      splits.parts.push_back(p);
      splits.train_parts.push_back(splits.train.slice(0, p, splits.num_train, parts.count).clone());
    }
    return splits;
  }
  // Only this process's episodes are read: part p holds split positions p, p + Q, ... (Q data parts)
  std::vector<int64_t> rows;
  for (int64_t i = 0; i < splits.num_train; ++i) {
    if (std::find(parts.mine.begin(), parts.mine.end(), static_cast<int>(i % parts.count)) != parts.mine.end()) {
      rows.push_back(train_episodes[static_cast<size_t>(i)]);
    }
  }
  const TrajectoryDataset dataset = ReadDatasetEpisodes(config.path, rows);
  const torch::Tensor kept = torch::from_blob(const_cast<float*>(dataset.states.data()),
                                              {dataset.num_episodes, dataset.info.horizon, dataset.info.state_dim()},
                                              torch::kFloat32);
  // rows are ascending in split order, so part p's episodes are every k-th row of `kept`, from p's first.
  const int64_t mine = static_cast<int64_t>(parts.mine.size());
  for (int64_t k = 0; k < mine; ++k) {
    splits.parts.push_back(parts.mine[static_cast<size_t>(k)]);
    splits.train_parts.push_back(kept.slice(0, k, kept.size(0), mine).clone());
  }
  splits.val = torch::empty({0, dataset.info.horizon, dataset.info.state_dim()});
  CopyDescription(dataset, splits);
  return splits;
}

}  // namespace flowplan::datasets
