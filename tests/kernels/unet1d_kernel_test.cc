// The native UNet kernel against LibTorch's operators: the same network
// scripted with portable code (torch.conv1d / group_norm / mish, nothing of
// kernels/) and models::UNet1D's C++ forward pass.

#include "kernels/unet1d_kernel.h"

#include <ATen/Parallel.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "jit/library.h"
#include "models/trajectory_net.h"
#include "models/unet1d.h"

namespace flowplan::kernels {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

struct Case {
  std::vector<int> dims;
  int64_t D, C, T, B;
  int kernel = 5, groups = 8;
  double time_scale = 1.0;
  int time_embed = 32;
};

/// A UNet with every parameter moved off its initial value (GroupNorm's 1 and
/// 0 included), so that a parameter packed in the wrong place shows.
std::shared_ptr<models::UNet1D> Perturbed(const Case& c) {
  models::UNetConfig config;
  config.down_dims = c.dims;
  config.kernel_size = c.kernel;
  config.groups = c.groups;
  config.time_scale = c.time_scale;
  config.time_embed_dim = c.time_embed;
  auto net = std::make_shared<models::UNet1D>(config, c.D, c.C);
  torch::NoGradGuard no_grad;
  for (torch::Tensor& p : net->parameters()) p.add_(0.2 * torch::randn_like(p));
  net->eval();
  return net;
}

/// The module's forward pass as flowplan calls scripts (jit::Call: the graph as compiled, no profiling).
torch::Tensor Forward(torch::jit::Module& module, const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond) {
  return jit::Call(module, "forward", {x, t, cond.defined() ? torch::IValue(cond) : torch::IValue()}).toTensor();
}

class NativeMatchesLibTorch : public ::testing::TestWithParam<Case> {};

TEST_P(NativeMatchesLibTorch, ScriptedNetworksAgree) {
  const Case c = GetParam();
  torch::manual_seed(7);
  const auto net = Perturbed(c);
  torch::jit::Module native = models::ScriptNetwork(*net, models::Kernels::kNative);
  torch::jit::Module portable = models::ScriptNetwork(*net, models::Kernels::kPortable);
  const torch::Tensor x = torch::randn({c.B, c.T, c.D}), t = torch::rand({c.B});
  const torch::Tensor cond = c.C > 0 ? torch::randn({c.B, c.C}) : torch::Tensor();
  torch::NoGradGuard no_grad;
  const torch::Tensor want = Forward(portable, x, t, cond), got = Forward(native, x, t, cond);
  ASSERT_EQ(got.sizes(), want.sizes());
  const double scale = want.abs().max().item<double>();
  EXPECT_GT(scale, 0.1);  // a network whose output is not all but zero
  EXPECT_LT((got - want).abs().max().item<double>(), 1e-5 * std::max(1.0, scale));
  // models::UNet1D's own forward pass (flowplan's Mish), and the kernel called directly.
  EXPECT_LT((net->Forward(x, t, cond) - got).abs().max().item<double>(), 1e-5 * std::max(1.0, scale));
}

INSTANTIATE_TEST_SUITE_P(
    Shapes, NativeMatchesLibTorch,
    ::testing::Values(Case{{32, 64, 128}, 14, 0, 64, 1},               // the Franka presets' network, one plan
                      Case{{32, 64, 128}, 14, 28, 64, 3},              // direct conditioning, three plans
                      Case{{32, 64, 128}, 14, 0, 32, 2},               // the halves of a split plan
                      Case{{16, 32, 64, 128}, 4, 8, 16, 2},            // four levels: 2 states at the bottom
                      Case{{8}, 2, 0, 5, 3, 3, 4},                     // one level (no down or up), odd T, k 3
                      Case{{24, 40}, 6, 0, 10, 2, 7, 8, 100.0},        // widths no multiple of 16, k 7, time scale
                      Case{{32, 64}, 14, 0, 64, 9},                    // a batch above the thread count
                      Case{{16, 48}, 16, 0, 16, 2, 5, 8, 1.0, 16},     // 16 states (a vector-wide output), 48 = 32 + 16
                      Case{{16, 32}, 4, 0, 16, 2, 17, 8}));            // a kernel wider than the horizon's halves

TEST(UNet1DKernelTest, PackedSizeIsEveryParameterOnce) {
  const Case c{{32, 64, 128}, 14, 28, 64, 1};
  const auto net = Perturbed(c);
  int64_t numbers = 0;
  for (const torch::Tensor& p : net->parameters()) numbers += p.numel();
  UNet1DShape shape;
  shape.state_dim = 14;
  shape.cond_dim = 28;
  shape.down_dims = {32, 64, 128};
  EXPECT_EQ(shape.PackedSize(), numbers + shape.time_embed_dim / 2);  // + the sinusoid's frequencies
}

TEST(UNet1DKernelTest, SameBitsForAnyThreadCount) {
  torch::manual_seed(3);
  const Case c{{32, 64, 128}, 14, 0, 64, 5};
  const auto net = Perturbed(c);
  torch::jit::Module native = models::ScriptNetwork(*net, models::Kernels::kNative);
  const torch::Tensor x = torch::randn({5, 64, 14}), t = torch::rand({5});
  torch::NoGradGuard no_grad;
  const int threads = at::get_num_threads();
  at::set_num_threads(1);
  const torch::Tensor one = Forward(native, x, t, {});
  at::set_num_threads(3);
  const torch::Tensor three = Forward(native, x, t, {});
  at::set_num_threads(threads);
  EXPECT_TRUE(torch::equal(one, three));
  // Each plan of a batch is computed alone: the same bits as a batch of one.
  EXPECT_TRUE(torch::equal(one.slice(0, 2, 3), Forward(native, x.slice(0, 2, 3), t.slice(0, 2, 3), {})));
}

TEST(UNet1DKernelTest, AnInputThatNeedsAGradientTakesLibTorchsOperators) {
  torch::manual_seed(4);
  const Case c{{16, 32}, 4, 6, 16, 2};
  const auto net = Perturbed(c);
  torch::jit::Module native = models::ScriptNetwork(*net, models::Kernels::kNative);
  torch::jit::Module portable = models::ScriptNetwork(*net, models::Kernels::kPortable);
  const torch::Tensor x0 = torch::randn({2, 16, 4}), t0 = torch::rand({2}), cond0 = torch::randn({2, 6});
  // The gradient with respect to each input in turn (x, t, cond), the others plain.
  for (int which = 0; which < 3; ++which) {
    auto gradient = [&](torch::jit::Module& m) {
      torch::Tensor x = x0.clone(), t = t0.clone(), cond = cond0.clone();
      torch::Tensor& wanted = which == 0 ? x : which == 1 ? t : cond;
      wanted.requires_grad_(true);
      Forward(m, x, t, cond).pow(2).sum().backward();
      return wanted.grad();
    };
    const torch::Tensor ours = gradient(native), want = gradient(portable);
    ASSERT_TRUE(ours.defined()) << "input " << which;
    EXPECT_GT(want.abs().max().item<double>(), 0.0) << "input " << which;
    EXPECT_TRUE(torch::allclose(ours, want)) << "input " << which;
  }
}

TEST(UNet1DKernelTest, BadInputsAreClearErrors) {
  UNet1DShape shape;
  shape.state_dim = 4;
  shape.down_dims = {16, 32};
  const Case c{{16, 32}, 4, 0, 16, 1};
  const auto net = Perturbed(c);
  const auto parameters = net->named_parameters();
  const auto buffers = net->named_buffers();
  auto lookup = [&](const std::string& name) {
    const torch::Tensor* p = parameters.find(name);
    return p != nullptr ? *p : *buffers.find(name);
  };
  const torch::Tensor packed = PackUNet1D(shape, lookup);
  const torch::Tensor x = torch::randn({1, 16, 4}), t = torch::rand({1});
  torch::NoGradGuard no_grad;
  EXPECT_EQ(UNet1DForward(x, t, {}, packed, shape).sizes(), x.sizes());
  EXPECT_THAT([&] { UNet1DForward(x, t, {}, packed.slice(0, 1), shape); },
              ThrowsMessage<std::runtime_error>(HasSubstr("packed: expected")));
  EXPECT_THAT([&] { UNet1DForward(torch::randn({1, 13, 4}), t, {}, packed, shape); },
              ThrowsMessage<std::runtime_error>(HasSubstr("the horizon 13 is not a multiple of 2")));
  EXPECT_THAT([&] { UNet1DForward(x, t, torch::randn({1, 3}), packed, shape); },
              ThrowsMessage<std::runtime_error>(HasSubstr("takes no condition")));
  EXPECT_THAT([&] { UNet1DForward(x.to(torch::kFloat64), t, {}, packed, shape); },
              ThrowsMessage<std::runtime_error>(HasSubstr("float32")));
  {
    torch::AutoGradMode grad(true);
    EXPECT_THAT([&] { UNet1DForward(x.clone().requires_grad_(true), t, {}, packed, shape); },
                ThrowsMessage<std::runtime_error>(HasSubstr("computes no gradient")));
    EXPECT_THAT([&] { UNet1DForward(x, t, {}, packed.clone().requires_grad_(true), shape); },
                ThrowsMessage<std::runtime_error>(HasSubstr("computes no gradient")));
  }
  UNet1DShape wider = shape;
  wider.down_dims = {16, 48};
  EXPECT_THAT([&] { PackUNet1D(wider, lookup); },
              ThrowsMessage<std::runtime_error>(HasSubstr("parameter down1_block0.block0.conv.weight: expected (48, 16, 5)")));
}

}  // namespace
}  // namespace flowplan::kernels
