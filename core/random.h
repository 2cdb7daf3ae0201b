#pragma once

#include <cmath>
#include <cstdint>

namespace flowplan {

/// Mixes a base seed and a stream index (episode, batch, sample) into an
/// independent 64-bit seed, so that what item `index` draws does not depend on
/// which thread runs it or in which order.
uint64_t StreamSeed(uint64_t base_seed, uint64_t index);

/// A small generator (xoshiro256++ seeded through SplitMix64) whose integer and
/// uniform outputs are the same with every compiler and standard library
/// (std::normal_distribution's are not); Normal() uses the C library's log,
/// sin and cos, so it matches wherever those do. Not thread-safe: each worker
/// owns its own.
class Rng {
 public:
  explicit Rng(uint64_t seed);

  uint64_t NextU64();
  /// Uniform in [0, 1).
  double Uniform();
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  /// Standard normal (Box–Muller, both values used).
  double Normal();
  double Normal(double mean, double stddev) { return mean + stddev * Normal(); }
  /// Uniform integer in [0, n).
  uint64_t Below(uint64_t n);

 private:
  uint64_t s_[4];
  double cached_normal_ = 0.0;
  bool has_cached_normal_ = false;
};

}  // namespace flowplan
