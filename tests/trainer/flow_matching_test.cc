#include "trainer/flow_matching.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/model_config.h"

namespace flowplan::trainer {
namespace {

TEST(FlowMatchingTest, OtPathEndpointsAreNoiseAndData) {
  const torch::Tensor x0 = torch::randn({2, 4, 3}), x1 = torch::randn({2, 4, 3});
  EXPECT_TRUE(torch::equal(InterpolateOt(x0, x1, torch::zeros({2})), x0));
  EXPECT_TRUE(torch::equal(InterpolateOt(x0, x1, torch::ones({2})), x1));
  const torch::Tensor mid = InterpolateOt(x0, x1, torch::tensor({0.25f, 0.75f}));
  EXPECT_TRUE(torch::allclose(mid[0], 0.25 * x1[0] + 0.75 * x0[0]));
  EXPECT_TRUE(torch::allclose(mid[1], 0.75 * x1[1] + 0.25 * x0[1]));
}

TEST(FlowMatchingTest, SplitHalvesKeepsEachHalfWithItsOwnEnds) {
  const torch::Tensor x = torch::arange(2 * 8 * 1, torch::kFloat32).reshape({2, 8, 1});
  const torch::Tensor halves = SplitHalves(x);
  ASSERT_EQ(halves.sizes(), (std::vector<int64_t>{4, 4, 1}));
  EXPECT_TRUE(torch::equal(halves[0], x[0].slice(0, 0, 4)));
  EXPECT_TRUE(torch::equal(halves[1], x[1].slice(0, 0, 4)));
  EXPECT_TRUE(torch::equal(halves[2], x[0].slice(0, 4, 8)));
  EXPECT_TRUE(torch::equal(halves[3], x[1].slice(0, 4, 8)));
  EXPECT_THROW(SplitHalves(torch::zeros({1, 7, 1})), Error);
}

TEST(FlowMatchingTest, TrainingBatchesAreSplitWithTheGivenProbability) {
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

/// A velocity field that returns a fixed tensor, to check what the loss compares.
class FixedVelocity : public models::VelocityNet {
 public:
  explicit FixedVelocity(torch::Tensor v) : v_(std::move(v)) {}
  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor&, const torch::Tensor&) override {
    seen_ = x;
    return v_;
  }
  void CheckHorizon(int64_t) const override {}
  std::string WriteScript(jit::ScriptWriter&) const override { return ""; }
  int64_t state_dim() const override { return v_.size(2); }
  int64_t cond_dim() const override { return 0; }
  torch::Tensor seen_;

 private:
  torch::Tensor v_;
};

TEST(FlowMatchingTest, InpaintedLossIgnoresTheEndsAndSeesTheDataThere) {
  const torch::Tensor x1 = torch::randn({3, 6, 2});
  // Copy the generator so we can recompute the draws the loss makes.
  auto generator = at::make_generator<at::CPUGeneratorImpl>(3);
  auto replay = at::make_generator<at::CPUGeneratorImpl>(3);
  const torch::Tensor x0 = torch::randn(x1.sizes(), replay, x1.options());
  const torch::Tensor target = x1 - x0;
  torch::Tensor v = target.clone();
  v.select(1, 0).fill_(100.0);  // wrong at the ends only
  v.select(1, 5).fill_(-100.0);
  FixedVelocity net(v);
  const double loss = FlowMatchingLoss(net, x1, models::Conditioning::kInpaint, generator).item<double>();
  EXPECT_NEAR(loss, 0.0, 1e-10);
  EXPECT_TRUE(torch::equal(net.seen_.select(1, 0), x1.select(1, 0)));
  EXPECT_TRUE(torch::equal(net.seen_.select(1, 5), x1.select(1, 5)));
}

TEST(FlowMatchingTest, LossDecreasesOnATinyProblem) {
  torch::manual_seed(0);
  models::ModelConfig config;
  config.unet.down_dims = {16, 32};
  auto net = models::MakeVelocityNet(config, 2, 0);
  // Straight lines from (-1, -1) to (1, 1) with small offsets.
  const torch::Tensor s = torch::linspace(-1, 1, 16).view({1, 16, 1});
  const torch::Tensor x1 = (s + 0.1 * torch::randn({64, 1, 2})).expand({64, 16, 2}).contiguous();
  torch::optim::Adam optimizer(net->parameters(), torch::optim::AdamOptions(1e-3));
  auto generator = at::make_generator<at::CPUGeneratorImpl>(1);
  auto eval_loss = [&] {
    auto g = at::make_generator<at::CPUGeneratorImpl>(99);
    torch::NoGradGuard no_grad;
    return FlowMatchingLoss(*net, x1, models::Conditioning::kInpaint, g).item<double>();
  };
  const double before = eval_loss();
  for (int i = 0; i < 150; ++i) {
    optimizer.zero_grad();
    FlowMatchingLoss(*net, x1, models::Conditioning::kInpaint, generator).backward();
    optimizer.step();
  }
  const double after = eval_loss();
  EXPECT_LT(after, 0.5 * before) << "before " << before << " after " << after;
}

}  // namespace
}  // namespace flowplan::trainer
