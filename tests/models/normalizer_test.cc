#include "models/normalizer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace flowplan::models {
namespace {

TEST(NormalizerTest, MapsTheTrainingRangeOntoMinusOneOne) {
  torch::manual_seed(0);
  const torch::Tensor data = torch::rand({50, 8, 3}) * torch::tensor({2.0f, 10.0f, 0.1f}) - 1.0;
  const MinMaxNormalizer n = MinMaxNormalizer::Fit(data);
  const torch::Tensor z = n.Normalize(data);
  EXPECT_NEAR(z.min().item<float>(), -1.0f, 1e-6);
  EXPECT_NEAR(z.max().item<float>(), 1.0f, 1e-6);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(z.select(2, d).min().item<float>(), -1.0f, 1e-6);
    EXPECT_NEAR(z.select(2, d).max().item<float>(), 1.0f, 1e-6);
  }
}

TEST(NormalizerTest, RoundTripInsideTheRange) {
  const torch::Tensor data = torch::linspace(-3.0, 5.0, 64).reshape({8, 4, 2});
  const MinMaxNormalizer n = MinMaxNormalizer::Fit(data);
  EXPECT_TRUE(torch::allclose(n.Denormalize(n.Normalize(data)), data, 1e-5, 1e-5));
}

TEST(NormalizerTest, DenormalizeClampsOutsideTheRange) {
  const MinMaxNormalizer n(torch::tensor({0.0f}), torch::tensor({2.0f}));
  EXPECT_FLOAT_EQ(n.Denormalize(torch::tensor({3.0f})).item<float>(), 2.0f);
  EXPECT_FLOAT_EQ(n.DenormalizeUnclamped(torch::tensor({3.0f})).item<float>(), 4.0f);
}

TEST(NormalizerTest, ConstantDimensionStaysFinite) {
  const torch::Tensor data = torch::ones({4, 5, 2});
  const MinMaxNormalizer n = MinMaxNormalizer::Fit(data);
  EXPECT_TRUE(torch::isfinite(n.Normalize(data)).all().item<bool>());
}

TEST(NormalizerTest, WrongDimensionIsAClearError) {
  const MinMaxNormalizer n(torch::zeros({4}), torch::ones({4}));
  EXPECT_THAT([&] { n.Normalize(torch::zeros({2, 3})); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("expected (..., 4)")));
}

}  // namespace
}  // namespace flowplan::models
