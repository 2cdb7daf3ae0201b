// A user's own robot through the command line, with no C++ of theirs: `robot
// import` of a URDF the test writes (a 4-joint arm on a lift, a mesh link
// behind a package:// path), `scenes import --robot` of a MoveIt scene and
// request naming its joints, and `plan --rrt-connect --robot` of that problem
// and of a start and goal given on the command line; h5py reads the plan file
// and the recount script recounts it with its own kinematics.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/support/command.h"
#include "tests/support/lift_arm_urdf.h"
#include "tests/support/scratch_dir.h"

namespace flowplan {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::Flowplan;
using testing::RunCommand;

TEST(RobotCliTest, AUrdfIsImportedAndPlannedForFromTheCommandLine) {
  const fs::path dir = testing::ScratchDir();
  testing::WritePrismStl(dir / "share" / "lift_arm_description" / "meshes" / "hand.stl", 0.04, 0.1);
  testing::WriteText(dir / "lift_arm.urdf", testing::LiftArmUrdf("package://lift_arm_description/meshes/hand.stl"));
  const std::string robot = (dir / "robot").string();
  const std::string import = "robot import " + (dir / "lift_arm.urdf").string() + " --package-dir " +
                             (dir / "share").string() + " --tip tool --tcp-offset 0,0,0.02 --overshoot 0.02 " +
                             "--pair-samples 1000 --out " + robot;
  const testing::Outcome imported = Flowplan(import);
  ASSERT_EQ(imported.exit_code, 0) << imported.output;
  EXPECT_THAT(imported.output, HasSubstr("planned joints (4): lift, shoulder, elbow, wrist"));
  EXPECT_TRUE(fs::is_regular_file(dir / "robot" / "robot.yaml"));
  EXPECT_TRUE(fs::is_regular_file(dir / "robot" / "meshes" / "hand_0.stl"));
  // A second import into the same folder is refused with one line naming the file, unless forced.
  const testing::Outcome again = Flowplan(import);
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_THAT(again.output, HasSubstr("robot.yaml exists (--force replaces it)"));

  // A MoveIt scene (a box beside the arm, in the base frame) and a request (MotionBenchMaker's layout).
  testing::WriteText(dir / "moveit" / "scene0001.yaml", R"(name: one box
robot_state:
  joint_state: {name: [lift, shoulder, elbow, wrist], position: [0.0, -1.5, 0.5, 0.0]}
world:
  collision_objects:
    - id: crate
      header: {frame_id: base}
      primitives: [{type: box, dimensions: [0.2, 0.2, 0.3]}]
      primitive_poses: [{position: [0.45, 0.3, 0.5], orientation: [0, 0, 0, 1]}]
)");
  testing::WriteText(dir / "moveit" / "request0001.yaml", R"(start_state:
  joint_state: {name: [lift, shoulder, elbow, wrist], position: [0.0, -1.5, 0.5, 0.0]}
goal_constraints:
  - joint_constraints:
      - {joint_name: lift, position: 0.25}
      - {joint_name: shoulder, position: 1.5}
      - {joint_name: elbow, position: 0.5}
      - {joint_name: wrist, position: 1.0}
)");
  const std::string problems = (dir / "problems.yaml").string();
  const testing::Outcome scenes =
      Flowplan("scenes import --robot " + robot + " --dir " + (dir / "moveit").string() + " --out " + problems);
  ASSERT_EQ(scenes.exit_code, 0) << scenes.output;
  EXPECT_THAT(scenes.output, HasSubstr("1 problems (0 refused"));

  const std::string config = std::string(FLOWPLAN_SOURCE_DIR) + "/configs/franka_joint.yaml";
  const std::string prefix = (dir / "plans").string();
  const testing::Outcome planned = Flowplan("plan --rrt-connect --robot " + robot + " --config " + config +
                                            " --problems " + problems + " -n 2 --no-plot threads=1 --out " + prefix);
  ASSERT_EQ(planned.exit_code, 0) << planned.output;
  EXPECT_THAT(planned.output, HasSubstr("2/2"));
  // The plan file, read by h5py: 2 plans of the config's horizon, 4 positions and 4 velocities, all valid, the
  // lift within its limits and moved to the goal's 0.25 m.
  const std::string check = std::string(FLOWPLAN_PYTHON) + " -c \"import h5py, numpy as np; f = h5py.File('" + prefix +
                            ".h5', 'r'); p = f['problems/scene0001/plans'][()]; v = f['problems/scene0001/valid'][()]; print(p.shape, int(v.sum()), " +
                            "float(p[..., 0].min()), float(p[..., 0].max()), float(np.abs(p[:, -1, 0] - 0.25).max()))\"";
  const testing::Outcome read = RunCommand(check);
  ASSERT_EQ(read.exit_code, 0) << read.output;
  double lowest = -1, highest = -1, miss = -1;
  int T = 0, D = 0, valid = 0;
  ASSERT_EQ(std::sscanf(read.output.c_str(), "(2, %d, %d) %d %lf %lf %lf", &T, &D, &valid, &lowest, &highest, &miss), 6)
      << read.output;
  EXPECT_EQ(D, 8);
  EXPECT_EQ(valid, 2);
  EXPECT_GE(lowest, -1e-6);
  EXPECT_LE(highest, 0.3 + 1e-6);
  EXPECT_LT(miss, 1e-5);

  // The recount script, with kinematics of its own composed from the robot the plan file carries, agrees.
  const testing::Outcome recount = RunCommand(std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                                              "/scripts/recount_plans.py " + prefix);
  EXPECT_EQ(recount.exit_code, 0) << recount.output;
  EXPECT_THAT(recount.output, HasSubstr("TCP 2/2 (flowplan 2), arm 2/2 (flowplan 2)"));

  // A start given on the command line inside the crate is refused with its reason.
  const testing::Outcome refused =
      Flowplan("plan --rrt-connect --robot " + robot + " --config " + config +
               " --box 0.45,0.3,0.5,0.2,0.2,0.3 --start 0,0.59,0,0 --goal 0.25,1.5,0.5,1 -n 1 --no-plot --force --out " + prefix);
  EXPECT_THAT(refused.output, HasSubstr("0/1"));
  std::ifstream report(prefix + ".json");
  const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  EXPECT_THAT(text, HasSubstr(R"("failure": "refused", "reason": "start: sphere)"));
  // `robot: DIR` in a config does what --robot does; the Franka's data set refuses it with one line.
  std::ifstream base(config);
  testing::WriteText(dir / "with_robot.yaml", "robot: " + robot + "\n" +
                                                  std::string((std::istreambuf_iterator<char>(base)), std::istreambuf_iterator<char>()));
  const testing::Outcome from_config = Flowplan("plan --planner-kind rrt_connect --config " + (dir / "with_robot.yaml").string() +
                                                " --start 0,-1.5,0.5,0 --goal 0.25,1.5,0.5,1 -n 2 --no-plot --force --out " + prefix);
  EXPECT_EQ(from_config.exit_code, 0) << from_config.output;
  EXPECT_THAT(from_config.output, HasSubstr("success 2/2"));
  const testing::Outcome generate = Flowplan("generate --config " + (dir / "with_robot.yaml").string());
  EXPECT_EQ(generate.exit_code, 1);
  EXPECT_THAT(generate.output, HasSubstr("a robot folder's data set is generate.dataset: robot_joint"));
  // --robot with a learned planner is refused.
  const testing::Outcome learned = Flowplan("plan --planner " + std::string(FLOWPLAN_SOURCE_DIR) +
                                            "/pretrained/franka_reach_planner.pt --robot " + robot + " --out " + prefix);
  EXPECT_EQ(learned.exit_code, 1);
  EXPECT_THAT(learned.output, HasSubstr("--robot: only with --rrt-connect"));
}

TEST(RobotCliTest, AUrdfIsImportedAndItsDataGeneratedTrainedExportedAndPlannedWithTheHybrid) {
  // The rest of "Adding your robot" (docs/robots.md): robot_joint data of the imported arm, a planner trained on it
  // (three steps: what is checked is that every command takes the robot, not what it learns), exported, and planned
  // with around a box, learned alone and as the hybrid's proposer.
  const fs::path dir = testing::ScratchDir();
  testing::WritePrismStl(dir / "meshes" / "hand.stl", 0.04, 0.1);
  testing::WriteText(dir / "lift_arm.urdf", testing::LiftArmUrdf((dir / "meshes" / "hand.stl").string()));
  const std::string robot = (dir / "robot").string();
  const testing::Outcome imported = Flowplan("robot import " + (dir / "lift_arm.urdf").string() +
                                             " --tip tool --pair-samples 500 --out " + robot);
  ASSERT_EQ(imported.exit_code, 0) << imported.output;
  const std::string config = (dir / "lift.yaml").string();
  testing::WriteText(config, "robot: " + robot + R"(
seed: 3
threads: 1
run_dir: )" + (dir / "run").string() + R"(
generate:
  dataset: robot_joint
  episodes: 12
  out: )" + (dir / "data.h5").string() + R"(
  robot_joint:
    horizon: 32
    record_every: 4
    joint_motion: {min_duration: 1.0, min_hold: 0.2}
data:
  path: )" + (dir / "data.h5").string() + R"(
  val_fraction: 0.2
model:
  name: unet1d
  unet: {down_dims: [8, 16]}
train: {steps: 3, batch_size: 4, eval_every: 0, checkpoint_every: 3}
)");
  const testing::Outcome generated = Flowplan("generate --config " + config + " --log-level info");
  ASSERT_EQ(generated.exit_code, 0) << generated.output;
  // The data set, read by h5py: up to 12 episodes of 32 states of 4 positions and 4 velocities, the robot it carries, and
  // every episode inside the joint limits (the lift within [0, 0.3] m) and starting at rest at its commanded start.
  const std::string read_data =
      std::string(FLOWPLAN_PYTHON) + " -c \"import h5py, numpy as np; f = h5py.File('" + (dir / "data.h5").string() +
      "', 'r'); s = f['states'][()]; print(s.shape, 'lift_arm' in str(f.attrs['robot']), float(s[..., 0].min()), "
      "float(s[..., 0].max()), float(np.abs(s[:, 0, :4] - f['commanded_start'][()]).max()), float(np.abs(s[:, 0, 4:]).max()))\"";
  const testing::Outcome data = RunCommand(read_data);
  ASSERT_EQ(data.exit_code, 0) << data.output;
  int N = 0, T = 0, D = 0;
  char carries[8] = {};
  double lowest = -1, highest = -1, off_start = -1, start_speed = -1;
  ASSERT_EQ(std::sscanf(data.output.c_str(), "(%d, %d, %d) %5s %lf %lf %lf %lf", &N, &T, &D, carries, &lowest, &highest,
                        &off_start, &start_speed), 8)
      << data.output;
  EXPECT_GE(N, 9);  // of 12: an episode whose joint outruns its speed limit under the noise is dropped
  EXPECT_LE(N, 12);
  EXPECT_EQ(T, 32);
  EXPECT_EQ(D, 8);
  EXPECT_STREQ(carries, "True");
  EXPECT_GE(lowest, 0.0);
  EXPECT_LE(highest, 0.3);
  EXPECT_LT(off_start, 1e-6);  // states are stored as float32
  EXPECT_EQ(start_speed, 0.0);

  const testing::Outcome trained = Flowplan("train --config " + config + " --log-level warn");
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  const std::string planner = (dir / "lift.pt").string();
  const testing::Outcome exported = Flowplan("export --ckpt " + (dir / "run").string() + " --out " + planner + " --log-level warn");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const std::string problem = " --box 0.45,0.3,0.5,0.2,0.2,0.3 --start 0.1,-1.5,0.5,0 --goal 0.25,1.5,0.5,1 --no-plot";
  const testing::Outcome hybrid = Flowplan("plan --ckpt " + (dir / "run").string() + " --planner-kind hybrid" + problem +
                                           " -n 2 --out " + (dir / "hybrid").string());
  ASSERT_EQ(hybrid.exit_code, 0) << hybrid.output;
  EXPECT_THAT(hybrid.output, HasSubstr("success 2/2"));
  // The hybrid's plan drawn: the arm by its collision spheres, as planned (without --robot).
  const testing::Outcome drawn = Flowplan("render " + (dir / "hybrid.h5").string() + " --out " + (dir / "drawn").string() +
                                          " render.width=160 render.height=120");
  ASSERT_EQ(drawn.exit_code, 0) << drawn.output;
  EXPECT_THAT(drawn.output, HasSubstr("32 frames of 160 x 120, the plan as planned, the lift_arm drawn by its collision spheres"));
  EXPECT_GT(fs::file_size(dir / "drawn.gif"), 1000u);
  EXPECT_GT(fs::file_size(dir / "drawn.png"), 1000u);
  // Executed in MuJoCo, from the folder the planner's config names: in the report, and drawn with --robot.
  const testing::Outcome executed = Flowplan("plan --ckpt " + (dir / "run").string() + " --planner-kind hybrid" +
                                             problem + " -n 2 --execute --out " + (dir / "executed").string());
  ASSERT_EQ(executed.exit_code, 0) << executed.output;
  EXPECT_THAT(executed.output, HasSubstr("success 2/2 (passed the plan checker: check.*), executed"));
  const testing::Outcome replayed = Flowplan("render " + (dir / "hybrid.h5").string() + " --robot " + robot +
                                             " --out " + (dir / "replayed").string() + " render.width=160 render.height=120");
  ASSERT_EQ(replayed.exit_code, 0) << replayed.output;
  EXPECT_THAT(replayed.output, HasSubstr("of 160 x 120, the plan executed in MuJoCo: "));
  EXPECT_GT(fs::file_size(dir / "replayed.gif"), 1000u);
  const testing::Outcome learned = Flowplan("plan --planner " + planner + problem + " -n 2 --out " + (dir / "learned").string());
  ASSERT_EQ(learned.exit_code, 0) << learned.output;
  std::ifstream report(dir / "learned.json");
  const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  EXPECT_THAT(text, HasSubstr("\"env\": \"robot_joint\""));
  std::ifstream hybrid_report(dir / "hybrid.json");
  const std::string hybrid_text((std::istreambuf_iterator<char>(hybrid_report)), std::istreambuf_iterator<char>());
  EXPECT_THAT(hybrid_text, HasSubstr("\"rrt_connect\": {"));
  EXPECT_THAT(hybrid_text, HasSubstr("\"hybrid\": {"));
  // Planners by name: an unknown one is one line listing those there are; a contradicting flag is named.
  const testing::Outcome unknown = Flowplan("plan --ckpt " + (dir / "run").string() + " --planner-kind prm" + problem);
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_THAT(unknown.output, HasSubstr("--planner-kind: expected one of learned, rrt_connect, hybrid, got \"prm\""));
  const testing::Outcome contradicting =
      Flowplan("plan --ckpt " + (dir / "run").string() + " --planner-kind learned --hybrid" + problem);
  EXPECT_EQ(contradicting.exit_code, 1);
  EXPECT_THAT(contradicting.output, HasSubstr("--planner-kind learned: contradicts --hybrid"));
  const testing::Outcome network_free =
      Flowplan("plan --ckpt " + (dir / "run").string() + " --planner-kind rrt_connect" + problem);
  EXPECT_EQ(network_free.exit_code, 1);
  EXPECT_THAT(network_free.output, HasSubstr("plans without a trained network; leave out --ckpt and --planner"));
  // A robot folder without masses cannot be simulated: one line naming the file and what is missing.
  std::ifstream yaml(robot + "/robot.yaml");
  std::string kept, line;
  bool in_inertia = false;
  while (std::getline(yaml, line)) {
    if (line.rfind("inertia:", 0) == 0) in_inertia = true;
    else if (!line.empty() && line[0] != ' ' && line[0] != '-') in_inertia = false;
    if (!in_inertia) kept += line + "\n";
  }
  testing::WriteText(dir / "massless" / "robot.yaml", kept);
  const testing::Outcome massless = Flowplan("generate --config " + config + " robot=" + (dir / "massless").string() +
                                             " generate.out=" + (dir / "massless.h5").string());
  EXPECT_EQ(massless.exit_code, 1);
  EXPECT_THAT(massless.output, HasSubstr("massless/robot.yaml: inertia: the links moved by joint \"lift\""));
  EXPECT_FALSE(fs::exists(dir / "massless.h5"));
}

// `problems --family` for a robot folder: the UR5's cage problems (the hardest family), planned by RRT-Connect and
// recounted by the script with kinematics of its own composed from the robot the plan file carries.
TEST(RobotCliTest, ASceneFamilyIsDrawnForARobotFolderAndPlanned) {
  const fs::path dir = testing::ScratchDir();
  const std::string robot = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/ur5";
  const std::string problems = (dir / "cage.yaml").string();
  const testing::Outcome drawn =
      Flowplan("problems --robot " + robot + " --family cage problems.count=3 --out " + problems);
  ASSERT_EQ(drawn.exit_code, 0) << drawn.output;
  EXPECT_THAT(drawn.output, HasSubstr("the families' lengths scaled by 0.996, the arm's reach over the Franka's"));
  EXPECT_THAT(drawn.output, HasSubstr("3 cage problems"));
  const std::string prefix = (dir / "plans").string();
  const testing::Outcome planned =
      Flowplan("plan --rrt-connect --robot " + robot + " --config " + FLOWPLAN_SOURCE_DIR +
               "/configs/robot_joint.yaml --problems " + problems +
               " -n 1 --no-plot threads=1 rrt_connect.max_iterations=1000000 --out " + prefix);
  ASSERT_EQ(planned.exit_code, 0) << planned.output;
  EXPECT_THAT(planned.output, HasSubstr("3/3 problems solved"));
  const testing::Outcome recount = RunCommand(std::string(FLOWPLAN_PYTHON) + " " + FLOWPLAN_SOURCE_DIR +
                                              "/scripts/recount_plans.py " + prefix);
  EXPECT_EQ(recount.exit_code, 0) << recount.output;
  EXPECT_THAT(recount.output, HasSubstr("TCP 3/3 (flowplan 3), arm 3/3 (flowplan 3)"));
  // A folder without a home posture cannot seed inverse kinematics: one line naming the file.
  fs::create_directories(dir / "no_home");
  std::ifstream in(robot + "/robot.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t home = text.find("\n  home: ");
  ASSERT_NE(home, std::string::npos);
  text.erase(home + 1, text.find('\n', home + 1) - home);
  testing::WriteText(dir / "no_home" / "robot.yaml", text);
  if (fs::exists(robot + "/meshes")) fs::copy(robot + "/meshes", dir / "no_home" / "meshes");
  const testing::Outcome refused = Flowplan("problems --robot " + (dir / "no_home").string() +
                                            " --family table --out " + (dir / "x.yaml").string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_THAT(refused.output, HasSubstr("no_home/robot.yaml: the scene families need a home posture (home:) of 6 "
                                        "values"));
  EXPECT_FALSE(fs::exists(dir / "x.yaml"));
}

// Every consumer of a robot, on tiny budgets, for each shipped folder: data generation, training, export, a scene
// family's problem planned by the exported planner, RRT-Connect and the hybrid, executed in MuJoCo and drawn.
class ShippedRobotCliTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedRobotCliTest, EveryConsumerRunsOnATinyBudget) {
  const fs::path dir = testing::ScratchDir();
  const std::string robot = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/" + GetParam();
  const std::string config = (dir / "tiny.yaml").string();
  testing::WriteText(config, "robot: " + robot + R"(
seed: 3
threads: 1
run_dir: )" + (dir / "run").string() + R"(
generate:
  dataset: robot_joint
  episodes: 12
  out: )" + (dir / "data.h5").string() + R"(
  robot_joint:
    horizon: 32
    record_every: 4
    joint_motion: {min_duration: 1.0, min_hold: 0.2}
data:
  path: )" + (dir / "data.h5").string() + R"(
  val_fraction: 0.2
model:
  name: unet1d
  unet: {down_dims: [8, 16]}
train: {steps: 3, batch_size: 4, eval_every: 0, checkpoint_every: 3}
)");
  const testing::Outcome generated = Flowplan("generate --config " + config + " --log-level warn");
  ASSERT_EQ(generated.exit_code, 0) << generated.output;
  const testing::Outcome trained = Flowplan("train --config " + config + " --log-level warn");
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  const std::string planner = (dir / "planner.pt").string();
  const testing::Outcome exported =
      Flowplan("export --ckpt " + (dir / "run").string() + " --out " + planner + " --log-level warn");
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const std::string problems = (dir / "table.yaml").string();
  const testing::Outcome drawn = Flowplan("problems --robot " + robot + " --family table problems.count=1 --out " + problems);
  ASSERT_EQ(drawn.exit_code, 0) << drawn.output;
  // The exported planner (3 training steps: its plans may fail, but it plans), RRT-Connect and the hybrid, with the
  // plans executed in MuJoCo.
  const testing::Outcome learned = Flowplan("plan --planner " + planner + " --problems " + problems +
                                            " -n 1 --no-plot --out " + (dir / "learned").string());
  ASSERT_EQ(learned.exit_code, 0) << learned.output;
  EXPECT_THAT(learned.output, HasSubstr("1 problems (0 refused), 1 plans each"));
  for (const std::string kind : {"rrt_connect", "hybrid"}) {
    const std::string ckpt = kind == "hybrid" ? " --ckpt " + (dir / "run").string() : " --config " + config;
    const testing::Outcome planned = Flowplan("plan --planner-kind " + kind + ckpt + " --problems " + problems +
                                              " -n 1 --no-plot --execute --out " + (dir / kind).string());
    ASSERT_EQ(planned.exit_code, 0) << planned.output;
    EXPECT_THAT(planned.output, HasSubstr("success 1/1 plans, executed 1/1")) << kind;
  }
  const testing::Outcome rendered = Flowplan("render " + (dir / "hybrid.h5").string() + " --problem table_0 --robot " + robot +
                                             " --out " + (dir / "video").string() + " render.width=160 render.height=120");
  ASSERT_EQ(rendered.exit_code, 0) << rendered.output;
  EXPECT_THAT(rendered.output, HasSubstr("the plan executed in MuJoCo: "));
  EXPECT_GT(fs::file_size(dir / "video.gif"), 1000u);
}

INSTANTIATE_TEST_SUITE_P(Robots, ShippedRobotCliTest, ::testing::Values("ur5", "fetch_arm"),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

}  // namespace
}  // namespace flowplan
