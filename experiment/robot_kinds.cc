#include "experiment/robot_kinds.h"

#include "collision/body_model.h"
#include "core/error.h"
#include "robotfiles/robot_folder.h"
#include "robotfiles/robot_model.h"
#include "sim/franka_execution.h"
#include "sim/franka_model.h"

namespace flowplan::experiment {
namespace {

/// The kinematic tree and TCP of a description, as text: what must match for a robot to move as another does.
/// `complete` adds what only simulating it needs to agree on too: each joint's type, every link's axis and the
/// values held joints are held at (a file made before the Franka's description carried its fingers' values is still
/// the built-in Franka without them).
std::string Kinematics(const kinematics::RobotDescription& d, bool complete = false) {
  std::string text = d.name + " " + std::to_string(d.num_joints) + " " + std::to_string(d.tcp_link);
  auto numbers = [&](const auto& values) {
    for (double v : values) text += " " + config::internal::FormatDouble(v);
  };
  for (const kinematics::RobotLink& link : d.links) {
    text += " | " + link.name + " " + std::to_string(link.parent) + " " + std::to_string(link.joint);
    numbers(link.pos);
    numbers(link.quat);
    if (link.joint >= 0 || complete) numbers(link.axis);  // a link that no planned joint moves has no axis that matters
    if (complete) {
      text += link.type == kinematics::JointType::kPrismatic ? " slide " : " hinge ";
      numbers(std::vector<double>{link.offset});
    }
  }
  numbers(d.tcp_pos);
  numbers(d.tcp_quat);
  return text;
}

// ---- The built-in Franka ----------------------------------------------------------------------------------------

const kinematics::RobotDescription& FrankaDescription() {
  static const kinematics::RobotDescription description = sim::LoadFrankaModel().description();
  return description;
}

/// Whether `robot` has the built-in Franka's kinematic tree and TCP (limits and collision spheres may differ).
bool IsBuiltInFranka(const kinematics::RobotDescription& robot) {
  static const std::string franka = Kinematics(FrankaDescription());
  return Kinematics(robot) == franka;
}

std::optional<kinematics::RobotDescription> ResolveFranka(const kinematics::RobotDescription& carried) {
  if (!IsBuiltInFranka(carried)) return std::nullopt;
  // A file made before the Franka's description said how its fingers move and which of its links may touch: the
  // built-in description's collision body, with the file's own limits.
  kinematics::RobotDescription robot = FrankaDescription();
  robot.joint_lower = carried.joint_lower;
  robot.joint_upper = carried.joint_upper;
  robot.velocity_limit = carried.velocity_limit;
  if (!carried.home.empty()) robot.home = carried.home;
  return robot;
}

class FrankaScene : public SimulatedScene {
 public:
  FrankaScene(const geometry::Scene& scene, const sim::ExecutionConfig& config)
      : model_(sim::MakeFrankaScene(scene, 1.0 / config.control_hz)),
        obstacles_(static_cast<int>(scene.size())),
        config_(config) {}
  std::unique_ptr<sim::ArmExecutor> Executor() const override {
    return std::make_unique<sim::FrankaExecutor>(model_, obstacles_, config_);
  }

 private:
  sim::FrankaModel model_;
  int obstacles_;
  sim::ExecutionConfig config_;
};

/// The Franka's MJCF, its fingers as the MJCF holds them, tracked by joint PD (execute.*).
class FrankaSimulator : public RobotSimulator {
 public:
  explicit FrankaSimulator(const sim::ExecutionConfig& config) : config_(config) {}
  std::unique_ptr<SimulatedScene> Scene(const geometry::Scene& scene,
                                        const std::map<std::string, double>& /*held*/) const override {
    return std::make_unique<FrankaScene>(scene, config_);
  }
  std::unique_ptr<render::ArmRenderer> Renderer(const geometry::Scene& scene,
                                                const render::RenderConfig& camera) const override {
    return std::make_unique<render::ArmRenderer>(scene, camera);
  }
  std::string drawn_by() const override { return "its MJCF's capsules"; }

