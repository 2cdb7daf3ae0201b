#include "experiment/trained_planner.h"

#include "checkpoints/checkpoint.h"
#include "core/error.h"
#include "models/conditioning.h"
#include "models/device.h"
#include "models/model_config.h"
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

}  // namespace flowplan::experiment
