#include "models/precision.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include "models/model_config.h"
#include "tests/support/tiny_model.h"

namespace flowplan::models {
namespace {

torch::Tensor Conv(const torch::Tensor& x, const torch::Tensor& w) { return torch::conv1d(x, w, {}, 1, 2); }

// Whether this CPU lacks native bf16 dot products (no avx512_bf16 or amx_bf16 flag). There, Debian's LibTorch
// (oneDNN 2.6) rounds a bf16 convolution's partial sums to bf16: errors up to about 2^-6.1 of Σ|x·w| against a
// float32 accumulation of the same rounded operands (an AVX2-only AMD EPYC), where CPUs with them (Intel's with AMX)
// stay within one bf16 step of the result.
bool BfloatPartialSums() {
  std::ifstream in("/proc/cpuinfo");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return text.find("avx512_bf16") == std::string::npos && text.find("amx_bf16") == std::string::npos;
}

TEST(AutocastScopeTest, RunsConvolutionsInBfloat16OnItsOwnThreadUntilTheOutermostScopeEnds) {
  const torch::Tensor x = torch::randn({2, 3, 16}), w = torch::randn({4, 3, 5});
  EXPECT_EQ(Conv(x, w).scalar_type(), torch::kFloat32);
  {
    const AutocastScope outer(Precision::kBf16);
    EXPECT_EQ(Conv(x, w).scalar_type(), torch::kBFloat16);
    torch::ScalarType other_thread = torch::kBFloat16;
    std::thread([&] { other_thread = Conv(x, w).scalar_type(); }).join();
    EXPECT_EQ(other_thread, torch::kFloat32) << "autocast must stay on the thread that opened the scope";
    { const AutocastScope inner(Precision::kBf16); }
    EXPECT_EQ(Conv(x, w).scalar_type(), torch::kBFloat16) << "an inner scope must not end the outer one";
  }
  EXPECT_EQ(Conv(x, w).scalar_type(), torch::kFloat32);
  const AutocastScope fp32(Precision::kFp32);
  EXPECT_EQ(Conv(x, w).scalar_type(), torch::kFloat32);
}

TEST(AutocastScopeTest, AConvolutionTakesBfloat16RoundedOperandsAndAccumulatesInFloat32) {
  // Reference without autocast: round the operands to bfloat16, convolve in
  // float32, round the result. The kernels accumulate in float32 in another
  // order, so the two may differ by one bfloat16 step at most: 2^-7 of the
  // power of two below the value, so at most 2^-7 of its magnitude.
  torch::manual_seed(1);
  const torch::Tensor x = torch::randn({4, 32, 64}), w = torch::randn({64, 32, 5}) * 0.1;
  const auto round = [](const torch::Tensor& t) { return t.to(torch::kBFloat16).to(torch::kFloat32); };
  const torch::Tensor reference = round(Conv(round(x), round(w)));
  torch::Tensor autocast;
  {
    const AutocastScope scope(Precision::kBf16);
    autocast = Conv(x, w);
  }
  ASSERT_EQ(autocast.scalar_type(), torch::kBFloat16);
  const torch::Tensor step = BfloatPartialSums()
                                 ? torch::conv1d(round(x).abs(), round(w).abs(), {}, 1, 2) * std::ldexp(1.0, -6)
                                 : reference.abs() * std::ldexp(1.0, -7) + 1e-6;
  EXPECT_TRUE(((autocast.to(torch::kFloat32) - reference).abs() <= step).all().item<bool>());
  // And it is not the float32 convolution.
  EXPECT_GT((autocast.to(torch::kFloat32) - Conv(x, w)).abs().max().item<double>(), 1e-3);
}

TEST(WidenBfloat16Test, WidensBfloat16AndPassesEveryOtherTensorThroughAsItIs) {
  const torch::Tensor f = torch::randn({3}), d = torch::randn({3}, torch::kFloat64);
  EXPECT_TRUE(WidenBfloat16(f).is_same(f));
  EXPECT_TRUE(WidenBfloat16(d).is_same(d));
  const torch::Tensor widened = WidenBfloat16(f.to(torch::kBFloat16));
  EXPECT_EQ(widened.scalar_type(), torch::kFloat32);
  EXPECT_TRUE(torch::equal(widened, f.to(torch::kBFloat16).to(torch::kFloat32)));
}

struct NetworkCase {
  const char* name;
  Architecture architecture;
  bool direct = false;  // conditioned on a (B, 2 D) start/goal vector
};

void PrintTo(const NetworkCase& c, std::ostream* os) { *os << c.name; }

class Bf16NetworkTest : public ::testing::TestWithParam<NetworkCase> {};

TEST_P(Bf16NetworkTest, ForwardAndBackwardRunUnderAutocastAndStayCloseToFloat32) {
  torch::manual_seed(2);
  const ModelConfig config = flowplan::testing::TinyModelConfig(GetParam().architecture);
  const int64_t D = 6, B = 8, T = 16;
  const int64_t C = GetParam().direct ? 2 * D : 0;
  NetworkPtr net = MakeNetwork(config, D, C);
  // The network's output and the gradient of a loss on it, in float32 and under bf16 autocast.
  const auto run = [&](Precision precision) {
    net->zero_grad();
    torch::Tensor out, loss;
    {
      const AutocastScope scope(precision);
      if (config.architecture == Architecture::kStateVae) {
        auto& vae = dynamic_cast<StateVae&>(*net);
        const StateVae::Encoding encoding = vae.Encode(torch::linspace(-1, 1, B * D).view({B, D}));
        EXPECT_EQ(encoding.log_var.scalar_type(), torch::kFloat32);
        out = vae.Decode(encoding.mean);
        loss = out.square().mean() + encoding.log_var.exp().mean();
      } else {
        auto& trajectory = dynamic_cast<TrajectoryNet&>(*net);
        out = trajectory.Forward(torch::linspace(-1, 1, B * T * D).view({B, T, D}), torch::linspace(0, 1, B),
                                 C > 0 ? torch::linspace(1, -1, B * C).view({B, C}) : torch::Tensor());
        loss = out.square().mean();
      }
    }
    EXPECT_EQ(out.scalar_type(), torch::kFloat32) << "networks return float32 under autocast too";
    loss.backward();
    std::vector<torch::Tensor> grads;
    for (const auto& p : net->parameters()) {
      EXPECT_EQ(p.grad().scalar_type(), torch::kFloat32);
      grads.push_back(p.grad().flatten().clone());
    }
    return std::make_pair(out.detach(), torch::cat(grads));
  };
  const auto [out32, grad32] = run(Precision::kFp32);
  const auto [out16, grad16] = run(Precision::kBf16);
  const double out_error = ((out16 - out32).norm() / out32.norm()).item<double>();
  EXPECT_GT(out_error, 1e-5) << "bf16 arithmetic should show in the output";
  EXPECT_LT(out_error, BfloatPartialSums() ? 1e-1 : 3e-2);
  EXPECT_TRUE(grad16.isfinite().all().item<bool>());
  EXPECT_GT(torch::cosine_similarity(grad16, grad32, 0).item<double>(), 0.995);
  // Back in float32 the network computes exactly what it did before.
  EXPECT_TRUE(torch::equal(run(Precision::kFp32).first, out32));
}

INSTANTIATE_TEST_SUITE_P(EveryNetwork, Bf16NetworkTest,
                         ::testing::Values(NetworkCase{"UNet1D", Architecture::kUNet1D},
                                           NetworkCase{"UNet1DDirect", Architecture::kUNet1D, true},
                                           NetworkCase{"Transformer", Architecture::kTransformer},
                                           NetworkCase{"TransformerDirect", Architecture::kTransformer, true},
                                           NetworkCase{"StateVae", Architecture::kStateVae}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace flowplan::models
