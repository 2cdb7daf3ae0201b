#include "experiment/experiment_config.h"

namespace flowplan::experiment {

namespace {

/// Configs written before model.architecture became model.name (older run
/// folders, checkpoints and exported planners) read as if written today.
YAML::Node Migrated(YAML::Node node) {
  if (node.IsMap() && node["model"] && node["model"].IsMap()) {
    YAML::Node model = node["model"];
    if (model["architecture"] && !model["name"]) {
      model["name"] = YAML::Clone(model["architecture"]);
      model.remove("architecture");
    }
  }
  return node;
}

}  // namespace

ExperimentConfig LoadExperiment(const std::string& path, const std::vector<std::string>& overrides) {
  ExperimentConfig result;
  if (!path.empty()) config::Apply(Migrated(config::ParseYamlFile(path)), result, path);
  for (const auto& assignment : overrides) config::Apply(config::ParseOverride(assignment), result, config::kCommandLine);
  return result;
}

ExperimentConfig LoadExperimentText(const std::string& yaml, const std::string& source,
                                    const std::string& overlay_path, const std::vector<std::string>& overrides) {
  ExperimentConfig result;
  config::Apply(Migrated(config::ParseYamlText(yaml, source)), result, source);
  if (!overlay_path.empty()) config::Apply(Migrated(config::ParseYamlFile(overlay_path)), result, overlay_path);
  for (const auto& assignment : overrides) config::Apply(config::ParseOverride(assignment), result, config::kCommandLine);
  return result;
}

std::string ToYaml(const ExperimentConfig& config) { return config::ToYaml(config); }

std::string DatasetConfigYaml(const ExperimentConfig& config) {
  YAML::Node node = config::internal::Encode(config);
  node.remove("threads");
  node["generate"].remove("out");
  YAML::Emitter out;
  out << node;
  return std::string(out.c_str()) + "\n";
}

}  // namespace flowplan::experiment
