// `flowplan robot import` on a URDF the test writes: a 4-joint arm on a
// vertical lift (one prismatic joint), a mesh link (binary STL behind a
// package:// path), primitives, a fixed tool link. The imported kinematics
// against MuJoCo's own reading of the same URDF, the written-out Jacobian
// products against autograd, the sphere cover against the geometry sampled in
// closed form, RRT-Connect's plans for it, and the errors a user meets.

#include "robotfiles/urdf_import.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "classical/rrt_connect.h"
#include "collision/checker.h"
#include "datasets/robot_joint_task.h"
#include "robotfiles/robot_model.h"
#include "core/error.h"
#include "jit/library.h"
#include "kinematics/robot.h"
#include "sim/franka_model.h"
#include "sim/mujoco_util.h"
#include "spheres/cover.h"
#include "spheres/mesh.h"
#include "tests/support/lift_arm_urdf.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::robotfiles {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

using testing::LiftArmUrdf;
using testing::WritePrismStl;
using testing::WriteText;

class RobotImportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = new fs::path(fs::temp_directory_path() / ("flowplan_robot_import_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    WritePrismStl(*root_ / "packages" / "lift_arm_description" / "meshes" / "hand.stl", 0.04, 0.1);
    WriteText(*root_ / "urdf" / "lift_arm.urdf", LiftArmUrdf("package://lift_arm_description/meshes/hand.stl"));
    ImportOptions options;
    options.package_dir = (*root_ / "packages").string();
    options.tip = "tool";
    options.overshoot = 0.015;
    options.pair_samples = 2000;
    ImportRobot((*root_ / "urdf" / "lift_arm.urdf").string(), options, (*root_ / "robot").string());
    file_ = new RobotFile(LoadRobotFile((*root_ / "robot").string()));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*root_);
    delete file_;
    delete root_;
  }
  static fs::path* root_;
  static RobotFile* file_;
};
fs::path* RobotImportTest::root_ = nullptr;
RobotFile* RobotImportTest::file_ = nullptr;

TEST_F(RobotImportTest, WritesTheJointsLimitsTcpAndMeshesOfTheUrdf) {
  const kinematics::RobotDescription d = file_->Description("robot.yaml");
  ASSERT_EQ(d.num_joints, 4);
  EXPECT_EQ(d.JointName(0), "lift");
  EXPECT_EQ(d.JointName(3), "wrist");
  EXPECT_EQ(d.joint_lower, (std::vector<double>{0.0, -2.8, -2.0, -3.0}));
  EXPECT_EQ(d.joint_upper, (std::vector<double>{0.3, 2.8, 2.0, 3.0}));
  EXPECT_EQ(d.velocity_limit, (std::vector<double>{0.2, 1.5, 1.5, 2.0}));
  EXPECT_EQ(file_->effort_limit, (std::vector<double>{500, 80, 60, 20}));
  EXPECT_EQ(d.links[static_cast<size_t>(d.FindLink("column"))].type, kinematics::JointType::kPrismatic);
  EXPECT_EQ(d.links[static_cast<size_t>(d.tcp_link)].name, "tool");
  EXPECT_TRUE(fs::is_regular_file(*root_ / "robot" / "meshes" / "hand_0.stl"));
  EXPECT_FALSE(fs::exists(*root_ / "robot" / "robot.yaml.partial"));
  // The base stands on the floor; the moving links do not.
  EXPECT_THAT(d.floor_exempt, ::testing::Contains("base"));
  EXPECT_THAT(d.floor_exempt, ::testing::Not(::testing::Contains("hand")));
  // Neighbours are never checked against each other; the base and the forearm are.
  auto ignored = [&](const std::string& a, const std::string& b) {
    for (const auto& pair : d.self_collision_ignore) {
      if ((pair[0] == a && pair[1] == b) || (pair[0] == b && pair[1] == a)) return true;
    }
    return false;
  };
  EXPECT_TRUE(ignored("base", "column"));
  EXPECT_TRUE(ignored("fore", "hand"));
  EXPECT_FALSE(ignored("base", "fore"));
}

TEST_F(RobotImportTest, KinematicsMatchMujocosReadingOfTheSameUrdf) {
  // MuJoCo reads the URDF itself (links joined by fixed joints kept apart, the mesh by its absolute path).
  const fs::path for_mujoco = *root_ / "mujoco" / "lift_arm.urdf";
  fs::create_directories(for_mujoco.parent_path());
  fs::copy_file(*root_ / "packages" / "lift_arm_description" / "meshes" / "hand.stl", for_mujoco.parent_path() / "hand.stl",
                fs::copy_options::overwrite_existing);
  WriteText(for_mujoco, LiftArmUrdf((for_mujoco.parent_path() / "hand.stl").string(),
                                    R"(<mujoco><compiler fusestatic="false" strippath="false" discardvisual="true"/></mujoco>)"));
  const sim::MjModelPtr model = sim::LoadModelFromFile(for_mujoco.string());
  const mjModel& m = *model;
  sim::MjDataPtr data = sim::MakeData(m);
  const kinematics::RobotDescription d = file_->Description("robot.yaml");
  const kinematics::Robot robot(d);
  torch::manual_seed(3);
  const int64_t B = 16;
  const torch::Tensor lower = torch::tensor(d.joint_lower, torch::kFloat64), upper = torch::tensor(d.joint_upper, torch::kFloat64);
  const torch::Tensor q = lower + (upper - lower) * torch::rand({B, 4}, torch::kFloat64);
  const auto frames = jit::Call(robot.module(), "link_frames", {q}).toTensorVector();
  const torch::Tensor tcp = robot.Tcp(q), centres = robot.SphereCentres(q);
  for (int64_t b = 0; b < B; ++b) {
    for (int j = 0; j < 4; ++j) {
      const int joint = mj_name2id(&m, mjOBJ_JOINT, d.JointName(j).c_str());
      ASSERT_GE(joint, 0) << d.JointName(j);
      data->qpos[m.jnt_qposadr[joint]] = q[b][j].item<double>();
    }
    mj_kinematics(&m, data.get());
    for (size_t l = 0; l < d.links.size(); ++l) {
      const int body = mj_name2id(&m, mjOBJ_BODY, d.links[l].name.c_str());
      ASSERT_GE(body, 0) << d.links[l].name;
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(frames[l][b][i][3].item<double>(), data->xpos[3 * body + i], 1e-9) << d.links[l].name;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(frames[l][b][i][k].item<double>(), data->xmat[9 * body + 3 * i + k], 1e-9);
      }
    }
    const int tool = mj_name2id(&m, mjOBJ_BODY, "tool");
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(tcp[b][i].item<double>(), data->xpos[3 * tool + i], 1e-9);
    for (size_t s = 0; s < d.spheres.size(); s += 7) {
      const int body = mj_name2id(&m, mjOBJ_BODY, d.links[static_cast<size_t>(d.spheres[s].link)].name.c_str());
      for (int i = 0; i < 3; ++i) {
        double expected = data->xpos[3 * body + i];
        for (int k = 0; k < 3; ++k) expected += data->xmat[9 * body + 3 * i + k] * d.spheres[s].centre[k];
        EXPECT_NEAR(centres[b][static_cast<int64_t>(s)][i].item<double>(), expected, 1e-9);
      }
    }
  }
}

