#pragma once

#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <vector>

#include "kinematics/trajectory_info.h"
#include "models/normalizer.h"

namespace flowplan::checkpoints {

inline constexpr const char* kCheckpointFormatName = "flowplan.checkpoint";
inline constexpr int64_t kCheckpointFormatVersion = 2;  // 2: robot description, data fingerprint

/// Everything in a checkpoint besides module and optimizer weights.
struct CheckpointHeader {
  int64_t step = 0;                       // optimizer steps taken
  std::string config_yaml;                // the run's resolved config
  models::MinMaxNormalizer normalizer;    // fitted on the training split
  std::vector<torch::Tensor> rng_states;  // (S,) uint8 state of each data part's torch::Generator, part 0 first
  kinematics::TrajectoryInfo trajectory;  // the data's: env, dt, T the network is trained for, labels, robot
  std::string data_fingerprint;           // datasets::DatasetFingerprint() of the training data
};

/// The trainable pieces a checkpoint stores; any may be null when loading.
struct CheckpointModules {
  torch::nn::Module* model = nullptr;           // online weights
  torch::nn::Module* ema = nullptr;             // EMA weights (used for evaluation and export)
  torch::optim::Optimizer* optimizer = nullptr;  // moments and per-parameter state
};

/// Writes a self-describing checkpoint atomically (temporary name, then rename).
/// @throws flowplan::Error if it cannot be written.
void SaveCheckpoint(const std::string& path, const CheckpointHeader& header, const CheckpointModules& modules);

/// Reads the header of a checkpoint.
/// @throws flowplan::Error naming the file for missing, truncated or foreign
///         files and for other format versions.
CheckpointHeader ReadCheckpointHeader(const std::string& path);

/// Loads the weights into the non-null members of `modules`, which must have the
/// architecture the checkpoint was written from; weights and optimizer state
/// end up on `device`, whichever device wrote them.
/// @throws flowplan::Error naming the file and the part that does not fit.
void LoadCheckpointWeights(const std::string& path, const CheckpointModules& modules,
                           const torch::Device& device = torch::kCPU);

}  // namespace flowplan::checkpoints
