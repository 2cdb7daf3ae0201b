#pragma once

#include <torch/torch.h>

#include <vector>

#include "core/config.h"
#include "jit/script_writer.h"
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
/// Decode's vector–Jacobian product is written out, so that planning in the
/// latent space runs in an exported planner without autograd.
class StateVae : public Network {
 public:
  StateVae(const StateVaeConfig& config, int64_t state_dim);

  struct Encoding {
    torch::Tensor mean;     // (N, L)
    torch::Tensor log_var;  // (N, L)
  };
  /// x: (N, D) normalized states.
  Encoding Encode(const torch::Tensor& x);
  /// z: (N, L) -> (N, D) normalized states.
  torch::Tensor Decode(const torch::Tensor& z);
  /// ∂/∂z of Σ ⟨g, Decode(z)⟩: z (N, L), g (N, D) -> (N, L).
  torch::Tensor DecodeVjp(const torch::Tensor& z, const torch::Tensor& g);

  /// Adds vae_encode(x) -> (mean, log_var), vae_decode(z) and vae_decode_vjp(z, g).
  void WriteScript(jit::ScriptModule& module) const;

  int64_t state_dim() const { return state_dim_; }
  int64_t latent_dim() const { return latent_; }

 private:
  std::vector<torch::nn::Linear> encoder_, decoder_;  // decoder_.back() is the output layer
  torch::nn::Linear mean_{nullptr}, log_var_{nullptr};
  int64_t state_dim_, latent_;
};

}  // namespace flowplan::models
