#include "datasets/particle_task.h"

#include "core/random.h"

namespace flowplan::datasets {
namespace {

class ParticleWorker : public EpisodeWorker {
 public:
  ParticleWorker(const sim::ParticleConfig& config, std::vector<Family> families)
      : config_(config), families_(std::move(families)) {}

  EpisodeRecord Run(int64_t index, uint64_t seed) override {
    Rng rng(seed);
    return Rollout(config_, static_cast<int>(index % static_cast<int64_t>(families_.size())), rng);
  }

  EpisodeRecord RunNominal(int family) override {
    sim::ParticleConfig quiet = config_;
    quiet.accel_noise = quiet.position_noise = quiet.start_jitter = 0.0;
    Rng unused(0);
    return Rollout(quiet, family, unused);
  }

 private:
  EpisodeRecord Rollout(const sim::ParticleConfig& config, int family, Rng& rng) const {
    const Family& f = families_[family];
    EpisodeRecord record;
    record.states = sim::RolloutParticle(config, {f.start[0], f.start[1]}, {f.goal[0], f.goal[1]}, rng);
    record.commanded_start = f.start;
    record.commanded_goal = f.goal;
    record.family = family;
    return record;
  }

  const sim::ParticleConfig config_;
  const std::vector<Family> families_;
};

}  // namespace

EpisodeLayout ParticleCrossTask::Layout() const {
  EpisodeLayout layout;
  layout.info.env = "particle";
  layout.info.dt = config_.dt;
  layout.info.horizon = config_.horizon;
  layout.info.state_labels = {"x", "y", "vx", "vy"};
  layout.point_dim = 2;
  layout.info.robot = kinematics::PointRobot("particle_disc", 2, config_.radius, 0.0, 1.0);
  return layout;
}

std::vector<Family> ParticleCrossTask::Families() const {
  return {{"(0,0)->(1,1)", {0.0, 0.0}, {1.0, 1.0}}, {"(0,1)->(1,0)", {0.0, 1.0}, {1.0, 0.0}}};
}

std::unique_ptr<EpisodeWorker> ParticleCrossTask::MakeWorker() const {
  return std::make_unique<ParticleWorker>(config_, Families());
}

}  // namespace flowplan::datasets
