#include "planning/euler.h"

#include "core/error.h"

namespace flowplan::planning {

torch::Tensor IntegrateEuler(torch::Tensor x, const VelocityField& velocity, const TimeGrid& grid,
                             const StateProjection& project, const StepCorrection& correct) {
  if (grid.steps < 1) throw Error("Euler sampler: expected at least one step, got " + std::to_string(grid.steps));
  const double h = grid.step_size();
  if (project) x = project(x);
  for (int i = 0; i < grid.steps; ++i) {
    const torch::Tensor t = torch::full({x.size(0)}, grid.time(i), x.options());
    x = x + h * velocity(x, t);
    if (correct) x = correct(x, grid.time(i + 1));
    if (project) x = project(x);
  }
  return x;
}

}  // namespace flowplan::planning
