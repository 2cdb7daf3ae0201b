#pragma once

#include <torch/torch.h>

#include <functional>

namespace flowplan::planning {

/// A velocity field: x (B, T, D), t (B,) -> dx/dt (B, T, D).
using VelocityField = std::function<torch::Tensor(const torch::Tensor& x, const torch::Tensor& t)>;

/// A constraint that holds at every time (inpainting): x (B, T, D) -> (B, T, D).
using StateProjection = std::function<torch::Tensor(const torch::Tensor& x)>;

/// A correction after the step that reached flow time t (guidance): x (B, T, D) -> (B, T, D).
using StepCorrection = std::function<torch::Tensor(const torch::Tensor& x, double t)>;

/// A uniform time grid of `steps` Euler steps from t_begin to t_end.
struct TimeGrid {
  double t_begin = 0.0;
  double t_end = 1.0;
  int steps = 10;
  double step_size() const { return (t_end - t_begin) / steps; }
  double time(int i) const { return t_begin + i * step_size(); }
};

/// Integrates dx/dt = velocity(x, t) with explicit Euler on `grid`:
///   x <- project(x);
///   for i: x <- x + h * velocity(x, t_i);  x <- correct(x, t_{i+1});  x <- project(x).
/// x: (B, T, D). The sampler knows nothing of networks, conditioning or costs;
/// `project` and `correct` may be null.
/// @throws flowplan::Error if grid.steps < 1.
torch::Tensor IntegrateEuler(torch::Tensor x, const VelocityField& velocity, const TimeGrid& grid,
                             const StateProjection& project = nullptr, const StepCorrection& correct = nullptr);

}  // namespace flowplan::planning
