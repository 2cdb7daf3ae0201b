// Executing a robot folder's plans in MuJoCo (robotfiles::LoadExecutionModel
// and sim::ArmExecutor): the UR5 folder tracks a move with the computed-torque
// law, touches an obstacle placed on its path and only that one, and MuJoCo's
// distances between the arm's spheres and an obstacle equal the ones flowplan's
// own collision checker computes, and its self-collision agrees with MuJoCo's
// contacts between the arm's collision meshes.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "collision/body_model.h"
#include "collision/checker.h"
#include "core/error.h"
#include "core/random.h"
#include "robotfiles/robot_model.h"
#include "sim/arm_execution.h"

namespace flowplan::robotfiles {
namespace {

constexpr double kDt = 1.0 / 15.0;
constexpr int kT = 48;

const std::string& Ur5Folder() {
  static const std::string folder = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/ur5";
  return folder;
}

/// A plan (T, 2J) from q0 to q1 with a smooth (cosine) time profile and consistent velocities.
std::vector<double> SmoothMove(const std::vector<double>& q0, const std::vector<double>& q1) {
  const size_t J = q0.size();
  std::vector<double> plan(kT * 2 * J);
  const double duration = (kT - 1) * kDt;
  for (int t = 0; t < kT; ++t) {
    const double s = 0.5 - 0.5 * std::cos(M_PI * t / (kT - 1));
    const double ds = 0.5 * M_PI / duration * std::sin(M_PI * t / (kT - 1));
    for (size_t j = 0; j < J; ++j) {
      plan[t * 2 * J + j] = q0[j] + s * (q1[j] - q0[j]);
      plan[t * 2 * J + J + j] = ds * (q1[j] - q0[j]);
    }
  }
  return plan;
}

/// How the checker's self-collision and MuJoCo's contacts between a robot folder's collision geometry compare on
/// random configurations within the limits (`plan --execute`'s model, the arm's geoms made to collide with one
/// another and with their parents, contacts reported up to `reach` apart).
struct SelfCollisionComparison {
  int configurations = 0;
  int geometry_overlaps = 0;  // configurations where the geometry of a checked pair overlaps by more than 0.1 mm
  int sphere_overlaps = 0;    // configurations the checker calls self-colliding
  int missed = 0;             // geometry overlaps the checker does not call self-colliding
  double deepest_missed = 0.0;  // m: the deepest geometry overlap among them
  int unexplained = 0;        // sphere overlaps whose pair's geometry MuJoCo finds farther than 2 * outside apart
  double outside = 0.0;       // m: how far the folder's spheres reach outside its geometry at most
};

SelfCollisionComparison CompareSelfCollision(const RobotFile& file, const std::string& dir, int configurations) {
  SelfCollisionComparison out;
  out.configurations = configurations;
  const kinematics::RobotDescription d = file.Description("robot.yaml");
  const auto body = std::make_shared<const collision::BodyModel>(d);
  const collision::Checker checker(body, std::make_shared<const collision::World>(geometry::Scene{}, 3), {});
  for (const LinkCover& cover : file.cover) out.outside = std::max(out.outside, cover.largest_outside);
  sim::ExecutionConfig config;
  const ExecutionModel model = LoadExecutionModel(file, dir, geometry::Scene{}, DriveSettings{}, config, "robot.yaml");
  mjModel& m = *model.model;
  m.opt.disableflags |= mjDSBL_FILTERPARENT;
  const double reach = 2.0 * out.outside + 1e-3;
  for (int g = 0; g < m.ngeom; ++g) {
    m.geom_conaffinity[g] = 1;
    m.geom_margin[g] = reach;  // a pair's margin is the larger of its geoms'
    m.geom_gap[g] = 0.0;
  }
  std::unique_ptr<mjData, decltype(&mj_deleteData)> data(mj_makeData(&m), mj_deleteData);
  auto link_of_geom = [&](int g) { return d.FindLink(mj_id2name(&m, mjOBJ_BODY, m.geom_bodyid[g])); };  // bodies are named after the links
  std::set<std::pair<int, int>> checked;
  for (const auto& [a, b] : body->self_pairs()) checked.insert({std::min(a, b), std::max(a, b)});
  Rng rng(7);
  for (int n = 0; n < configurations; ++n) {
    std::vector<double> q(static_cast<size_t>(d.num_joints));
    for (int j = 0; j < d.num_joints; ++j) q[j] = rng.Uniform(d.joint_lower[j], d.joint_upper[j]);
    for (int j = 0; j < d.num_joints; ++j) data->qpos[model.drives.qpos[j]] = q[j];
    mj_kinematics(&m, data.get());
    mj_collision(&m, data.get());
    std::map<std::pair<int, int>, double> nearest;  // checked link pair -> MuJoCo's smallest distance
    for (int c = 0; c < data->ncon; ++c) {
      const int a = link_of_geom(data->contact[c].geom1), b = link_of_geom(data->contact[c].geom2);
      const std::pair<int, int> pair{std::min(a, b), std::max(a, b)};
      if (a < 0 || b < 0 || a == b || !checked.count(pair)) continue;
      const auto at = nearest.find(pair);
      nearest[pair] = at == nearest.end() ? data->contact[c].dist : std::min(at->second, data->contact[c].dist);
    }
    double deepest = 0.0;
    for (const auto& [pair, distance] : nearest) deepest = std::min(deepest, distance);
    const collision::Contact contact = checker.FirstContact(q.data());
    const bool self = contact.kind == collision::Contact::Kind::kSelf;
    if (deepest < -1e-4) {
      ++out.geometry_overlaps;
      if (!self) {
        ++out.missed;
        out.deepest_missed = std::max(out.deepest_missed, -deepest);
      }
    }
    if (self) {
      ++out.sphere_overlaps;
      const int a = body->sphere_link(contact.sphere), b = body->sphere_link(contact.other);
      const auto at = nearest.find({std::min(a, b), std::max(a, b)});
      out.unexplained += at == nearest.end() || at->second > 2.0 * out.outside;
    }
  }
  return out;
}

class RobotExecutionTest : public ::testing::Test {
 protected:
  Eigen::Vector3d Tcp(const std::vector<double>& q) {
    Eigen::Vector3d tcp;
    body_.Tcp(q.data(), tcp.data());
    return tcp;
  }
  sim::ExecutionResult Execute(const RobotFile& file, const geometry::Scene& scene, const std::vector<double>& plan,
                               const Eigen::Vector3d& goal) {
    const ExecutionModel model = LoadExecutionModel(file, Ur5Folder(), scene, DriveSettings{}, config_, "ur5");
    sim::ArmExecutor executor(*model.model, model.drives, static_cast<int>(scene.size()), config_);
    return executor.Execute(plan, kT, kDt, goal);
  }

