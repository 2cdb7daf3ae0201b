#include "models/state_vae.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "jit/library.h"

namespace flowplan::models {
namespace {

TEST(StateVaeTest, ShapesFollowTheConfig) {
  StateVaeConfig config;
  config.hidden = {32, 16};
  config.latent = 5;
  StateVae vae(config, 14);
  const StateVae::Encoding e = vae.Encode(torch::randn({3, 14}));
  EXPECT_EQ(e.mean.sizes(), torch::IntArrayRef({3, 5}));
  EXPECT_EQ(e.log_var.sizes(), torch::IntArrayRef({3, 5}));
  EXPECT_EQ(vae.Decode(e.mean).sizes(), torch::IntArrayRef({3, 14}));
  EXPECT_THAT([&] { vae.Encode(torch::randn({3, 13})); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("state VAE: x: expected (N, 14)")));
}

TEST(StateVaeTest, ScriptMatchesTheNetworkAndItsDecodeVjpIsAutogradsVectorJacobianProduct) {
  torch::manual_seed(3);
  StateVaeConfig config;
  config.hidden = {32, 16};
  config.latent = 6;
  StateVae vae(config, 4);
  vae.to(torch::kFloat64);
  const torch::Tensor z = torch::randn({5, 6}, torch::kFloat64).requires_grad_(true);
  const torch::Tensor g = torch::randn({5, 4}, torch::kFloat64);
  (vae.Decode(z) * g).sum().backward();
  torch::NoGradGuard no_grad;
  const torch::jit::Module script = vae.ToScript();
  EXPECT_TRUE(torch::allclose(jit::Call(script, "decode_vjp", {z.detach(), g}).toTensor(), z.grad(), 1e-12, 1e-12));
  EXPECT_TRUE(torch::equal(jit::Call(script, "decode", {z.detach()}).toTensor(), vae.Decode(z.detach())));
  const torch::Tensor x = torch::randn({5, 4}, torch::kFloat64);
  const auto encoded = jit::Call(script, "encode", {x}).toTuple()->elements();
  EXPECT_TRUE(torch::equal(encoded[0].toTensor(), vae.Encode(x).mean));
  EXPECT_TRUE(torch::equal(encoded[1].toTensor(), vae.Encode(x).log_var));
}

}  // namespace
}  // namespace flowplan::models
