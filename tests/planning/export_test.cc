// The exported TorchScript planner against the in-process FlowPlanner, loaded
// by LibTorch's torch::jit::load and by Python's torch.jit.load, unguided and
// guided around obstacles, for a point robot (the particle) and the Franka.

#include "planning/export.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>

#include "kinematics/arm_kinematics.h"
#include "models/model_config.h"
#include "planning/ddpm_planner.h"
#include "planning/flow_planner.h"
#include "planning/latent_planner.h"
#include "sim/franka_model.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::models {
void PrintTo(Conditioning c, std::ostream* os) { *os << config::EnumName(c); }
}  // namespace flowplan::models

namespace flowplan::planning {
void PrintTo(Splitting s, std::ostream* os) { *os << config::EnumName(s); }

namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

std::shared_ptr<const kinematics::Robot> Disc() {
  return kinematics::MakeRobot(kinematics::PointRobot("disc", 2, 0.05, 0.0, 1.0));
}

std::shared_ptr<const kinematics::Robot> Franka() {
  static const auto robot = kinematics::MakeRobot(sim::LoadFrankaModel().description());
  return robot;
}

FlowPlanner MakePlanner(Conditioning conditioning, Splitting splitting, std::shared_ptr<const kinematics::Robot> robot,
                        std::vector<int> down_dims = {32, 64, 128, 256},
                        models::Architecture architecture = models::Architecture::kUNet1D) {
  torch::manual_seed(11);
  const int64_t J = robot->num_joints(), D = 2 * J;
  models::ModelConfig config;  // the default UNet exercises every block type
  config.architecture = architecture;
  config.unet.down_dims = down_dims;
  config.transformer.d_model = 64;
  auto net = models::MakeTrajectoryNet(config, D, ConditionDim(conditioning, D));
  // Random weights would make the velocity tiny; scale them up so that a
  // mistake anywhere in the script shows in the plan.
  torch::NoGradGuard no_grad;
  for (auto& p : net->parameters()) p.mul_(1.5);
  const auto& d = robot->description();
  torch::Tensor lo = torch::full({D}, -2.0f), hi = torch::full({D}, 2.0f);
  for (int64_t j = 0; j < J; ++j) {
    lo[j] = static_cast<float>(d.joint_lower[j]);
    hi[j] = static_cast<float>(d.joint_upper[j]);
  }
  guidance::GuidanceConfig guidance;
  guidance.scale = 0.5;
  guidance.clip = 5.0;  // exercised by the script too
  SamplerConfig sampler;
  sampler.steps = 10;
  sampler.splitting = splitting;
  return FlowPlanner(net, models::MinMaxNormalizer(lo, hi), conditioning, 64, sampler,
                     GuidanceSetup{robot, 0.05, guidance});
}

ExportMetadata Metadata(int64_t D) {
  std::vector<std::string> labels;
  for (int64_t i = 0; i < D; ++i) labels.push_back("s" + std::to_string(i));
  return ExportMetadata{"test", 0.05, labels, "seed: 0\n"};
}

struct Request {
  torch::Tensor start, goal, noise, renoise, obstacles;
};

/// Starts and goals inside the normalizer's range, and obstacles between them.
Request MakeRequest(const FlowPlanner& planner, int64_t B) {
  torch::manual_seed(5);
  const int64_t D = planner.state_dim(), W = planner.guidance().robot->workspace_dim();
  const torch::Tensor lo = planner.normalizer().lo(), hi = planner.normalizer().hi();
  auto state = [&] { return lo + (hi - lo) * (0.3 + 0.4 * torch::rand({B, D})); };
  Request r{state(), state(), torch::randn({B, 64, D}), torch::randn({B, 64, D}), torch::Tensor()};
  r.obstacles = W == 2 ? torch::tensor({{0.5f, 0.5f, 0.2f}, {0.3f, 0.6f, 0.1f}})
                       : torch::tensor({{0.5f, 0.0f, 0.4f, 0.15f}, {0.3f, 0.2f, 0.5f, 0.1f}});
  return r;
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

float MaxDifference(const torch::Tensor& a, const torch::Tensor& b) { return (a - b).abs().max().item<float>(); }

using Variant = std::tuple<Conditioning, Splitting>;
class ExportTest : public ::testing::TestWithParam<Variant> {
 protected:
  FlowPlanner Planner() const { return MakePlanner(std::get<0>(GetParam()), std::get<1>(GetParam()), Disc()); }
};

TEST_P(ExportTest, TorchScriptMatchesTheInProcessPlannerInCpp) {
  const FlowPlanner planner = Planner();
  const std::string path = (flowplan::testing::ScratchDir() / "planner_cpp.pt").string();
  ExportPlanner(planner, Metadata(4), path);
  torch::jit::Module loaded = torch::jit::load(path);
  const Request r = MakeRequest(planner, 3);
  const torch::jit::IValue none;
  const torch::Tensor expected = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise);
  const torch::Tensor got = loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise).toTensor();
  ASSERT_EQ(got.sizes(), expected.sizes());
  EXPECT_LT(MaxDifference(got, expected), 1e-5);
  // The plan must actually depend on the network: compare with a plan of other noise.
  EXPECT_GT(MaxDifference(planner.PlanWithNoise(r.start, r.goal, -r.noise, r.renoise), expected), 1e-2);