TEST_F(RobotImportTest, WrittenOutJacobianProductsOfTheSlideMatchAutograd) {
  const kinematics::Robot robot(file_->Description("robot.yaml"));
  torch::manual_seed(5);
  const torch::Tensor q0 = torch::rand({6, 4}, torch::kFloat64) * torch::tensor({0.3, 2.0, 2.0, 2.0}, torch::kFloat64);
  const torch::Tensor g = torch::randn({6, 3}, torch::kFloat64);
  const torch::Tensor q = q0.clone().requires_grad_(true);
  const torch::Tensor expected = torch::autograd::grad({(robot.Tcp(q) * g).sum()}, {q})[0];
  const torch::Tensor written = jit::Call(robot.module(), "tcp_vjp", {q0, g}).toTensor();
  EXPECT_LT((written - expected).abs().max().item<double>(), 1e-12);
  EXPECT_GT(expected.select(1, 0).abs().max().item<double>(), 0.1);  // the lift moves the TCP
  // Autograd itself against central differences on the lift.
  const double h = 1e-6;
  torch::Tensor plus = q0.clone(), minus = q0.clone();
  plus.select(1, 0) += h;
  minus.select(1, 0) -= h;
  const torch::Tensor numeric = ((robot.Tcp(plus) - robot.Tcp(minus)) * g).sum(1) / (2 * h);
  EXPECT_LT((numeric - expected.select(1, 0)).abs().max().item<double>(), 1e-7);
  const int64_t S = robot.num_spheres();
  const torch::Tensor rows = torch::randperm(6 * S, torch::kInt64).slice(0, 0, S);
  const torch::Tensor gs = torch::randn({S, 3}, torch::kFloat64);
  const torch::Tensor dense = torch::zeros({6 * S, 3}, torch::kFloat64).index_copy(0, rows, gs).view({6, S, 3});
  const torch::Tensor sphere_expected = torch::autograd::grad({(robot.SphereCentres(q) * dense).sum()}, {q})[0];
  const auto poses = jit::Call(robot.module(), "spheres", {q0}).toTuple()->elements();
  const torch::Tensor sphere_written =
      jit::Call(robot.module(), "spheres_vjp", {poses[0], poses[1], poses[2], rows, gs}).toTensor();
  EXPECT_LT((sphere_written - sphere_expected).abs().max().item<double>(), 1e-12);
}

TEST_F(RobotImportTest, SpheresCoverTheCollisionGeometrySampledInClosedForm) {
  const kinematics::RobotDescription d = file_->Description("robot.yaml");
  // Points on the surfaces, in their link frames: the base's box (centre z 0.05, sides 0.2 0.2 0.1), the column's
  // cylinder (r 0.05, z 0..0.4), the upper arm's (r 0.04 along x, 0..0.3), the hand's prism's corners (r 0.04, z
  // 0..0.1).
  std::vector<std::pair<std::string, std::array<double, 3>>> points;
  for (int i = 0; i <= 20; ++i) {
    for (int k = 0; k <= 20; ++k) {
      const double u = -0.1 + 0.2 * i / 20, v = -0.1 + 0.2 * k / 20, w = 0.1 * k / 20;
      points.push_back({"base", {u, v, 0.1}});
      points.push_back({"base", {u, v, 0.0}});
      points.push_back({"base", {u, 0.1, w}});
      points.push_back({"base", {-0.1, u, w}});
    }
  }
  for (int i = 0; i < 72; ++i) {
    const double a = 2 * M_PI * i / 72;
    for (int k = 0; k <= 40; ++k) {
      points.push_back({"column", {0.05 * std::cos(a), 0.05 * std::sin(a), 0.4 * k / 40}});
      points.push_back({"upper", {0.3 * k / 40, 0.04 * std::cos(a), 0.04 * std::sin(a)}});
    }
    points.push_back({"column", {0.05 * std::cos(a) * (i % 5) / 4, 0.05 * std::sin(a) * (i % 5) / 4, 0.4}});
  }
  for (int k = 0; k < 8; ++k) {
    const double a = 2 * M_PI * k / 8;
    points.push_back({"hand", {0.04 * std::cos(a), 0.04 * std::sin(a), 0.0}});
    points.push_back({"hand", {0.04 * std::cos(a), 0.04 * std::sin(a), 0.1}});
  }
  for (const auto& [link, p] : points) {
    const int l = d.FindLink(link);
    double nearest = INFINITY;
    for (const auto& s : d.spheres) {
      if (s.link != l) continue;
      const double gap = std::sqrt(std::pow(p[0] - s.centre[0], 2) + std::pow(p[1] - s.centre[1], 2) +
                                   std::pow(p[2] - s.centre[2], 2)) - s.radius;
      nearest = std::min(nearest, gap);
    }
    EXPECT_LE(nearest, 1e-9) << link << " point " << p[0] << " " << p[1] << " " << p[2];
  }
  // Tightness: no sphere centre lies farther outside its geometry than the spheres may reach.
  for (const LinkCover& cover : file_->cover) {
    EXPECT_EQ(cover.largest_uncovered, 0.0) << cover.link;
    EXPECT_LT(cover.largest_outside, 0.02) << cover.link;  // the overshoot asked for, 0.015, and a little
  }
}

