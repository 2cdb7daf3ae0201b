#include "experiment/trained_planner.h"

#include <spdlog/spdlog.h>

#include "checkpoints/checkpoint.h"
#include "core/error.h"
#include "core/format.h"
#include "jit/library.h"
#include "models/conditioning.h"
#include "models/device.h"
#include "models/model_config.h"
#include "models/trajectory_net.h"
#include "planning/assemble.h"
#include "trainer/run_dir.h"

namespace flowplan::experiment {

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

void CheckExportedKeys(const ExperimentConfig& exported, const ExperimentConfig& changed, const std::string& file) {
  CheckSameNetwork(exported, changed, file);
  const auto before = config::ListKeys(exported), after = config::ListKeys(changed);
  for (size_t i = 0; i < before.size(); ++i) {
    const std::string& key = before[i].key;
    const bool compiled = key == "sampler.splitting" || key == "sampler.ddpm.guide_on" || key == "guidance.user_cost" ||
                          key.rfind("objective.ddpm.", 0) == 0;
    if (compiled && before[i].default_value != after[i].default_value) {
      throw Error(key + ": is compiled into " + file + " (" + before[i].default_value +
                  "); plan from the run folder with --ckpt, or export again with the setting");
    }
  }
}

TrainedPlanner LoadTrainedPlanner(const std::string& ckpt, const std::string& overlay_path,
                                  const std::vector<std::string>& overrides,
                                  const std::optional<geometry::Scene>& scene) {
  TrainedPlanner loaded;
  loaded.checkpoint = trainer::ResolveCheckpoint(ckpt);
  const checkpoints::CheckpointHeader header = checkpoints::ReadCheckpointHeader(loaded.checkpoint);
  const std::string where = loaded.checkpoint + " (stored config)";
  loaded.config = LoadExperimentText(header.config_yaml, where, overlay_path, overrides);
  CheckSameNetwork(LoadExperimentText(header.config_yaml, where, "", {}), loaded.config, loaded.checkpoint);
  if (scene) loaded.config.scene = *scene;
  loaded.step = header.step;
  const int64_t D = header.normalizer.dim();
  const models::NetworkPtr net =
      models::MakeNetwork(loaded.config.model, D, models::ConditionDim(loaded.config.objective.conditioning, D));
  const torch::Device device = models::ParseDevice(loaded.config.device, "device");
  checkpoints::LoadCheckpointWeights(loaded.checkpoint, {nullptr, net.get(), nullptr}, device);
  net->to(device);
  net->eval();
  planning::PlannerParts parts;
  parts.net = net;
  parts.normalizer = header.normalizer;
  parts.objective = loaded.config.objective;
  parts.sampler = loaded.config.sampler;
  parts.guidance = loaded.config.guidance;
  parts.trajectory = header.trajectory;
  parts.config_yaml = ToYaml(loaded.config);
  loaded.planner = planning::AssemblePlanner(parts);
  return loaded;
}

std::unique_ptr<planning::LearnedPlanner> AssembleExported(const planning::LearnedPlanner& file,
                                                           const ExperimentConfig& given) {
  if (file.kind() == "latent") {
    throw Error(file.source() + ": a VAE planner has no native kernels; it plans with the file's own code");
  }
  if (!given.guidance.user_cost.empty()) {
    // The cost is compiled into the file; assembling again would compile whatever is at its path now.
    throw Error(file.source() + ": its user cost (" + given.guidance.user_cost +
                ") is compiled into it; it plans with the file's own code");
  }
  CheckExportedKeys(LoadExperimentText(file.config_yaml(), file.source() + " (its config)", "", {}), given,
                    file.source());
  ExperimentConfig config = given;
  config.device = "cpu";
  const torch::jit::Module& module = file.module();
  planning::PlannerParts parts;
  try {
    const torch::jit::Module normalizer = module.attr("normalizer").toModule();
    parts.normalizer = models::MinMaxNormalizer(normalizer.attr("lo").toTensor().clone(),
                                                normalizer.attr("hi").toTensor().clone());
    const int64_t D = parts.normalizer.dim();
    const models::NetworkPtr net =
        models::MakeNetwork(config.model, D, models::ConditionDim(config.objective.conditioning, D));
    const torch::jit::Module exported = module.attr("sampler").toModule().attr("network").toModule();
    auto* trajectory_net = dynamic_cast<models::TrajectoryNet*>(net.get());
    if (trajectory_net == nullptr) throw Error(file.source() + ": its network is not a trajectory network");
    models::ReadScriptedWeights(*trajectory_net, exported, file.source());
    net->eval();
    // The weights read back must make the file's network: its forward pass on one random input, against the
    // network written again with the same (portable) code.
    torch::NoGradGuard no_grad;
    const int64_t T = file.info().horizon, C = trajectory_net->cond_dim();
    auto generator = at::make_generator<at::CPUGeneratorImpl>(7);
    const torch::Tensor x = torch::randn({2, T, D}, generator, torch::kFloat32);
    const torch::Tensor t = torch::rand({2}, generator, torch::kFloat32);
    const c10::IValue cond = C > 0 ? c10::IValue(torch::randn({2, C}, generator, torch::kFloat32)) : c10::IValue();
    const torch::Tensor theirs = jit::Call(exported, "forward", {x, t, cond}).toTensor();
    const torch::Tensor ours =
        jit::Call(models::ScriptNetwork(*trajectory_net, models::Kernels::kPortable), "forward", {x, t, cond}).toTensor();
    const double scale = std::max(1.0, theirs.abs().max().item<double>());
    if (!((ours - theirs).abs().max().item<double>() <= 1e-5 * scale)) {
      throw Error(file.source() + ": the network read back from it does not compute what its own does");
    }
    parts.net = net;
  } catch (const c10::Error& e) {
    throw Error(file.source() + ": cannot read its network and normalizer: " + FirstLine(e.what_without_backtrace()));
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {  // torch::jit::ObjectAttributeError: a module without our submodules
    throw Error(file.source() + ": cannot read its network and normalizer: " + FirstLine(e.what()));
  }
  parts.objective = config.objective;
  parts.sampler = config.sampler;
  parts.guidance = config.guidance;
  parts.trajectory = file.info();
  parts.config_yaml = ToYaml(config);
  const std::unique_ptr<planning::LearnedPlanner> assembled = planning::AssemblePlanner(parts);
  return std::make_unique<planning::LearnedPlanner>(assembled->module(), file.source());
}

namespace {

/// The file's config with flowplan's native kernels.
ExperimentConfig NativeConfig(const planning::LearnedPlanner& file) {
  ExperimentConfig config = LoadExperimentText(file.config_yaml(), file.source() + " (its config)", "", {});
  config.sampler.network_kernels = models::Kernels::kNative;
  config.guidance.distance_kernels = models::Kernels::kNative;
  return config;
}

}  // namespace

std::unique_ptr<planning::LearnedPlanner> AssembleNative(const planning::LearnedPlanner& file) {
  return AssembleExported(file, NativeConfig(file));
}

std::unique_ptr<planning::LearnedPlanner> AssembleOrKeep(std::unique_ptr<planning::LearnedPlanner> file,
                                                         const ExperimentConfig& config, bool* assembled) {
  if (assembled != nullptr) *assembled = false;
  try {
    auto planner = AssembleExported(*file, config);
    if (assembled != nullptr) *assembled = true;
    return planner;
  } catch (const Error& e) {
    // A VAE and a compiled-in user cost are expected to plan so; anything else is worth a warning.
    if (file->kind() == "latent" || !config.guidance.user_cost.empty()) {
      spdlog::info("{}", e.what());
    } else {
      spdlog::warn("{}: plans with the file's own code, not flowplan's native kernels: {}", file->source(), e.what());
    }
    return file;
  }
}

std::unique_ptr<planning::LearnedPlanner> LoadExportedPlanner(const std::string& path) {
  std::unique_ptr<planning::LearnedPlanner> file = planning::LearnedPlanner::Load(path);
  const ExperimentConfig config = NativeConfig(*file);
  return AssembleOrKeep(std::move(file), config);
}

}  // namespace flowplan::experiment
