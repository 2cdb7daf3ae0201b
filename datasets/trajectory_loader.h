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
  torch::Tensor train;  // (N_train, T, D); undefined when loaded by parts without validation (see LoadTrajectorySplits)
  torch::Tensor val;    // (N_val, T, D), possibly empty
  EvalPairTensors train_pairs;
  EvalPairTensors test_pairs;
  kinematics::TrajectoryInfo info;        // env, dt, T, state labels (D), robot
  std::string fingerprint;                // DatasetFingerprint() of the file; empty when loaded by parts
  int64_t num_train = 0;                  // N_train of the whole split
  std::vector<int> parts;                 // the data parts train_parts holds (ascending); empty: none split off
  std::vector<torch::Tensor> train_parts;  // (N_p, T, D) per part: training episodes p, p + Q, ... in split order (Q data parts)
  int64_t horizon() const { return info.horizon; }        // T
  int64_t state_dim() const { return info.state_dim(); }  // D
};

/// Which training episodes a process of a data-parallel job keeps.
struct PartSelection {
  int count = 1;          // Q: the i-th training episode (in split order) is in part i mod Q
  std::vector<int> mine;  // the parts to keep, ascending
  bool everything = true;  // also the whole training split, the validation episodes and the fingerprint
};

/// Reads `config.path` and splits its episodes with a permutation drawn from `seed`.
/// @throws flowplan::Error if the file is bad or leaves no training episode.
TrajectorySplits LoadTrajectorySplits(const DataConfig& config, uint64_t seed);

/// The same, keeping the training episodes of `parts.mine` in `train_parts`;
/// without `parts.everything` only those episodes are read from the file
/// (train and val stay undefined/empty and the fingerprint empty).
/// @throws flowplan::Error as above, and if there are fewer training episodes than parts.
TrajectorySplits LoadTrajectorySplits(const DataConfig& config, uint64_t seed, const PartSelection& parts);

/// The same, from a dataset already in memory.
TrajectorySplits SplitTrajectories(const TrajectoryDataset& dataset, double val_fraction,
                                   uint64_t seed, const std::string& where);

/// Evaluation pairs of a dataset as tensors.
EvalPairTensors ToTensors(const EvalPairs& pairs, int64_t state_dim);

}  // namespace flowplan::datasets
