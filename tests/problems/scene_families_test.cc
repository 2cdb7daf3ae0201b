// Procedural scene families, checked with MuJoCo (the arm's collision geoms
// against the scene's shapes, its kinematics for the TCP) and plain geometry.

#include "problems/scene_families.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>

#include "core/config.h"
#include "core/error.h"
#include "sim/franka_execution.h"
#include "sim/franka_model.h"
#include "sim/franka_self_collision.h"
#include "sim/mujoco_util.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::problems {
namespace {

const kinematics::Robot& Franka() {
  static const kinematics::Robot arm(sim::LoadFrankaModel().description());
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
    double height = 0.0;
    if (family == "table") {
      ASSERT_TRUE(OverFootprint(Named(p, "table"), goal.tcp_position, height));
      EXPECT_GT(height, 0.0);
      EXPECT_GT(-approach.z(), 0.999);  // down
    } else if (family == "shelf") {
      EXPECT_LT(std::abs(approach.z()), 1e-3);  // horizontal
      int below = 0, above = 0;
      for (size_t k = 0; k < p.scene.boxes.size(); ++k) {
        const std::string& name = p.obstacle_names[k];
        if (name.rfind("shelf", 0) != 0 && name != "lid") continue;
        if (OverFootprint(p.scene.boxes[k], goal.tcp_position, height)) (height > 0 ? below : above) += 1;
      }
      EXPECT_GE(below, 1);  // between two boards
      EXPECT_GE(above, 1);
    } else if (family == "box") {
      ASSERT_TRUE(OverFootprint(Named(p, "box_bottom"), goal.tcp_position, height));
      const geometry::BoxObstacle& wall = Named(p, "box_near");
      EXPECT_LT(goal.tcp_position.z(), wall.centre[2] + 0.5 * wall.size[2]);  // below the rim
      EXPECT_GT(-approach.z(), 0.999);
    } else if (family == "cage") {
      ASSERT_TRUE(OverFootprint(Named(p, "table"), goal.tcp_position, height));
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
        EXPECT_LT((goal.tcp_position - axis).head<2>().norm(), (post - axis).head<2>().norm());
      }
      EXPECT_LT(std::abs(approach.z()), 1e-3);
    } else if (family == "under_table") {
      ASSERT_TRUE(OverFootprint(Named(p, "table_top"), goal.tcp_position, height));
      EXPECT_LT(height, 0.0);  // under it
      EXPECT_GT(start.tcp_position.z(), Named(p, "table_top").centre[2]);  // the start above it
    }
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

}  // namespace
}  // namespace flowplan::problems
