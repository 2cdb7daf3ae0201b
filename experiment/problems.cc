// `flowplan problems`: random planning problems for the Franka or a robot
// folder, either with spheres blocking the straight path (problems.*) or from
// a procedural scene family (--family; problems/scene_families.h).
// docs/planning.md.

#include <spdlog/spdlog.h>

#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"
#include "experiment/commands.h"
#include "experiment/plan.h"
#include "kinematics/robot.h"
#include "problems/blocked_problems.h"
#include "problems/scene_families.h"
#include "robotfiles/robot_folder.h"
#include "sim/franka_model.h"

namespace flowplan::experiment {

void MakeProblems(const ProblemsArgs& args) {
  CheckOutputFree(args.out, args.force);
  const ExperimentConfig config = args.config.Load();
  const int threads = ConfigureThreads(config);
  const std::string folder = !args.robot.empty() ? args.robot : config.robot;
  if (!args.family.empty()) {
    const problems::FamilyArm arm = folder.empty() ? problems::FrankaFamilyArm() : problems::FolderFamilyArm(folder);
    if (arm.scale != 1.0 || arm.shift != 0.0) {
      const std::string shift = arm.shift == 0.0 ? "" : fmt::format(", and the scenes {:.3f} m farther out for its "
                                                                    "wider base", arm.shift);
      spdlog::info("{}: the families' lengths scaled by {:.3f}, the arm's reach over the Franka's{}", folder,
                   arm.scale, shift);
    }
    const problems::ProblemSet set = problems::MakeFamilyProblems(arm, args.family,
                                                                  static_cast<uint64_t>(config.seed),
                                                                  config.problems.count, config.problems.clearance,
                                                                  threads);
    EnsureParentFolder(args.out);
    WriteFileAtomically(args.out, problems::ProblemSetYaml(set));
    size_t obstacles = 0;
    for (const auto& problem : set.problems) obstacles += static_cast<size_t>(problem.scene.size());
    spdlog::info("wrote {}: {} {} problems, {} obstacles", args.out, set.problems.size(), args.family, obstacles);
    return;
  }
  const kinematics::Robot arm = folder.empty() ? kinematics::Robot(sim::LoadFrankaModel().description(), "the Franka")
                                               : kinematics::Robot(robotfiles::LoadRobot(folder), folder);
  problems::ProblemSet set;
  try {
    set = problems::MakeBlockedProblems(arm, config.problems, static_cast<uint64_t>(config.seed));
  } catch (const Error& e) {
    throw Error(std::string("problems.") + e.what());
  }
  EnsureParentFolder(args.out);
  WriteFileAtomically(args.out, problems::ProblemSetYaml(set));
  size_t spheres = 0, boxes = 0;
  for (const auto& problem : set.problems) {
    spheres += problem.scene.spheres.size();
    boxes += problem.scene.boxes.size();
  }
  spdlog::info("wrote {}: {} problems, {} spheres and {} boxes, each blocking the straight TCP path with its first "
               "sphere", args.out, set.problems.size(), spheres, boxes);
}

Command AddProblemsCommand(CLI::App& app) {
  auto args = std::make_shared<ProblemsArgs>();
  CLI::App* command =
      app.add_subcommand("problems", "draw random problems for the Franka or a robot folder (--robot): spheres "
                                     "blocking the straight path (problems.*), or a scene family (--family)");
  args->config.Add(command, false);
  command->add_option("--out", args->out, "YAML file of problems")->required();
  command->add_flag("--force", args->force, "replace the --out file if it exists");
  command->add_option("--robot", args->robot,
                      "a robot folder (`flowplan robot import`; or robot: in the config) to draw the problems for");
  std::string families;
  for (const auto& name : problems::SceneFamilies()) families += (families.empty() ? "" : ", ") + name;
  command->add_option("--family", args->family,
                      "a procedural scene family (" + families + "); problems.count and problems.clearance apply");
  return {command, [args] { MakeProblems(*args); }};
}

}  // namespace flowplan::experiment
