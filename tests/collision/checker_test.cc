// flowplan's one validity check (collision/) against references that share
// no code with it: MuJoCo's kinematics for the body's placement, the
// TorchScript distances of geometry/ for the obstacles, brute force over every
// sphere and obstacle for the screened checks, and dense sampling for the
// certified motion check.

#include "collision/checker.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/random.h"
#include "jit/library.h"
#include "kinematics/robot.h"
#include "sim/franka_model.h"
#include "sim/mujoco_util.h"

namespace flowplan::collision {
namespace {

using ::testing::HasSubstr;

const sim::FrankaModel& Model() {
  static const sim::FrankaModel model = sim::LoadFrankaModel();
  return model;
}

std::shared_ptr<const BodyModel> Franka() {
  static const auto body = std::make_shared<const BodyModel>(Model().description());
  return body;
}

std::vector<double> RandomQ(Rng& rng) {
  const auto& d = Model().description();
  std::vector<double> q(7);
  for (int j = 0; j < 7; ++j) q[j] = rng.Uniform(d.joint_lower[j], d.joint_upper[j]);
  return q;
}

/// A scene of every kind in front of the arm, some of it turned.
geometry::Scene Clutter() {
  geometry::Scene scene;
  scene.spheres.push_back({{0.45, 0.2, 0.5}, 0.08});
  scene.boxes.push_back({{0.55, -0.25, 0.3}, {0.2, 0.1, 0.3}, {0.9238795, 0.0, 0.0, 0.3826834}, NAN});
  scene.boxes.push_back({{0.4, 0.0, 0.05}, {0.6, 1.0, 0.04}, {}, NAN});
  scene.cylinders.push_back({{0.3, 0.45, 0.35}, 0.05, 0.4, {0.9659258, 0.258819, 0.0, 0.0}, NAN});
  scene.capsules.push_back({{-0.3, -0.4, 0.6}, {-0.1, -0.5, 0.9}, 0.05});
  return scene;
}

/// Every sphere's clearance from every obstacle (S, K), by the TorchScript distances on the script kinematics'
/// sphere centres: what the checker's screened loops must agree with.
torch::Tensor BruteClearances(const std::vector<double>& q, const geometry::SceneRows& rows) {
  static const kinematics::Robot robot(Model().description());
  const torch::Tensor centres = robot.SphereCentres(torch::tensor(q, torch::kFloat64).view({1, 7}))[0];  // (S, 3)
  const torch::Tensor distances =
      jit::CallFunction("scene_distance_only", {centres, rows}).toTensor();  // (S, K)
  return distances - robot.SphereRadii().unsqueeze(1);
}

TEST(BodyModelTest, PlacesTheTcpAndSpheresAsMujocoAndTheScriptsDo) {
  const BodyModel& body = *Franka();
  const kinematics::Robot robot(Model().description());
  const mjModel& m = Model().mj();
  sim::MjDataPtr d = sim::MakeData(m);
  Rng rng(3);
  std::vector<Frame> frames(static_cast<size_t>(body.num_links()));
  std::vector<double> centres(static_cast<size_t>(3 * body.num_spheres()));
  for (int trial = 0; trial < 50; ++trial) {
    const std::vector<double> q = RandomQ(rng);
    for (int j = 0; j < 7; ++j) d->qpos[j] = q[j];
    mj_kinematics(&m, d.get());
    double tcp[3];
    body.Tcp(q.data(), tcp);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(tcp[i], d->site_xpos[3 * Model().tcp_site() + i], 1e-12);
    body.Place(q.data(), frames.data(), centres.data());
    for (int l = 0; l < body.num_links(); ++l) {
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(frames[l].p[i], d->xpos[3 * (l + 1) + i], 1e-12);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(frames[l].R[3 * i + k], d->xmat[9 * (l + 1) + 3 * i + k], 1e-12);
      }
    }
    const torch::Tensor script = robot.SphereCentres(torch::tensor(q, torch::kFloat64).view({1, 7}))[0];
    for (int s = 0; s < body.num_spheres(); ++s) {
      const int original = body.description_sphere(s);
      EXPECT_EQ(body.sphere_radius(s), robot.description().spheres[original].radius);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(centres[3 * s + i], script[original][i].item<double>(), 1e-12);
    }
  }
}

TEST(BodyModelTest, AHeldFingerSlidesAlongItsAxis) {
  const auto& robot = Model().description();
  const BodyModel closed(robot);
  const BodyModel open(WithHeld(robot, {{"panda_finger_joint1", 0.04}, {"panda_finger_joint2", 0.04}}));
  const std::vector<double> q = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  std::vector<Frame> f0(static_cast<size_t>(closed.num_links())), f1(f0.size());
  std::vector<double> c0(static_cast<size_t>(3 * closed.num_spheres())), c1(c0.size());
  closed.Place(q.data(), f0.data(), c0.data());
  open.Place(q.data(), f1.data(), c1.data());
  const int left = robot.FindLink("left_finger"), right = robot.FindLink("right_finger");
  double gap0 = 0.0, gap1 = 0.0;
  for (int i = 0; i < 3; ++i) {
    gap0 += std::pow(f0[left].p[i] - f0[right].p[i], 2);
    gap1 += std::pow(f1[left].p[i] - f1[right].p[i], 2);
  }
  EXPECT_NEAR(std::sqrt(gap0), 0.0, 1e-12);
  EXPECT_NEAR(std::sqrt(gap1), 0.08, 1e-12);  // each 4 cm out, opposite ways
  EXPECT_THAT([&] { WithHeld(robot, {{"panda_joint3", 0.1}}); },
              ::testing::ThrowsMessage<Error>(HasSubstr("held joint panda_joint3: robot \"franka_panda\" plans it")));
  EXPECT_THAT([&] { WithHeld(robot, {{"gripper", 0.1}}); },
              ::testing::ThrowsMessage<Error>(HasSubstr("held joint gripper: robot \"franka_panda\" has no such joint")));
}

TEST(BodyModelTest, TravelBoundsHoldAlongRandomSegments) {
  const BodyModel& body = *Franka();
  Rng rng(5);
  std::vector<Frame> frames(static_cast<size_t>(body.num_links()));
  std::vector<double> a(static_cast<size_t>(3 * body.num_spheres())), c(a.size());
  for (int trial = 0; trial < 100; ++trial) {
    const std::vector<double> qa = RandomQ(rng), qb = RandomQ(rng);
    body.Place(qa.data(), frames.data(), a.data());
    for (int k = 1; k <= 20; ++k) {
      std::vector<double> q(7);
      for (int j = 0; j < 7; ++j) q[j] = qa[j] + k / 20.0 * (qb[j] - qa[j]);
      body.Place(q.data(), frames.data(), c.data());
      for (int s = 0; s < body.num_spheres(); ++s) {
        double moved = 0.0, bound = 0.0;
        for (int i = 0; i < 3; ++i) moved += std::pow(c[3 * s + i] - a[3 * s + i], 2);
        for (int j = 0; j < 7; ++j) bound += body.sphere_travel(s)[j] * std::abs(q[j] - qa[j]);
        EXPECT_LE(std::sqrt(moved), bound + 1e-12) << "sphere " << s;
      }
    }
  }
}

TEST(BodyModelTest, TheStaticTravelBoundIsNeverBelowTheTightOneAndHoldsAlongRandomSegments) {
  // What the motion check screens with first: it must bound every sphere's motion on the link, and never be
  // tighter than Travel (a piece the static bound certifies, the tight one certifies too).
  const BodyModel& body = *Franka();
  const int L = body.num_links(), J = body.num_joints();
  Rng rng(6);
  std::vector<Frame> frames(static_cast<size_t>(L));
  std::vector<double> a(static_cast<size_t>(3 * body.num_spheres())), c(a.size());
  std::vector<double> axes(static_cast<size_t>(3 * J)), points(axes.size());
  std::vector<double> bounds(static_cast<size_t>(3 * L)), clusters(static_cast<size_t>(3 * body.num_clusters()));
  for (int trial = 0; trial < 100; ++trial) {
    const std::vector<double> qa = RandomQ(rng), qb = RandomQ(rng);
    std::vector<double> dq(static_cast<size_t>(J));
    for (int j = 0; j < J; ++j) dq[static_cast<size_t>(j)] = std::abs(qb[j] - qa[j]);
    body.Place(qa.data(), frames.data(), a.data());
    body.JointAxes(frames.data(), axes.data(), points.data());
    body.PlaceBounds(qa.data(), frames.data(), bounds.data(), clusters.data());
    for (int l = 0; l < L; ++l) {
      if (body.bound_radius(l) < 0) continue;
      const uint64_t mask = body.ancestor_joints(l);
      const double static_bound = body.StaticTravel(l, mask, dq.data());
      EXPECT_LE(body.Travel(l, mask, dq.data(), axes.data(), points.data(), &bounds[static_cast<size_t>(3 * l)]),
                static_bound + 1e-12) << "link " << l;
      for (int k = 1; k <= 20; ++k) {
        std::vector<double> q(7);
        for (int j = 0; j < 7; ++j) q[j] = qa[j] + k / 20.0 * (qb[j] - qa[j]);
        body.Place(q.data(), frames.data(), c.data());
        for (int s = body.first_sphere(l); s < body.first_sphere(l + 1); ++s) {
          double moved = 0.0;
          for (int i = 0; i < 3; ++i) moved += std::pow(c[3 * s + i] - a[3 * s + i], 2);
          EXPECT_LE(std::sqrt(moved), static_bound + 1e-12) << "link " << l << ", sphere " << s;
        }
      }
      body.Place(qa.data(), frames.data(), a.data());
    }
  }
}

TEST(BodyModelTest, LinkAndClusterTravelBoundsHoldFromEitherEndForAnySetOfJoints) {
  // What the motion check certifies with: along a segment, no sphere centre of link l moves (through the joints
  // of a mask, the others held) farther from where it is at either end than Travel of the link's bounding
  // sphere, nor than Travel of its cluster's bounding sphere, measured at that end.
  const BodyModel& body = *Franka();
  const int L = body.num_links(), J = body.num_joints(), S = body.num_spheres();
  Rng rng(61);
  std::vector<Frame> frames(static_cast<size_t>(L));
  std::vector<double> c(static_cast<size_t>(3 * S));
  int tighter = 0, compared = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const std::vector<double> qa = RandomQ(rng), qb = RandomQ(rng);
    const uint64_t mask = trial % 3 == 0 ? ~uint64_t{0} : (rng.NextU64() & ((uint64_t{1} << J) - 1));
    std::vector<double> dq(static_cast<size_t>(J));
    for (int j = 0; j < J; ++j) dq[static_cast<size_t>(j)] = (mask >> j & 1) ? std::abs(qb[j] - qa[j]) : 0.0;
    // The segment moves only the mask's joints: from qa towards qb in those, qa's values in the others.
    std::vector<double> qe = qa;
    for (int j = 0; j < J; ++j) {
      if (mask >> j & 1) qe[static_cast<size_t>(j)] = qb[j];
    }
    std::vector<std::vector<double>> samples;
    for (int k = 0; k <= 40; ++k) {
      std::vector<double> q(static_cast<size_t>(J));
      for (int j = 0; j < J; ++j) q[j] = qa[j] + k / 40.0 * (qe[j] - qa[j]);
      body.Place(q.data(), frames.data(), c.data());
      samples.push_back(c);
    }
    for (const std::vector<double>* end_q : {&qa, static_cast<const std::vector<double>*>(&qe)}) {
      const std::vector<double>& end = end_q == &qa ? samples.front() : samples.back();
      std::vector<double> axes(static_cast<size_t>(3 * J)), points(axes.size());
      std::vector<double> bounds(static_cast<size_t>(3 * L)), clusters(static_cast<size_t>(3 * body.num_clusters()));
      body.Place(end_q->data(), frames.data(), c.data());
      body.JointAxes(frames.data(), axes.data(), points.data());
      body.PlaceBounds(end_q->data(), frames.data(), bounds.data(), clusters.data());
      for (int l = 0; l < L; ++l) {
        if (body.bound_radius(l) < 0) continue;
        const uint64_t joints = mask & body.ancestor_joints(l);
        const double link_travel =
            body.Travel(l, joints, dq.data(), axes.data(), points.data(), &bounds[static_cast<size_t>(3 * l)]);
        for (int cl = body.first_cluster(l); cl < body.first_cluster(l + 1); ++cl) {
          const double cluster_travel = body.Travel(l, joints, dq.data(), axes.data(), points.data(),
                                                    &clusters[static_cast<size_t>(3 * cl)], body.cluster_radius(cl));
          ++compared;
          tighter += cluster_travel < link_travel - 1e-9;
          for (int s = body.first_in_cluster(cl); s < body.first_in_cluster(cl + 1); ++s) {
            for (const std::vector<double>& at : samples) {
              double moved = 0.0;
              for (int i = 0; i < 3; ++i) moved += std::pow(at[3 * s + i] - end[3 * s + i], 2);
              ASSERT_LE(std::sqrt(moved), link_travel + 1e-12) << "trial " << trial << ", link " << l << ", sphere " << s;
              ASSERT_LE(std::sqrt(moved), cluster_travel + 1e-12)
                  << "trial " << trial << ", cluster " << cl << ", sphere " << s;
            }
          }
        }
      }
    }
  }
  // The cluster bound is worth having: tighter than its link's for many clusters.
  EXPECT_GT(tighter, compared / 4) << tighter << " of " << compared;
}

