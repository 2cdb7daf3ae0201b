#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace flowplan::trainer {

/// The files of a training run:
///   RUN_DIR/config.yaml                  resolved config
///   RUN_DIR/metrics.jsonl                one JSON object per logged step
///   RUN_DIR/checkpoints/step_00001000.pt periodic checkpoints
///   RUN_DIR/planner.pt                   exported TorchScript planner (by `flowplan export`)
class RunDir {
 public:
  explicit RunDir(std::string root) : root_(std::move(root)) {}

  const std::string& root() const { return root_; }
  std::string config() const { return root_ + "/config.yaml"; }
  std::string metrics() const { return root_ + "/metrics.jsonl"; }
  std::string checkpoints() const { return root_ + "/checkpoints"; }
  std::string checkpoint(int64_t step) const;
  std::string planner() const { return root_ + "/planner.pt"; }

  /// Creates the folders. @throws flowplan::Error if that fails.
  void Create() const;
  /// Steps of the checkpoints on disk, ascending.
  std::vector<int64_t> CheckpointSteps() const;
  /// Path of the newest checkpoint. @throws flowplan::Error naming the run if there is none.
  std::string LatestCheckpoint() const;
  /// Deletes all but the newest `keep` checkpoints.
  void PruneCheckpoints(int keep) const;

 private:
  std::string root_;
};

/// Resolves a --ckpt argument: a checkpoint file, or a run folder meaning its newest checkpoint.
std::string ResolveCheckpoint(const std::string& path);

}  // namespace flowplan::trainer
