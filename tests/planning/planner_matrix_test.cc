// Every configurable branch of a learned planner meets a test before a user:
// one parameterised test over the axes the config allows (sampler, network,
// conditioning, splitting, schedule, clip, robot, obstacle shapes, user cost),
// over a covering set that holds every value of every axis and every valid
// pair of values. Each case assembles a tiny planner, checks its network's
// TorchScript against the C++ network, plans in-process, saves the planner,
// loads it with torch::jit::load and with Python's torch.jit.load (nothing but
// PyTorch), and requires the same plans to 1e-5 (under torch.no_grad(), and
// under torch.inference_mode() unless a user cost needs autograd), and that
// guidance changed the plan wherever there are obstacles to avoid.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <numeric>
#include <set>

#include "jit/library.h"
#include "models/model_config.h"
#include "models/trajectory_net.h"
#include "planning/assemble.h"
#include "tests/support/planners.h"
#include "tests/support/scratch_dir.h"
#include "tests/support/tiny_model.h"

namespace flowplan::planning {
namespace {

// The axes and their values.
const std::vector<std::vector<std::string>> kAxes = {
    {"flow", "ddpm", "latent"},                               // 0 sampler
    {"unet1d", "transformer", "state_vae"},                   // 1 network
    {"inpaint", "direct"},                                    // 2 conditioning
    {"none", "midpoint"},                                     // 3 splitting
    {"one_minus_t", "ratio", "rising"},                       // 4 schedule
    {"0", "1"},                                               // 5 clip
    {"particle", "franka"},                                   // 6 robot
    {"free", "spheres", "boxes", "cylinders", "capsules", "all"},  // 7 obstacles
    {"none", "above"},                                        // 8 user cost
};
const char* const kAxisNames[] = {"sampler", "network", "conditioning", "splitting", "schedule",
                                  "clip",    "robot",   "obstacles",    "user_cost"};

using Case = std::vector<int>;  // a value index per axis

/// What the config allows: the VAE planner takes a state VAE and no conditioning or splitting (its
/// conditioning is reported as inpaint here); trajectory samplers take trajectory networks; only the flow
/// sampler splits.
bool Valid(const Case& c) {
  const bool latent = c[0] == 2, vae = c[1] == 2;
  if (latent != vae) return false;
  if (latent && (c[2] != 0 || c[3] != 0)) return false;
  if (c[0] == 1 && c[3] != 0) return false;
  return true;
}

/// A greedy covering set: cases chosen one by one, each covering the most pairs (of valid cases) not yet covered.
std::vector<Case> CoveringSet() {
  std::vector<Case> all;
  Case c(kAxes.size(), 0);
  while (true) {
    if (Valid(c)) all.push_back(c);
    size_t axis = 0;
    while (axis < c.size() && ++c[axis] == static_cast<int>(kAxes[axis].size())) c[axis++] = 0;
    if (axis == c.size()) break;
  }
  auto pairs = [](const Case& k) {
    std::set<std::tuple<int, int, int, int>> out;
    for (int a = 0; a < static_cast<int>(k.size()); ++a) {
      for (int b = a + 1; b < static_cast<int>(k.size()); ++b) out.insert({a, k[a], b, k[b]});
    }
    return out;
  };
  std::set<std::tuple<int, int, int, int>> uncovered;
  for (const Case& k : all) {
    for (const auto& p : pairs(k)) uncovered.insert(p);
  }
  std::vector<Case> chosen;
  while (!uncovered.empty()) {
    const Case* best = nullptr;
    size_t best_count = 0;
    for (const Case& k : all) {
      size_t count = 0;
      for (const auto& p : pairs(k)) count += uncovered.count(p);
      if (count > best_count) {
        best = &k;
        best_count = count;
      }
    }
    chosen.push_back(*best);
    for (const auto& p : pairs(*best)) uncovered.erase(p);
  }
  return chosen;
}

std::string Name(const Case& c) {
  std::string out;
  for (size_t axis = 0; axis < c.size(); ++axis) out += (axis ? "_" : "") + kAxes[axis][c[axis]];
  return out;
}

void WriteFloats(const std::string& path, const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kFloat32).contiguous();
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(c.data_ptr<float>()), static_cast<std::streamsize>(c.numel() * 4));
}

