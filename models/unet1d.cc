#include "models/unet1d.h"

#include <cmath>

#include "core/error.h"
#include "kernels/unet1d_kernel.h"
#include "models/mish.h"
#include "models/precision.h"

namespace flowplan::models {

void UNetConfig::Validate() const {
  if (down_dims.size() < 1) throw Error("model.unet.down_dims: expected at least one level");
  for (size_t i = 0; i < down_dims.size(); ++i) {
    if (down_dims[i] % groups != 0) {
      throw Error("model.unet.down_dims[" + std::to_string(i) + "]: expected a multiple of model.unet.groups (" +
                  std::to_string(groups) + "), got " + std::to_string(down_dims[i]));
    }
  }
  if (kernel_size % 2 == 0) {
    throw Error("model.unet.kernel_size: expected an odd size, got " + std::to_string(kernel_size));
  }
  if (time_embed_dim % 2 != 0) {
    throw Error("model.unet.time_embed_dim: expected an even size, got " + std::to_string(time_embed_dim));
  }
}

namespace internal {

namespace {

/// "[a]" of a 1-D size option as a 2-D TorchScript list "[fill, a]".
std::string Pair(int64_t fill, int64_t a) { return "[" + std::to_string(fill) + ", " + std::to_string(a) + "]"; }

int64_t Padding(const torch::nn::detail::ConvNdOptions<1>& options) {
  return (*c10::get<torch::ExpandingArray<1>>(options.padding()))[0];
}

}  // namespace

/// The script expression of a 1-D convolution (transposed when the options
/// say so) of x (B, C, T). A batch of at most 4 goes straight to LibTorch's
/// im2col + GEMM kernel as a 2-D convolution of height 1, which LibTorch 1.13
/// picks by itself only for a batch of one: for B = 2..4 (the two halves of a
/// split plan) its oneDNN path took 1.4-2.8x longer at these sizes
/// (docs/performance.md). Larger batches, and an empty one (which the im2col
/// kernel refuses), take torch.conv1d. Only what the UNet's convolutions use
/// is written: one group, no dilation, no output padding, zero padding.
std::string ScriptConv(const std::string& x, const std::string& weight, const std::string& bias,
                       const torch::nn::detail::ConvNdOptions<1>& options) {
  FLOWPLAN_DEMAND(options.groups() == 1 && (*options.dilation())[0] == 1 && (*options.output_padding())[0] == 0 &&
                  c10::get_if<torch::enumtype::kZeros>(&options.padding_mode()) != nullptr);
  const int64_t k = (*options.kernel_size())[0], stride = (*options.stride())[0], padding = Padding(options);
  const std::string geometry = Pair(1, stride) + ", " + Pair(0, padding);
  const std::string few = "(" + x + ".size(0) > 0 and " + x + ".size(0) <= 4)";
  if (options.transposed()) {
    return "(torch.slow_conv_transpose2d(" + x + ".unsqueeze(2), " + weight + ".unsqueeze(2), " + Pair(1, k) +
           ", " + bias + ", " + geometry + ", [0, 0], [1, 1]).squeeze(2) if " + few + " else " +
           "torch.conv_transpose1d(" + x + ", " + weight + ", " + bias + ", " + std::to_string(stride) + ", " +
           std::to_string(padding) + "))";
  }
  return "(torch.thnn_conv2d(" + x + ".unsqueeze(2), " + weight + ".unsqueeze(2), " + Pair(1, k) + ", " + bias +
         ", " + geometry + ").squeeze(2) if " + few + " else torch.conv1d(" + x + ", " + weight + ", " + bias +
         ", " + std::to_string(stride) + ", " + std::to_string(padding) + "))";
}

ConvBlock::ConvBlock(int in, int out, int kernel, int groups) : padding_(kernel / 2), groups_(groups) {
  conv_ = register_module("conv", torch::nn::Conv1d(torch::nn::Conv1dOptions(in, out, kernel).padding(kernel / 2)));
  norm_ = register_module("norm", torch::nn::GroupNorm(torch::nn::GroupNormOptions(groups, out)));
}

torch::Tensor ConvBlock::Forward(const torch::Tensor& x) { return Mish(norm_(WidenBfloat16(conv_(x)))); }

std::string ConvBlock::WriteScript(jit::ScriptWriter& w, const std::string& prefix, const std::string& x) const {
  const std::string c = w.Let(ScriptConv(x, w.Tensor(prefix + ".conv.weight", conv_->weight),
                                         w.Tensor(prefix + ".conv.bias", conv_->bias), conv_->options));
  const std::string n = w.Let("torch.group_norm(" + c + ", " + std::to_string(groups_) + ", " +
                              w.Tensor(prefix + ".norm.weight", norm_->weight) + ", " +
                              w.Tensor(prefix + ".norm.bias", norm_->bias) + ", " +
                              jit::ScriptFloat(norm_->options.eps()) + ")");
  return w.Let("torch.mish(" + n + ")");
}

ResidualBlock::ResidualBlock(int in, int out, int cond_dim, int kernel, int groups) : out_(out) {
  block0_ = register_module("block0", std::make_shared<ConvBlock>(in, out, kernel, groups));
  block1_ = register_module("block1", std::make_shared<ConvBlock>(out, out, kernel, groups));
  film_ = register_module("film", torch::nn::Linear(cond_dim, 2 * out));
  if (in != out) {
    residual_ = register_module("residual", torch::nn::Conv1d(torch::nn::Conv1dOptions(in, out, 1)));
  }
}

torch::Tensor ResidualBlock::Forward(const torch::Tensor& x, const torch::Tensor& cond) {
  torch::Tensor h = block0_->Forward(x);
  const torch::Tensor film = film_(Mish(cond)).unsqueeze(-1);  // (B, 2*out, 1)
  h = film.slice(1, 0, out_) * h + film.slice(1, out_, 2 * out_);
  h = block1_->Forward(h);
  return h + (residual_ ? residual_(x) : x);
}

std::string ResidualBlock::WriteScript(jit::ScriptWriter& w, const std::string& prefix, const std::string& x,
                                       const std::string& film, int64_t film_offset) const {
  std::string h = block0_->WriteScript(w, prefix + ".block0", x);
  const std::string scale = std::to_string(film_offset) + ":" + std::to_string(film_offset + out_);
  const std::string shift = std::to_string(film_offset + out_) + ":" + std::to_string(film_offset + 2 * out_);
  h = w.Let(film + "[:, " + scale + "] * " + h + " + " + film + "[:, " + shift + "]");
  h = block1_->WriteScript(w, prefix + ".block1", h);
  const std::string skip = residual_ ? ScriptConv(x, w.Tensor(prefix + ".residual.weight", residual_->weight),
                                                  w.Tensor(prefix + ".residual.bias", residual_->bias),
                                                  residual_->options)
                                     : x;
  return w.Let(h + " + " + skip);
}

}  // namespace internal

UNet1D::UNet1D(const UNetConfig& config, int64_t state_dim, int64_t cond_dim)
    : config_(config), state_dim_(state_dim), cond_dim_(cond_dim) {
  config_.Validate();
  const int e = config.time_embed_dim;
  const int half = e / 2;
  // Sinusoidal frequencies exp(-k ln(10000) / (half - 1)), k = 0 .. half-1.
  frequencies_ = register_buffer(
      "frequencies", torch::exp(torch::arange(half, torch::kFloat32) * (-std::log(10000.0) / (half - 1))));
  time_in_ = register_module("time_in", torch::nn::Linear(e, 4 * e));
  time_out_ = register_module("time_out", torch::nn::Linear(4 * e, e));
  const int cond = e + static_cast<int>(cond_dim);
  const int k = config.kernel_size, g = config.groups;

  std::vector<int> dims = {static_cast<int>(state_dim)};
  dims.insert(dims.end(), config.down_dims.begin(), config.down_dims.end());
  const size_t levels = config.down_dims.size();
  for (size_t i = 0; i < levels; ++i) {
    Level level;
    const std::string name = "down" + std::to_string(i);
    level.block0 = register_module(name + "_block0", std::make_shared<internal::ResidualBlock>(dims[i], dims[i + 1], cond, k, g));
    level.block1 = register_module(name + "_block1", std::make_shared<internal::ResidualBlock>(dims[i + 1], dims[i + 1], cond, k, g));
    if (i + 1 < levels) {
      level.down = register_module(name + "_down", torch::nn::Conv1d(torch::nn::Conv1dOptions(dims[i + 1], dims[i + 1], 3).stride(2).padding(1)));
    }
    down_.push_back(level);
  }
  const int mid = dims.back();
  mid0_ = register_module("mid0", std::make_shared<internal::ResidualBlock>(mid, mid, cond, k, g));
  mid1_ = register_module("mid1", std::make_shared<internal::ResidualBlock>(mid, mid, cond, k, g));
  // Up levels mirror the down levels except the deepest: (dims[i+1] -> dims[i]) for i = levels-1 .. 1.
  for (size_t i = levels - 1; i >= 1; --i) {
    Level level;
    const std::string name = "up" + std::to_string(levels - 1 - i);
    level.block0 = register_module(name + "_block0", std::make_shared<internal::ResidualBlock>(2 * dims[i + 1], dims[i], cond, k, g));
    level.block1 = register_module(name + "_block1", std::make_shared<internal::ResidualBlock>(dims[i], dims[i], cond, k, g));
    level.up = register_module(name + "_up", torch::nn::ConvTranspose1d(torch::nn::ConvTranspose1dOptions(dims[i], dims[i], 4).stride(2).padding(1)));
    up_.push_back(level);
  }
  final_block_ = register_module("final_block", std::make_shared<internal::ConvBlock>(dims[1], dims[1], k, g));
  final_conv_ = register_module("final_conv", torch::nn::Conv1d(torch::nn::Conv1dOptions(dims[1], state_dim, 1)));
}

void UNet1D::CheckHorizon(int64_t horizon) const {
  const int64_t factor = int64_t{1} << (config_.down_dims.size() - 1);
  if (horizon < factor || horizon % factor != 0) {
    throw Error("UNet1D with " + std::to_string(config_.down_dims.size()) +
                " levels (model.unet.down_dims) needs a horizon that is a multiple of " + std::to_string(factor) +
                ", got " + std::to_string(horizon));
  }
}

torch::Tensor UNet1D::TimeFeature(const torch::Tensor& t) const {
  const torch::Tensor angles = (t * config_.time_scale).unsqueeze(-1) * frequencies_.unsqueeze(0);  // (B, half)
  const torch::Tensor embedding = torch::cat({angles.sin(), angles.cos()}, -1);                     // (B, e)
  return torch::linear(Mish(torch::linear(embedding, time_in_->weight, time_in_->bias)), time_out_->weight,
                       time_out_->bias);
}

torch::Tensor UNet1D::Forward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond) {
  CheckTrajectoryInputs(x, t, cond, state_dim_, cond_dim_);
  CheckHorizon(x.size(1));
  torch::Tensor feature = TimeFeature(t);
  if (cond_dim_ > 0) feature = torch::cat({feature, cond}, -1);

  torch::Tensor h = x.transpose(1, 2);  // (B, D, T)
  std::vector<torch::Tensor> skips;
  for (Level& level : down_) {
    h = level.block0->Forward(h, feature);
    h = level.block1->Forward(h, feature);
    skips.push_back(h);
    if (level.down) h = level.down(h);
  }
  h = mid0_->Forward(h, feature);
  h = mid1_->Forward(h, feature);
  for (Level& level : up_) {
    // Skips are taken deepest first; the shallowest one is left unused.
    h = torch::cat({h, skips.back()}, 1);
    skips.pop_back();
    h = level.block0->Forward(h, feature);
    h = level.block1->Forward(h, feature);
    h = level.up(h);
  }
  h = WidenBfloat16(final_conv_(final_block_->Forward(h)));
  return h.transpose(1, 2);  // (B, T, D)
}

