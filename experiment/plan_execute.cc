// `flowplan plan --execute`: the plans tracked in MuJoCo among the scene's
// obstacles, as real collision geoms.

#include "core/error.h"
#include "core/parallel.h"
#include "experiment/plan.h"

namespace flowplan::experiment {

validity::PlanChecker MakePlanChecker(const PlanSubject& subject) {
  return validity::PlanChecker(subject.robot, subject.trajectory.dt, subject.config.check);
}

std::unique_ptr<RobotSimulator> ExecutionSimulator(const PlanArgs& args, const PlanSubject& subject) {
  if (!args.execute) return nullptr;
  if (!subject.robot->is_arm() || subject.robot->workspace_dim() != 3) {
    throw Error("--execute: execution in MuJoCo needs an arm in 3-D (the Franka or a robot folder); this planner's "
                "robot is \"" + subject.robot->description().name + "\"");
  }
  return RequireSimulator(subject.robot->description(), subject.config.robot, subject.config, "--execute");
}

std::vector<sim::ExecutionResult> ExecutePlans(const torch::Tensor& plans, const PlanSubject& subject,
                                               const PlanInputs& inputs, const RobotSimulator& simulator, int threads) {
  const std::unique_ptr<SimulatedScene> scene = simulator.Scene(inputs.scene, inputs.world.held);
  std::vector<std::unique_ptr<sim::ArmExecutor>> workers;
  for (int w = 0; w < threads; ++w) workers.push_back(scene->Executor());
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
