// flowplan beside PyTorch eager on the same weights, in one run: the Franka
// UNet's forward pass at B = 1 and 64, a training step at B = 256 (fp32 and bf16), and a
// 10-step plan at B = 1 (unguided, and guided with splitting around one
// sphere, eight spheres and the shelf scene's shapes), in-process and from the
// exported TorchScript file; throughput at B = 64 (the flow planner, MPD,
// RRT-Connect); then
// bench/eager_reference.py runs the same work in plain PyTorch with the same
// thread count, in float32 and with the network under bf16 autocast, checks
// that its plans equal the exported planner's, and the ratios are printed.
// docs/performance.md has the figures.
//
//   speed_bench [--checkpoint CKPT] [--threads N] [--repeats R] [--out DIR] [--python PY]
//
// Without --checkpoint it writes a checkpoint with freshly initialised
// weights of configs/franka_reach.yaml's network (the timings do not depend on
// the weights; the checks do not need trained ones).

#include <spdlog/spdlog.h>
#include <torch/script.h>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "checkpoints/checkpoint.h"
#include "core/error.h"
#include "experiment/experiment_config.h"
#include "experiment/trained_planner.h"
#include "classical/rrt_connect.h"
#include "geometry/scene.h"
#include "geometry/scene_rows.h"
#include "jit/library.h"
#include "models/model_config.h"
#include "models/precision.h"
#include "objectives/objective.h"
#include "sim/franka_model.h"
#include "trainer/sharded_gradient.h"

namespace flowplan {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

/// Median wall time of `body` in ms over `repeats` calls, after `warmup` calls.
double MedianMs(int repeats, const std::function<void()>& body, int warmup = 3) {
  for (int i = 0; i < warmup; ++i) body();
  std::vector<double> ms;
  for (int i = 0; i < repeats; ++i) {
    const auto begin = Clock::now();
    body();
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - begin).count());
  }
  std::nth_element(ms.begin(), ms.begin() + static_cast<long>(ms.size() / 2), ms.end());
  return ms[ms.size() / 2];
}

/// A checkpoint of configs/franka_reach.yaml's network with fresh weights,
/// a normalizer spanning the joint limits (and +-2 rad/s) and the Franka.
std::string WriteFreshCheckpoint(const std::string& dir, const std::vector<std::string>& overrides = {},
                                 const std::string& name = "fresh_franka.pt") {
  const experiment::ExperimentConfig config =
      experiment::LoadExperiment(std::string(FLOWPLAN_SOURCE_DIR) + "/configs/franka_reach.yaml", overrides);
  const auto robot = sim::LoadFrankaModel().description();
  const int64_t D = 14, T = 64;
  torch::manual_seed(0);
  auto net = models::MakeNetwork(config.model, D, models::ConditionDim(config.objective.conditioning, D));
  auto ema = models::MakeNetwork(config.model, D, models::ConditionDim(config.objective.conditioning, D));
  models::CopyWeights(*net, *ema);
  torch::Tensor lo = torch::full({D}, -2.0f), hi = torch::full({D}, 2.0f);
  for (int j = 0; j < 7; ++j) {
    lo[j] = static_cast<float>(robot.joint_lower[j]);
    hi[j] = static_cast<float>(robot.joint_upper[j]);
  }
  checkpoints::CheckpointHeader header;
  header.step = 0;
  header.config_yaml = experiment::ToYaml(config);
  header.normalizer = models::MinMaxNormalizer(lo, hi);
  header.rng_states = {at::detail::getDefaultCPUGenerator().get_state()};
  header.trajectory.env = "franka";
  header.trajectory.dt = 1.0 / 15.0;
  for (int j = 1; j <= 7; ++j) header.trajectory.state_labels.push_back("q" + std::to_string(j));
  for (int j = 1; j <= 7; ++j) header.trajectory.state_labels.push_back("dq" + std::to_string(j));
  header.trajectory.horizon = T;
  header.trajectory.robot = robot;
  header.data_fingerprint = "none";
  const std::string path = dir + "/" + name;
  checkpoints::SaveCheckpoint(path, header, {net.get(), ema.get(), nullptr});
  return path;
}

