// `flowplan plan` on tiny models: the files it writes, checked by an
// independent script, its determinism, execution in MuJoCo, and bad input.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "tests/support/command.h"
#include "tests/support/scratch_dir.h"

namespace flowplan {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using flowplan::testing::ExpectCleanFailure;
using flowplan::testing::ExpectOk;
using flowplan::testing::Flowplan;
using flowplan::testing::Outcome;
using flowplan::testing::ReadText;
using flowplan::testing::RunCommand;
using flowplan::testing::Source;

std::string CheckPlan(const std::string& prefix) {
  return std::string(FLOWPLAN_PYTHON) + " " + Source("tests/cli/check_plan.py") + " " + prefix + ".h5 " + prefix +
         ".json";
}

/// A particle model of the tiny smoke config, trained once for the suite.
class ParticlePlanTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // ScratchDir() names a test, and no test runs yet: one folder for the suite.
    dir_ = new fs::path(fs::path(::testing::TempDir()) / ("flowplan_" + std::to_string(::getpid()) + "_ParticlePlanTest"));
    // A folder of this name left by an earlier process with the same pid would hold a finished run, which `train`
    // refuses to train into: the suite's set-up then failed and its tests were reported skipped.
    fs::remove_all(*dir_);
    fs::create_directories(*dir_);
    const std::string paths = " generate.out=" + Path("data.h5") + " data.path=" + Path("data.h5") +
                              " run_dir=" + Path("run") + " --log-level warn";
    ASSERT_EQ(Flowplan("generate --config " + Source("tests/cli/tiny.yaml") + paths).exit_code, 0);
    ASSERT_EQ(Flowplan("train --config " + Source("tests/cli/tiny.yaml") + paths).exit_code, 0);
    ASSERT_EQ(Flowplan("export --ckpt " + Path("run") + " --log-level warn").exit_code, 0);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
  }
  static std::string Path(const std::string& name) { return (*dir_ / name).string(); }
  static fs::path* dir_;
};
fs::path* ParticlePlanTest::dir_ = nullptr;

TEST_F(ParticlePlanTest, WritesPlansReportAndFigureThatAnIndependentScriptConfirms) {
  std::ofstream(Path("scene.yaml")) << "spheres:\n  - {centre: [0.5, 0.3], radius: 0.1}\n";
  const Outcome outcome = Flowplan("plan --ckpt " + Path("run") + " --start 0,0 --goal 1,0 --scene " +
                                   Path("scene.yaml") + " --sphere 0.3,0.7,0.05 -n 20 --seed 4 --out " + Path("p"));
  ExpectOk(outcome);
  EXPECT_THAT(outcome.output, HasSubstr("20 plans in"));
  EXPECT_TRUE(fs::exists(Path("p.png")));
  const std::string report = ReadText(Path("p.json"));
  EXPECT_THAT(report, HasSubstr("\"scene\": {\"spheres\": [[0.5, 0.3, 0.1], [0.3, 0.7, 0.05]]}"));
  EXPECT_THAT(report, HasSubstr("\"obstacles\": [\"spheres[0]\", \"spheres[1]\"]"));
  EXPECT_THAT(report, HasSubstr("\"arm_clearance\": ["));
  const Outcome check = RunCommand(CheckPlan(Path("p")));
  EXPECT_EQ(check.exit_code, 0) << check.output;
}

TEST_F(ParticlePlanTest, EveryShapeFromTheCommandLineAndFromAFileIsPlannedAroundAndReported) {
  // 2-D analogues: a rotated rectangle, a cylinder seen from the side, a stadium.
  std::ofstream(Path("shapes.yaml")) << "boxes: [{centre: [0.5, 0.25], size: [0.1, 0.2], angle: 0.3}]\n"
                                        "capsules: [{a: [0.2, 0.6], b: [0.3, 0.7], radius: 0.04}]\n";
  const Outcome outcome = Flowplan("plan --ckpt " + Path("run") + " --start 0,0 --goal 1,0 --scene " +
                                   Path("shapes.yaml") + " --cylinder 0.75,0.4,0.05,0.2,1.2 guidance.scale=2 "
                                   "--sphere 0.4,0.8,0.05 -n 12 --seed 2 --out " + Path("shapes"));
  ExpectOk(outcome);
  EXPECT_TRUE(fs::exists(Path("shapes.png")));
  const std::string report = ReadText(Path("shapes.json"));
  EXPECT_THAT(report, HasSubstr("\"obstacles\": [\"spheres[0]\", \"boxes[0]\", \"cylinders[0]\", \"capsules[0]\"]"));
  EXPECT_THAT(report, HasSubstr("\"boxes\": [[0.5, 0.25, 0.1, 0.2, 0.3]]"));
  EXPECT_THAT(report, HasSubstr("\"scale\": 2.0,")) << "an override right after a shape's numbers is an override";
  const Outcome check = RunCommand(CheckPlan(Path("shapes")));
  EXPECT_EQ(check.exit_code, 0) << check.output;
  ExpectCleanFailure(Flowplan("plan --ckpt " + Path("run") + " --start 0,0 --goal 1,0 --box 0.5,0.3,0.1"),
                     "--box \"0.5,0.3,0.1\": expected cx,cy,lx,ly[,angle] (the robot's workspace is 2-D), got 3 numbers");
  std::ofstream(Path("turned.yaml")) << "boxes: [{centre: [0.5, 0.25], size: [0.1, 0.2], quaternion: [1, 0, 0, 0]}]\n";
  ExpectCleanFailure(Flowplan("plan --ckpt " + Path("run") + " --start 0,0 --goal 1,0 --scene " + Path("turned.yaml")),
                     "turned.yaml: boxes[0].quaternion: a 2-D obstacle is turned by `angle`");
}