  // Guided, with the default scale and with one given per call.
  const torch::Tensor guided = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise, r.obstacles);
  EXPECT_GT(MaxDifference(guided, expected), 1e-3) << "guidance changed nothing";
  EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise, r.obstacles).toTensor(),
                          guided),
            1e-5);
  guidance::GuidanceConfig stronger = planner.guidance().config;
  stronger.scale = 2.0;
  const torch::Tensor strong = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise, r.obstacles, &stronger);
  EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise, r.obstacles, 2.0).toTensor(),
                          strong),
            1e-5);
  // No obstacles, or a scale of 0, is the unguided plan.
  EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise, torch::zeros({0, 3}))
                              .toTensor(),
                          expected),
            1e-5);
  EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise, r.obstacles, 0.0).toTensor(),
                          expected),
            1e-5);
  EXPECT_EQ(loaded.attr("horizon").toInt(), 64);
  EXPECT_EQ(loaded.attr("state_dim").toInt(), 4);
  EXPECT_EQ(loaded.attr("env").toStringRef(), "test");
  EXPECT_EQ(loaded.attr("format_version").toInt(), kExportFormatVersion);
}

INSTANTIATE_TEST_SUITE_P(Variants, ExportTest,
                         ::testing::Combine(::testing::Values(Conditioning::kInpaint, Conditioning::kDirect),
                                            ::testing::Values(Splitting::kNone, Splitting::kMidpoint)),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param) == Conditioning::kInpaint ? "Inpaint" : "Direct") +
                                  (std::get<1>(info.param) == Splitting::kNone ? "" : "Split");
                         });

/// Runs tests/planning/run_exported_planner.py on `path` with the request
/// written next to it; returns its guided plan (made under torch.inference_mode()).
torch::Tensor PlanInPython(const std::string& dir, const std::string& path, const Request& r, int64_t D) {
  WriteFloats(dir + "/start.bin", r.start);
  WriteFloats(dir + "/goal.bin", r.goal);
  WriteFloats(dir + "/noise.bin", r.noise);
  WriteFloats(dir + "/renoise.bin", r.renoise);
  WriteFloats(dir + "/obstacles.bin", r.obstacles);
  const std::string command = std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                              "/tests/planning/run_exported_planner.py " + path + " " + dir + " " +
                              std::to_string(r.start.size(0)) + " " + std::to_string(r.obstacles.size(0));
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  return ReadFloats(dir + "/plan.bin", {r.start.size(0), 64, D});
}

TEST(ExportTest, GuidedPointPlannerMatchesInPythonUnderInferenceMode) {
  for (const Splitting splitting : {Splitting::kNone, Splitting::kMidpoint}) {
    const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, splitting, Disc());
    const std::string dir = flowplan::testing::ScratchDir().string();
    const std::string path = dir + "/planner_py.pt";
    ExportPlanner(planner, Metadata(4), path);
    const Request r = MakeRequest(planner, 3);
    const torch::Tensor got = PlanInPython(dir, path, r, 4);
    EXPECT_LT(MaxDifference(got, planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise, r.obstacles)), 1e-5);
  }
}

DdpmPlanner MakeDdpmPlanner(std::shared_ptr<const kinematics::Robot> robot) {
  const FlowPlanner flow = MakePlanner(Conditioning::kInpaint, Splitting::kNone, robot, {32, 64});
  objectives::DdpmConfig schedule;
  schedule.steps = 8;  // small, so the test is quick; guided: the last 2 steps and 3 extra
  DdpmSamplerConfig sampler;
  sampler.extra_steps = 3;
  sampler.guide_iterations = 2;
  return DdpmPlanner(flow.net(), flow.normalizer(), Conditioning::kInpaint, 64, schedule, sampler, flow.guidance());
}

