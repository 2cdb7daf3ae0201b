#include "sim/franka_joint_motion.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "sim/franka_rollout.h"
#include "sim/franka_self_collision.h"

namespace flowplan::sim {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

JointVector Vector(std::initializer_list<double> values) {
  JointVector v;
  int i = 0;
  for (double x : values) v[i++] = x;
  return v;
}

TEST(MinimumJerkMotionTest, RestToRestWithTheClosedFormPeakAndDerivativesThatMatchDifferences) {
  const JointVector from = Vector({0.1, -0.5, 0.3, -2.0, 0.0, 1.5, 0.7});
  const JointVector to = Vector({-1.2, 0.4, 0.9, -1.0, 1.0, 2.5, -0.3});
  const MinimumJerkMotion motion(from, to, 2.0);
  JointVector p, v, a;
  motion.Sample(0.0, &p, &v, &a);
  EXPECT_LT((p - from).norm(), 1e-15);
  EXPECT_EQ(v.norm(), 0.0);
  motion.Sample(2.0, &p, &v, &a);
  EXPECT_LT((p - to).norm(), 1e-15);
  EXPECT_EQ(v.norm(), 0.0);
  motion.Sample(3.0, &p, &v, &a);  // held after the end
  EXPECT_LT((p - to).norm(), 1e-15);
  // Peak speed at the middle: 15/8 of the mean speed; zero acceleration there.
  motion.Sample(1.0, &p, &v, &a);
  EXPECT_LT((v - 15.0 / 8.0 * (to - from) / 2.0).norm(), 1e-12);
  EXPECT_LT(a.norm(), 1e-12);
  EXPECT_LT((p - 0.5 * (from + to)).norm(), 1e-12);
  // Central differences of the position and velocity.
  const double h = 1e-6;
  for (double t : {0.3, 0.77, 1.4, 1.9}) {
    JointVector p1, v1, a1, p2, v2, a2;
    motion.Sample(t, &p, &v, &a);
    motion.Sample(t - h, &p1, &v1, &a1);
    motion.Sample(t + h, &p2, &v2, &a2);
    EXPECT_LT(((p2 - p1) / (2 * h) - v).norm(), 1e-7) << "t = " << t;
    EXPECT_LT(((v2 - v1) / (2 * h) - a).norm(), 1e-6) << "t = " << t;
  }
}

TEST(MinimumJerkMotionTest, DurationPutsThePeakOfTheBindingJointAtItsShareOfTheLimit) {
  const FrankaModel model = LoadFrankaModel();
  const JointVector& limit = model.limits().velocity;
  JointMotionConfig config;
  config.speed_share = 0.5;
  config.min_duration = 0.1;
  const JointVector from = JointVector::Zero();
  const JointVector to = Vector({0.2, 0.1, 0.0, -0.3, 2.0, 0.5, 0.0});  // joint 5 binds
  const double duration = MinimumJerkMotion::Duration(from, to, limit, config);
  EXPECT_NEAR(duration, 15.0 / 8.0 * 2.0 / (0.5 * limit[4]), 1e-12);
  JointVector p, v, a;
  MinimumJerkMotion(from, to, duration).Sample(duration / 2, &p, &v, &a);
  EXPECT_NEAR(std::abs(v[4]), 0.5 * limit[4], 1e-12);
  for (int j = 0; j < 7; ++j) EXPECT_LE(std::abs(v[j]), 0.5 * limit[j] + 1e-12);
  // A short motion takes min_duration.
  config.min_duration = 1.5;
  EXPECT_EQ(MinimumJerkMotion::Duration(from, 0.01 * to, limit, config), 1.5);
}

TEST(JointTrackingTest, NoiseFreeTrackingFollowsTheReferenceAndEndsAtTheGoal) {
  FrankaRolloutConfig config;
  FrankaModel model = LoadFrankaModel();
  model.SetPhysics(config.physics_timestep(), config.integrator);
  const JointVector from = Vector({-1.0, -0.3, 0.5, -2.2, 0.4, 1.8, 0.2});
  const JointVector to = Vector({1.2, 0.5, -0.4, -1.4, -0.8, 2.4, 1.5});
  JointMotionConfig motion_config;
  const double duration = MinimumJerkMotion::Duration(from, to, model.limits().velocity, motion_config);
  ASSERT_LT(duration, 3.8);
  const MinimumJerkMotion motion(from, to, duration);
  FrankaSimulator simulator(model, config);
  FrankaEpisode episode;
  Rng rng(3);
  simulator.RolloutJoints(motion, motion_config, FrankaSimulator::StateCheck(), Augmentation::kNone, rng, &episode);
  ASSERT_FALSE(episode.rejected) << episode.reject_reason;
  EXPECT_EQ(episode.warnings, 0);
  for (int t = 0; t < 64; ++t) {
    JointVector p, v, a;
    motion.Sample(t * config.record_dt(), &p, &v, &a);
    const Eigen::Map<const JointVector> q(&episode.states[14 * t]);
    // The torque is held between 30 Hz control steps: a lag of a few mrad.
    EXPECT_LT((q - p).cwiseAbs().maxCoeff(), 5e-3) << "state " << t;
  }
  const Eigen::Map<const JointVector> last(&episode.states[14 * 63]), last_speed(&episode.states[14 * 63 + 7]);
  EXPECT_LT((last - to).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_LT(last_speed.cwiseAbs().maxCoeff(), 1e-2);
}

TEST(JointTrackingTest, TheStateCheckRejectsTheEpisodeWithItsReason) {
  FrankaRolloutConfig config;
  FrankaModel model = LoadFrankaModel();
  model.SetPhysics(config.physics_timestep(), config.integrator);
  const JointVector from = FrankaReadyPose(), to = FrankaReadyPose() + Vector({1.0, 0, 0, 0, 0, 0, 0});
  const MinimumJerkMotion motion(from, to, 2.0);
  FrankaSimulator simulator(model, config);
  FrankaEpisode episode;
  Rng rng(3);
  int calls = 0;
  const FrankaSimulator::StateCheck check = [&](const JointVector& q) {
    ++calls;
    return q[0] > from[0] + 0.5 ? std::string("collision test") : std::string();
  };
  simulator.RolloutJoints(motion, JointMotionConfig{}, check, Augmentation::kPerJointNoise, rng, &episode);
  EXPECT_TRUE(episode.rejected);
  EXPECT_THAT(episode.reject_reason, StartsWith("collision test at t = "));
  EXPECT_GT(calls, 10);
  EXPECT_LT(calls, 63 * 2);
}

// An independent capsule distance: closest points of two segments (Ericson,
// Real-Time Collision Detection, 5.1.9), from the geoms' poses in MuJoCo.
double SegmentDistance(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1, const Eigen::Vector3d& p2,
                       const Eigen::Vector3d& q2) {
  const Eigen::Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a < 1e-15 && e < 1e-15) return r.norm();
  if (a < 1e-15) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e < 1e-15) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 1e-15 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p1 + s * d1) - (p2 + t * d2)).norm();
}

