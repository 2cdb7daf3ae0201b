#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <vector>

#include "core/config.h"
#include "models/network.h"

namespace flowplan::models {

/// The `model.vae` section: the VAE of "Reaching Through Latent Space" (SPEC section 2).
struct StateVaeConfig {
  std::vector<int> hidden = {512, 512};  // widths of the encoder's and (mirrored) decoder's hidden layers
  int latent = 64;                       // L

  template <class V>
  void Visit(V& v) {
    v.Field("hidden", hidden, "hidden layer widths of the encoder (the decoder mirrors them)", config::Positive());
    v.Field("latent", latent, "latent dimension", config::Positive());
  }
};

/// A variational autoencoder over single normalized states (D,): an MLP
/// encoder (ReLU) to a Gaussian over the latent (L,), an MLP decoder back.
/// Its script (ToScript) also writes out Decode's vector–Jacobian product, so
/// that planning in the latent space runs without autograd.
class StateVae : public Network {
 public:
  StateVae(const StateVaeConfig& config, int64_t state_dim);

  struct Encoding {
    torch::Tensor mean;     // (M, L)
    torch::Tensor log_var;  // (M, L)
  };
  /// x: (M, D) normalized states.
  Encoding Encode(const torch::Tensor& x);
  /// z: (M, L) -> (M, D) normalized states.
  torch::Tensor Decode(const torch::Tensor& z);

  /// The VAE as a TorchScript module: encode(x) -> (mean, log_var), decode(z)
  /// and decode_vjp(z, g), its parameters copied into buffers.
  torch::jit::Module ToScript() const;

  int64_t state_dim() const { return state_dim_; }
  int64_t latent_dim() const { return latent_; }

 private:
  std::vector<torch::nn::Linear> encoder_, decoder_;  // decoder_.back() is the output layer
  torch::nn::Linear mean_{nullptr}, log_var_{nullptr};
  int64_t state_dim_, latent_;
};

}  // namespace flowplan::models