TEST(ExportTest, GuidedDdpmPlannerMatchesInCppAndPython) {
  for (const auto& robot : {Disc(), Franka()}) {
    const DdpmPlanner planner = MakeDdpmPlanner(robot);
    const int64_t D = planner.state_dim();
    const std::string dir = flowplan::testing::ScratchDir().string();
    const std::string path = dir + "/ddpm.pt";
    ExportPlanner(planner, Metadata(D), path);
    torch::manual_seed(9);
    const FlowPlanner reference = MakePlanner(Conditioning::kInpaint, Splitting::kNone, robot, {32, 64});
    Request r = MakeRequest(reference, 2);
    r.renoise = torch::randn({2, 7, 64, D});
    const torch::Tensor expected = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise, r.obstacles);
    const torch::Tensor unguided = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise);
    EXPECT_GT(MaxDifference(expected, unguided), 1e-3) << "guidance changed nothing";
    torch::jit::Module loaded = torch::jit::load(path);
    EXPECT_EQ(loaded.attr("planner").toStringRef(), "ddpm");
    EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise, r.obstacles).toTensor(),
                            expected),
              1e-5);
    EXPECT_LT(MaxDifference(PlanInPython(dir, path, r, D), expected), 1e-5);
    EXPECT_THAT([&] { loaded.run_method("plan", r.start, r.goal, r.noise, r.noise); },
                ThrowsMessage<std::exception>(HasSubstr("plan: renoise: expected the noise of the DDPM steps")));
  }
}

TEST(ExportTest, GuidedLatentPlannerMatchesInCppAndPython) {
  for (const auto& robot : {Disc(), Franka()}) {
    const FlowPlanner reference = MakePlanner(Conditioning::kInpaint, Splitting::kNone, robot, {32, 64});
    const int64_t D = reference.state_dim();
    torch::manual_seed(13);
    models::StateVaeConfig vae_config;
    vae_config.hidden = {32, 32};
    vae_config.latent = 8;
    auto vae = std::make_shared<models::StateVae>(vae_config, D);
    LatentPlannerConfig config;
    config.iterations = 3;
    GuidanceSetup guidance = reference.guidance();
    guidance.config.scale = 20.0;  // random weights: make the obstacles' pull visible in the plan
    const LatentPlanner planner(vae, reference.normalizer(), 64, config, guidance);
    const std::string dir = flowplan::testing::ScratchDir().string();
    const std::string path = dir + "/latent.pt";
    ExportPlanner(planner, Metadata(D), path);
    Request r = MakeRequest(reference, 2);
    r.noise = torch::randn({2, 8});
    // A large obstacle around the first start's TCP, so that the random decoder's states meet it.
    const int64_t J = robot->num_joints();
    r.obstacles = torch::cat({robot->Tcp(r.start.slice(0, 0, 1).slice(1, 0, J)), torch::full({1, 1}, 0.3f)}, 1);
    const torch::Tensor expected = planner.PlanWithNoise(r.start, r.goal, r.noise, r.obstacles);
    torch::jit::Module loaded = torch::jit::load(path);
    EXPECT_EQ(loaded.attr("planner").toStringRef(), "latent");
    EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, torch::jit::IValue(), r.obstacles)
                                .toTensor(),
                            expected),
              1e-5);
    EXPECT_LT(MaxDifference(PlanInPython(dir, path, r, D), expected), 1e-5);
  }
}

TEST(ExportTest, TransformerPlannerMatchesInCppAndPython) {
  for (const Conditioning conditioning : {Conditioning::kInpaint, Conditioning::kDirect}) {
    const FlowPlanner planner =
        MakePlanner(conditioning, Splitting::kMidpoint, Disc(), {}, models::Architecture::kTransformer);
    const std::string dir = flowplan::testing::ScratchDir().string();
    const std::string path = dir + "/transformer.pt";
    ExportPlanner(planner, Metadata(4), path);
    const Request r = MakeRequest(planner, 2);
    const torch::Tensor expected = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise, r.obstacles);
    torch::jit::Module loaded = torch::jit::load(path);
    EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise, r.obstacles).toTensor(),
                            expected),
              1e-5);
    EXPECT_LT(MaxDifference(PlanInPython(dir, path, r, 4), expected), 1e-5);
  }
}

