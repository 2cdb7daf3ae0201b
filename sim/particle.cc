#include "sim/particle.h"

#include <algorithm>

namespace flowplan::sim {

std::vector<double> RolloutParticle(const ParticleConfig& config, const std::array<double, 2>& start,
                                    const std::array<double, 2>& goal, Rng& rng) {
  std::vector<double> states(static_cast<size_t>(config.horizon) * kParticleStateDim);
  double p[2], v[2] = {0.0, 0.0};
  for (int axis = 0; axis < 2; ++axis) {
    p[axis] = std::clamp(start[axis] + config.start_jitter * rng.Normal(), 0.0, 1.0);
  }
  for (int step = 0; step < config.horizon; ++step) {
    double* state = &states[static_cast<size_t>(step) * kParticleStateDim];
    state[0] = p[0];
    state[1] = p[1];
    state[2] = v[0];
    state[3] = v[1];
    for (int axis = 0; axis < 2; ++axis) {
      const double accel =
          config.kp * (goal[axis] - p[axis]) - config.kd * v[axis] + config.accel_noise * rng.Normal();
      v[axis] += accel * config.dt;
      p[axis] += v[axis] * config.dt + config.position_noise * rng.Normal();
      p[axis] = std::clamp(p[axis], 0.0, 1.0);
    }
  }
  return states;
}

}  // namespace flowplan::sim
