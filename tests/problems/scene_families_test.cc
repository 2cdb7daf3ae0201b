// Procedural scene families, checked with MuJoCo (the arm's collision geoms
// against the scene's shapes, its kinematics for the TCP) and plain geometry:
// for the built-in Franka, and for the UR5 robot folder (robots/ur5) whose
// joints turn ±2π, and the arm on a lift (robots/fetch_arm).

#include "problems/scene_families.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <tuple>

#include "core/config.h"
#include "core/error.h"
#include "robotfiles/robot_folder.h"
#include "robotfiles/robot_model.h"
#include "sim/franka_execution.h"
#include "sim/franka_model.h"
#include "sim/franka_self_collision.h"
#include "sim/mujoco_util.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::problems {
namespace {

const FamilyArm& Franka() {
  static const FamilyArm arm = FrankaFamilyArm();
  return arm;
}

constexpr double kClearance = 0.01;

/// Deepest penetration (m, >= 0) of the arm's MuJoCo collision geoms into the
/// scene's obstacles at q; 0 if they do not touch. `exact`: with no contact
/// margin, so that MuJoCo's convex solver measures the shapes themselves;
/// otherwise the execution model as it is (its margin measures distances).
double MujocoPenetration(const geometry::Scene& scene, const std::vector<double>& q, bool exact) {
  const sim::FrankaModel model = sim::MakeFrankaScene(scene, 0.001);
  sim::MjModelPtr m_ptr = sim::CopyModel(model.mj());
  mjModel& m = *m_ptr;
  if (exact) {
    for (int g = 0; g < m.ngeom; ++g) m.geom_margin[g] = m.geom_gap[g] = 0.0;
  }
  auto d = sim::MakeData(m);
  for (int j = 0; j < 7; ++j) d->qpos[j] = q[j];
  mj_forward(&m, d.get());
  double deepest = 0.0;
  for (int c = 0; c < d->ncon; ++c) deepest = std::max(deepest, -d->contact[c].dist);
  return deepest;
}

/// p in the frame of a box: (x, y, z) relative to its centre along its axes.
Eigen::Vector3d InBox(const geometry::BoxObstacle& b, const Eigen::Vector3d& p) {
  const Eigen::Quaterniond q(b.quaternion[0], b.quaternion[1], b.quaternion[2], b.quaternion[3]);
  return q.normalized().inverse() * (p - Eigen::Vector3d(b.centre[0], b.centre[1], b.centre[2]));
}

/// Whether p lies over or under box b's footprint, and how far above its centre.
bool OverFootprint(const geometry::BoxObstacle& b, const Eigen::Vector3d& p, double& height) {
  const Eigen::Vector3d local = InBox(b, p);
  height = local.z();
  return std::abs(local.x()) < 0.5 * b.size[0] && std::abs(local.y()) < 0.5 * b.size[1];
}

const geometry::BoxObstacle& Named(const Problem& p, const std::string& name) {
  for (size_t k = 0; k < p.scene.boxes.size(); ++k) {
    if (p.obstacle_names[k] == name) return p.scene.boxes[k];
  }
  throw std::runtime_error("no box " + name);
}

/// Whether the goal (and for under_table the start) TCP lies where `family` says, the gripper's approach (TCP z
/// axis) as the family says: over the table, between two shelves, inside the box below its rim, inside the posts,
/// under the table top.
void ExpectWhereTheFamilySays(const std::string& family, const Problem& p, const Eigen::Vector3d& goal,
                              const Eigen::Vector3d& start, const Eigen::Vector3d& approach) {
  double height = 0.0;
  if (family == "table") {
    ASSERT_TRUE(OverFootprint(Named(p, "table"), goal, height));
    EXPECT_GT(height, 0.0);
    EXPECT_GT(-approach.z(), 0.999);  // down
  } else if (family == "shelf") {
    EXPECT_LT(std::abs(approach.z()), 1e-3);  // horizontal
    int below = 0, above = 0;
    for (size_t k = 0; k < p.scene.boxes.size(); ++k) {
      const std::string& name = p.obstacle_names[k];
      if (name.rfind("shelf", 0) != 0 && name != "lid") continue;
      if (OverFootprint(p.scene.boxes[k], goal, height)) (height > 0 ? below : above) += 1;
    }
    EXPECT_GE(below, 1);  // between two boards
    EXPECT_GE(above, 1);
    const geometry::BoxObstacle& back = Named(p, "back");
    EXPECT_GT(approach.dot(Eigen::Vector3d(back.centre.data()) - goal), 0.0);  // pointing in
  } else if (family == "box") {
    ASSERT_TRUE(OverFootprint(Named(p, "box_bottom"), goal, height));
    const geometry::BoxObstacle& wall = Named(p, "box_near");
    EXPECT_LT(goal.z(), wall.centre[2] + 0.5 * wall.size[2]);  // below the rim
    EXPECT_GT(-approach.z(), 0.999);
  } else if (family == "cage") {
    ASSERT_TRUE(OverFootprint(Named(p, "table"), goal, height));
    // Inside the posts: the TCP is nearer the cage's axis than any post.
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < p.scene.cylinders.size(); ++k) {
      const std::string& name = p.obstacle_names[p.scene.boxes.size() + k];
      if (name.rfind("post", 0) == 0) axis += 0.25 * Eigen::Vector3d(p.scene.cylinders[k].centre.data());
    }
    for (size_t k = 0; k < p.scene.cylinders.size(); ++k) {
      const std::string& name = p.obstacle_names[p.scene.boxes.size() + k];
      if (name.rfind("post", 0) != 0) continue;
      const Eigen::Vector3d post(p.scene.cylinders[k].centre.data());
      EXPECT_LT((goal - axis).head<2>().norm(), (post - axis).head<2>().norm());
    }
    EXPECT_LT(std::abs(approach.z()), 1e-3);
    // Pointing in: from the front bar towards the back bar.
    Eigen::Vector3d front = Eigen::Vector3d::Zero(), back = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < p.scene.cylinders.size(); ++k) {
      const std::string& name = p.obstacle_names[p.scene.boxes.size() + k];
      if (name == "front_bar") front = Eigen::Vector3d(p.scene.cylinders[k].centre.data());
      if (name == "back_bar") back = Eigen::Vector3d(p.scene.cylinders[k].centre.data());
    }
    EXPECT_GT(approach.dot(back - front), 0.0);
  } else if (family == "under_table") {
    ASSERT_TRUE(OverFootprint(Named(p, "table_top"), goal, height));
    EXPECT_LT(height, 0.0);  // under it
    EXPECT_GT(start.z(), Named(p, "table_top").centre[2]);  // the start above it
  }
}