TEST_F(ParticlePlanTest, AnExportedFileTakesEveryGuidanceSettingPerCall) {
  // What the run folder plans with guidance.margin=0.1 guidance.clip=0.5 sampler.steps=6, the exported file plans too.
  const std::string common = " --start 0,0 --goal 1,0 --sphere 0.5,0.3,0.1 -n 8 --seed 3 --no-plot"
                             " guidance.margin=0.1 guidance.clip=0.5 sampler.steps=6 guidance.schedule=rising";
  ExpectOk(Flowplan("plan --ckpt " + Path("run") + common + " --out " + Path("set_run")));
  ExpectOk(Flowplan("plan --planner " + Path("run/planner.pt") + common + " --out " + Path("set_file")));
  ExpectOk(Flowplan("plan --planner " + Path("run/planner.pt") + " --start 0,0 --goal 1,0 --sphere 0.5,0.3,0.1 -n 8 "
                    "--seed 3 --no-plot --out " + Path("unset_file")));
  const std::string compare = std::string(FLOWPLAN_PYTHON) + " -c \"import h5py, numpy as np; p = lambda n: h5py.File('" +
                              Path("") + "' + n + '.h5')['plans'][...]; d = np.abs(p('set_run') - p('set_file')).max(); "
                              "assert d < 1e-5, d; assert np.abs(p('set_file') - p('unset_file')).max() > 1e-3\"";
  EXPECT_EQ(std::system(compare.c_str()), 0);
}

TEST_F(ParticlePlanTest, AnExportedFileCarriesOnlyTheSceneItIsGivenAndOutputsGoToTheWorkingFolder) {
  // The training config's scene (a disc here) is not an obstacle of the exported file; a scene given to export is.
  const std::string config_scene = " \"scene.spheres=[{centre: [0.5, 0.3], radius: 0.1}]\" --log-level warn";
  ExpectOk(Flowplan("export --ckpt " + Path("run") + config_scene + " --out " + Path("plain.pt")));
  std::ofstream(Path("baked.yaml")) << "boxes: [{centre: [0.5, 0.6], size: [0.1, 0.1]}]\n";
  ExpectOk(Flowplan("export --ckpt " + Path("run") + config_scene + " --scene " + Path("baked.yaml") + " --out " +
                    Path("baked.pt")));
  // Planned from the suite's folder as the working folder, with no --out: PREFIX is ./plan.
  const std::string plan = "cd " + Path("") + " && " + FLOWPLAN_BINARY + " plan --start 0,0 --goal 1,0 -n 2 --no-plot ";
  const Outcome plain = RunCommand(plan + "--planner plain.pt");
  ExpectOk(plain);
  EXPECT_THAT(plain.output, HasSubstr("around 0 obstacles ("));
  EXPECT_THAT(ReadText(Path("plan.json")), HasSubstr("\"obstacles\": []"));
  ExpectCleanFailure(RunCommand(plan + "--planner plain.pt"), "plan.json: exists; give --force to replace it");
  const Outcome baked = RunCommand(plan + "--planner baked.pt --force");
  ExpectOk(baked);
  EXPECT_THAT(baked.output,
              HasSubstr("around 1 obstacle: boxes[0] [0.5, 0.6, 0.1, 0.1, 0] from the scene baked into baked.pt ("));
  EXPECT_THAT(ReadText(Path("plan.json")), HasSubstr("\"obstacles\": [\"boxes[0]\"]"));
  // Obstacles of the command line are added to the baked scene, and the log says so.
  const Outcome both = RunCommand(plan + "--planner baked.pt --sphere 0.3,0.7,0.05 --force");
  ExpectOk(both);
  EXPECT_THAT(both.output, HasSubstr("around 2 obstacles: spheres[0] [0.3, 0.7, 0.05], boxes[0] [0.5, 0.6, 0.1, 0.1, "
                                     "0] from the scene baked into baked.pt and the command line ("));
}

TEST_F(ParticlePlanTest, AUserCostFileChangesThePlansInProcessAndFromTheExportedFile) {
  // Keep the disc above y = 0.2 between start and goal (both at y = 0).
  std::ofstream(Path("above.py")) << "def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor:\n"
                                     "    return (torch.relu(0.2 - self.robot.tcp(q)[:, :, 1]) ** 2).sum(1)\n";
  const std::string common = " --start 0,0 --goal 1,0 --sphere 0.5,0.8,0.05 -n 16 --seed 5 --no-plot";
  const std::string cost = " guidance.user_cost=" + Path("above.py") + " guidance.user_cost_weight=5";
  ExpectOk(Flowplan("plan --ckpt " + Path("run") + common + " --out " + Path("no_cost")));
  ExpectOk(Flowplan("plan --ckpt " + Path("run") + common + cost + " --out " + Path("cost_run")));
  ExpectOk(Flowplan("export --ckpt " + Path("run") + cost + " --out " + Path("cost.pt") + " --log-level warn"));
  ExpectOk(Flowplan("plan --planner " + Path("cost.pt") + common + " --out " + Path("cost_file")));
  // The cost of every plan's interior states falls, in all to less than half; the exported file plans what the
  // run folder plans.
  const std::string compare =
      std::string(FLOWPLAN_PYTHON) + " -c \"import h5py, numpy as np; p = lambda n: h5py.File('" + Path("") +
      "' + n + '.h5')['plans'][...]; c = lambda n: (np.maximum(0.2 - p(n)[:, 1:-1, 1], 0) ** 2).sum(1); "
      "assert np.all(c('cost_run') < c('no_cost')) and c('cost_run').sum() < 0.5 * c('no_cost').sum(), "
      "(c('no_cost'), c('cost_run')); d = np.abs(p('cost_run') - p('cost_file')).max(); assert d < 1e-5, d\"";
  EXPECT_EQ(std::system(compare.c_str()), 0);
}

