#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/config.h"
#include "datasets/episode_task.h"
#include "datasets/franka_task.h"
#include "sim/particle.h"

namespace flowplan::datasets {

/// Which dataset `flowplan generate` builds.
enum class DatasetKind { kParticleCross, kFrankaCross, kFrankaReach, kFrankaJoint };

inline const config::EnumNames<DatasetKind>& EnumEntries(DatasetKind) {
  static const config::EnumNames<DatasetKind> names = {{DatasetKind::kParticleCross, "particle_cross"},
                                                       {DatasetKind::kFrankaCross, "franka_cross"},
                                                       {DatasetKind::kFrankaReach, "franka_reach"},
                                                       {DatasetKind::kFrankaJoint, "franka_joint"}};
  return names;
}

/// The `generate` section of an experiment config.
struct GenerateConfig {
  DatasetKind dataset = DatasetKind::kParticleCross;
  int64_t episodes = 10000;
  std::string out = "data/particle_cross.h5";
  sim::ParticleConfig particle;
  FrankaTaskConfig franka;

  template <class V>
  void Visit(V& v) {
    v.Field("dataset", dataset, "which dataset to generate");
    v.Field("episodes", episodes, "number of episodes", config::Positive());
    v.Field("out", out, "output HDF5 file");
    v.Field("particle", particle, "2-D particle dynamics");
    v.Field("franka", franka, "Franka Panda simulation, controller and augmentation");
  }
};

/// The task that rolls out episodes of `config.dataset`.
std::unique_ptr<EpisodeTask> MakeTask(const GenerateConfig& config);

}  // namespace flowplan::datasets
