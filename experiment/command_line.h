#pragma once

// What the subcommands of `flowplan` share: the --config / key=value options,
// thread setup, number lists on the command line, output folders. Each
// subcommand is one file of experiment/ with an Add…Command function
// (experiment/commands.h).

#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

#include "core/format.h"
#include "experiment/experiment_config.h"

namespace flowplan::experiment {

/// A subcommand: its CLI11 app and what runs when the command line chose it.
struct Command {
  CLI::App* app = nullptr;
  std::function<void()> run;
};

inline constexpr const char* kOverrideHelp =
    "config overrides key.sub=value, applied after the file (see `flowplan config keys`)";

/// --config FILE.yaml and trailing key=value overrides.
struct ConfigArgs {
  std::string path;
  std::vector<std::string> overrides;

  /// Adds both to `command`; `help` describes the file.
  void Add(CLI::App* command, bool required, const std::string& help = "experiment config (YAML)");
  /// Defaults, then the file, then the overrides.
  ExperimentConfig Load() const;
};

/// Worker threads from config.threads (0: all cores). LibTorch itself runs
/// single-threaded: the workers take fixed shards of the work, so results do
/// not depend on the thread count.
int ConfigureThreads(const ExperimentConfig& config);

/// Creates the folder `path` is in, if it has one.
void EnsureParentFolder(const std::string& path);

/// The run folder a checkpoint belongs to: RUN/checkpoints/step_N.pt -> RUN.
std::string RunFolderOf(const std::string& checkpoint);

using flowplan::ParseNumbers;  // core/format.h

}  // namespace flowplan::experiment
