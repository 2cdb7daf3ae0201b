#include "planning/script_planner.h"

#include <chrono>
#include <filesystem>

#include "core/error.h"
#include "core/format.h"
#include "guidance/scene.h"
#include "planning/export.h"

namespace flowplan::planning {

ScriptPlanner::ScriptPlanner(const std::string& path) : path_(path) {
  if (!std::filesystem::is_regular_file(path)) throw Error(path + ": no such exported planner file");
  try {
    module_ = torch::jit::load(path);
  } catch (const c10::Error& e) {
    throw Error(path + ": not a TorchScript module: " + FirstLine(e.what_without_backtrace()));
  }
  try {
    const int64_t version = module_.attr("format_version").toInt();
    if (version != kExportFormatVersion) {
      throw Error(path + ": exported planner format_version " + std::to_string(version) +
                  " is not supported (this build plans with version " + std::to_string(kExportFormatVersion) +
                  "; export it again)");
    }
    horizon_ = module_.attr("horizon").toInt();
    state_dim_ = module_.attr("state_dim").toInt();
    noise_shape_ = module_.attr("noise_shape").toIntVector();
    renoise_shape_ = module_.attr("renoise_shape").toIntVector();
    env_ = module_.attr("env").toStringRef();
    dt_ = module_.attr("dt").toDouble();
    config_yaml_ = module_.attr("config").toStringRef();
    for (const auto& label : module_.attr("state_labels").toListRef()) state_labels_.push_back(label.toStringRef());
    robot_ = kinematics::RobotFromYaml(module_.attr("robot").toStringRef(), path + ": attribute robot");
  } catch (const c10::Error& e) {
    throw Error(path + ": not a flowplan planner (" + FirstLine(e.what_without_backtrace()) + ")");
  }
}

PlanResult ScriptPlanner::Plan(const PlanRequest& request) const {
  const auto started = std::chrono::steady_clock::now();
  CheckEnds(request.start, request.goal, state_dim_, "plan");
  if (request.obstacles.defined()) guidance::CheckObstacles(request.obstacles, robot_.workspace_dim, "plan: obstacles");
  auto generator = at::make_generator<at::CPUGeneratorImpl>(request.seed);
  auto with_batch = [&](const std::vector<int64_t>& shape) {
    std::vector<int64_t> out = {request.start.size(0)};
    out.insert(out.end(), shape.begin(), shape.end());
    return out;
  };
  const torch::Tensor noise = torch::randn(with_batch(noise_shape_), generator, torch::kFloat32);
  const torch::jit::IValue renoise =
      renoise_shape_.empty() ? torch::jit::IValue()
                             : torch::jit::IValue(torch::randn(with_batch(renoise_shape_), generator, torch::kFloat32));
  const torch::jit::IValue obstacles =
      request.obstacles.defined() ? torch::jit::IValue(request.obstacles.to(torch::kFloat32)) : torch::jit::IValue();
  const torch::jit::IValue scale = request.guidance ? torch::jit::IValue(request.guidance->scale) : torch::jit::IValue();
  PlanResult result;
  try {
    result.plans = module_.run_method("plan", request.start.to(torch::kFloat32), request.goal.to(torch::kFloat32), noise,
                                      renoise, obstacles, scale)
                       .toTensor();
  } catch (const c10::Error& e) {
    throw Error(path_ + ": " + LastLine(e.what_without_backtrace()));
  }
  result.found = torch::ones({request.start.size(0)}, torch::kBool);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.seconds.assign(static_cast<size_t>(request.start.size(0)), seconds);
  return result;
}

}  // namespace flowplan::planning
