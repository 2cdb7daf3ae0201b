#include "planning/assemble.h"

#include <functional>
#include <vector>

#include "core/error.h"
#include "core/format.h"
#include "jit/library.h"
#include "kinematics/robot.h"
#include "models/device.h"
#include "planning/samplers.h"

namespace flowplan::planning {
namespace {

/// A sampler of one objective: the planner kind it makes, the config section
/// whose numbers are its per-call settings, and its builder.
struct SamplerKind {
  objectives::ObjectiveKind objective;
  const char* planner;
  const char* settings;  // a key prefix of the sampler section; "" for every key directly under it
  std::function<torch::jit::Module(const SamplerContext&)> build;
};

// One line per objective.
const std::vector<SamplerKind> kSamplers = {
    {objectives::ObjectiveKind::kFlowMatching, "flow_matching", "", BuildFlowSampler},
    {objectives::ObjectiveKind::kDdpm, "ddpm", "ddpm", BuildDdpmSampler},
    {objectives::ObjectiveKind::kVae, "latent", "latent", BuildLatentSampler},
};

/// The per-call settings of a planner: every number of the guidance section
/// and of its sampler's part of the sampler section.
c10::Dict<std::string, double> Settings(const PlannerParts& parts, const SamplerKind& kind) {
  c10::Dict<std::string, double> settings;
  for (const auto& [key, value] : config::ListNumbers(parts.guidance, "guidance")) settings.insert(key, value);
  const std::string prefix = std::string("sampler.") + kind.settings;
  for (const auto& [key, value] : config::ListNumbers(parts.sampler, "sampler")) {
    const bool direct = key.find('.', std::string("sampler.").size()) == std::string::npos;
    if (kind.settings[0] == '\0' ? direct : key.rfind(prefix + ".", 0) == 0) settings.insert(key, value);
  }
  return settings;
}

}  // namespace

std::unique_ptr<LearnedPlanner> AssemblePlanner(const PlannerParts& parts) {
  FLOWPLAN_DEMAND(parts.net != nullptr && parts.normalizer.fitted());
  const kinematics::TrajectoryInfo& trajectory = parts.trajectory;
  const int64_t D = trajectory.state_dim(), J = trajectory.robot.num_joints;
  FLOWPLAN_DEMAND(parts.normalizer.dim() == D);
  if (D != 2 * J) {
    throw Error("planner: states of " + std::to_string(D) + " dimensions (" + Join(trajectory.state_labels) +
                "); a planner plans the positions and velocities of the robot's " + std::to_string(J) +
                " joints (D = " + std::to_string(2 * J) + ")");
  }
  const SamplerKind* kind = nullptr;
  for (const SamplerKind& k : kSamplers) {
    if (k.objective == parts.objective.name) kind = &k;
  }
  FLOWPLAN_DEMAND(kind != nullptr);
  // Modules of their own (not shared with anything outside), so that moving the planner moves only them.
  const kinematics::Robot robot(trajectory.robot, "planner robot");
  const torch::jit::Module normalizer = parts.normalizer.module().deepcopy();
  const torch::jit::Module guide = guidance::BuildGuide(parts.guidance, robot, normalizer, trajectory.dt);
  const torch::jit::Module sampler = kind->build(SamplerContext{parts, normalizer, robot.module(), guide});
  const bool splitting = parts.objective.name == objectives::ObjectiveKind::kFlowMatching &&
                         parts.sampler.splitting != Splitting::kNone;
  std::vector<int64_t> noise_shape = {trajectory.horizon, D}, renoise_shape;
  if (parts.objective.name == objectives::ObjectiveKind::kDdpm) {
    renoise_shape = {parts.objective.ddpm.steps - 1, trajectory.horizon, D};
  } else if (parts.objective.name == objectives::ObjectiveKind::kVae) {
    noise_shape = {sampler.attr("vae").toModule().attr("latent_dim").toInt()};
  } else if (splitting) {
    renoise_shape = {trajectory.horizon, D};
  }
  c10::List<std::string> labels;
  for (const std::string& label : trajectory.state_labels) labels.push_back(label);
  torch::jit::Module module =
      jit::ModuleBuilder("Planner")
          .Submodule("normalizer", normalizer)
          .Submodule("robot", robot.module())
          .Submodule("sampler", sampler)
          .Attribute("settings", Settings(parts, *kind))
          .Attribute("schedule", std::string(config::EnumName(parts.guidance.schedule)))
          .Attribute("guide_at", std::string(config::EnumName(parts.sampler.guide_at)))
          .Attribute("noise_shape", c10::List<int64_t>(noise_shape))
          .Attribute("renoise_shape", c10::ListType::ofInts(), c10::List<int64_t>(renoise_shape))
          .Attribute("state_dim", D)
          .Attribute("horizon", trajectory.horizon)
          .Attribute("num_joints", J)
          .Attribute("workspace_dim", static_cast<int64_t>(trajectory.robot.workspace_dim))
          .Attribute("planner", std::string(kind->planner))
          .Attribute("conditioning", std::string(parts.objective.name == objectives::ObjectiveKind::kVae
                                                     ? "none"
                                                     : config::EnumName(parts.objective.conditioning)))
          .Attribute("splitting", std::string(splitting ? config::EnumName(parts.sampler.splitting) : "none"))
          .Attribute("dt", trajectory.dt)
          .Attribute("env", trajectory.env)
          .Attribute("state_labels", c10::ListType::ofStrings(), labels)
          .Attribute("robot_description", kinematics::RobotToYaml(trajectory.robot))
          .Attribute("config", parts.config_yaml)
          .Attribute("format_version", kExportFormatVersion)
          .Methods("planning/planner.py")
          .Build();
  module.eval();
  module.to(models::DeviceOf(*parts.net));
  return std::make_unique<LearnedPlanner>(module);
}

}  // namespace flowplan::planning