TEST_F(RobotImportTest, RrtConnectPlansForTheImportedArmPassThePlanChecker) {
  kinematics::TrajectoryInfo info;
  info.env = "robot folder";
  info.dt = 0.1;
  info.horizon = 32;
  info.robot = file_->Description("robot.yaml");
  for (int j = 1; j <= 4; ++j) info.state_labels.push_back("q" + std::to_string(j));
  for (int j = 1; j <= 4; ++j) info.state_labels.push_back("dq" + std::to_string(j));
  const classical::RrtConnectPlanner planner(info, classical::RrtConnectConfig{});
  planning::PlanRequest request;
  // From reaching out on one side, low, to the other side, high, around a ball in the way.
  request.start = torch::tensor({{0.0, -1.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0}, {0.05, -1.2, 0.3, 1.0, 0.0, 0.0, 0.0, 0.0}}, torch::kFloat32);
  request.goal = torch::tensor({{0.25, 1.5, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0}, {0.28, 1.3, 0.7, -1.0, 0.0, 0.0, 0.0, 0.0}}, torch::kFloat32);
  request.scene = geometry::SphereRows(torch::tensor({{0.35, 0.35, 0.5, 0.12}}, torch::kFloat64));
  request.seed = 1;
  const planning::PlanResult result = planner.Plan(request);
  ASSERT_EQ(result.plans.sizes(), (std::vector<int64_t>{2, 32, 8}));
  for (int64_t b = 0; b < 2; ++b) {
    ASSERT_TRUE(result.found[b].item<bool>()) << result.failure[static_cast<size_t>(b)];
    const auto verdict = planner.checker().Check(result.plans[b].unsqueeze(0), request.start[b], request.goal[b],
                                                 request.scene, torch::Tensor(), {}, false)[0];
    EXPECT_TRUE(verdict.valid()) << verdict.reason;
    // The lift moved: the plans use the prismatic joint, within its limits.
    const torch::Tensor lift = result.plans[b].select(1, 0);
    EXPECT_GE(lift.min().item<float>(), -1e-6);
    EXPECT_LE(lift.max().item<float>(), 0.3 + 1e-6);
    EXPECT_GT((lift[-1] - lift[0]).item<float>(), 0.15);
  }
  // A start inside the ball is refused with the reason, not "no plan found".
  request.start = torch::tensor({{0.0, 0.78, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}}, torch::kFloat32);
  request.goal = request.goal.slice(0, 0, 1);
  const planning::PlanResult refused = planner.Plan(request);
  EXPECT_TRUE(refused.refused[0]) << refused.failure[0];
  EXPECT_THAT(refused.failure[0], HasSubstr("start"));
}

TEST(RotateInertiaTest, TurnsPrincipalMomentsIntoTheLinkFrameInClosedForm) {
  // Principal moments (1, 2, 3) along axes turned by theta about z: the link-frame tensor is R diag R^T, whose x-y
  // block is [[c^2 + 2 s^2, -c s], [-c s, s^2 + 2 c^2]] (a 90 deg turn swaps the x and y moments).
  const double theta = M_PI / 4, c = std::cos(theta), s = std::sin(theta);
  const std::array<double, 6> turned = RotateInertia({1, 2, 3, 0, 0, 0}, {std::cos(theta / 2), 0, 0, std::sin(theta / 2)});
  const std::array<double, 6> expected = {c * c + 2 * s * s, s * s + 2 * c * c, 3, -c * s, 0, 0};
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(turned[k], expected[k], 1e-12) << k;
  const std::array<double, 6> quarter = RotateInertia({1, 2, 3, 0, 0, 0}, {std::cos(M_PI / 4), 0, 0, std::sin(M_PI / 4)});
  EXPECT_NEAR(quarter[0], 2, 1e-12);
  EXPECT_NEAR(quarter[1], 1, 1e-12);
  // An off-diagonal tensor turned there and back is itself.
  const std::array<double, 6> full = {0.3, 0.2, 0.25, 0.01, -0.02, 0.015};
  const std::array<double, 4> q = {0.9, 0.1, -0.3, 0.2}, inverse = {0.9, -0.1, 0.3, -0.2};
  const std::array<double, 6> back = RotateInertia(RotateInertia(full, q), inverse);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(back[k], full[k], 1e-12) << k;
}

TEST_F(RobotImportTest, TheSimulationModelMovesAsTheKinematicsAndWeighsWhatTheUrdfSays) {
  DriveSettings drives;
  drives.armature = 0.1;
  drives.damping = 0.0;
  const SimulationModel simulation = LoadSimulationModel(*file_, drives, "robot.yaml");
  const mjModel& m = *simulation.model;
  ASSERT_EQ(m.nv, 4);
  sim::MjDataPtr data = sim::MakeData(m);
  const kinematics::RobotDescription d = file_->Description("robot.yaml");
  const kinematics::Robot robot(d);
  torch::manual_seed(5);
  const torch::Tensor lower = torch::tensor(d.joint_lower, torch::kFloat64), upper = torch::tensor(d.joint_upper, torch::kFloat64);
  const torch::Tensor q = lower + (upper - lower) * torch::rand({8, 4}, torch::kFloat64);
  const torch::Tensor tcp = robot.Tcp(q);
  for (int64_t b = 0; b < 8; ++b) {
    for (int j = 0; j < 4; ++j) data->qpos[simulation.qpos[static_cast<size_t>(j)]] = q[b][j].item<double>();
    mj_kinematics(&m, data.get());
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(data->site_xpos[3 * simulation.tcp_site + i], tcp[b][i].item<double>(), 1e-9);
  }
  // At rest, the vertical lift holds up the five links above it (1 kg each in the URDF): its gravity force is
  // 5 kg x 9.81 m/s^2 and its diagonal of the mass matrix 5 kg plus the armature.
  mj_resetData(&m, data.get());
  data->qpos[simulation.qpos[1]] = 0.7;
  data->qpos[simulation.qpos[2]] = -0.4;
  mj_forward(&m, data.get());
  const int lift = simulation.dof[0];
  EXPECT_NEAR(data->qfrc_bias[lift], 5 * 9.81, 1e-9);
  std::vector<double> mass(16);
  mj_fullM(&m, mass.data(), data->qM);
  EXPECT_NEAR(mass[static_cast<size_t>(5 * lift)], 5.1, 1e-9);
  // The motors are limited to the URDF's efforts, in the planned joints' order.
  for (int j = 0; j < 4; ++j) EXPECT_EQ(m.actuator_ctrlrange[2 * j + 1], file_->effort_limit[static_cast<size_t>(j)]);
}

