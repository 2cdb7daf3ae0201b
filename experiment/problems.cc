// `flowplan problems`: random Franka planning problems whose straight path is
// blocked (problems.*, docs/planning.md).

#include <spdlog/spdlog.h>

#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"
#include "experiment/commands.h"
#include "kinematics/robot.h"
#include "problems/blocked_problems.h"
#include "sim/franka_model.h"

namespace flowplan::experiment {

Command AddProblemsCommand(CLI::App& app) {
  struct Args {
    ConfigArgs config;
    std::string out;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command =
      app.add_subcommand("problems", "draw random Franka problems whose straight path is blocked (problems.*)");
  args->config.Add(command, false);
  command->add_option("--out", args->out, "YAML file of problems")->required();
  return {command, [args] {
            const ExperimentConfig config = args->config.Load();
            ConfigureThreads(config);
            const kinematics::Robot arm(sim::LoadFrankaModel().description(), "the Franka");
            problems::BlockedProblemSet set;
            try {
              set = problems::MakeBlockedProblems(arm, config.problems, static_cast<uint64_t>(config.seed));
            } catch (const Error& e) {
              throw Error(std::string("problems.") + e.what());
            }
            EnsureParentFolder(args->out);
            WriteFileAtomically(args->out, config::ToYaml(set));
            size_t spheres = 0;
            for (const auto& problem : set.problems) spheres += problem.scene.spheres.size();
            spdlog::info("wrote {}: {} problems, {} spheres, each blocking the straight TCP path with its first",
                         args->out, set.problems.size(), spheres);
          }};
}

}  // namespace flowplan::experiment
