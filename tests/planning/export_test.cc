// The exported TorchScript planner against the in-process FlowPlanner, loaded
// by LibTorch's torch::jit::load and by Python's torch.jit.load.

#include "planning/export.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "models/model_config.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::planning {
namespace {

FlowPlanner MakePlanner(Conditioning conditioning, Splitting splitting = Splitting::kNone) {
  torch::manual_seed(11);
  models::ModelConfig config;  // the default UNet: every block type is exercised
  auto net = models::MakeVelocityNet(config, 4, ConditionDim(conditioning, 4));
  // Random weights would make the velocity tiny; scale them up so that a
  // mistake anywhere in the script shows in the plan.
  torch::NoGradGuard no_grad;
  for (auto& p : net->parameters()) p.mul_(1.5);
  models::MinMaxNormalizer normalizer(torch::tensor({0.f, 0.f, -2.f, -2.f}), torch::tensor({1.f, 1.f, 2.f, 2.f}));
  return FlowPlanner(net, normalizer, conditioning, 64, SamplerConfig{10, splitting});
}

ExportMetadata Metadata() { return ExportMetadata{"particle", 0.05, {"x", "y", "vx", "vy"}, "seed: 0\n"}; }

struct Request {
  torch::Tensor start, goal, noise, renoise;
};

Request MakeRequest() {
  torch::manual_seed(5);
  return {torch::rand({3, 4}) * torch::tensor({1.f, 1.f, 0.5f, 0.5f}), torch::rand({3, 4}), torch::randn({3, 64, 4}),
          torch::randn({3, 64, 4})};
}

void WriteFloats(const std::string& path, const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kFloat32).contiguous();
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(c.data_ptr<float>()), c.numel() * 4);
}

torch::Tensor ReadFloats(const std::string& path, std::vector<int64_t> shape) {
  std::ifstream in(path, std::ios::binary);
  torch::Tensor t = torch::empty(shape, torch::kFloat32);
  in.read(reinterpret_cast<char*>(t.data_ptr<float>()), t.numel() * 4);
  EXPECT_TRUE(in.good()) << "could not read " << path;
  return t;
}

using Variant = std::tuple<Conditioning, Splitting>;
class ExportTest : public ::testing::TestWithParam<Variant> {
 protected:
  FlowPlanner Planner() const { return MakePlanner(std::get<0>(GetParam()), std::get<1>(GetParam())); }
};

TEST_P(ExportTest, TorchScriptMatchesTheInProcessPlannerInCpp) {
  const FlowPlanner planner = Planner();
  const std::string path = (flowplan::testing::ScratchDir() / "planner_cpp.pt").string();
  ExportPlanner(planner, Metadata(), path);
  torch::jit::Module loaded = torch::jit::load(path);
  const Request r = MakeRequest();
  const torch::Tensor expected = planner.Plan(r.start, r.goal, r.noise, r.renoise);
  const torch::Tensor got = loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise).toTensor();
  ASSERT_EQ(got.sizes(), expected.sizes());
  EXPECT_LT((got - expected).abs().max().item<float>(), 1e-5);
  // The plan must actually depend on the network: compare with a plan of other noise.
  EXPECT_GT((planner.Plan(r.start, r.goal, -r.noise, r.renoise) - expected).abs().max().item<float>(), 1e-2);
  EXPECT_EQ(loaded.attr("horizon").toInt(), 64);
  EXPECT_EQ(loaded.attr("state_dim").toInt(), 4);
  EXPECT_EQ(loaded.attr("env").toStringRef(), "particle");
}