/// The case's obstacles near the straight path between start and goal, whose midpoint is `middle` (W,).
geometry::SceneRows Scene(const std::string& which, const torch::Tensor& middle) {
  const int64_t W = middle.size(0);
  const std::vector<double> m(middle.data_ptr<double>(), middle.data_ptr<double>() + W);
  const bool d3 = W == 3;
  std::map<std::string, std::vector<double>> rows;
  auto at = [&](std::vector<double> offset) {
    std::vector<double> p;
    for (int64_t i = 0; i < W; ++i) p.push_back(m[static_cast<size_t>(i)] + offset[static_cast<size_t>(i)]);
    return p;
  };
  auto join = [](std::vector<double> a, const std::vector<double>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  rows["spheres"] = join(at({0.0, 0.01, 0.0}), {0.12});
  rows["boxes"] = join(at({0.01, 0.0, 0.0}), d3 ? std::vector<double>{0.2, 0.1, 0.15, 0.9, 0.1, 0.2, 0.3}
                                                 : std::vector<double>{0.2, 0.1, 0.4});
  rows["cylinders"] = join(at({0.0, -0.01, 0.02}), d3 ? std::vector<double>{0.08, 0.25, 0.7, 0.7, 0.0, 0.1}
                                                       : std::vector<double>{0.08, 0.25, 0.5});
  rows["capsules"] = join(join(at({-0.05, 0.02, 0.0}), at({0.05, 0.03, 0.01})), {0.06});
  geometry::SceneRows scene;
  for (const std::string& kind : geometry::ObstacleKinds()) {
    if (which == kind || which == "all") scene.insert(kind, torch::tensor(rows[kind], torch::kFloat32).view({1, -1}));
  }
  return scene;
}

class PlannerMatrixTest : public ::testing::TestWithParam<Case> {};

TEST_P(PlannerMatrixTest, InProcessCppAndPythonPlanAlike) {
  const Case& c = GetParam();
  const auto value = [&](int axis) { return kAxes[static_cast<size_t>(axis)][static_cast<size_t>(c[axis])]; };
  const bool franka = value(6) == "franka";
  const kinematics::TrajectoryInfo trajectory = franka ? testing::FrankaTrajectory(16) : testing::DiscTrajectory(16);
  const int64_t J = trajectory.robot.num_joints, D = 2 * J;
  const kinematics::Robot robot(trajectory.robot);

  // The network: tiny, with weights scaled up so that a mistake anywhere shows in the plan.
  torch::manual_seed(11);
  models::ModelConfig model = testing::TinyModelConfig(value(1) == "unet1d"        ? models::Architecture::kUNet1D
                                                       : value(1) == "transformer" ? models::Architecture::kTransformer
                                                                                   : models::Architecture::kStateVae);
  model.transformer.d_model = 16;  // smaller still than the shared tiny config: 40 cases each plan three ways
  model.vae.latent = 8;
  PlannerParts parts;
  parts.objective.name = value(0) == "flow"   ? objectives::ObjectiveKind::kFlowMatching
                         : value(0) == "ddpm" ? objectives::ObjectiveKind::kDdpm
                                              : objectives::ObjectiveKind::kVae;
  parts.objective.conditioning = value(2) == "inpaint" ? models::Conditioning::kInpaint : models::Conditioning::kDirect;
  parts.objective.ddpm.steps = 6;
  parts.net = models::MakeNetwork(model, D, models::ConditionDim(parts.objective.conditioning, D));
  {
    torch::NoGradGuard no_grad;
    for (auto& p : parts.net->parameters()) p.mul_(1.5);
  }
  parts.net->eval();
  torch::Tensor lo = torch::full({D}, -2.0f), hi = torch::full({D}, 2.0f);
  for (int64_t j = 0; j < J; ++j) {
    lo[j] = static_cast<float>(trajectory.robot.joint_lower[static_cast<size_t>(j)]);
    hi[j] = static_cast<float>(trajectory.robot.joint_upper[static_cast<size_t>(j)]);
  }
  parts.normalizer = models::MinMaxNormalizer(lo, hi);
  parts.trajectory = trajectory;
  parts.sampler.steps = 4;
  parts.sampler.splitting = value(3) == "midpoint" ? Splitting::kMidpoint : Splitting::kNone;
  parts.sampler.latent.iterations = 2;
  parts.guidance.scale = 0.5;
  parts.guidance.clip = value(5) == "1" ? 1.0 : 0.0;
  parts.guidance.smoothness_weight = 1e-4;
  parts.guidance.joint_limit_weight = 0.01;
  const std::filesystem::path dir = flowplan::testing::ScratchDir();
  if (value(8) == "above") {
    // Keep the TCP above (y for the particle, z for the Franka) its middle height.
    parts.guidance.user_cost = (dir / "above.py").string();
    std::ofstream(parts.guidance.user_cost) << "def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                                            << "    height = self.robot.tcp(q)[:, :, " << (franka ? 2 : 1) << "]\n"
                                            << "    return torch.relu(" << (franka ? 0.4 : 0.1) << " - height).sum(1)\n";
  }
  parts.config_yaml = "{}\n";
  // Half the cases (by the parity of their values) plan with the native kernels (the UNet's and the obstacle
  // distances'), half with LibTorch's operators only; Python loads libflowplan_kernels for the first half.
  const bool native = std::accumulate(c.begin(), c.end(), 0) % 2 == 0;
  parts.sampler.network_kernels = native ? models::Kernels::kNative : models::Kernels::kPortable;
  parts.guidance.distance_kernels = parts.sampler.network_kernels;
  const auto planner = AssemblePlanner(parts);

  // The network's TorchScript against the C++ network (the one computation written twice), at batches that
  // take the UNet script's two convolution paths (at most 4, and more).
  if (value(0) != "latent") {
    torch::NoGradGuard no_grad;
    const auto net = std::dynamic_pointer_cast<models::TrajectoryNet>(parts.net);
    const torch::jit::Module script = planner->module().attr("sampler").toModule().attr("network").toModule();
    for (const int64_t batch : {1, 2, 6}) {
      const torch::Tensor x = torch::randn({batch, 16, D}), t = torch::rand({batch});
      const torch::Tensor cond = net->cond_dim() > 0 ? torch::randn({batch, net->cond_dim()}) : torch::Tensor();
      const torch::Tensor ours = jit::Call(script, "forward", {x, t, cond.defined() ? c10::IValue(cond) : c10::IValue()}).toTensor();
      EXPECT_LT((ours - net->Forward(x, t, cond)).abs().max().item<float>(), 1e-5) << "batch " << batch;
    }
    const torch::Tensor none = jit::Call(script, "forward", {torch::zeros({0, 16, D}), torch::zeros({0}),
                                                             net->cond_dim() > 0 ? c10::IValue(torch::zeros({0, net->cond_dim()}))
                                                                                 : c10::IValue()}).toTensor();
    EXPECT_EQ(none.sizes(), torch::IntArrayRef({0, 16, D})) << "an empty batch";
    // The weights read back from the script (how flowplan plans with an exported file's weights) are the
    // network's, bit for bit, whichever kernels wrote it.
    torch::manual_seed(99);
    const models::NetworkPtr fresh = models::MakeNetwork(model, D, models::ConditionDim(parts.objective.conditioning, D));
    models::ReadScriptedWeights(dynamic_cast<models::TrajectoryNet&>(*fresh), script, "the matrix's planner");
    const auto want = parts.net->named_parameters(true), got = fresh->named_parameters(true);
    ASSERT_EQ(want.size(), got.size());
    for (const auto& entry : want) EXPECT_TRUE(torch::equal(entry.value(), got[entry.key()])) << entry.key();
    const auto want_buffers = parts.net->named_buffers(true), got_buffers = fresh->named_buffers(true);
    for (const auto& entry : want_buffers) EXPECT_TRUE(torch::equal(entry.value(), got_buffers[entry.key()])) << entry.key();
  }

  // Start and goal: positions at 40 % and 60 % of the range, velocities 0; the scene around the middle.
  const int64_t B = 3;
  torch::manual_seed(5);
  torch::Tensor start = torch::zeros({B, D}), goal = torch::zeros({B, D});
  start.slice(1, 0, J).copy_((lo + 0.4 * (hi - lo)).slice(0, 0, J).expand({B, J}) + 0.01 * torch::randn({B, J}));
  goal.slice(1, 0, J).copy_((lo + 0.6 * (hi - lo)).slice(0, 0, J).expand({B, J}));
  const torch::Tensor middle = robot.Tcp(((start + goal) * 0.5).slice(1, 0, J).slice(0, 0, 1).to(torch::kFloat64))[0];
  const geometry::SceneRows scene = Scene(value(7), middle.contiguous());
  const auto& noise_shape = planner->noise_shape();
  std::vector<int64_t> shape = {B};
  shape.insert(shape.end(), noise_shape.begin(), noise_shape.end());
  const torch::Tensor noise = torch::randn(shape);
  torch::Tensor renoise;
  if (!planner->renoise_shape().empty()) {
    std::vector<int64_t> re = {B};
    re.insert(re.end(), planner->renoise_shape().begin(), planner->renoise_shape().end());
    renoise = torch::randn(re);
  }
  PlanSettings settings;
  settings.schedule = value(4);
  const torch::Tensor ours = planner->PlanWithNoise(start, goal, noise, renoise, scene, settings);
  ASSERT_EQ(ours.sizes(), torch::IntArrayRef({B, 16, D}));
  EXPECT_TRUE(torch::isfinite(ours).all().item<bool>());
  EXPECT_TRUE(torch::equal(ours, planner->PlanWithNoise(start, goal, noise, renoise, scene, settings)))
      << "the same call twice gives the same bytes";
  // Guidance does something where there are obstacles or a user cost.
  if (value(7) != "free" || value(8) != "none") {
    PlanSettings off = settings;
    off.values["guidance.scale"] = 0.0;
    EXPECT_GT((ours - planner->PlanWithNoise(start, goal, noise, renoise, scene, off)).abs().max().item<float>(), 1e-4);
  }

  // The saved file, loaded by LibTorch.
  const std::string file = (dir / "planner.pt").string();
  planner->Save(file);
  const auto loaded = LearnedPlanner::Load(file);
  EXPECT_LT((loaded->PlanWithNoise(start, goal, noise, renoise, scene, settings) - ours).abs().max().item<float>(), 1e-5);

  // ... and by Python, with nothing but PyTorch (and flowplan's kernel library for a native network).
  WriteFloats((dir / "start.bin").string(), start);
  WriteFloats((dir / "goal.bin").string(), goal);
  WriteFloats((dir / "noise.bin").string(), noise);
  if (renoise.defined()) WriteFloats((dir / "renoise.bin").string(), renoise);
  WriteFloats((dir / "plan.bin").string(), ours);
  std::string kinds;
  for (const auto& entry : scene) {
    WriteFloats((dir / (entry.key() + ".bin")).string(), entry.value());
    kinds += (kinds.empty() ? "" : ",") + entry.key();
  }
  const std::string command = std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                              "/tests/planning/check_exported_planner.py " + file + " " + dir.string() + " " +
                              std::to_string(B) + " " + value(4) + " " + (kinds.empty() ? "-" : kinds) + " " +
                              (value(8) == "none" ? "inference" : "no_grad") +
                              (native ? std::string(" ") + FLOWPLAN_KERNELS_LIBRARY : std::string());
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
}

INSTANTIATE_TEST_SUITE_P(CoveringSet, PlannerMatrixTest, ::testing::ValuesIn(CoveringSet()),
                         [](const auto& info) { return Name(info.param); });

TEST(PlannerMatrix, TheCoveringSetHoldsEveryValueAndEveryValidPair) {
  const std::vector<Case> cases = CoveringSet();
  for (size_t a = 0; a < kAxes.size(); ++a) {
    for (size_t va = 0; va < kAxes[a].size(); ++va) {
      EXPECT_TRUE(std::any_of(cases.begin(), cases.end(), [&](const Case& c) { return c[a] == static_cast<int>(va); }))
          << kAxisNames[a] << " = " << kAxes[a][va];
    }
  }
  EXPECT_LT(cases.size(), 40u) << "the covering set grew: mind the test budget";
}

}  // namespace
}  // namespace flowplan::planning
