#pragma once

// A learned planner (flow matching, DDPM, the VAE planner): a TorchScript
// module of class Planner (planning/planner.py), assembled in-process from a
// trained network (planning/assemble.h) or loaded from an exported file. The
// module is the planner: planning in-process runs it, and `flowplan export`
// saves it (docs/export.md).

#include <torch/script.h>
#include <torch/torch.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "kinematics/trajectory_info.h"
#include "planning/planner.h"

namespace flowplan::planning {

/// The exported planner's format; a file of another version is refused.
// 4: one planning stack, obstacle shapes, per-call settings; 5: guidance variants (guide_at), best of N.
inline constexpr int64_t kExportFormatVersion = 5;

class LearnedPlanner : public Planner {
 public:
  /// Wraps a Planner module; `source` names it in messages (a file, or "in-process").
  /// @throws flowplan::Error naming `source` if the module is not a flowplan planner of this format.
  explicit LearnedPlanner(torch::jit::Module module, std::string source = "in-process");

  /// Loads an exported file. @throws flowplan::Error naming the file.
  static std::unique_ptr<LearnedPlanner> Load(const std::string& path);

  /// Writes the module to `path` atomically; it loads with torch.jit.load / torch::jit::load alone.
  /// @throws flowplan::Error if it cannot be written.
  void Save(const std::string& path) const;

  /// Plans with noise drawn from request.seed (noise, then renoise; with N =
  /// guidance.candidates > 1, N of each per plan), under torch.no_grad.
  PlanResult Plan(const PlanRequest& request) const override;

  /// Plans from explicit noise: the module's plan().
  /// @param start, goal (B, D) raw states
  /// @param noise       (B, *noise_shape()) standard normal; (B, N, *noise_shape()) with N = guidance.candidates > 1
  /// @param renoise     the same for renoise_shape(), or undefined when renoise_shape() is empty
  /// @returns           (B, T, D) raw plans on the CPU
  torch::Tensor PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                              const torch::Tensor& renoise = torch::Tensor(),
                              const geometry::SceneRows& scene = geometry::SceneRows(),
                              const PlanSettings& settings = {}) const;

  /// The guidance cost (B,) float64 of raw plans (B, T, D) in `scene` with
  /// this call's settings: the weighted sum of the cost terms the planner
  /// guides with (what best of N ranks by), whatever the scale.
  torch::Tensor GuidanceCost(const torch::Tensor& plans, const geometry::SceneRows& scene,
                             const PlanSettings& settings = {}) const;

  int64_t horizon() const override { return info_.horizon; }
  int64_t state_dim() const override { return info_.state_dim(); }

  const torch::jit::Module& module() const { return module_; }
  const std::string& source() const { return source_; }
  const kinematics::TrajectoryInfo& info() const { return info_; }
  /// "flow_matching", "ddpm" or "latent".
  const std::string& kind() const { return kind_; }
  /// The resolved config of the run the planner was trained in (YAML).
  const std::string& config_yaml() const { return config_yaml_; }
  /// Every per-call setting with the planner's value (the module's `settings`).
  const std::map<std::string, double>& settings() const { return settings_; }
  const std::string& schedule() const { return schedule_; }
  /// Where the flow planner guides ("state", "velocity", "prediction"; sampler.guide_at).
  const std::string& guide_at() const { return guide_at_; }
  const std::vector<int64_t>& noise_shape() const { return noise_shape_; }
  const std::vector<int64_t>& renoise_shape() const { return renoise_shape_; }

 private:
  torch::jit::Module module_;
  std::string source_;
  kinematics::TrajectoryInfo info_;
  std::string kind_, config_yaml_, schedule_, guide_at_;
  std::map<std::string, double> settings_;
  std::vector<int64_t> noise_shape_, renoise_shape_;
};

}  // namespace flowplan::planning
