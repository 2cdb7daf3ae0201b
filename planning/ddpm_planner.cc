#include "planning/ddpm_planner.h"

#include <chrono>
#include <cmath>

#include "core/error.h"
#include "guidance/scene.h"
#include "models/device.h"
#include "models/trajectory_net.h"
#include "planning/script_parts.h"

namespace flowplan::planning {

DdpmPlanner::DdpmPlanner(models::TrajectoryNetPtr net, models::MinMaxNormalizer normalizer,
                         models::Conditioning conditioning, int64_t horizon, const objectives::DdpmConfig& schedule,
                         DdpmSamplerConfig sampler, GuidanceSetup guidance)
    : net_(std::move(net)),
      normalizer_(std::move(normalizer)),
      conditioning_(conditioning),
      horizon_(horizon),
      schedule_(schedule),
      sampler_(sampler),
      guidance_(std::move(guidance)) {
  FLOWPLAN_DEMAND(net_ != nullptr && normalizer_.dim() == net_->state_dim());
  FLOWPLAN_DEMAND(net_->cond_dim() == models::ConditionDim(conditioning_, net_->state_dim()));
  net_->CheckHorizon(horizon_);
  for (int k = 0; k < schedule_.steps; ++k) {
    const double a = schedule_.alpha_bar(k), a_before = schedule_.alpha_bar_before(k), beta = schedule_.beta(k);
    x0_from_x_.push_back(1.0 / std::sqrt(a));
    x0_from_eps_.push_back(std::sqrt(1.0 / a - 1.0));
    c1_.push_back(beta * std::sqrt(a_before) / (1.0 - a));
    c2_.push_back((1.0 - a_before) * std::sqrt(schedule_.alpha(k)) / (1.0 - a));
    std_.push_back(std::sqrt(beta * (1.0 - a_before) / (1.0 - a)));
  }
}

int DdpmPlanner::GuidedSteps() const {
  return static_cast<int>(std::ceil(sampler_.guide_fraction * schedule_.steps - 1e-9));
}

void DdpmPlanner::CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                               const torch::Tensor& renoise) const {
  CheckEnds(start, goal, state_dim(), "plan");
  const int64_t B = start.size(0), D = state_dim(), N = schedule_.steps;
  if (!noise.defined() || noise.sizes() != torch::IntArrayRef({B, horizon_, D})) {
    throw Error("plan: noise: expected (" + std::to_string(B) + ", " + std::to_string(horizon_) + ", " +
                std::to_string(D) + "), got " + models::ShapeString(noise));
  }
  if (!renoise.defined() || renoise.sizes() != torch::IntArrayRef({B, N - 1, horizon_, D})) {
    throw Error("plan: renoise: expected the noise of the DDPM steps (" + std::to_string(B) + ", " +
                std::to_string(N - 1) + ", " + std::to_string(horizon_) + ", " + std::to_string(D) + "), got " +
                models::ShapeString(renoise));
  }
}

torch::Tensor DdpmPlanner::PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal,
                                         const torch::Tensor& noise, const torch::Tensor& renoise,
                                         const torch::Tensor& obstacles,
                                         const guidance::GuidanceConfig* settings) const {
  CheckRequest(start, goal, noise, renoise);
  torch::NoGradGuard no_grad;
  const guidance::GuidanceConfig& config = settings != nullptr ? *settings : guidance_.config;
  const std::unique_ptr<guidance::Guide> guide = MakeCallGuide(guidance_, normalizer_, config, obstacles);
  const torch::Tensor obstacles_f = guide ? obstacles.to(torch::kFloat32) : torch::Tensor();
  const torch::Tensor start_raw = start.to(torch::kFloat32), goal_raw = goal.to(torch::kFloat32);
  // The network's device (config `device`); guidance runs on the CPU, where the robot's kinematics live.
  const torch::Device device = models::DeviceOf(*net_);
  const torch::Tensor s = normalizer_.Normalize(start_raw).to(device), g = normalizer_.Normalize(goal_raw).to(device);
  const bool inpaint = conditioning_ == models::Conditioning::kInpaint;
  const torch::Tensor cond = models::ConditionVector(conditioning_, s, g);
  auto project = [&](const torch::Tensor& x) { return inpaint ? models::Inpaint(x, s, g) : x; };
  const int64_t B = start.size(0);
  const int guided_steps = GuidedSteps();
  const torch::Tensor renoise_f = renoise.to(device, torch::kFloat32);
  // One denoising step at k: the posterior mean, guided; the caller adds noise.
  auto denoise = [&](const torch::Tensor& x, int k, bool guided) {
    const torch::Tensor t = torch::full({B}, static_cast<double>(k), x.options());
    const torch::Tensor eps = net_->Forward(x, t, cond);
    const torch::Tensor x0 = (x0_from_x_[k] * x - x0_from_eps_[k] * eps).clamp(-1.0, 1.0);
    torch::Tensor mean = c1_[k] * x0 + c2_[k] * x;
    if (guided && guide) {
      for (int i = 0; i < sampler_.guide_iterations; ++i) {
        mean = project(mean - config.scale * guide->Gradient(mean.to(torch::kCPU), obstacles_f).to(device));
      }
    }
    return mean;
  };
  torch::Tensor x = project(noise.to(device, torch::kFloat32));
  for (int k = schedule_.steps - 1; k >= 0; --k) {
    x = denoise(x, k, k < guided_steps);
    if (k > 0) x = x + (sampler_.noise_scale * std_[k]) * renoise_f.select(1, schedule_.steps - 1 - k);
    x = project(x);
  }
  for (int e = 0; e < sampler_.extra_steps; ++e) x = project(denoise(x, 0, true));
  const torch::Tensor plan = normalizer_.Denormalize(x.to(torch::kCPU));
  return inpaint ? models::Inpaint(plan, start_raw, goal_raw) : plan;
}

