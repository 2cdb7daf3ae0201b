#pragma once

#include <torch/torch.h>

#include <functional>

namespace flowplan::planning {

/// A velocity field: x (B, T, D), t (B,) -> dx/dt (B, T, D).
using VelocityField = std::function<torch::Tensor(const torch::Tensor& x, const torch::Tensor& t)>;

/// A correction applied to the state at time t: once before the first step and
/// after every step (inpainting, guidance). x: (B, T, D) -> (B, T, D).
using StateHook = std::function<torch::Tensor(const torch::Tensor& x, double t)>;

/// A uniform time grid of `steps` Euler steps from t_begin to t_end.
struct TimeGrid {
  double t_begin = 0.0;
  double t_end = 1.0;
  int steps = 10;
  double step_size() const { return (t_end - t_begin) / steps; }
  double time(int i) const { return t_begin + i * step_size(); }
};

/// Integrates dx/dt = velocity(x, t) with explicit Euler on `grid`:
///   x <- hook(x, t0);  for i: x <- hook(x + h * velocity(x, t_i), t_{i+1}).
/// x: (B, T, D). The sampler knows nothing of networks, conditioning or costs.
/// @throws flowplan::Error if grid.steps < 1.
torch::Tensor IntegrateEuler(torch::Tensor x, const VelocityField& velocity, const TimeGrid& grid,
                             const StateHook& hook = nullptr);

}  // namespace flowplan::planning
