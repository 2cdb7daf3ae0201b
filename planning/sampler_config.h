#pragma once

#include "core/config.h"
#include "models/kernels.h"

namespace flowplan::planning {

/// Inference-time trajectory splitting (SPEC section 2).
enum class Splitting {
  kNone,
  // After the full loop: re-noise the plan to t = 0.5, cut it into halves that
  // take the states beside the midpoint as their missing boundary conditions,
  // and integrate each half from t = 0.5 to 1 with half the steps (guided too).
  kMidpoint,
};

inline const config::EnumNames<Splitting>& EnumEntries(Splitting) {
  static const config::EnumNames<Splitting> names = {{Splitting::kNone, "none"}, {Splitting::kMidpoint, "midpoint"}};
  return names;
}

/// Where the flow planner takes the cost's gradient and how it applies it
/// (sampler.guide_at; docs/planning.md, "Guidance variants"). The DDPM planner
/// always guides its posterior mean, the latent planner its waypoints.
enum class GuidanceTarget {
  kState,       // at x_t after each Euler step, moving x_t: x <- x - s b(t) grad C(x)
  kVelocity,    // at the clean prediction x̂1 = x_t + (1 - t) v, added to the velocity: v <- v - s b(t) grad C(x̂1)
  kPrediction,  // sampler.prediction_iterations steps on x̂1, then the Euler step heads for the moved x̂1
};

inline const config::EnumNames<GuidanceTarget>& EnumEntries(GuidanceTarget) {
  static const config::EnumNames<GuidanceTarget> names = {{GuidanceTarget::kState, "state"},
                                                          {GuidanceTarget::kVelocity, "velocity"},
                                                          {GuidanceTarget::kPrediction, "prediction"}};
  return names;
}

/// What the DDPM planner's guidance moves.
enum class DdpmGuideOn {
  // Motion Planning Diffusion's: guide_iterations steps of the scale on the
  // posterior mean, before the step's noise is added.
  kPosteriorMean,
  // The Flow Planner paper's baseline: guide_iterations steps on the sample
  // after the step's noise is added, weighted by that step's posterior
  // variance (0 at the last step).
  kSampleByVariance,
};

inline const config::EnumNames<DdpmGuideOn>& EnumEntries(DdpmGuideOn) {
  static const config::EnumNames<DdpmGuideOn> names = {{DdpmGuideOn::kPosteriorMean, "posterior_mean"},
                                                       {DdpmGuideOn::kSampleByVariance, "sample_by_variance"}};
  return names;
}

/// How the DDPM planner samples and guides (Motion Planning Diffusion's scheme by default).
struct DdpmSamplerConfig {
  DdpmGuideOn guide_on = DdpmGuideOn::kPosteriorMean;
  double guide_fraction = 0.25;  // guidance in the last ceil(fraction · steps) denoising steps
  int guide_iterations = 5;      // gradient steps on the posterior mean per guided step
  int extra_steps = 5;           // noise-free denoising steps at k = 0 after the chain, guided
  double noise_scale = 1.0;      // factor on the standard deviation of the noise each step adds

  template <class V>
  void Visit(V& v) {
    v.Field("guide_on", guide_on, "what guidance moves: the posterior mean (MPD) or the noised sample (the paper's baseline)");
    v.Field("guide_fraction", guide_fraction, "guide the last ceil(fraction * steps) denoising steps",
            config::Probability());
    v.Field("guide_iterations", guide_iterations, "gradient steps per guided denoising step", config::NonNegative());
    v.Field("extra_steps", extra_steps, "noise-free guided steps at the end", config::NonNegative());
    v.Field("noise_scale", noise_scale, "factor on the noise added at each step", config::NonNegative());
  }
};

/// How the latent (VAE) planner optimizes its waypoints.
struct LatentPlannerConfig {
  int iterations = 10;         // Adam steps on the latent per waypoint
  double lr = 0.05;            // Adam step size
  double goal_weight = 1.0;    // weight of the TCP's distance to the goal TCP
  double prior_weight = 1e-3;  // weight of 0.5 |z|^2 (the latent's standard-normal prior)
  double goal_tolerance = 0.01;  // world units: waypoints stop once the TCP is this close to the goal

