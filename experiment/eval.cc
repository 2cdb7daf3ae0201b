// `flowplan eval stitching`: the stitching error of a trained planner on its
// dataset's test (stitching) and training pairs.

#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "datasets/h5.h"
#include "datasets/trajectory_dataset.h"
#include "datasets/trajectory_loader.h"
#include "eval/stitching.h"
#include "experiment/commands.h"
#include "experiment/trained_planner.h"

namespace flowplan::experiment {
namespace {

void WritePlans(const std::string& path, const eval::StitchingResult& test, const eval::StitchingResult& train) {
  AtomicFile target(path);
  {
    auto file = datasets::h5::File::Create(target.temp_path());
    for (const eval::StitchingResult* result : {&test, &train}) {
      if (!result->plans.defined()) continue;
      const torch::Tensor plans = result->plans.contiguous();
      const torch::Tensor index = result->pair_index.to(torch::kInt32).contiguous();
      file.CreateGroup("/" + result->pairs);
      file.WriteFloat32("/" + result->pairs + "/plans", plans.sizes().vec(), plans.data_ptr<float>());
      file.WriteInt32("/" + result->pairs + "/pair_index", index.sizes().vec(), index.data_ptr<int32_t>());
    }
    file.Close();
  }
  target.Commit();
}

}  // namespace

std::string StitchingPlansFile(const std::string& report) {
  return std::filesystem::path(report).replace_extension(".plans.h5").string();
}

std::string EvaluateStitching(const EvalArgs& args) {
  // Stitching is measured on the network alone: unguided.
  std::vector<std::string> overrides = args.overlay.overrides;
  overrides.push_back("guidance.scale=0");
  const TrainedPlanner loaded = LoadTrainedPlanner(args.ckpt, args.overlay.path, overrides);
  const int threads = ConfigureThreads(loaded.config);
  const datasets::TrajectoryDataset dataset = datasets::ReadDataset(loaded.config.data.path);
  if (dataset.info.state_dim() != loaded.planner->state_dim()) {
    throw Error(loaded.config.data.path + ": states have " + std::to_string(dataset.info.state_dim()) +
                " dimensions, the checkpoint plans " + std::to_string(loaded.planner->state_dim()));
  }
  const auto test_pairs = datasets::ToTensors(dataset.test_pairs, dataset.info.state_dim());
  const auto train_pairs = datasets::ToTensors(dataset.train_pairs, dataset.info.state_dim());
  const auto& labels = dataset.info.state_labels;
  const eval::StitchingResult test =
      eval::EvaluateStitching(*loaded.planner, test_pairs, labels, "test", loaded.config.eval, threads);
  const eval::StitchingResult train =
      eval::EvaluateStitching(*loaded.planner, train_pairs, labels, "train", loaded.config.eval, threads);
  const std::string out = args.out.empty() ? RunFolderOf(loaded.checkpoint) + "/eval_stitching.json" : args.out;
  EnsureParentFolder(out);
  WriteFileAtomically(out, "{\"checkpoint\": " + JsonString(loaded.checkpoint) + ", \"step\": " +
                               std::to_string(loaded.step) + ", \"data\": " + JsonString(loaded.config.data.path) +
                               ", \"sampler_steps\": " + std::to_string(loaded.config.sampler.steps) +
                               ", \"sampler_splitting\": " +
                               JsonString(config::EnumName(loaded.config.sampler.splitting)) +
                               ", \"test\": " + eval::ToJson(test) + ", \"train\": " + eval::ToJson(train) + "}\n");
  const std::string plans = StitchingPlansFile(out);
  WritePlans(plans, test, train);
  spdlog::info("stitching error (step {}, {} plans): test pairs {:.4f} ± {:.4f}, training pairs {:.4f} ± {:.4f}; "
               "wrote {} and {}",
               loaded.step, loaded.config.eval.num_plans, test.mean, test.stddev, train.mean, train.stddev, out, plans);
  return out;
}

Command AddEvalCommand(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* eval = app.add_subcommand("eval", "evaluate a trained planner");
  eval->require_subcommand(1);
  CLI::App* stitching = eval->add_subcommand("stitching", "stitching error on the dataset's test and training pairs");
  stitching->add_option("--ckpt", args->ckpt, "checkpoint file, or a run folder (its newest checkpoint)")->required();
  stitching->add_option("--out", args->out, "JSON report (default: RUN_DIR/eval_stitching.json)");
  args->overlay.Add(stitching, false, "YAML applied over the checkpoint's config");
  return {stitching, [args] { EvaluateStitching(*args); }};
}

}  // namespace flowplan::experiment
