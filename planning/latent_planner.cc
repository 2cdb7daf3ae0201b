#include "planning/latent_planner.h"

#include <chrono>

#include "core/error.h"
#include "models/device.h"
#include "guidance/collision_cost.h"
#include "guidance/scene.h"
#include "planning/script_parts.h"

namespace flowplan::planning {
namespace {

constexpr double kAdamBeta1 = 0.9;
constexpr double kAdamBeta2 = 0.999;
constexpr double kAdamEpsilon = 1e-8;
constexpr double kMinDistance = 1e-9;

}  // namespace

LatentPlanner::LatentPlanner(std::shared_ptr<models::StateVae> vae, models::MinMaxNormalizer normalizer,
                             int64_t horizon, LatentPlannerConfig config, GuidanceSetup guidance)
    : vae_(std::move(vae)),
      normalizer_(std::move(normalizer)),
      horizon_(horizon),
      config_(config),
      guidance_(std::move(guidance)) {
  FLOWPLAN_DEMAND(vae_ != nullptr && normalizer_.dim() == vae_->state_dim());
  if (!guidance_.robot) throw Error("latent planner: the planner has no robot description (its goal is a TCP point)");
  if (horizon_ < 2) throw Error("latent planner: expected a horizon of at least 2 states");
  // Its optimization interleaves the decoder with the robot's kinematics, which live on the CPU.
  if (!models::DeviceOf(*vae_).is_cpu()) throw Error("device: the VAE planner runs on the CPU only; set device=cpu");
}

torch::Tensor LatentPlanner::PlanWithNoise(const torch::Tensor& start, const torch::Tensor& goal,
                                           const torch::Tensor& noise, const torch::Tensor& obstacles,
                                           const guidance::GuidanceConfig* settings) const {
  CheckEnds(start, goal, state_dim(), "plan");
  const int64_t B = start.size(0), D = state_dim(), L = vae_->latent_dim(), J = guidance_.robot->num_joints();
  if (!noise.defined() || noise.sizes() != torch::IntArrayRef({B, L})) {
    throw Error("plan: noise: expected the latent noise (" + std::to_string(B) + ", " + std::to_string(L) + "), got " +
                models::ShapeString(noise));
  }
  torch::NoGradGuard no_grad;
  const guidance::GuidanceConfig& guidance = settings != nullptr ? *settings : guidance_.config;
  std::unique_ptr<guidance::CollisionCost> collision;
  if (obstacles.defined() && obstacles.numel() > 0 && guidance.scale != 0.0 && guidance.collision_weight != 0.0) {
    guidance::CheckObstacles(obstacles, static_cast<int>(guidance_.robot->workspace_dim()), "plan: obstacles");
    collision = std::make_unique<guidance::CollisionCost>(guidance_.robot, guidance.margin);
  }
  const torch::Tensor obstacles_f = collision ? obstacles.to(torch::kFloat32) : torch::Tensor();
  const torch::Tensor start_raw = start.to(torch::kFloat32), goal_raw = goal.to(torch::kFloat32);
  const torch::Tensor goal_tcp = guidance_.robot->Tcp(goal_raw.slice(1, 0, J));  // (B, W)
  const torch::Tensor scale = 0.5 * (normalizer_.hi() - normalizer_.lo());       // (D,)
  const models::StateVae::Encoding encoding = vae_->Encode(normalizer_.Normalize(start_raw));
  torch::Tensor z = encoding.mean + (0.5 * encoding.log_var).exp() * noise.to(torch::kFloat32);
  torch::Tensor m = torch::zeros_like(z), v = torch::zeros_like(z);
  torch::Tensor done = torch::zeros({B, 1}, torch::kFloat32);  // 1 once a waypoint reached the goal
  std::vector<torch::Tensor> waypoints = {start_raw};
  int64_t adam_step = 0;
  for (int64_t i = 1; i < horizon_; ++i) {
    for (int it = 0; it < config_.iterations; ++it) {
      const torch::Tensor x = normalizer_.DenormalizeUnclamped(vae_->Decode(z));  // (B, D) raw
      const torch::Tensor q = x.slice(1, 0, J);
      const torch::Tensor diff = guidance_.robot->Tcp(q) - goal_tcp;
      const torch::Tensor direction = diff / diff.norm(2, 1, true).clamp_min(kMinDistance);
      torch::Tensor gradient = torch::cat(
          {config_.goal_weight * guidance_.robot->TcpVjp(q, direction), torch::zeros({B, D - J})}, 1);  // raw
      if (collision) {
        torch::Tensor part = collision->ValueAndGradient(x.view({B, 1, D}), obstacles_f).gradient.view({B, D});
        if (guidance.clip > 0.0) part = part / (part.norm(2, -1, true).clamp_min(guidance.clip) / guidance.clip);
        gradient = gradient + (guidance.scale * guidance.collision_weight) * part;
      }
      const torch::Tensor g = vae_->DecodeVjp(z, gradient * scale) + config_.prior_weight * z;
      ++adam_step;
      m = kAdamBeta1 * m + (1.0 - kAdamBeta1) * g;
      v = kAdamBeta2 * v + (1.0 - kAdamBeta2) * g * g;
      const double m_correction = 1.0 - std::pow(kAdamBeta1, static_cast<double>(adam_step));
      const double v_correction = 1.0 - std::pow(kAdamBeta2, static_cast<double>(adam_step));
      const torch::Tensor update = (m / m_correction) / ((v / v_correction).sqrt() + kAdamEpsilon);
      z = z - (config_.lr * update) * (1.0 - done);
    }
    const torch::Tensor waypoint = normalizer_.Denormalize(vae_->Decode(z));
    const torch::Tensor next = done * waypoints.back() + (1.0 - done) * waypoint;
    waypoints.push_back(next);
    const torch::Tensor reached =
        ((guidance_.robot->Tcp(next.slice(1, 0, J)) - goal_tcp).norm(2, 1, true) < config_.goal_tolerance);
    done = torch::max(done, reached.to(torch::kFloat32));
  }
  return torch::stack(waypoints, 1);
}

PlanResult LatentPlanner::Plan(const PlanRequest& request) const {
  const auto started = std::chrono::steady_clock::now();
  CheckEnds(request.start, request.goal, state_dim(), "plan");
  auto generator = at::make_generator<at::CPUGeneratorImpl>(request.seed);
  const int64_t B = request.start.size(0);
  const torch::Tensor noise = torch::randn({B, vae_->latent_dim()}, generator, torch::kFloat32);
  PlanResult result;
  result.plans = PlanWithNoise(request.start, request.goal, noise, request.obstacles,
                               request.guidance ? &*request.guidance : nullptr);
  result.found = torch::ones({B}, torch::kBool);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  result.seconds.assign(static_cast<size_t>(B), seconds);
  return result;
}

void LatentPlanner::WriteScript(jit::ScriptModule& module) const {
  const int64_t D = state_dim(), L = vae_->latent_dim(), J = guidance_.robot->num_joints();
  const std::string Ds = std::to_string(D), Ls = std::to_string(L), Js = std::to_string(J);
  WritePlanningSupport(module, normalizer_, guidance_);
  vae_->WriteScript(module);
  const bool collides = guidance_.config.collision_weight != 0.0;
  const guidance::GuidanceConfig& g = guidance_.config;
  std::string s = R"PY(
def plan(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor] = None, obstacles: Optional[Tensor] = None, scale: Optional[float] = None) -> Tensor:
    assert start.dim() == 2 and start.size(1) == )PY" + Ds + R"PY(, "plan: start: expected (B, )PY" + Ds + R"PY()"
    assert goal.dim() == 2 and goal.size(0) == start.size(0) and goal.size(1) == )PY" + Ds + R"PY(, "plan: goal: expected the shape of start"
    assert noise.dim() == 2 and noise.size(0) == start.size(0) and noise.size(1) == )PY" + Ls + R"PY(, "plan: noise: expected the latent noise (B, )PY" + Ls + R"PY()"
    guidance_scale = self.guidance_scale if scale is None else scale
    assert guidance_scale >= 0.0, "plan: scale: expected a non-negative guidance scale"
    guided: Optional[Tensor] = None
    if obstacles is not None:
        assert obstacles.dim() == 2 and obstacles.size(1) == )PY" + std::to_string(guidance_.robot->workspace_dim() + 1) + R"PY(, "plan: obstacles: expected (K, W + 1) rows of centre and radius"
        assert bool(torch.isfinite(obstacles).all()), "plan: obstacles: expected finite values"
        assert bool((obstacles[:, -1] >= 0).all()), "plan: obstacles: expected non-negative radii"
        if obstacles.size(0) > 0 and guidance_scale != 0.0 and )PY" + (collides ? "True" : "False") + R"PY(:
            guided = obstacles.float()
    B = start.size(0)
    start = start.float()
    goal = goal.float()
    goal_tcp = self.robot_tcp(goal[:, 0:)PY" + Js + R"PY(])
    scale_n = 0.5 * (self.hi - self.lo)
    mean, log_var = self.vae_encode(self.normalize(start))
    z = mean + torch.exp(0.5 * log_var) * noise.float()
    m = torch.zeros_like(z)
    v = torch.zeros_like(z)
    done = torch.zeros([B, 1], dtype=z.dtype, device=z.device)
    waypoints = [start]
    adam_step = 0
    for i in range()PY" + std::to_string(horizon_ - 1) + R"PY():
        for it in range()PY" + std::to_string(config_.iterations) + R"PY():
            x = self.denormalize_unclamped(self.vae_decode(z))
            q = x[:, 0:)PY" + Js + R"PY(]
            diff = self.robot_tcp(q) - goal_tcp
            direction = diff / torch.norm(diff, 2, 1, True).clamp_min()PY" + jit::ScriptFloat(kMinDistance) + R"PY()
            gradient = torch.cat([)PY" + jit::ScriptFloat(config_.goal_weight) + " * self.robot_tcp_vjp(q, direction), torch.zeros([B, " +
       std::to_string(D - J) + R"PY(], dtype=z.dtype, device=z.device)], 1)
)PY";
  if (collides) {
    s += R"PY(            if guided is not None:
                value, part = self.guidance_cost_collision(x.view(B, 1, )PY" + Ds + R"PY(), guided)
                part = part.view(B, )PY" + Ds + R"PY()
)PY";
    if (g.clip > 0.0) {
      const std::string clip = jit::ScriptFloat(g.clip);
      s += "                part = part / (torch.norm(part, 2, -1, True).clamp_min(" + clip + ") / " + clip + ")\n";
    }
    s += "                gradient = gradient + (guidance_scale * " + jit::ScriptFloat(g.collision_weight) + ") * part\n";
  }
  s += R"PY(            grad = self.vae_decode_vjp(z, gradient * scale_n) + )PY" + jit::ScriptFloat(config_.prior_weight) + R"PY( * z
            adam_step += 1
            m = )PY" + jit::ScriptFloat(kAdamBeta1) + " * m + " + jit::ScriptFloat(1.0 - kAdamBeta1) + R"PY( * grad
            v = )PY" + jit::ScriptFloat(kAdamBeta2) + " * v + " + jit::ScriptFloat(1.0 - kAdamBeta2) + R"PY( * grad * grad
            m_correction = 1.0 - )PY" + jit::ScriptFloat(kAdamBeta1) + R"PY( ** float(adam_step)
            v_correction = 1.0 - )PY" + jit::ScriptFloat(kAdamBeta2) + R"PY( ** float(adam_step)
            update = (m / m_correction) / (torch.sqrt(v / v_correction) + )PY" + jit::ScriptFloat(kAdamEpsilon) + R"PY()
            z = z - ()PY" + jit::ScriptFloat(config_.lr) + R"PY( * update) * (1.0 - done)
        waypoint = self.denormalize(self.vae_decode(z))
        nxt = done * waypoints[-1] + (1.0 - done) * waypoint
        waypoints.append(nxt)
        reached = torch.norm(self.robot_tcp(nxt[:, 0:)PY" + Js + R"PY(]) - goal_tcp, 2, 1, True) < )PY" + jit::ScriptFloat(config_.goal_tolerance) + R"PY(
        done = torch.max(done, reached.to(z.dtype))
    return torch.stack(waypoints, 1)
)PY";
  s += SampleMethod("[" + Ls + "]", "");
  module.Define(s);
  module.Attribute("planner", c10::StringType::get(), std::string("latent"));
  WriteNoiseShapes(module, {L}, {});
  module.Attribute("horizon", c10::IntType::get(), horizon_);
  module.Attribute("state_dim", c10::IntType::get(), D);
  module.Attribute("steps", c10::IntType::get(), static_cast<int64_t>(config_.iterations));
  module.Attribute("splitting", c10::StringType::get(), std::string("none"));
  module.Attribute("conditioning", c10::StringType::get(), std::string("none"));
}

}  // namespace flowplan::planning
