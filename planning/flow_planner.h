#pragma once

#include <torch/torch.h>

#include <algorithm>
#include <cstdint>
#include <memory>

#include "core/config.h"
#include "guidance/guide.h"
#include "jit/script_writer.h"
#include "kinematics/robot.h"
#include "models/normalizer.h"
#include "models/trajectory_net.h"
#include "models/conditioning.h"
#include "planning/euler.h"
#include "planning/planner.h"
#include "planning/sampler_config.h"

namespace flowplan::planning {

// How start and goal reach the network is the network's business (models/);
// samplers use the same names.
using models::ConditionDim;
using models::Conditioning;
using models::ConditionVector;
using models::Inpaint;

/// What guidance needs besides the network: the robot whose collision spheres
/// meet the obstacles, the time between states, and the default settings.
struct GuidanceSetup {
  std::shared_ptr<const kinematics::Robot> robot;  // null: the planner cannot be guided
  double dt = 0.0;                                  // s between the states of a plan
  guidance::GuidanceConfig config;                  // a call's settings unless it gives its own
};

/// The guide of one planning call around `obstacles` (K, W+1) with `config`,
/// or null when the call is unguided (no obstacles, or scale 0).
/// @throws flowplan::Error if obstacles are given to a planner without a robot, or are malformed.
std::unique_ptr<guidance::Guide> MakeCallGuide(const GuidanceSetup& setup, const models::MinMaxNormalizer& normalizer,
                                               const guidance::GuidanceConfig& config, const torch::Tensor& obstacles);

/// A trained flow planner: network, normalizer, conditioning, Euler sampler
/// with optional splitting, and guidance around obstacles. Planning does not
/// change it, and may run from several threads at once. The network always
/// runs without autograd; guidance takes the cost's gradient by formula.
class FlowPlanner : public Planner {
 public:
  /// @param horizon T the network was trained for; @throws if the network cannot take it.
  FlowPlanner(models::TrajectoryNetPtr net, models::MinMaxNormalizer normalizer, Conditioning conditioning,
              int64_t horizon, SamplerConfig sampler, GuidanceSetup guidance = {});

  /// Plans with noise drawn from request.seed (noise, then renoise when splitting).
  PlanResult Plan(const PlanRequest& request) const override;

  /// Plans from `start` to `goal` in raw units from explicit noise: what the
  /// exported planner's plan() computes.
  /// @param start     (B, D) raw start states
  /// @param goal      (B, D) raw goal states
  /// @param noise     (B, T, D) standard-normal initial noise
  /// @param renoise   (B, T, D) standard-normal noise for splitting's re-noising; needed
  ///                  only when sampler.splitting is not none
  /// @param obstacles (K, W+1) rows [centre, radius] to avoid; undefined or K = 0: unguided
  /// @param settings  guidance settings of this call; null: the planner's
  /// @returns         (B, T, D) raw plans, interior states clamped to the training range;
  ///                  under inpainting states 0 and T-1 are exactly start and goal
  /// @throws flowplan::Error on shape mismatches and bad obstacles
  torch::Tensor PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                              const torch::Tensor& renoise = torch::Tensor(),
                              const torch::Tensor& obstacles = torch::Tensor(),
                              const guidance::GuidanceConfig* settings = nullptr) const;

  /// The same in normalized units, without the final clamp; `guide` null: unguided.
  /// start_n, goal_n: (B, D); noise, renoise: (B, T, D) -> (B, T, D).
  torch::Tensor PlanNormalized(const torch::Tensor& start_n, const torch::Tensor& goal_n, const torch::Tensor& noise,
                               const torch::Tensor& renoise, const guidance::Guide* guide,
                               const torch::Tensor& obstacles, double scale) const;

  /// The network's velocity field with this planner's conditioning applied.
  VelocityField Velocity(const torch::Tensor& start_n, const torch::Tensor& goal_n) const;

  /// Writes the whole planner into `module`: the network (net_velocity and the
  /// checked velocity), the normalizer, the robot, the guidance cost and the
  /// sampler (integrate, plan, sample). See docs/export.md.
  /// @throws flowplan::Error if the planner has no robot description.
  void WriteScript(jit::ScriptModule& module) const override;

  int64_t horizon() const override { return horizon_; }
  int64_t state_dim() const override { return normalizer_.dim(); }
  const models::TrajectoryNetPtr& net() const { return net_; }
  const models::MinMaxNormalizer& normalizer() const { return normalizer_; }
  Conditioning conditioning() const { return conditioning_; }
  const SamplerConfig& sampler() const { return sampler_; }
  const GuidanceSetup& guidance() const { return guidance_; }

 private:
  void CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                    const torch::Tensor& renoise) const;
  /// Integrates x (B, T', D) over `grid` with boundaries start_n, goal_n (B, D).
  torch::Tensor Integrate(const torch::Tensor& x, const torch::Tensor& start_n, const torch::Tensor& goal_n,
                          const TimeGrid& grid, const guidance::Guide* guide, const torch::Tensor& obstacles,
                          double scale) const;

  models::TrajectoryNetPtr net_;
  models::MinMaxNormalizer normalizer_;
  Conditioning conditioning_;
  int64_t horizon_;
  SamplerConfig sampler_;
  GuidanceSetup guidance_;
};

}  // namespace flowplan::planning
