#pragma once

// The kinds of robot flowplan executes and draws in MuJoCo, told apart by the
// planned robot's description and folder, so that no command asks which robot
// it has:
//  - the built-in Franka (sim/franka_model.h): its MJCF among the scene's
//    obstacles, plans tracked by joint PD at libfranka's gains (execute.*)
//    among its collision capsules, drawn by those capsules;
//  - a robot folder (robotfiles/, robot: DIR or --robot DIR): its model among
//    the obstacles, tracked by the computed-torque law (generate.robot_joint's
//    drives) among its collision geometry, drawn by its collision spheres.
// A new kind is its own functions and one entry of RobotKinds().

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "experiment/experiment_config.h"
#include "geometry/scene.h"
#include "kinematics/robot_description.h"
#include "render/arm_renderer.h"
#include "sim/arm_execution.h"

namespace flowplan::experiment {

/// A robot among one scene's obstacles in MuJoCo: owns the model its executors run on.
class SimulatedScene {
 public:
  virtual ~SimulatedScene() = default;
  /// An executor of plans (T, 2J) among the scene's obstacles, with its own mjData: one per thread. The scene
  /// must outlive it.
  virtual std::unique_ptr<sim::ArmExecutor> Executor() const = 0;
};

/// A robot prepared for one command, its files read once: a scene per problem to execute plans in, and renderers.
class RobotSimulator {
 public:
  virtual ~RobotSimulator() = default;
  /// The robot among `scene`'s obstacles (3-D), the joints of `held` (a gripper's fingers) at those values.
  virtual std::unique_ptr<SimulatedScene> Scene(const geometry::Scene& scene,
                                                const std::map<std::string, double>& held) const = 0;
  /// Draws the robot among `scene`'s obstacles.
  virtual std::unique_ptr<render::ArmRenderer> Renderer(const geometry::Scene& scene,
                                                        const render::RenderConfig& camera) const = 0;
  /// How the renderer draws the robot, for captions: "its MJCF's capsules", "its collision spheres".
  virtual std::string drawn_by() const = 0;
};

/// One kind of robot.
struct RobotKind {
  std::string name;
  /// The robot a planner file, checkpoint or plan file carries, as this kind plans it (the built-in Franka: its
  /// collision body with the file's limits), or std::nullopt if the robot is not of this kind.
  std::function<std::optional<kinematics::RobotDescription>(const kinematics::RobotDescription& carried)> resolve;
  /// The simulator of the planned robot `planned`, given the robot folder `folder` (may be empty) and the drives
  /// and execute.* of `config`; nullptr if this kind does not simulate it.
  /// @throws flowplan::Error for a robot of this kind that cannot be simulated (a folder whose robot moves
  ///   otherwise than `planned`, a file that cannot be read).
  std::function<std::unique_ptr<RobotSimulator>(const kinematics::RobotDescription& planned,
                                                const std::string& folder, const ExperimentConfig& config)>
      simulate;
};

/// Every kind, in the order they are asked.
const std::vector<RobotKind>& RobotKinds();

/// The robot a planner file, checkpoint or plan file carries, as the first kind that takes it plans it; the
/// carried robot itself if none does.
kinematics::RobotDescription ResolveRobot(const kinematics::RobotDescription& carried);

/// The simulator of the first kind that simulates `planned` (see RobotKind::simulate), or nullptr if none does.
std::unique_ptr<RobotSimulator> FindSimulator(const kinematics::RobotDescription& planned, const std::string& folder,
                                              const ExperimentConfig& config);

/// FindSimulator's simulator.
/// @throws flowplan::Error, prefixed by `what` (e.g. "--execute"), if no kind simulates `planned`.
std::unique_ptr<RobotSimulator> RequireSimulator(const kinematics::RobotDescription& planned,
                                                 const std::string& folder, const ExperimentConfig& config,
                                                 const std::string& what);

}  // namespace flowplan::experiment
