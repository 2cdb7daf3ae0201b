// The native whole-arm collision hinge (guidance/arm_collision.py over
// flowplan::arm_collision, kernels/arm_collision_kernel.h) against the
// script it stands for (guidance/collision.py over LibTorch's operators,
// itself held to central differences and autograd in cost_test.cc): the
// Franka among every kind of shape in float64 and float32, pairs just inside
// and just beyond a sphere's reach, the same
// bits for any thread count, what the operator does not take going to the
// script, and bad input as one clear error.

#include <ATen/Parallel.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "guidance/guide.h"
#include "jit/library.h"
#include "kinematics/robot.h"
#include "models/normalizer.h"
#include "sim/franka_model.h"

namespace flowplan::guidance {
namespace {

using ::testing::HasSubstr;

const kinematics::Robot& Franka() {
  static const kinematics::Robot robot(sim::LoadFrankaModel().description());
  return robot;
}

c10::Dict<std::string, double> Opts(const GuidanceConfig& config) {
  c10::Dict<std::string, double> opts;
  for (const auto& [key, value] : config::ListNumbers(config, "guidance")) opts.insert(key, value);
  return opts;
}

/// The collision term (the chain's first) of the guide with distances in `kernels`.
torch::jit::Module Collision(models::Kernels kernels) {
  GuidanceConfig config;
  config.distance_kernels = kernels;
  const models::MinMaxNormalizer unit(-torch::ones({14}), torch::ones({14}));
  return BuildGuide(config, Franka(), unit.module(), 0.05).attr("costs").toModule().attr("term").toModule();
}

struct Evaluated {
  torch::Tensor value, grad_q, grad_qd;
};

Evaluated Evaluate(const torch::jit::Module& term, const torch::Tensor& q, const geometry::SceneRows& scene) {
  const auto out = jit::Call(term, "value_and_gradient", {q, torch::zeros_like(q), scene, Opts(GuidanceConfig())})
                       .toTuple()
                       ->elements();
  return {out[0].toTensor(), out[1].toTensor(), out[2].toTensor()};
}

/// Franka configurations (B, T, 7) inside the limits.
torch::Tensor Configurations(int64_t B, int64_t T, uint64_t seed) {
  torch::manual_seed(seed);
  const auto& d = Franka().description();
  const torch::Tensor lo = torch::tensor(d.joint_lower, torch::kFloat64), hi = torch::tensor(d.joint_upper, torch::kFloat64);
  return lo + (hi - lo) * (0.1 + 0.8 * torch::rand({B, T, 7}, torch::kFloat64));
}

/// A crowded scene about the arm's sphere centres `centres` (M, S, 3): shapes of every kind, rotated, some
/// swallowing spheres, some grazing them, some far; and one sphere obstacle whose surface lies 1e-5 m inside
/// a collision sphere's reach (margin 0.05 + radius), and one 1e-5 m beyond it.
geometry::SceneRows CrowdedScene(const torch::Tensor& centres, double radius_of_first, uint64_t seed) {
  torch::manual_seed(seed);
  const int64_t M = centres.size(0), S = centres.size(1);
  auto somewhere = [&] {
    const int64_t m = torch::randint(M, {1}).item<int64_t>(), s = torch::randint(S, {1}).item<int64_t>();
    return centres[m][s] + (torch::rand({3}, torch::kFloat64) - 0.5) * 0.3;
  };
  auto rows = [&](int64_t K, auto make) {
    std::vector<torch::Tensor> out;
    for (int64_t k = 0; k < K; ++k) out.push_back(make());
    return torch::stack(out);
  };
  const torch::Tensor c0 = centres[0][0];
  const double reach = 0.05 + radius_of_first;
  geometry::SceneRows scene;
  scene.insert("spheres", torch::cat({rows(4, [&] { return torch::cat({somewhere(), torch::rand({1}, torch::kFloat64) * 0.08 + 0.01}); }),
                                      torch::cat({c0 + torch::tensor({reach + 0.1 - 1e-5, 0.0, 0.0}, torch::kFloat64),
                                                  torch::tensor({0.1}, torch::kFloat64)}).view({1, 4}),
                                      torch::cat({c0 - torch::tensor({reach + 0.1 + 1e-5, 0.0, 0.0}, torch::kFloat64),
                                                  torch::tensor({0.1}, torch::kFloat64)}).view({1, 4}),
                                      torch::tensor({{3.0, 3.0, 3.0, 0.2}}, torch::kFloat64)}));
  scene.insert("boxes", rows(5, [&] {
                 return torch::cat({somewhere(), torch::rand({3}, torch::kFloat64) * 0.2 + 0.02,
                                    torch::randn({4}, torch::kFloat64)});
               }));
  scene.insert("cylinders", rows(4, [&] {
                 return torch::cat({somewhere(), torch::rand({2}, torch::kFloat64) * 0.15 + 0.02,
                                    torch::randn({4}, torch::kFloat64)});
               }));
  scene.insert("capsules", rows(3, [&] {
                 const torch::Tensor a = somewhere();
                 return torch::cat({a, a + (torch::rand({3}, torch::kFloat64) - 0.5) * 0.3,
                                    torch::rand({1}, torch::kFloat64) * 0.05 + 0.01});
               }));
  return scene;
}

TEST(ArmCollisionTest, NativeHingeMatchesTheScriptAmongEveryKindOfShapeInBothPrecisions) {
  const torch::jit::Module native = Collision(models::Kernels::kNative);
  const torch::jit::Module script = Collision(models::Kernels::kPortable);
  EXPECT_EQ(native.type()->name()->name(), "ArmCollisionCost");
  EXPECT_EQ(script.type()->name()->name(), "CollisionCost");
  const double radius0 = Franka().description().spheres[0].radius;
  for (uint64_t seed : {1, 2, 3}) {
    const torch::Tensor q = Configurations(3, 24, seed);
    const geometry::SceneRows scene = CrowdedScene(Franka().SphereCentres(q.reshape({-1, 7})).view({3 * 24, -1, 3}),
                                                   radius0, seed);
    const Evaluated n = Evaluate(native, q, scene), s = Evaluate(script, q, scene);
    ASSERT_EQ(n.value.sizes(), torch::IntArrayRef({3}));
    ASSERT_EQ(n.grad_q.sizes(), q.sizes());
    EXPECT_GT(s.value.min().item<double>(), 0.0) << "the test needs active pairs in every trajectory";
    EXPECT_GT((s.grad_q.abs() > 0).sum().item<int64_t>(), 100) << "and gradients at many states";
    EXPECT_LT((n.value - s.value).abs().max().item<double>(), 1e-10 * std::max(1.0, s.value.abs().max().item<double>()));
    EXPECT_LT((n.grad_q - s.grad_q).abs().max().item<double>(), 1e-10);
    EXPECT_EQ(n.grad_qd.abs().max().item<double>(), 0.0);

    const torch::Tensor q32 = q.to(torch::kFloat32);
    const Evaluated n32 = Evaluate(native, q32, scene), s32 = Evaluate(script, q32, scene);
    EXPECT_EQ(n32.value.scalar_type(), torch::kFloat32);
    EXPECT_EQ(n32.grad_q.scalar_type(), torch::kFloat32);
    // float32: sums of a few hundred terms of about 0.01-0.1 m, and lever arms of about 1 m times unit normals.
    EXPECT_LT((n32.value.to(torch::kFloat64) - s.value).abs().max().item<double>(), 1e-4 * s.value.abs().max().item<double>());
    EXPECT_LT((n32.grad_q.to(torch::kFloat64) - s.grad_q).abs().max().item<double>(), 1e-3 * s.grad_q.abs().max().item<double>());
    EXPECT_LT((n32.grad_q - s32.grad_q).abs().max().item<double>(), 1e-3 * s.grad_q.abs().max().item<double>());
  }
}

TEST(ArmCollisionTest, APairJustInsideTheReachCountsAndOneJustBeyondDoesNot) {
  // Only the two sphere obstacles 1e-5 m inside and beyond the first collision sphere's reach, at a
  // configuration where no other collision sphere comes near them: the hinge is the 1e-5 m of the first.
  const torch::jit::Module native = Collision(models::Kernels::kNative);
  const torch::Tensor q = torch::tensor(Franka().description().home, torch::kFloat64).view({1, 1, 7});
  const torch::Tensor centres = Franka().SphereCentres(q.view({1, 7}));  // (1, S, 3)
  const double reach = 0.05 + Franka().description().spheres[0].radius;
  // Directly below the base's first sphere, where no other sphere of the arm comes within reach.
  geometry::SceneRows scene;
  scene.insert("spheres", torch::cat({centres[0][0] - torch::tensor({0.0, 0.0, reach + 0.1 - 1e-5}, torch::kFloat64),
                                      torch::tensor({0.1}, torch::kFloat64)}).view({1, 4}));
  const Evaluated inside = Evaluate(native, q, scene);
  const Evaluated script_inside = Evaluate(Collision(models::Kernels::kPortable), q, scene);
  EXPECT_NEAR(script_inside.value.item<double>(), 1e-5, 1e-9) << "the scene must touch the first sphere alone";
  EXPECT_NEAR(inside.value.item<double>(), script_inside.value.item<double>(), 1e-12);
  scene.insert_or_assign("spheres", torch::cat({centres[0][0] - torch::tensor({0.0, 0.0, reach + 0.1 + 1e-5}, torch::kFloat64),
                                                torch::tensor({0.1}, torch::kFloat64)}).view({1, 4}));
  EXPECT_EQ(Evaluate(native, q, scene).value.item<double>(), 0.0);
  EXPECT_EQ(Evaluate(native, q, scene).grad_q.abs().max().item<double>(), 0.0);
}

TEST(ArmCollisionTest, SameBitsForAnyThreadCount) {
  const torch::jit::Module native = Collision(models::Kernels::kNative);
  // 111 configurations: one thread's chunk and two threads' split them differently, also across the
  // vectorised loops' remainders.
  const torch::Tensor q = Configurations(3, 37, 11).to(torch::kFloat32);
  const geometry::SceneRows scene =
      CrowdedScene(Franka().SphereCentres(q.to(torch::kFloat64).reshape({-1, 7})).view({3 * 37, -1, 3}),
                   Franka().description().spheres[0].radius, 11);
  const int threads = at::get_num_threads();
  at::set_num_threads(1);
  const Evaluated one = Evaluate(native, q, scene);
  at::set_num_threads(2);
  const Evaluated two = Evaluate(native, q, scene);
  at::set_num_threads(threads);
  EXPECT_GT(one.value.min().item<float>(), 0.0f);
  EXPECT_TRUE(torch::equal(one.value, two.value));
  EXPECT_TRUE(torch::equal(one.grad_q, two.grad_q));
}

TEST(ArmCollisionTest, WhatTheOperatorDoesNotTakeGoesToTheScript) {
  const torch::jit::Module native = Collision(models::Kernels::kNative);
  const torch::jit::Module script = Collision(models::Kernels::kPortable);
  const torch::Tensor q = Configurations(2, 5, 4);
  const geometry::SceneRows scene =
      CrowdedScene(Franka().SphereCentres(q.reshape({-1, 7})).view({10, -1, 3}), Franka().description().spheres[0].radius, 4);
  // q that needs a gradient: autograd follows the script, with the script's numbers.
  const torch::Tensor tracked = q.clone().requires_grad_(true);
  const Evaluated n = Evaluate(native, tracked, scene);
  EXPECT_TRUE(n.value.requires_grad());
  EXPECT_TRUE(torch::equal(n.value.detach(), Evaluate(script, q, scene).value));
  // Without obstacles: zeros of the right shapes.
  const Evaluated none = Evaluate(native, q, geometry::SceneRows());
  EXPECT_EQ(none.value.abs().max().item<double>(), 0.0);
  EXPECT_EQ(none.grad_q.sizes(), q.sizes());
}

TEST(ArmCollisionTest, BadInputIsOneClearError) {
  const c10::OperatorHandle op = c10::Dispatcher::singleton().findSchemaOrThrow("flowplan::arm_collision", "");
  const torch::jit::Module arm = Franka().module();
  auto call = [&](const torch::Tensor& q, const torch::Tensor& ancestors, const std::string& kind,
                  const torch::Tensor& rows) {
    const torch::Tensor reach = arm.attr("sphere_radii").toTensor() + 0.05;
    torch::jit::Stack stack{q, arm.attr("fixed"), arm.attr("fixed_cross"), arm.attr("fixed_cross_sq"),
                            arm.attr("link_joint"), arm.attr("link_turns"), arm.attr("parents"),
                            arm.attr("frame_points"), ancestors, reach,
                            c10::List<std::string>({kind}), c10::List<torch::Tensor>({rows}), true};
    op.callBoxed(&stack);
  };
  const torch::Tensor q = torch::zeros({3, 7}, torch::kFloat64);
  const torch::Tensor ancestors = arm.attr("ancestors").toTensor();
  const torch::Tensor box = torch::tensor({{0.5, 0.0, 0.2, 0.1, 0.1, 0.1, 1.0, 0.0, 0.0, 0.0}}, torch::kFloat64);
  auto message = [&](auto&& f) {
    try {
      f();
    } catch (const c10::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(message([&] { call(q, ancestors, "boxes", box); }),
              HasSubstr("arm_collision: boxes: expected (K, 19) rows (prepared_scene), got (1, 10)"));
  EXPECT_THAT(message([&] { call(q, ancestors, "cones", box); }), HasSubstr("arm_collision: unknown shape kind cones"));
  EXPECT_THAT(message([&] { call(q.to(torch::kInt64), ancestors, "spheres", torch::zeros({1, 4})); }),
              HasSubstr("arm_collision: expected float32 or float64 q"));
  EXPECT_THAT(message([&] { call(q, ancestors.slice(1, 1), "spheres", torch::zeros({1, 4})); }),
              HasSubstr("arm_collision: expected ancestors (J, S)"));
}

}  // namespace
}  // namespace flowplan::guidance
