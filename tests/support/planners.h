// Small planners for tests: the particle's and the Franka's trajectory
// descriptions, networks whose output is known in closed form (written as
// TorchScript, as every network a planner runs is), and the parts a planner
// is assembled from.
#pragma once

#include <torch/torch.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "jit/script_writer.h"
#include "kinematics/robot_description.h"
#include "kinematics/trajectory_info.h"
#include "models/model_config.h"
#include "models/normalizer.h"
#include "models/trajectory_net.h"
#include "planning/assemble.h"
#include "sim/franka_model.h"

namespace flowplan::testing {

/// A disc of radius 0.05 in [-1, 1]²: states (x, y, vx, vy), T states 0.1 s apart.
inline kinematics::TrajectoryInfo DiscTrajectory(int64_t horizon = 16) {
  kinematics::TrajectoryInfo info;
  info.env = "particle";
  info.dt = 0.1;
  info.horizon = horizon;
  info.state_labels = {"x", "y", "vx", "vy"};
  info.robot = kinematics::PointRobot("disc", 2, 0.05, -1.0, 1.0);
  return info;
}

/// The Franka: states (q1..q7, dq1..dq7) at 15 Hz.
inline kinematics::TrajectoryInfo FrankaTrajectory(int64_t horizon = 16) {
  kinematics::TrajectoryInfo info;
  info.env = "franka";
  info.dt = 1.0 / 15.0;
  info.horizon = horizon;
  for (int j = 1; j <= 7; ++j) info.state_labels.push_back("q" + std::to_string(j));
  for (int j = 1; j <= 7; ++j) info.state_labels.push_back("dq" + std::to_string(j));
  static const kinematics::RobotDescription franka = sim::LoadFrankaModel().description();
  info.robot = franka;
  return info;
}

/// The identity normalizer on D dims: raw == normalized on [-1, 1].
inline models::MinMaxNormalizer UnitNormalizer(int64_t D) {
  return models::MinMaxNormalizer(-torch::ones({D}), torch::ones({D}));
}

/// A trajectory network given by TorchScript lines that read x (B, T, D), t (B,),
/// cond and buffers, and assign `out` (B, T, D). Its C++ Forward() is not used
/// by planners and throws.
class ScriptedNet : public models::TrajectoryNet {
 public:
  ScriptedNet(int64_t state_dim, std::vector<std::string> lines,
              std::vector<std::pair<std::string, torch::Tensor>> buffers = {}, int64_t cond_dim = 0)
      : state_dim_(state_dim), cond_dim_(cond_dim), lines_(std::move(lines)), buffers_(std::move(buffers)) {}
  torch::Tensor Forward(const torch::Tensor&, const torch::Tensor&, const torch::Tensor&) override {
    throw std::logic_error("ScriptedNet runs only as TorchScript");
  }
  void CheckHorizon(int64_t) const override {}
  std::string WriteScript(jit::ScriptWriter& writer) const override {
    for (const auto& [name, value] : buffers_) writer.Tensor(name, value);
    for (const std::string& line : lines_) writer.Line(line);
    return "out";
  }
  int64_t state_dim() const override { return state_dim_; }
  int64_t cond_dim() const override { return cond_dim_; }

 private:
  int64_t state_dim_, cond_dim_;
  std::vector<std::string> lines_;
  std::vector<std::pair<std::string, torch::Tensor>> buffers_;
};

/// Velocity zero everywhere: plans stay where the noise (and guidance) put them.
inline std::shared_ptr<models::TrajectoryNet> ZeroVelocity(int64_t D, int64_t cond_dim = 0) {
  return std::make_shared<ScriptedNet>(D, std::vector<std::string>{"out = torch.zeros_like(x)"},
                                       std::vector<std::pair<std::string, torch::Tensor>>{}, cond_dim);
}

/// A small UNet with fresh weights (seeded), for any conditioning.
inline std::shared_ptr<models::TrajectoryNet> TinyUNet(int64_t D, int64_t cond_dim, uint64_t seed = 0) {
  torch::manual_seed(seed);
  models::ModelConfig config;
  config.unet.down_dims = {16, 32};
  return models::MakeTrajectoryNet(config, D, cond_dim);
}

/// The parts of a planner of `net` for `trajectory`, guidance off unless set.
inline planning::PlannerParts Parts(models::NetworkPtr net, const kinematics::TrajectoryInfo& trajectory,
                                    models::MinMaxNormalizer normalizer) {
  planning::PlannerParts parts;
  parts.net = std::move(net);
  parts.normalizer = std::move(normalizer);
  parts.trajectory = trajectory;
  parts.config_yaml = "{}\n";
  return parts;
}

/// A sphere scene (K, W + 1) as the rows a planning call takes.
inline geometry::SceneRows Spheres(const torch::Tensor& rows) { return geometry::SphereRows(rows); }

}  // namespace flowplan::testing
