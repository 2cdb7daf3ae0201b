// The training objectives: what each loss compares, the DDPM schedule, and
// that each loss trains its network on a tiny problem.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "models/model_config.h"
#include "objectives/ddpm.h"
#include "objectives/flow_matching.h"
#include "objectives/objective.h"
#include "objectives/vae.h"
#include "tests/support/tiny_model.h"

namespace flowplan::objectives {
namespace {

using ::testing::HasSubstr;

TEST(FlowMatchingTest, OtPathEndpointsAreNoiseAndData) {
  const torch::Tensor x0 = torch::randn({2, 4, 3}), x1 = torch::randn({2, 4, 3});
  EXPECT_TRUE(torch::equal(InterpolateOt(x0, x1, torch::zeros({2})), x0));
  EXPECT_TRUE(torch::equal(InterpolateOt(x0, x1, torch::ones({2})), x1));
  const torch::Tensor mid = InterpolateOt(x0, x1, torch::tensor({0.25f, 0.75f}));
  EXPECT_TRUE(torch::allclose(mid[0], 0.25 * x1[0] + 0.75 * x0[0]));
  EXPECT_TRUE(torch::allclose(mid[1], 0.75 * x1[1] + 0.25 * x0[1]));
}

/// A trajectory network that returns a fixed tensor, to check what a loss compares.
class FixedOutput : public models::TrajectoryNet {
 public:
  explicit FixedOutput(torch::Tensor v) : v_(std::move(v)) {}
  torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor&) override {
    seen_x_ = x;
    seen_t_ = t;
    return v_;
  }
  void CheckHorizon(int64_t) const override {}
  std::string WriteScript(jit::ScriptWriter&) const override { return ""; }
  int64_t state_dim() const override { return v_.size(2); }
  int64_t cond_dim() const override { return 0; }
  torch::Tensor seen_x_, seen_t_;

