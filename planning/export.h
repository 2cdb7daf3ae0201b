#pragma once

#include <torch/script.h>

#include <string>
#include <vector>

#include "planning/planner.h"

namespace flowplan::planning {

/// Bumped whenever the methods or attributes of an exported module change.
/// 3: guidance (obstacles and scale arguments), tcp(), collision_spheres(), the robot description.
inline constexpr int64_t kExportFormatVersion = 3;

/// What an exported planner carries besides what its components write, for its users.
struct ExportMetadata {
  std::string env;                        // "particle", "franka"
  double dt = 0.0;                        // s between states of a plan
  std::vector<std::string> state_labels;  // (D,)
  std::string config_yaml;                // the training run's resolved config
};

/// A self-contained TorchScript module computing `planner` with nothing from
/// flowplan: each component (network, normalizer, robot, costs, sampler)
/// writes its own methods and buffers (Planner::WriteScript), and the metadata
/// becomes attributes. See docs/export.md.
/// @throws flowplan::Error if the planner cannot be exported.
torch::jit::Module BuildScriptPlanner(const Planner& planner, const ExportMetadata& metadata);

/// Writes BuildScriptPlanner() to `path` atomically.
/// @throws flowplan::Error if the file cannot be written.
void ExportPlanner(const Planner& planner, const ExportMetadata& metadata, const std::string& path);

}  // namespace flowplan::planning
