// The native guidance gradient of an arm (guidance/arm_guide.py over
// flowplan::arm_guidance, kernels/arm_guidance_kernel.h) against what it
// stands for: the guide's cost chain through the normalizer in the same guide
// (its collision term the native hinge, held to the scripts in
// arm_collision_test.cc), and the whole portable guide (LibTorch's operators
// only, sharing no code with the kernel, itself held to central differences
// and autograd in cost_test.cc); with every term on and off, the cap on and
// off, float64 and float32; the same bits for any thread count; which guides
// have it and what goes to the chain; bad input as one clear error.

#include <ATen/Parallel.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <limits>

#include "core/error.h"
#include "guidance/guide.h"
#include "jit/library.h"
#include "kinematics/robot.h"
#include "models/normalizer.h"
#include "sim/franka_model.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::guidance {
namespace {

using ::testing::HasSubstr;

constexpr double kDt = 0.05;

const kinematics::Robot& Franka() {
  static const kinematics::Robot robot(sim::LoadFrankaModel().description());
  return robot;
}

/// A normalizer of the Franka's states: positions over the joint ranges, velocities over +-2 rad/s, float32 as
/// a trained planner's.
models::MinMaxNormalizer StateNormalizer() {
  const auto& d = Franka().description();
  const torch::Tensor lo = torch::cat({torch::tensor(d.joint_lower, torch::kFloat64), torch::full({7}, -2.0, torch::kFloat64)});
  const torch::Tensor hi = torch::cat({torch::tensor(d.joint_upper, torch::kFloat64), torch::full({7}, 2.0, torch::kFloat64)});
  return models::MinMaxNormalizer(lo.to(torch::kFloat32), hi.to(torch::kFloat32));
}

torch::jit::Module Guide(models::Kernels kernels, const std::string& user_cost = "") {
  GuidanceConfig config;
  config.distance_kernels = kernels;
  config.user_cost = user_cost;
  static const models::MinMaxNormalizer normalizer = StateNormalizer();
  return BuildGuide(config, Franka(), normalizer.module(), kDt);
}

/// The settings of a call: the config's, then `over`.
c10::Dict<std::string, double> Opts(const std::map<std::string, double>& over = {}) {
  c10::Dict<std::string, double> opts;
  for (const auto& [key, value] : config::ListNumbers(GuidanceConfig(), "guidance")) opts.insert(key, value);
  for (const auto& [key, value] : over) opts.insert_or_assign(key, value);
  return opts;
}

torch::Tensor Gradient(const torch::jit::Module& guide, const torch::Tensor& x, const geometry::SceneRows& scene,
                       const c10::Dict<std::string, double>& opts) {
  torch::NoGradGuard no_grad;
  return jit::Call(guide, "gradient", {x, scene, opts}).toTensor();
}

/// The guide's native gradient (None where it has none or the operator does not take the tensors).
c10::IValue NativeGradient(const torch::jit::Module& guide, const torch::Tensor& x, const geometry::SceneRows& scene,
                           const c10::Dict<std::string, double>& opts) {
  torch::NoGradGuard no_grad;
  return jit::Call(guide, "native_gradient", {x, scene, opts});
}

/// The chain's gradient in the same guide: Guide.gradient's second branch, written out.
torch::Tensor ChainGradient(const torch::jit::Module& guide, const torch::Tensor& x, const geometry::SceneRows& scene,
                            const c10::Dict<std::string, double>& opts) {
  torch::NoGradGuard no_grad;
  const torch::jit::Module normalizer = guide.attr("normalizer").toModule();
  const torch::Tensor raw = jit::Call(normalizer, "denormalize_unclamped", {x}).toTensor();
  return jit::Call(guide, "raw_gradient", {raw, scene, opts}).toTensor() *
         jit::Call(normalizer, "raw_per_normalized", {}).toTensor();
}

/// Normalized plans (B, T, 14) a little beyond [-1, 1] (some states outside the joint limits).
torch::Tensor Plans(int64_t B, int64_t T, uint64_t seed) {
  torch::manual_seed(seed);
  return torch::rand({B, T, 14}, torch::kFloat64) * 2.2 - 1.1;
}

/// Shapes of every kind about the arm's sphere centres at plans x, rotated; rows in float64 and prepared
/// (as a planner prepares a call's scene once).
geometry::SceneRows SceneAbout(const torch::jit::Module& guide, const torch::Tensor& x, uint64_t seed) {
  torch::NoGradGuard no_grad;
  const torch::Tensor raw =
      jit::Call(guide.attr("normalizer").toModule(), "denormalize_unclamped", {x.to(torch::kFloat64)}).toTensor();
  const torch::Tensor centres = Franka().SphereCentres(raw.slice(2, 0, 7).reshape({-1, 7}));  // (M, S, 3)
  torch::manual_seed(seed);
  auto somewhere = [&] {
    const int64_t m = torch::randint(centres.size(0), {1}).item<int64_t>();
    const int64_t s = torch::randint(centres.size(1), {1}).item<int64_t>();
    return centres[m][s] + (torch::rand({3}, torch::kFloat64) - 0.5) * 0.3;
  };
  auto rows = [&](int64_t K, auto make) {
    std::vector<torch::Tensor> out;
    for (int64_t k = 0; k < K; ++k) out.push_back(make());
    return torch::stack(out);
  };
  geometry::SceneRows scene;
  scene.insert("spheres", rows(3, [&] { return torch::cat({somewhere(), torch::rand({1}, torch::kFloat64) * 0.08 + 0.01}); }));
  scene.insert("boxes", rows(3, [&] {
                 return torch::cat({somewhere(), torch::rand({3}, torch::kFloat64) * 0.2 + 0.02, torch::randn({4}, torch::kFloat64)});
               }));
  scene.insert("cylinders", rows(2, [&] {
                 return torch::cat({somewhere(), torch::rand({2}, torch::kFloat64) * 0.15 + 0.02, torch::randn({4}, torch::kFloat64)});
               }));
  scene.insert("capsules", rows(2, [&] {
                 const torch::Tensor a = somewhere();
                 return torch::cat({a, a + (torch::rand({3}, torch::kFloat64) - 0.5) * 0.3, torch::rand({1}, torch::kFloat64) * 0.05 + 0.01});
               }));
  return geometry::PreparedRows(scene, 3);
}

geometry::SceneRows AsFloat(const geometry::SceneRows& scene) {
  geometry::SceneRows out;
  for (const auto& entry : scene) out.insert(entry.key(), entry.value().to(torch::kFloat32));
  return out;
}

double Largest(const torch::Tensor& t) { return t.abs().max().item<double>(); }

// Each setting turns a term on, off or into its other regime: the defaults (collision and smoothness, capped);
// every term at once with a joint-speed hinge active on most segments; the joint-limit hinge without a cap; a
// cap that binds on every state; the collision term alone; every term but collision, the joint-speed hinge
// active on some segments only (and a sigma of 0 where smoothness is off: the chain never reads it).
const std::vector<std::map<std::string, double>> kSettings = {
    {{"guidance.clip", 1.0}},
    {{"guidance.clip", 1.0}, {"guidance.joint_speed_weight", 0.3}, {"guidance.joint_speed_ratio", 0.2},
     {"guidance.joint_limit_weight", 0.2}, {"guidance.smoothness_weight", 0.02}},
    {{"guidance.clip", 0.0}, {"guidance.joint_limit_weight", 0.3}, {"guidance.smoothness_sigma", 3.0}},
    {{"guidance.clip", 0.01}, {"guidance.collision_weight", 5.0}, {"guidance.margin", 0.1}},
    {{"guidance.clip", 1.0}, {"guidance.smoothness_weight", 0.0}, {"guidance.collision_weight", 1.0}},
    {{"guidance.clip", 0.5}, {"guidance.collision_weight", 0.0}, {"guidance.joint_speed_weight", 1.0},
     {"guidance.joint_speed_ratio", 2.5}, {"guidance.joint_limit_weight", 0.2}},
    {{"guidance.clip", 1.0}, {"guidance.smoothness_weight", 0.0}, {"guidance.smoothness_sigma", 0.0},
     {"guidance.joint_speed_weight", 0.3}},
};

TEST(ArmGuidanceTest, OneNativeCallGivesTheChainsGradientInBothPrecisions) {
  const torch::jit::Module guide = Guide(models::Kernels::kNative);
  for (uint64_t seed : {1, 2}) {
    const torch::Tensor x = Plans(3, 20, seed);
    const geometry::SceneRows scene = SceneAbout(guide, x, seed);
    for (const auto& over : kSettings) {
      const auto opts = Opts(over);
      ASSERT_FALSE(NativeGradient(guide, x, scene, opts).isNone()) << "the operator must take float64 plans";
      const torch::Tensor chain = ChainGradient(guide, x, scene, opts);
      const torch::Tensor native = Gradient(guide, x, scene, opts);
      ASSERT_EQ(native.sizes(), x.sizes());
      ASSERT_EQ(native.scalar_type(), torch::kFloat64);
      EXPECT_GT((chain.abs() > 0).sum().item<int64_t>(), x.numel() / 4) << "the test needs gradients at many entries";
      EXPECT_LT(Largest(native - chain), 1e-12 * Largest(chain)) << "seed " << seed;
      if (over.at("guidance.clip") == 0.0) {
        EXPECT_TRUE(torch::equal(native, chain)) << "uncapped, every number is rounded as the chain rounds it";
      }

      const torch::Tensor x32 = x.to(torch::kFloat32);
      const geometry::SceneRows scene32 = AsFloat(scene);
      ASSERT_FALSE(NativeGradient(guide, x32, scene32, opts).isNone()) << "and float32 plans";
      const torch::Tensor native32 = Gradient(guide, x32, scene32, opts);
      ASSERT_EQ(native32.scalar_type(), torch::kFloat32);
      // float32: the operators' and the kernel's sums round alike but for their order.
      const torch::Tensor chain32 = ChainGradient(guide, x32, scene32, opts);
      EXPECT_LT(Largest(native32 - chain32), 1e-5 * Largest(chain)) << "seed " << seed;
      if (over.at("guidance.clip") == 0.0) {
        EXPECT_TRUE(torch::equal(native32, chain32)) << "float32, uncapped";
      }
    }
  }
}

TEST(ArmGuidanceTest, ShortPlansAndStridedPlans) {
  // One state (no segment), two states (one segment, both ends), and plans that are a strided view.
  const torch::jit::Module guide = Guide(models::Kernels::kNative);
  const auto opts = Opts(kSettings[1]);
  for (int64_t T : {1, 2}) {
    const torch::Tensor x = Plans(2, T, 20 + T);
    const geometry::SceneRows scene = SceneAbout(guide, x, 20 + T);
    const torch::Tensor chain = ChainGradient(guide, x, scene, opts);
    EXPECT_LT(Largest(Gradient(guide, x, scene, opts) - chain), 1e-12 * Largest(chain)) << "T = " << T;
  }
  const torch::Tensor wide = Plans(12, 16, 23);
  const torch::Tensor x = wide.slice(0, 0, 12, 3);  // every third plan: not contiguous
  ASSERT_FALSE(x.is_contiguous());
  const geometry::SceneRows scene = SceneAbout(guide, x, 23);
  const torch::Tensor chain = ChainGradient(guide, x, scene, opts);
  EXPECT_LT(Largest(Gradient(guide, x, scene, opts) - chain), 1e-12 * Largest(chain));
}

TEST(ArmGuidanceTest, ANaNStateSpreadsAsInTheChain) {
  // A NaN in one state's position: the chain's gradient is NaN there and at its neighbours (smoothness, joint
  // speed) and, through each state's cap, across the whole state; the native gradient has NaN at the same entries
  // and the chain's numbers elsewhere.
  const torch::jit::Module guide = Guide(models::Kernels::kNative);
  torch::Tensor x = Plans(2, 12, 31);
  const geometry::SceneRows scene = SceneAbout(guide, x, 31);
  x[1][5][2] = std::numeric_limits<double>::quiet_NaN();
  for (const auto& over : {kSettings[1], kSettings[2]}) {
    const auto opts = Opts(over);
    const torch::Tensor chain = ChainGradient(guide, x, scene, opts), native = Gradient(guide, x, scene, opts);
    EXPECT_GT(torch::isnan(chain).sum().item<int64_t>(), 0);
    EXPECT_TRUE(torch::equal(torch::isnan(native), torch::isnan(chain)));
    const torch::Tensor finite = ~torch::isnan(chain);
    EXPECT_LT(Largest(native.masked_select(finite) - chain.masked_select(finite)), 1e-12 * Largest(chain.masked_select(finite)));
  }
}

TEST(ArmGuidanceTest, NativeGradientMatchesThePortableGuide) {
  // The portable guide computes everything with LibTorch's operators: no code in common with the kernel.
  const torch::jit::Module native = Guide(models::Kernels::kNative);
  const torch::jit::Module portable = Guide(models::Kernels::kPortable);
  const torch::Tensor x = Plans(2, 24, 7);
  const geometry::SceneRows scene = SceneAbout(native, x, 7);
  for (const auto& over : kSettings) {
    const auto opts = Opts(over);
    const torch::Tensor reference = Gradient(portable, x, scene, opts);
    EXPECT_LT(Largest(Gradient(native, x, scene, opts) - reference), 1e-9 * Largest(reference));
  }
}

TEST(ArmGuidanceTest, SameBitsForAnyThreadCount) {
  const torch::jit::Module guide = Guide(models::Kernels::kNative);
  // 5 plans of 37 states: one thread's chunks of the collision hinge and two threads' split them differently.
  const torch::Tensor x = Plans(5, 37, 3).to(torch::kFloat32);
  const geometry::SceneRows scene = AsFloat(SceneAbout(guide, x, 3));
  const auto opts = Opts(kSettings[1]);
  const int threads = at::get_num_threads();
  at::set_num_threads(1);
  const torch::Tensor one = Gradient(guide, x, scene, opts);
  at::set_num_threads(2);
  const torch::Tensor two = Gradient(guide, x, scene, opts);
  at::set_num_threads(threads);
  EXPECT_GT(Largest(one), 0.0);
  EXPECT_TRUE(torch::equal(one, two));
}

TEST(ArmGuidanceTest, WhoHasTheNativeGradientAndWhatGoesToTheChain) {
  const torch::jit::Module native = Guide(models::Kernels::kNative);
  const torch::Tensor x = Plans(2, 10, 5);
  const geometry::SceneRows scene = SceneAbout(native, x, 5);
  const auto opts = Opts(kSettings[1]);
  // Portable kernels, and a user cost (the operator knows the built-in terms only): the chain, the same numbers.
  const torch::Tensor chain = ChainGradient(native, x, scene, opts);
  const torch::jit::Module portable = Guide(models::Kernels::kPortable);
  EXPECT_TRUE(torch::equal(Gradient(portable, x, scene, opts), ChainGradient(portable, x, scene, opts)));
  const std::string cost = (flowplan::testing::ScratchDir() / "arm_guidance_zero.py").string();
  std::ofstream(cost) << "def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                         "    return (q * 0.0).sum([1, 2])\n";
  const torch::jit::Module with_user = Guide(models::Kernels::kNative, cost);
  EXPECT_TRUE(native.hasattr("native_kinds"));
  EXPECT_FALSE(portable.hasattr("native_kinds"));
  EXPECT_FALSE(with_user.hasattr("native_kinds"));
  const torch::Tensor user = Gradient(with_user, x, scene, opts);
  EXPECT_TRUE(torch::equal(user, ChainGradient(with_user, x, scene, opts)));
  EXPECT_TRUE(torch::equal(user, chain)) << "a user cost of zero adds nothing";
  // x that needs a gradient: the chain (with the script's collision term), which autograd can follow.
  const torch::Tensor tracked = x.clone().requires_grad_(true);
  const torch::Tensor through = jit::Call(native, "gradient", {tracked, scene, opts}).toTensor();
  EXPECT_TRUE(through.requires_grad());
  EXPECT_TRUE(torch::equal(through.detach(), ChainGradient(portable, x, scene, opts)));
  // float64 statistics with float32 plans: the chain, whose result is float64.
  torch::jit::Module wide_statistics = StateNormalizer().module().clone();
  wide_statistics.to(torch::kFloat64);  // as a user's planner.double() leaves it
  ASSERT_EQ(wide_statistics.attr("lo").toTensor().scalar_type(), torch::kFloat64);
  const torch::jit::Module wide = BuildGuide(GuidanceConfig(), Franka(), wide_statistics, kDt);
  const torch::Tensor x32 = x.to(torch::kFloat32);
  EXPECT_TRUE(NativeGradient(wide, x32, scene, opts).isNone());
  EXPECT_EQ(Gradient(wide, x32, scene, opts).scalar_type(), torch::kFloat64);
  // Without obstacles: the other terms alone.
  EXPECT_LT(Largest(Gradient(native, x, geometry::SceneRows(), opts) - ChainGradient(native, x, geometry::SceneRows(), opts)),
            1e-12 * Largest(chain));
}

TEST(ArmGuidanceTest, BadInputIsOneClearError) {
  const torch::jit::Module guide = Guide(models::Kernels::kNative);
  const torch::Tensor x = Plans(1, 8, 9);
  const geometry::SceneRows scene = SceneAbout(guide, x, 9);
  auto opts = Opts();
  ASSERT_EQ(opts.erase("guidance.joint_speed_ratio"), 1u);
  EXPECT_THAT([&] { Gradient(guide, x, scene, opts); },
              ::testing::ThrowsMessage<Error>(HasSubstr("arm_guidance: opts: no setting guidance.joint_speed_ratio")));
  const c10::OperatorHandle op = c10::Dispatcher::singleton().findSchemaOrThrow("flowplan::arm_guidance", "");
  const torch::jit::Module arm = Franka().module();
  const torch::jit::Module normalizer = guide.attr("normalizer").toModule();
  auto call = [&](const torch::Tensor& plans) {
    torch::jit::Stack stack{plans, normalizer.attr("lo"), normalizer.attr("hi"), arm.attr("fixed"),
                            arm.attr("fixed_cross"), arm.attr("fixed_cross_sq"), arm.attr("link_joint"),
                            arm.attr("link_turns"), arm.attr("parents"), arm.attr("frame_points"),
                            arm.attr("ancestors"), arm.attr("sphere_radii"), arm.attr("lower"), arm.attr("upper"),
                            arm.attr("velocity_limit"), kDt, c10::List<std::string>(), c10::List<torch::Tensor>(),
                            Opts()};
    op.callBoxed(&stack);
  };
  EXPECT_THAT([&] { call(torch::zeros({1, 8, 12}, torch::kFloat64)); },
              ::testing::ThrowsMessage<c10::Error>(HasSubstr("arm_guidance: expected D = 2 J = 14")));
  EXPECT_THAT([&] { call(torch::zeros({1, 8, 14}, torch::kInt64)); },
              ::testing::ThrowsMessage<c10::Error>(HasSubstr("arm_guidance: expected float32 or float64 x")));
}

}  // namespace
}  // namespace flowplan::guidance
