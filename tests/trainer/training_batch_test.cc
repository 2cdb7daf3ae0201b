#include "trainer/training_batch.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace flowplan::trainer {
namespace {

TEST(TrainingBatchTest, SplitHalvesKeepsEachHalfWithItsOwnEnds) {
  const torch::Tensor x = torch::arange(2 * 8 * 1, torch::kFloat32).reshape({2, 8, 1});
  const torch::Tensor halves = SplitHalves(x);
  ASSERT_EQ(halves.sizes(), (std::vector<int64_t>{4, 4, 1}));
  EXPECT_TRUE(torch::equal(halves[0], x[0].slice(0, 0, 4)));
  EXPECT_TRUE(torch::equal(halves[1], x[1].slice(0, 0, 4)));
  EXPECT_TRUE(torch::equal(halves[2], x[0].slice(0, 4, 8)));
  EXPECT_TRUE(torch::equal(halves[3], x[1].slice(0, 4, 8)));
  EXPECT_THROW(SplitHalves(torch::zeros({1, 7, 1})), Error);
}

TEST(TrainingBatchTest, TrainingBatchesAreSplitWithTheGivenProbability) {
  // Row i of the data holds the value i everywhere, so each drawn row says where it came from.
  const torch::Tensor data = torch::arange(20, torch::kFloat32).view({20, 1, 1}).expand({20, 8, 3}).contiguous();
  auto generator = at::make_generator<at::CPUGeneratorImpl>(5);
  const torch::Tensor whole = DrawTrainingTrajectories(data, 6, 0.0, generator);
  ASSERT_EQ(whole.sizes(), (std::vector<int64_t>{6, 8, 3}));
  const torch::Tensor split = DrawTrainingTrajectories(data, 6, 1.0, generator);
  ASSERT_EQ(split.sizes(), (std::vector<int64_t>{12, 4, 3}));
  // First halves, then the second halves of the same rows, in the same order.
  EXPECT_TRUE(torch::equal(split.slice(0, 0, 6), split.slice(0, 6, 12)));
  for (int64_t i = 0; i < 6; ++i) EXPECT_TRUE(torch::equal(split[i], data[split[i][0][0].item<int64_t>()].slice(0, 0, 4)));
  int splits = 0;
  for (int draw = 0; draw < 400; ++draw) splits += DrawTrainingTrajectories(data, 2, 0.5, generator).size(1) == 4;
  EXPECT_NEAR(splits / 400.0, 0.5, 0.1);  // 4 standard deviations
}

}  // namespace
}  // namespace flowplan::trainer
