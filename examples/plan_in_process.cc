// Plans motions of an exported Franka planner in-process, around a sphere,
// and checks every plan with the plan checker that every flowplan success
// passes (docs/planning.md, "Valid or nothing").
//
//   build/examples/plan_in_process [PLANNER.pt]   (default: the shipped reach planner)
//
// It links against flowplan_experiment, for LoadExportedPlanner (the file's
// weights with flowplan's native kernels), ResolveRobot (the robot a file
// carries, with the built-in Franka's collision body) and the file's config.
#include <torch/script.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/error.h"
#include "experiment/experiment_config.h"
#include "experiment/plan.h"
#include "experiment/trained_planner.h"
#include "geometry/scene.h"
#include "geometry/scene_rows.h"
#include "kinematics/robot.h"
#include "planning/learned_planner.h"
#include "validity/plan_check.h"

int main(int argc, char** argv) {
  using namespace flowplan;
  if (argc > 1 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::printf("usage: plan_in_process [PLANNER.pt]\nplans 16 motions of an exported Franka planner (default: the "
                "shipped reach planner) around a sphere and checks each with the plan checker\n");
    return 0;
  }
  try {
    const std::string file = argc > 1 ? argv[1] : FLOWPLAN_SOURCE_DIR "/pretrained/franka_reach_planner.pt";
    at::set_num_threads(2);
    torch::jit::setGraphExecutorOptimize(false);  // no profiling runs: the first plan is as fast as the next
    // The file's planner with flowplan's native kernels (planning::LearnedPlanner::Load(file): its own code).
    std::unique_ptr<planning::LearnedPlanner> planner = experiment::LoadExportedPlanner(file);
    const kinematics::TrajectoryInfo& info = planner->info();
    // The robot the file carries, with the Franka's collision body for checks.
    const auto robot = kinematics::MakeRobot(experiment::ResolveRobot(info.robot), file + ": robot");
    const int64_t B = 16, D = planner->state_dim(), J = robot->num_joints();

    // Start and goal: TCP points 0.6 m apart, reached by the robot's IK with the gripper pointing down; at rest.
    const kinematics::IkSolution ik = robot->InverseTcp(torch::tensor({0.5, -0.3, 0.2, 0.5, 0.3, 0.2},
                                                                      torch::kFloat64).view({2, 3}));
    if (!ik.converged.all().item<bool>()) throw Error("the start or goal TCP point is out of the robot's reach");
    torch::Tensor ends = torch::zeros({2, D});  // (2, D): positions, then velocities
    ends.slice(1, 0, J).copy_(ik.q);

    geometry::Scene scene;
    scene.spheres.push_back({{0.5, 0.0, 0.2}, 0.1});  // centre (m), radius (m)

    planning::PlanRequest request;
    request.start = ends[0].expand({B, D}).contiguous();  // (B, D)
    request.goal = ends[1].expand({B, D}).contiguous();
    request.scene = geometry::Rows(scene, 3, "the example's scene");
    request.seed = 1;  // same seed, same plans
    const planning::PlanResult result = planner->Plan(request);  // plans (B, T, D)

    // What a valid plan is comes with the file (its config's `check` section).
    const validity::CheckConfig check =
        experiment::LoadExperimentText(planner->config_yaml(), file + " (its config)", "", {}).check;
    const validity::PlanChecker checker(robot, info.dt, check);
    const std::vector<validity::PlanVerdict> verdicts =
        checker.Check(result.plans, ends[0], ends[1], request.scene, result.found);
    int valid = 0;
    for (const validity::PlanVerdict& verdict : verdicts) valid += verdict.valid();
    std::printf("%lld plans of %lld states in %.3f s: %d valid\n", static_cast<long long>(B),
                static_cast<long long>(result.plans.size(1)), result.call_seconds[0], valid);
    for (size_t i = 0; i < verdicts.size(); ++i) {
      if (!verdicts[i].valid()) std::printf("  plan %zu: %s\n", i, verdicts[i].reason.c_str());
    }
    return valid > 0 ? 0 : 1;
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
