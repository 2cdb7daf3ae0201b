#pragma once

#include "datasets/episode_task.h"
#include "sim/particle.h"

namespace flowplan::datasets {

/// The 2-D particle "X" dataset (SPEC section 3): episode i belongs to family
/// i mod 2, (0,0) -> (1,1) or (0,1) -> (1,0). State [x, y, vx, vy], W = 2.
class ParticleCrossTask : public EpisodeTask {
 public:
  explicit ParticleCrossTask(const sim::ParticleConfig& config) : config_(config) {}
  EpisodeLayout Layout() const override;
  std::vector<Family> Families() const override;
  std::unique_ptr<EpisodeWorker> MakeWorker() const override;

 private:
  sim::ParticleConfig config_;
};

}  // namespace flowplan::datasets
