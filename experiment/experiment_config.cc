#include "experiment/experiment_config.h"

namespace flowplan::experiment {

ExperimentConfig LoadExperiment(const std::string& path, const std::vector<std::string>& overrides) {
  return config::Load<ExperimentConfig>(path, overrides);
}

ExperimentConfig LoadExperimentText(const std::string& yaml, const std::string& source,
                                    const std::string& overlay_path, const std::vector<std::string>& overrides) {
  ExperimentConfig result;
  YAML::Node stored = config::ParseYamlText(yaml, source);
  // Configs written before model.architecture became model.name (e.g. inside older checkpoints).
  if (stored["model"] && stored["model"]["architecture"] && !stored["model"]["name"]) {
    stored["model"]["name"] = YAML::Clone(stored["model"]["architecture"]);
    stored["model"].remove("architecture");
  }
  config::Apply(stored, result, source);
  if (!overlay_path.empty()) config::Apply(config::ParseYamlFile(overlay_path), result, overlay_path);
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
