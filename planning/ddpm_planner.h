#pragma once

#include <torch/torch.h>

#include "models/normalizer.h"
#include "models/trajectory_net.h"
#include "objectives/ddpm_schedule.h"
#include "planning/flow_planner.h"
#include "planning/planner.h"
#include "planning/sampler_config.h"

namespace flowplan::planning {

/// Motion Planning Diffusion's planner: ancestral DDPM sampling with an
/// ε-predicting trajectory network, inpainted start and goal, and MPD's
/// guidance (SPEC section 2): only the last ceil(guide_fraction · N) denoising
/// steps are guided, each by guide_iterations gradient steps on the posterior
/// mean (x ← x − s · Σ_k w_k clip(∇C_k), no b_t) before the step's noise is
/// added, then extra_steps noise-free steps at k = 0, guided likewise.
///
/// Noise of a call: `noise` (B, T, D) is x_{N−1}; `renoise` (B, N−1, T, D)
/// holds the standard-normal noise added after the steps k = N−1 … 1.
class DdpmPlanner : public Planner {
 public:
  DdpmPlanner(models::TrajectoryNetPtr net, models::MinMaxNormalizer normalizer, models::Conditioning conditioning,
              int64_t horizon, const objectives::DdpmConfig& schedule, DdpmSamplerConfig sampler,
              GuidanceSetup guidance);

  PlanResult Plan(const PlanRequest& request) const override;

  /// As FlowPlanner::PlanWithNoise, with the noise of this class's comment.
  torch::Tensor PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                              const torch::Tensor& renoise, const torch::Tensor& obstacles = torch::Tensor(),
                              const guidance::GuidanceConfig* settings = nullptr) const;

  void WriteScript(jit::ScriptModule& module) const override;

  int64_t horizon() const override { return horizon_; }
  int64_t state_dim() const override { return normalizer_.dim(); }
  const objectives::DdpmSchedule& schedule() const { return schedule_; }

 private:
  /// The denoising steps as the sampler takes them: k, and whether noise follows.
  int GuidedSteps() const;
  void CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                    const torch::Tensor& renoise) const;

  models::TrajectoryNetPtr net_;
  models::MinMaxNormalizer normalizer_;
  models::Conditioning conditioning_;
  int64_t horizon_;
  objectives::DdpmSchedule schedule_;
  DdpmSamplerConfig sampler_;
  GuidanceSetup guidance_;
  // Per step k (N,): x0 = clamp(a_k x − b_k ε), mean = c1_k x0 + c2_k x, std_k of the added noise.
  std::vector<double> x0_from_x_, x0_from_eps_, c1_, c2_, std_;
};

}  // namespace flowplan::planning
