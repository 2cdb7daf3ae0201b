#include "datasets/generate_config.h"

#include "core/error.h"
#include "datasets/particle_task.h"

namespace flowplan::datasets {

std::unique_ptr<EpisodeTask> MakeTask(const GenerateConfig& config) {
  switch (config.dataset) {
    case DatasetKind::kParticleCross:
      return std::make_unique<ParticleCrossTask>(config.particle);
  }
  FLOWPLAN_DEMAND(false);
  return nullptr;
}

}  // namespace flowplan::datasets