TEST_F(ParticlePlanTest, SameSeedSameBytesForAnyThreadCountAndFromTheExportedFile) {
  const std::string common = " --start 0,0 --goal 1,0 --sphere 0.5,0.3,0.1 -n 40 --seed 9 --no-plot";
  ExpectOk(Flowplan("plan --ckpt " + Path("run") + common + " threads=1 --out " + Path("one")));
  ExpectOk(Flowplan("plan --ckpt " + Path("run") + common + " threads=2 --out " + Path("two")));
  ExpectOk(Flowplan("plan --planner " + Path("run/planner.pt") + common + " --out " + Path("file")));
  EXPECT_EQ(ReadText(Path("one.h5")), ReadText(Path("two.h5")));
  // The exported planner plans the same paths from the same seed (to float32 rounding).
  const std::string compare = std::string(FLOWPLAN_PYTHON) +
                              " -c \"import h5py, numpy as np; a = h5py.File('" + Path("one.h5") +
                              "')['plans'][...]; b = h5py.File('" + Path("file.h5") +
                              "')['plans'][...]; d = np.abs(a - b).max(); assert d < 1e-5, d\"";
  EXPECT_EQ(std::system(compare.c_str()), 0);
}

TEST_F(ParticlePlanTest, BadInputsEndInOneClearLine) {
  const std::string run = "plan --ckpt " + Path("run") + " ";
  ExpectCleanFailure(Flowplan(run + "--start 0.5,0.3 --goal 1,0 --sphere 0.5,0.3,0.1"), "start is inside obstacle spheres[0]");
  ExpectCleanFailure(Flowplan(run + "--start 0,0 --goal 0.5,0.3 --sphere 0.5,0.3,0.1"), "goal is inside obstacle spheres[0]");
  ExpectCleanFailure(Flowplan(run + "--start 0,0 --goal 1,0 --sphere 0.5,0.3,0.2,0.1"), "expected cx,cy,r");
  ExpectCleanFailure(Flowplan(run + "--start 0,0 --goal 1,0 --sphere 0.5,0.3,-0.1"), "non-negative radius");
  ExpectCleanFailure(Flowplan(run + "--start 0,0,0 --goal 1,0"), "--start: expected 2 positions or 4 state values");
  ExpectCleanFailure(Flowplan(run + "--start 0,nan --goal 1,0"), "--start value 2 \"nan\": not a finite number");
  ExpectCleanFailure(Flowplan(run + "--start 1.5,0 --goal 1,0"), "--start: x = 1.5 is outside [0, 1]");
  ExpectCleanFailure(Flowplan(run + "--goal 1,0"), "either as --start");
  ExpectCleanFailure(Flowplan("plan --rrt-connect --start 0,0 --goal 1,0"), "plan --planner-kind rrt_connect (--rrt-connect): expected --config FILE");
  std::ofstream(Path("three_d.yaml")) << "spheres:\n  - {centre: [0.5, 0.3, 0.2], radius: 0.1}\n";
  ExpectCleanFailure(Flowplan(run + "--start 0,0 --goal 1,0 --scene " + Path("three_d.yaml")),
                     "three_d.yaml: spheres[0].centre: expected 2 values (the robot's workspace is 2-D), got 3");
  std::ofstream(Path("no_radius.yaml")) << "spheres:\n  - {centre: [0.5, 0.3]}\n";
  ExpectCleanFailure(Flowplan(run + "--start 0,0 --goal 1,0 --scene " + Path("no_radius.yaml")),
                     "no_radius.yaml: spheres[0].radius: missing");
  std::ofstream(Path("nan_radius.yaml")) << "spheres:\n  - {centre: [0.5, 0.3], radius: .nan}\n";
  ExpectCleanFailure(Flowplan(run + "--start 0,0 --goal 1,0 --scene " + Path("nan_radius.yaml")),
                     "spheres[0].radius: expected a number");
  ExpectCleanFailure(Flowplan(run + "--start 0,0 --goal 1,0 --execute"), "execution in MuJoCo needs an arm in 3-D (the Franka or a robot folder); this planner's robot is \"particle_disc\"");
  ExpectCleanFailure(Flowplan("plan --planner " + Path("run/planner.pt") + " --start 0,0 --goal 1,0 sampler.splitting=midpoint"),
                     "sampler.splitting: is compiled into");
  ExpectCleanFailure(Flowplan("plan --planner " + Path("run/planner.pt") + " --start 0,0 --goal 1,0 model.unet.groups=4"),
                     "model.unet.groups: the network was trained with");
  EXPECT_FALSE(fs::exists(Path("run/plan.h5")));  // nothing half-written by the failures
}

TEST(EagerReferenceTest, TheNetworkAndThePlansMatchAPlainPyTorchImplementation) {
  // bench/eager_reference.py: the UNet, normalizer, Franka kinematics, costs and sampler written in plain PyTorch
  // (torch.nn, autograd), loading a checkpoint's weights, against the planner flowplan exports from it.
  const fs::path dir = flowplan::testing::ScratchDir();
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  const std::string config = " --config " + Source("configs/franka_reach.yaml") + " generate.out=" + path("data.h5") +
                             " data.path=" + path("data.h5") + " run_dir=" + path("run") +
                             " generate.episodes=16 generate.franka.horizon=16 model.unet.down_dims=[8,16,32]"
                             " train.steps=3 train.batch_size=4 train.eval_every=0 --log-level warn";
  ExpectOk(Flowplan("generate" + config));
  ExpectOk(Flowplan("train" + config));
  ExpectOk(Flowplan("export --ckpt " + path("run") + " --out " + path("split.pt") + " sampler.splitting=midpoint --log-level warn"));
  // The same network as MPD's DDPM, for the reference's DDPM sampler.
  ExpectOk(Flowplan("train" + config + " run_dir=" + path("run_mpd") + " objective.name=ddpm"));
  ExpectOk(Flowplan("export --ckpt " + path("run_mpd") + " --out " + path("mpd.pt") + " --log-level warn"));
  const Outcome check = RunCommand(std::string(FLOWPLAN_PYTHON) + " " + Source("bench/eager_reference.py") +
                                   " --checkpoint " + path("run/checkpoints/step_00000003.pt") + " --export " +
                                   path("split.pt") + " --mpd-checkpoint " + path("run_mpd/checkpoints/step_00000003.pt") +
                                   " --mpd-export " + path("mpd.pt") + " --threads 1 --json " + path("eager.json") +
                                   " --check-only");
  EXPECT_EQ(check.exit_code, 0) << check.output;
  EXPECT_THAT(check.output, HasSubstr("guided_shapes_split_plan"));
  EXPECT_THAT(check.output, HasSubstr("mpd_guided_plan"));
}

