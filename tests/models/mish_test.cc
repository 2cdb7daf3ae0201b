#include "models/mish.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.h"

namespace flowplan::models {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Values over the range that matters, the edges of the kernel's clamps and
// huge ones, first (the vector loop's body) and last (its scalar tail), in
// more elements than one parallel task takes.
torch::Tensor Points() {
  torch::manual_seed(4);
  const torch::Tensor edges = torch::tensor({-100.0f, -87.5f, -87.0f, -86.9f, -20.0f, -1e-30f, 0.0f, 1e-30f, 19.99f,
                                             20.0f, 20.01f, 1e10f, 3e38f, -1e10f, -3e38f});
  return torch::cat({edges, torch::linspace(-100, 100, 40001), torch::randn({4096}) * 3, edges});
}

TEST(MishTest, MatchesTorchMishInFloat64) {
  const torch::Tensor x = Points();
  const torch::Tensor ours = Mish(x).to(torch::kFloat64);
  const torch::Tensor reference = torch::mish(x.to(torch::kFloat64));
  // Below -87 mish is under 1.5e-36 in magnitude and the kernel gives -0.
  const torch::Tensor relative = (ours - reference).abs() / (reference.abs() + 1.5e-36);
  EXPECT_TRUE(((ours - reference).abs() <= reference.abs() * 4e-7 + 1.5e-36).all().item<bool>())
      << "largest relative error " << relative.max().item<double>() << " at x = "
      << x[relative.argmax()].item<float>();
  // Shapes and strides of the input do not matter.
  const torch::Tensor strided = torch::randn({6, 5, 4}).transpose(0, 2);
  EXPECT_TRUE(torch::allclose(Mish(strided), torch::mish(strided), 1e-6, 1e-7));
  EXPECT_EQ(Mish(strided).sizes(), strided.sizes());
}

TEST(MishTest, GradientMatchesAutogradOfTorchMishInFloat64) {
  const torch::Tensor x = Points();
  const torch::Tensor leaf = x.clone().requires_grad_(true);
  const torch::Tensor y = Mish(leaf);
  ASSERT_TRUE(y.grad_fn());
  EXPECT_THAT(y.grad_fn()->name(), ::testing::HasSubstr("MishFunction")) << "float32 must take flowplan's kernel";
  const torch::Tensor g = torch::linspace(-2, 2, x.numel());
  y.backward(g);
  const torch::Tensor reference_leaf = x.to(torch::kFloat64).requires_grad_(true);
  torch::mish(reference_leaf).backward(g.to(torch::kFloat64));
  const torch::Tensor ours = leaf.grad().to(torch::kFloat64), reference = reference_leaf.grad();
  EXPECT_TRUE(((ours - reference).abs() <= reference.abs() * 2e-6 + 1e-6).all().item<bool>())
      << "largest difference " << (ours - reference).abs().max().item<double>();
}

TEST(MishTest, InfinitiesAndNanGiveTheLimitsAndNan) {
  const torch::Tensor x = torch::tensor({kInf, -kInf, NAN, 1.0f}).repeat({20});  // vector body and tail
  const torch::Tensor leaf = x.clone().requires_grad_(true);
  const torch::Tensor y = Mish(leaf);
  y.backward(torch::ones_like(y));
  for (int64_t i : {int64_t{0}, int64_t{76}}) {
    EXPECT_EQ(y[i].item<float>(), kInf);
    EXPECT_EQ(y[i + 1].item<float>(), 0.0f);
    EXPECT_TRUE(std::isnan(y[i + 2].item<float>()));
    EXPECT_EQ(leaf.grad()[i].item<float>(), 1.0f);
    EXPECT_EQ(leaf.grad()[i + 1].item<float>(), 0.0f);
    EXPECT_TRUE(std::isnan(leaf.grad()[i + 2].item<float>()));
  }
}

TEST(MishTest, SameBitsForAnyThreadCount) {
  const torch::Tensor x = Points().repeat({4});  // several parallel tasks
  const int threads = at::get_num_threads();
  const auto run = [&](int n) {
    at::set_num_threads(n);
    const torch::Tensor leaf = x.clone().requires_grad_(true);
    const torch::Tensor y = Mish(leaf);
    y.backward(torch::ones_like(y));
    return std::make_pair(y.detach(), leaf.grad());
  };
  const auto one = run(1), two = run(2);
  at::set_num_threads(threads);
  EXPECT_TRUE(torch::equal(one.first, two.first));
  EXPECT_TRUE(torch::equal(one.second, two.second));
}

TEST(MishTest, OtherTypesGoToTorchMishAndBfloat16IsWidened) {
  const torch::Tensor d = torch::randn({100}, torch::kFloat64);
  EXPECT_TRUE(torch::equal(Mish(d), torch::mish(d)));
  const torch::Tensor b = torch::randn({100}).to(torch::kBFloat16);
  EXPECT_EQ(Mish(b).scalar_type(), torch::kFloat32);
  EXPECT_TRUE(torch::allclose(Mish(b), torch::mish(b.to(torch::kFloat32)), 1e-6, 1e-7));
}

TEST(MishTest, ASecondDerivativeIsAClearError) {
  const torch::Tensor x = torch::randn({8}).requires_grad_(true);
  const torch::Tensor y = Mish(x).sum();
  EXPECT_THAT([&] { torch::autograd::grad({y}, {x}, {}, true, true); },
              ::testing::Throws<std::exception>());
}

}  // namespace
}  // namespace flowplan::models
