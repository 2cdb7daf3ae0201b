#pragma once

#include <torch/torch.h>

#include <cstdint>

#include "core/config.h"
#include "models/normalizer.h"
#include "models/velocity_net.h"
#include "planning/conditioning.h"
#include "planning/euler.h"

namespace flowplan::planning {

/// The `sampler` section of an experiment config.
struct SamplerConfig {
  int steps = 10;  // Euler steps from t = 0 (noise) to t = 1 (data)

  template <class V>
  void Visit(V& v) {
    v.Field("steps", steps, "Euler steps from noise to a plan", config::Positive());
  }
};

/// A trained flow planner: network, normalizer, conditioning and sampler.
/// Planning does not change it; concurrent calls need separate planners only
/// because LibTorch modules are not re-entrant under autograd.
class FlowPlanner {
 public:
  /// @param horizon T the network was trained for; @throws if the network cannot take it.
  FlowPlanner(models::VelocityNetPtr net, models::MinMaxNormalizer normalizer, Conditioning conditioning,
              int64_t horizon, SamplerConfig sampler);

  /// Plans from `start` to `goal` in raw units.
  /// @param start  (B, D) raw start states
  /// @param goal   (B, D) raw goal states
  /// @param noise  (B, T, D) standard-normal initial noise
  /// @returns      (B, T, D) raw plans, interior states clamped to the training range;
  ///               under inpainting states 0 and T-1 are exactly start and goal
  /// @throws flowplan::Error on shape mismatches
  torch::Tensor Plan(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise) const;

  /// Plan() with noise drawn from `generator`.
  torch::Tensor Sample(const torch::Tensor& start, const torch::Tensor& goal, at::Generator& generator) const;

  /// The same in normalized units, without the final clamp.
  /// start_n, goal_n: (B, D); noise: (B, T, D) -> (B, T, D).
  torch::Tensor PlanNormalized(const torch::Tensor& start_n, const torch::Tensor& goal_n,
                               const torch::Tensor& noise) const;

  /// The network's velocity field with this planner's conditioning applied.
  VelocityField Velocity(const torch::Tensor& start_n, const torch::Tensor& goal_n) const;

  const models::VelocityNetPtr& net() const { return net_; }
  const models::MinMaxNormalizer& normalizer() const { return normalizer_; }
  Conditioning conditioning() const { return conditioning_; }
  int64_t horizon() const { return horizon_; }
  int64_t state_dim() const { return normalizer_.dim(); }
  const SamplerConfig& sampler() const { return sampler_; }

 private:
  void CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise) const;

  models::VelocityNetPtr net_;
  models::MinMaxNormalizer normalizer_;
  Conditioning conditioning_;
  int64_t horizon_;
  SamplerConfig sampler_;
};

}  // namespace flowplan::planning