TEST_F(RobotImportTest, ExecutionCollidesWithTheCollisionGeometryTheSpheresCover) {
  // `plan --execute`'s model: the hand's mesh (MuJoCo collides with its hull; the prism is convex) and the
  // primitives as geoms. The smallest distance MuJoCo reports from them to an obstacle lies between the spheres'
  // clearance (they cover the geometry) and that plus the farthest the spheres reach outside it.
  const std::string dir = (*root_ / "robot").string();
  const kinematics::RobotDescription d = file_->Description("robot.yaml");
  const collision::BodyModel body(d);
  const std::vector<double> q = {0.15, 0.7, -0.4, 0.5};
  double tcp[3];
  body.Tcp(q.data(), tcp);
  geometry::Scene scene;
  double clearance = 0.0;
  for (const double dx : {0.12, -0.12, 0.0}) {  // the first spot a few centimetres from the arm
    scene.spheres = {{{tcp[0] + dx, tcp[1], tcp[2] + 0.05}, 0.03}};
    const collision::Checker checker(std::make_shared<collision::BodyModel>(body),
                                     std::make_shared<collision::World>(scene, 3), {});
    clearance = checker.Clearance(q.data());
    if (clearance > 0.005 && clearance < 0.1) break;
  }
  ASSERT_GT(clearance, 0.005);
  ASSERT_LT(clearance, 0.1);
  double outside = 0.0;
  for (const LinkCover& cover : file_->cover) outside = std::max(outside, cover.largest_outside);

  sim::ExecutionConfig config;
  const ExecutionModel model = LoadExecutionModel(*file_, dir, scene, DriveSettings{}, config, "robot.yaml");
  int meshes = 0;
  for (int g = 0; g < model.model->ngeom; ++g) meshes += model.model->geom_type[g] == mjGEOM_MESH;
  EXPECT_EQ(meshes, 1);
  sim::ArmExecutor executor(*model.model, model.drives, 1, config);
  const int T = 8;
  std::vector<double> plan(static_cast<size_t>(T * 8), 0.0);  // held at q, at rest
  for (int t = 0; t < T; ++t) std::copy(q.begin(), q.end(), plan.begin() + t * 8);
  const sim::ExecutionResult r = executor.Execute(plan, T, 0.1, Eigen::Vector3d(tcp[0], tcp[1], tcp[2]));
  EXPECT_LT(r.max_tracking_error, 1e-6);
  EXPECT_TRUE(r.contacts.empty());
  EXPECT_GE(r.min_distance[0], clearance - 1e-6);
  EXPECT_LE(r.min_distance[0], clearance + outside + 1e-6);

  // A collision mesh that is gone is one error naming it.
  RobotFile broken = *file_;
  for (CollisionGeometry& g : broken.geometry) {
    if (g.shape == "mesh") g.mesh = "meshes/gone.stl";
  }
  EXPECT_THAT([&] { LoadExecutionModel(broken, dir, scene, DriveSettings{}, config, "robot.yaml"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("meshes/gone.stl")));
}

TEST_F(RobotImportTest, RobotJointEpisodesTrackTheirReferenceInsideTheLimitsAndClearOfTheArm) {
  datasets::RobotJointTaskConfig config;
  config.rollout.horizon = 32;  // 2.07 s at 15 Hz
  const datasets::RobotJointTask task((*root_ / "robot").string(), config);
  const datasets::EpisodeLayout layout = task.Layout();
  ASSERT_EQ(layout.info.state_dim(), 8);
  ASSERT_EQ(layout.point_dim, 4);
  const kinematics::RobotDescription d = file_->Description("robot.yaml");
  collision::Floor floor;
  floor.present = true;
  const collision::Checker checker(std::make_shared<const collision::BodyModel>(d),
                                   std::make_shared<const collision::World>(geometry::Scene{}, 3, floor), {});
  const auto worker = task.MakeWorker(), twin = task.MakeWorker();
  int kept = 0;
  for (uint64_t seed = 0; seed < 6; ++seed) {
    const datasets::EpisodeRecord record = worker->Run(0, seed);
    const datasets::EpisodeRecord again = twin->Run(0, seed);
    EXPECT_EQ(again.states, record.states) << "same seed, same episode";
    EXPECT_EQ(again.extras, record.extras);
    if (record.rejected) continue;
    ++kept;
    ASSERT_EQ(record.states.size(), 32u * 8);
    for (int j = 0; j < 4; ++j) {
      EXPECT_EQ(record.states[static_cast<size_t>(j)], record.commanded_start[static_cast<size_t>(j)]);
      // The episode holds the goal for at least min_hold: the last state is there, up to the noise.
      EXPECT_NEAR(record.states[31 * 8 + static_cast<size_t>(j)], record.commanded_goal[static_cast<size_t>(j)], 0.02);
    }
    for (int t = 0; t < 32; ++t) {
      const double* state = &record.states[static_cast<size_t>(t) * 8];
      EXPECT_TRUE(checker.Valid(state)) << "t = " << t;
      for (int j = 0; j < 4; ++j) {
        EXPECT_GE(state[j], d.joint_lower[static_cast<size_t>(j)]);
        EXPECT_LE(state[j], d.joint_upper[static_cast<size_t>(j)]);
        EXPECT_LE(std::abs(state[4 + j]), d.velocity_limit[static_cast<size_t>(j)]);
        EXPECT_LE(std::abs(record.extras.at("torques")[static_cast<size_t>(t) * 4 + j]), file_->effort_limit[static_cast<size_t>(j)]);
      }
    }
  }
  EXPECT_GE(kept, 4);
  // Planned joints numbered against the tree's order (--joints reversed): joint j is not MuJoCo's joint j, and each
  // motor must still drive its own joint, or the episodes miss their goals.
  ImportOptions reversed;
  reversed.package_dir = (*root_ / "packages").string();
  reversed.tip = "tool";
  reversed.joints = {"wrist", "elbow", "shoulder", "lift"};
  reversed.pair_samples = 500;
  ImportRobot((*root_ / "urdf" / "lift_arm.urdf").string(), reversed, (*root_ / "reversed").string());
  const RobotFile reversed_file = LoadRobotFile((*root_ / "reversed").string());
  const SimulationModel simulation = LoadSimulationModel(reversed_file, DriveSettings{}, "reversed");
  EXPECT_EQ(simulation.dof, (std::vector<int>{3, 2, 1, 0}));
  const datasets::RobotJointTask reversed_task((*root_ / "reversed").string(), config);
  const auto reversed_worker = reversed_task.MakeWorker();
  int reached = 0;
  for (uint64_t seed = 0; seed < 6; ++seed) {
    const datasets::EpisodeRecord record = reversed_worker->Run(0, seed);
    if (record.rejected) continue;
    bool near = true;
    for (int j = 0; j < 4; ++j) {
      near = near && std::abs(record.states[31 * 8 + static_cast<size_t>(j)] - record.commanded_goal[static_cast<size_t>(j)]) < 0.02;
    }
    reached += near;
  }
  EXPECT_GE(reached, 4);
  // Without masses there is nothing to simulate: one line naming the link.
  RobotFile massless = *file_;
  massless.inertia.clear();
  EXPECT_THAT([&] { SimulationXml(massless, DriveSettings{}, "robot.yaml"); },
              ::testing::ThrowsMessage<Error>(HasSubstr("robot.yaml: inertia: the links moved by joint \"lift\"")));
}


TEST(ShippedRobotTest, Ur5FollowsThePublishedDenavitHartenbergParameters) {
  // robots/ur5 against the standard DH product written here: T = prod Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i).
  const kinematics::RobotDescription d = LoadRobot(std::string(FLOWPLAN_SOURCE_DIR) + "/robots/ur5");
  ASSERT_EQ(d.num_joints, 6);
  const double D[6] = {0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823};
  const double A[6] = {0.0, -0.425, -0.39225, 0.0, 0.0, 0.0};
  const double alpha[6] = {M_PI / 2, 0.0, 0.0, M_PI / 2, -M_PI / 2, 0.0};
  const kinematics::Robot robot(d);
  torch::manual_seed(11);
  const torch::Tensor q = (torch::rand({20, 6}, torch::kFloat64) * 2 - 1) * M_PI;
  const torch::Tensor tcp = robot.Tcp(q);
  for (int64_t b = 0; b < 20; ++b) {
    double T[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    for (int i = 0; i < 6; ++i) {
      const double th = q[b][i].item<double>(), ct = std::cos(th), st = std::sin(th);
      const double ca = std::cos(alpha[i]), sa = std::sin(alpha[i]);
      const double step[4][4] = {{ct, -st * ca, st * sa, A[i] * ct},
                                 {st, ct * ca, -ct * sa, A[i] * st},
                                 {0, sa, ca, D[i]},
                                 {0, 0, 0, 1}};
      double next[4][4] = {};
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
          for (int k = 0; k < 4; ++k) next[r][c] += T[r][k] * step[k][c];
        }
      }
      std::memcpy(T, next, sizeof(T));
    }
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(tcp[b][i].item<double>(), T[i][3], 1e-12) << "b " << b;
  }
  // The joints' published speeds and torques.
  EXPECT_THAT(d.velocity_limit, ::testing::Each(::testing::DoubleEq(M_PI)));
  EXPECT_EQ(LoadRobotFile(std::string(FLOWPLAN_SOURCE_DIR) + "/robots/ur5").effort_limit,
            (std::vector<double>{150, 150, 150, 28, 28, 28}));
}

