// `flowplan plan --execute`: the plans tracked in MuJoCo among the scene's
// obstacles, as real collision geoms.

#include "core/error.h"
#include "core/parallel.h"
#include "experiment/plan.h"
#include "sim/franka_model.h"

namespace flowplan::experiment {
namespace {

/// Execution needs the built-in Franka: the planner's robot must have its kinematics and geometry (limits may differ).
void CheckBuiltInFranka(const kinematics::Robot& robot) {
  if (!IsBuiltInFranka(robot.description())) {
    throw Error("--execute: execution in MuJoCo needs the built-in Franka; this planner's robot is \"" +
                robot.description().name + "\"" +
                (robot.description().name == "franka_panda" ? " with other kinematics" : ""));
  }
}

}  // namespace

namespace {

/// The kinematic tree and TCP of a description, as text: what must match for a robot to move as another does.
std::string Kinematics(const kinematics::RobotDescription& d) {
  std::string text = d.name + " " + std::to_string(d.num_joints) + " " + std::to_string(d.tcp_link);
  auto numbers = [&](const auto& values) {
    for (double v : values) text += " " + config::internal::FormatDouble(v);
  };
  for (const kinematics::RobotLink& link : d.links) {
    text += " | " + link.name + " " + std::to_string(link.parent) + " " + std::to_string(link.joint);
    numbers(link.pos);
    numbers(link.quat);
    if (link.joint >= 0) numbers(link.axis);  // a link that no planned joint moves has no axis that matters
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

std::vector<sim::ExecutionResult> ExecutePlans(const torch::Tensor& plans, const PlanSubject& subject,
                                               const PlanInputs& inputs, int threads) {
  CheckBuiltInFranka(*subject.robot);
  const sim::ExecutionConfig& config = subject.config.execute;
  const sim::FrankaModel world = sim::MakeFrankaScene(inputs.scene, 1.0 / config.control_hz);
  const int K = static_cast<int>(inputs.scene.size());
  std::vector<std::unique_ptr<sim::FrankaExecutor>> workers;
  for (int w = 0; w < threads; ++w) workers.push_back(std::make_unique<sim::FrankaExecutor>(world, K, config));
  const int64_t N = plans.size(0), T = plans.size(1), J = subject.robot->num_joints();
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
