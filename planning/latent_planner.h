#pragma once

#include <torch/torch.h>

#include <memory>

#include "models/normalizer.h"
#include "models/state_vae.h"
#include "planning/flow_planner.h"
#include "planning/planner.h"
#include "planning/sampler_config.h"

namespace flowplan::planning {

/// The VAE baseline's planner ("Reaching Through Latent Space", SPEC section 2):
/// activation maximization in the latent space of a state VAE. From the latent
/// of the start state (its encoding's mean plus its standard deviation times
/// `noise`), Adam steps on the latent lower
///   goal_weight · |TCP(decode(z)) − TCP(goal)| + collision cost (guidance.*,
///   scaled by the guidance scale) + prior_weight · |z|²/2,
/// and after `iterations` steps the decoded state becomes the next waypoint;
/// once a waypoint's TCP is within goal_tolerance of the goal, it is held for
/// the rest of the T states. Gradients are written out (the decoder's and the
/// kinematics' vector–Jacobian products), so the exported planner needs no
/// autograd. The goal is not imposed: a plan ends where the optimization got.
///
/// Noise of a call: `noise` (B, L), standard normal; no renoise.
class LatentPlanner : public Planner {
 public:
  LatentPlanner(std::shared_ptr<models::StateVae> vae, models::MinMaxNormalizer normalizer, int64_t horizon,
                LatentPlannerConfig config, GuidanceSetup guidance);

  PlanResult Plan(const PlanRequest& request) const override;

  /// start, goal (B, D) raw; noise (B, L); obstacles (K, W+1) or undefined -> (B, T, D) raw.
  torch::Tensor PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                              const torch::Tensor& obstacles = torch::Tensor(),
                              const guidance::GuidanceConfig* settings = nullptr) const;

  void WriteScript(jit::ScriptModule& module) const override;

  int64_t horizon() const override { return horizon_; }
  int64_t state_dim() const override { return normalizer_.dim(); }

 private:
  std::shared_ptr<models::StateVae> vae_;
  models::MinMaxNormalizer normalizer_;
  int64_t horizon_;
  LatentPlannerConfig config_;
  GuidanceSetup guidance_;
};

}  // namespace flowplan::planning