class SceneFamilyTest : public ::testing::TestWithParam<std::string> {};

TEST_P(SceneFamilyTest, StartsAndGoalsAreFreeWithinLimitsAndWhereTheFamilySaysTheyAre) {
  const std::string family = GetParam();
  const ProblemSet set = MakeFamilyProblems(Franka(), family, 11, 5, kClearance, 2);
  ASSERT_EQ(set.problems.size(), 5u);
  const sim::FrankaModel model = sim::LoadFrankaModel();
  const auto& limits = model.limits();
  const sim::FrankaCollisionModel collision_model(0.0);
  sim::FrankaCollisionChecker checker(collision_model);
  for (const Problem& p : set.problems) {
    SCOPED_TRACE(p.name);
    ASSERT_EQ(p.obstacle_names.size(), static_cast<size_t>(p.scene.size()));
    EXPECT_TRUE(p.scene.spheres.empty());
    EXPECT_GE(p.scene.boxes.size(), 1u);
    for (const auto* q : {&p.start_q, &p.goal_q}) {
      ASSERT_EQ(q->size(), 7u);
      for (int j = 0; j < 7; ++j) {
        EXPECT_GE((*q)[j], limits.q_lower[j]);
        EXPECT_LE((*q)[j], limits.q_upper[j]);
      }
      EXPECT_EQ(MujocoPenetration(p.scene, *q, true), 0.0);  // MuJoCo's capsules against the real shapes
      // The execution model (distances measured within its margin) agrees: no contact.
      EXPECT_EQ(MujocoPenetration(p.scene, *q, false), 0.0);
      // Free of itself and above the floor (MuJoCo's capsules, the data set's and the plan checker's check).
      EXPECT_EQ(checker.FirstCollision(Eigen::Map<const sim::JointVector>(q->data())), "");
    }
    EXPECT_GE(p.start_clearance, kClearance);
    EXPECT_GE(p.goal_clearance, kClearance);
    const sim::FrankaPose goal = sim::FrankaForwardKinematics(model, p.goal_q);
    const sim::FrankaPose start = sim::FrankaForwardKinematics(model, p.start_q);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(p.goal_tcp[k], goal.tcp_position[k], 1e-6);
      EXPECT_NEAR(p.start_tcp[k], start.tcp_position[k], 1e-6);
    }
    const Eigen::Vector3d approach = goal.tcp_rotation.col(2);  // the gripper's pointing direction
    ExpectWhereTheFamilySays(family, p, goal.tcp_position, start.tcp_position, approach);
  }
}