  template <class V>
  void Visit(V& v) {
    v.Field("iterations", iterations, "Adam steps on the latent per waypoint", config::Positive());
    v.Field("lr", lr, "Adam step size on the latent", config::Positive());
    v.Field("goal_weight", goal_weight, "weight of the TCP distance to the goal", config::NonNegative());
    v.Field("prior_weight", prior_weight, "weight of the latent prior 0.5 |z|^2", config::NonNegative());
    v.Field("goal_tolerance", goal_tolerance, "stop adding waypoints once the TCP is this close to the goal",
            config::Positive());
  }
};

/// The `sampler` section of an experiment config: how each planner samples.
struct SamplerConfig {
  SamplerConfig() = default;
  /// The flow sampler's settings, every other planner's at their defaults.
  explicit SamplerConfig(int euler_steps, Splitting split = Splitting::kNone) : steps(euler_steps), splitting(split) {}

  int steps = 10;  // flow matching: Euler steps from t = 0 (noise) to t = 1 (data)
  Splitting splitting = Splitting::kNone;
  double split_time = 0.5;  // splitting: the flow time the halves are re-noised to and restart from
  // How the flow planner guides (docs/planning.md, "Guidance variants"); the guidance section says how strongly.
  GuidanceTarget guide_at = GuidanceTarget::kState;
  double guide_from = 0.0;        // no guidance before this flow time
  int prediction_iterations = 1;  // guide_at prediction: gradient steps on x̂1 per Euler step
  int final_iterations = 0;       // gradient steps of the guidance scale on the finished plan, each stage of splitting
  double final_denoise_time = 0.0;  // after each final step, one Euler step from this flow time to 1 (0: none)
  double final_spread = 0.0;        // final steps: states over which one state's push decays (0: each state alone)
  double final_joint_speed_weight = 0.0;  // final steps: added to guidance.joint_speed_weight
  int midpoint_iterations = 0;      // splitting: gradient steps on the first stage's plan before re-noising
  // The network's code in the planner: native kernels where the network has them (in-process default), or
  // LibTorch's operators only (what `flowplan export` writes unless told --kernels native).
  models::Kernels network_kernels = models::Kernels::kNative;
  DdpmSamplerConfig ddpm;
  LatentPlannerConfig latent;

  template <class V>
  void Visit(V& v) {
    v.Field("steps", steps, "flow matching: Euler steps from noise to a plan", config::Positive());
    v.Field("splitting", splitting, "flow matching: inference-time trajectory splitting");
    v.Field("split_time", split_time, "flow matching, splitting: flow time the halves are re-noised to",
            config::InRange(0.01, 0.99));
    v.Field("guide_at", guide_at,
            "flow matching: guide x_t (state), the velocity by the gradient at x̂1 (velocity), or x̂1 (prediction)");
    v.Field("guide_from", guide_from, "flow matching: no guidance before this flow time", config::InRange(0.0, 1.0));
    v.Field("prediction_iterations", prediction_iterations,
            "flow matching, guide_at prediction: gradient steps on x̂1 per Euler step", config::Positive());
    v.Field("final_iterations", final_iterations,
            "flow matching: gradient steps of the guidance scale on the finished plan (each stage of splitting)",
            config::NonNegative());
    v.Field("final_denoise_time", final_denoise_time,
            "flow matching: after each final gradient step, one Euler step from this flow time to 1 (0: none)",
            config::InRange(0.0, 0.999));
    v.Field("final_spread", final_spread,
            "flow matching: the final steps spread each state's push over its neighbours, decaying over this many "
            "states, the end states fixed (the covariant step of a speed metric; 0: each state moves alone)",
            config::InRange(0.0, 1e6));
    v.Field("final_joint_speed_weight", final_joint_speed_weight,
            "flow matching: added to guidance.joint_speed_weight in the final steps only", config::NonNegative());
    v.Field("midpoint_iterations", midpoint_iterations,
            "flow matching, splitting: gradient steps on the first stage's plan before re-noising",
            config::NonNegative());
    v.Field("network_kernels", network_kernels,
            "the network's code: native kernels (needs libflowplan_kernels where the planner runs) or portable");
    v.Field("ddpm", ddpm, "DDPM planner (MPD): guidance schedule");
    v.Field("latent", latent, "latent (VAE) planner: activation maximization");
  }
};

}  // namespace flowplan::planning
