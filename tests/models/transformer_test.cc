#include "models/transformer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace flowplan::models {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

TransformerConfig Small() {
  TransformerConfig c;
  c.d_model = 32;
  c.heads = 4;
  return c;
}

TEST(TransformerTest, OutputHasTheInputShapeForAnyHorizon) {
  torch::manual_seed(0);
  Transformer net(Small(), 4, 0);
  for (int64_t T : {7, 16, 64}) {
    const torch::Tensor x = torch::randn({3, T, 4});
    EXPECT_EQ(net.Forward(x, torch::rand({3}), torch::Tensor()).sizes(), x.sizes());
  }
}

TEST(TransformerTest, TheDefaultIsSpecsSize) {
  const TransformerConfig c;
  EXPECT_EQ(c.d_model, 256);
  EXPECT_EQ(c.heads, 4);
  EXPECT_EQ(c.layers, 2);
}

TEST(TransformerTest, ConditioningTokensChangeTheOutputButAreNotReadOut) {
  torch::manual_seed(1);
  Transformer net(Small(), 4, 8);
  const torch::Tensor x = torch::randn({2, 16, 4}), t = torch::rand({2});
  const torch::Tensor cond = torch::randn({2, 8});
  const torch::Tensor out = net.Forward(x, t, cond);
  EXPECT_EQ(out.sizes(), x.sizes());  // the start/goal tokens are attended to, not returned
  EXPECT_GT((out - net.Forward(x, t, cond + 0.5)).abs().max().item<float>(), 1e-4);
  // Only the second row's condition changes: the first row's output is its own.
  torch::Tensor other = cond.clone();
  other[1] += 1.0;
  const torch::Tensor mixed = net.Forward(x, t, other);
  EXPECT_LT((mixed[0] - out[0]).abs().max().item<float>(), 1e-6);
  EXPECT_GT((mixed[1] - out[1]).abs().max().item<float>(), 1e-4);
  EXPECT_THAT([&] { net.Forward(x, t, torch::Tensor()); }, ThrowsMessage<Error>(HasSubstr("cond: expected (2, 8)")));
}

TEST(TransformerTest, PositionsAndTimeMatter) {
  // Attention alone is permutation-equivariant; the sinusoidal positions break
  // that, so reversing the states does not just reverse the output.
  torch::manual_seed(2);
  Transformer net(Small(), 4, 0);
  const torch::Tensor x = torch::randn({1, 16, 4}), t = torch::full({1}, 0.3f);
  const torch::Tensor out = net.Forward(x, t, torch::Tensor());
  const torch::Tensor reversed = net.Forward(x.flip({1}), t, torch::Tensor()).flip({1});
  EXPECT_GT((out - reversed).abs().max().item<float>(), 1e-4);
  EXPECT_GT((out - net.Forward(x, t + 0.5, torch::Tensor())).abs().max().item<float>(), 1e-4);
}

TEST(TransformerTest, StatesInTheBatchDoNotSeeEachOther) {
  torch::manual_seed(3);
  Transformer net(Small(), 4, 0);
  const torch::Tensor x = torch::randn({2, 16, 4}), t = torch::rand({2});
  const torch::Tensor alone = net.Forward(x.slice(0, 0, 1), t.slice(0, 0, 1), torch::Tensor());
  EXPECT_LT((net.Forward(x, t, torch::Tensor())[0] - alone[0]).abs().max().item<float>(), 1e-5);
}

TEST(TransformerTest, InvalidConfigNamesTheKey) {
  TransformerConfig c = Small();
  c.heads = 5;
  EXPECT_THAT([&] { Transformer(c, 4, 0); }, ThrowsMessage<Error>(HasSubstr("model.transformer.heads")));
  EXPECT_THAT([&] { Transformer(Small(), 4, 0).Forward(torch::randn({2, 16, 3}), torch::rand({2}), torch::Tensor()); },
              ThrowsMessage<Error>(HasSubstr("expected")));
}

}  // namespace
}  // namespace flowplan::models