 private:
  torch::Tensor v_;
};

TEST(FlowMatchingTest, InpaintedLossIgnoresTheEndsAndSeesTheDataThere) {
  const torch::Tensor x1 = torch::randn({3, 6, 2});
  FlowMatchingObjective objective;
  auto generator = at::make_generator<at::CPUGeneratorImpl>(3);
  const ObjectiveBatch batch = objective.Draw(x1, generator);
  torch::Tensor v = (x1 - batch.noise).clone();
  v.select(1, 0).fill_(100.0);  // wrong at the ends only
  v.select(1, 5).fill_(-100.0);
  FixedOutput net(v);
  EXPECT_NEAR(objective.Loss(net, batch, models::Conditioning::kInpaint).item<double>(), 0.0, 1e-10);
  EXPECT_TRUE(torch::equal(net.seen_x_.select(1, 0), x1.select(1, 0)));
  EXPECT_TRUE(torch::equal(net.seen_x_.select(1, 5), x1.select(1, 5)));
  EXPECT_TRUE(torch::equal(net.seen_t_, batch.time));
  // Under direct conditioning every state counts.
  EXPECT_GT(objective.Loss(net, batch, models::Conditioning::kDirect).item<double>(), 100.0);
}

TEST(DdpmTest, ScheduleIsMpdsExponentialAndEndsInNoise) {
  DdpmConfig config;  // 25 steps, beta 1e-4 .. 1.0, clipped at 0.999
  const DdpmSchedule schedule(config);
  ASSERT_EQ(schedule.betas.size(0), 25);
  EXPECT_NEAR(schedule.beta(0), 1e-4, 1e-12);
  // beta_k = 1e-4 exp(ln(1e4)/25 · 25k/24): a constant ratio between steps.
  const double ratio = std::exp(std::log(1e4) / 25.0 * 25.0 / 24.0);
  for (int k = 1; k < 24; ++k) EXPECT_NEAR(schedule.beta(k) / schedule.beta(k - 1), ratio, 1e-9) << k;
  EXPECT_DOUBLE_EQ(schedule.beta(24), 0.999);
  EXPECT_LT(schedule.alpha_bar(24), 1e-3);  // the first sampling step starts from (nearly) pure noise
  EXPECT_GT(schedule.alpha_bar(0), 0.9998);
  EXPECT_NEAR(schedule.alpha_bar(3), (1 - schedule.beta(0)) * (1 - schedule.beta(1)) * (1 - schedule.beta(2)) *
                                         (1 - schedule.beta(3)),
              1e-15);
}

TEST(DdpmTest, LinearScheduleIsDdpmsAsTheFlowPlannerPapersBaselineUsedIt) {
  // 10 steps, beta 1e-4 .. 0.02 evenly spaced: the largest training noise std
  // is sqrt(1 - ᾱ_9) ≈ 0.31, far from the unit noise sampling starts from.
  DdpmConfig config;
  config.steps = 10;
  config.schedule = BetaSchedule::kLinear;
  config.beta_end = 0.02;
  const DdpmSchedule schedule(config);
  ASSERT_EQ(schedule.betas.size(0), 10);
  for (int k = 0; k < 10; ++k) EXPECT_NEAR(schedule.beta(k), 1e-4 + k * (0.02 - 1e-4) / 9.0, 1e-15) << k;
  double product = 1.0;
  for (int k = 0; k < 10; ++k) product *= 1.0 - (1e-4 + k * (0.02 - 1e-4) / 9.0);
  EXPECT_NEAR(schedule.alpha_bar(9), product, 1e-14);
  EXPECT_NEAR(std::sqrt(1.0 - schedule.alpha_bar(9)), 0.3103, 1e-4);
}

TEST(DdpmTest, LossRegressesTheNoiseOfTheDrawnStep) {
  const torch::Tensor x1 = torch::randn({4, 8, 3});
  DdpmObjective objective(DdpmConfig{});
  auto generator = at::make_generator<at::CPUGeneratorImpl>(5);
  const ObjectiveBatch batch = objective.Draw(x1, generator);
  EXPECT_TRUE((batch.time >= 0).all().item<bool>() && (batch.time <= 24).all().item<bool>());
  EXPECT_TRUE(torch::equal(batch.time, batch.time.round()));
  FixedOutput net(batch.noise);
  EXPECT_NEAR(objective.Loss(net, batch, models::Conditioning::kDirect).item<double>(), 0.0, 1e-12);
  // The network saw sqrt(ᾱ_k) x1 + sqrt(1 − ᾱ_k) ε at the interior.
  const int64_t k = batch.time[2].item<int64_t>();
  const double a = objective.schedule().alpha_bar(static_cast<int>(k));
  EXPECT_TRUE(torch::allclose(net.seen_x_[2], std::sqrt(a) * x1[2] + std::sqrt(1 - a) * batch.noise[2], 1e-5, 1e-6));
}

TEST(ObjectiveTest, AnObjectiveRejectsTheWrongKindOfNetwork) {
  models::ModelConfig vae;
  vae.architecture = models::Architecture::kStateVae;
  auto net = models::MakeNetwork(vae, 4, 0);
  FlowMatchingObjective flow;
  auto generator = at::make_generator<at::CPUGeneratorImpl>(1);
  const ObjectiveBatch batch = flow.Draw(torch::randn({2, 8, 4}), generator);
  EXPECT_THAT([&] { flow.Loss(*net, batch, models::Conditioning::kInpaint); },
              ::testing::ThrowsMessage<Error>(HasSubstr("flow_matching trains a trajectory network")));
  models::ModelConfig unet;
  unet.unet.down_dims = {8};
  auto trajectory = models::MakeNetwork(unet, 4, 0);
  VaeObjective vae_objective(VaeObjectiveConfig{}, 64);
  EXPECT_THAT([&] { vae_objective.Loss(*trajectory, vae_objective.Draw(batch.x1, generator), {}); },
              ::testing::ThrowsMessage<Error>(HasSubstr("vae trains a state VAE")));
}

/// Straight lines from (-1, -1) to (1, 1) with small offsets: (64, 16, 2).
torch::Tensor Lines() {
  const torch::Tensor s = torch::linspace(-1, 1, 16).view({1, 16, 1});
  return (s + 0.1 * torch::randn({64, 1, 2})).expand({64, 16, 2}).contiguous();
}

struct Case {
  const char* name;
  ObjectiveKind objective;
  models::Architecture architecture;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class TrainsTest : public ::testing::TestWithParam<Case> {};

TEST_P(TrainsTest, LossHalvesOnATinyProblem) {
  torch::manual_seed(0);
  const models::ModelConfig model = flowplan::testing::TinyModelConfig(GetParam().architecture);
  ObjectiveConfig config;
  config.name = GetParam().objective;
  const auto objective = MakeObjective(config, model);
  auto net = models::MakeNetwork(model, 2, 0);
  const torch::Tensor x1 = Lines();
  torch::optim::Adam optimizer(net->parameters(), torch::optim::AdamOptions(1e-3));
  auto generator = at::make_generator<at::CPUGeneratorImpl>(1);
  auto eval_loss = [&] {
    auto g = at::make_generator<at::CPUGeneratorImpl>(99);
    torch::NoGradGuard no_grad;
    return objective->Loss(*net, objective->Draw(x1, g), config.conditioning).item<double>();
  };
  const double before = eval_loss();
  for (int i = 0; i < 150; ++i) {
    optimizer.zero_grad();
    objective->Loss(*net, objective->Draw(x1, generator), config.conditioning).backward();
    optimizer.step();
  }
  const double after = eval_loss();
  EXPECT_LT(after, 0.5 * before) << "before " << before << " after " << after;
}

INSTANTIATE_TEST_SUITE_P(Zoo, TrainsTest,
                         ::testing::Values(Case{"FlowUNet", ObjectiveKind::kFlowMatching, models::Architecture::kUNet1D},
                                           Case{"FlowTransformer", ObjectiveKind::kFlowMatching,
                                                models::Architecture::kTransformer},
                                           Case{"DdpmUNet", ObjectiveKind::kDdpm, models::Architecture::kUNet1D},
                                           Case{"Vae", ObjectiveKind::kVae, models::Architecture::kStateVae}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace flowplan::objectives
