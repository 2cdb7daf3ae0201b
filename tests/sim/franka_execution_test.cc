#include "sim/franka_execution.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "sim/franka_ik.h"

namespace flowplan::sim {
namespace {

constexpr double kDt = 1.0 / 15.0;

/// A plan (T, 14) from q0 to q1 with a smooth (cosine) time profile and consistent velocities.
std::vector<double> SmoothMove(const JointVector& q0, const JointVector& q1, int T) {
  std::vector<double> plan(static_cast<size_t>(T * 14));
  const double duration = (T - 1) * kDt;
  for (int t = 0; t < T; ++t) {
    const double s = 0.5 - 0.5 * std::cos(M_PI * t / (T - 1));
    const double ds = 0.5 * M_PI / duration * std::sin(M_PI * t / (T - 1));
    for (int j = 0; j < 7; ++j) {
      plan[t * 14 + j] = q0[j] + s * (q1[j] - q0[j]);
      plan[t * 14 + 7 + j] = ds * (q1[j] - q0[j]);
    }
  }
  return plan;
}

class FrankaExecutionTest : public ::testing::Test {
 protected:
  JointVector Ik(const Eigen::Vector3d& target) {
    MjDataPtr d = MakeData(model_.mj());
    return SolveTcpIkOrThrow(model_, *d, target, FrankaReadyPose());
  }
  Eigen::Vector3d Tcp(const JointVector& q) {
    MjDataPtr d = MakeData(model_.mj());
    return FrankaForwardKinematics(model_, *d, q).tcp_position;
  }
  FrankaModel model_ = LoadFrankaModel();
  ExecutionConfig config_;
};

TEST_F(FrankaExecutionTest, TracksASmoothMoveToTheGoalWithoutObstacles) {
  const JointVector q0 = Ik({0.5, -0.3, 0.3}), q1 = Ik({0.5, 0.3, 0.3});
  const FrankaModel scene = MakeFrankaScene({}, 1.0 / config_.control_hz);
  FrankaExecutor executor(scene, 0, config_);
  const ExecutionResult r = executor.Execute(SmoothMove(q0, q1, 64), 64, kDt, Tcp(q1));
  EXPECT_EQ(r.num_states, 64 + 15);
  EXPECT_LT(r.goal_distance, 2e-3);
  EXPECT_LT(r.max_tracking_error, 0.02);
  EXPECT_TRUE(r.contacts.empty());
  EXPECT_EQ(r.warnings, 0);
  // The recorded TCP follows the plan's: state 32 is half-way along y.
  EXPECT_NEAR(r.tcp[32 * 3 + 1], Tcp(Eigen::Map<const JointVector>(&SmoothMove(q0, q1, 64)[32 * 14]))[1], 0.01);
}

TEST_F(FrankaExecutionTest, TheComputedTorqueLawTracksTheSameMoveOnTheModelsOwnInertia) {
  const JointVector q0 = Ik({0.5, -0.3, 0.3}), q1 = Ik({0.5, 0.3, 0.3});
  ExecutionConfig config = config_;
  config.controller = TrackingLaw::kComputedTorque;
  const FrankaModel scene = MakeFrankaScene({}, 1.0 / config.control_hz);
  FrankaExecutor pd(scene, 0, config_), computed(scene, 0, config);
  const ExecutionResult by_pd = pd.Execute(SmoothMove(q0, q1, 64), 64, kDt, Tcp(q1));
  const ExecutionResult by_model = computed.Execute(SmoothMove(q0, q1, 64), 64, kDt, Tcp(q1));
  // Feedforward on the arm's own mass matrix leaves only the spline's and the integrator's errors.
  EXPECT_LT(by_model.max_tracking_error, 1e-3);
  EXPECT_LT(by_model.max_tracking_error, 0.2 * by_pd.max_tracking_error);
  EXPECT_LT(by_model.goal_distance, 1e-4);
}

TEST_F(FrankaExecutionTest, APlanThroughAnObstacleMakesContactAndFarOnesDoNot) {
  const JointVector q0 = Ik({0.5, -0.3, 0.2}), q1 = Ik({0.5, 0.3, 0.2});
  geometry::Scene obstacles;
  obstacles.spheres = {{{0.5, 0.0, 0.2}, 0.1}, {{-0.6, 0.0, 0.3}, 0.1}};
  const FrankaModel scene = MakeFrankaScene(obstacles, 1.0 / config_.control_hz);
  FrankaExecutor executor(scene, 2, config_);
  const ExecutionResult r = executor.Execute(SmoothMove(q0, q1, 64), 64, kDt, Tcp(q1));
  ASSERT_FALSE(r.contacts.empty());
  for (const ContactEvent& c : r.contacts) {
    EXPECT_EQ(c.obstacle, 0) << c.arm_geom;
    EXPECT_GT(c.max_depth, 0.0);
    EXPECT_LE(c.first_time, c.last_time);
  }
  EXPECT_LT(r.min_distance[0], 0.0);
  EXPECT_GT(r.min_distance[1], 0.3);  // behind the robot
}

TEST_F(FrankaExecutionTest, EveryShapeIsACollisionGeomOfItsOwn) {
  // Each shape astride the straight move from (0.5, -0.3, 0.2) to (0.5, 0.3, 0.2)
  // makes contact; the same shape 0.8 m higher does not.
  const JointVector q0 = Ik({0.5, -0.3, 0.2}), q1 = Ik({0.5, 0.3, 0.2});
  const std::vector<double> plan = SmoothMove(q0, q1, 64);
  const double s = std::sqrt(0.5);
  for (double lift : {0.0, 0.8}) {
    geometry::Scene scene;
    scene.boxes.push_back({{0.5, 0.0, 0.2 + lift}, {0.1, 0.1, 0.1}, {s, 0.0, 0.0, s}, NAN});
    scene.cylinders.push_back({{0.5, 0.0, 0.2 + lift}, 0.05, 0.2, {s, 0.0, s, 0.0}, NAN});  // axis along x
    scene.capsules.push_back({{0.45, -0.05, 0.2 + lift}, {0.55, -0.05, 0.2 + lift}, 0.03});
    for (int k = 0; k < 3; ++k) {
      geometry::Scene one;
      if (k == 0) one.boxes = scene.boxes;
      if (k == 1) one.cylinders = scene.cylinders;
      if (k == 2) one.capsules = scene.capsules;
      const FrankaModel world = MakeFrankaScene(one, 1.0 / config_.control_hz);
      FrankaExecutor executor(world, 1, config_);
      const ExecutionResult r = executor.Execute(plan, 64, kDt, Tcp(q1));
      EXPECT_EQ(r.contacts.empty(), lift > 0) << "shape " << k << " lifted " << lift;
      if (lift > 0) {
        EXPECT_GT(r.min_distance[0], 0.2) << "shape " << k;
      } else {
        EXPECT_LT(r.min_distance[0], 0.0) << "shape " << k;
      }
    }
  }
}

TEST_F(FrankaExecutionTest, ACylinderTheArmPassesCloseToIsNotTouched) {
  // A bar along y at (0.5, 0.05, 0.2), r = 0.04: the straight joint-space move
  // passes it 3 mm to 27 mm away (the arm's collision spheres, by hand from
  // their centres). MuJoCo's convex solver, measuring the shapes grown by the
  // execution model's 0.5 m margin, reported overlaps of up to 5 cm here; the
  // model must report none, as MuJoCo does with no margin at all.
  const JointVector q0 = Ik({0.5, -0.3, 0.2}), q1 = Ik({0.5, 0.3, 0.2});
  const double s = std::sqrt(0.5);
  geometry::Scene bar;
  bar.cylinders.push_back({{0.5, 0.05, 0.2}, 0.04, 0.2, {s, s, 0.0, 0.0}, NAN});
  const FrankaModel world = MakeFrankaScene(bar, 1.0 / config_.control_hz);
  MjModelPtr exact_model = CopyModel(world.mj());
  for (int g = 0; g < exact_model->ngeom; ++g) exact_model->geom_margin[g] = exact_model->geom_gap[g] = 0.0;
  auto d = MakeData(world.mj());
  auto exact = MakeData(*exact_model);
  double nearest = INFINITY;
  for (int i = 0; i <= 20; ++i) {
    const JointVector q = q0 + (q1 - q0) * (i / 20.0);
    for (int j = 0; j < kFrankaJoints; ++j) d->qpos[j] = exact->qpos[j] = q[j];
    mj_forward(&world.mj(), d.get());
    mj_forward(exact_model.get(), exact.get());
    EXPECT_EQ(exact->ncon, 0) << "state " << i;
    for (int c = 0; c < d->ncon; ++c) {
      EXPECT_GE(d->contact[c].dist, 0.0) << "state " << i;
      nearest = std::min(nearest, static_cast<double>(d->contact[c].dist));
    }
  }
  // Reported as near: 0 where the grown shapes' solver claimed an overlap that
  // the exact check rejects (a lower bound of the 3 mm or more, not a distance).
  EXPECT_LT(nearest, 0.05);
}

TEST_F(FrankaExecutionTest, DistancesAreThoseOfTheCapsules) {
  // Holding the ready pose, with an obstacle 5 cm below the TCP: the fingers'
  // capsules reach to about the TCP, so the distance is close to 5 cm minus the radius.
  const JointVector q = FrankaReadyPose();
  const Eigen::Vector3d tcp = Tcp(q);
  const Eigen::Vector3d below = tcp - Eigen::Vector3d(0, 0, 0.15);
  geometry::Scene obstacles;
  obstacles.spheres = {{{below.x(), below.y(), below.z()}, 0.1}};
  // A box whose top face is 5 cm below the TCP, measured by MuJoCo's box collider.
  obstacles.boxes = {{{below.x(), below.y(), below.z() - 0.1}, {0.4, 0.4, 0.2}, {}, NAN}};
  const FrankaModel scene = MakeFrankaScene(obstacles, 1.0 / config_.control_hz);
  FrankaExecutor executor(scene, 2, config_);
  const ExecutionResult r = executor.Execute(SmoothMove(q, q, 8), 8, kDt, tcp);
  EXPECT_NEAR(r.min_distance[0], 0.05, 0.02);
  EXPECT_NEAR(r.min_distance[1], r.min_distance[0], 1e-3);
  EXPECT_TRUE(r.contacts.empty());
  EXPECT_LT(r.goal_distance, 1e-3);
}

TEST(SmoothPlanTest, FiltersKeepLinesAndEnds) {
  const int T = 9;
  std::vector<double> line(T * 14), bumpy(T * 14);
  for (int t = 0; t < T; ++t) {
    for (int i = 0; i < 14; ++i) {
      line[t * 14 + i] = 0.1 * t + i;
      bumpy[t * 14 + i] = (t % 2 == 0 ? 1.0 : -1.0);
    }
  }
  for (PlanSmoothing s : {PlanSmoothing::kMovingAverage, PlanSmoothing::kSavitzkyGolay}) {
    const std::vector<double> out = SmoothPlan(line, T, 14, s, 5);
    for (size_t k = 0; k < out.size(); ++k) EXPECT_NEAR(out[k], line[k], 1e-12);
    const std::vector<double> smooth = SmoothPlan(bumpy, T, 14, s, 5);
    EXPECT_EQ(smooth[0], 1.0);
    EXPECT_EQ(smooth[(T - 1) * 14], 1.0);
    EXPECT_LT(std::abs(smooth[4 * 14]), 1.0);
  }
  // A parabola passes the quadratic Savitzky–Golay filter unchanged.
  std::vector<double> parabola(T * 14);
  for (int t = 0; t < T; ++t) {
    for (int i = 0; i < 14; ++i) parabola[t * 14 + i] = 0.3 * t * t - t;
  }
  const std::vector<double> out = SmoothPlan(parabola, T, 14, PlanSmoothing::kSavitzkyGolay, 5);
  for (size_t k = 0; k < out.size(); ++k) EXPECT_NEAR(out[k], parabola[k], 1e-9);
  ExecutionConfig even;
  even.smoothing_window = 4;
  EXPECT_THAT([&] { even.Validate(); }, ::testing::ThrowsMessage<Error>(::testing::HasSubstr("execute.smoothing_window")));
}

}  // namespace
}  // namespace flowplan::sim
