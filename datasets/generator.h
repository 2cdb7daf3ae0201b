#pragma once

#include <cstdint>
#include <string>

#include "datasets/episode_task.h"
#include "datasets/trajectory_dataset.h"

namespace flowplan::datasets {

struct GenerateOptions {
  int64_t episodes = 0;     // N episodes in the whole dataset
  uint64_t seed = 0;        // episode i draws from StreamSeed(seed, i)
  int threads = 1;          // worker threads, each with its own EpisodeWorker
  int shard_index = 0;      // this call generates shard k of n: episodes [k*N/n, (k+1)*N/n)
  int shard_count = 1;
  std::string config_yaml;  // stored in the file, must not depend on threads or shard
  bool show_progress = true;
};

/// Rolls out episodes in parallel. The result is the same for any thread count,
/// and the shards of a dataset concatenate to the unsharded dataset. Rejected
/// episodes are left out and counted. Evaluation pairs come from the task's
/// noise-free nominal rollouts: a training pair per family and a test pair for
/// every (start of family i, goal of family j) that no family connects.
/// @throws flowplan::Error if every episode is rejected or on interrupt.
TrajectoryDataset GenerateDataset(const EpisodeTask& task, const GenerateOptions& options);

}  // namespace flowplan::datasets