TEST(ShippedRobotTest, FrankaPandaFolderMovesAsTheBuiltInFrankaInsideTighterSpheres) {
  // robots/franka_panda, imported from a URDF, against the built-in Franka read from its MJCF: the same joints,
  // limits, speeds and TCP; its spheres cover the published collision meshes and reach at most about 1 cm outside.
  const std::string dir = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/franka_panda";
  const kinematics::RobotDescription d = LoadRobot(dir);
  const kinematics::RobotDescription builtin = sim::LoadFrankaModel().description();
  ASSERT_EQ(d.num_joints, 7);
  for (int j = 0; j < 7; ++j) EXPECT_EQ(d.JointName(j), "panda_joint" + std::to_string(j + 1));
  EXPECT_EQ(d.joint_lower, builtin.joint_lower);
  EXPECT_EQ(d.joint_upper, builtin.joint_upper);
  EXPECT_EQ(d.velocity_limit, builtin.velocity_limit);
  const sim::JointVector ready = sim::FrankaReadyPose();
  ASSERT_EQ(d.home.size(), 7u);
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(d.home[static_cast<size_t>(j)], ready[j], 1e-15);
  torch::manual_seed(13);
  const torch::Tensor lower = torch::tensor(d.joint_lower, torch::kFloat64);
  const torch::Tensor upper = torch::tensor(d.joint_upper, torch::kFloat64);
  const torch::Tensor q = lower + torch::rand({50, 7}, torch::kFloat64) * (upper - lower);
  EXPECT_LT((kinematics::Robot(d).Tcp(q) - kinematics::Robot(builtin).Tcp(q)).abs().max().item<double>(), 1e-9);
  // The cover, on surface samples the fit never saw. The right finger's mesh is the left one's turned half a turn
  // about z (the URDF's collision origin): its spheres are turned back onto finger.obj.
  int links = 0;
  for (size_t l = 0; l < d.links.size(); ++l) {
    const std::string& name = d.links[l].name;
    std::vector<spheres::Sphere> cover;
    for (const auto& s : d.spheres) {
      if (s.link != static_cast<int>(l)) continue;
      cover.push_back({s.centre, s.radius});
      if (name == "panda_rightfinger") cover.back().centre = {-s.centre[0], -s.centre[1], s.centre[2]};
    }
    if (cover.empty()) continue;
    ++links;
    const std::string file = name.find("finger") != std::string::npos ? "finger" : name.substr(std::string("panda_").size());
    const spheres::CoverReport report = spheres::CheckCover(spheres::LoadMesh(dir + "/meshes/" + file + ".obj"), cover,
                                                            0.004, 103, 0);
    EXPECT_GT(report.samples, 100) << name;
    EXPECT_EQ(report.uncovered, 0) << name << ": " << report.largest_uncovered << " m outside every sphere";
    EXPECT_LT(report.largest_outside, 0.0105) << name;
  }
  EXPECT_EQ(links, 11);  // panda_link0 … panda_link7, the hand, two fingers
}