TEST(InstalledPlanTest, AnInstalledBinaryPlansAndDrawsFromAnotherFolder) {
  // cmake --install into a fresh prefix, then everything from a folder that is neither the source nor the build
  // tree, with a config the test writes there.
  const fs::path dir = flowplan::testing::ScratchDir();
  const std::string prefix = (dir / "prefix").string(), work = (dir / "work").string();
  ExpectOk(RunCommand("cmake --install " + std::string(FLOWPLAN_BUILD_DIR) + " --prefix " + prefix));
  fs::create_directories(work);
  fs::copy_file(Source("tests/cli/tiny.yaml"), work + "/tiny.yaml");
  const std::string binary = prefix + "/bin/flowplan";
  auto installed = [&](const std::string& arguments) { return RunCommand("cd " + work + " && " + binary + " " + arguments); };
  ExpectOk(installed("generate --config tiny.yaml generate.out=data.h5 data.path=data.h5 run_dir=run --log-level warn"));
  ExpectOk(installed("train --config tiny.yaml generate.out=data.h5 data.path=data.h5 run_dir=run --log-level warn"));
  const Outcome plan = installed("plan --ckpt run --start 0,0 --goal 1,0 --sphere 0.5,0.3,0.1 --box 0.3,0.7,0.1,0.1 "
                                 "-n 4 --out p --log-level debug");
  ExpectOk(plan);
  EXPECT_THAT(plan.output, HasSubstr("with " + prefix + "/share/flowplan/plot.py"));
  EXPECT_TRUE(fs::exists(work + "/p.png") && fs::exists(work + "/p.json") && fs::exists(work + "/p.h5"));
  ExpectOk(installed("export --ckpt run --log-level warn"));
  ExpectOk(installed("export --ckpt run --log-level warn"));  // written again over the first
  const Outcome onto_itself = installed("export --planner run/planner.pt --out run/planner.pt");
  EXPECT_NE(onto_itself.exit_code, 0);
  EXPECT_THAT(onto_itself.output, HasSubstr("run/planner.pt: is the planner being read; give another --out"));
  ExpectOk(installed("plan --planner run/planner.pt --start 0,0 --goal 1,0 --capsule 0.4,0.2,0.6,0.2,0.05 -n 2 --no-plot "
                     "--out q --log-level warn"));
  // The installed Python package plans with the exported particle planner through flowplan's native kernels.
  const Outcome python = RunCommand(
      "cd " + work + " && PYTHONPATH=" + prefix + "/lib/python3/dist-packages " + FLOWPLAN_PYTHON +
      " -c \"import torch, flowplan; p = flowplan.load_planner('run/planner.pt', native=True); "
      "x = p.sample(torch.tensor([0., 0., 0., 0.]), torch.tensor([1., 0., 0., 0.]), 3, "
      "spheres=torch.tensor([[0.5, 0.3, 0.1]])); print(p.native, x.shape[0], x.shape[2], flowplan.__file__)\"");
  ExpectOk(python);
  EXPECT_THAT(python.output, HasSubstr("True 3 4 " + prefix + "/lib/python3/dist-packages/flowplan/__init__.py"));
  // So do the planning math's TorchScript files, as Python modules, compiled by PyTorch itself: a point 0.3 from the
  // centre of a sphere of radius 0.1 is 0.2 from it.
  const Outcome script = RunCommand(
      "cd " + work + " && PYTHONPATH=" + prefix + "/lib/python3/dist-packages " + FLOWPLAN_PYTHON +
      " -c \"import torch; from flowplan.script.geometry.scene import prepared_scene, scene_distance; "
      "s = prepared_scene({'spheres': torch.tensor([[0.5, 0.0, 0.2, 0.1]], dtype=torch.float64)}, 3); "
      "d = torch.jit.script(scene_distance)(torch.tensor([[0.5, 0.3, 0.2]], dtype=torch.float64), s)[0]; "
      "print(abs(d.item() - 0.2) < 1e-12)\"");
  ExpectOk(script);
  EXPECT_THAT(script.output, HasSubstr("True"));
}

/// A Franka reach model trained for two steps: enough to exercise IK, FK, guidance and execution.
TEST(FrankaPlanTest, RandomBlockedProblemsAreSolvedByRrtConnectThroughTheProblemsScript) {
  const fs::path dir = flowplan::testing::ScratchDir();
  const std::string problems = (dir / "problems.yaml").string(), out = (dir / "out").string();
  const std::string data = (dir / "reach.h5").string();  // RRT-Connect takes the robot from its config's data
  ExpectOk(Flowplan("generate --config " + Source("configs/franka_reach.yaml") + " generate.episodes=2 generate.out=" +
                    data + " --log-level warn"));
  ExpectOk(Flowplan("problems problems.count=2 seed=4 --log-level warn --out " + problems));
  ExpectOk(RunCommand("cd " + std::string(FLOWPLAN_SOURCE_DIR) + " && " + FLOWPLAN_PYTHON +
                      " scripts/franka_problems.py " + problems + " --planners rrt_connect --samples 2 --out " + out +
                      " --flowplan " + FLOWPLAN_BINARY + " --set data.path=" + data));
  const Outcome summary = RunCommand(std::string(FLOWPLAN_PYTHON) + " -c \"import json; s = json.load(open('" + out +
                                     "/summary.json')); r = s['planners']['rrt_connect']; "
                                     "print(s['problems'], r['arm_clear_rate'], r['problems_solved_arm'])\"");
  ExpectOk(summary);
  // The classical planner checks the whole arm against the spheres itself: every plan is clear.
  EXPECT_EQ(summary.output, "2 1 1.0\n");
  // One `flowplan plan --problems` report for the planner, which the independent script confirms.
  const Outcome check = RunCommand(CheckPlan(out + "/rrt_connect/plans"));
  EXPECT_EQ(check.exit_code, 0) << check.output;
}

