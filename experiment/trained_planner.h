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

/// The planner an exported file holds, assembled again in-process from the
/// file's network weights and normalizer with `config`: the file's own config
/// (LoadExperimentText of file.config_yaml()), changed in nothing compiled
/// into the file (CheckExportedKeys) but free in the kernels
/// (sampler.network_kernels, guidance.distance_kernels), every per-call number
/// and the scene. How flowplan plans with a portable file at the speed of its
/// native operators. The network read back is held to the file's: the same
/// forward pass on a random input, to 1e-5.
/// @throws flowplan::Error naming the file if its weights do not fit its
///   config or do not compute what its network does, a compiled-in key
///   changed, it is a VAE planner (no native kernels), or it carries a user
///   cost (compiled into the file; assembling again would read the cost's
///   file as it is now).
std::unique_ptr<planning::LearnedPlanner> AssembleExported(const planning::LearnedPlanner& file,
                                                           const ExperimentConfig& config);

/// AssembleExported with the file's own config and flowplan's native kernels
/// (the network's and the collision cost's).
/// @throws flowplan::Error as AssembleExported.
std::unique_ptr<planning::LearnedPlanner> AssembleNative(const planning::LearnedPlanner& file);

/// AssembleExported(*file, config), or `file` itself, with a log line saying
/// why, when it cannot be assembled again (info for a VAE planner or a user
/// cost, a warning for anything else). `assembled`, when given, says which.
std::unique_ptr<planning::LearnedPlanner> AssembleOrKeep(std::unique_ptr<planning::LearnedPlanner> file,
                                                         const ExperimentConfig& config, bool* assembled = nullptr);

/// An exported planner file as flowplan plans with it: AssembleNative, or the
/// file as written when it cannot be assembled again (AssembleOrKeep).
/// @throws flowplan::Error naming the file if it is not a flowplan planner.
std::unique_ptr<planning::LearnedPlanner> LoadExportedPlanner(const std::string& path);

/// Throws, naming the key, if `changed` differs from `trained` in anything that
/// shapes the trained network (model.*, objective.name, objective.conditioning).
/// `where` names the stored config in the message.
void CheckSameNetwork(const ExperimentConfig& trained, const ExperimentConfig& changed, const std::string& where);

/// Throws, naming the key and `file`, if `changed` differs from `exported` in
/// the network (CheckSameNetwork) or in what is compiled into an exported file
/// (sampler.splitting, sampler.ddpm.guide_on, guidance.user_cost,
/// objective.ddpm.*); every number of guidance.* and of its sampler is a
/// per-call setting.
void CheckExportedKeys(const ExperimentConfig& exported, const ExperimentConfig& changed, const std::string& file);

}  // namespace flowplan::experiment
