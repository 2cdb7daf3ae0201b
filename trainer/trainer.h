#pragma once

#include <cstdint>
#include <string>

#include <functional>
#include <utility>
#include <vector>

#include "datasets/trajectory_loader.h"
#include "distributed/communicator.h"
#include "models/model_config.h"
#include "models/normalizer.h"
#include "objectives/objective.h"
#include "trainer/trainer_config.h"

namespace flowplan::trainer {

/// Named scores of the EMA weights at an evaluation (e.g. "stitch_test_mean"),
/// in the order they are logged; NaN where a score does not apply.
using Scores = std::vector<std::pair<std::string, double>>;

/// Scores the EMA weights `net` (with the run's normalizer) besides the
/// validation loss, e.g. by planning with them. Called on rank 0 only.
using Evaluator = std::function<Scores(const models::NetworkPtr& net, const models::MinMaxNormalizer& normalizer)>;

/// Everything a training run needs besides the data.
struct TrainingSetup {
  std::string run_dir;
  std::string config_yaml;  // resolved experiment config, stored in the run and every checkpoint
  std::string data_path;    // where the data came from, for messages
  uint64_t seed = 0;
  int threads = 1;  // worker threads; results do not depend on it
  torch::Device device = torch::kCPU;  // networks, optimizer state and batches (draws stay on the CPU)
  models::ModelConfig model;
  objectives::ObjectiveConfig objective;
  TrainerConfig train;
  Evaluator evaluate;  // null: the validation loss only
  int64_t stop_at_step = 0;  // > 0: stop there with a checkpoint (the schedule still spans train.steps)
  /// The job this process belongs to; null: a single process. In a job of R
  /// processes each trains train.data_parts / R parts of the data, gradients
  /// are summed over all of them, and rank 0 alone writes the run folder and
  /// evaluates.
  distributed::Communicator* communicator = nullptr;
  int64_t bucket_bytes = 25 << 20;  // gradient all-reduce bucket size
};

/// What a finished run reports.
struct TrainResult {
  int64_t first_step = 0;       // the step this call started from (> 0 when resumed)
  int64_t steps = 0;            // the step it stopped at
  double train_loss = 0.0;       // mean loss over the last logging window
  double val_loss = 0.0;         // EMA weights, NaN without a validation split
  Scores scores;                 // EMA weights, the evaluator's last scores
  std::string checkpoint;        // the final checkpoint
  double seconds = 0.0;
};

/// Whether a run starts afresh or continues its folder's newest checkpoint.
enum class TrainStart { kFresh, kResume };

/// Trains a network with `setup.objective` on `data`, or resumes the run in
/// `setup.run_dir` from its newest checkpoint (continuing bit-exactly). The
/// weights do not depend on the thread count: LibTorch runs single-threaded and
/// `setup.threads` workers share fixed gradient shards. Nor, up to the order of
/// floating-point sums, on the number of processes (see TrainingSetup::communicator).
/// Writes config.yaml, metrics.jsonl and checkpoints; on SIGINT (to any
/// process of a job) writes a checkpoint of the current step and throws.
/// @throws flowplan::Error for settings the data cannot take (horizon, split), a
///   fresh start in a folder that holds checkpoints, or a resume without one.
TrainResult Train(const TrainingSetup& setup, const datasets::TrajectorySplits& data, TrainStart start);

/// Validation loss of `net` under `objective` on `val` (N, T, D) normalized,
/// with noise and times from a generator seeded by `seed`: comparable between
/// evaluations.
double ValidationLoss(const objectives::Objective& objective, models::Network& net, const torch::Tensor& val,
                      models::Conditioning conditioning, int batch_size, uint64_t seed);

}  // namespace flowplan::trainer