TEST(FrankaPlanTest, PlansFromTcpPointsExecutesInMujocoAndRejectsUnreachableTargets) {
  const fs::path dir = flowplan::testing::ScratchDir();
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  const std::string config = " --config " + Source("configs/franka_reach.yaml") + " generate.out=" + path("data.h5") +
                             " data.path=" + path("data.h5") + " run_dir=" + path("run") +
                             " generate.episodes=24 generate.franka.horizon=16 model.unet.down_dims=[8,16]"
                             " train.steps=2 train.batch_size=4 train.eval_every=0 sampler.steps=2 --log-level warn";
  ExpectOk(Flowplan("generate" + config));
  ExpectOk(Flowplan("train" + config));
  const std::string plan = "plan --ckpt " + path("run") + " --start-tcp 0.5,-0.3,0.2 --goal-tcp 0.5,0.3,0.2 ";
  const Outcome outcome =
      Flowplan(plan + "--scene " + Source("configs/scenes/franka_sphere.yaml") + " --radius 0.05 -n 3 --execute --out " +
               path("p"));
  ExpectOk(outcome);
  EXPECT_THAT(outcome.output, HasSubstr("executed"));
  const std::string report = ReadText(path("p.json"));
  EXPECT_THAT(report, HasSubstr("\"scene\": {\"spheres\": [[0.5, 0, 0.2, 0.05]]}"));
  EXPECT_THAT(report, HasSubstr("\"executed\": {\"goal_distance\": "));
  EXPECT_THAT(report, HasSubstr("\"success_rate_executed\": "));
  const Outcome check = RunCommand(CheckPlan(path("p")));
  EXPECT_EQ(check.exit_code, 0) << check.output;
  // RRT-Connect on the same robot, horizon and dt (the config's generator makes them; no data file), around a
  // 0.10 m sphere.
  const Outcome rrt = Flowplan("plan --rrt-connect" + config + " data.path=" + path("none.h5") + " --start-tcp 0.5,-0.3,0.2 --goal-tcp 0.5,0.3,0.2 --scene " +
                               Source("configs/scenes/franka_sphere.yaml") + " --radius 0.1 -n 2 --execute --out " +
                               path("rrt") + " --max-speed-ratio 3 check.max_speed_ratio=3");  // 16 states: a fast move around the sphere
  ExpectOk(rrt);
  const std::string rrt_report = ReadText(path("rrt.json"));
  EXPECT_THAT(rrt_report, HasSubstr("\"planner\": \"rrt_connect\""));
  EXPECT_THAT(rrt_report, HasSubstr("\"success_rate\": 1, \"success_rate_executed\": 1, \"tcp_clear_rate\": 1, \"arm_clear_rate\": 1"));
  const Outcome check_rrt = RunCommand(CheckPlan(path("rrt")));
  EXPECT_EQ(check_rrt.exit_code, 0) << check_rrt.output;
  ExpectCleanFailure(Flowplan(plan.substr(0, plan.find("--goal-tcp")) + "--goal-tcp 2,0,0.5"),
                     "--goal-tcp: target (2, 0, 0.5) is unreachable");
  ExpectCleanFailure(Flowplan(plan + "--sphere 0.5,-0.3,0.2,0.05"), "start is inside obstacle spheres[1]");  // 0: the preset's
  ExpectCleanFailure(Flowplan(plan + "--sphere 0.5,0.3,0.2"), "expected cx,cy,cz,r");
  ExpectCleanFailure(Flowplan(plan + "--box 0.5,0,0.2,0.1,0.1,0.1,0,0,0,0"),
                     "--box \"0.5,0,0.2,0.1,0.1,0.1,0,0,0,0\".quaternion: expected a non-zero quaternion");
  ExpectCleanFailure(Flowplan(plan + "--cylinder 0.5,0,0.2,-0.1,0.2"), "--cylinder \"0.5,0,0.2,-0.1,0.2\": expected a non-negative radius");
}

