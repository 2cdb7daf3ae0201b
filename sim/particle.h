#pragma once

#include <array>
#include <vector>

#include "core/config.h"
#include "core/random.h"

namespace flowplan::sim {

/// A point mass in the unit square under PD control towards a goal, with
/// Gaussian noise on the acceleration and on the position (SPEC section 3).
struct ParticleConfig {
  double dt = 0.05;              // s, one step between recorded states
  int horizon = 64;              // recorded states per episode, the first one included
  double kp = 1.0;               // 1/s², PD stiffness
  double kd = 0.5;               // 1/s, PD damping
  double accel_noise = 0.02;     // m/s², std of the acceleration noise per step and axis
  double position_noise = 0.01;  // m, std of the position noise per step and axis
  double start_jitter = 0.05;    // m, std of the start position around the commanded start
  double radius = 0.03;          // m, the particle's disc, for collision costs and clearances

  template <class V>
  void Visit(V& v) {
    v.Field("dt", dt, "seconds between recorded states", config::Positive());
    v.Field("horizon", horizon, "recorded states per episode", config::AtLeast(2));
    v.Field("kp", kp, "PD stiffness (1/s^2)", config::NonNegative());
    v.Field("kd", kd, "PD damping (1/s)", config::NonNegative());
    v.Field("accel_noise", accel_noise, "std of the acceleration noise (0: none)",
            config::NonNegative());
    v.Field("position_noise", position_noise, "std of the position noise (0: none)",
            config::NonNegative());
    v.Field("start_jitter", start_jitter, "std of the start position around the commanded start",
            config::NonNegative());
    v.Field("radius", radius, "radius of the particle's disc, for planning around obstacles",
            config::NonNegative());
  }
};

/// State layout of the particle: [x, y, vx, vy].
inline constexpr int kParticleStateDim = 4;

/// Rolls out one episode from `start` (jittered by start_jitter) to `goal`.
/// Returns the recorded states, (T, 4) row-major with T = config.horizon; state 0
/// is the (jittered) start at rest. Positions stay in [0, 1].
std::vector<double> RolloutParticle(const ParticleConfig& config, const std::array<double, 2>& start,
                                    const std::array<double, 2>& goal, Rng& rng);

}  // namespace flowplan::sim
