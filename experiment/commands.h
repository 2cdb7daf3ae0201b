#pragma once

// One function per `flowplan` subcommand; apps/flowplan/main.cc only parses
// flags and calls these.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "experiment/experiment_config.h"
#include "kinematics/robot.h"
#include "planning/flow_planner.h"
#include "planning/zoo.h"
#include "trainer/trainer.h"

namespace flowplan::experiment {

/// Worker threads from config.threads (0: all cores). LibTorch itself runs
/// single-threaded: the workers take fixed shards of the work, so results do
/// not depend on the thread count.
int ConfigureThreads(const ExperimentConfig& config);

struct GenerateRequest {
  int shard_index = 0;  // --shard k/n
  int shard_count = 1;
  std::string out;      // --out, overrides generate.out (e.g. one file per shard)
};

/// `flowplan generate`: rolls out config.generate and writes the HDF5 file.
void RunGenerate(const ExperimentConfig& config, const GenerateRequest& request);

/// `flowplan merge`: joins shards (in the order given) into one file.
void RunMerge(const std::vector<std::string>& inputs, const std::string& out);

struct TrainRequest {
  trainer::TrainStart start = trainer::TrainStart::kFresh;
  int64_t until_step = 0;  // --until: stop (with a checkpoint) at this step; 0: run to train.steps
};

/// `flowplan train`: trains (or resumes) the run in config.run_dir.
void RunTrain(const ExperimentConfig& config, const TrainRequest& request);

/// `flowplan train --resume RUN_DIR`: the run's stored config with `overrides`
/// (e.g. train.steps=8000 to train longer).
/// @throws flowplan::Error if an override changes what CheckResumable() forbids.
void RunResume(const std::string& run_dir, const std::vector<std::string>& overrides, int64_t until_step);

/// Throws, naming the key, if `changed` differs from `trained` in anything but
/// what a resumed run may change: threads, train.steps, the log / eval /
/// checkpoint intervals, keep_checkpoints, val_batch_size, sampler.*, eval.*,
/// guidance.*, scene.* and execute.*.
/// Anything else (data, seed, optimizer, batch, network, objective) would make the
/// resumed run a different one. `where` names the stored config in the message.
void CheckResumable(const ExperimentConfig& trained, const ExperimentConfig& changed, const std::string& where);

/// Throws, naming the key, if `changed` differs from `trained` in anything that
/// shapes the trained network (model.*, objective.name, objective.conditioning). `where` names the
/// stored config in the message.
void CheckSameNetwork(const ExperimentConfig& trained, const ExperimentConfig& changed, const std::string& where);

/// Draws `config.problems` for the Franka (seed: config.seed) and writes them
/// as YAML to `out` (docs/planning.md).
/// @throws flowplan::Error for a bad problems section or an unwritable `out`.
void RunProblems(const ExperimentConfig& config, const std::string& out);

/// A planner restored from a checkpoint (EMA weights), with the config it was trained with.
struct LoadedPlanner {
  ExperimentConfig config;
  std::unique_ptr<planning::Planner> planner;
  std::string checkpoint;
  int64_t step = 0;
  std::string env;
  double dt = 0.0;
  std::vector<std::string> state_labels;
  std::shared_ptr<const kinematics::Robot> robot;
};

/// Loads `ckpt` (a checkpoint file or a run folder = its newest checkpoint); the
/// checkpoint's config is overlaid with `overlay_path` and `overrides`
/// (e.g. sampler.steps=20).
/// @throws flowplan::Error for missing, corrupt or foreign checkpoints.
LoadedPlanner LoadPlanner(const std::string& ckpt, const std::string& overlay_path,
                          const std::vector<std::string>& overrides);

struct EvalRequest {
  std::string ckpt;
  std::string overlay_path;
  std::vector<std::string> overrides;
  std::string out;  // JSON report; default RUN_DIR/eval_stitching.json
};

/// `flowplan eval stitching`: stitching error on the dataset's test and training pairs.
void RunEvalStitching(const EvalRequest& request);

/// `flowplan export`: writes the TorchScript planner (default RUN_DIR/planner.pt).
void RunExport(const EvalRequest& request);

/// The joint angles of `flowplan fk --q=…`: exactly 7 comma-separated finite numbers.
/// @throws flowplan::Error naming the field that is empty, not a number or not finite,
///   or the count when it is not 7.
std::vector<double> ParseJointAngles(const std::string& text);

/// `flowplan fk`: prints the Franka's TCP and flange positions for joint angles
/// `q` (7 values, rad) through MuJoCo and through the LibTorch kinematics; warns
/// about angles outside the joint limits.
/// @throws flowplan::Error for a wrong number of joint values.
void RunFrankaFk(const std::vector<double>& q);

}  // namespace flowplan::experiment