TEST(FrankaPlanTest, BoxesAndCylindersBetweenJointGoalsForTheLearnedPlannerAndRrtConnect) {
  // A wall (a box) and a post (a cylinder) between two joint configurations, from the command line; the plans'
  // TCP clearances are checked by an independent script, RRT-Connect's whole-arm plans by MuJoCo's contacts.
  const fs::path dir = flowplan::testing::ScratchDir();
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  const std::string config = " --config " + Source("configs/franka_reach.yaml") + " generate.out=" + path("data.h5") +
                             " data.path=" + path("data.h5") + " run_dir=" + path("run") +
                             " generate.episodes=16 generate.franka.horizon=16 model.unet.down_dims=[8,16]"
                             " train.steps=2 train.batch_size=4 train.eval_every=0 sampler.steps=2 --log-level warn";
  ExpectOk(Flowplan("generate" + config));
  ExpectOk(Flowplan("train" + config));
  const std::string shapes = " --start -0.55,0.35,0,-2.2,0,2.55,0.23 --goal 0.55,0.35,0,-2.2,0,2.55,1.33"
                             " --box 0.5,0,0.15,0.5,0.04,0.3,0.9990482,0,0,0.0436194 --cylinder 0.25,0.1,0.2,0.04,0.4 "
                             "--max-speed-ratio 3 check.max_speed_ratio=3 -n 2 --no-plot scene.spheres=[]";  // not the preset's sphere
  ExpectOk(Flowplan("plan --ckpt " + path("run") + shapes + " --out " + path("learned")));
  const Outcome check = RunCommand(CheckPlan(path("learned")));
  EXPECT_EQ(check.exit_code, 0) << check.output;
  const Outcome rrt = Flowplan("plan --rrt-connect" + config + shapes + " --execute --out " + path("rrt"));
  ExpectOk(rrt);
  const std::string report = ReadText(path("rrt.json"));
  EXPECT_THAT(report, HasSubstr("\"obstacles\": [\"boxes[0]\", \"cylinders[0]\"]"));
  EXPECT_THAT(report, HasSubstr("\"success_rate\": 1, \"success_rate_executed\": 1"));
  EXPECT_THAT(report, HasSubstr("\"arm_clear_rate\": 1"));
  const Outcome check_rrt = RunCommand(CheckPlan(path("rrt")));
  EXPECT_EQ(check_rrt.exit_code, 0) << check_rrt.output;
}

TEST(FrankaPlanTest, AnOlderExportedPlannerPlansProblemsWithHeldFingersAndNoFloorThroughTheHybrid) {
  // The shipped planner's robot description predates finger joints; it is the built-in Franka, so it plans with the
  // built-in collision body, whose fingers a problem may hold open. The start reaches below z = 0, legal without a
  // floor and refused with one.
  const fs::path dir = flowplan::testing::ScratchDir();
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  auto problems = [&](const std::string& floor) {
    return "source: test\nproblems:\n"
           "  - {name: low, start_q: [0, 1.5, 0, -1.0, 0, 2.5, 0.785], goal_q: [0.6, 0.3, 0, -1.8, 0, 2.0, 0.785],"
           " floor_height: " + floor + ", held: [{joint: panda_finger_joint1, value: 0.04},"
           " {joint: panda_finger_joint2, value: 0.04}], scene: {}}\n";
  };
  std::ofstream(path("free.yaml")) << problems("-.inf");
  std::ofstream(path("floor.yaml")) << problems("0");
  const std::string common = " --planner " + Source("pretrained/franka_reach_planner.pt") +
                             " --hybrid -n 1 --no-plot --max-speed-ratio 3 check.max_speed_ratio=3 --log-level warn";
  ExpectOk(Flowplan("plan" + common + " --problems " + path("free.yaml") + " --out " + path("free")));
  EXPECT_THAT(ReadText(path("free.json")), HasSubstr("\"planned\": 1, \"refused\": 0"));
  EXPECT_THAT(ReadText(path("free.json")), HasSubstr("\"success_rate\": 1"));
  ExpectOk(Flowplan("plan" + common + " --problems " + path("floor.yaml") + " --out " + path("floor")));
  EXPECT_THAT(ReadText(path("floor.json")), HasSubstr("\"status\": \"refused\", \"reason\": \"start: sphere "));
  EXPECT_THAT(ReadText(path("floor.json")), HasSubstr("floor"));
}

