#include "models/transformer.h"

#include <cmath>

#include "core/error.h"
#include "models/mish.h"
#include "models/precision.h"

namespace flowplan::models {

void TransformerConfig::Validate() const {
  if (d_model % heads != 0) {
    throw Error("model.transformer.heads: expected a divisor of model.transformer.d_model (" + std::to_string(d_model) +
                "), got " + std::to_string(heads));
  }
  if (d_model % 2 != 0) throw Error("model.transformer.d_model: expected an even width, got " + std::to_string(d_model));
}

Transformer::Transformer(const TransformerConfig& config, int64_t state_dim, int64_t cond_dim)
    : config_(config), state_dim_(state_dim), cond_dim_(cond_dim) {
  config_.Validate();
  const int d = config.d_model, half = d / 2;
  frequencies_ = register_buffer(
      "frequencies", torch::exp(torch::arange(half, torch::kFloat32) * (-std::log(10000.0) / (half - 1))));
  embed_ = register_module("embed", torch::nn::Linear(state_dim, d));
  time_in_ = register_module("time_in", torch::nn::Linear(d, 4 * d));
  time_out_ = register_module("time_out", torch::nn::Linear(4 * d, d));
  if (cond_dim > 0) {
    if (cond_dim % 2 != 0) throw Error("transformer: the condition must hold a start and a goal of equal size");
    cond_in_ = register_module("cond_in", torch::nn::Linear(cond_dim / 2, d));
  }
  for (int i = 0; i < config.layers; ++i) {
    Layer layer;
    const std::string name = "layer" + std::to_string(i);
    layer.norm1 = register_module(name + "_norm1", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
    layer.qkv = register_module(name + "_qkv", torch::nn::Linear(d, 3 * d));
    layer.out = register_module(name + "_out", torch::nn::Linear(d, d));
    layer.norm2 = register_module(name + "_norm2", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
    layer.up = register_module(name + "_up", torch::nn::Linear(d, config.mlp_ratio * d));
    layer.down = register_module(name + "_down", torch::nn::Linear(config.mlp_ratio * d, d));
    layers_.push_back(layer);
  }
  final_norm_ = register_module("final_norm", torch::nn::LayerNorm(torch::nn::LayerNormOptions({d})));
  head_ = register_module("head", torch::nn::Linear(d, state_dim));
}

void Transformer::CheckHorizon(int64_t horizon) const {
  if (horizon < 1) throw Error("transformer: expected a horizon of at least one state, got " + std::to_string(horizon));
}

torch::Tensor Transformer::Sinusoid(const torch::Tensor& values) const {
  const torch::Tensor angles = values.unsqueeze(-1) * frequencies_.unsqueeze(0);  // (N, d/2)
  return torch::cat({angles.sin(), angles.cos()}, -1);
}

torch::Tensor Transformer::Forward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond) {
  CheckTrajectoryInputs(x, t, cond, state_dim_, cond_dim_);
  const int64_t B = x.size(0), T = x.size(1), d = config_.d_model, H = config_.heads, dh = d / H;
  const torch::Tensor positions = Sinusoid(torch::arange(T, x.options()));                      // (T, d)
  torch::Tensor tokens = WidenBfloat16(embed_(x)) + positions.unsqueeze(0);  // (B, T, d), float32 under autocast too
  const torch::Tensor time = WidenBfloat16(time_out_(Mish(time_in_(Sinusoid(t * config_.time_scale)))));  // (B, d)
  std::vector<torch::Tensor> parts = {time.unsqueeze(1)};
  if (cond_dim_ > 0) parts.push_back(WidenBfloat16(cond_in_(cond.view({B, 2, cond_dim_ / 2}))));  // start and goal tokens
  parts.push_back(tokens);
  torch::Tensor h = torch::cat(parts, 1);  // (B, N, d)
  const int64_t N = h.size(1);
  for (Layer& layer : layers_) {
    const torch::Tensor qkv = layer.qkv(layer.norm1(h)).view({B, N, 3, H, dh}).permute({2, 0, 3, 1, 4});  // (3, B, H, N, dh)
    const torch::Tensor scores = torch::matmul(qkv[0], qkv[1].transpose(-2, -1)) * (1.0 / std::sqrt(double(dh)));
    const torch::Tensor attended = torch::matmul(torch::softmax(WidenBfloat16(scores), -1), qkv[2]);  // (B, H, N, dh)
    h = h + layer.out(attended.transpose(1, 2).reshape({B, N, d}));
    h = h + layer.down(torch::gelu(layer.up(layer.norm2(h))));
  }
  return WidenBfloat16(head_(final_norm_(h.slice(1, N - T, N))));
}

std::string Transformer::WriteScript(jit::ScriptWriter& w) const {
  const std::string d = std::to_string(config_.d_model), H = std::to_string(config_.heads);
  const std::string dh = std::to_string(config_.d_model / config_.heads);
  auto linear = [&](const std::string& name, const torch::nn::Linear& l, const std::string& in) {
    return "torch.linear(" + in + ", " + w.Tensor(name + ".weight", l->weight) + ", " + w.Tensor(name + ".bias", l->bias) + ")";
  };
  auto norm = [&](const std::string& name, const torch::nn::LayerNorm& n, const std::string& in) {
    return "torch.layer_norm(" + in + ", [" + d + "], " + w.Tensor(name + ".weight", n->weight) + ", " +
           w.Tensor(name + ".bias", n->bias) + ", " + jit::ScriptFloat(n->options.eps()) + ")";
  };
  const std::string freq = w.Tensor("frequencies", frequencies_);
  w.Line("B = x.size(0)");
  w.Line("T = x.size(1)");
  const std::string pos = w.Let("torch.arange(T, dtype=x.dtype, device=x.device).unsqueeze(-1) * " + freq + ".unsqueeze(0)");
  const std::string tokens = w.Let(linear("embed", embed_, "x") + " + torch.cat([torch.sin(" + pos + "), torch.cos(" + pos + ")], -1).unsqueeze(0)");
  const std::string ang = w.Let("(t * " + jit::ScriptFloat(config_.time_scale) + ").unsqueeze(-1) * " + freq + ".unsqueeze(0)");
  const std::string time = w.Let(linear("time_out", time_out_, "torch.mish(" + linear("time_in", time_in_, "torch.cat([torch.sin(" + ang + "), torch.cos(" + ang + ")], -1)") + ")"));
  std::string h;
  if (cond_dim_ > 0) {
    w.Line("assert cond is not None");
    h = w.Let("torch.cat([" + time + ".unsqueeze(1), " + linear("cond_in", cond_in_, "cond.view(B, 2, " + std::to_string(cond_dim_ / 2) + ")") + ", " + tokens + "], 1)");
  } else {
    h = w.Let("torch.cat([" + time + ".unsqueeze(1), " + tokens + "], 1)");
  }
  w.Line("N = " + h + ".size(1)");
  for (size_t i = 0; i < layers_.size(); ++i) {
    const std::string name = "layer" + std::to_string(i);
    const std::string qkv = w.Let(linear(name + "_qkv", layers_[i].qkv, norm(name + "_norm1", layers_[i].norm1, h)) +
                                  ".view(B, N, 3, " + H + ", " + dh + ").permute(2, 0, 3, 1, 4)");
    const std::string scores = w.Let("torch.matmul(" + qkv + "[0], " + qkv + "[1].transpose(-2, -1)) * " +
                                     jit::ScriptFloat(1.0 / std::sqrt(double(config_.d_model / config_.heads))));
    const std::string attended = w.Let("torch.matmul(torch.softmax(" + scores + ", -1), " + qkv + "[2])");
    h = w.Let(h + " + " + linear(name + "_out", layers_[i].out, attended + ".transpose(1, 2).reshape(B, N, " + d + ")"));
    h = w.Let(h + " + " + linear(name + "_down", layers_[i].down, "torch.gelu(" + linear(name + "_up", layers_[i].up, norm(name + "_norm2", layers_[i].norm2, h)) + ")"));
  }
  return w.Let(linear("head", head_, norm("final_norm", final_norm_, h + "[:, N - T:N]")));
}

}  // namespace flowplan::models
