#pragma once

#include <torch/torch.h>

#include <string>
#include <vector>

#include "core/config.h"
#include "models/trajectory_net.h"

namespace flowplan::models {

/// Temporal UNet in the style of Diffuser / Diffusion Policy (SPEC section 2).
struct UNetConfig {
  std::vector<int> down_dims = {32, 64, 128, 256};  // channels per level; T halves between levels
  int kernel_size = 5;                              // temporal kernel of the residual blocks
  int groups = 8;                                   // GroupNorm groups
  int time_embed_dim = 32;                          // sinusoidal size; MLP 32 -> 128 -> 32
  double time_scale = 1.0;                          // flow time is multiplied by this before the embedding

  template <class V>
  void Visit(V& v) {
    v.Field("down_dims", down_dims, "channels per UNet level", config::Positive());
    v.Field("kernel_size", kernel_size, "temporal kernel size (odd)", config::Positive());
    v.Field("groups", groups, "GroupNorm groups (must divide every width)", config::Positive());
    v.Field("time_embed_dim", time_embed_dim, "sinusoidal time embedding size (even)",
            config::AtLeast(4));
    v.Field("time_scale", time_scale, "factor on the flow time before the sinusoidal embedding",
            config::Positive());
  }

  /// @throws flowplan::Error naming the `model.unet.*` key at fault.
  void Validate() const;
};

namespace internal {

/// Conv1d(k) -> GroupNorm -> Mish on (B, C, T).
class ConvBlock : public torch::nn::Module {
 public:
  ConvBlock(int in, int out, int kernel, int groups);
  torch::Tensor Forward(const torch::Tensor& x);
  std::string WriteScript(jit::ScriptWriter& w, const std::string& prefix, const std::string& x) const;
  double norm_eps() const { return norm_->options.eps(); }

 private:
  torch::nn::Conv1d conv_{nullptr};
  torch::nn::GroupNorm norm_{nullptr};
  int padding_;
  int groups_;
};

/// Two ConvBlocks with FiLM (scale and shift from the condition) between them
/// and a 1x1 residual convolution when the width changes.
class ResidualBlock : public torch::nn::Module {
 public:
  ResidualBlock(int in, int out, int cond_dim, int kernel, int groups);
  /// x: (B, in, T), cond: (B, cond_dim) -> (B, out, T)
  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& cond);
  /// Writes the block's forward pass; `film` names the (B, F, 1) FiLM
  /// output of every block at once (UNet1D::WriteScript), whose rows
  /// film_offset .. film_offset + 2 * out are this block's scale and shift.
  std::string WriteScript(jit::ScriptWriter& w, const std::string& prefix, const std::string& x,
                          const std::string& film, int64_t film_offset) const;
  const torch::nn::Linear& film() const { return film_; }

 private:
  std::shared_ptr<ConvBlock> block0_, block1_;
  torch::nn::Linear film_{nullptr};
  torch::nn::Conv1d residual_{nullptr};  // null when in == out
  int out_;
};

}  // namespace internal

class UNet1D : public TrajectoryNet {
 public:

  /// @param state_dim D, @param cond_dim C (0: no global condition).
  UNet1D(const UNetConfig& config, int64_t state_dim, int64_t cond_dim);

  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& t,
                        const torch::Tensor& cond) override;
  void CheckHorizon(int64_t horizon) const override;
  std::string WriteScript(jit::ScriptWriter& writer) const override;
  /// flowplan::unet1d (kernels/unet1d_kernel.h) for float32 CPU inputs that
  /// need no gradient, at any batch (it was faster than LibTorch's operators
  /// from B = 1 to 64: docs/performance.md).
  void WriteNativeKernel(jit::ScriptWriter& writer) const override;
  int64_t state_dim() const override { return state_dim_; }
  int64_t cond_dim() const override { return cond_dim_; }

 private:
  struct Level {
    std::shared_ptr<internal::ResidualBlock> block0, block1;
    torch::nn::Conv1d down{nullptr};           // null on the last down level
    torch::nn::ConvTranspose1d up{nullptr};    // every up level has one (there is one up level fewer than down)
  };

  torch::Tensor TimeFeature(const torch::Tensor& t) const;

  UNetConfig config_;
  int64_t state_dim_;
  int64_t cond_dim_;
  torch::Tensor frequencies_;  // (time_embed_dim / 2,) buffer
  torch::nn::Linear time_in_{nullptr}, time_out_{nullptr};
  std::vector<Level> down_, up_;
  std::shared_ptr<internal::ResidualBlock> mid0_, mid1_;
  std::shared_ptr<internal::ConvBlock> final_block_;
  torch::nn::Conv1d final_conv_{nullptr};
};

}  // namespace flowplan::models
