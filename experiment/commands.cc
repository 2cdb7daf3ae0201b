#include "experiment/commands.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>

#include "checkpoints/checkpoint.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "core/parallel.h"
#include "datasets/generator.h"
#include "datasets/h5.h"
#include "datasets/trajectory_dataset.h"
#include "distributed/communicator.h"
#include "distributed/world.h"
#include "models/device.h"
#include "eval/stitching.h"
#include "kinematics/arm_kinematics.h"
#include "planning/export.h"
#include "sim/franka_model.h"
#include "trainer/run_dir.h"
#include "trainer/trainer.h"

namespace flowplan::experiment {
namespace fs = std::filesystem;

int ConfigureThreads(const ExperimentConfig& config) {
  // Arithmetic on denormal floats is orders of magnitude slower on x86; flush
  // them to zero before any worker thread starts (the threads inherit the mode).
  at::globalContext().setFlushDenormal(true);
  at::set_num_threads(1);
  return ResolveThreadCount(config.threads);
}

namespace {

void EnsureParentFolder(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty()) MakeDirectories(parent.string());
}

/// The run folder a checkpoint belongs to: RUN/checkpoints/step_N.pt -> RUN.
std::string RunFolderOf(const std::string& checkpoint) {
  const fs::path folder = fs::path(checkpoint).parent_path();
  if (folder.filename() == "checkpoints") return folder.parent_path().string();
  return folder.empty() ? std::string(".") : folder.string();
}

void WritePlans(const std::string& path, const eval::StitchingResult& test, const eval::StitchingResult& train) {
  AtomicFile target(path);
  {
    auto file = datasets::h5::File::Create(target.temp_path());
    for (const eval::StitchingResult* result : {&test, &train}) {
      if (!result->plans.defined()) continue;
      const torch::Tensor plans = result->plans.contiguous();
      const torch::Tensor index = result->pair_index.to(torch::kInt32).contiguous();
      file.CreateGroup("/" + result->pairs);
      file.WriteFloat32("/" + result->pairs + "/plans", plans.sizes().vec(), plans.data_ptr<float>());
      file.WriteInt32("/" + result->pairs + "/pair_index", index.sizes().vec(), index.data_ptr<int32_t>());
    }
    file.Close();
  }
  target.Commit();
}

}  // namespace

void RunGenerate(const ExperimentConfig& config, const GenerateRequest& request) {
  const int threads = ResolveThreadCount(config.threads);
  const std::string out = request.out.empty() ? config.generate.out : request.out;
  EnsureParentFolder(out);
  AtomicFile probe(out);  // fails early, before any rollout, if the file cannot be written
  const auto task = datasets::MakeTask(config.generate);
  datasets::GenerateOptions options;
  options.episodes = config.generate.episodes;
  options.seed = static_cast<uint64_t>(config.seed);
  options.threads = threads;
  options.shard_index = request.shard_index;
  options.shard_count = request.shard_count;
  options.config_yaml = DatasetConfigYaml(config);
  spdlog::info("generating {} episodes of {} on {} threads{}", config.generate.episodes,
               config::EnumName(config.generate.dataset), threads,
               request.shard_count > 1 ? " (shard " + std::to_string(request.shard_index) + "/" +
                                             std::to_string(request.shard_count) + ")"
                                       : std::string());
  const datasets::TrajectoryDataset dataset = datasets::GenerateDataset(*task, options);
  datasets::WriteDataset(out, dataset);
  spdlog::info("wrote {}: {} episodes x {} states x {} dims ({} rejected, {} simulator warnings)", out,
               dataset.num_episodes, dataset.horizon, dataset.state_dim, dataset.rejected_episodes,
               dataset.simulator_warnings);
}

void RunMerge(const std::vector<std::string>& inputs, const std::string& out) {
  if (inputs.empty()) throw Error("merge: expected at least one input file");
  std::vector<datasets::TrajectoryDataset> shards;
  for (const auto& path : inputs) shards.push_back(datasets::ReadDataset(path));
  EnsureParentFolder(out);
  const datasets::TrajectoryDataset merged = datasets::MergeDatasets(shards, inputs);
  datasets::WriteDataset(out, merged);
  spdlog::info("wrote {}: {} episodes from {} shard{}", out, merged.num_episodes, inputs.size(),
               inputs.size() == 1 ? "" : "s");
}

