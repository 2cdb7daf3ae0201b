#include "experiment/experiment_config.h"

#include <spdlog/spdlog.h>

namespace flowplan::experiment {

namespace {

/// Keys that no longer mean anything: RRT-Connect's own margin and motion resolution (it is valid by the plan
/// checker's check.* now) and the sampled self-check's resolution (self-collision is certified along motions).
constexpr std::pair<const char*, const char*> kRetiredKeys[] = {
    {"rrt_connect", "margin"}, {"rrt_connect", "resolution"}, {"check", "self_resolution"}};

/// Configs written before model.architecture became model.name, or with retired keys (older run folders,
/// checkpoints and exported planners) read as if written today; `source` is named in a warning when `warn`.
YAML::Node Migrated(YAML::Node node, const std::string& source = "", bool warn = false) {
  if (node.IsMap() && node["model"] && node["model"].IsMap()) {
    YAML::Node model = node["model"];
    if (model["architecture"] && !model["name"]) {
      model["name"] = YAML::Clone(model["architecture"]);
      model.remove("architecture");
    }
  }
  for (const auto& [section, key] : kRetiredKeys) {
    if (node.IsMap() && node[section] && node[section].IsMap() && node[section][key]) {
      if (warn) {
        spdlog::warn("{}: {}.{} is no longer used (RRT-Connect and the plan checker share check.*); ignored",
                     source, section, key);
      }
      node[section].remove(key);
    }
  }
  return node;
}

}  // namespace

ExperimentConfig LoadExperiment(const std::string& path, const std::vector<std::string>& overrides) {
  ExperimentConfig result;
  if (!path.empty()) config::Apply(Migrated(config::ParseYamlFile(path), path, true), result, path);
  for (const auto& assignment : overrides) config::Apply(config::ParseOverride(assignment), result, config::kCommandLine);
  return result;
}

ExperimentConfig LoadExperimentText(const std::string& yaml, const std::string& source,
                                    const std::string& overlay_path, const std::vector<std::string>& overrides) {
  ExperimentConfig result;
  config::Apply(Migrated(config::ParseYamlText(yaml, source)), result, source);
  if (!overlay_path.empty()) {
    config::Apply(Migrated(config::ParseYamlFile(overlay_path), overlay_path, true), result, overlay_path);
  }
  for (const auto& assignment : overrides) config::Apply(config::ParseOverride(assignment), result, config::kCommandLine);
  return result;
}

std::string ToYaml(const ExperimentConfig& config) { return config::ToYaml(config, /*skip_unset=*/true); }

std::string DatasetConfigYaml(const ExperimentConfig& config) {
  YAML::Node node = config::internal::Encode(config);
  node.remove("threads");
  node["generate"].remove("out");
  YAML::Emitter out;
  out << node;
  return std::string(out.c_str()) + "\n";
}

}  // namespace flowplan::experiment
