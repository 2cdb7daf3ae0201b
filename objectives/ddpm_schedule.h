#pragma once

#include <torch/torch.h>

#include "core/config.h"

namespace flowplan::objectives {

/// How β grows over the diffusion steps.
enum class BetaSchedule {
  kExponential,  // Motion Planning Diffusion's
  kLinear,       // DDPM's (Ho et al.; diffusers' "linear"): β_k = linspace(β_start, β_end, N)_k
};

inline const config::EnumNames<BetaSchedule>& EnumEntries(BetaSchedule) {
  static const config::EnumNames<BetaSchedule> names = {{BetaSchedule::kExponential, "exponential"},
                                                        {BetaSchedule::kLinear, "linear"}};
  return names;
}

/// The `objective.ddpm` section: the noise schedule (MPD's by default).
struct DdpmConfig {
  int steps = 25;            // N diffusion steps
  BetaSchedule schedule = BetaSchedule::kExponential;
  double beta_start = 1e-4;  // β of the first step
  double beta_end = 1.0;     // β of the last step before clipping (MPD: 1.0)
  double beta_max = 0.999;   // clip on β, so that 1/sqrt(ᾱ) stays finite while ᾱ at the last step is ~0

  template <class V>
  void Visit(V& v) {
    v.Field("steps", steps, "diffusion steps N", config::AtLeast(2));
    v.Field("schedule", schedule, "how beta grows from beta_start to beta_end");
    v.Field("beta_start", beta_start, "beta of the first step", config::InRange(1e-8, 1.0));
    v.Field("beta_end", beta_end, "beta of the last step before the clip", config::InRange(1e-8, 1.0));
    v.Field("beta_max", beta_max, "largest beta after clipping", config::InRange(1e-8, 0.9999999));
  }
};

/// The β schedule: exponential (Motion Planning Diffusion's: with x = linspace(0, N, N)
/// and a = ln(β_end/β_start)/N, β_k = β_start exp(a x_k)) or linear
/// (linspace(β_start, β_end, N)), clipped at beta_max; α_k = 1 − β_k, ᾱ_k = Π_{i ≤ k} α_i. Steps k = 0 … N−1; step N−1 is (nearly)
/// pure noise.
struct DdpmSchedule {
  explicit DdpmSchedule(const DdpmConfig& config);

  int steps = 0;
  torch::Tensor betas;       // (N,) float64
  torch::Tensor alphas;      // (N,)
  torch::Tensor alpha_bars;  // (N,)

  double beta(int k) const { return betas[k].item<double>(); }
  double alpha(int k) const { return alphas[k].item<double>(); }
  double alpha_bar(int k) const { return alpha_bars[k].item<double>(); }
  /// ᾱ_{k−1}, 1 for k = 0.
  double alpha_bar_before(int k) const { return k == 0 ? 1.0 : alpha_bar(k - 1); }
};

}  // namespace flowplan::objectives
