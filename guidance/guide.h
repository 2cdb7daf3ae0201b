#pragma once

// Guidance of a sampler towards low cost (SPEC section 2): after each sampler
// step, the normalized trajectories move against the gradient of the cost of
// their de-normalized states,
//   x ← x − s · b_t · Σ_k w_k · clip(∇ C_k(denormalize(x))) · (hi − lo)/2,
// over the weighted terms of the cost (collision, smoothness), with
// b_t = 1 − t (the paper's choice) or (1 − t)/t, and clip() capping the norm of
// each state's gradient of each term in raw units, as MPD does (without it the
// GP prior's gradient on early, noisy samples dwarfs the collision term).

#include <torch/torch.h>

#include <memory>
#include <string>

#include "core/config.h"
#include "guidance/cost.h"
#include "jit/script_writer.h"
#include "kinematics/robot.h"
#include "models/normalizer.h"

namespace flowplan::guidance {

/// b_t, the factor on the gradient at flow time t (0 noise, 1 data).
enum class GuidanceSchedule {
  kOneMinusT,  // 1 − t
  kRatio,      // (1 − t)/t, with t at least kMinRatioTime
  kRising,     // t: strongest after the last step, where the network's own pull back to the data is strongest
};

inline const config::EnumNames<GuidanceSchedule>& EnumEntries(GuidanceSchedule) {
  static const config::EnumNames<GuidanceSchedule> names = {{GuidanceSchedule::kOneMinusT, "one_minus_t"},
                                                            {GuidanceSchedule::kRatio, "ratio"},
                                                            {GuidanceSchedule::kRising, "rising"}};
  return names;
}

/// Smallest t the (1 − t)/t schedule divides by.
inline constexpr double kMinRatioTime = 1e-3;

/// The `guidance` section of an experiment config. Every field can also be set
/// for one planning call (`flowplan plan guidance.scale=2`, PlanRequest::guidance).
struct GuidanceConfig {
  double scale = 1.0;  // s; 0: unguided
  GuidanceSchedule schedule = GuidanceSchedule::kOneMinusT;
  double clip = 0.0;                // cap on each term's gradient norm per state (raw units), 0: none
  double collision_weight = 0.1;    // weight of the collision cost (SPEC / the paper)
  double smoothness_weight = 1e-6;  // weight of the GP smoothness prior
  double margin = 0.05;             // world units added to the radii in the collision hinge (MPD: 0.05 m)
  double smoothness_sigma = 1.0;    // σ of the GP prior

  template <class V>
  void Visit(V& v) {
    v.Field("scale", scale, "guidance scale s (0: unguided)", config::NonNegative());
    v.Field("schedule", schedule, "b_t, the factor on the cost gradient at flow time t");
    v.Field("clip", clip, "cap on the norm of each cost term's gradient at each state (raw units), 0 for none",
            config::NonNegative());
    v.Field("collision_weight", collision_weight, "weight of the collision cost", config::NonNegative());
    v.Field("smoothness_weight", smoothness_weight, "weight of the GP smoothness prior", config::NonNegative());
    v.Field("margin", margin, "clearance added to the radii in the collision hinge (world units)",
            config::NonNegative());
    v.Field("smoothness_sigma", smoothness_sigma, "sigma of the GP smoothness prior", config::Positive());
  }
};

/// b_t of `schedule` at flow time t.
double GuidanceFactor(GuidanceSchedule schedule, double t);

/// collision_weight · CollisionCost + smoothness_weight · SmoothnessCost for
/// `robot`, whose states are sampled `dt` s apart.
std::shared_ptr<const WeightedSumCost> MakeGuidanceCost(const GuidanceConfig& config,
                                                        std::shared_ptr<const kinematics::Robot> robot, double dt);

/// Applies guidance to normalized trajectories. Immutable; safe to share between threads.
class Guide {
 public:
  Guide(std::shared_ptr<const WeightedSumCost> cost, models::MinMaxNormalizer normalizer, GuidanceConfig config);

  /// Σ_k w_k clip(∇ C_k) with respect to normalized x (B, T, D), each term's
  /// raw gradient capped at config.clip per state (when positive). `obstacles` (K, W+1).
  torch::Tensor Gradient(const torch::Tensor& x_n, const torch::Tensor& obstacles) const;

  /// x − scale · b_t · Gradient(x): one guidance step at flow time t.
  torch::Tensor Step(const torch::Tensor& x_n, double t, const torch::Tensor& obstacles, double scale) const;

  /// Adds `guide_gradient(self, x, obstacles)` (Gradient), `guide(self, x,
  /// t: float, obstacles, scale: float)` (Step) and the cost's methods. Needs the normalizer's and the robot's methods in the module.
  void WriteScript(jit::ScriptModule& module) const;

  const GuidanceConfig& config() const { return config_; }

 private:
  std::shared_ptr<const WeightedSumCost> cost_;
  models::MinMaxNormalizer normalizer_;
  GuidanceConfig config_;
};

}  // namespace flowplan::guidance