TEST(ShippedRobotTest, FetchArmFollowsThePublishedJointOffsets) {
  // robots/fetch_arm against the product written here of the published joint origins (all with identity
  // rotations) and axes: T = prod Trans(origin_i) Motion(axis_i, q_i), the lift a slide along z.
  const std::string dir = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/fetch_arm";
  const kinematics::RobotDescription d = LoadRobot(dir);
  ASSERT_EQ(d.num_joints, 8);
  const double origin[9][3] = {{-0.086875, 0, 0.37743}, {0.119525, 0, 0.34858}, {0.117, 0, 0.06}, {0.219, 0, 0},
                               {0.133, 0, 0},          {0.197, 0, 0},          {0.1245, 0, 0},   {0.1385, 0, 0},
                               {0.16645, 0, 0}};  // the last: the gripper (the TCP) past the wrist roll
  const char axis[8] = {'s', 'z', 'y', 'x', 'y', 'x', 'y', 'x'};  // s: the slide along z
  const kinematics::Robot robot(d);
  torch::manual_seed(12);
  const torch::Tensor lower = torch::tensor(d.joint_lower, torch::kFloat64);
  const torch::Tensor upper = torch::tensor(d.joint_upper, torch::kFloat64);
  const torch::Tensor q = lower + torch::rand({20, 8}, torch::kFloat64) * (upper - lower);
  const torch::Tensor tcp = robot.Tcp(q);
  for (int64_t b = 0; b < 20; ++b) {
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int i = 0; i < 8; ++i) {
      p += R * Eigen::Vector3d(origin[i][0], origin[i][1], origin[i][2]);
      const double v = q[b][i].item<double>();
      if (axis[i] == 's') {
        p += R * Eigen::Vector3d(0, 0, v);
      } else {
        const Eigen::Vector3d a = axis[i] == 'x' ? Eigen::Vector3d::UnitX()
                                  : axis[i] == 'y' ? Eigen::Vector3d::UnitY()
                                                   : Eigen::Vector3d::UnitZ();
        R = R * Eigen::AngleAxisd(v, a).toRotationMatrix();
      }
    }
    p += R * Eigen::Vector3d(origin[8][0], origin[8][1], origin[8][2]);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(tcp[b][i].item<double>(), p[i], 1e-12) << "b " << b;
  }
  // The published limits (the continuous joints planned within ±π), speeds and efforts.
  EXPECT_EQ(d.joint_lower, (std::vector<double>{0, -1.6056, -1.221, -M_PI, -2.251, -M_PI, -2.16, -M_PI}));
  EXPECT_EQ(d.joint_upper, (std::vector<double>{0.38615, 1.6056, 1.518, M_PI, 2.251, M_PI, 2.16, M_PI}));
  EXPECT_EQ(d.velocity_limit, (std::vector<double>{0.1, 1.256, 1.454, 1.571, 1.521, 1.571, 2.268, 2.268}));
  EXPECT_EQ(LoadRobotFile(dir).effort_limit, (std::vector<double>{450, 33.82, 131.76, 76.94, 66.18, 29.35, 25.7, 7.36}));
}

/// The lift arm as an MJCF: a slide, hinges through their bodies' origins, a capsule, a box, a mesh, a motor per
/// joint, the speed limits as a custom numeric. `joint` replaces the wrist's joint element.
std::string LiftArmMjcf(const std::string& wrist = R"(<joint name="wrist" axis="0 0 1" range="-3 3"/>)",
                        const std::string& custom = R"(<custom><numeric name="velocity_limit" data="0.2 1.5 1.5 2"/></custom>)") {
  return R"(<mujoco model="lift_arm_mjcf">
  <compiler angle="radian" meshdir="." autolimits="true"/>
  <asset><mesh name="hand" file="hand.stl"/></asset>)" + custom + R"(
  <worldbody>
    <body name="base">
      <geom type="box" size="0.1 0.1 0.05" pos="0 0 0.05"/>
      <body name="column" pos="0 0 0.1">
        <joint name="lift" type="slide" axis="0 0 1" range="0 0.3"/>
        <geom type="cylinder" size="0.05 0.2" pos="0 0 0.2"/>
        <body name="upper" pos="0 0 0.45" quat="0.9887710779 0 0 0.1494381325">
          <joint name="shoulder" axis="0 0 1" range="-2.8 2.8"/>
          <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
          <body name="fore" pos="0.3 0 0">
            <joint name="elbow" axis="0 1 0" range="-2 2"/>
            <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.035"/>
            <body name="hand" pos="0.25 0 0" quat="0.7071067812 0 0.7071067812 0">
              )" + wrist + R"(
              <geom type="mesh" mesh="hand"/>
              <geom type="sphere" size="0.02" pos="0 0 0.1" contype="0" conaffinity="0"/>
              <body name="tool" pos="0 0 0.12"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="lift" gear="1" ctrlrange="-500 500"/>
    <motor joint="shoulder" gear="80" ctrlrange="-1 1"/>
    <motor joint="elbow" gear="1" forcerange="-60 60" forcelimited="true"/>
    <motor joint="wrist" gear="1" ctrlrange="-20 20"/>
  </actuator>
</mujoco>
)";
}

