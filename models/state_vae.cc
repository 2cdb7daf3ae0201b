#include "models/state_vae.h"

#include "core/error.h"
#include "jit/library.h"
#include "models/precision.h"

namespace flowplan::models {

StateVae::StateVae(const StateVaeConfig& config, int64_t state_dim) : state_dim_(state_dim), latent_(config.latent) {
  if (config.hidden.empty()) throw Error("model.vae.hidden: expected at least one hidden layer");
  int64_t width = state_dim;
  for (size_t i = 0; i < config.hidden.size(); ++i) {
    encoder_.push_back(register_module("encoder" + std::to_string(i), torch::nn::Linear(width, config.hidden[i])));
    width = config.hidden[i];
  }
  mean_ = register_module("mean", torch::nn::Linear(width, latent_));
  log_var_ = register_module("log_var", torch::nn::Linear(width, latent_));
  width = latent_;
  for (size_t i = config.hidden.size(); i-- > 0;) {
    decoder_.push_back(register_module("decoder" + std::to_string(decoder_.size()), torch::nn::Linear(width, config.hidden[i])));
    width = config.hidden[i];
  }
  decoder_.push_back(register_module("decoder" + std::to_string(decoder_.size()), torch::nn::Linear(width, state_dim)));
}

StateVae::Encoding StateVae::Encode(const torch::Tensor& x) {
  if (!x.defined() || x.dim() != 2 || x.size(1) != state_dim_) {
    throw Error("state VAE: x: expected (N, " + std::to_string(state_dim_) + ")");
  }
  torch::Tensor h = x;
  for (auto& layer : encoder_) h = torch::relu(layer(h));
  return {WidenBfloat16(mean_(h)), WidenBfloat16(log_var_(h))};
}

torch::Tensor StateVae::Decode(const torch::Tensor& z) {
  torch::Tensor h = z;
  for (size_t i = 0; i + 1 < decoder_.size(); ++i) h = torch::relu(decoder_[i](h));
  return WidenBfloat16(decoder_.back()(h));
}

torch::jit::Module StateVae::ToScript() const {
  // Written op for op as Encode, Decode and DecodeVjp compute.
  jit::ModuleBuilder module("StateVae");
  auto buffer = [&](const std::string& name, const torch::Tensor& value) {
    module.Buffer(name, value);
    return "self." + name;
  };
  std::string encode = "def encode(self, x: Tensor) -> Tuple[Tensor, Tensor]:\n    h = x\n";
  for (size_t i = 0; i < encoder_.size(); ++i) {
    const std::string w = buffer("encoder" + std::to_string(i) + "_weight", encoder_[i]->weight);
    const std::string b = buffer("encoder" + std::to_string(i) + "_bias", encoder_[i]->bias);
    encode += "    h = torch.relu(torch.linear(h, " + w + ", " + b + "))\n";
  }
  encode += "    return torch.linear(h, " + buffer("mean_weight", mean_->weight) + ", " + buffer("mean_bias", mean_->bias) +
            "), torch.linear(h, " + buffer("log_var_weight", log_var_->weight) + ", " +
            buffer("log_var_bias", log_var_->bias) + ")\n";
  std::vector<std::pair<std::string, std::string>> layers;
  for (size_t i = 0; i < decoder_.size(); ++i) {
    layers.emplace_back(buffer("decoder" + std::to_string(i) + "_weight", decoder_[i]->weight),
                        buffer("decoder" + std::to_string(i) + "_bias", decoder_[i]->bias));
  }
  std::string decode = "\ndef decode(self, z: Tensor) -> Tensor:\n    h = z\n";
  std::string vjp = "\ndef decode_vjp(self, z: Tensor, g: Tensor) -> Tensor:\n    h = z\n";
  for (size_t i = 0; i + 1 < layers.size(); ++i) {
    decode += "    h = torch.relu(torch.linear(h, " + layers[i].first + ", " + layers[i].second + "))\n";
    vjp += "    pre" + std::to_string(i) + " = torch.linear(h, " + layers[i].first + ", " + layers[i].second + ")\n";
    vjp += "    h = torch.relu(pre" + std::to_string(i) + ")\n";
  }
  decode += "    return torch.linear(h, " + layers.back().first + ", " + layers.back().second + ")\n";
  vjp += "    grad = torch.matmul(g, " + layers.back().first + ")\n";
  for (size_t i = layers.size() - 1; i-- > 0;) {
    vjp += "    grad = torch.matmul(grad * (pre" + std::to_string(i) + " > 0).to(grad.dtype), " + layers[i].first + ")\n";
  }
  vjp += "    return grad\n";
  return module.Attribute("latent_dim", latent_).GeneratedMethods(encode + decode + vjp, "the state VAE").Build();
}

}  // namespace flowplan::models