void RunTrain(const ExperimentConfig& config, const TrainRequest& request) {
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
  trainer::TrainingSetup setup;
  setup.run_dir = config.run_dir;
  setup.config_yaml = ToYaml(config);
  setup.data_path = config.data.path;
  setup.seed = static_cast<uint64_t>(config.seed);
  setup.threads = threads;
  if (world && device.is_cuda() && !device.has_index()) {
    // One GPU per process on each machine.
    device = models::ParseDevice("cuda:" + std::to_string(world->local_rank), "device (LOCAL_RANK)");
  }
  setup.device = device;
  setup.model = config.model;
  setup.objective = config.objective;
  setup.train = config.train;
  setup.sampler = config.sampler;
  setup.eval = config.eval;
  setup.stop_at_step = request.until_step;
  setup.communicator = communicator.get();
  setup.bucket_bytes = static_cast<int64_t>(config.distributed.bucket_mb * (1 << 20));
  spdlog::info("training {} on {} ({} threads) into {}", config::EnumName(config.model.architecture),
               config.data.path, threads, config.run_dir);
  const trainer::TrainResult result = trainer::Train(setup, data, request.start);
  if (result.steps == result.first_step) {
    spdlog::info("nothing left to train: the run ended at step {}; val loss {:.5f}, stitching error test {:.4f} ± "
                 "{:.4f}; checkpoint {}",
                 result.steps, result.val_loss, result.test.mean, result.test.stddev, result.checkpoint);
    return;
  }
  spdlog::info("trained {} steps, to step {}, in {:.1f} s: loss {:.5f}, val loss {:.5f}, stitching error test {:.4f} ± {:.4f}; "
               "checkpoint {}",
               result.steps - result.first_step, result.steps, result.seconds, result.train_loss, result.val_loss, result.test.mean,
               result.test.stddev, result.checkpoint);
}

void CheckSameNetwork(const ExperimentConfig& trained, const ExperimentConfig& changed, const std::string& where) {
  const auto before = config::ListKeys(trained), after = config::ListKeys(changed);
  for (size_t i = 0; i < before.size(); ++i) {
    const std::string& key = before[i].key;
    const bool shapes_network = key.rfind("model.", 0) == 0 || key == "objective.name" || key == "objective.conditioning";
    if (shapes_network && before[i].default_value != after[i].default_value) {
      throw Error(key + ": the network was trained with " + before[i].default_value + " (" + where + "), got " +
                  after[i].default_value + "; a trained network's architecture and conditioning cannot change");
    }
  }
}

void CheckResumable(const ExperimentConfig& trained, const ExperimentConfig& changed, const std::string& where) {
  // What a resumed run may change without becoming another run: its length,
  // how often it logs, evaluates and saves, the threads (results do not depend
  // on them), and how evaluations sample.
  static const std::vector<std::string> kMayChange = {"threads",
                                                       "train.steps",
                                                       "train.log_every",
                                                       "train.eval_every",
                                                       "train.checkpoint_every",
                                                       "train.keep_checkpoints",
                                                       "train.val_batch_size",
                                                       "sampler.",  // a trailing dot: every key below
                                                       "eval.",
                                                       "guidance.",
                                                       "scene.",
                                                       "execute.",
                                                       "distributed.",
                                                       "device"};
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
                   before[i].default_value, after[i].default_value, after[i].default_value,
                   after[i].default_value);
    }
  }
}

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
  RunTrain(config, TrainRequest{trainer::TrainStart::kResume, until_step});
}