TEST(ExportTest, GuidedFrankaPlannerMatchesInCppAndPython) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kMidpoint, Franka(), {32, 64});
  const std::string dir = flowplan::testing::ScratchDir().string();
  const std::string path = dir + "/franka.pt";
  ExportPlanner(planner, Metadata(14), path);
  const Request r = MakeRequest(planner, 2);
  const torch::Tensor expected = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise, r.obstacles);
  const torch::Tensor unguided = planner.PlanWithNoise(r.start, r.goal, r.noise, r.renoise);
  EXPECT_GT(MaxDifference(expected, unguided), 1e-3) << "guidance changed nothing";
  torch::jit::Module loaded = torch::jit::load(path);
  EXPECT_LT(MaxDifference(loaded.run_method("plan", r.start, r.goal, r.noise, r.renoise, r.obstacles).toTensor(),
                          expected),
            1e-5);
  EXPECT_LT(MaxDifference(PlanInPython(dir, path, r, 14), expected), 1e-5);
}

TEST(ExportTest, GuidanceCostAndStepMatchTheCppCostInFloat64) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kNone, Franka(), {32, 64});
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata(14));
  const Request r = MakeRequest(planner, 3);
  const torch::Tensor x = planner.normalizer().DenormalizeUnclamped(0.8 * torch::rand({3, 64, 14}) - 0.4)
                              .to(torch::kFloat64);
  const torch::Tensor obstacles = r.obstacles.to(torch::kFloat64);
  const auto cost = guidance::MakeGuidanceCost(planner.guidance().config, Franka(), 0.05);
  const guidance::CostAndGradient expected = cost->ValueAndGradient(x, obstacles);
  const auto got = module.run_method("guidance_cost", x, obstacles).toTuple()->elements();
  EXPECT_GT(expected.value.min().item<double>(), 0.0);
  EXPECT_LT((got[0].toTensor() - expected.value).abs().max().item<double>(), 1e-9);
  EXPECT_LT((got[1].toTensor() - expected.gradient).abs().max().item<double>(), 1e-9);
}

TEST(ExportTest, TcpAndCollisionSpheresAreTheRobotsKinematics) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kNone, Franka(), {32, 64});
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata(14));
  torch::manual_seed(2);
  const torch::Tensor q = torch::rand({2, 5, 7}, torch::kFloat64) * 2 - 1;  // any leading dims
  const auto& arm = dynamic_cast<const kinematics::ArmKinematics&>(*Franka());
  const kinematics::FkResult fk = arm.Forward(q.view({10, 7}));
  const torch::Tensor tcp = module.run_method("tcp", q).toTensor();
  ASSERT_EQ(tcp.sizes(), (std::vector<int64_t>{2, 5, 3}));
  EXPECT_LT((tcp.view({10, 3}) - fk.tcp_position).abs().max().item<double>(), 1e-12);
  const torch::Tensor spheres = module.run_method("collision_spheres", q).toTensor();
  const int64_t S = arm.num_spheres();
  ASSERT_EQ(spheres.sizes(), (std::vector<int64_t>{2, 5, S, 4}));
  EXPECT_LT((spheres.view({10, S, 4}).slice(2, 0, 3) - fk.sphere_centres).abs().max().item<double>(), 1e-12);
  EXPECT_TRUE(torch::equal(spheres[1][3].select(1, 3), arm.SphereRadii()));
  EXPECT_THAT([&] { module.run_method("tcp", torch::zeros({3, 6})); },
              ThrowsMessage<std::exception>(HasSubstr("tcp: q: expected (..., 7)")));
}

TEST(ExportTest, IkIsTheRobotsInverseKinematics) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kNone, Franka(), {32, 64});
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata(14));
  const torch::Tensor targets = torch::tensor({{0.5, -0.3, 0.2}, {0.5, 0.3, 0.2}, {0.4, 0.1, 0.5}}, torch::kFloat64);
  const auto& arm = dynamic_cast<const kinematics::ArmKinematics&>(*Franka());
  const kinematics::IkSolution expected = arm.InverseTcp(targets);
  const torch::Tensor got = module.run_method("ik", targets.view({3, 1, 3})).toTensor();
  ASSERT_EQ(got.sizes(), (std::vector<int64_t>{3, 1, 7}));
  EXPECT_LT((got.view({3, 7}) - expected.q).abs().max().item<double>(), 1e-9);
  // float32 targets give float32 joints.
  EXPECT_EQ(module.run_method("ik", targets.to(torch::kFloat32)).toTensor().scalar_type(), torch::kFloat32);
  EXPECT_THAT([&] { module.run_method("ik", torch::tensor({2.0, 0.0, 0.5})); },
              ThrowsMessage<std::exception>(HasSubstr("ik: a target is out of reach")));
}

