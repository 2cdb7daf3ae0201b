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

#include "collision/body_model.h"
#include "collision/checker.h"
#include "core/error.h"
#include "core/random.h"
#include "robotfiles/robot_model.h"
#include "sim/arm_execution.h"
#include "tests/support/smooth_move.h"

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
  return flowplan::testing::SmoothMove(q0, q1, kT, kDt);
}

/// How the collision spheres' self-collision and MuJoCo's contacts between a robot folder's collision geometry
/// compare, link pair by link pair, on random configurations within the limits (`plan --execute`'s model, the arm's
/// geoms made to collide with one another and with their parents, contacts reported up to `reach` apart).
struct SelfCollisionComparison {
  int geometry_overlaps = 0;    // (configuration, checked pair)s whose geometry overlaps by more than 0.1 mm
  int sphere_overlaps = 0;      // (configuration, checked pair)s whose spheres overlap
  int missed = 0;               // geometry overlaps whose pair's spheres do not overlap
  double deepest_missed = 0.0;  // m: the deepest geometry overlap among them
  int unexplained = 0;          // sphere overlaps whose pair MuJoCo reports no nearer than 2 * outside
  int checker_disagrees = 0;    // configurations the checker judges otherwise than the pairs' spheres say
  double outside = 0.0;         // m: how far the folder's spheres reach outside its geometry at most
};

SelfCollisionComparison CompareSelfCollision(const RobotFile& file, const std::string& dir, int configurations) {
  SelfCollisionComparison out;
  const kinematics::RobotDescription d = file.Description("robot.yaml");
  const auto body = std::make_shared<const collision::BodyModel>(d);
  const collision::Checker checker(body, std::make_shared<const collision::World>(geometry::Scene{}, 3), {});
  for (const LinkCover& cover : file.cover) out.outside = std::max(out.outside, cover.largest_outside);
  sim::ExecutionConfig config;
  const ExecutionModel model = LoadExecutionModel(file, dir, geometry::Scene{}, DriveSettings{}, config, "robot.yaml");
  mjModel& m = *model.model;
  m.opt.disableflags |= mjDSBL_FILTERPARENT;
  // MuJoCo measures overlaps exactly; a pair that does not overlap it reports when its estimate of their distance
  // (exact for primitives, approximate between meshes) is within the margin.
  const double reach = 2.0 * out.outside + 1e-3;
  for (int g = 0; g < m.ngeom; ++g) {
    m.geom_conaffinity[g] = 1;
    m.geom_margin[g] = reach;  // a pair's margin is the larger of its geoms'
    m.geom_gap[g] = 0.0;
  }
  std::unique_ptr<mjData, decltype(&mj_deleteData)> data(mj_makeData(&m), mj_deleteData);
  auto link_of_geom = [&](int g) { return d.FindLink(mj_id2name(&m, mjOBJ_BODY, m.geom_bodyid[g])); };  // bodies are named after the links
  std::vector<std::pair<int, int>> checked;
  for (const auto& [a, b] : body->self_pairs()) checked.push_back({std::min(a, b), std::max(a, b)});
  std::vector<collision::Frame> frames(static_cast<size_t>(body->num_links()));
  std::vector<double> centres(static_cast<size_t>(3 * body->num_spheres()));
  // The smallest gap between a sphere of link a and one of link b, computed here from the placed spheres.
  auto sphere_gap = [&](int a, int b) {
    double gap = INFINITY;
    for (int s = body->first_sphere(a); s < body->first_sphere(a + 1); ++s) {
      for (int t = body->first_sphere(b); t < body->first_sphere(b + 1); ++t) {
        const double* cs = &centres[static_cast<size_t>(3 * s)];
        const double* ct = &centres[static_cast<size_t>(3 * t)];
        gap = std::min(gap, std::hypot(cs[0] - ct[0], cs[1] - ct[1], cs[2] - ct[2]) - body->sphere_radius(s) -
                                body->sphere_radius(t));
      }
    }
    return gap;
  };
  Rng rng(7);
  for (int n = 0; n < configurations; ++n) {
    std::vector<double> q(static_cast<size_t>(d.num_joints));
    for (int j = 0; j < d.num_joints; ++j) q[j] = rng.Uniform(d.joint_lower[j], d.joint_upper[j]);
    for (int j = 0; j < d.num_joints; ++j) data->qpos[model.drives.qpos[j]] = q[j];
    mj_kinematics(&m, data.get());
    mj_collision(&m, data.get());
    std::map<std::pair<int, int>, double> nearest;  // link pair -> MuJoCo's smallest distance
    for (int c = 0; c < data->ncon; ++c) {
      const int a = link_of_geom(data->contact[c].geom1), b = link_of_geom(data->contact[c].geom2);
      if (a < 0 || b < 0 || a == b) continue;
      const std::pair<int, int> pair{std::min(a, b), std::max(a, b)};
      const auto at = nearest.find(pair);
      nearest[pair] = at == nearest.end() ? data->contact[c].dist : std::min(at->second, data->contact[c].dist);
    }
    body->Place(q.data(), frames.data(), centres.data());
    bool any_sphere_overlap = false;
    for (const auto& pair : checked) {
      const auto at = nearest.find(pair);
      const double geometry = at == nearest.end() ? INFINITY : at->second;
      const bool spheres_overlap = sphere_gap(pair.first, pair.second) < 0.0;
      any_sphere_overlap = any_sphere_overlap || spheres_overlap;
      if (geometry < -1e-4) {
        ++out.geometry_overlaps;
        if (!spheres_overlap) {
          ++out.missed;
          out.deepest_missed = std::max(out.deepest_missed, -geometry);
        }
      }
      if (spheres_overlap) {
        ++out.sphere_overlaps;
        out.unexplained += geometry > 2.0 * out.outside;
      }
    }
    out.checker_disagrees +=
        (checker.FirstContact(q.data()).kind == collision::Contact::Kind::kSelf) != any_sphere_overlap;
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
  // configuration within the limits and for every link pair the checker checks: where MuJoCo finds the pair's mesh
  // hulls overlapping, the pair's spheres overlap (the hulls hold the meshes, so this also says the meshes are near
  // enough to convex where the links meet); where the pair's spheres overlap, MuJoCo finds its hulls within
  // 2 * outside of each other. And the checker calls a configuration self-colliding exactly when some checked pair's
  // spheres overlap.
  const SelfCollisionComparison r = CompareSelfCollision(file_, Ur5Folder(), 3000);
  EXPECT_EQ(r.missed, 0) << "the deepest overlap missed: " << r.deepest_missed << " m";
  EXPECT_EQ(r.unexplained, 0);
  EXPECT_EQ(r.checker_disagrees, 0);
  // Enough of both for the checks to mean something.
  EXPECT_GE(r.geometry_overlaps, 300) << r.geometry_overlaps;
  EXPECT_GE(r.sphere_overlaps, 300) << r.sphere_overlaps;
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