void RunProblems(const ExperimentConfig& config, const std::string& out) {
  const kinematics::ArmKinematics arm(sim::LoadFrankaModel().description());
  guidance::BlockedProblemSet set;
  try {
    set = guidance::MakeBlockedProblems(arm, config.problems, static_cast<uint64_t>(config.seed));
  } catch (const Error& e) {
    throw Error(std::string("problems.") + e.what());
  }
  EnsureParentFolder(out);
  WriteFileAtomically(out, config::ToYaml(set));
  size_t spheres = 0;
  for (const auto& problem : set.problems) spheres += problem.scene.spheres.size();
  spdlog::info("wrote {}: {} problems, {} spheres, each blocking the straight TCP path with its first", out,
               set.problems.size(), spheres);
}

LoadedPlanner LoadPlanner(const std::string& ckpt, const std::string& overlay_path,
                          const std::vector<std::string>& overrides) {
  LoadedPlanner loaded;
  loaded.checkpoint = trainer::ResolveCheckpoint(ckpt);
  const checkpoints::CheckpointHeader header = checkpoints::ReadCheckpointHeader(loaded.checkpoint);
  const std::string where = loaded.checkpoint + " (stored config)";
  loaded.config = LoadExperimentText(header.config_yaml, where, overlay_path, overrides);
  CheckSameNetwork(LoadExperimentText(header.config_yaml, where, "", {}), loaded.config, loaded.checkpoint);
  loaded.step = header.step;
  loaded.env = header.env;
  loaded.dt = header.dt;
  loaded.state_labels = header.state_labels;
  const int64_t D = header.normalizer.dim();
  const models::NetworkPtr net =
      models::MakeNetwork(loaded.config.model, D, models::ConditionDim(loaded.config.objective.conditioning, D));
  const torch::Device device = models::ParseDevice(loaded.config.device, "device");
  checkpoints::LoadCheckpointWeights(loaded.checkpoint, {nullptr, net.get(), nullptr}, device);
  net->to(device);
  net->eval();
  loaded.robot = kinematics::MakeRobot(header.robot, loaded.checkpoint);
  loaded.planner = planning::MakeLearnedPlanner({net, header.normalizer, loaded.config.objective, header.horizon,
                                                 loaded.config.sampler,
                                                 planning::GuidanceSetup{loaded.robot, header.dt, loaded.config.guidance}});
  return loaded;
}

void RunEvalStitching(const EvalRequest& request) {
  LoadedPlanner loaded = LoadPlanner(request.ckpt, request.overlay_path, request.overrides);
  const int threads = ConfigureThreads(loaded.config);
  const datasets::TrajectoryDataset dataset = datasets::ReadDataset(loaded.config.data.path);
  if (dataset.state_dim != loaded.planner->state_dim()) {
    throw Error(loaded.config.data.path + ": states have " + std::to_string(dataset.state_dim) +
                " dimensions, the checkpoint plans " + std::to_string(loaded.planner->state_dim()));
  }
  const auto test_pairs = datasets::ToTensors(dataset.test_pairs, dataset.state_dim);
  const auto train_pairs = datasets::ToTensors(dataset.train_pairs, dataset.state_dim);
  const eval::StitchingResult test = eval::EvaluateStitching(*loaded.planner, test_pairs, dataset.state_labels, "test", loaded.config.eval, threads);
  const eval::StitchingResult train =
      eval::EvaluateStitching(*loaded.planner, train_pairs, dataset.state_labels, "train", loaded.config.eval, threads);

  const std::string run = RunFolderOf(loaded.checkpoint);
  const std::string out = request.out.empty() ? run + "/eval_stitching.json" : request.out;
  EnsureParentFolder(out);
  const std::string json =
      "{\"checkpoint\": " + JsonString(loaded.checkpoint) + ", \"step\": " + std::to_string(loaded.step) +
      ", \"data\": " + JsonString(loaded.config.data.path) +
      ", \"sampler_steps\": " + std::to_string(loaded.config.sampler.steps) +
      ", \"sampler_splitting\": " + JsonString(config::EnumName(loaded.config.sampler.splitting)) +
      ", \"test\": " + eval::ToJson(test) + ", \"train\": " + eval::ToJson(train) + "}\n";
  WriteFileAtomically(out, json);
  const std::string plans = fs::path(out).replace_extension(".plans.h5").string();
  WritePlans(plans, test, train);
  spdlog::info("stitching error (step {}, {} plans): test pairs {:.4f} ± {:.4f}, training pairs {:.4f} ± {:.4f}; "
               "wrote {} and {}",
               loaded.step, loaded.config.eval.num_plans, test.mean, test.stddev, train.mean, train.stddev, out, plans);
}