TEST(WorldTest, DistancesAreTheScriptsAndTheBoundsAreBelowThem) {
  const geometry::Scene scene = Clutter();
  const geometry::SceneRows rows = geometry::Rows(scene, 3, "test");
  const World world(rows, 3);
  ASSERT_EQ(world.size(), 5);
  Rng rng(7);
  torch::Tensor points = torch::empty({400, 3}, torch::kFloat64);
  for (int n = 0; n < 400; ++n) {
    for (int i = 0; i < 3; ++i) points[n][i] = rng.Uniform(-0.6, 1.0);
  }
  const torch::Tensor script = jit::CallFunction("scene_distance_only", {points, rows}).toTensor();  // (400, K)
  for (int n = 0; n < 400; ++n) {
    const double p[3] = {points[n][0].item<double>(), points[n][1].item<double>(), points[n][2].item<double>()};
    for (int k = 0; k < world.size(); ++k) {
      const double d = world.Distance(k, p);
      EXPECT_NEAR(d, script[n][k].item<double>(), 1e-12) << world.obstacle(k).name;
      EXPECT_LE(world.LowerBound(k, p), d + 1e-15) << world.obstacle(k).name;
    }
  }
}

TEST(CheckerTest, ConfigurationsAgreeWithBruteForceOverEverySphereAndObstacle) {
  const geometry::SceneRows rows = geometry::Rows(Clutter(), 3, "test");
  for (const double margin : {0.0, 0.03}) {
    const Checker checker(Franka(), std::make_shared<const World>(rows, 3), {margin, 0.001});
    Rng rng(11);
    int invalid = 0;
    for (int trial = 0; trial < 300; ++trial) {
      const std::vector<double> q = RandomQ(rng);
      const torch::Tensor brute = BruteClearances(q, rows);
      const double smallest = brute.min().item<double>();
      EXPECT_NEAR(checker.Clearance(q.data()), smallest, 1e-12);
      const Contact contact = checker.FirstContact(q.data());
      const bool obstacle_contact = smallest < margin;
      // Self-collision may also object; an obstacle contact must be found whenever brute force finds one.
      if (obstacle_contact) {
        ASSERT_TRUE(contact.found());
        ++invalid;
      }
      if (contact.kind == Contact::Kind::kObstacle) {
        const int s = Franka()->description_sphere(contact.sphere);
        EXPECT_NEAR(contact.distance, brute[s][contact.other].item<double>(), 1e-12);
        EXPECT_LT(contact.distance, margin);
      }
      if (!contact.found()) {
        EXPECT_GE(smallest, margin);
      }
    }
    EXPECT_GT(invalid, 20);  // the scene is in the way of many configurations
  }
}