PlanResult DdpmPlanner::Plan(const PlanRequest& request) const {
  const auto started = std::chrono::steady_clock::now();
  CheckEnds(request.start, request.goal, state_dim(), "plan");
  auto generator = at::make_generator<at::CPUGeneratorImpl>(request.seed);
  const int64_t B = request.start.size(0);
  const torch::Tensor noise = torch::randn({B, horizon_, state_dim()}, generator, torch::kFloat32);
  const torch::Tensor renoise =
      torch::randn({B, schedule_.steps - 1, horizon_, state_dim()}, generator, torch::kFloat32);
  PlanResult result;
  result.plans = PlanWithNoise(request.start, request.goal, noise, renoise, request.obstacles,
                               request.guidance ? &*request.guidance : nullptr);
  result.found = torch::ones({B}, torch::kBool);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.seconds.assign(static_cast<size_t>(B), seconds);
  return result;
}

void DdpmPlanner::WriteScript(jit::ScriptModule& module) const {
  const bool inpaint = conditioning_ == models::Conditioning::kInpaint;
  const int64_t N = schedule_.steps;
  const std::string D = std::to_string(state_dim()), T = std::to_string(horizon_), N1 = std::to_string(N - 1);
  WritePlanningSupport(module, normalizer_, guidance_);
  WriteTrajectoryNetwork(module, *net_, conditioning_, horizon_, "noise_prediction");
  auto list = [](const std::vector<double>& values) {
    std::string out = "[";
    for (size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + jit::ScriptFloat(values[i]);
    return out + "]";
  };
  std::string s = R"PY(
def denoise(self, x: Tensor, k: int, cond: Optional[Tensor], s: Tensor, g: Tensor, guided: Optional[Tensor], scale: float) -> Tensor:
    x0_from_x = )PY" + list(x0_from_x_) + R"PY(
    x0_from_eps = )PY" + list(x0_from_eps_) + R"PY(
    c1 = )PY" + list(c1_) + R"PY(
    c2 = )PY" + list(c2_) + R"PY(
    t = torch.full([x.size(0)], float(k), dtype=x.dtype, device=x.device)
    eps = self.network(x, t, cond)
    x0 = torch.clamp(x0_from_x[k] * x - x0_from_eps[k] * eps, -1.0, 1.0)
    mean = c1[k] * x0 + c2[k] * x
    if guided is not None:
        for i in range()PY" + std::to_string(sampler_.guide_iterations) + R"PY():
            mean = mean - scale * self.guide_gradient(mean, guided)
)PY";
  if (inpaint) s += "            mean = self.inpaint(mean, s, g)\n";
  s += "    return mean\n";
  s += PlanPreamble(state_dim(), horizon_, guidance_.robot->workspace_dim());
  s += R"PY(    assert renoise is not None and renoise.dim() == 4 and renoise.size(0) == start.size(0) and renoise.size(1) == )PY" + N1 +
       " and renoise.size(2) == " + T + " and renoise.size(3) == " + D +
       R"PY(, "plan: renoise: expected the noise of the DDPM steps (B, )PY" + N1 + ", " + T + ", " + D + R"PY()"
    std = )PY" + list(std_) + R"PY(
)PY";
  s += inpaint ? "    cond: Optional[Tensor] = None\n    x = self.inpaint(noise.float(), s, g)\n"
               : "    cond: Optional[Tensor] = torch.cat([s, g], -1)\n    x = noise.float()\n";
  s += "    noise_after = renoise.float()\n";
  s += "    for j in range(" + std::to_string(N) + "):\n";
  s += "        k = " + std::to_string(N - 1) + " - j\n";
  s += "        x = self.denoise(x, k, cond, s, g, guided if k < " + std::to_string(GuidedSteps()) +
       " else None, guidance_scale)\n";
  s += "        if k > 0:\n";
  s += "            x = x + (" + jit::ScriptFloat(sampler_.noise_scale) + " * std[k]) * noise_after[:, j]\n";
  if (inpaint) s += "        x = self.inpaint(x, s, g)\n";
  s += "    for e in range(" + std::to_string(sampler_.extra_steps) + "):\n";
  s += "        x = self.denoise(x, 0, cond, s, g, guided, guidance_scale)\n";
  if (inpaint) s += "        x = self.inpaint(x, s, g)\n";
  s += inpaint ? "    return self.inpaint(self.denormalize(x), start, goal)\n" : "    return self.denormalize(x)\n";
  s += SampleMethod("[" + T + ", " + D + "]", "[" + N1 + ", " + T + ", " + D + "]");
  module.Define(s);
  module.Attribute("planner", c10::StringType::get(), std::string("ddpm"));
  WriteNoiseShapes(module, {horizon_, state_dim()}, {N - 1, horizon_, state_dim()});
  module.Attribute("horizon", c10::IntType::get(), horizon_);
  module.Attribute("state_dim", c10::IntType::get(), state_dim());
  module.Attribute("steps", c10::IntType::get(), N);
  module.Attribute("splitting", c10::StringType::get(), std::string("none"));
  module.Attribute("conditioning", c10::StringType::get(), std::string(config::EnumName(conditioning_)));
}

}  // namespace flowplan::planning
