// `flowplan plan --execute`: the plans tracked in MuJoCo among the scene's
// obstacles, as real collision geoms.

#include "core/error.h"
#include "core/parallel.h"
#include "experiment/plan.h"
#include "collision/body_model.h"
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

}  // namespace

bool IsBuiltInFranka(const kinematics::RobotDescription& robot) {
  static const sim::FrankaModel model = sim::LoadFrankaModel();
  return Kinematics(model.description()) == Kinematics(robot);
}

kinematics::RobotDescription ResolveRobot(const kinematics::RobotDescription& carried) {
  if (!IsBuiltInFranka(carried)) return carried;
  // A file made before the Franka's description said how its fingers move and which of its links may touch: the
  // built-in description's collision body, with the file's own limits.
  kinematics::RobotDescription robot = sim::LoadFrankaModel().description();
  robot.joint_lower = carried.joint_lower;
  robot.joint_upper = carried.joint_upper;
  robot.velocity_limit = carried.velocity_limit;
  if (!carried.home.empty()) robot.home = carried.home;
  return robot;
}

validity::PlanChecker MakePlanChecker(const PlanSubject& subject) {
  return validity::PlanChecker(subject.robot, subject.trajectory.dt, subject.config.check);
}

robotfiles::ExecutionModel FolderExecution(const std::string& folder, const kinematics::RobotDescription& planned_robot,
                                           const geometry::Scene& scene, const std::map<std::string, double>& held,
                                           const ExperimentConfig& config) {
  const std::string& name = planned_robot.name;
  if (folder.empty()) {
    throw Error("--execute: the planner's robot \"" + name + "\" is not the built-in Franka and its config names no "
                "robot folder (robot: DIR) to simulate it from");
  }
  robotfiles::RobotFile file = robotfiles::LoadRobotFile(folder);
  const std::string where = folder + "/robot.yaml";
  // Both with the problem's held joints (a gripper's fingers) at the problem's values.
  kinematics::RobotDescription planned = planned_robot;
  if (!held.empty()) {
    file.robot = collision::WithHeld(file.robot, held);
    planned = collision::WithHeld(planned, held);
  }
  if (Kinematics(file.Description(where), true) != Kinematics(planned, true)) {
    throw Error("--execute: " + where + ": its robot \"" + file.robot.name + "\" does not move as the planner's \"" +
                name + "\" does (another kinematic tree, joint type, held value or TCP)");
  }
  // The drives `generate` simulates the robot with.
  return robotfiles::LoadExecutionModel(file, folder, scene, config.generate.robot_joint.drives, config.execute, where);
}

std::vector<sim::ExecutionResult> ExecutePlans(const torch::Tensor& plans, const PlanSubject& subject,
                                               const PlanInputs& inputs, int threads) {
  const sim::ExecutionConfig& config = subject.config.execute;
  const int K = static_cast<int>(inputs.scene.size());
  // The built-in Franka tracks plans with its joint PD gains among its MJCF's capsules; a robot folder's arm with
  // the computed-torque law among its collision geometry.
  std::unique_ptr<sim::FrankaModel> franka;
  robotfiles::ExecutionModel folder;
  std::vector<std::unique_ptr<sim::ArmExecutor>> workers;
  if (IsBuiltInFranka(subject.robot->description())) {
    franka = std::make_unique<sim::FrankaModel>(sim::MakeFrankaScene(inputs.scene, 1.0 / config.control_hz));
    for (int w = 0; w < threads; ++w) workers.push_back(std::make_unique<sim::FrankaExecutor>(*franka, K, config));
  } else {
    folder = FolderExecution(subject.config.robot, subject.robot->description(), inputs.scene, inputs.world.held,
                             subject.config);
    for (int w = 0; w < threads; ++w) {
      workers.push_back(std::make_unique<sim::ArmExecutor>(*folder.model, folder.drives, K, config));
    }
  }
  const int64_t N = plans.size(0), T = plans.size(1), J = subject.robot->num_joints();
  if (plans.size(2) < 2 * J) {
    throw Error("--execute: the plans hold " + std::to_string(plans.size(2)) + " values a state; execution tracks " +
                "positions and velocities (" + std::to_string(2 * J) + ")");
  }
  std::vector<sim::ExecutionResult> executed(static_cast<size_t>(N));
  const Eigen::Vector3d target(inputs.goal_tcp[0].item<double>(), inputs.goal_tcp[1].item<double>(),
                               inputs.goal_tcp[2].item<double>());
  const torch::Tensor arm_states = plans.to(torch::kFloat64).slice(2, 0, 2 * J).contiguous();
  ParallelFor(static_cast<int>(N), threads, [&](int worker, int i) {
    const double* p = arm_states[i].data_ptr<double>();
    executed[i] = workers[worker]->Execute(std::vector<double>(p, p + T * 2 * J), T, subject.trajectory.dt, target);
  });
  return executed;
}

}  // namespace flowplan::experiment