std::string UNet1D::WriteScript(jit::ScriptWriter& w) const {
  const std::string angles = w.Let("(t * " + jit::ScriptFloat(config_.time_scale) + ").unsqueeze(-1) * " +
                                   w.Tensor("frequencies", frequencies_) + ".unsqueeze(0)");
  const std::string embedding = w.Let("torch.cat([torch.sin(" + angles + "), torch.cos(" + angles + ")], -1)");
  const std::string hidden = w.Let("torch.mish(torch.linear(" + embedding + ", " + w.Tensor("time_in.weight", time_in_->weight) +
                                   ", " + w.Tensor("time_in.bias", time_in_->bias) + "))");
  std::string feature = w.Let("torch.linear(" + hidden + ", " + w.Tensor("time_out.weight", time_out_->weight) + ", " +
                              w.Tensor("time_out.bias", time_out_->bias) + ")");
  if (cond_dim_ > 0) {
    w.Line("assert cond is not None");
    feature = w.Let("torch.cat([" + feature + ", cond], -1)");
  }
  // Every residual block's FiLM layer reads the same Mish(feature): one
  // linear layer with their weights stacked computes them all (B, F, 1).
  std::vector<const internal::ResidualBlock*> blocks;
  for (const Level& level : down_) blocks.insert(blocks.end(), {level.block0.get(), level.block1.get()});
  blocks.insert(blocks.end(), {mid0_.get(), mid1_.get()});
  for (const Level& level : up_) blocks.insert(blocks.end(), {level.block0.get(), level.block1.get()});
  std::vector<torch::Tensor> film_weights, film_biases;
  std::vector<int64_t> film_offsets;
  int64_t film_rows = 0;
  for (const internal::ResidualBlock* block : blocks) {
    film_weights.push_back(block->film()->weight);
    film_biases.push_back(block->film()->bias);
    film_offsets.push_back(film_rows);
    film_rows += block->film()->weight.size(0);
  }
  const std::string film =
      w.Let("torch.linear(torch.mish(" + feature + "), " + w.Tensor("films.weight", torch::cat(film_weights, 0)) + ", " +
            w.Tensor("films.bias", torch::cat(film_biases, 0)) + ").unsqueeze(-1)");
  size_t next_block = 0;
  auto write_block = [&](const internal::ResidualBlock& block, const std::string& name, const std::string& x) {
    return block.WriteScript(w, name, x, film, film_offsets[next_block++]);
  };

  std::string h = w.Let("x.transpose(1, 2)");
  std::vector<std::string> skips;
  for (size_t i = 0; i < down_.size(); ++i) {
    const std::string name = "down" + std::to_string(i);
    h = write_block(*down_[i].block0, name + "_block0", h);
    h = write_block(*down_[i].block1, name + "_block1", h);
    skips.push_back(h);
    if (down_[i].down) {
      h = w.Let(internal::ScriptConv(h, w.Tensor(name + "_down.weight", down_[i].down->weight),
                                     w.Tensor(name + "_down.bias", down_[i].down->bias), down_[i].down->options));
    }
  }
  h = write_block(*mid0_, "mid0", h);
  h = write_block(*mid1_, "mid1", h);
  for (size_t i = 0; i < up_.size(); ++i) {
    const std::string name = "up" + std::to_string(i);
    h = w.Let("torch.cat([" + h + ", " + skips.back() + "], 1)");
    skips.pop_back();
    h = write_block(*up_[i].block0, name + "_block0", h);
    h = write_block(*up_[i].block1, name + "_block1", h);
    h = w.Let(internal::ScriptConv(h, w.Tensor(name + "_up.weight", up_[i].up->weight),
                                   w.Tensor(name + "_up.bias", up_[i].up->bias), up_[i].up->options));
  }
  FLOWPLAN_DEMAND(next_block == blocks.size());  // every block's FiLM rows were read, in the order stacked
  h = final_block_->WriteScript(w, "final_block", h);
  h = w.Let(internal::ScriptConv(h, w.Tensor("final_conv.weight", final_conv_->weight),
                                 w.Tensor("final_conv.bias", final_conv_->bias), final_conv_->options));
  return w.Let(h + ".transpose(1, 2)");
}