TEST(CheckerTest, SelfCollisionIsEveryCheckedPairOfSpheresThatOverlap) {
  const BodyModel& body = *Franka();
  const Checker checker(Franka(), std::make_shared<const World>(), {});
  std::vector<std::vector<bool>> checked(static_cast<size_t>(body.num_links()),
                                         std::vector<bool>(static_cast<size_t>(body.num_links()), false));
  for (const auto& [a, b] : body.self_pairs()) checked[a][b] = checked[b][a] = true;
  EXPECT_FALSE(checked[body.description().FindLink("link1")][body.description().FindLink("link2")]);
  EXPECT_TRUE(checked[body.description().FindLink("link1")][body.description().FindLink("hand")]);
  Rng rng(13);
  std::vector<Frame> frames(static_cast<size_t>(body.num_links()));
  std::vector<double> c(static_cast<size_t>(3 * body.num_spheres()));
  int colliding = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const std::vector<double> q = RandomQ(rng);
    body.Place(q.data(), frames.data(), c.data());
    bool overlap = false;
    for (int s = 0; s < body.num_spheres() && !overlap; ++s) {
      for (int t = s + 1; t < body.num_spheres() && !overlap; ++t) {
        if (!checked[body.sphere_link(s)][body.sphere_link(t)]) continue;
        double d2 = 0.0;
        for (int i = 0; i < 3; ++i) d2 += std::pow(c[3 * s + i] - c[3 * t + i], 2);
        overlap = std::sqrt(d2) < body.sphere_radius(s) + body.sphere_radius(t);
      }
    }
    const Contact contact = checker.FirstContact(q.data());
    EXPECT_EQ(contact.found(), overlap);
    if (contact.found()) {
      EXPECT_EQ(contact.kind, Contact::Kind::kSelf);
      ++colliding;
    }
  }
  EXPECT_GT(colliding, 50);  // random configurations fold the arm into itself often
}