  RobotFile file_ = LoadRobotFile(Ur5Folder());
  collision::BodyModel body_{file_.Description("ur5")};
  sim::ExecutionConfig config_;
  std::vector<double> q0_ = {0.0, -1.2, 1.4, -1.8, -1.57, 0.0}, q1_ = {1.6, -1.2, 1.4, -1.8, -1.57, 0.0};
};

TEST_F(RobotExecutionTest, TracksAMoveToTheGoalWithoutObstacles) {
  const sim::ExecutionResult r = Execute(file_, {}, SmoothMove(q0_, q1_), Tcp(q1_));
  EXPECT_EQ(r.num_states, kT + 15);
  EXPECT_LT(r.goal_distance, 1e-3);
  EXPECT_LT(r.max_tracking_error, 1e-3);
  EXPECT_TRUE(r.contacts.empty());
  EXPECT_EQ(r.warnings, 0);
  // The recorded states follow the plan: half-way, joint 1 is half-way.
  EXPECT_NEAR(r.states[(kT / 2) * 12 + 0], SmoothMove(q0_, q1_)[(kT / 2) * 12 + 0], 1e-3);
}

TEST_F(RobotExecutionTest, AnObstacleOnThePathIsTouchedAndAFarOneIsNot) {
  const std::vector<double> plan = SmoothMove(q0_, q1_);
  const std::vector<double> middle(plan.begin() + (kT / 2) * 12, plan.begin() + (kT / 2) * 12 + 6);
  geometry::Scene scene;
  const Eigen::Vector3d on_path = Tcp(middle);
  scene.spheres.push_back({{on_path.x(), on_path.y(), on_path.z()}, 0.05});
  scene.spheres.push_back({{2.0, 2.0, 2.0}, 0.05});
  const sim::ExecutionResult r = Execute(file_, scene, plan, Tcp(q1_));
  ASSERT_FALSE(r.contacts.empty());
  for (const sim::ContactEvent& contact : r.contacts) {
    EXPECT_EQ(contact.obstacle, 0);
    EXPECT_GT(contact.max_depth, 0.0);
    EXPECT_GT(contact.first_time, 0.3 * (kT - 1) * kDt);  // reached along the way, not at the start
  }
  EXPECT_LT(r.min_distance[0], 0.0);
  EXPECT_GE(r.min_distance[1], sim::kMeasuredDistance);
}

TEST_F(RobotExecutionTest, MujocoMeasuresTheSpheresAsTheCollisionCheckerDoes) {
  // Without collision geometry, the links carry their spheres: at rest at one configuration, MuJoCo's distance
  // from them to each obstacle is the checker's clearance (both closed forms for spheres and boxes).
  RobotFile spheres_only = file_;
  spheres_only.geometry.clear();
  const std::vector<double> q = {0.4, -1.0, 1.2, -1.5, -1.57, 0.3};
  // A sphere and a box beside the tool, a few centimetres from the arm.
  const Eigen::Vector3d tcp = Tcp(q);
  geometry::Scene scene;
  scene.spheres.push_back({{tcp.x(), tcp.y() + 0.2, tcp.z()}, 0.05});
  geometry::BoxObstacle box;
  box.centre = {tcp.x() - 0.2, tcp.y(), tcp.z()};
  box.size = {0.1, 0.2, 0.3};
  scene.boxes.push_back(box);
  const sim::ExecutionResult r = Execute(spheres_only, scene, SmoothMove(q, q), Tcp(q));
  ASSERT_EQ(r.min_distance.size(), 2u);
  EXPECT_LT(r.max_tracking_error, 1e-6);  // held still: the distances are those of q
  for (int k = 0; k < 2; ++k) {
    geometry::Scene one;
    if (k == 0) one.spheres = scene.spheres;
    if (k == 1) one.boxes = scene.boxes;
    const collision::Checker checker(std::make_shared<collision::BodyModel>(body_),
                                     std::make_shared<collision::World>(one, 3), {});
    const double clearance = checker.Clearance(q.data());
    ASSERT_GT(clearance, 0.0) << "obstacle " << k << " touches the arm: contact forces would move it";
    ASSERT_LT(clearance, 0.2) << "obstacle " << k << " is too far from the arm to test anything";
    EXPECT_NEAR(r.min_distance[k], clearance, 1e-6) << "obstacle " << k;
  }
}

TEST_F(RobotExecutionTest, SelfCollisionAgreesWithMujocosContactsOnRandomConfigurations) {
  // The UR5's spheres cover its collision meshes and reach at most `outside` beyond them, so on every random
  // configuration within the limits, wherever MuJoCo finds the meshes' hulls of a pair the checker checks
  // overlapping, the checker finds the configuration self-colliding (the hulls hold the meshes, so this also says
  // the meshes are near enough to convex where the links meet), and wherever the checker finds two links'
  // spheres overlapping, MuJoCo finds those links' hulls within 2 * outside of each other.
  const SelfCollisionComparison r = CompareSelfCollision(file_, Ur5Folder(), 3000);
  EXPECT_EQ(r.missed, 0) << "the deepest overlap missed: " << r.deepest_missed << " m";
  EXPECT_EQ(r.unexplained, 0);
  // Enough of both for the checks to mean something (617 and 1131 when written).
  EXPECT_GE(r.geometry_overlaps, 300);
  EXPECT_GE(r.sphere_overlaps, r.geometry_overlaps);
  EXPECT_GT(r.outside, 0.005);
  EXPECT_LT(r.outside, 0.02);
}

TEST_F(RobotExecutionTest, JointPdIsTheFrankasGainsAndRefusedForAFolder) {
  config_.controller = sim::TrackingLaw::kJointPd;
  EXPECT_THAT([&] { LoadExecutionModel(file_, Ur5Folder(), {}, DriveSettings{}, config_, "robots/ur5/robot.yaml"); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr(
                  "execute.controller: joint_pd tracks with execute.kp and execute.kd, the Franka's gains; "
                  "robots/ur5/robot.yaml's arm tracks with computed_torque")));
}

}  // namespace
}  // namespace flowplan::robotfiles
