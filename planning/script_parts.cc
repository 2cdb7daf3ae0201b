#include "planning/script_parts.h"

#include "core/error.h"
#include "planning/flow_planner.h"

namespace flowplan::planning {

void WriteTrajectoryNetwork(jit::ScriptModule& module, const models::TrajectoryNet& net,
                            models::Conditioning conditioning, int64_t horizon, const std::string& checked) {
  const std::string D = std::to_string(net.state_dim()), T = std::to_string(horizon);
  const std::string C = std::to_string(net.cond_dim());
  jit::ScriptWriter writer(module, "p_");
  const std::string out = net.WriteScript(writer);
  writer.Line("return " + out);
  module.Define("def network(self, x: Tensor, t: Tensor, cond: Optional[Tensor]) -> Tensor:\n" + writer.Body(1));
  std::string s = "def " + checked + R"PY((self, x: Tensor, t: Tensor, cond: Optional[Tensor]) -> Tensor:
    assert x.dim() == 3 and x.size(1) == )PY" + T + " and x.size(2) == " + D + ", \"" + checked +
                  ": x: expected (B, " + T + ", " + D + R"PY(), normalized"
    assert t.dim() == 1 and t.size(0) == x.size(0), ")PY" + checked + R"PY(: t: expected (B,) with the B of x"
)PY";
  s += conditioning == models::Conditioning::kInpaint
           ? "    assert cond is None, \"" + checked + ": cond: this planner conditions by inpainting; pass None\"\n"
           : "    assert cond is not None and cond.dim() == 2 and cond.size(0) == x.size(0) and cond.size(1) == " + C +
                 ", \"" + checked + ": cond: expected (B, " + C + "), the normalized start and goal\"\n";
  s += "    return self.network(x, t, cond)\n";
  module.Define(s);
}

void WritePlanningSupport(jit::ScriptModule& module, const models::MinMaxNormalizer& normalizer,
                          const GuidanceSetup& guidance) {
  if (!guidance.robot) throw Error("export: the planner has no robot description (retrain with a current dataset)");
  normalizer.WriteScript(module);
  guidance.robot->WriteScript(module);
  guidance::Guide(guidance::MakeGuidanceCost(guidance.config, guidance.robot, guidance.dt), normalizer, guidance.config)
      .WriteScript(module);
  module.Define(R"PY(
def inpaint(self, x: Tensor, start: Tensor, goal: Tensor) -> Tensor:
    return torch.cat([start.unsqueeze(1), x[:, 1:-1], goal.unsqueeze(1)], 1)
)PY");
  module.Attribute("guidance_scale", c10::FloatType::get(), guidance.config.scale);
  module.Attribute("guidance", c10::StringType::get(), config::ToYaml(guidance.config));
}

std::string PlanPreamble(int64_t state_dim, int64_t horizon, int64_t workspace_dim) {
  const std::string D = std::to_string(state_dim), T = std::to_string(horizon);
  const std::string K1 = std::to_string(workspace_dim + 1);
  return R"PY(
def plan(self, start: Tensor, goal: Tensor, noise: Tensor, renoise: Optional[Tensor] = None, obstacles: Optional[Tensor] = None, scale: Optional[float] = None) -> Tensor:
    assert start.dim() == 2 and start.size(1) == )PY" + D + R"PY(, "plan: start: expected (B, )PY" + D + R"PY()"
    assert goal.dim() == 2 and goal.size(0) == start.size(0) and goal.size(1) == )PY" + D + R"PY(, "plan: goal: expected the shape of start"
    assert noise.dim() == 3 and noise.size(0) == start.size(0) and noise.size(1) == )PY" + T + " and noise.size(2) == " + D + R"PY(, "plan: noise: expected (B, )PY" + T + ", " + D + R"PY()"
    guidance_scale = self.guidance_scale if scale is None else scale
    assert guidance_scale >= 0.0, "plan: scale: expected a non-negative guidance scale"
    guided: Optional[Tensor] = None
    if obstacles is not None:
        assert obstacles.dim() == 2 and obstacles.size(1) == )PY" + K1 + R"PY(, "plan: obstacles: expected (K, )PY" + K1 + R"PY() rows of centre and radius"
        assert bool(torch.isfinite(obstacles).all()), "plan: obstacles: expected finite values"
        assert bool((obstacles[:, -1] >= 0).all()), "plan: obstacles: expected non-negative radii"
        if obstacles.size(0) > 0 and guidance_scale != 0.0:
            guided = obstacles.float()
    start = start.float()
    goal = goal.float()
    s = self.normalize(start)
    g = self.normalize(goal)
)PY";
}

void WriteNoiseShapes(jit::ScriptModule& module, const std::vector<int64_t>& noise,
                      const std::vector<int64_t>& renoise) {
  module.Attribute("noise_shape", c10::ListType::ofInts(), c10::List<int64_t>(noise));
  module.Attribute("renoise_shape", c10::ListType::ofInts(), c10::List<int64_t>(renoise));
}

std::string SampleMethod(const std::string& noise_shape, const std::string& renoise_shape) {
  std::string s = R"PY(
def sample(self, start: Tensor, goal: Tensor, num_samples: int, obstacles: Optional[Tensor] = None, scale: Optional[float] = None) -> Tensor:
    assert start.dim() == 1 and goal.dim() == 1, "sample: expected start and goal of shape (D,)"
    noise = torch.randn([num_samples] + )PY" + noise_shape + R"PY(, dtype=self.lo.dtype, device=self.lo.device)
)PY";
  s += renoise_shape.empty()
           ? "    renoise: Optional[Tensor] = None\n"
           : "    renoise: Optional[Tensor] = torch.randn([num_samples] + " + renoise_shape +
                 ", dtype=self.lo.dtype, device=self.lo.device)\n";
  s += "    return self.plan(start.unsqueeze(0).expand(num_samples, -1), goal.unsqueeze(0).expand(num_samples, -1), "
       "noise, renoise, obstacles, scale)\n";
  return s;
}

}  // namespace flowplan::planning