TEST(CheckerTest, TheFloorIsChecked) {
  // The ready pose with the shoulder bowed down until the hand goes below the floor.
  Floor floor;
  floor.present = true;
  floor.height = 0.0;
  const Checker with(Franka(), std::make_shared<const World>(geometry::SceneRows(), 3, floor), {});
  const Checker without(Franka(), std::make_shared<const World>(), {});
  const std::vector<double> down = {0.0, 1.7, 0.0, -0.5, 0.0, 3.0, 0.785};
  double tcp[3];
  Franka()->Tcp(down.data(), tcp);
  ASSERT_LT(tcp[2], 0.0);
  EXPECT_TRUE(without.Valid(down.data()));
  const Contact contact = with.FirstContact(down.data());
  EXPECT_EQ(contact.kind, Contact::Kind::kFloor);
  EXPECT_THAT(with.Describe(contact), HasSubstr("from the floor"));
  const std::vector<double> ready = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  EXPECT_TRUE(with.Valid(ready.data()));  // link0 and link1 stand on the floor and are not checked against it
}

TEST(CheckerTest, AMotionCertifiedValidHasNoContactAtAnySampleAndAnInvalidOneNamesOne) {
  const geometry::SceneRows rows = geometry::Rows(Clutter(), 3, "test");
  const double margin = 0.01, resolution = 0.001;
  const Checker checker(Franka(), std::make_shared<const World>(rows, 3), {margin, resolution});
  Rng rng(17);
  int valid = 0, invalid = 0;
  const Checker relaxed(Franka(), std::make_shared<const World>(rows, 3), {margin - 0.5 * resolution, resolution});
  for (int trial = 0; trial < 2000 && (valid < 25 || invalid < 25); ++trial) {
    const std::vector<double> qa = RandomQ(rng);
    std::vector<double> qb = RandomQ(rng);
    for (int j = 0; j < 7; ++j) qb[j] = qa[j] + 0.5 * (qb[j] - qa[j]);
    if (!checker.Valid(qa.data()) || !checker.Valid(qb.data())) continue;
    const MotionVerdict verdict = checker.CheckMotion(qa.data(), qb.data());
    if (verdict.valid) {
      if (valid >= 25) continue;
      ++valid;
      // Dense samples: none comes closer than the margin by more than half the resolution.
      for (int k = 1; k < 400; ++k) {
        std::vector<double> q(7);
        for (int j = 0; j < 7; ++j) q[j] = qa[j] + k / 400.0 * (qb[j] - qa[j]);
        ASSERT_TRUE(relaxed.Valid(q.data())) << "trial " << trial << " sample " << k << ": "
                                             << relaxed.Describe(relaxed.FirstContact(q.data()));
      }
    } else {
      ++invalid;
      std::vector<double> q(7);
      for (int j = 0; j < 7; ++j) q[j] = qa[j] + verdict.fraction * (qb[j] - qa[j]);
      EXPECT_FALSE(checker.Valid(q.data()));
      EXPECT_GT(verdict.fraction, 0.0);
      EXPECT_LT(verdict.fraction, 1.0);
    }
  }
  EXPECT_GE(valid, 25);
  EXPECT_GE(invalid, 25);
}

