// A planned move for execution tests: joint positions and consistent velocities along a cosine time profile.
#pragma once

#include <cmath>
#include <vector>

namespace flowplan::testing {

/// A plan (T, 2J) = [q, q̇] from q0 to q1 (J each) over T states dt s apart, with a smooth (cosine) time profile.
inline std::vector<double> SmoothMove(const std::vector<double>& q0, const std::vector<double>& q1, int T, double dt) {
  const size_t J = q0.size();
  std::vector<double> plan(static_cast<size_t>(T) * 2 * J);
  const double duration = (T - 1) * dt;
  for (int t = 0; t < T; ++t) {
    const double s = 0.5 - 0.5 * std::cos(M_PI * t / (T - 1));
    const double ds = 0.5 * M_PI / duration * std::sin(M_PI * t / (T - 1));
    for (size_t j = 0; j < J; ++j) {
      plan[t * 2 * J + j] = q0[j] + s * (q1[j] - q0[j]);
      plan[t * 2 * J + J + j] = ds * (q1[j] - q0[j]);
    }
  }
  return plan;
}

}  // namespace flowplan::testing