TEST_P(SceneFamilyTest, ProblemIDependsOnlyOnSeedFamilyAndI) {
  const std::string family = GetParam();
  const ProblemSet two = MakeFamilyProblems(Franka(), family, 5, 2, kClearance, 1);
  const ProblemSet three = MakeFamilyProblems(Franka(), family, 5, 3, kClearance, 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(config::ToYaml(two.problems[i]), config::ToYaml(three.problems[i])) << i;
  }
  const ProblemSet other = MakeFamilyProblems(Franka(), family, 6, 1, kClearance, 1);
  EXPECT_NE(config::ToYaml(other.problems[0]), config::ToYaml(two.problems[0]));
  // The problem file reads back to the same values.
  const std::string path = (flowplan::testing::ScratchDir() / "problems.yaml").string();
  std::ofstream(path) << ProblemSetYaml(three);
  EXPECT_EQ(config::ToYaml(LoadProblemSet(path)), config::ToYaml(three));
}

INSTANTIATE_TEST_SUITE_P(Families, SceneFamilyTest, ::testing::ValuesIn(SceneFamilies()),
                         [](const ::testing::TestParamInfo<std::string>& info) { return info.param; });

TEST(SceneFamiliesTest, FamiliesDifferAndAnUnknownOneIsNamed) {
  EXPECT_THAT(SceneFamilies(), ::testing::ElementsAre("table", "shelf", "box", "cage", "under_table"));
  const ProblemSet table = MakeFamilyProblems(Franka(), "table", 5, 1, kClearance);
  const ProblemSet shelf = MakeFamilyProblems(Franka(), "shelf", 5, 1, kClearance);
  EXPECT_NE(table.problems[0].start_q, shelf.problems[0].start_q);
  try {
    MakeFamilyProblems(Franka(), "kitchen", 5, 1, kClearance);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("\"kitchen\" is not one of table, shelf, box, cage, under_table"));
  }
}

std::string Folder(const std::string& robot) { return std::string(FLOWPLAN_SOURCE_DIR) + "/robots/" + robot; }

const FamilyArm& Ur5() {
  static const FamilyArm arm = FolderFamilyArm(Folder("ur5"));
  return arm;
}

const FamilyArm& FetchArm() {
  static const FamilyArm arm = FolderFamilyArm(Folder("fetch_arm"));
  return arm;
}

// (robot folder, family)
class FolderFamilyTest : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

// The shipped folders' problems (the UR5: six joints turning ±2π; the arm on a lift: eight joints, one of them
// prismatic), checked against the folder's own MuJoCo model (`plan --execute`'s, built from robot.yaml's
// tree and collision meshes): its TCP site where the problem says, pointing as the family says, its collision
// geometry clear of every obstacle, every joint on home's side of a whole turn.
TEST_P(FolderFamilyTest, AFolderRobotsProblemsAreFreeReachedAndOnHomesSide) {
  const auto& [robot, family] = GetParam();
  const FamilyArm& arm = robot == "ur5" ? Ur5() : FetchArm();
  const ProblemSet set = MakeFamilyProblems(arm, family, 3, 4, kClearance, 2);
  const std::string dir = Folder(robot);
  const robotfiles::RobotFile file = robotfiles::LoadRobotFile(dir);
  const int J = arm.robot.num_joints;
  ASSERT_EQ(J, robot == "ur5" ? 6 : 8);
  for (const Problem& p : set.problems) {
    SCOPED_TRACE(p.name);
    ASSERT_EQ(p.obstacle_names.size(), static_cast<size_t>(p.scene.size()));
    const robotfiles::ExecutionModel model =
        robotfiles::LoadExecutionModel(file, dir, p.scene, robotfiles::DriveSettings{}, sim::ExecutionConfig{}, robot);
    mjModel& m = *model.model;
    for (int g = 0; g < m.ngeom; ++g) m.geom_margin[g] = m.geom_gap[g] = 0.0;  // overlaps only
    auto d = sim::MakeData(m);
    const int site = model.drives.tcp_site;
    ASSERT_GE(site, 0);
    // The start and goal on home's side of every whole turn.
    for (const auto& [q, tcp, reference] : {std::tuple{&p.start_q, &p.start_tcp, &arm.robot.home},
                                            std::tuple{&p.goal_q, &p.goal_tcp, &arm.robot.home}}) {
      ASSERT_EQ(q->size(), static_cast<size_t>(J));
      for (int j = 0; j < J; ++j) {
        EXPECT_GE((*q)[j], arm.robot.joint_lower[j]);
        EXPECT_LE((*q)[j], arm.robot.joint_upper[j]);
        // No whole turn that stays within the limits brings the joint nearer its reference.
        for (const double turn : {-2.0 * M_PI, 2.0 * M_PI}) {
          const double other = (*q)[j] + turn;
          if (other < arm.robot.joint_lower[j] || other > arm.robot.joint_upper[j]) continue;
          EXPECT_LE(std::abs((*q)[j] - (*reference)[j]), std::abs(other - (*reference)[j])) << "joint " << j;
        }
        d->qpos[model.drives.qpos[j]] = (*q)[j];
      }
      mj_forward(&m, d.get());
      for (int k = 0; k < 3; ++k) EXPECT_NEAR((*tcp)[k], d->site_xpos[3 * site + k], 1e-6);
      int touching = 0;
      for (int c = 0; c < d->ncon; ++c) touching += d->contact[c].dist < 0.0 ? 1 : 0;
      EXPECT_EQ(touching, 0);  // the collision meshes' hulls against the real shapes
    }
    // Where the family puts the goal, and the gripper's approach (the TCP's z axis), from MuJoCo's site frame.
    for (int j = 0; j < J; ++j) d->qpos[model.drives.qpos[j]] = p.start_q[j];
    mj_forward(&m, d.get());
    const Eigen::Vector3d start(d->site_xpos + 3 * site);
    for (int j = 0; j < J; ++j) d->qpos[model.drives.qpos[j]] = p.goal_q[j];
    mj_forward(&m, d.get());
    const Eigen::Vector3d goal(d->site_xpos + 3 * site);
    const Eigen::Vector3d approach(d->site_xmat[9 * site + 2], d->site_xmat[9 * site + 5], d->site_xmat[9 * site + 8]);
    ExpectWhereTheFamilySays(family, p, goal, start, approach);
    EXPECT_GE(p.start_clearance, kClearance);
    EXPECT_GE(p.goal_clearance, kClearance);
  }
}