/// The eight-sphere scene of the throughput figures (K = 8, 4): the paper's
/// 0.10 m sphere between the start and goal TCPs and seven of 0.05 m around
/// the workspace, clear of the start and goal postures (bench/eager_reference.py
/// has the same list).
torch::Tensor EightSpheres() {
  return torch::tensor({{0.5f, 0.0f, 0.2f, 0.1f}, {0.3f, -0.5f, 0.6f, 0.05f}, {0.3f, 0.5f, 0.6f, 0.05f},
                        {0.7f, -0.4f, 0.5f, 0.05f}, {0.7f, 0.4f, 0.5f, 0.05f}, {0.6f, 0.0f, 0.8f, 0.05f},
                        {0.2f, -0.3f, 0.1f, 0.05f}, {0.2f, 0.3f, 0.1f, 0.05f}});
}

/// Reads the flat {"key": number} pairs of a JSON file (the reference's output).
std::map<std::string, double> ReadNumbers(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  std::map<std::string, double> out;
  for (size_t at = s.find('"'); at != std::string::npos; at = s.find('"', at + 1)) {
    const size_t end = s.find('"', at + 1);
    if (end == std::string::npos) break;
    const std::string key = s.substr(at + 1, end - at - 1);
    size_t value = s.find_first_not_of(" :", end + 1);
    if (value != std::string::npos && (std::isdigit(s[value]) || s[value] == '-')) {
      out[key] = std::strtod(s.c_str() + value, nullptr);
    }
    at = end;
  }
  return out;
}

