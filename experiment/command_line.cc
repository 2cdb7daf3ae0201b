#include "experiment/command_line.h"

#include <torch/torch.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/parallel.h"

namespace flowplan::experiment {
namespace fs = std::filesystem;

void ConfigArgs::Add(CLI::App* command, bool required, const std::string& help) {
  auto* option = command->add_option("--config", path, help);
  option->check(CLI::ExistingFile);
  if (required) option->required();
  command->add_option("overrides", overrides, kOverrideHelp);
}

ExperimentConfig ConfigArgs::Load() const { return LoadExperiment(path, overrides); }

int ConfigureThreads(const ExperimentConfig& config) {
  // Arithmetic on denormal floats is orders of magnitude slower on x86; flush
  // them to zero before any worker thread starts (the threads inherit the mode).
  at::globalContext().setFlushDenormal(true);
  at::set_num_threads(1);
  return ResolveThreadCount(config.threads);
}

void EnsureParentFolder(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty()) MakeDirectories(parent.string());
}

std::string RunFolderOf(const std::string& checkpoint) {
  const fs::path folder = fs::path(checkpoint).parent_path();
  if (folder.filename() == "checkpoints") return folder.parent_path().string();
  return folder.empty() ? std::string(".") : folder.string();
}

}  // namespace flowplan::experiment
