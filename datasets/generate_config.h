#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/config.h"
#include "datasets/episode_task.h"
#include "datasets/franka_task.h"
#include "datasets/robot_joint_task.h"
#include "sim/particle.h"

namespace flowplan::datasets {

/// Which dataset `flowplan generate` builds.
enum class DatasetKind { kParticleCross, kFrankaCross, kFrankaReach, kFrankaJoint, kRobotJoint };

inline const config::EnumNames<DatasetKind>& EnumEntries(DatasetKind) {
  static const config::EnumNames<DatasetKind> names = {{DatasetKind::kParticleCross, "particle_cross"},
                                                       {DatasetKind::kFrankaCross, "franka_cross"},
                                                       {DatasetKind::kFrankaReach, "franka_reach"},
                                                       {DatasetKind::kFrankaJoint, "franka_joint"},
                                                       {DatasetKind::kRobotJoint, "robot_joint"}};
  return names;
}

/// The `generate` section of an experiment config.
struct GenerateConfig {
  DatasetKind dataset = DatasetKind::kParticleCross;
  int64_t episodes = 10000;
  std::string out = "data/particle_cross.h5";
  sim::ParticleConfig particle;
  FrankaTaskConfig franka;
  RobotJointTaskConfig robot_joint;

  template <class V>
  void Visit(V& v) {
    v.Field("dataset", dataset, "which dataset to generate");
    v.Field("episodes", episodes, "number of episodes", config::Positive());
    v.Field("out", out, "output HDF5 file");
    v.Field("particle", particle, "2-D particle dynamics");
    v.Field("franka", franka, "Franka Panda simulation, controller and augmentation");
    v.Field("robot_joint", robot_joint, "robot_joint: simulation and motions of the robot folder named by robot:");
  }
};

/// The task that rolls out episodes of `config.dataset`; robot_joint rolls out
/// the robot of `robot_folder` (the config's `robot:`), which the built-in data
/// sets refuse.
/// @throws flowplan::Error if robot_joint has no folder or another data set has one.
std::unique_ptr<EpisodeTask> MakeTask(const GenerateConfig& config, const std::string& robot_folder = "");

}  // namespace flowplan::datasets
