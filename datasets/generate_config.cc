#include "datasets/generate_config.h"

#include "core/error.h"
#include "datasets/franka_task.h"
#include "datasets/particle_task.h"

namespace flowplan::datasets {

std::unique_ptr<EpisodeTask> MakeTask(const GenerateConfig& config) {
  switch (config.dataset) {
    case DatasetKind::kParticleCross:
      return std::make_unique<ParticleCrossTask>(config.particle);
    case DatasetKind::kFrankaCross:
      return std::make_unique<FrankaTask>(FrankaGoals::kCross, config.franka, "generate.franka");
    case DatasetKind::kFrankaReach:
      return std::make_unique<FrankaTask>(FrankaGoals::kReach, config.franka, "generate.franka");
    case DatasetKind::kFrankaJoint:
      return std::make_unique<FrankaTask>(FrankaGoals::kJoint, config.franka, "generate.franka");
  }
  FLOWPLAN_DEMAND(false);
  return nullptr;
}

}  // namespace flowplan::datasets