INSTANTIATE_TEST_SUITE_P(Families, FolderFamilyTest,
                         ::testing::Combine(::testing::Values("ur5", "fetch_arm"), ::testing::ValuesIn(SceneFamilies())),
                         [](const auto& info) { return std::get<0>(info.param) + "_" + std::get<1>(info.param); });

TEST(SceneFamiliesTest, TheScaleShiftAndFacingAreTheArmsReachBaseAndHomeAgainstTheFrankas) {
  EXPECT_EQ(FamilyScale(Franka().robot), 1.0);
  // The Franka with every length halved (exact in binary floating point) reaches half as far.
  kinematics::RobotDescription half = Franka().robot;
  for (auto& link : half.links) {
    for (double& v : link.pos) v *= 0.5;
  }
  for (double& v : half.tcp_pos) v *= 0.5;
  for (auto& sphere : half.spheres) {
    for (double& v : sphere.centre) v *= 0.5;
    sphere.radius *= 0.5;
  }
  EXPECT_EQ(FamilyScale(half), 0.5);
  EXPECT_GT(Ur5().scale, 0.9);
  EXPECT_LT(Ur5().scale, 1.1);
  // The shift: how much wider the links that never turn are than the Franka's base (link0, fixed at the origin),
  // scaled. A base sphere of 0.5 m at the origin makes the Franka's base that wide.
  EXPECT_EQ(FamilyShift(Franka().robot, 1.0), 0.0);
  const kinematics::RobotDescription& franka = Franka().robot;
  double link0 = 0.0;
  for (const auto& sphere : franka.spheres) {
    if (sphere.link != 0) continue;
    link0 = std::max(link0, std::hypot(sphere.centre[0], sphere.centre[1]) + sphere.radius);
  }
  ASSERT_EQ(franka.links[0].parent, -1);
  ASSERT_EQ(franka.links[0].pos, (std::array<double, 3>{0.0, 0.0, 0.0}));
  ASSERT_GT(link0, 0.05);
  kinematics::RobotDescription wide = franka;
  wide.spheres.push_back({0, {0.0, 0.0, 0.1}, 0.5, "pedestal"});
  EXPECT_NEAR(FamilyShift(wide, 1.0), 0.5 - link0, 1e-12);
  EXPECT_NEAR(FamilyShift(wide, 2.0), 0.5 - 2.0 * link0, 1e-12);
  EXPECT_EQ(FamilyShift(wide, 10.0), 0.0);
  // The arm on a lift stands on a base cylinder of 0.28 m radius, which its spheres cover; the UR5's base is narrow.
  EXPECT_GE(FetchArm().shift + FetchArm().scale * link0, 0.28);
  EXPECT_LT(FetchArm().shift + FetchArm().scale * link0, 0.28 + 0.05);
  EXPECT_EQ(Ur5().shift, 0.0);
  // The facing: the TCP's azimuth at home. The UR5's TCP at zero is at (-0.81725, -0.19145) (its DH parameters,
  // robots/ur5/README.md); the Franka's ready pose has its TCP on the x axis.
  EXPECT_NEAR(Ur5().facing, std::atan2(-0.19145, -0.81725), 1e-9);
  EXPECT_NEAR(FamilyFacing(Franka().robot), 0.0, 1e-9);
  kinematics::RobotDescription point;
  point.kind = kinematics::RobotKind::kPoint;
  point.name = "ball";
  EXPECT_THROW(FamilyScale(point), Error);
}

}  // namespace
}  // namespace flowplan::problems
