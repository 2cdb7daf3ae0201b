#include "planning/learned_planner.h"

#include <chrono>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "jit/library.h"

namespace flowplan::planning {
namespace {

std::vector<int64_t> WithBatch(const std::vector<int64_t>& batch, const std::vector<int64_t>& shape) {
  std::vector<int64_t> out = batch;
  out.insert(out.end(), shape.begin(), shape.end());
  return out;
}

}  // namespace

LearnedPlanner::LearnedPlanner(torch::jit::Module module, std::string source)
    : module_(std::move(module)), source_(std::move(source)) {
  try {
    const int64_t version = module_.attr("format_version").toInt();
    if (version != kExportFormatVersion) {
      throw Error(source_ + ": exported planner format_version " + std::to_string(version) +
                  " is not supported (this build plans with version " + std::to_string(kExportFormatVersion) +
                  "; export it again)");
    }
    kind_ = module_.attr("planner").toStringRef();
    info_.env = module_.attr("env").toStringRef();
    info_.dt = module_.attr("dt").toDouble();
    info_.horizon = module_.attr("horizon").toInt();
    for (const auto& label : module_.attr("state_labels").toListRef()) info_.state_labels.push_back(label.toStringRef());
    info_.robot = kinematics::RobotFromYaml(module_.attr("robot_description").toStringRef(), source_ + ": attribute robot_description");
    config_yaml_ = module_.attr("config").toStringRef();
    schedule_ = module_.attr("schedule").toStringRef();
    guide_at_ = module_.attr("guide_at").toStringRef();
    for (const auto& entry : module_.attr("settings").toGenericDict()) {
      settings_.emplace(entry.key().toStringRef(), entry.value().toDouble());
    }
    noise_shape_ = module_.attr("noise_shape").toIntVector();
    renoise_shape_ = module_.attr("renoise_shape").toIntVector();
  } catch (const Error&) {
    throw;
  } catch (const c10::Error& e) {
    throw Error(source_ + ": not a flowplan planner (" + FirstLine(e.what_without_backtrace()) + ")");
  } catch (const std::exception& e) {  // torch::jit::ObjectAttributeError: a module without our attributes
    throw Error(source_ + ": not a flowplan planner (" + FirstLine(e.what()) + ")");
  }
}

std::unique_ptr<LearnedPlanner> LearnedPlanner::Load(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw Error(path + ": no such exported planner file");
  torch::jit::Module module;
  try {
    module = torch::jit::load(path);
  } catch (const c10::Error& e) {
    throw Error(path + ": not a TorchScript module: " + FirstLine(e.what_without_backtrace()));
  }
  module.eval();
  return std::make_unique<LearnedPlanner>(module, path);
}

void LearnedPlanner::Save(const std::string& path) const {
  AtomicFile file(path);
  try {
    module_.save(file.temp_path());
  } catch (const c10::Error& e) {
    throw Error(path + ": cannot write the exported planner: " + FirstLine(e.what_without_backtrace()));
  }
  file.Commit();
}

torch::Tensor LearnedPlanner::PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal,
                                            const torch::Tensor& noise, const torch::Tensor& renoise,
                                            const geometry::SceneRows& scene, const PlanSettings& settings) const {
  CheckEnds(start, goal, state_dim(), "plan");
  torch::jit::Kwargs kwargs;
  if (renoise.defined()) kwargs["renoise"] = renoise;
  for (const auto& entry : scene) kwargs[entry.key()] = entry.value();
  if (!settings.values.empty()) {
    c10::Dict<std::string, double> values;
    for (const auto& [key, value] : settings.values) values.insert(key, value);
    kwargs["settings"] = values;
  }
  if (settings.schedule) kwargs["schedule"] = *settings.schedule;
  if (settings.guide_at) kwargs["guide_at"] = *settings.guide_at;
  torch::NoGradGuard no_grad;
  return jit::Call(module_, "plan", {start, goal, noise}, kwargs).toTensor().to(torch::kCPU);
}

torch::Tensor LearnedPlanner::GuidanceCost(const torch::Tensor& plans, const geometry::SceneRows& scene,
                                           const PlanSettings& settings) const {
  if (!plans.defined() || plans.dim() != 3 || plans.size(2) != state_dim()) {
    throw Error("guidance cost: plans: expected (B, T, " + std::to_string(state_dim()) + "), got " +
                (plans.defined() ? ShapeText(plans.sizes().vec()) : "(undefined)"));
  }
  c10::Dict<std::string, double> values;
  for (const auto& [key, value] : settings.values) values.insert(key, value);
  const c10::IValue opts =
      jit::Call(module_, "call_settings", {c10::IValue(), settings.values.empty() ? c10::IValue() : c10::IValue(values)});
  const torch::jit::Module guide = module_.attr("sampler").toModule().attr("guide").toModule();
  torch::NoGradGuard no_grad;
  return jit::Call(guide, "value", {plans.to(torch::kFloat32), scene, opts}).toTensor().to(torch::kFloat64);
}

PlanResult LearnedPlanner::Plan(const PlanRequest& request) const {
  const auto started = std::chrono::steady_clock::now();
  CheckEnds(request.start, request.goal, state_dim(), "plan");
  const int64_t B = request.start.size(0);
  // Best of N draws N noises per plan (planning/planner.py checks the count).
  const auto given = request.settings.values.find("guidance.candidates");
  const auto candidates = static_cast<int64_t>(given != request.settings.values.end() ? given->second
                                                                                        : settings_.at("guidance.candidates"));
  const std::vector<int64_t> batch = candidates > 1 ? std::vector<int64_t>{B, candidates} : std::vector<int64_t>{B};
  auto generator = at::make_generator<at::CPUGeneratorImpl>(request.seed);
  const torch::Tensor noise = torch::randn(WithBatch(batch, noise_shape_), generator, torch::kFloat32);
  const torch::Tensor renoise = renoise_shape_.empty()
                                    ? torch::Tensor()
                                    : torch::randn(WithBatch(batch, renoise_shape_), generator, torch::kFloat32);
  PlanResult result;
  result.plans = PlanWithNoise(request.start, request.goal, noise, renoise, request.scene, request.settings);
  result.found = torch::ones({B}, torch::kBool);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.call_seconds.assign(static_cast<size_t>(B), seconds);
  result.call_plans.assign(static_cast<size_t>(B), B);
  return result;
}

}  // namespace flowplan::planning
