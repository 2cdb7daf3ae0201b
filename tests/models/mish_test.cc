#include "models/mish.h"

#include <gtest/gtest.h>

#include <cmath>

namespace flowplan::models {
namespace {

// Values over the whole float32 range that matters, and the edges of the kernel's clamps.
torch::Tensor Points() {
  torch::manual_seed(4);
  return torch::cat({torch::linspace(-100, 100, 20001), torch::randn({4096}) * 3,
                     torch::tensor({-87.5f, -87.0f, -86.9f, -20.0f, -1e-30f, 0.0f, 1e-30f, 19.99f, 20.0f, 20.01f,
                                    3e38f})});
}

TEST(MishTest, MatchesTorchMishInFloat64) {
  const torch::Tensor x = Points();
  const torch::Tensor ours = Mish(x).to(torch::kFloat64);
  const torch::Tensor reference = torch::mish(x.to(torch::kFloat64));
  EXPECT_TRUE(((ours - reference).abs() <= reference.abs() * 4e-7 + 1e-30).all().item<bool>())
      << "largest relative error " << ((ours - reference).abs() / (reference.abs() + 1e-30)).max().item<double>();
  // Shapes and strides of the input do not matter.
  const torch::Tensor strided = torch::randn({6, 5, 4}).transpose(0, 2);
  EXPECT_TRUE(torch::allclose(Mish(strided), torch::mish(strided), 1e-6, 1e-7));
  EXPECT_EQ(Mish(strided).sizes(), strided.sizes());
}

TEST(MishTest, GradientMatchesAutogradOfTorchMishInFloat64) {
  const torch::Tensor x = Points().slice(0, 0, -1);  // without 3e38, whose mish' is 1 but whose product overflows
  const torch::Tensor leaf = x.clone().requires_grad_(true);
  const torch::Tensor g = torch::linspace(-2, 2, x.numel());
  Mish(leaf).backward(g);
  const torch::Tensor reference_leaf = x.to(torch::kFloat64).requires_grad_(true);
  torch::mish(reference_leaf).backward(g.to(torch::kFloat64));
  const torch::Tensor ours = leaf.grad().to(torch::kFloat64), reference = reference_leaf.grad();
  EXPECT_TRUE(((ours - reference).abs() <= reference.abs() * 2e-6 + 1e-6).all().item<bool>())
      << "largest difference " << (ours - reference).abs().max().item<double>();
}

TEST(MishTest, OtherTypesGoToTorchMishAndBfloat16IsWidened) {
  const torch::Tensor d = torch::randn({100}, torch::kFloat64);
  EXPECT_TRUE(torch::equal(Mish(d), torch::mish(d)));
  const torch::Tensor b = torch::randn({100}).to(torch::kBFloat16);
  EXPECT_EQ(Mish(b).scalar_type(), torch::kFloat32);
  EXPECT_TRUE(torch::allclose(Mish(b), torch::mish(b.to(torch::kFloat32)), 1e-6, 1e-7));
}

TEST(MishTest, NanStaysNan) {
  EXPECT_TRUE(std::isnan(Mish(torch::tensor({NAN})).item<float>()));
}

}  // namespace
}  // namespace flowplan::models
