#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "datasets/trajectory_dataset.h"

namespace flowplan::datasets {

/// The `data` section of an experiment config: which file to train on and how to split it.
struct DataConfig {
  std::string path = "data/particle_cross.h5";
  double val_fraction = 0.05;  // episodes held out for the validation loss

  template <class V>
  void Visit(V& v) {
    v.Field("path", path, "HDF5 trajectory file written by `flowplan generate`");
    v.Field("val_fraction", val_fraction, "fraction of episodes held out for validation",
            config::InRange(0.0, 0.5));
  }
};

/// Evaluation start/goal pairs as tensors, in raw (de-normalized) units.
struct EvalPairTensors {
  torch::Tensor start;             // (P, D)
  torch::Tensor goal;              // (P, D)
  std::vector<std::string> names;  // (P,)
};

/// A dataset split into training and validation episodes, as float32 tensors in
/// raw units (normalization belongs to the model, see models::MinMaxNormalizer).
struct TrajectorySplits {
  torch::Tensor train;  // (N_train, T, D)
  torch::Tensor val;    // (N_val, T, D), possibly empty
  EvalPairTensors train_pairs;
  EvalPairTensors test_pairs;
  std::string env;
  double dt = 0.0;
  std::vector<std::string> state_labels;  // (D,)
  kinematics::RobotDescription robot;
  std::string fingerprint;                // DatasetFingerprint() of the file
  int64_t horizon() const { return train.size(1); }
  int64_t state_dim() const { return train.size(2); }
};

/// Reads `config.path` and splits its episodes with a permutation drawn from `seed`.
/// @throws flowplan::Error if the file is bad or leaves no training episode.
TrajectorySplits LoadTrajectorySplits(const DataConfig& config, uint64_t seed);

/// The same, from a dataset already in memory.
TrajectorySplits SplitTrajectories(const TrajectoryDataset& dataset, double val_fraction,
                                   uint64_t seed, const std::string& where);

/// Evaluation pairs of a dataset as tensors.
EvalPairTensors ToTensors(const EvalPairs& pairs, int64_t state_dim);

}  // namespace flowplan::datasets