TEST(FrankaPlanTest, AProblemFileIsPlannedByOneProcessWithRefusalsAsAStatusAndTheHybridNamesEachPlansRoute) {
  const fs::path dir = flowplan::testing::ScratchDir();
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  const std::string config = " --config " + Source("configs/franka_reach.yaml") + " generate.out=" + path("data.h5") +
                             " data.path=" + path("data.h5") + " run_dir=" + path("run") +
                             " generate.episodes=16 generate.franka.horizon=16 model.unet.down_dims=[8,16]"
                             " train.steps=2 train.batch_size=4 train.eval_every=0 sampler.steps=2 --log-level warn";
  ExpectOk(Flowplan("generate" + config));
  ExpectOk(Flowplan("train" + config));
  // Free space; a board between the ends; a start inside a sphere (refused, not an error).
  std::ofstream(path("problems.yaml"))
      << "source: test\nproblems:\n"
         "  - {name: free, start_q: [0, -0.785, 0, -2.356, 0, 1.571, 0.785], goal_q: [0.4, -0.5, 0, -2.0, 0, 1.6, 0.785],"
         " scene: {}}\n"
         "  - {name: board, start_q: [-0.55, 0.35, 0, -2.2, 0, 2.55, 0.23], goal_q: [0.55, 0.35, 0, -2.2, 0, 2.55, 1.33],"
         " scene: {boxes: [{centre: [0.5, 0, 0.15], size: [0.5, 0.04, 0.3]}]}}\n"
         "  - {name: inside, start_q: [0, -0.785, 0, -2.356, 0, 1.571, 0.785], goal_q: [0.4, -0.5, 0, -2.0, 0, 1.6, 0.785],"
         " scene: {spheres: [{centre: [0.307, 0, 0.487], radius: 0.05}]}}\n";
  const std::string fast = " check.max_speed_ratio=3 --max-speed-ratio 3 -n 2";  // 16 states
  ExpectOk(Flowplan("plan --rrt-connect" + config + " data.path=" + path("none.h5") + " --problems " +
                    path("problems.yaml") + " --execute --out " + path("rrt") + fast));
  const std::string rrt = ReadText(path("rrt.json"));
  EXPECT_THAT(rrt, HasSubstr("\"num_problems\": 3, \"planned\": 2, \"refused\": 1, \"num_samples\": 2"));
  EXPECT_THAT(rrt, HasSubstr("{\"name\": \"inside\", \"status\": \"refused\", \"reason\": \"start: sphere "));
  EXPECT_THAT(rrt, HasSubstr("\"success_rate\": 0.6666667, \"problems_solved\": 2, \"problems_solved_rate\": 0.6666667, \"success_rate_executed\": "
                             "0.6666667"));
  Outcome check = RunCommand(CheckPlan(path("rrt")));
  EXPECT_EQ(check.exit_code, 0) << check.output;
  // One of those plans executed and drawn: a video Pillow opens, frame by frame, and a picture.
  ExpectOk(Flowplan("render " + path("rrt.h5") + " --problem board --index 1 --out " + path("board") +
                    " render.width=160 render.height=120 --log-level warn"));
  const Outcome frames = RunCommand(std::string(FLOWPLAN_PYTHON) + " -c \"from PIL import Image; g = Image.open('" +
                                    path("board.gif") + "'); p = Image.open('" + path("board.png") +
                                    "'); print(g.n_frames, g.size, p.size)\"");
  EXPECT_EQ(frames.output, "31 (160, 120) (320, 240)\n");  // 16 states and 1 s held at 15 Hz; 2 x 2 stills
  ExpectCleanFailure(Flowplan("render " + path("rrt.h5") + " --log-level warn"),
                     "no plans; this is a --problems file: give --problem NAME, one of board, free");

  // The hybrid: a two-step network's proposals are not valid plans, so RRT-Connect makes them, and says so.
  ExpectOk(Flowplan("plan --ckpt " + path("run") + " --hybrid hybrid.proposals=3 hybrid.seeded_fallback=false --problems " +
                    path("problems.yaml") + " --limit 2 --out " + path("hybrid") + fast));
  const std::string hybrid = ReadText(path("hybrid.json"));
  EXPECT_THAT(hybrid, HasSubstr("\"planner\": \"hybrid("));
  EXPECT_THAT(hybrid, HasSubstr("\"num_problems\": 2, \"planned\": 2, \"refused\": 0"));
  EXPECT_THAT(hybrid, HasSubstr("\"success_rate\": 1, \"problems_solved\": 2, \"problems_solved_rate\": 1"));
  EXPECT_THAT(hybrid, HasSubstr("\"route\": \"rrt_connect\""));
  EXPECT_THAT(hybrid, HasSubstr("\"per\": \"plan, the wall time of the call that made it\""));
  check = RunCommand(CheckPlan(path("hybrid")));
  EXPECT_EQ(check.exit_code, 0) << check.output;
  // Seeded by the proposal of least guidance cost, and checked by the same independent script.
  ExpectOk(Flowplan("plan --ckpt " + path("run") + " --hybrid hybrid.proposals=3 hybrid.seeded_fallback=true --problems " +
                    path("problems.yaml") + " --limit 2 --out " + path("seeded") + fast));
  const std::string seeded = ReadText(path("seeded.json"));
  EXPECT_THAT(seeded, HasSubstr("\"success_rate\": 1, \"problems_solved\": 2, \"problems_solved_rate\": 1"));
  EXPECT_THAT(seeded, HasSubstr("\"route\": \"rrt_connect seeded by proposal "));
  check = RunCommand(CheckPlan(path("seeded")));
  EXPECT_EQ(check.exit_code, 0) << check.output;
  // The learned planner alone: its plans are checked and fail, with reasons.
  ExpectOk(Flowplan("plan --ckpt " + path("run") + " --problems " + path("problems.yaml") + " --out " + path("fp") + fast));
  EXPECT_THAT(ReadText(path("fp.json")), HasSubstr("\"success\": false, \"failure\": \""));
  check = RunCommand(CheckPlan(path("fp")));
  EXPECT_EQ(check.exit_code, 0) << check.output;

  ExpectCleanFailure(Flowplan("plan --ckpt " + path("run") + " --problems " + path("problems.yaml") +
                              " --start 0,0,0,-2,0,2,0"),
                     "--problems: every problem gives its own start, goal and scene");
  ExpectCleanFailure(Flowplan("plan --rrt-connect --hybrid" + config + " --problems " + path("problems.yaml")),
                     "--hybrid: a learned planner (--ckpt or --planner) proposes");
  std::ofstream(path("short.yaml")) << "problems:\n  - {name: short, start_q: [0, 0], goal_q: [0, 0], scene: {}}\n";
  ExpectCleanFailure(Flowplan("plan --ckpt " + path("run") + " --problems " + path("short.yaml") + " --out " +
                              path("short") + config.substr(config.find(" --log-level"))),
                     "problems[0] (short): start_q: expected 7 joint positions for this planner's robot, got 2");
  EXPECT_FALSE(fs::exists(path("short.json")));
  EXPECT_FALSE(fs::exists(path("short.h5")));
}

