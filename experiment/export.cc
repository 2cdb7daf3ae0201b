// `flowplan export`: the planner a checkpoint makes, saved as TorchScript
// (docs/export.md). It is the module flowplan plans with in-process.

#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "experiment/commands.h"
#include "experiment/trained_planner.h"
#include "core/error.h"
#include "geometry/scene.h"
#include "trainer/run_dir.h"

namespace flowplan::experiment {

Command AddExportCommand(CLI::App& app) {
  struct Args {
    std::string ckpt, planner, out, scene, kernels = "portable";
    ConfigArgs overlay;
  };
  auto args = std::make_shared<Args>();
  CLI::App* command = app.add_subcommand("export", "write the self-contained TorchScript planner");
  CLI::Option* ckpt = command->add_option("--ckpt", args->ckpt, "checkpoint file, or a run folder");
  command
      ->add_option("--planner", args->planner,
                   "an exported planner file instead of a checkpoint: written again with --kernels, --scene (default: "
                   "the scene baked into it) and the per-call settings of the overrides (what is compiled into it "
                   "cannot change)")
      ->check(CLI::ExistingFile)
      ->excludes(ckpt);
  command->add_option("--out", args->out, "output file (default: RUN_DIR/planner.pt)");
  command
      ->add_option("--scene", args->scene,
                   "a scene file baked into the file: `flowplan plan --planner FILE` plans around it unless given "
                   "--scene or obstacles of its own (default: none; the training config's scene is not kept)")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--kernels", args->kernels,
                   "the code in the file of the network and of the collision cost's distances: portable (PyTorch "
                   "alone loads it) or native (faster; needs libflowplan_kernels loaded first, docs/export.md). "
                   "This option decides, whatever sampler.network_kernels and guidance.distance_kernels a config says")
      ->check(CLI::IsMember({"portable", "native"}));
  args->overlay.Add(command, false, "YAML applied over the checkpoint's config");
  return {command, [args] {
            if (args->ckpt.empty() == args->planner.empty()) throw Error("export: give --ckpt or --planner");
            // An exported file runs anywhere: its weights are written from the CPU.
            std::vector<std::string> overrides = args->overlay.overrides;
            overrides.push_back("device=cpu");
            overrides.push_back("sampler.network_kernels=" + args->kernels);
            overrides.push_back("guidance.distance_kernels=" + args->kernels);
            // The file carries no obstacle its user did not ask for.
            const geometry::Scene scene = args->scene.empty() ? geometry::Scene{} : geometry::LoadScene(args->scene);
            std::unique_ptr<planning::LearnedPlanner> planner;
            std::string source, out = args->out;
            std::string baked = args->scene.empty() ? std::string("none") : args->scene;
            if (!args->planner.empty()) {
              if (out.empty()) throw Error("export --planner: give --out (the file is not written over)");
              if (std::filesystem::exists(out) && std::filesystem::equivalent(out, args->planner)) {
                throw Error(out + ": is the planner being read; give another --out");
              }
              const auto file = planning::LearnedPlanner::Load(args->planner);
              ExperimentConfig config = LoadExperimentText(file->config_yaml(), args->planner + " (its config)",
                                                           args->overlay.path, overrides);
              if (!args->scene.empty()) {
                config.scene = scene;
              } else if (config.scene.size() > 0) {  // the scene baked into the file stays
                baked = "the " + std::to_string(config.scene.size()) + " obstacles baked into " + args->planner;
              }
              planner = AssembleExported(*file, config);
              source = args->planner;
            } else {
              TrainedPlanner loaded = LoadTrainedPlanner(args->ckpt, args->overlay.path, overrides, scene);
              source = loaded.checkpoint + " (step " + std::to_string(loaded.step) + ")";
              if (out.empty()) out = trainer::RunDir(RunFolderOf(loaded.checkpoint)).planner();
              planner = std::move(loaded.planner);
            }
            EnsureParentFolder(out);
            planner->Save(out);
            const int64_t D = planner->state_dim(), T = planner->horizon();
            auto batch_shape = [](const std::vector<int64_t>& shape) {
              std::string text = "(B";
              for (const int64_t n : shape) text += ", " + std::to_string(n);
              return text + ")";
            };
            const std::string renoise =
                planner->renoise_shape().empty() ? "" : ", renoise " + batch_shape(planner->renoise_shape());
            spdlog::info("exported {} to {} ({} kernels): plan(start (B, {}), goal (B, {}), noise {}{}, scene...) -> "
                         "(B, {}, {}); baked scene: {}",
                         source, out, args->kernels, D, D, batch_shape(planner->noise_shape()), renoise, T, D, baked);
          }};
}

}  // namespace flowplan::experiment