TEST(MjcfImportTest, AnMjcfBecomesARobotFolderWhoseKinematicsAreMujocos) {
  const fs::path dir = testing::ScratchDir();
  WritePrismStl(dir / "hand.stl", 0.04, 0.1);
  WriteText(dir / "arm.xml", LiftArmMjcf());
  ImportOptions options;
  options.tip = "tool";
  options.overshoot = 0.02;
  options.pair_samples = 500;
  const ImportResult imported = ImportRobot((dir / "arm.xml").string(), options, (dir / "robot").string());
  const RobotFile file = LoadRobotFile((dir / "robot").string());
  const kinematics::RobotDescription d = file.Description("robot.yaml");
  EXPECT_EQ(d.name, "lift_arm_mjcf");
  ASSERT_EQ(d.num_joints, 4);
  EXPECT_EQ(d.JointName(0), "lift");
  EXPECT_EQ(d.links[static_cast<size_t>(d.FindLink("column"))].type, kinematics::JointType::kPrismatic);
  EXPECT_EQ(d.joint_upper, (std::vector<double>{0.3, 2.8, 2.0, 3.0}));
  EXPECT_EQ(d.velocity_limit, (std::vector<double>{0.2, 1.5, 1.5, 2.0}));
  EXPECT_EQ(file.effort_limit, (std::vector<double>{500, 80, 60, 20}));
  // The mesh is written into the folder, and the sphere that does not collide is not collision geometry.
  EXPECT_TRUE(fs::is_regular_file(dir / "robot" / file.geometry.back().mesh)) << file.geometry.back().mesh;
  for (const CollisionGeometry& g : file.geometry) EXPECT_NE(g.shape, "sphere");
  // Bodies, TCP and spheres against MuJoCo's kinematics of the same file.
  char error[1000] = "";
  const sim::MjModelPtr model(mj_loadXML((dir / "arm.xml").string().c_str(), nullptr, error, sizeof(error)));
  ASSERT_TRUE(model) << error;
  sim::MjDataPtr data = sim::MakeData(*model);
  const kinematics::Robot robot(d);
  torch::manual_seed(4);
  const torch::Tensor lower = torch::tensor(d.joint_lower, torch::kFloat64), upper = torch::tensor(d.joint_upper, torch::kFloat64);
  const torch::Tensor q = lower + (upper - lower) * torch::rand({8, 4}, torch::kFloat64);
  const auto frames = jit::Call(robot.module(), "link_frames", {q}).toTensorVector();
  const torch::Tensor tcp = robot.Tcp(q);
  for (int64_t b = 0; b < 8; ++b) {
    for (int j = 0; j < 4; ++j) data->qpos[j] = q[b][j].item<double>();
    mj_kinematics(model.get(), data.get());
    for (size_t l = 0; l < d.links.size(); ++l) {
      const int body = mj_name2id(model.get(), mjOBJ_BODY, d.links[l].name.c_str());
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(frames[l][b][i][3].item<double>(), data->xpos[3 * body + i], 1e-9) << d.links[l].name;
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(frames[l][b][i][k].item<double>(), data->xmat[9 * body + 3 * i + k], 1e-9);
      }
    }
    const int tool = mj_name2id(model.get(), mjOBJ_BODY, "tool");
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(tcp[b][i].item<double>(), data->xpos[3 * tool + i], 1e-9);
  }
  // Every vertex of the hand's mesh, placed by MuJoCo, lies in a sphere of the hand.
  const int mesh = 0, hand = d.FindLink("hand");
  int geom = 0;
  while (model->geom_type[geom] != mjGEOM_MESH) ++geom;
  for (int v = 0; v < model->mesh_vertnum[mesh]; ++v) {
    const float* raw = model->mesh_vert + 3 * (model->mesh_vertadr[mesh] + v);
    const mjtNum local[3] = {raw[0], raw[1], raw[2]};
    mjtNum p[3];  // in the hand's frame: MuJoCo keeps a mesh about its own centre and places it by the geom's pose
    mju_rotVecQuat(p, local, model->geom_quat + 4 * geom);
    for (int i = 0; i < 3; ++i) p[i] += model->geom_pos[3 * geom + i];
    double nearest = INFINITY;
    for (const auto& sphere : d.spheres) {
      if (sphere.link != hand) continue;
      nearest = std::min(nearest, std::sqrt(std::pow(p[0] - sphere.centre[0], 2) + std::pow(p[1] - sphere.centre[1], 2) +
                                            std::pow(p[2] - sphere.centre[2], 2)) - sphere.radius);
    }
    EXPECT_LE(nearest, 1e-6) << "vertex " << v;
  }
}