int Main(int argc, char** argv) {
  std::string checkpoint, out = "build/speed_bench", python = FLOWPLAN_PYTHON;
  int threads = 2, repeats = 20;
  bool eager = true;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error(arg + ": expects a value");
      return argv[++i];
    };
    if (arg == "--checkpoint") checkpoint = value();
    else if (arg == "--threads") threads = std::stoi(value());
    else if (arg == "--repeats") repeats = std::stoi(value());
    else if (arg == "--out") out = value();
    else if (arg == "--python") python = value();
    else if (arg == "--no-eager") eager = false;
    else if (arg == "--help" || arg == "-h") {
      std::printf(
          "usage: speed_bench [--checkpoint CKPT] [--threads N] [--repeats R] [--out DIR] [--python PY] [--no-eager]\n"
          "flowplan beside PyTorch eager on the same weights: the Franka UNet's forward pass, a training step, and\n"
          "plans in-process and from the exported file, each the median of R timed repeats on N threads; then\n"
          "bench/eager_reference.py (run by PY, skipped with --no-eager) times the same work in plain PyTorch and\n"
          "checks its plans. Without --checkpoint, freshly initialised weights of configs/franka_reach.yaml's\n"
          "network. Writes DIR/flowplan.json and DIR/eager.json (default build/speed_bench).\n");
      return 0;
    } else throw Error("unknown argument " + arg + " (speed_bench --help lists them)");
  }
  fs::create_directories(out);
  at::globalContext().setFlushDenormal(true);
  at::set_num_threads(threads);
  if (checkpoint.empty()) checkpoint = WriteFreshCheckpoint(out);
  spdlog::info("checkpoint {}, {} threads, median of {} repeats", checkpoint, threads, repeats);

  // The paper's sampler (no end-game steps), whatever the config's defaults: the figures and the eager
  // reference are of that.
  const experiment::TrainedPlanner plain =
      experiment::LoadTrainedPlanner(checkpoint, "", {"sampler.splitting=none", "sampler.final_iterations=0"});
  const experiment::TrainedPlanner split =
      experiment::LoadTrainedPlanner(checkpoint, "", {"sampler.splitting=midpoint", "sampler.final_iterations=0"});
  const auto& config = plain.config;
  const int64_t T = plain.planner->horizon(), D = plain.planner->state_dim();
  FLOWPLAN_DEMAND(config.sampler.steps == 10);
  if (plain.planner->kind() != "flow_matching") throw Error(checkpoint + ": not a flow-matching planner");
  const planning::LearnedPlanner* flow = plain.planner.get();
  const planning::LearnedPlanner* flow_split = split.planner.get();
  const models::MinMaxNormalizer normalizer = checkpoints::ReadCheckpointHeader(plain.checkpoint).normalizer;

  std::map<std::string, double> ms;
  // The network alone, as the planner calls it.
  {
    const int64_t C = models::ConditionDim(config.objective.conditioning, D);
    auto net = std::dynamic_pointer_cast<models::TrajectoryNet>(models::MakeNetwork(config.model, D, C));
    checkpoints::LoadCheckpointWeights(plain.checkpoint, {nullptr, net.get(), nullptr});
    net->eval();
    for (int64_t B : {1, 64}) {
      const torch::Tensor x = torch::randn({B, T, D}), t = torch::full({B}, 0.5f);
      const torch::Tensor cond = C > 0 ? torch::zeros({B, C}) : torch::Tensor();
      c10::InferenceMode inference;
      ms["forward_b" + std::to_string(B)] = MedianMs(repeats, [&] { net->Forward(x, t, cond); });
    }
  }
  // A training step: the trainer's sharded gradient (4 shards over the threads) and AdamW, in
  // float32 and under bf16 autocast (train.precision).
  for (const models::Precision precision : {models::Precision::kFp32, models::Precision::kBf16}) {
    at::set_num_threads(1);  // the trainer runs LibTorch single-threaded, parallel over shards
    const int64_t C = models::ConditionDim(config.objective.conditioning, D);
    auto net = models::MakeNetwork(config.model, D, C);
    checkpoints::LoadCheckpointWeights(plain.checkpoint, {nullptr, net.get(), nullptr});
    trainer::ShardedGradient gradient(*net, [&] { return models::MakeNetwork(config.model, D, C); },
                                      config.train.shards, threads);
    torch::optim::AdamW optimizer(net->parameters(), torch::optim::AdamWOptions(1e-4).weight_decay(0.01));
    const auto objective = objectives::MakeObjective(config.objective, config.model);
    auto generator = at::make_generator<at::CPUGeneratorImpl>(0);
    const torch::Tensor x1 = torch::rand({256, T, D}) * 2 - 1;
    const auto conditioning = config.objective.conditioning;
    const std::string key = precision == models::Precision::kFp32 ? "train_step_b256" : "train_step_b256_bf16";
    ms[key] = MedianMs(std::max(5, repeats / 4), [&] {
      gradient.Compute(objective->Draw(x1, generator), [&](models::Network& n, const objectives::ObjectiveBatch& b) {
        const models::AutocastScope autocast(precision);
        return objective->Loss(n, b, conditioning);
      });
      optimizer.step();
    }, 1);
    at::set_num_threads(threads);
  }
  // Plans at B = 1 between two fixed states (40 % and 60 % of the normalizer range), around the 0.10 m sphere.
  const torch::Tensor start = normalizer.lo() * 0.6 + normalizer.hi() * 0.4;
  const torch::Tensor goal = normalizer.lo() * 0.4 + normalizer.hi() * 0.6;
  torch::manual_seed(1);
  const torch::Tensor s = start.unsqueeze(0).clone(), g = goal.unsqueeze(0).clone();
  const torch::Tensor noise = torch::randn({1, T, D}), renoise = torch::randn({1, T, D});
  const torch::Tensor obstacles = torch::tensor({{0.5f, 0.0f, 0.2f, 0.1f}});
  const geometry::SceneRows sphere = geometry::SphereRows(obstacles);
  {
    c10::InferenceMode inference;
    ms["plan_b1"] = MedianMs(repeats, [&] { flow->PlanWithNoise(s, g, noise); });
  }
  // The same plans around eight spheres, and among the boxes and the cylinder of configs/scenes/franka_shelf.yaml.
  const geometry::SceneRows eight = geometry::SphereRows(EightSpheres());
  const geometry::SceneRows shelf =
      geometry::Rows(geometry::LoadScene(std::string(FLOWPLAN_SOURCE_DIR) + "/configs/scenes/franka_shelf.yaml"), 3,
                     "configs/scenes/franka_shelf.yaml");
  using Scenes = std::vector<std::pair<std::string, const geometry::SceneRows*>>;
  const Scenes every_scene = {{"", &sphere}, {"_8", &eight}, {"_shelf", &shelf}};
  // A guided split plan at B = 1 by `planner` around each scene, as ms["plan_guided_split_b1" + scene + suffix].
  const auto time_split_plans = [&](const planning::LearnedPlanner& planner, const std::string& suffix,
                                    const Scenes& scenes) {
    for (const auto& [scene, rows] : scenes) {
      ms["plan_guided_split_b1" + scene + suffix] =
          MedianMs(repeats, [&] { planner.PlanWithNoise(s, g, noise, renoise, *rows); });
    }
  };
  time_split_plans(*flow_split, "", every_scene);
  // The same split plans with the preset's own sampler defaults (its end-game: configs/franka_reach.yaml), which a
  // planner exported from the preset plans with unless a call says otherwise.
  time_split_plans(*experiment::LoadTrainedPlanner(checkpoint, "", {"sampler.splitting=midpoint"}).planner, "_defaults",
                   every_scene);
  // The planner's network as the planners call it (the TorchScript module, with flowplan's native UNet kernel),
  // and the same planners with LibTorch's operators only (sampler.network_kernels=portable and
  // guidance.distance_kernels=portable, what an export without --kernels native holds), side by side.
  {
    torch::jit::Module network = flow->module().attr("sampler").toModule().attr("network").toModule();
    const experiment::TrainedPlanner portable = experiment::LoadTrainedPlanner(
        checkpoint, "", {"sampler.splitting=none", "sampler.final_iterations=0", "sampler.network_kernels=portable", "guidance.distance_kernels=portable"});
    const experiment::TrainedPlanner portable_split = experiment::LoadTrainedPlanner(
        checkpoint, "", {"sampler.splitting=midpoint", "sampler.final_iterations=0", "sampler.network_kernels=portable", "guidance.distance_kernels=portable"});
    torch::jit::Module portable_network =
        portable.planner->module().attr("sampler").toModule().attr("network").toModule();
    for (int64_t B : {1, 64}) {
      const torch::Tensor x = torch::randn({B, T, D}), t = torch::full({B}, 0.5f);
      const int64_t C = models::ConditionDim(config.objective.conditioning, D);
      const torch::IValue cond = C > 0 ? torch::IValue(torch::zeros({B, C})) : torch::IValue();
      c10::InferenceMode inference;
      const std::string key = "planner_forward_b" + std::to_string(B);
      ms[key] = MedianMs(repeats, [&] { jit::Call(network, "forward", {x, t, cond}); });
      ms[key + "_portable"] = MedianMs(repeats, [&] { jit::Call(portable_network, "forward", {x, t, cond}); });
    }
    {
      c10::InferenceMode inference;
      ms["plan_b1_portable"] = MedianMs(repeats, [&] { portable.planner->PlanWithNoise(s, g, noise); });
    }
    time_split_plans(*portable_split.planner, "_portable", every_scene);
    // The native network with the distances on LibTorch's operators: what the native distances alone save.
    const experiment::TrainedPlanner script_distances = experiment::LoadTrainedPlanner(
        checkpoint, "", {"sampler.splitting=midpoint", "sampler.final_iterations=0", "guidance.distance_kernels=portable"});
    time_split_plans(*script_distances.planner, "_script_distances", {{"_8", &eight}, {"_shelf", &shelf}});
  }

  const std::string mpd_checkpoint = WriteFreshCheckpoint(out, {"objective.name=ddpm"}, "fresh_franka_mpd.pt");
  const std::string mpd_file = out + "/mpd_planner.pt";
  // Throughput: B = 64 plans in one call, guided and split (the flow planner) or guided (MPD: the same network as
  // a DDPM, fresh weights), around one sphere and around eight; RRT-Connect per plan (8 searches, one per plan, the
  // call's wall time over 8). The start and goal are the postures of the TCPs (0.5, -/+0.3, 0.2), gripper down.
  {
    const experiment::TrainedPlanner mpd = experiment::LoadTrainedPlanner(mpd_checkpoint, "", {});
    mpd.planner->Save(mpd_file);  // the eager reference checks its DDPM sampler against this file
    const classical::RrtConnectPlanner rrt(plain.planner->info(), config.rrt_connect, config.check);
    const torch::Tensor ends =
        jit::Call(flow->module(), "ik", {torch::tensor({{0.5, -0.3, 0.2}, {0.5, 0.3, 0.2}}, torch::kFloat64)}).toTensor();
    const torch::Tensor rest = torch::zeros({1, D - ends.size(1)});
    const torch::Tensor q_start = torch::cat({ends.slice(0, 0, 1).to(torch::kFloat32), rest}, 1);
    const torch::Tensor q_goal = torch::cat({ends.slice(0, 1, 2).to(torch::kFloat32), rest}, 1);
    for (const auto& [suffix, rows] : {std::pair<std::string, torch::Tensor>{"", obstacles}, {"_8", EightSpheres()}}) {
      const geometry::SceneRows scene = geometry::SphereRows(rows);
      planning::PlanRequest request;
      request.start = q_start.expand({64, D}).contiguous();
      request.goal = q_goal.expand({64, D}).contiguous();
      request.scene = scene;
      request.seed = 1;
      const int few = std::max(3, repeats / 10);
      ms["plan_guided_split_b64" + suffix] = MedianMs(few, [&] { flow_split->Plan(request); }, 1);
      ms["mpd_guided_b64" + suffix] = MedianMs(few, [&] { mpd.planner->Plan(request); }, 1);
      request.start = q_start.expand({8, D}).contiguous();
      request.goal = q_goal.expand({8, D}).contiguous();
      int64_t found = 0;
      ms["rrt_connect_per_plan" + suffix] = MedianMs(few, [&] {
        found = rrt.Plan(request).found.sum().item<int64_t>();
      }, 1) / 8.0;
      if (found != 8) spdlog::warn("RRT-Connect found {} of 8 plans around {} sphere(s)", found, rows.size(0));
    }
  }

  const std::string plain_file = out + "/planner.pt", split_file = out + "/planner_split.pt";
  plain.planner->Save(plain_file);
  split.planner->Save(split_file);
  {
    torch::jit::Module module = torch::jit::load(plain_file);
    c10::InferenceMode inference;
    ms["plan_b1_exported"] = MedianMs(repeats, [&] { module.run_method("plan", s, g, noise); });
  }
  {
    torch::jit::Module module = torch::jit::load(split_file);
    torch::NoGradGuard no_grad;
    ms["plan_guided_split_b1_exported"] =
        MedianMs(repeats, [&] { module.run_method("plan", s, g, noise, renoise, obstacles); });
    // The eight spheres and the shelf scene's shapes as the file's keyword arguments (docs/export.md, "Obstacles").
    torch::jit::Method plan = module.get_method("plan");
    for (const auto& [suffix, rows] : {std::pair<std::string, geometry::SceneRows>{"_8", eight}, {"_shelf", shelf}}) {
      torch::jit::Kwargs kwargs;
      for (const auto& entry : rows) kwargs[entry.key()] = entry.value();
      ms["plan_guided_split_b1" + suffix + "_exported"] =
          MedianMs(repeats, [&] { plan({s, g, noise, renoise}, kwargs); });
    }
  }

  std::map<std::string, double> reference;
  if (eager) {
    const std::string json = out + "/eager.json";
    std::remove(json.c_str());
    const std::string command = python + " " + FLOWPLAN_SOURCE_DIR + "/bench/eager_reference.py --checkpoint " +
                                checkpoint + " --export " + split_file + " --threads " + std::to_string(threads) +
                                " --repeats " + std::to_string(repeats) + " --json " + json +
                                " --kernels " + FLOWPLAN_KERNELS_LIBRARY + " --mpd-checkpoint " + mpd_checkpoint +
                                " --mpd-export " + mpd_file;
    spdlog::info("running {}", command);
    if (std::system(command.c_str()) != 0) throw Error("the eager reference failed: " + command);
    reference = ReadNumbers(json);
  }

  // Every figure beside eager PyTorch's: in float32, and with eager's network under bf16 autocast (the
  // reference's "_bf16" keys; the training rows are their own fp32 and bf16 pair).
  const auto cell = [](const std::map<std::string, double>& figures, const std::string& key, double divisor) {
    const auto found = figures.find(key);
    if (found == figures.end()) return std::pair<std::string, std::string>{"-", "-"};
    char time[32], ratio[32];
    std::snprintf(time, sizeof(time), "%.2f ms", found->second);
    std::snprintf(ratio, sizeof(ratio), "%.2fx", found->second / divisor);
    return std::pair<std::string, std::string>{time, ratio};
  };
  std::printf("\n%-28s %12s %12s %12s %9s %12s %9s\n", "", "flowplan", "exported", "eager fp32", "eager/fp",
              "eager bf16", "bf16/fp");
  for (const std::string key : {"forward_b1", "forward_b64", "planner_forward_b1", "planner_forward_b64",
                                "train_step_b256", "train_step_b256_bf16", "plan_b1", "plan_guided_split_b1",
                                "plan_guided_split_b1_8", "plan_guided_split_b1_shelf", "plan_guided_split_b64", "plan_guided_split_b64_8",
                                "mpd_guided_b64", "mpd_guided_b64_8", "rrt_connect_per_plan",
                                "rrt_connect_per_plan_8"}) {
    const auto exported = ms.find(key + "_exported");
    char exported_ms[32] = "";
    if (exported != ms.end()) std::snprintf(exported_ms, sizeof(exported_ms), "%.2f ms", exported->second);
    // The planners' network is the forward pass eager's figures are of.
    const std::string eager_key = key.rfind("planner_", 0) == 0 ? key.substr(8) : key;
    const auto [fp32, fp32_ratio] = cell(reference, eager_key, ms[key]);
    const bool training = key.rfind("train_step", 0) == 0;
    const auto [bf16, bf16_ratio] = training ? std::pair<std::string, std::string>{"", ""}
                                             : cell(reference, eager_key + "_bf16", ms[key]);
    std::printf("%-28s %9.2f ms %12s %12s %9s %12s %9s\n", key.c_str(), ms[key], exported_ms, fp32.c_str(),
                fp32_ratio.c_str(), bf16.c_str(), bf16_ratio.c_str());
  }
  if (reference.count("train_step_b256") > 0) {
    // flowplan's bf16 step against eager's fp32 step (the row above sets it beside eager's bf16 step).
    std::printf("%-28s %12s %12s %9.2f ms %8.2fx\n", "  bf16 against eager fp32", "", "", reference["train_step_b256"],
                reference["train_step_b256"] / ms["train_step_b256_bf16"]);
  }
  // The planners' native kernels (the UNet's, the obstacle distances') against the same planners on LibTorch's
  // operators; then the native distances alone (the network native in both columns).
  std::printf("\n%-26s %12s %12s %9s\n", "", "native", "portable", "speed-up");
  for (const std::string key : {"planner_forward_b1", "planner_forward_b64", "plan_b1", "plan_guided_split_b1",
                                "plan_guided_split_b1_8", "plan_guided_split_b1_shelf"}) {
    std::printf("%-26s %9.2f ms %9.2f ms %8.2fx\n", key.c_str(), ms[key], ms[key + "_portable"],
                ms[key + "_portable"] / ms[key]);
  }
  std::printf("\n%-28s %12s %12s\n", "guided split plan, B = 1", "paper's", "preset's");
  std::printf("%-28s %12s %12s\n", "(sampler)", "", "end-game");
  for (const std::string key : {"plan_guided_split_b1", "plan_guided_split_b1_8", "plan_guided_split_b1_shelf"}) {
    std::printf("%-28s %9.2f ms %9.2f ms\n", key.c_str(), ms[key], ms[key + "_defaults"]);
  }
  std::printf("\n%-26s %12s %12s %9s\n", "distances alone", "native", "script", "speed-up");
  for (const std::string key : {"plan_guided_split_b1_8", "plan_guided_split_b1_shelf"}) {
    std::printf("%-26s %9.2f ms %9.2f ms %8.2fx\n", key.c_str(), ms[key], ms[key + "_script_distances"],
                ms[key + "_script_distances"] / ms[key]);
  }
  // Throughput in plans and training samples per second.
  std::printf("\nthroughput (\"_8\": eight spheres)     flowplan       eager fp32     eager bf16\n");
  for (const std::string key : {"plan_guided_split_b64", "plan_guided_split_b64_8", "mpd_guided_b64", "mpd_guided_b64_8"}) {
    std::string rates[2] = {"-", "-"};
    for (int i = 0; i < 2; ++i) {
      const auto ref = reference.find(key + (i == 0 ? "" : "_bf16"));
      if (ref == reference.end()) continue;
      char rate[32];
      std::snprintf(rate, sizeof(rate), "%.1f plans/s", 64e3 / ref->second);
      rates[i] = rate;
    }
    std::printf("%-34s %8.1f plans/s %14s %14s\n", key.c_str(), 64e3 / ms[key], rates[0].c_str(), rates[1].c_str());
  }
  for (const std::string key : {"rrt_connect_per_plan", "rrt_connect_per_plan_8"}) {
    std::printf("%-34s %8.1f plans/s\n", key.c_str(), 1e3 / ms[key]);
  }
  for (const std::string key : {"train_step_b256", "train_step_b256_bf16"}) {
    const auto ref = reference.find(key);
    std::printf("%-34s %8.2f steps/s, %6.0f samples/s   eager %s\n", key.c_str(), 1e3 / ms[key], 256e3 / ms[key],
                ref == reference.end() ? "-" : (std::to_string(256e3 / ref->second).substr(0, 6) + " samples/s").c_str());
  }
  // The arithmetic limit of a forward pass: its FLOPs at the best rate this
  // machine's LibTorch reaches, a large convolution of the UNet's kind (oneDNN);
  // a large matrix product (OpenBLAS) for comparison.
  {
    c10::InferenceMode inference;
    const torch::Tensor x = torch::randn({64, 256, 64}), w = torch::randn({256, 256, 5});
    const double conv_ms = MedianMs(10, [&] { torch::conv1d(x, w, {}, 1, 2); });
    const double conv_gflops = 2.0 * 64 * 256 * 256 * 5 * 64 / (conv_ms * 1e6);
    const torch::Tensor a = torch::randn({1024, 1024}), b = torch::randn({1024, 1024});
    const double gemm_ms = MedianMs(10, [&] { torch::mm(a, b); });
    const double gemm_gflops = 2.0 * 1024 * 1024 * 1024 / (gemm_ms * 1e6);
    std::printf("\non %d threads: convolution (64, 256, 64) * (256, 256, 5) %.1f GFLOP/s, matrix product 1024^3 "
                "%.1f GFLOP/s\n", threads, conv_gflops, gemm_gflops);
    ms["conv_gflops"] = conv_gflops;
    ms["gemm_gflops"] = gemm_gflops;
    if (reference.count("flops_b1") != 0) {
      const double limit_ms = reference["flops_b1"] / (conv_gflops * 1e6);
      std::printf("forward B=1: %.1f MFLOP -> arithmetic limit %.3f ms; the planners' network %.3f ms = %.1fx the "
                  "limit (the C++ training network %.2f ms = %.1fx)\n", reference["flops_b1"] / 1e6, limit_ms,
                  ms["planner_forward_b1"], ms["planner_forward_b1"] / limit_ms, ms["forward_b1"],
                  ms["forward_b1"] / limit_ms);
      ms["flops_b1"] = reference["flops_b1"];
    }
  }
  std::ofstream json(out + "/flowplan.json");
  json << "{";
  bool first = true;
  for (const auto& [key, value] : ms) {
    json << (first ? "" : ", ") << "\"" << key << "\": " << value;
    first = false;
  }
  json << "}\n";
  return 0;
}

}  // namespace
}  // namespace flowplan

int main(int argc, char** argv) {
  try {
    return flowplan::Main(argc, argv);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 1;
  }
}
