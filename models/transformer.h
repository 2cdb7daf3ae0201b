#pragma once

#include <torch/torch.h>

#include <vector>

#include "core/config.h"
#include "models/trajectory_net.h"

namespace flowplan::models {

/// The `model.transformer` section (SPEC section 2: d_model 256, 4 heads, 2 layers).
struct TransformerConfig {
  int d_model = 256;
  int heads = 4;
  int layers = 2;
  int mlp_ratio = 4;         // hidden width of each layer's MLP is mlp_ratio · d_model
  double time_scale = 1.0;   // the objective's time is multiplied by this before the sinusoidal embedding

  template <class V>
  void Visit(V& v) {
    v.Field("d_model", d_model, "token width", config::Positive());
    v.Field("heads", heads, "attention heads (must divide d_model)", config::Positive());
    v.Field("layers", layers, "encoder layers", config::Positive());
    v.Field("mlp_ratio", mlp_ratio, "MLP hidden width as a multiple of d_model", config::Positive());
    v.Field("time_scale", time_scale, "factor on the time before the sinusoidal embedding", config::Positive());
  }

  /// @throws flowplan::Error naming the `model.transformer.*` key at fault.
  void Validate() const;
};

/// A pre-norm transformer encoder over the T states of a trajectory: each state
/// is a token (linear embedding plus sinusoidal position), the time is one
/// more token (sinusoidal embedding and an MLP) and, under direct
/// conditioning, start and goal are two more; attention over all tokens, then
/// a linear read-out of the state tokens.
class Transformer : public TrajectoryNet {
 public:
  Transformer(const TransformerConfig& config, int64_t state_dim, int64_t cond_dim);

  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond) override;
  void CheckHorizon(int64_t horizon) const override;
  std::string WriteScript(jit::ScriptWriter& writer) const override;
  int64_t state_dim() const override { return state_dim_; }
  int64_t cond_dim() const override { return cond_dim_; }

 private:
  struct Layer {
    torch::nn::LayerNorm norm1{nullptr}, norm2{nullptr};
    torch::nn::Linear qkv{nullptr}, out{nullptr}, up{nullptr}, down{nullptr};
  };
  /// Sinusoidal features of `values` (M,) -> (M, d_model).
  torch::Tensor Sinusoid(const torch::Tensor& values) const;

  TransformerConfig config_;
  int64_t state_dim_, cond_dim_;
  torch::Tensor frequencies_;  // (d_model / 2,) buffer
  torch::nn::Linear embed_{nullptr}, time_in_{nullptr}, time_out_{nullptr}, cond_in_{nullptr};
  std::vector<Layer> layers_;
  torch::nn::LayerNorm final_norm_{nullptr};
  torch::nn::Linear head_{nullptr};
};

}  // namespace flowplan::models
