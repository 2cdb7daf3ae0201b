#include "datasets/generate_config.h"

#include "core/error.h"
#include "datasets/franka_task.h"
#include "datasets/particle_task.h"
#include "datasets/robot_joint_task.h"

namespace flowplan::datasets {

std::unique_ptr<EpisodeTask> MakeTask(const GenerateConfig& config, const std::string& robot_folder) {
  if (config.dataset == DatasetKind::kRobotJoint) {
    if (robot_folder.empty()) {
      throw Error("generate.dataset: robot_joint needs a robot folder: set robot: DIR (`flowplan robot import` writes one)");
    }
    return std::make_unique<RobotJointTask>(robot_folder, config.robot_joint, "generate.robot_joint");
  }
  if (!robot_folder.empty()) {
    throw Error("robot: " + robot_folder + ": generate.dataset " + config::EnumName(config.dataset) +
                " is the built-in robot's; a robot folder's data set is generate.dataset: robot_joint");
  }
  switch (config.dataset) {
    case DatasetKind::kParticleCross:
      return std::make_unique<ParticleCrossTask>(config.particle);
    case DatasetKind::kFrankaCross:
      return std::make_unique<FrankaTask>(FrankaGoals::kCross, config.franka, "generate.franka");
    case DatasetKind::kFrankaReach:
      return std::make_unique<FrankaTask>(FrankaGoals::kReach, config.franka, "generate.franka");
    case DatasetKind::kFrankaJoint:
      return std::make_unique<FrankaTask>(FrankaGoals::kJoint, config.franka, "generate.franka");
    case DatasetKind::kRobotJoint:
      break;
  }
  FLOWPLAN_DEMAND(false);
  return nullptr;
}

}  // namespace flowplan::datasets