 private:
  sim::ExecutionConfig config_;
};

std::unique_ptr<RobotSimulator> SimulateFranka(const kinematics::RobotDescription& planned,
                                               const std::string& /*folder*/, const ExperimentConfig& config) {
  if (!IsBuiltInFranka(planned)) return nullptr;
  return std::make_unique<FrankaSimulator>(config.execute);
}

// ---- A robot folder ---------------------------------------------------------------------------------------------

class FolderScene : public SimulatedScene {
 public:
  FolderScene(robotfiles::ExecutionModel model, int obstacles, const sim::ExecutionConfig& config)
      : model_(std::move(model)), obstacles_(obstacles), config_(config) {}
  std::unique_ptr<sim::ArmExecutor> Executor() const override {
    return std::make_unique<sim::ArmExecutor>(*model_.model, model_.drives, obstacles_, config_);
  }

 private:
  robotfiles::ExecutionModel model_;
  int obstacles_;
  sim::ExecutionConfig config_;
};

/// The folder's model (robot.yaml read once), tracked by the computed-torque law with the drives `generate`
/// simulates the robot with; drawn by the planned robot's collision spheres.
class FolderSimulator : public RobotSimulator {
 public:
  FolderSimulator(const std::string& folder, const kinematics::RobotDescription& planned,
                  const ExperimentConfig& config)
      : folder_(folder),
        where_(folder + "/robot.yaml"),
        file_(robotfiles::LoadRobotFile(folder)),
        planned_(planned),
        drives_(config.generate.robot_joint.drives),
        execute_(config.execute) {}

  std::unique_ptr<SimulatedScene> Scene(const geometry::Scene& scene,
                                        const std::map<std::string, double>& held) const override {
    // Both with the problem's held joints (a gripper's fingers) at the problem's values.
    robotfiles::RobotFile file = file_;
    kinematics::RobotDescription planned = planned_;
    if (!held.empty()) {
      file.robot = collision::WithHeld(file.robot, held);
      planned = collision::WithHeld(planned, held);
    }
    if (Kinematics(file.Description(where_), true) != Kinematics(planned, true)) {
      throw Error(where_ + ": its robot \"" + file.robot.name + "\" does not move as the planned \"" + planned.name +
                  "\" does (another kinematic tree, joint type, held value or TCP)");
    }
    return std::make_unique<FolderScene>(
        robotfiles::LoadExecutionModel(file, folder_, scene, drives_, execute_, where_),
        static_cast<int>(scene.size()), execute_);
  }
  std::unique_ptr<render::ArmRenderer> Renderer(const geometry::Scene& scene,
                                                const render::RenderConfig& camera) const override {
    return std::make_unique<render::ArmRenderer>(planned_, scene, camera);
  }
  std::string drawn_by() const override { return "its collision spheres"; }

 private:
  std::string folder_, where_;
  robotfiles::RobotFile file_;
  kinematics::RobotDescription planned_;
  robotfiles::DriveSettings drives_;
  sim::ExecutionConfig execute_;
};

std::unique_ptr<RobotSimulator> SimulateFolder(const kinematics::RobotDescription& planned, const std::string& folder,
                                               const ExperimentConfig& config) {
  if (folder.empty()) return nullptr;
  return std::make_unique<FolderSimulator>(folder, planned, config);
}

}  // namespace

const std::vector<RobotKind>& RobotKinds() {
  static const std::vector<RobotKind> kinds = {
      {"franka", ResolveFranka, SimulateFranka},
      {"folder", [](const kinematics::RobotDescription&) { return std::optional<kinematics::RobotDescription>(); },
       SimulateFolder},
  };
  return kinds;
}

kinematics::RobotDescription ResolveRobot(const kinematics::RobotDescription& carried) {
  for (const RobotKind& kind : RobotKinds()) {
    if (std::optional<kinematics::RobotDescription> resolved = kind.resolve(carried)) return *resolved;
  }
  return carried;
}

std::unique_ptr<RobotSimulator> FindSimulator(const kinematics::RobotDescription& planned, const std::string& folder,
                                              const ExperimentConfig& config) {
  for (const RobotKind& kind : RobotKinds()) {
    if (std::unique_ptr<RobotSimulator> simulator = kind.simulate(planned, folder, config)) return simulator;
  }
  return nullptr;
}

std::unique_ptr<RobotSimulator> RequireSimulator(const kinematics::RobotDescription& planned,
                                                 const std::string& folder, const ExperimentConfig& config,
                                                 const std::string& what) {
  std::unique_ptr<RobotSimulator> simulator = FindSimulator(planned, folder, config);
  if (!simulator) {
    throw Error(what + ": the robot \"" + planned.name + "\" is not the built-in Franka, and no robot folder " +
                "(robot: DIR in the config, or --robot DIR) is given to simulate it from");
  }
  return simulator;
}

}  // namespace flowplan::experiment
