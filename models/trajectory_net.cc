#include "models/trajectory_net.h"

#include <map>

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
  torch::NoGradGuard no_grad;
  // Markers are whole numbers that float32 holds exactly, far from the small constants a script may carry; a
  // network of more elements than one pass can number is marked a window at a time (the rest set to zero).
  constexpr int64_t kFirst = int64_t{1} << 20, kWindow = (int64_t{1} << 24) - kFirst;
  std::vector<torch::Tensor> kept;
  for (const torch::Tensor& w : weights) kept.push_back(w.clone());
  struct Restore {  // the network's own weights back, however this ends
    std::vector<torch::Tensor>& weights;
    std::vector<torch::Tensor>& kept;
    ~Restore() {
      torch::NoGradGuard no_grad;
      for (size_t i = 0; i < weights.size(); ++i) weights[i].copy_(kept[i]);
    }
  } restore{weights, kept};
  torch::Tensor values = torch::empty({count}, torch::kFloat64);
  torch::Tensor written = torch::zeros({count}, torch::kBool);
  std::map<std::string, torch::Tensor> marked_somewhere;  // per script tensor: elements that held a marker
  std::map<std::string, torch::Tensor> constants;         // per script tensor: its values with every weight zero
  for (int64_t window = 0; window < count; window += kWindow) {
    int64_t next = 0;
    for (torch::Tensor& w : weights) {
      const torch::Tensor index = torch::arange(next, next + w.numel(), torch::kFloat64);
      const torch::Tensor inside = (index >= window) & (index < window + kWindow);
      w.copy_(torch::where(inside, index - window + kFirst, torch::zeros_like(index)).view(w.sizes()));
      next += w.numel();
    }
    const torch::jit::Module marked = ScriptNetwork(net, Kernels::kPortable);
    for (const auto& entry : marked.named_buffers(false)) {
      const std::string& name = entry.name;
      if (!scripted.hasattr(name) || !scripted.attr(name).isTensor()) {
        throw Error(where + ": the network has no weight " + name + " that its config's model.* asks for");
      }
      const torch::Tensor given = scripted.attr(name).toTensor();
      if (given.sizes() != entry.value.sizes()) {
        throw Error(where + ": network weight " + name + " is " + ShapeString(given) +
                    ", its config's model.* makes it " + ShapeString(entry.value));
      }
      const torch::Tensor marker = entry.value.to(torch::kFloat64).flatten();
      const torch::Tensor value = given.to(torch::kFloat64).flatten();
      const torch::Tensor is_marker = (marker >= kFirst) & (marker < kFirst + kWindow) & (marker == marker.round());
      auto [at, fresh] = marked_somewhere.emplace(name, is_marker.clone());
      if (!fresh) at->second |= is_marker;
      if (window == 0) constants[name] = marker.masked_fill(is_marker, 0.0);
      const torch::Tensor index = (marker.masked_select(is_marker) - kFirst).to(torch::kLong) + window;
      const torch::Tensor found = value.masked_select(is_marker);
      // An element written to several places must hold one value in all of them.
      const torch::Tensor before = values.index({index}), seen = written.index({index});
      if (!torch::equal(before.masked_select(seen), found.masked_select(seen))) {
        throw Error(where + ": network weight " + name + " holds one weight of the network twice, with two values");
      }
      values.index_put_({index}, found);
      written.index_put_({index}, true);
    }
  }
  // What is not a weight anywhere is a constant of the script: the file's must be the same.
  for (const auto& [name, mask] : marked_somewhere) {
    const torch::Tensor value = scripted.attr(name).toTensor().to(torch::kFloat64).flatten();
    if (!torch::equal(value.masked_select(~mask), constants.at(name).masked_select(~mask))) {
      throw Error(where + ": network weight " + name + " is not a rearrangement of the network's weights");
    }
  }
  if (!written.all().item<bool>()) {
    throw Error(where + ": " + std::to_string(count - written.sum().item<int64_t>()) +
                " of the network's weights are not in its script");
  }
  int64_t next = 0;
  for (torch::Tensor& kept_weight : kept) {  // what Restore writes back: the weights read
    kept_weight.copy_(values.slice(0, next, next + kept_weight.numel()).view(kept_weight.sizes()));
    next += kept_weight.numel();
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
