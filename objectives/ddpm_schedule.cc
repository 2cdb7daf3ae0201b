#include "objectives/ddpm_schedule.h"

#include <cmath>

#include "core/error.h"

namespace flowplan::objectives {

DdpmSchedule::DdpmSchedule(const DdpmConfig& config) : steps(config.steps) {
  if (config.beta_end < config.beta_start) {
    throw Error("objective.ddpm.beta_end: expected at least objective.ddpm.beta_start");
  }
  if (config.schedule == BetaSchedule::kLinear) {
    betas = torch::linspace(config.beta_start, config.beta_end, config.steps, torch::kFloat64).clamp_max(config.beta_max);
  } else {
    const torch::Tensor x = torch::linspace(0.0, config.steps, config.steps, torch::kFloat64);
    const double a = std::log(config.beta_end / config.beta_start) / config.steps;
    betas = (config.beta_start * torch::exp(a * x)).clamp_max(config.beta_max);
  }
  alphas = 1.0 - betas;
  alpha_bars = torch::cumprod(alphas, 0);
}

}  // namespace flowplan::objectives