void UNet1D::WriteNativeKernel(jit::ScriptWriter& w) const {
  kernels::UNet1DShape shape;
  shape.state_dim = state_dim_;
  shape.cond_dim = cond_dim_;
  shape.down_dims.assign(config_.down_dims.begin(), config_.down_dims.end());
  shape.kernel_size = config_.kernel_size;
  shape.groups = config_.groups;
  shape.time_embed_dim = config_.time_embed_dim;
  shape.time_scale = config_.time_scale;
  shape.norm_eps = final_block_->norm_eps();
  const auto parameters = named_parameters();
  torch::Tensor packed;
  try {
    packed = kernels::PackUNet1D(shape, [&](const std::string& name) {
      if (name == "frequencies") return frequencies_;
      const torch::Tensor* p = parameters.find(name);
      return p != nullptr ? *p : torch::Tensor();
    });
  } catch (const std::runtime_error& e) {
    throw Error(e.what());
  }
  // float32 (the one floating type of 4 bytes) on the CPU (no device index), no input needing a gradient
  w.Line("if x.is_floating_point() and x.element_size() == 4 and x.get_device() < 0 and not x.requires_grad "
         "and not t.requires_grad and (cond is None or not cond.requires_grad):");
  w.Indent();
  w.Line("return ops.flowplan.unet1d(x, t, cond, " + w.Tensor("native.packed", packed) + ", " +
         jit::ScriptIntList(shape.down_dims) + ", " + std::to_string(shape.kernel_size) + ", " +
         std::to_string(shape.groups) + ", " + std::to_string(shape.time_embed_dim) + ", " +
         jit::ScriptFloat(shape.time_scale) + ", " + jit::ScriptFloat(shape.norm_eps) + ")");
  w.Dedent();
}

}  // namespace flowplan::models