TEST(MjcfImportTest, WhatAnMjcfCannotSayIsOneErrorNamingIt) {
  const fs::path dir = testing::ScratchDir();
  WritePrismStl(dir / "hand.stl", 0.04, 0.1);
  auto error = [&](const std::string& text) {
    WriteText(dir / "arm.xml", text);
    try {
      ImportRobot((dir / "arm.xml").string(), ImportOptions{}, (dir / "robot").string());
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(error(LiftArmMjcf(R"(<joint name="wrist" type="ball"/>)")),
              AllOf(HasSubstr("arm.xml: joint \"wrist\""), HasSubstr("ball")));
  EXPECT_THAT(error(LiftArmMjcf(R"(<joint name="wrist" axis="0 0 1" pos="0 0 0.01" range="-3 3"/>)")),
              AllOf(HasSubstr("arm.xml: joint \"wrist\""), HasSubstr("through its body's origin")));
  EXPECT_THAT(error(LiftArmMjcf(R"(<joint name="wrist" axis="0 0 1" range="-3 3"/>)", "")),
              AllOf(HasSubstr("arm.xml"), HasSubstr("--velocity-limit")));
  EXPECT_FALSE(fs::exists(dir / "robot" / "robot.yaml"));
}

class RobotImportErrorTest : public ::testing::Test {
 protected:
  std::string ImportError(const std::string& urdf_text, ImportOptions options = {}) {
    const fs::path dir = testing::ScratchDir();
    WritePrismStl(dir / "hand.stl", 0.04, 0.1);
    const fs::path path = dir / "arm.urdf";
    WriteText(path, urdf_text);
    options.pair_samples = 100;
    options.overshoot = 0.03;
    try {
      ImportRobot(path.string(), options, (dir / "robot").string());
    } catch (const Error& e) {
      EXPECT_FALSE(fs::exists(dir / "robot" / "robot.yaml"));
      return e.what();
    }
    ADD_FAILURE() << "the import did not fail";
    return "";
  }
};

TEST_F(RobotImportErrorTest, AMalformedUrdfNamesTheFile) {
  std::string text = LiftArmUrdf("hand.stl");
  text.resize(text.size() / 2);
  EXPECT_THAT(ImportError(text), HasSubstr("arm.urdf: "));
}

TEST_F(RobotImportErrorTest, AJointWithoutLimitsIsNamed) {
  EXPECT_THAT(ImportError(LiftArmUrdf("hand.stl", "", "")), AllOf(HasSubstr("arm.urdf: "), HasSubstr("wrist")));
}

TEST_F(RobotImportErrorTest, AMissingTipLinkIsNamed) {
  ImportOptions options;
  options.tip = "gripper";
  EXPECT_THAT(ImportError(LiftArmUrdf("hand.stl"), options), AllOf(HasSubstr("arm.urdf: "), HasSubstr("\"gripper\"")));
}

TEST_F(RobotImportErrorTest, AMissingCollisionMeshNamesTheLinkAndTheFile) {
  EXPECT_THAT(ImportError(LiftArmUrdf("meshes/nowhere.stl")),
              AllOf(HasSubstr("arm.urdf: link \"hand\" collision 0"), HasSubstr("meshes/nowhere.stl"), HasSubstr("no such file")));
}

TEST_F(RobotImportErrorTest, AColladaCollisionMeshIsRefusedByName) {
  const fs::path dir = testing::ScratchDir();
  WriteText(dir / "hand.dae", "<COLLADA/>");
  EXPECT_THAT(ImportError(LiftArmUrdf("hand.dae")),
              AllOf(HasSubstr("link \"hand\""), HasSubstr(".dae"), HasSubstr("STL or OBJ only")));
}

TEST_F(RobotImportErrorTest, HoldsAndTipsThatCannotBeAreNamed) {
  ImportOptions fixed;
  fixed.hold["tool_joint"] = 0.1;
  EXPECT_THAT(ImportError(LiftArmUrdf("hand.stl"), fixed), HasSubstr("--hold: joint \"tool_joint\" is fixed"));
  ImportOptions outside;
  outside.hold["lift"] = 0.5;
  EXPECT_THAT(ImportError(LiftArmUrdf("hand.stl"), outside), HasSubstr("--hold: lift = 0.5 is outside its limits [0.0, 0.3]"));
  ImportOptions tip;
  tip.joints = {"shoulder", "elbow"};
  tip.base = "column";
  tip.tip = "base";
  EXPECT_THAT(ImportError(LiftArmUrdf("hand.stl"), tip), HasSubstr("--tip: link \"base\" is not below the base \"column\""));
}

TEST(RobotImportMimicTest, AMimicJointFollowsItsHeldLeaderWhateverTheirNamesOrder) {
  // Two fingers on the hand: "a_finger" mimics "b_finger", which liburdfdom visits after it (names in order).
  const fs::path dir = testing::ScratchDir();
  WritePrismStl(dir / "hand.stl", 0.04, 0.1);
  const std::string fingers = R"(
  <link name="finger_a"><collision><geometry><box size="0.01 0.02 0.04"/></geometry></collision></link>
  <link name="finger/b"><collision><geometry><mesh filename="hand.stl" scale="0.2 0.2 0.4"/></geometry></collision></link>
  <joint name="a_finger" type="prismatic"><parent link="hand"/><child link="finger_a"/><origin xyz="0 0.03 0.1"/>
    <axis xyz="0 1 0"/><limit lower="-0.04" upper="0" velocity="0.1" effort="20"/><mimic joint="b_finger" multiplier="-1"/></joint>
  <joint name="b_finger" type="prismatic"><parent link="hand"/><child link="finger/b"/><origin xyz="0 -0.03 0.1"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" velocity="0.1" effort="20"/></joint>)";
  std::string urdf = LiftArmUrdf("hand.stl");
  urdf.insert(urdf.rfind("</robot>"), fingers);
  WriteText(dir / "arm.urdf", urdf);
  ImportOptions options;
  options.tip = "tool";
  options.hold["b_finger"] = 0.03;
  options.overshoot = 0.03;
  options.pair_samples = 100;
  const ImportResult result = ImportRobot((dir / "arm.urdf").string(), options, (dir / "robot").string());
  const kinematics::RobotDescription& d = result.file.robot;
  EXPECT_EQ(d.num_joints, 4);  // the fingers are held, not planned
  EXPECT_EQ(d.links[static_cast<size_t>(d.FindLink("finger/b"))].offset, 0.03);
  EXPECT_EQ(d.links[static_cast<size_t>(d.FindLink("finger_a"))].offset, -0.03);
  // A link name with a '/' makes a file name without one, inside the folder.
  EXPECT_TRUE(fs::is_regular_file(dir / "robot" / "meshes" / "finger_b_0.stl"));
  // Held by a mimic of a planned joint is refused, naming both.
  ImportOptions planned = options;
  planned.hold.clear();
  planned.tip.clear();
  planned.pair_samples = 10;
  try {
    ImportUrdf((dir / "arm.urdf").string(), planned);
    ADD_FAILURE() << "a mimic of a planned joint was accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("\"a_finger\" mimics \"b_finger\", which is planned")));
  }
}

}  // namespace
}  // namespace flowplan::robotfiles
