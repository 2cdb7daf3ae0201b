#include "planning/flow_planner.h"

#include <chrono>

#include "core/error.h"
#include "guidance/scene.h"
#include "models/device.h"
#include "planning/script_parts.h"

namespace flowplan::planning {

using models::ShapeString;

FlowPlanner::FlowPlanner(models::TrajectoryNetPtr net, models::MinMaxNormalizer normalizer,
                         Conditioning conditioning, int64_t horizon, SamplerConfig sampler, GuidanceSetup guidance)
    : net_(std::move(net)),
      normalizer_(std::move(normalizer)),
      conditioning_(conditioning),
      horizon_(horizon),
      sampler_(sampler),
      guidance_(std::move(guidance)) {
  FLOWPLAN_DEMAND(net_ != nullptr);
  FLOWPLAN_DEMAND(normalizer_.dim() == net_->state_dim());
  FLOWPLAN_DEMAND(net_->cond_dim() == ConditionDim(conditioning_, net_->state_dim()));
  net_->CheckHorizon(horizon_);
  if (sampler_.steps < 1) throw Error("sampler.steps: expected a positive value, got " + std::to_string(sampler_.steps));
  if (sampler_.splitting != Splitting::kNone) models::CheckHalfHorizon(*net_, horizon_, "sampler.splitting plans");
  if (guidance_.robot && guidance_.robot->num_joints() > state_dim()) {
    throw Error("robot \"" + guidance_.robot->description().name + "\" has " +
                std::to_string(guidance_.robot->num_joints()) + " joints, more than the " +
                std::to_string(state_dim()) + " state dimensions the planner plans");
  }
}

void FlowPlanner::CheckRequest(const torch::Tensor& start, const torch::Tensor& goal, const torch::Tensor& noise,
                               const torch::Tensor& renoise) const {
  CheckEnds(start, goal, state_dim(), "plan");
  const std::string want_noise = "(" + std::to_string(start.size(0)) + ", " + std::to_string(horizon_) + ", " +
                                 std::to_string(state_dim()) + ")";
  auto noise_ok = [&](const torch::Tensor& n) {
    return n.defined() && n.dim() == 3 && n.size(0) == start.size(0) && n.size(1) == horizon_ &&
           n.size(2) == state_dim();
  };
  if (!noise_ok(noise)) throw Error("plan: noise: expected " + want_noise + ", got " + ShapeString(noise));
  if (sampler_.splitting != Splitting::kNone && !noise_ok(renoise)) {
    throw Error("plan: renoise: sampler.splitting needs re-noising noise " + want_noise + ", got " + ShapeString(renoise));
  }
}

VelocityField FlowPlanner::Velocity(const torch::Tensor& start_n, const torch::Tensor& goal_n) const {
  const torch::Tensor cond = ConditionVector(conditioning_, start_n, goal_n);
  const bool inpaint = conditioning_ == Conditioning::kInpaint;
  return [this, cond, inpaint, start_n, goal_n](const torch::Tensor& x, const torch::Tensor& t) {
    return net_->Forward(inpaint ? Inpaint(x, start_n, goal_n) : x, t, cond);
  };
}

torch::Tensor FlowPlanner::Integrate(const torch::Tensor& x, const torch::Tensor& start_n, const torch::Tensor& goal_n,
                                     const TimeGrid& grid, const guidance::Guide* guide, const torch::Tensor& obstacles,
                                     double scale) const {
  StateProjection project;
  if (conditioning_ == Conditioning::kInpaint) {
    project = [&](const torch::Tensor& state) { return Inpaint(state, start_n, goal_n); };
  }
  StepCorrection correct;
  if (guide != nullptr) {
    // Guidance runs on the CPU, where the robot's kinematics live (a no-op move there).
    correct = [&](const torch::Tensor& state, double t) {
      return guide->Step(state.to(torch::kCPU), t, obstacles, scale).to(state.device());
    };
  }
  return IntegrateEuler(x, Velocity(start_n, goal_n), grid, project, correct);
}

torch::Tensor FlowPlanner::PlanNormalized(const torch::Tensor& start_n, const torch::Tensor& goal_n,
                                          const torch::Tensor& noise, const torch::Tensor& renoise,
                                          const guidance::Guide* guide, const torch::Tensor& obstacles,
                                          double scale) const {
  CheckRequest(start_n, goal_n, noise, renoise);
  torch::Tensor x = Integrate(noise, start_n, goal_n, TimeGrid{0.0, 1.0, sampler_.steps}, guide, obstacles, scale);
  if (sampler_.splitting == Splitting::kNone) return x;

  // Midpoint splitting: the states on either side of the middle become the
  // boundaries of the two halves, so the joined plan has no duplicate state.
  const int64_t B = x.size(0), half = horizon_ / 2;
  const torch::Tensor before_mid = x.select(1, half - 1), after_mid = x.select(1, half);
  x = 0.5 * renoise + 0.5 * x;  // back to t = 0.5 on the OT path
  const torch::Tensor halves = torch::cat({x.slice(1, 0, half), x.slice(1, half, horizon_)}, 0);  // (2B, T/2, D)
  const torch::Tensor starts = torch::cat({start_n, after_mid}, 0);
  const torch::Tensor goals = torch::cat({before_mid, goal_n}, 0);
  const torch::Tensor refined =
      Integrate(halves, starts, goals, TimeGrid{0.5, 1.0, SplitSteps(sampler_)}, guide, obstacles, scale);
  return torch::cat({refined.slice(0, 0, B), refined.slice(0, B, 2 * B)}, 1);
}

std::unique_ptr<guidance::Guide> MakeCallGuide(const GuidanceSetup& setup, const models::MinMaxNormalizer& normalizer,
                                               const guidance::GuidanceConfig& config, const torch::Tensor& obstacles) {
  if (!obstacles.defined() || obstacles.numel() == 0 || config.scale == 0.0) return nullptr;
  if (!setup.robot) throw Error("plan: obstacles: this planner has no robot description to guide with");
  guidance::CheckObstacles(obstacles, static_cast<int>(setup.robot->workspace_dim()), "plan: obstacles");
  return std::make_unique<guidance::Guide>(guidance::MakeGuidanceCost(config, setup.robot, setup.dt), normalizer,
                                           config);
}

torch::Tensor FlowPlanner::PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal,
                                         const torch::Tensor& noise, const torch::Tensor& renoise,
                                         const torch::Tensor& obstacles,
                                         const guidance::GuidanceConfig* settings) const {
  CheckRequest(start, goal, noise, renoise);
  torch::NoGradGuard no_grad;
  const guidance::GuidanceConfig& config = settings != nullptr ? *settings : guidance_.config;
  const std::unique_ptr<guidance::Guide> guide = MakeCallGuide(guidance_, normalizer_, config, obstacles);
  const torch::Tensor start_raw = start.to(torch::kFloat32), goal_raw = goal.to(torch::kFloat32);
  const torch::Tensor obstacles_f = guide ? obstacles.to(torch::kFloat32) : torch::Tensor();
  const torch::Device device = models::DeviceOf(*net_);  // config `device`; plans come back to the CPU
  const torch::Tensor plan_n =
      PlanNormalized(normalizer_.Normalize(start_raw).to(device), normalizer_.Normalize(goal_raw).to(device),
                     noise.to(device, torch::kFloat32),
                     renoise.defined() ? renoise.to(device, torch::kFloat32) : renoise, guide.get(), obstacles_f,
                     config.scale)
          .to(torch::kCPU);
  const torch::Tensor plan = normalizer_.Denormalize(plan_n);
  // The ends are the requested states exactly, not their normalize/clamp round trip.
  return conditioning_ == Conditioning::kInpaint ? Inpaint(plan, start_raw, goal_raw) : plan;
}

