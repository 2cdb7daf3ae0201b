#include "planning/export.h"

#include "core/atomic_file.h"
#include "core/error.h"
#include "models/script_writer.h"

namespace flowplan::planning {
namespace {

// Bumped whenever the methods or attributes of the exported module change.
constexpr int64_t kExportFormatVersion = 2;  // 2: velocity() checks its arguments

std::string PlannerSource(const FlowPlanner& planner, const std::string& velocity_body) {
  const bool inpaint = planner.conditioning() == Conditioning::kInpaint;
  const bool splitting = planner.sampler().splitting != Splitting::kNone;
  const std::string D = std::to_string(planner.state_dim());
  const std::string T = std::to_string(planner.horizon());
  const std::string H = std::to_string(planner.horizon() / 2);
  std::string s;
  // net_velocity is the network alone, called by the Euler loop; velocity is
  // the same for callers, with its arguments checked.
  s += "def net_velocity(self, x: Tensor, t: Tensor, cond: Optional[Tensor]) -> Tensor:\n";
  s += velocity_body;
  s += R"PY(
def velocity(self, x: Tensor, t: Tensor, cond: Optional[Tensor]) -> Tensor:
    assert x.dim() == 3 and x.size(1) == )PY" + T + " and x.size(2) == " + D + R"PY(, "velocity: x: expected (B, )PY" + T + ", " + D + R"PY(), normalized"
    assert t.dim() == 1 and t.size(0) == x.size(0), "velocity: t: expected (B,) with the B of x"
)PY";
  s += inpaint ? "    assert cond is None, \"velocity: cond: this planner conditions by inpainting; pass None\"\n"
               : "    assert cond is not None and cond.dim() == 2 and cond.size(0) == x.size(0) and cond.size(1) == " +
                     std::to_string(2 * planner.state_dim()) + ", \"velocity: cond: expected (B, " +
                     std::to_string(2 * planner.state_dim()) + "), the normalized start and goal\"\n";
  s += "    return self.net_velocity(x, t, cond)\n";
  s += R"PY(
def normalize(self, x: Tensor) -> Tensor:
    return (x - self.lo) / (self.hi - self.lo) * 2.0 - 1.0

def denormalize(self, x: Tensor) -> Tensor:
    return (torch.clamp(x, -1.0, 1.0) + 1.0) * 0.5 * (self.hi - self.lo) + self.lo

def inpaint(self, x: Tensor, start: Tensor, goal: Tensor) -> Tensor:
    return torch.cat([start.unsqueeze(1), x[:, 1:-1], goal.unsqueeze(1)], 1)

def integrate(self, x: Tensor, s: Tensor, g: Tensor, t0: float, steps: int) -> Tensor:
)PY";
  s += inpaint ? "    cond: Optional[Tensor] = None\n    x = self.inpaint(x, s, g)\n"
               : "    cond: Optional[Tensor] = torch.cat([s, g], -1)\n";
  s += "    h = (1.0 - t0) / steps\n";
  s += "    for i in range(steps):\n";
  s += "        t = torch.full([x.size(0)], t0 + i * h, dtype=x.dtype, device=x.device)\n";
  if (inpaint) {
    s += "        x = x + h * self.net_velocity(self.inpaint(x, s, g), t, cond)\n";
    s += "        x = self.inpaint(x, s, g)\n";
  } else {
    s += "        x = x + h * self.net_velocity(x, t, cond)\n";
  }
  s += "    return x\n";
  s += R"PY(
def plan(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor] = None) -> Tensor:
    assert start.dim() == 2 and start.size(1) == )PY" + D + R"PY(, "plan: start: expected (B, )PY" + D + R"PY()"
    assert goal.dim() == 2 and goal.size(0) == start.size(0) and goal.size(1) == )PY" + D + R"PY(, "plan: goal: expected the shape of start"
    assert noise.dim() == 3 and noise.size(0) == start.size(0) and noise.size(1) == )PY" + T + " and noise.size(2) == " + D + R"PY(, "plan: noise: expected (B, )PY" + T + ", " + D + R"PY()"
    start = start.float()
    goal = goal.float()
    s = self.normalize(start)
    g = self.normalize(goal)
    x = self.integrate(noise.float(), s, g, 0.0, )PY" + std::to_string(planner.sampler().steps) + R"PY()
)PY";
  if (splitting) {
    s += R"PY(    assert renoise is not None, "plan: renoise: this planner splits trajectories and needs re-noising noise (B, )PY" + T + ", " + D + R"PY()"
    assert renoise.size() == noise.size(), "plan: renoise: expected the shape of noise"
    B = x.size(0)
    before_mid = x[:, )PY" + H + R"PY( - 1]
    after_mid = x[:, )PY" + H + R"PY(]
    x = 0.5 * renoise.float() + 0.5 * x
    halves = torch.cat([x[:, 0:)PY" + H + "], x[:, " + H + ":" + T + R"PY(]], 0)
    refined = self.integrate(halves, torch.cat([s, after_mid], 0), torch.cat([before_mid, g], 0), 0.5, )PY" +
         std::to_string(SplitSteps(planner.sampler())) + R"PY()
    x = torch.cat([refined[0:B], refined[B:2 * B]], 1)
)PY";
  }
  s += inpaint ? "    return self.inpaint(self.denormalize(x), start, goal)\n" : "    return self.denormalize(x)\n";
  s += R"PY(