TEST(CheckerTest, APathIsJudgedAsItsStatesAndThenItsMotionsOneByOne) {
  // CheckPath places each state once; its verdict must be the one of FirstContact on every state in order, then
  // CheckMotion on every consecutive pair in order: the same first failure, contact and configurations checked.
  const geometry::SceneRows rows = geometry::Rows(Clutter(), 3, "test");
  const Checker checker(Franka(), std::make_shared<const World>(rows, 3), {0.01, 0.001});
  Rng rng(23);
  int valid = 0, bad_state = 0, bad_motion = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // 3 to 8 states along a bent line between two random configurations.
    const std::vector<double> qa = RandomQ(rng), qb = RandomQ(rng), bend = RandomQ(rng);
    const int n = 3 + trial % 6;
    std::vector<double> path(static_cast<size_t>(n * 7));
    for (int t = 0; t < n; ++t) {
      const double s = t / (n - 1.0);
      for (int j = 0; j < 7; ++j) {
        path[static_cast<size_t>(t * 7 + j)] =
            qa[j] + s * (qb[j] - qa[j]) + 0.3 * std::sin(M_PI * s) * (bend[j] - 0.5 * (qa[j] + qb[j]));
      }
    }
    if (trial % 50 == 7) path[static_cast<size_t>(2 * 7 + 2)] = std::nan("");
    const PathVerdict verdict = checker.CheckPath(path.data(), n);
    int first_state = -1;
    Contact state_contact;
    for (int t = 0; t < n && first_state < 0; ++t) {
      state_contact = checker.FirstContact(&path[static_cast<size_t>(t * 7)]);
      if (state_contact.found()) first_state = t;
    }
    ASSERT_EQ(verdict.state, first_state) << "trial " << trial;
    if (first_state >= 0) {
      ++bad_state;
      EXPECT_EQ(verdict.state_contact.kind, state_contact.kind);
      EXPECT_EQ(verdict.state_contact.sphere, state_contact.sphere);
      EXPECT_EQ(verdict.state_contact.other, state_contact.other);
      EXPECT_EQ(verdict.motion, -1);
      EXPECT_FALSE(verdict.valid());
      continue;
    }
    int first_motion = -1;
    int64_t checks = 0;
    MotionVerdict motion;
    for (int t = 0; t + 1 < n && first_motion < 0; ++t) {
      motion = checker.CheckMotion(&path[static_cast<size_t>(t * 7)], &path[static_cast<size_t>((t + 1) * 7)]);
      checks += motion.checks;
      if (!motion.valid) first_motion = t;
    }
    ASSERT_EQ(verdict.motion, first_motion) << "trial " << trial;
    EXPECT_EQ(verdict.checks, checks) << "trial " << trial;
    EXPECT_EQ(verdict.valid(), first_motion < 0);
    if (first_motion >= 0) {
      ++bad_motion;
      EXPECT_EQ(verdict.motion_verdict.fraction, motion.fraction);
      EXPECT_EQ(verdict.motion_verdict.contact.sphere, motion.contact.sphere);
      EXPECT_EQ(verdict.motion_verdict.contact.other, motion.contact.other);
    } else {
      ++valid;
    }
  }
  // Every kind of verdict was met.
  EXPECT_GE(valid, 10);
  EXPECT_GE(bad_state, 10);
  EXPECT_GE(bad_motion, 10);
  // No states is a valid path; a negative count is a caller's error, not a valid path.
  EXPECT_TRUE(checker.CheckPath(nullptr, 0).valid());
  EXPECT_THROW(checker.CheckPath(nullptr, -1), InternalError);
}

