// `flowplan generate` and `flowplan merge`: datasets (docs/dataset_format.md).

#include <spdlog/spdlog.h>

#include <memory>
#include <regex>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/parallel.h"
#include "datasets/generator.h"
#include "datasets/trajectory_dataset.h"
#include "experiment/commands.h"

namespace flowplan::experiment {
namespace {

struct GenerateArgs {
  ConfigArgs config;
  std::string shard = "0/1";  // --shard k/n
  std::string out;            // --out, overrides generate.out (e.g. one file per shard)
};

/// k/n of --shard. @throws flowplan::Error for anything else.
std::pair<int, int> ParseShard(const std::string& text) {
  static const std::regex pattern(R"((\d+)/(\d+))");
  std::smatch match;
  if (!std::regex_match(text, match, pattern)) throw Error("--shard: expected k/n (e.g. 0/4), got \"" + text + "\"");
  int index = 0, count = 0;
  try {
    index = std::stoi(match[1].str());
    count = std::stoi(match[2].str());
  } catch (const std::out_of_range&) {
    throw Error("--shard: expected k/n with numbers that fit an int, got \"" + text + "\"");
  }
  if (count < 1 || index >= count) throw Error("--shard: expected k/n with 0 <= k < n, got \"" + text + "\"");
  return {index, count};
}

std::string RunGenerate(const GenerateArgs& args) {
  const ExperimentConfig config = args.config.Load();
  const auto [shard_index, shard_count] = ParseShard(args.shard);
  const int threads = ResolveThreadCount(config.threads);
  const std::string out = args.out.empty() ? config.generate.out : args.out;
  EnsureParentFolder(out);
  AtomicFile probe(out);  // fails early, before any rollout, if the file cannot be written
  const auto task = datasets::MakeTask(config.generate, config.robot);
  datasets::GenerateOptions options;
  options.episodes = config.generate.episodes;
  options.seed = static_cast<uint64_t>(config.seed);
  options.threads = threads;
  options.shard_index = shard_index;
  options.shard_count = shard_count;
  options.config_yaml = DatasetConfigYaml(config);
  spdlog::info("generating {} episodes of {} on {} threads{}", config.generate.episodes,
               config::EnumName(config.generate.dataset), threads,
               shard_count > 1 ? " (shard " + std::to_string(shard_index) + "/" + std::to_string(shard_count) + ")"
                               : std::string());
  const datasets::TrajectoryDataset dataset = datasets::GenerateDataset(*task, options);
  datasets::WriteDataset(out, dataset);
  spdlog::info("wrote {}: {} episodes x {} states x {} dims ({} rejected, {} simulator warnings)", out,
               dataset.num_episodes, dataset.info.horizon, dataset.info.state_dim(), dataset.rejected_episodes,
               dataset.simulator_warnings);
  return out;
}

}  // namespace

std::string Generate(const std::string& config_path, const std::vector<std::string>& overrides) {
  GenerateArgs args;
  args.config.path = config_path;
  args.config.overrides = overrides;
  return RunGenerate(args);
}

Command AddGenerateCommand(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  CLI::App* command = app.add_subcommand("generate", "roll out a dataset and write it as HDF5 (generate.*)");
  args->config.Add(command, true);
  command->add_option("--shard", args->shard, "generate part k of n (episodes [kN/n, (k+1)N/n))");
  command->add_option("--out", args->out, "output file (default: generate.out)");
  return {command, [args] { RunGenerate(*args); }};
}

Command AddMergeCommand(CLI::App& app) {
  auto inputs = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>();
  CLI::App* command = app.add_subcommand("merge", "join dataset shards written with --shard");
  command->add_option("inputs", *inputs, "shard files in order")->required()->check(CLI::ExistingFile);
  command->add_option("--out", *out, "merged file")->required();
  return {command, [inputs, out] {
            std::vector<datasets::TrajectoryDataset> shards;
            for (const auto& path : *inputs) shards.push_back(datasets::ReadDataset(path));
            EnsureParentFolder(*out);
            const datasets::TrajectoryDataset merged = datasets::MergeDatasets(shards, *inputs);
            datasets::WriteDataset(*out, merged);
            spdlog::info("wrote {}: {} episodes from {} shard{}", *out, merged.num_episodes, inputs->size(),
                         inputs->size() == 1 ? "" : "s");
          }};
}

}  // namespace flowplan::experiment