TEST(SceneImportTest, AMoveItFolderImportsAndRrtConnectPlansItsSceneInMujoco) {
  // MotionBenchMaker's layout: sceneNNNN.yaml and requestNNNN.yaml. The scene of
  // configs/scenes/franka_shelf.yaml (a table top, an upright board turned about
  // z, a bottle) written as a MoveIt planning scene, and a joint-space request
  // across the board.
  const fs::path dir = flowplan::testing::ScratchDir();
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  fs::create_directories(dir / "set");
  const std::string scene = R"(world:
  collision_objects:
    - header: {frame_id: panda_link0}
      id: table
      primitives: [{type: box, dimensions: [0.5, 1.0, 0.04]}]
      primitive_poses: [{position: [0.6, 0.0, 0.0], orientation: [0, 0, 0, 1]}]
    - header: {frame_id: panda_link0}
      id: board
      primitives: [{type: box, dimensions: [0.2, 0.03, 0.22]}]
      primitive_poses: [{position: {x: 0.447, y: 0.176, z: 0.42}, orientation: {x: 0, y: 0, z: 0.1864, w: 0.9825}}]
    - header: {frame_id: panda_link0}
      id: bottle
      primitives: [{type: cylinder, dimensions: [0.2, 0.04]}]
      primitive_poses: [{position: [0.55, -0.2, 0.12], orientation: [0, 0, 0, 1]}]
)";
  std::ofstream(path("set/scene0001.yaml")) << scene;
  std::ofstream(path("set/request0001.yaml"))
      << "start_state:\n  joint_state:\n    name: [panda_joint1, panda_joint2, panda_joint3, panda_joint4, "
         "panda_joint5, panda_joint6, panda_joint7, panda_finger_joint1]\n"
         "    position: [0, -0.3, 0, -2.2, 0, 2, 0.8, 0.04]\n"
         "goal_constraints:\n  - joint_constraints:\n"
         "      - {joint_name: panda_joint1, position: 0.75}\n      - {joint_name: panda_joint2, position: -0.3}\n"
         "      - {joint_name: panda_joint3, position: 0}\n      - {joint_name: panda_joint4, position: -2.2}\n"
         "      - {joint_name: panda_joint5, position: 0}\n      - {joint_name: panda_joint6, position: 2}\n"
         "      - {joint_name: panda_joint7, position: 0.8}\n";
  ExpectOk(Flowplan("scenes import --dir " + path("set") + " --out " + path("problems.yaml") + " --scenes-dir " +
                    path("scenes")));
  const std::string problems = ReadText(path("problems.yaml"));
  EXPECT_THAT(problems, HasSubstr("name: scene0001"));
  EXPECT_THAT(problems, HasSubstr("obstacle_names: [table, board, bottle]"));
  ASSERT_TRUE(fs::exists(path("scenes/scene0001.yaml")));
  // Run again, it replaces nothing without --force: not the problem file, and not a scene file either.
  ExpectCleanFailure(Flowplan("scenes import --dir " + path("set") + " --out " + path("problems.yaml")),
                     path("problems.yaml") + ": exists; give --force to replace it");
  ExpectCleanFailure(Flowplan("scenes import --dir " + path("set") + " --out " + path("other.yaml") +
                              " --scenes-dir " + path("scenes")),
                     path("scenes/scene0001.yaml") + ": exists; give --force to replace it");
  EXPECT_FALSE(fs::exists(path("other.yaml")));
  std::ofstream(path("problems.yaml")) << "stale\n";
  ExpectOk(Flowplan("scenes import --dir " + path("set") + " --out " + path("problems.yaml") + " --scenes-dir " +
                    path("scenes") + " --force"));
  EXPECT_EQ(ReadText(path("problems.yaml")), problems);

  const std::string config = " --config " + Source("configs/franka_reach.yaml") + " data.path=" + path("none.h5") +
                             " --log-level warn";
  const Outcome rrt = Flowplan("plan --rrt-connect" + config + " --start 0,-0.3,0,-2.2,0,2,0.8 --goal 0.75,-0.3,0,-2.2,0,2,0.8"
                               " --scene " + path("scenes/scene0001.yaml") + " -n 2 --execute --no-plot --max-speed-ratio 3"
                               " check.max_speed_ratio=3 scene.spheres=[] --out " + path("rrt"));
  ExpectOk(rrt);
  const std::string report = ReadText(path("rrt.json"));
  EXPECT_THAT(report, HasSubstr("\"obstacles\": [\"boxes[0]\", \"boxes[1]\", \"cylinders[0]\"]"));
  EXPECT_THAT(report, HasSubstr("\"success_rate\": 1, \"success_rate_executed\": 1"));
  EXPECT_THAT(report, HasSubstr("\"arm_clear_rate\": 1"));

  // A malformed file in the folder: one error naming it and the entry, nothing written.
  std::string bad = scene;
  bad.replace(bad.find("[0.2, 0.04]"), 11, "[0.2]");
  std::ofstream(path("set/scene0002.yaml")) << bad;
  fs::copy_file(path("set/request0001.yaml"), path("set/request0002.yaml"));
  ExpectCleanFailure(Flowplan("scenes import --dir " + path("set") + " --out " + path("again.yaml")),
                     path("set/scene0002.yaml") + ": world.collision_objects[2] (bottle).primitives[0].dimensions: "
                     "a cylinder needs 2 values (height, radius), got 1");
  EXPECT_FALSE(fs::exists(path("again.yaml")));

  // Two scenes of the same name (pairs from two folders) would share a scene file.
  fs::create_directories(dir / "other");
  fs::copy_file(path("set/scene0001.yaml"), path("other/scene0001.yaml"));
  ExpectCleanFailure(Flowplan("scenes import " + path("set/scene0001.yaml") + " " + path("set/request0001.yaml") + " " +
                              path("other/scene0001.yaml") + " " + path("set/request0001.yaml") + " --out " +
                              path("twice.yaml")),
                     "scenes import: two scenes are called scene0001");
  EXPECT_FALSE(fs::exists(path("twice.yaml")));

  // A procedural family from the same command that draws the blocked problems.
  ExpectOk(Flowplan("problems --family box problems.count=2 --out " + path("box.yaml")));
  const std::string box = ReadText(path("box.yaml"));
  EXPECT_THAT(box, HasSubstr("source: family box"));
  EXPECT_THAT(box, HasSubstr("name: box/1"));
  // An existing problem file is replaced only when asked to.
  ExpectCleanFailure(Flowplan("problems --family table problems.count=2 --out " + path("box.yaml")),
                     path("box.yaml") + ": exists; give --force to replace it");
  EXPECT_EQ(ReadText(path("box.yaml")), box);
  ExpectOk(Flowplan("problems --family table problems.count=2 --force --out " + path("box.yaml")));
  EXPECT_THAT(ReadText(path("box.yaml")), HasSubstr("source: family table"));
  ExpectCleanFailure(Flowplan("problems --family kitchen --out " + path("k.yaml")),
                     "scene family \"kitchen\" is not one of table, shelf, box, cage, under_table");
}

}  // namespace
}  // namespace flowplan