void RunExport(const EvalRequest& request) {
  // An exported file runs anywhere: its weights are written from the CPU.
  std::vector<std::string> overrides = request.overrides;
  overrides.push_back("device=cpu");
  LoadedPlanner loaded = LoadPlanner(request.ckpt, request.overlay_path, overrides);
  const std::string out = request.out.empty() ? trainer::RunDir(RunFolderOf(loaded.checkpoint)).planner() : request.out;
  EnsureParentFolder(out);
  planning::ExportMetadata metadata;
  metadata.env = loaded.env;
  metadata.dt = loaded.dt;
  metadata.state_labels = loaded.state_labels;
  metadata.config_yaml = ToYaml(loaded.config);
  planning::ExportPlanner(*loaded.planner, metadata, out);
  spdlog::info("exported {} (step {}) to {}: plan(start (B, {}), goal (B, {}), noise (B, {}, {})) -> (B, {}, {})",
               loaded.checkpoint, loaded.step, out, loaded.planner->state_dim(), loaded.planner->state_dim(),
               loaded.planner->horizon(), loaded.planner->state_dim(), loaded.planner->horizon(),
               loaded.planner->state_dim());
}

}  // namespace flowplan::experiment

namespace flowplan::experiment {

std::vector<double> ParseJointAngles(const std::string& text) {
  std::vector<double> q;
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(',', begin);
    const std::string field = text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
    const std::string where = "--q value " + std::to_string(q.size() + 1) + " \"" + field + "\"";
    char* rest = nullptr;
    errno = 0;
    const double value = std::strtod(field.c_str(), &rest);
    if (field.empty() || rest != field.c_str() + field.size() || field.find_first_of(" \t") != std::string::npos) {
      throw Error(where + ": not a number (expected 7 comma-separated angles in rad)");
    }
    if (errno == ERANGE || !std::isfinite(value)) throw Error(where + ": not a finite number");
    q.push_back(value);
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  if (q.size() != sim::kFrankaJoints) {
    throw Error("--q: expected 7 joint angles, got " + std::to_string(q.size()) + " in \"" + text + "\"");
  }
  return q;
}

void RunFrankaFk(const std::vector<double>& q) {
  const sim::FrankaModel model = sim::LoadFrankaModel();
  const sim::FrankaLimits& limits = model.limits();
  for (size_t j = 0; j < q.size() && j < static_cast<size_t>(sim::kFrankaJoints); ++j) {
    if (q[j] < limits.q_lower[j] || q[j] > limits.q_upper[j]) {
      spdlog::warn("q{} = {} is outside the joint's limits [{}, {}]", j + 1, q[j], limits.q_lower[j], limits.q_upper[j]);
    }
  }
  const sim::FrankaPose pose = sim::FrankaForwardKinematics(model, q);
  const kinematics::ArmKinematics fk(model.description());
  const torch::Tensor tcp = fk.Tcp(torch::tensor(q, torch::kFloat64).view({1, -1}))[0];
  const Eigen::Vector3d torch_tcp(tcp[0].item<double>(), tcp[1].item<double>(), tcp[2].item<double>());
  auto text = [](const Eigen::Vector3d& p) { return fmt::format("({:.9f}, {:.9f}, {:.9f})", p.x(), p.y(), p.z()); };
  fmt::print("TCP (MuJoCo):     {} m\n", text(pose.tcp_position));
  fmt::print("TCP (LibTorch):   {} m\n", text(torch_tcp));
  fmt::print("flange (MuJoCo):  {} m\n", text(pose.flange_position));
  fmt::print("|TCP difference|: {:.3g} m\n", (pose.tcp_position - torch_tcp).norm());
}

}  // namespace flowplan::experiment