TEST(FrankaCollisionTest, AgreesWithCapsuleDistancesAndTheFloorComputedByHand) {
  const FrankaCollisionModel collision_model(0.0);
  FrankaCollisionChecker checker(collision_model);
  EXPECT_EQ(checker.FirstCollision(FrankaReadyPose()), "");

  // The reference: the capsules' segments from MuJoCo's kinematics, distances by hand.
  const FrankaModel model = LoadFrankaModel();
  const mjModel& m = model.mj();
  MjDataPtr d = MakeData(m);
  const int link0 = mj_name2id(&m, mjOBJ_BODY, "link0"), link1 = mj_name2id(&m, mjOBJ_BODY, "link1");
  const int link5 = mj_name2id(&m, mjOBJ_BODY, "link5"), link7 = mj_name2id(&m, mjOBJ_BODY, "link7");
  std::mt19937_64 random(11);
  int self = 0, floor = 0, clear = 0, borderline = 0;
  for (int n = 0; n < 400; ++n) {
    JointVector q;
    for (int j = 0; j < 7; ++j) {
      q[j] = std::uniform_real_distribution<double>(model.limits().q_lower[j], model.limits().q_upper[j])(random);
    }
    for (int j = 0; j < 7; ++j) d->qpos[j] = q[j];
    mj_kinematics(&m, d.get());
    double deepest = INFINITY, lowest = INFINITY;
    for (int g1 = 0; g1 < m.ngeom; ++g1) {
      if (m.geom_group[g1] != kCollisionGeomGroup) continue;
      auto segment = [&](int g, Eigen::Vector3d* a, Eigen::Vector3d* b) {
        const Eigen::Vector3d centre(d->geom_xpos[3 * g], d->geom_xpos[3 * g + 1], d->geom_xpos[3 * g + 2]);
        const Eigen::Vector3d axis(d->geom_xmat[9 * g + 2], d->geom_xmat[9 * g + 5], d->geom_xmat[9 * g + 8]);
        const double half = m.geom_type[g] == mjGEOM_CAPSULE ? m.geom_size[3 * g + 1] : 0.0;
        *a = centre - half * axis;
        *b = centre + half * axis;
      };
      Eigen::Vector3d a1, b1;
      segment(g1, &a1, &b1);
      const int body1 = m.geom_bodyid[g1];
      if (body1 != link0 && body1 != link1) lowest = std::min(lowest, std::min(a1.z(), b1.z()) - m.geom_size[3 * g1]);
      for (int g2 = g1 + 1; g2 < m.ngeom; ++g2) {
        const int body2 = m.geom_bodyid[g2];
        if (m.geom_group[g2] != kCollisionGeomGroup || body1 == body2) continue;
        // MuJoCo's parent filter, on bodies welded together: the hand and fingers move with link7.
        const int weld1 = m.body_weldid[body1], weld2 = m.body_weldid[body2];
        if (weld1 == weld2 || m.body_parentid[weld1] == weld2 || m.body_parentid[weld2] == weld1) continue;
        auto pair = [&](int x, int y) { return (body1 == x && body2 == y) || (body1 == y && body2 == x); };
        if (pair(link0, link1) || pair(link5, link7)) continue;
        Eigen::Vector3d a2, b2;
        segment(g2, &a2, &b2);
        deepest = std::min(deepest, SegmentDistance(a1, b1, a2, b2) - m.geom_size[3 * g1] - m.geom_size[3 * g2]);
      }
    }
    const std::string verdict = checker.FirstCollision(q);
    if (std::abs(deepest) < 1e-6 || std::abs(lowest) < 1e-6) {
      ++borderline;
      continue;
    }
    if (deepest < 0) {
      ++self;
      EXPECT_FALSE(verdict.empty() || verdict.rfind("floor-", 0) == 0) << "overlap " << deepest << " missed at n = " << n;
    } else if (lowest < 0) {
      ++floor;
      EXPECT_THAT(verdict, StartsWith("floor-")) << "lowest point " << lowest << " at n = " << n;
    } else {
      ++clear;
      EXPECT_EQ(verdict, "") << "n = " << n;
    }
  }
  // The sample holds every kind of case.
  EXPECT_GT(self, 10);
  EXPECT_GT(floor, 10);
  EXPECT_GT(clear, 100);
  EXPECT_EQ(borderline, 0);

  // Without a floor nothing is found below it.
  const FrankaCollisionModel no_floor(-INFINITY);
  FrankaCollisionChecker free_checker(no_floor);
  JointVector down = FrankaReadyPose();
  down[1] = 1.7;  // shoulder forward past horizontal: the hand goes below the base
  down[3] = -0.1;
  EXPECT_THAT(checker.FirstCollision(down), HasSubstr("floor-"));
  EXPECT_EQ(free_checker.FirstCollision(down).rfind("floor-", 0), std::string::npos);
}

}  // namespace
}  // namespace flowplan::sim
