// `flowplan export`: the planner a checkpoint makes, saved as TorchScript
// (docs/export.md). It is the module flowplan plans with in-process.

#include <spdlog/spdlog.h>

#include <memory>

#include "experiment/commands.h"
#include "experiment/trained_planner.h"
#include "trainer/run_dir.h"

namespace flowplan::experiment {

Command AddExportCommand(CLI::App& app) {
  struct Args {
    std::string ckpt, out;
    ConfigArgs overlay;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app.add_subcommand("export", "write the self-contained TorchScript planner");
  command->add_option("--ckpt", args->ckpt, "checkpoint file, or a run folder")->required();
  command->add_option("--out", args->out, "output file (default: RUN_DIR/planner.pt)");
  args->overlay.Add(command, false, "YAML applied over the checkpoint's config");
  return {command, [args] {
            // An exported file runs anywhere: its weights are written from the CPU.
            std::vector<std::string> overrides = args->overlay.overrides;
            overrides.push_back("device=cpu");
            const TrainedPlanner loaded = LoadTrainedPlanner(args->ckpt, args->overlay.path, overrides);
            const std::string out =
                args->out.empty() ? trainer::RunDir(RunFolderOf(loaded.checkpoint)).planner() : args->out;
            EnsureParentFolder(out);
            loaded.planner->Save(out);
            const int64_t D = loaded.planner->state_dim(), T = loaded.planner->horizon();
            spdlog::info("exported {} (step {}) to {}: plan(start (B, {}), goal (B, {}), noise (B, {}, {})) -> (B, {}, {})",
                         loaded.checkpoint, loaded.step, out, D, D, T, D, T, D);
          }};
}

}  // namespace flowplan::experiment