TEST(CheckerTest, APointRobotInTwoDimensions) {
  const kinematics::RobotDescription disc = kinematics::PointRobot("disc", 2, 0.05, 0.0, 1.0);
  geometry::Scene scene;
  scene.boxes.push_back({{0.5, 0.5}, {0.2, 0.6}, {}, 0.3});
  const Checker checker(std::make_shared<const BodyModel>(disc),
                        std::make_shared<const World>(geometry::Rows(scene, 2, "test"), 2), {0.0, 0.001});
  const double left[2] = {0.1, 0.5}, right[2] = {0.9, 0.5}, below[2] = {0.5, 0.05}, inside[2] = {0.5, 0.5};
  EXPECT_TRUE(checker.Valid(left));
  EXPECT_FALSE(checker.Valid(inside));
  EXPECT_FALSE(checker.MotionValid(left, right));
  EXPECT_TRUE(checker.MotionValid(left, below));
  const MotionVerdict through = checker.CheckMotion(left, right);
  EXPECT_THAT(checker.Describe(through.contact), HasSubstr("the robot is"));
}

TEST(CheckerTest, NaNIsNeverValid) {
  const Checker checker(Franka(), std::make_shared<const World>(), {});
  std::vector<double> q = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  EXPECT_TRUE(checker.Valid(q.data()));
  q[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(checker.Valid(q.data()));
  const std::vector<double> ready = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  EXPECT_FALSE(checker.MotionValid(ready.data(), q.data()));
}

}  // namespace
}  // namespace flowplan::collision
