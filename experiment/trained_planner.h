#pragma once

// A learned planner restored from a training run's checkpoint: its EMA weights
// assembled with the run's config, overlaid with a call's settings.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "experiment/experiment_config.h"
#include "planning/learned_planner.h"

namespace flowplan::experiment {

struct TrainedPlanner {
  ExperimentConfig config;                          // the run's, with the overlay and overrides
  std::unique_ptr<planning::LearnedPlanner> planner;
  std::string checkpoint;                           // the file it was loaded from
  int64_t step = 0;
};

/// Loads `ckpt` (a checkpoint file or a run folder = its newest checkpoint); the
/// checkpoint's config is overlaid with `overlay_path` and `overrides` (e.g.
/// sampler.steps=20), which may change how it plans but not the network.
/// `scene`, when given, replaces the config's scene section in the config the
/// planner carries (an exported file keeps only the scene it is given).
/// @throws flowplan::Error for missing, corrupt or foreign checkpoints, and
///   for overrides of what shapes the network.
TrainedPlanner LoadTrainedPlanner(const std::string& ckpt, const std::string& overlay_path,
                                  const std::vector<std::string>& overrides,
                                  const std::optional<geometry::Scene>& scene = std::nullopt);

/// Throws, naming the key, if `changed` differs from `trained` in anything that
/// shapes the trained network (model.*, objective.name, objective.conditioning).
/// `where` names the stored config in the message.
void CheckSameNetwork(const ExperimentConfig& trained, const ExperimentConfig& changed, const std::string& where);

}  // namespace flowplan::experiment