def sample(self, start: Tensor, goal: Tensor, num_samples: int) -> Tensor:
    assert start.dim() == 1 and goal.dim() == 1, "sample: expected start and goal of shape (D,)"
    noise = torch.randn([num_samples, )PY" + T + ", " + D + R"PY(], dtype=self.lo.dtype, device=self.lo.device)
)PY";
  s += splitting ? "    renoise: Optional[Tensor] = torch.randn([num_samples, " + T + ", " + D +
                       "], dtype=self.lo.dtype, device=self.lo.device)\n"
                 : "    renoise: Optional[Tensor] = None\n";
  s += "    return self.plan(start.unsqueeze(0).expand(num_samples, -1), goal.unsqueeze(0).expand(num_samples, -1), "
       "noise, renoise)\n";
  return s;
}

}  // namespace

torch::jit::Module BuildScriptPlanner(const FlowPlanner& planner, const ExportMetadata& metadata) {
  models::ScriptWriter writer;
  const std::string out = planner.net()->WriteScript(writer);
  writer.Line("return " + out);

  torch::jit::Module module("FlowPlanner");
  for (const auto& [name, tensor] : writer.tensors()) module.register_buffer(name, tensor);
  module.register_buffer("lo", planner.normalizer().lo().clone());
  module.register_buffer("hi", planner.normalizer().hi().clone());
  module.register_attribute("format_version", c10::IntType::get(), kExportFormatVersion);
  module.register_attribute("horizon", c10::IntType::get(), planner.horizon());
  module.register_attribute("state_dim", c10::IntType::get(), planner.state_dim());
  module.register_attribute("steps", c10::IntType::get(), static_cast<int64_t>(planner.sampler().steps));
  module.register_attribute("splitting", c10::StringType::get(),
                            std::string(config::EnumName(planner.sampler().splitting)));
  module.register_attribute("dt", c10::FloatType::get(), metadata.dt);
  module.register_attribute("env", c10::StringType::get(), metadata.env);
  module.register_attribute("conditioning", c10::StringType::get(),
                            std::string(config::EnumName(planner.conditioning())));
  c10::List<std::string> labels;
  for (const auto& label : metadata.state_labels) labels.push_back(label);
  module.register_attribute("state_labels", c10::ListType::ofStrings(), labels);
  module.register_attribute("config", c10::StringType::get(), metadata.config_yaml);

  const std::string source = PlannerSource(planner, writer.Body(1));
  try {
    module.define(source);
  } catch (const c10::Error& e) {
    throw InternalError(std::string("exported planner source does not compile: ") + e.what_without_backtrace());
  }
  return module;
}

void ExportPlanner(const FlowPlanner& planner, const ExportMetadata& metadata, const std::string& path) {
  torch::jit::Module module = BuildScriptPlanner(planner, metadata);
  AtomicFile file(path);
  try {
    module.save(file.temp_path());
  } catch (const c10::Error& e) {
    throw Error(path + ": cannot write the exported planner: " + e.what_without_backtrace());
  }
  file.Commit();
}

}  // namespace flowplan::planning