TEST_P(ExportTest, TorchScriptMatchesTheInProcessPlannerInPython) {
  const FlowPlanner planner = Planner();
  const std::string dir = flowplan::testing::ScratchDir().string();
  const std::string path = dir + "/planner_py.pt";
  ExportPlanner(planner, Metadata(), path);
  const Request r = MakeRequest();
  WriteFloats(dir + "/start.bin", r.start);
  WriteFloats(dir + "/goal.bin", r.goal);
  WriteFloats(dir + "/noise.bin", r.noise);
  WriteFloats(dir + "/renoise.bin", r.renoise);
  const std::string command = std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                              "/tests/planning/run_exported_planner.py " + path + " " + dir + " 3";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const torch::Tensor got = ReadFloats(dir + "/plan.bin", {3, 64, 4});
  const torch::Tensor expected = planner.Plan(r.start, r.goal, r.noise, r.renoise);
  EXPECT_LT((got - expected).abs().max().item<float>(), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Variants, ExportTest,
                         ::testing::Combine(::testing::Values(Conditioning::kInpaint, Conditioning::kDirect),
                                            ::testing::Values(Splitting::kNone, Splitting::kMidpoint)),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param) == Conditioning::kInpaint ? "Inpaint" : "Direct") +
                                  (std::get<1>(info.param) == Splitting::kNone ? "" : "Split");
                         });

TEST(ExportTest, SplittingPlannerWithoutRenoiseIsRejected) {
  torch::jit::Module module = BuildScriptPlanner(MakePlanner(Conditioning::kInpaint, Splitting::kMidpoint), Metadata());
  const Request r = MakeRequest();
  EXPECT_THAT([&] { module.run_method("plan", r.start, r.goal, r.noise); },
              ::testing::ThrowsMessage<std::exception>(::testing::HasSubstr("plan: renoise")));
}

TEST(ExportTest, BadShapesAreRejectedByTheScript) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint);
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata());
  EXPECT_THAT([&] { module.run_method("plan", torch::zeros({2, 3}), torch::zeros({2, 3}), torch::zeros({2, 64, 4})); },
              ::testing::ThrowsMessage<std::exception>(::testing::HasSubstr("plan: start: expected (B, 4)")));
}

TEST(ExportTest, VelocityIsTheNetworkAndChecksItsArguments) {
  for (const Conditioning conditioning : {Conditioning::kInpaint, Conditioning::kDirect}) {
    const FlowPlanner planner = MakePlanner(conditioning);
    torch::jit::Module module = BuildScriptPlanner(planner, Metadata());
    torch::manual_seed(3);
    const torch::Tensor x = torch::randn({2, 64, 4}), t = torch::rand({2});
    const torch::Tensor cond = conditioning == Conditioning::kDirect ? torch::rand({2, 8}) : torch::Tensor();
    torch::NoGradGuard no_grad;
    const torch::Tensor expected = planner.net()->Forward(x, t, cond);
    const torch::jit::IValue script_cond = cond.defined() ? torch::jit::IValue(cond) : torch::jit::IValue();
    const torch::Tensor got = module.run_method("velocity", x, t, script_cond).toTensor();
    EXPECT_LT((got - expected).abs().max().item<float>(), 1e-5);
    using ::testing::HasSubstr;
    using ::testing::ThrowsMessage;
    EXPECT_THAT([&] { module.run_method("velocity", torch::zeros({2, 63, 4}), t, script_cond); },
                ThrowsMessage<std::exception>(HasSubstr("velocity: x: expected (B, 64, 4)")));
    EXPECT_THAT([&] { module.run_method("velocity", x, torch::zeros({3}), script_cond); },
                ThrowsMessage<std::exception>(HasSubstr("velocity: t: expected (B,)")));
    EXPECT_THAT([&] { module.run_method("velocity", x, t, torch::zeros({2, 5})); },
                ThrowsMessage<std::exception>(HasSubstr("velocity: cond")));
  }
}

TEST(ExportTest, SampleStartsAndEndsAtTheRequest) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kMidpoint);
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata());
  const torch::Tensor start = torch::tensor({0.0f, 0.0f, 0.0f, 0.0f}), goal = torch::tensor({1.0f, 0.0f, 0.1f, 0.0f});
  const torch::Tensor plans = module.run_method("sample", start, goal, 5).toTensor();
  ASSERT_EQ(plans.sizes(), (std::vector<int64_t>{5, 64, 4}));
  EXPECT_TRUE(torch::equal(plans.select(1, 0), start.expand({5, 4})));
  EXPECT_TRUE(torch::equal(plans.select(1, 63), goal.expand({5, 4})));
}

}  // namespace
}  // namespace flowplan::planning