TEST(ExportTest, SplittingPlannerWithoutRenoiseIsRejected) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kMidpoint, Disc(), {32, 64});
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata(4));
  const Request r = MakeRequest(planner, 3);
  EXPECT_THAT([&] { module.run_method("plan", r.start, r.goal, r.noise); },
              ThrowsMessage<std::exception>(HasSubstr("plan: renoise")));
}

TEST(ExportTest, BadShapesAndObstaclesAreRejectedByTheScript) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kNone, Disc(), {32, 64});
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata(4));
  const torch::jit::IValue none;
  EXPECT_THAT([&] { module.run_method("plan", torch::zeros({2, 3}), torch::zeros({2, 3}), torch::zeros({2, 64, 4})); },
              ThrowsMessage<std::exception>(HasSubstr("plan: start: expected (B, 4)")));
  const torch::Tensor s = torch::full({2, 4}, 0.5f), noise = torch::zeros({2, 64, 4});
  EXPECT_THAT([&] { module.run_method("plan", s, s, noise, none, torch::zeros({1, 4})); },
              ThrowsMessage<std::exception>(HasSubstr("plan: obstacles: expected (K, 3)")));
  EXPECT_THAT([&] { module.run_method("plan", s, s, noise, none, torch::tensor({{0.5f, 0.5f, -0.1f}})); },
              ThrowsMessage<std::exception>(HasSubstr("non-negative radii")));
  EXPECT_THAT([&] { module.run_method("plan", s, s, noise, none, torch::tensor({{NAN, 0.5f, 0.1f}})); },
              ThrowsMessage<std::exception>(HasSubstr("finite")));
}

TEST(ExportTest, VelocityIsTheNetworkAndChecksItsArguments) {
  for (const Conditioning conditioning : {Conditioning::kInpaint, Conditioning::kDirect}) {
    const FlowPlanner planner = MakePlanner(conditioning, Splitting::kNone, Disc());
    torch::jit::Module module = BuildScriptPlanner(planner, Metadata(4));
    torch::manual_seed(3);
    const torch::Tensor x = torch::randn({2, 64, 4}), t = torch::rand({2});
    const torch::Tensor cond = conditioning == Conditioning::kDirect ? torch::rand({2, 8}) : torch::Tensor();
    torch::NoGradGuard no_grad;
    const torch::Tensor expected = planner.net()->Forward(x, t, cond);
    const torch::jit::IValue script_cond = cond.defined() ? torch::jit::IValue(cond) : torch::jit::IValue();
    const torch::Tensor got = module.run_method("velocity", x, t, script_cond).toTensor();
    EXPECT_LT(MaxDifference(got, expected), 1e-5);
    EXPECT_THAT([&] { module.run_method("velocity", torch::zeros({2, 63, 4}), t, script_cond); },
                ThrowsMessage<std::exception>(HasSubstr("velocity: x: expected (B, 64, 4)")));
    EXPECT_THAT([&] { module.run_method("velocity", x, torch::zeros({3}), script_cond); },
                ThrowsMessage<std::exception>(HasSubstr("velocity: t: expected (B,)")));
    EXPECT_THAT([&] { module.run_method("velocity", x, t, torch::zeros({2, 5})); },
                ThrowsMessage<std::exception>(HasSubstr("velocity: cond")));
  }
}

TEST(ExportTest, SampleStartsAndEndsAtTheRequest) {
  const FlowPlanner planner = MakePlanner(Conditioning::kInpaint, Splitting::kMidpoint, Disc(), {32, 64});
  torch::jit::Module module = BuildScriptPlanner(planner, Metadata(4));
  const torch::Tensor start = torch::tensor({0.1f, 0.1f, 0.0f, 0.0f}), goal = torch::tensor({0.9f, 0.2f, 0.1f, 0.0f});
  const torch::Tensor obstacles = torch::tensor({{0.5f, 0.15f, 0.05f}});
  const torch::Tensor plans = module.run_method("sample", start, goal, 5, obstacles).toTensor();
  ASSERT_EQ(plans.sizes(), (std::vector<int64_t>{5, 64, 4}));
  EXPECT_TRUE(torch::equal(plans.select(1, 0), start.expand({5, 4})));
  EXPECT_TRUE(torch::equal(plans.select(1, 63), goal.expand({5, 4})));
}

}  // namespace
}  // namespace flowplan::planning
