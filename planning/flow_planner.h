#pragma once

#include <torch/torch.h>

#include <algorithm>
#include <cstdint>

#include "core/config.h"
#include "models/normalizer.h"
#include "models/velocity_net.h"
#include "planning/conditioning.h"
#include "planning/euler.h"

namespace flowplan::planning {

/// Inference-time trajectory splitting (SPEC section 2).
enum class Splitting {
  kNone,
  // After the full loop: re-noise the plan to t = 0.5, cut it into halves that
  // take the states beside the midpoint as their missing boundary conditions,
  // and integrate each half from t = 0.5 to 1 with half the steps.
  kMidpoint,
};

inline const config::EnumNames<Splitting>& EnumEntries(Splitting) {
  static const config::EnumNames<Splitting> names = {{Splitting::kNone, "none"}, {Splitting::kMidpoint, "midpoint"}};
  return names;
}

/// The `sampler` section of an experiment config.
struct SamplerConfig {
  int steps = 10;  // Euler steps from t = 0 (noise) to t = 1 (data)
  Splitting splitting = Splitting::kNone;

  template <class V>
  void Visit(V& v) {
    v.Field("steps", steps, "Euler steps from noise to a plan", config::Positive());
    v.Field("splitting", splitting, "inference-time trajectory splitting");
  }
};

/// Euler steps of the second (t = 0.5 -> 1) stage of splitting: half the steps, at least one.
inline int SplitSteps(const SamplerConfig& sampler) { return std::max(1, sampler.steps / 2); }

/// A trained flow planner: network, normalizer, conditioning and sampler.
/// Planning does not change it, and Plan() (which runs without autograd) may be
/// called from several threads at once.
class FlowPlanner {
 public:
  /// @param horizon T the network was trained for; @throws if the network cannot take it.
  FlowPlanner(models::VelocityNetPtr net, models::MinMaxNormalizer normalizer, Conditioning conditioning,
              int64_t horizon, SamplerConfig sampler);

  /// Plans from `start` to `goal` in raw units.
  /// @param start    (B, D) raw start states
  /// @param goal     (B, D) raw goal states
  /// @param noise    (B, T, D) standard-normal initial noise
  /// @param renoise  (B, T, D) standard-normal noise for splitting's re-noising; needed
  ///                 only when sampler.splitting is not none
  /// @returns        (B, T, D) raw plans, interior states clamped to the training range;
  ///                 under inpainting states 0 and T-1 are exactly start and goal
  /// @throws flowplan::Error on shape mismatches
  torch::Tensor Plan(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                     const torch::Tensor& renoise = torch::Tensor()) const;

  /// Plan() with all noise drawn from `generator`.
  torch::Tensor Sample(const torch::Tensor& start, const torch::Tensor& goal, at::Generator& generator) const;

  /// The same in normalized units, without the final clamp.
  /// start_n, goal_n: (B, D); noise, renoise: (B, T, D) -> (B, T, D).
  torch::Tensor PlanNormalized(const torch::Tensor& start_n, const torch::Tensor& goal_n, const torch::Tensor& noise,
                               const torch::Tensor& renoise = torch::Tensor()) const;

  /// The network's velocity field with this planner's conditioning applied.
  VelocityField Velocity(const torch::Tensor& start_n, const torch::Tensor& goal_n) const;

  const models::VelocityNetPtr& net() const { return net_; }
  const models::MinMaxNormalizer& normalizer() const { return normalizer_; }
  Conditioning conditioning() const { return conditioning_; }
  int64_t horizon() const { return horizon_; }
  int64_t state_dim() const { return normalizer_.dim(); }
  const SamplerConfig& sampler() const { return sampler_; }

 private:
  void CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                    const torch::Tensor& renoise) const;
  /// Integrates x (B, T', D) over `grid` with boundaries start_n, goal_n (B, D).
  torch::Tensor Integrate(const torch::Tensor& x, const torch::Tensor& start_n, const torch::Tensor& goal_n,
                          const TimeGrid& grid) const;

  models::VelocityNetPtr net_;
  models::MinMaxNormalizer normalizer_;
  Conditioning conditioning_;
  int64_t horizon_;
  SamplerConfig sampler_;
};

}  // namespace flowplan::planning
