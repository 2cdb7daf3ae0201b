#include "models/conditioning.h"

#include <gtest/gtest.h>

namespace flowplan::models {
namespace {

TEST(ConditioningTest, InpaintOverwritesOnlyTheEnds) {
  const torch::Tensor x = torch::zeros({2, 5, 3});
  const torch::Tensor start = torch::ones({2, 3}), goal = 2 * torch::ones({2, 3});
  const torch::Tensor y = Inpaint(x, start, goal);
  EXPECT_TRUE(torch::equal(y.select(1, 0), start));
  EXPECT_TRUE(torch::equal(y.select(1, 4), goal));
  EXPECT_TRUE(torch::equal(y.slice(1, 1, 4), x.slice(1, 1, 4)));
  EXPECT_FALSE(ConditionVector(Conditioning::kInpaint, start, goal).defined());
  EXPECT_EQ(ConditionVector(Conditioning::kDirect, start, goal).sizes(), (std::vector<int64_t>{2, 6}));
}

}  // namespace
}  // namespace flowplan::models
