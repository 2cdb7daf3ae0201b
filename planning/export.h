#pragma once

#include <torch/script.h>

#include <string>
#include <vector>

#include "planning/flow_planner.h"

namespace flowplan::planning {

/// What an exported planner carries besides its weights, for its users.
struct ExportMetadata {
  std::string env;                        // "particle", "franka"
  double dt = 0.0;                        // s between states of a plan
  std::vector<std::string> state_labels;  // (D,)
  std::string config_yaml;                // the training run's resolved config
};

/// Builds a self-contained TorchScript module computing FlowPlanner::Plan with
/// nothing from flowplan: weights and normalizer statistics are buffers, the
/// network, normalization, inpainting and the Euler loop are TorchScript
/// methods. See docs/export.md for its methods:
///   plan(start (B, D), goal (B, D), noise (B, T, D)) -> (B, T, D)
///   sample(start (D,), goal (D,), num_samples: int) -> (num_samples, T, D)
torch::jit::Module BuildScriptPlanner(const FlowPlanner& planner, const ExportMetadata& metadata);

/// Writes BuildScriptPlanner() to `path` atomically.
/// @throws flowplan::Error if the file cannot be written.
void ExportPlanner(const FlowPlanner& planner, const ExportMetadata& metadata, const std::string& path);

}  // namespace flowplan::planning
