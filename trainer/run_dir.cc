#include "trainer/run_dir.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <regex>

#include "core/atomic_file.h"
#include "core/error.h"

namespace flowplan::trainer {
namespace fs = std::filesystem;

std::string RunDir::checkpoint(int64_t step) const {
  char name[32];
  std::snprintf(name, sizeof(name), "step_%08lld.pt", static_cast<long long>(step));
  return checkpoints() + "/" + name;
}

void RunDir::Create() const {
  MakeDirectories(root_);
  MakeDirectories(checkpoints());
}

std::vector<int64_t> RunDir::CheckpointSteps() const {
  std::vector<int64_t> steps;
  std::error_code ec;
  if (!fs::is_directory(checkpoints(), ec)) return steps;
  static const std::regex pattern(R"(step_(\d{8})\.pt)");
  for (const auto& entry : fs::directory_iterator(checkpoints(), ec)) {
    std::smatch match;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, match, pattern)) steps.push_back(std::stoll(match[1].str()));
  }
  std::sort(steps.begin(), steps.end());
  return steps;
}

std::string RunDir::LatestCheckpoint() const {
  std::error_code ec;
  if (!fs::is_directory(root_, ec)) throw Error(root_ + ": no such run folder");
  const auto steps = CheckpointSteps();
  if (steps.empty()) throw Error(root_ + ": run folder holds no checkpoint (checkpoints/step_*.pt)");
  return checkpoint(steps.back());
}

void RunDir::PruneCheckpoints(int keep) const {
  const auto steps = CheckpointSteps();
  for (size_t i = 0; i + static_cast<size_t>(keep) < steps.size(); ++i) {
    std::error_code ec;
    fs::remove(checkpoint(steps[i]), ec);
  }
}

std::string ResolveCheckpoint(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return RunDir(path).LatestCheckpoint();
  return path;
}

}  // namespace flowplan::trainer
