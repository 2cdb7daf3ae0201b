// `flowplan train`: trains a run, or resumes one, scoring the EMA weights by
// their stitching error while it trains.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "datasets/trajectory_loader.h"
#include "distributed/communicator.h"
#include "distributed/world.h"
#include "eval/stitching.h"
#include "experiment/commands.h"
#include "experiment/trained_planner.h"
#include "models/device.h"
#include "planning/assemble.h"
#include "trainer/trainer.h"

namespace flowplan::experiment {
namespace {

struct TrainArgs {
  ConfigArgs config;
  std::string resume;      // --resume RUN_DIR
  int64_t until_step = 0;  // --until: stop (with a checkpoint) at this step; 0: run to train.steps
};

/// Stitching errors of the EMA weights on the data's test and training pairs,
/// planned unguided (the network alone); none for data without pairs (the
/// general data sets of motions between random configurations).
trainer::Evaluator StitchingEvaluator(const ExperimentConfig& config, const datasets::TrajectorySplits& data,
                                      int threads) {
  return [&config, &data, threads](const models::NetworkPtr& net, const models::MinMaxNormalizer& normalizer) {
    if (data.test_pairs.names.empty() && data.train_pairs.names.empty()) return trainer::Scores{};
    planning::PlannerParts parts;
    parts.net = net;
    parts.normalizer = normalizer;
    parts.objective = config.objective;
    parts.sampler = config.sampler;
    parts.guidance = config.guidance;
    parts.guidance.scale = 0.0;
    parts.trajectory = data.info;
    const auto planner = planning::AssemblePlanner(parts);
    trainer::Scores scores;
    for (const auto& [pairs, label] : {std::pair{&data.test_pairs, "test"}, std::pair{&data.train_pairs, "train"}}) {
      double mean = NAN, stddev = NAN;
      if (!pairs->names.empty()) {
        const eval::StitchingResult result =
            eval::EvaluateStitching(*planner, *pairs, data.info.state_labels, label, config.eval, threads);
        mean = result.mean;
        stddev = result.stddev;
      }
      scores.emplace_back(std::string("stitch_") + label + "_mean", mean);
      scores.emplace_back(std::string("stitch_") + label + "_std", stddev);
    }
    return scores;
  };
}

void RunTrain(const ExperimentConfig& config, trainer::TrainStart start, int64_t until_step) {
  torch::Device device = models::ParseDevice(config.device, "device");
  distributed::ResolveBackend(config.distributed, device.is_cuda() ? "cuda" : "cpu");  // a bad value fails here too
  // Launched as one of several processes (torchrun, Slurm): join the job first,
  // so that a missing peer is reported before any work.
  const std::optional<distributed::World> world = distributed::WorldFromEnvironment();
  std::unique_ptr<distributed::Communicator> communicator;
  if (world) {
    if (world->rank != 0 && spdlog::get_level() < spdlog::level::warn) spdlog::set_level(spdlog::level::warn);
    spdlog::info("joining a {} job of {} processes at {}:{}", world->source, world->size, world->master_addr,
                 world->master_port);
    communicator = distributed::Connect(*world, config.distributed, device.is_cuda() ? "cuda" : "cpu");
  }
  int threads = ConfigureThreads(config);
  if (world && config.threads == 0) threads = std::max(1, threads / world->local_size);  // share the machine
  // Every process reads only its own data parts; rank 0 (or a lone process)
  // also the whole split, for the normalizer, the validation loss and the fingerprint.
  datasets::PartSelection parts;
  parts.count = config.train.data_parts;
  const int rank = world ? world->rank : 0, ranks = world ? world->size : 1;
  for (int p = rank; p < parts.count; p += ranks) parts.mine.push_back(p);
  parts.everything = rank == 0;
  const datasets::TrajectorySplits data =
      datasets::LoadTrajectorySplits(config.data, static_cast<uint64_t>(config.seed), parts);
  if (world && device.is_cuda() && !device.has_index()) {
    // One GPU per process on each machine.
    device = models::ParseDevice("cuda:" + std::to_string(world->local_rank), "device (LOCAL_RANK)");
  }
  trainer::TrainingSetup setup;
  setup.run_dir = config.run_dir;
  setup.config_yaml = ToYaml(config);
  setup.data_path = config.data.path;
  setup.seed = static_cast<uint64_t>(config.seed);
  setup.threads = threads;
  setup.device = device;
  setup.model = config.model;
  setup.objective = config.objective;
  setup.train = config.train;
  setup.evaluate = StitchingEvaluator(config, data, threads);
  setup.stop_at_step = until_step;
  setup.communicator = communicator.get();
  setup.bucket_bytes = static_cast<int64_t>(config.distributed.bucket_mb * (1 << 20));
  spdlog::info("training {} on {} ({} threads) into {}", config::EnumName(config.model.architecture),
               config.data.path, threads, config.run_dir);
  const trainer::TrainResult result = trainer::Train(setup, data, start);
  std::string scores;
  for (const auto& [name, value] : result.scores) scores += fmt::format(", {} {:.4f}", name, value);
  if (result.steps == result.first_step) {
    spdlog::info("nothing left to train: the run ended at step {}; val loss {:.5f}{}; checkpoint {}", result.steps,
                 result.val_loss, scores, result.checkpoint);
    return;
  }
  spdlog::info("trained {} steps, to step {}, in {:.1f} s: loss {:.5f}, val loss {:.5f}{}; checkpoint {}",
               result.steps - result.first_step, result.steps, result.seconds, result.train_loss, result.val_loss,
               scores, result.checkpoint);
}

/// Throws, naming the key, if `changed` differs from `trained` in anything but
/// what a resumed run may change. `where` names the stored config in the message.
void CheckResumable(const ExperimentConfig& trained, const ExperimentConfig& changed, const std::string& where) {
  // What a resumed run may change without becoming another run: its length,
  // how often it logs, evaluates and saves, the threads (results do not depend
  // on them), and how evaluations sample.
  static const std::vector<std::string> kMayChange = {
      "threads", "train.steps", "train.log_every", "train.eval_every", "train.checkpoint_every",
      "train.keep_checkpoints", "train.val_batch_size",
      "sampler.", "eval.", "guidance.", "scene.", "execute.", "distributed.", "device"};  // a trailing dot: every key below
  const auto before = config::ListKeys(trained), after = config::ListKeys(changed);
  for (size_t i = 0; i < before.size(); ++i) {
    const std::string& key = before[i].key;
    if (before[i].default_value == after[i].default_value) continue;
    const bool may_change = std::any_of(kMayChange.begin(), kMayChange.end(), [&](const std::string& allowed) {
      return allowed.back() == '.' ? key.rfind(allowed, 0) == 0 : key == allowed;
    });
    if (!may_change) {
      throw Error(key + ": the run was trained with " + before[i].default_value + " (" + where + "), got " +
                  after[i].default_value + "; a resumed run can change only its length, intervals, threads, "
                  "sampler.*, eval.*, guidance.*, scene.*, execute.* and distributed.* (start a new run_dir for the rest)");
    }
    if (key == "train.steps") {
      spdlog::warn("train.steps: {} -> {}: the cosine learning-rate schedule now spans {} steps, so the rate "
                   "jumps to that schedule's value at the current step (a warm restart, not the run that "
                   "train.steps={} from the start would have been)",
                   before[i].default_value, after[i].default_value, after[i].default_value, after[i].default_value);
    }
  }
}

/// The run's stored config with `overrides` (e.g. train.steps=8000 to train longer).
void RunResume(const std::string& run_dir, const std::vector<std::string>& overrides, int64_t until_step) {
  const std::string stored = run_dir + "/config.yaml";
  if (!std::filesystem::is_regular_file(stored)) {
    throw Error(run_dir + ": not a run folder (it has no config.yaml); --resume takes the run_dir of a training run");
  }
  const std::string text = ReadFile(stored);
  const ExperimentConfig trained = LoadExperimentText(text, stored, "", {});
  ExperimentConfig config = LoadExperimentText(text, stored, "", overrides);
  CheckResumable(trained, config, stored);
  config.run_dir = run_dir;
  RunTrain(config, trainer::TrainStart::kResume, until_step);
}

}  // namespace

std::string Train(const std::string& config_path, const std::vector<std::string>& overrides,
                  const std::string& resume_dir, int64_t until_step) {
  if (!resume_dir.empty()) {
    if (!config_path.empty()) throw Error("train: give either a config or a run folder to resume, not both");
    RunResume(resume_dir, overrides, until_step);
    return resume_dir;
  }
  if (config_path.empty()) throw Error("train: expected a config file or a run folder to resume");
  const ExperimentConfig config = LoadExperiment(config_path, overrides);
  RunTrain(config, trainer::TrainStart::kFresh, until_step);
  return config.run_dir;
}

Command AddTrainCommand(CLI::App& app) {
  auto args = std::make_shared<TrainArgs>();
  CLI::App* command = app.add_subcommand("train", "train a planner (train.*, model.*, objective.*) or resume a run");
  args->config.Add(command, false);
  command->add_option("--resume", args->resume, "continue the run in this folder from its newest checkpoint");
  command->add_option("--until", args->until_step, "stop with a checkpoint at this step (0: train.steps)")
      ->check(CLI::NonNegativeNumber);
  return {command, [args] {
            if (!args->resume.empty() && !args->config.path.empty()) {
              throw Error("train: give either --config or --resume, not both");
            }
            if (args->resume.empty() && args->config.path.empty()) {
              throw Error("train: expected --config FILE or --resume RUN_DIR");
            }
            Train(args->config.path, args->config.overrides, args->resume, args->until_step);
          }};
}

}  // namespace flowplan::experiment
