#pragma once

#include <torch/script.h>

#include <string>
#include <vector>

#include "kinematics/robot_description.h"
#include "planning/planner.h"

namespace flowplan::planning {

/// An exported planner file (flowplan export) behind the Planner interface, so
/// that `flowplan plan --planner FILE` and evaluations run what a deployment
/// runs. Noise is drawn from the request's seed exactly as FlowPlanner::Plan
/// draws it, so the same seed gives the in-process planner's plans.
class ScriptPlanner : public Planner {
 public:
  /// @throws flowplan::Error naming the file if it is missing, not a TorchScript
  ///   module, or not a flowplan planner of export format kExportFormatVersion.
  explicit ScriptPlanner(const std::string& path);

  /// Plans with the file's guidance settings; of request.guidance only the
  /// scale can change (the rest is compiled into the file).
  PlanResult Plan(const PlanRequest& request) const override;

  int64_t horizon() const override { return horizon_; }
  int64_t state_dim() const override { return state_dim_; }

  const std::string& path() const { return path_; }
  const std::string& env() const { return env_; }
  double dt() const { return dt_; }
  const std::vector<std::string>& state_labels() const { return state_labels_; }
  const kinematics::RobotDescription& robot() const { return robot_; }
  const std::string& config_yaml() const { return config_yaml_; }

 private:
  std::string path_;
  mutable torch::jit::Module module_;  // run_method is not const; running it is thread-safe
  int64_t horizon_ = 0, state_dim_ = 0;
  std::vector<int64_t> noise_shape_, renoise_shape_;  // after B; renoise empty: none
  std::string env_, config_yaml_;
  double dt_ = 0.0;
  std::vector<std::string> state_labels_;
  kinematics::RobotDescription robot_;
};

}  // namespace flowplan::planning
