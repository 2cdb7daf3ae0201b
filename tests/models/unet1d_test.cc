#include "models/unet1d.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/model_config.h"
#include "models/trajectory_net.h"

namespace flowplan::models {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

UNetConfig Small() {
  UNetConfig c;
  c.down_dims = {16, 32, 64};
  return c;
}

TEST(UNet1DTest, OutputHasTheInputShape) {
  torch::manual_seed(0);
  UNet1D net(UNetConfig{}, 4, 0);
  for (int64_t T : {8, 32, 64}) {
    const torch::Tensor x = torch::randn({3, T, 4});
    EXPECT_EQ(net.Forward(x, torch::rand({3}), torch::Tensor()).sizes(), x.sizes());
  }
}

TEST(UNet1DTest, DirectConditioningTakesACondVector) {
  UNet1D net(Small(), 14, 28);
  const torch::Tensor x = torch::randn({2, 16, 14});
  EXPECT_EQ(net.Forward(x, torch::rand({2}), torch::randn({2, 28})).sizes(), x.sizes());
  EXPECT_THAT([&] { net.Forward(x, torch::rand({2}), torch::Tensor()); },
              ThrowsMessage<Error>(HasSubstr("cond: expected (2, 28)")));
}

TEST(UNet1DTest, HorizonItCannotTakeIsAClearError) {
  UNet1D net(UNetConfig{}, 4, 0);  // 4 levels: T must be a multiple of 8
  EXPECT_THAT([&] { net.Forward(torch::randn({1, 30, 4}), torch::rand({1}), torch::Tensor()); },
              ThrowsMessage<Error>(AllOf(HasSubstr("multiple of 8"), HasSubstr("got 30"))));
  EXPECT_THAT([&] { net.CheckHorizon(4); }, ThrowsMessage<Error>(HasSubstr("got 4")));
}

TEST(UNet1DTest, WrongStateDimensionIsAClearError) {
  UNet1D net(Small(), 4, 0);
  EXPECT_THAT([&] { net.Forward(torch::randn({2, 16, 5}), torch::rand({2}), torch::Tensor()); },
              ThrowsMessage<Error>(HasSubstr("x: expected (B, T, 4), got (2, 16, 5)")));
  EXPECT_THAT([&] { net.Forward(torch::randn({2, 16, 4}), torch::rand({3}), torch::Tensor()); },
              ThrowsMessage<Error>(HasSubstr("t: expected (2,)")));
}

TEST(UNet1DTest, InvalidConfigNamesTheKey) {
  UNetConfig c;
  c.down_dims = {32, 60};
  EXPECT_THAT([&] { UNet1D(c, 4, 0); }, ThrowsMessage<Error>(HasSubstr("model.unet.down_dims[1]")));
  c = UNetConfig{};
  c.kernel_size = 4;
  EXPECT_THAT([&] { UNet1D(c, 4, 0); }, ThrowsMessage<Error>(HasSubstr("model.unet.kernel_size")));
}

TEST(UNet1DTest, TimeChangesTheOutput) {
  torch::manual_seed(1);
  UNet1D net(Small(), 4, 0);
  const torch::Tensor x = torch::randn({1, 16, 4});
  const torch::Tensor a = net.Forward(x, torch::tensor({0.1f}), torch::Tensor());
  const torch::Tensor b = net.Forward(x, torch::tensor({0.9f}), torch::Tensor());
  EXPECT_GT((a - b).abs().max().item<float>(), 1e-4);
}

TEST(ModelConfigTest, CopyWeightsMakesAnIdenticalNetwork) {
  torch::manual_seed(3);
  auto a = MakeTrajectoryNet(ModelConfig{}, 4, 0);
  torch::manual_seed(4);
  auto b = MakeTrajectoryNet(ModelConfig{}, 4, 0);
  const torch::Tensor x = torch::randn({2, 16, 4}), t = torch::rand({2});
  EXPECT_FALSE(torch::equal(a->Forward(x, t, {}), b->Forward(x, t, {})));
  CopyWeights(*a, *b);
  EXPECT_TRUE(torch::equal(a->Forward(x, t, {}), b->Forward(x, t, {})));
  EXPECT_GT(CountParameters(*a), 1000000);
}

TEST(ModelConfigTest, WeightsThatAreNotTheScriptsAreOneClearError) {
  // The planner matrix reads every network's weights back from its script; here what cannot be read back.
  torch::manual_seed(3);
  ModelConfig config;
  config.unet = Small();
  auto small = MakeTrajectoryNet(config, 4, 0);
  const torch::jit::Module script = ScriptNetwork(*small, Kernels::kPortable);
  auto other_state = MakeTrajectoryNet(config, 6, 0);
  EXPECT_THAT([&] { ReadScriptedWeights(*other_state, script, "f.pt"); },
              ThrowsMessage<Error>(HasSubstr("f.pt: network weight p_down0_block0_block0_conv_weight is (16, 4, 5), "
                                             "its config's model.* makes it (16, 6, 5)")));
  auto default_size = MakeTrajectoryNet(ModelConfig{}, 4, 0);
  EXPECT_THAT([&] { ReadScriptedWeights(*default_size, script, "f.pt"); },
              ThrowsMessage<Error>(HasSubstr("f.pt: network weight p_films_bias is (896,), its config's model.* makes it "
                                             "(3840,)")));
  ModelConfig transformer;
  transformer.architecture = Architecture::kTransformer;
  auto another_kind = MakeTrajectoryNet(transformer, 4, 0);
  EXPECT_THAT([&] { ReadScriptedWeights(*another_kind, script, "f.pt"); },
              ThrowsMessage<Error>(HasSubstr("f.pt: network weight p_frequencies is (16,), its config's model.* makes it")));
  torch::manual_seed(4);
  auto same = MakeTrajectoryNet(config, 4, 0);
  ReadScriptedWeights(*same, script, "f.pt");
  const torch::Tensor x = torch::randn({2, 16, 4}), t = torch::rand({2});
  EXPECT_TRUE(torch::equal(small->Forward(x, t, {}), same->Forward(x, t, {})));
}

TEST(ModelConfigTest, ANetworkOfMoreWeightsThanOneMarkingPassIsReadBackInWindows) {
  ModelConfig config;
  config.unet.down_dims = {64, 128, 256, 512};  // 15.8 million weights: more than one pass numbers (15.7 million)
  torch::manual_seed(3);
  auto big = MakeTrajectoryNet(config, 14, 0);
  EXPECT_GT(CountParameters(*big), (1 << 24) - (1 << 20));
  const torch::jit::Module script = ScriptNetwork(*big, Kernels::kPortable);
  torch::manual_seed(4);
  auto again = MakeTrajectoryNet(config, 14, 0);
  ReadScriptedWeights(*again, script, "big.pt");
  const auto want = big->named_parameters(true), got = again->named_parameters(true);
  for (const auto& entry : want) EXPECT_TRUE(torch::equal(entry.value(), got[entry.key()])) << entry.key();
}

}  // namespace
}  // namespace flowplan::models
