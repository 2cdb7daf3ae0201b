#include "models/trajectory_net.h"

#include "core/error.h"
#include "core/format.h"
#include "jit/script_writer.h"

namespace flowplan::models {

std::string ShapeString(const torch::Tensor& tensor) {
  return tensor.defined() ? ShapeText(tensor.sizes().vec()) : "(undefined)";
}

void CheckTrajectoryInputs(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond,
                         int64_t state_dim, int64_t cond_dim) {
  if (!x.defined() || x.dim() != 3 || x.size(2) != state_dim) {
    throw Error("trajectory network: x: expected (B, T, " + std::to_string(state_dim) + "), got " + ShapeString(x));
  }
  const int64_t batch = x.size(0);
  if (!t.defined() || t.dim() != 1 || t.size(0) != batch) {
    throw Error("trajectory network: t: expected (" + std::to_string(batch) + ",), got " + ShapeString(t));
  }
  if (cond_dim == 0 && cond.defined()) {
    throw Error("trajectory network: cond: this network takes no global condition, got " + ShapeString(cond));
  }
  if (cond_dim > 0 && (!cond.defined() || cond.dim() != 2 || cond.size(0) != batch || cond.size(1) != cond_dim)) {
    throw Error("trajectory network: cond: expected (" + std::to_string(batch) + ", " + std::to_string(cond_dim) +
                "), got " + ShapeString(cond));
  }
}

torch::jit::Module ScriptNetwork(const TrajectoryNet& net, Kernels kernels) {
  const std::string D = std::to_string(net.state_dim()), C = std::to_string(net.cond_dim());
  jit::ModuleBuilder builder("TrajectoryNetwork");
  jit::ScriptWriter writer(builder, "p_");
  if (kernels == Kernels::kNative) net.WriteNativeKernel(writer);
  const std::string out = net.WriteScript(writer);  // the variable holding the output
  std::string source = R"PY(
def forward(self, x: Tensor, t: Tensor, cond: Optional[Tensor]) -> Tensor:
    assert x.dim() == 3 and x.size(2) == )PY" + D + R"PY(, "network: x: expected (B, T, )PY" + D + R"PY(), normalized, got " + str(x.shape)
    assert t.dim() == 1 and t.size(0) == x.size(0), "network: t: expected (B,) with the B of x, got " + str(t.shape)
)PY";
  source += net.cond_dim() == 0
                ? "    assert cond is None, \"network: cond: this network takes no condition; pass None\"\n"
                : "    assert cond is not None and cond.dim() == 2 and cond.size(0) == x.size(0) and cond.size(1) == " + C +
                      ", \"network: cond: expected (B, " + C + "), the normalized start and goal\"\n";
  source += writer.Body(1) + "    return " + out + "\n";
  return builder.Attribute("state_dim", net.state_dim())
      .Attribute("cond_dim", net.cond_dim())
      .GeneratedMethods(source, "the network's forward pass")
      .Build();
}

void ReadScriptedWeights(TrajectoryNet& net, const torch::jit::Module& scripted, const std::string& where) {
  std::vector<torch::Tensor> weights;  // every parameter and buffer, in one numbering of their elements
  for (auto& entry : net.named_parameters(true)) weights.push_back(entry.value());
  for (auto& entry : net.named_buffers(true)) weights.push_back(entry.value());
  int64_t count = 0;
  for (const torch::Tensor& w : weights) count += w.numel();
  // Markers are whole numbers that float32 holds exactly, far from the small constants a script may carry.
  constexpr double kFirst = 1 << 20, kEnd = 1 << 24;
  if (kFirst + static_cast<double>(count) > kEnd) {
    throw Error(where + ": a network of " + std::to_string(count) + " weights is too large to read back");
  }
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> kept;
  int64_t next = 0;
  for (torch::Tensor& w : weights) {
    kept.push_back(w.clone());
    w.copy_(torch::arange(kFirst + next, kFirst + next + w.numel(), torch::kFloat64).view(w.sizes()));
    next += w.numel();
  }
  const torch::jit::Module marked = ScriptNetwork(net, Kernels::kPortable);
  for (size_t i = 0; i < weights.size(); ++i) weights[i].copy_(kept[i]);
  torch::Tensor values = torch::empty({count}, torch::kFloat64);
  torch::Tensor written = torch::zeros({count}, torch::kBool);
  for (const auto& entry : marked.named_buffers(false)) {
    const std::string& name = entry.name;
    if (!scripted.hasattr(name) || !scripted.attr(name).isTensor()) {
      throw Error(where + ": the network has no weight " + name + " that its config's model.* asks for");
    }
    const torch::Tensor given = scripted.attr(name).toTensor();
    if (given.sizes() != entry.value.sizes()) {
      throw Error(where + ": network weight " + name + " is " + ShapeString(given) + ", its config's model.* makes it " +
                  ShapeString(entry.value));
    }
    const torch::Tensor marker = entry.value.to(torch::kFloat64).flatten();
    const torch::Tensor value = given.to(torch::kFloat64).flatten();
    const torch::Tensor is_marker = (marker >= kFirst) & (marker < kFirst + count) & (marker == marker.round());
    if (!torch::equal(marker.masked_select(~is_marker), value.masked_select(~is_marker))) {
      throw Error(where + ": network weight " + name + " is not a rearrangement of the network's weights");
    }
    const torch::Tensor index = (marker.masked_select(is_marker) - kFirst).to(torch::kLong);
    values.index_put_({index}, value.masked_select(is_marker));
    written.index_put_({index}, true);
  }
  if (!written.all().item<bool>()) {
    throw Error(where + ": " + std::to_string(count - written.sum().item<int64_t>()) +
                " of the network's weights are not in its script");
  }
  next = 0;
  for (torch::Tensor& w : weights) {
    w.copy_(values.slice(0, next, next + w.numel()).view(w.sizes()));
    next += w.numel();
  }
}

}  // namespace flowplan::models

namespace flowplan::models {

void CheckHalfHorizon(const TrajectoryNet& net, int64_t horizon, const std::string& what) {
  try {
    if (horizon % 2 != 0) throw Error("the horizon " + std::to_string(horizon) + " is odd");
    net.CheckHorizon(horizon / 2);
  } catch (const Error& e) {
    throw Error(what + " halves of " + std::to_string(horizon / 2) + " states, which the network cannot take: " +
                e.what());
  }
}

}  // namespace flowplan::models
