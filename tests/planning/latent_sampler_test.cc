// The VAE planner's sampler (planning/latent_sampler.py) on a VAE that is the
// identity, where its loop can be checked by hand.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "models/state_vae.h"
#include "planning/assemble.h"
#include "tests/support/planners.h"

namespace flowplan::planning {
namespace {

/// A state VAE that is the identity on (D,) states: encoder and decoder are
/// relu(z) − relu(−z) through a hidden layer [I; −I], the posterior is nearly a
/// point (log-variance −30). Planning in its latent space is then planning in
/// the state space itself, so the planner's loop can be checked by hand.
std::shared_ptr<models::StateVae> IdentityVae(int64_t D) {
  models::StateVaeConfig config;
  config.hidden = {static_cast<int>(2 * D)};
  config.latent = static_cast<int>(D);
  auto vae = std::make_shared<models::StateVae>(config, D);
  const torch::Tensor eye = torch::eye(D);
  const torch::Tensor split = torch::cat({eye, -eye}, 0);  // (2D, D)
  const torch::Tensor join = torch::cat({eye, -eye}, 1);   // (D, 2D)
  torch::NoGradGuard no_grad;
  for (auto& item : vae->named_parameters()) {
    const std::string& name = item.key();
    torch::Tensor& p = item.value();
    if (name.find("bias") != std::string::npos) {
      p.fill_(name == "log_var.bias" ? -30.0 : 0.0);
    } else if (name == "encoder0.weight" || name == "decoder0.weight") {
      p.copy_(split);
    } else if (name == "mean.weight" || name == "decoder1.weight") {
      p.copy_(join);
    } else {
      p.zero_();
    }
  }
  return vae;
}

struct Fixture {
  std::shared_ptr<models::StateVae> vae = IdentityVae(4);
  // Off the axes: the identity's ReLU pair has no gradient at exactly 0.
  torch::Tensor start = torch::tensor({{-0.6f, 0.01f, 0.01f, 0.01f}});
  torch::Tensor goal = torch::tensor({{0.6f, 0.01f, 0.01f, 0.01f}});

  std::unique_ptr<LearnedPlanner> Planner(double scale) const {
    PlannerParts parts = testing::Parts(vae, testing::DiscTrajectory(48), testing::UnitNormalizer(4));
    parts.objective.name = objectives::ObjectiveKind::kVae;
    parts.sampler.latent.lr = 0.01;
    parts.sampler.latent.goal_tolerance = 0.02;
    parts.guidance.scale = scale;
    parts.guidance.collision_weight = 1.0;
    parts.guidance.smoothness_weight = 0.0;
    parts.guidance.clip = 1.0;
    return AssemblePlanner(parts);
  }
};

TEST(LatentSamplerTest, IdentityVaeWalksStraightToTheGoalAndStaysThere) {
  const Fixture s;
  const torch::Tensor plan = s.Planner(0.0)->PlanWithNoise(s.start, s.goal, torch::zeros({1, 4}));
  ASSERT_EQ(plan.sizes(), torch::IntArrayRef({1, 48, 4}));
  EXPECT_TRUE(torch::equal(plan[0][0], s.start[0]));
  const torch::Tensor position = plan[0].slice(1, 0, 2);  // (T, 2)
  const torch::Tensor to_goal = (position - s.goal[0].slice(0, 0, 2)).norm(2, 1);
  EXPECT_LT(to_goal[-1].item<float>(), 0.02);
  // Straight: the path stays near the line y = 0.01 (Adam turns the prior's
  // tiny pull toward z = 0 into steps of up to lr) and moves toward the goal.
  EXPECT_LT((position.select(1, 1) - 0.01).abs().max().item<float>(), 0.01);
  EXPECT_TRUE(torch::all(position.select(1, 0).diff() >= -1e-3).item<bool>());
  // Once within the tolerance, the waypoint is held.
  const int64_t reached = (to_goal < 0.02).nonzero()[0].item<int64_t>();
  EXPECT_LT(reached, 47);
  EXPECT_TRUE(torch::equal(plan[0].slice(0, reached), plan[0][reached].expand({48 - reached, 4})));
}

TEST(LatentSamplerTest, CollisionCostStepsAroundADisc) {
  const Fixture s;
  // Slightly below the line, so that the push has a side.
  const torch::Tensor disc = torch::tensor({{0.0f, -0.02f, 0.15f}});
  const geometry::SceneRows scene = testing::Spheres(disc);
  const torch::Tensor noise = torch::zeros({1, 4});
  auto clearance = [&](const torch::Tensor& plan) {
    return ((plan[0].slice(1, 0, 2) - disc[0].slice(0, 0, 2)).norm(2, 1) - 0.15 - 0.05).min().item<float>();
  };
  const torch::Tensor straight = s.Planner(0.0)->PlanWithNoise(s.start, s.goal, noise, {}, scene);
  const torch::Tensor around = s.Planner(3.0)->PlanWithNoise(s.start, s.goal, noise, {}, scene);
  EXPECT_LT(clearance(straight), -0.1);
  EXPECT_GT(clearance(around), 0.0);
  EXPECT_LT((around[0][-1].slice(0, 0, 2) - s.goal[0].slice(0, 0, 2)).norm().item<float>(), 0.02);
}

TEST(LatentSamplerTest, WrongNoiseShapeIsAClearError) {
  const Fixture s;
  EXPECT_THAT([&] { s.Planner(0.0)->PlanWithNoise(s.start, s.goal, torch::zeros({1, 48, 4})); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("plan: noise: expected [1, 4], got [1, 48, 4]")));
}

}  // namespace
}  // namespace flowplan::planning