PlanResult FlowPlanner::Plan(const PlanRequest& request) const {
  const auto started = std::chrono::steady_clock::now();
  CheckEnds(request.start, request.goal, state_dim(), "plan");
  auto generator = at::make_generator<at::CPUGeneratorImpl>(request.seed);
  const std::vector<int64_t> shape = {request.start.size(0), horizon_, state_dim()};
  const torch::Tensor noise = torch::randn(shape, generator, torch::kFloat32);
  const torch::Tensor renoise =
      sampler_.splitting == Splitting::kNone ? torch::Tensor() : torch::randn(shape, generator, torch::kFloat32);
  PlanResult result;
  result.plans = PlanWithNoise(request.start, request.goal, noise, renoise, request.obstacles,
                               request.guidance ? &*request.guidance : nullptr);
  result.found = torch::ones({request.start.size(0)}, torch::kBool);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.seconds.assign(static_cast<size_t>(request.start.size(0)), seconds);
  return result;
}

void FlowPlanner::WriteScript(jit::ScriptModule& module) const {
  const bool inpaint = conditioning_ == Conditioning::kInpaint;
  const bool splitting = sampler_.splitting != Splitting::kNone;
  const std::string D = std::to_string(state_dim());
  const std::string T = std::to_string(horizon_);
  const std::string H = std::to_string(horizon_ / 2);
  WritePlanningSupport(module, normalizer_, guidance_);
  WriteTrajectoryNetwork(module, *net_, conditioning_, horizon_, "velocity");

  std::string s = R"PY(
def integrate(self, x: Tensor, s: Tensor, g: Tensor, t0: float, steps: int, obstacles: Optional[Tensor], scale: float) -> Tensor:
)PY";
  s += inpaint ? "    cond: Optional[Tensor] = None\n    x = self.inpaint(x, s, g)\n"
               : "    cond: Optional[Tensor] = torch.cat([s, g], -1)\n";
  s += R"PY(    h = (1.0 - t0) / steps
    for i in range(steps):
        t = torch.full([x.size(0)], t0 + i * h, dtype=x.dtype, device=x.device)
)PY";
  s += inpaint ? "        x = x + h * self.network(self.inpaint(x, s, g), t, cond)\n"
               : "        x = x + h * self.network(x, t, cond)\n";
  s += R"PY(        if obstacles is not None:
            x = self.guide(x, t0 + (i + 1) * h, obstacles, scale)
)PY";
  if (inpaint) s += "        x = self.inpaint(x, s, g)\n";
  s += "    return x\n";
  s += PlanPreamble(state_dim(), horizon_, guidance_.robot->workspace_dim());
  s += "    x = self.integrate(noise.float(), s, g, 0.0, " + std::to_string(sampler_.steps) + ", guided, guidance_scale)\n";
  if (splitting) {
    s += R"PY(    assert renoise is not None, "plan: renoise: this planner splits trajectories and needs re-noising noise (B, )PY" + T + ", " + D + R"PY()"
    assert renoise.size() == noise.size(), "plan: renoise: expected the shape of noise"
    B = x.size(0)
    before_mid = x[:, )PY" + H + R"PY( - 1]
    after_mid = x[:, )PY" + H + R"PY(]
    x = 0.5 * renoise.float() + 0.5 * x
    halves = torch.cat([x[:, 0:)PY" + H + "], x[:, " + H + ":" + T + R"PY(]], 0)
    refined = self.integrate(halves, torch.cat([s, after_mid], 0), torch.cat([before_mid, g], 0), 0.5, )PY" +
         std::to_string(SplitSteps(sampler_)) + R"PY(, guided, guidance_scale)
    x = torch.cat([refined[0:B], refined[B:2 * B]], 1)
)PY";
  }
  s += inpaint ? "    return self.inpaint(self.denormalize(x), start, goal)\n" : "    return self.denormalize(x)\n";
  s += SampleMethod("[" + T + ", " + D + "]", splitting ? "[" + T + ", " + D + "]" : "");
  module.Define(s);

  module.Attribute("planner", c10::StringType::get(), std::string("flow_matching"));
  WriteNoiseShapes(module, {horizon_, state_dim()}, splitting ? std::vector<int64_t>{horizon_, state_dim()}
                                                              : std::vector<int64_t>{});
  module.Attribute("horizon", c10::IntType::get(), horizon_);
  module.Attribute("state_dim", c10::IntType::get(), state_dim());
  module.Attribute("steps", c10::IntType::get(), static_cast<int64_t>(sampler_.steps));
  module.Attribute("splitting", c10::StringType::get(), std::string(config::EnumName(sampler_.splitting)));
  module.Attribute("conditioning", c10::StringType::get(), std::string(config::EnumName(conditioning_)));
}

}  // namespace flowplan::planning
