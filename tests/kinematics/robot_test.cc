// The kinematics module (kinematics/arm.py, point.py) against MuJoCo's own
// kinematics, autograd against central differences, the written-out
// vector–Jacobian products against autograd, and the IK against MuJoCo's FK.

#include "kinematics/robot.h"

#include <ATen/Parallel.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "jit/library.h"
#include "sim/franka_ik.h"
#include "sim/franka_model.h"

namespace flowplan::kinematics {
namespace {

using ::testing::HasSubstr;

class ForwardKinematicsTest : public ::testing::Test {
 protected:
  // Random configurations within the joint limits, (B, 7) float64.
  torch::Tensor RandomQ(int64_t batch, uint64_t seed) {
    torch::manual_seed(seed);
    const auto& limits = model_.limits();
    const torch::Tensor lower = torch::from_blob(const_cast<double*>(limits.q_lower.data()), {7}, torch::kFloat64);
    const torch::Tensor upper = torch::from_blob(const_cast<double*>(limits.q_upper.data()), {7}, torch::kFloat64);
    return lower + (upper - lower) * torch::rand({batch, 7}, torch::kFloat64);
  }

  /// Link frames (B, L, 4, 4), TCP (B, 3) and sphere centres (B, S, 3) of q (B, 7).
  struct Fk {
    torch::Tensor link_frames, tcp_position, sphere_centres;
  };
  Fk Forward(const torch::Tensor& q) const {
    const auto frames = jit::Call(fk_.module(), "link_frames", {q}).toTensorVector();
    return {torch::stack(frames, 1), fk_.Tcp(q), fk_.SphereCentres(q)};
  }

  sim::FrankaModel model_ = sim::LoadFrankaModel();
  Robot fk_{model_.description()};
  int64_t num_links_ = static_cast<int64_t>(model_.description().links.size());
};

TEST_F(ForwardKinematicsTest, MatchesMujocoInFloat64) {
  const torch::Tensor q = RandomQ(32, 1);
  const Fk result = Forward(q);
  ASSERT_EQ(result.link_frames.sizes(), (std::vector<int64_t>{32, 11, 4, 4}));
  ASSERT_EQ(result.tcp_position.sizes(), (std::vector<int64_t>{32, 3}));
  ASSERT_EQ(result.sphere_centres.sizes(), (std::vector<int64_t>{32, fk_.num_spheres(), 3}));
  const mjModel& m = model_.mj();
  sim::MjDataPtr d = sim::MakeData(m);
  const auto& spheres = model_.description().spheres;
  for (int64_t b = 0; b < q.size(0); ++b) {
    for (int j = 0; j < 7; ++j) d->qpos[j] = q[b][j].item<double>();
    mj_kinematics(&m, d.get());
    for (int64_t l = 0; l < num_links_; ++l) {
      const int body = static_cast<int>(l) + 1;
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(result.link_frames[b][l][i][3].item<double>(), d->xpos[3 * body + i], 1e-6);
        for (int k = 0; k < 3; ++k) {
          EXPECT_NEAR(result.link_frames[b][l][i][k].item<double>(), d->xmat[9 * body + 3 * i + k], 1e-6);
        }
      }
    }
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(result.tcp_position[b][i].item<double>(), d->site_xpos[3 * model_.tcp_site() + i], 1e-6);
    }
    // Every sphere sits at its link-frame centre as MuJoCo places that link's body.
    for (size_t s = 0; s < spheres.size(); ++s) {
      const int body = spheres[s].link + 1;
      for (int i = 0; i < 3; ++i) {
        double expected = d->xpos[3 * body + i];
        for (int k = 0; k < 3; ++k) expected += d->xmat[9 * body + 3 * i + k] * spheres[s].centre[k];
        EXPECT_NEAR(result.sphere_centres[b][static_cast<int64_t>(s)][i].item<double>(), expected, 1e-6) << s;
      }
    }
  }
  const torch::Tensor radii = fk_.SphereRadii();
  ASSERT_EQ(radii.sizes(), (std::vector<int64_t>{fk_.num_spheres()}));
  for (int64_t s = 0; s < fk_.num_spheres(); ++s) EXPECT_EQ(radii[s].item<double>(), spheres[s].radius);
}

TEST_F(ForwardKinematicsTest, KnownPosesThroughTorch) {
  const torch::Tensor ready =
      torch::tensor({0.0, -M_PI / 4, 0.0, -3 * M_PI / 4, 0.0, M_PI / 2, M_PI / 4}, torch::kFloat64).view({1, 7});
  const torch::Tensor tcp = fk_.Tcp(ready);
  EXPECT_NEAR(tcp[0][0].item<double>(), 0.306890566, 1e-9);
  EXPECT_NEAR(tcp[0][1].item<double>(), 0.0, 1e-9);
  EXPECT_NEAR(tcp[0][2].item<double>(), 0.590282052 - 0.107, 1e-9);
  // Robotics Toolbox pose: hand frame moved 0.103 m along its z axis.
  const torch::Tensor q = torch::tensor({1.4, 0.2, 1.8, 0.7, 0.1, 3.1, 2.9}, torch::kFloat64).view({1, 7});
  const torch::Tensor hand = Forward(q).link_frames[0][8];
  const torch::Tensor p = hand.index({torch::indexing::Slice(0, 3), 3}) +
                          0.103 * hand.index({torch::indexing::Slice(0, 3), 2});
  EXPECT_NEAR(p[0].item<double>(), 0.44682295, 1e-8);
  EXPECT_NEAR(p[1].item<double>(), 0.16168396, 1e-8);
  EXPECT_NEAR(p[2].item<double>(), 0.96798113, 1e-8);
}

TEST_F(ForwardKinematicsTest, Float32AgreesWithFloat64) {
  const torch::Tensor q = RandomQ(16, 2);
  const Fk a = Forward(q);
  const Fk b = Forward(q.to(torch::kFloat32));
  EXPECT_EQ(b.tcp_position.scalar_type(), torch::kFloat32);
  EXPECT_LT((a.sphere_centres - b.sphere_centres.to(torch::kFloat64)).abs().max().item<double>(), 1e-5);
  EXPECT_LT((a.link_frames - b.link_frames.to(torch::kFloat64)).abs().max().item<double>(), 1e-5);
}

TEST_F(ForwardKinematicsTest, AutogradMatchesCentralDifferences) {
  const torch::Tensor q0 = RandomQ(4, 3);
  torch::manual_seed(4);
  const torch::Tensor w_tcp = torch::randn({4, 3}, torch::kFloat64);
  const torch::Tensor w_spheres = torch::randn({4, fk_.num_spheres(), 3}, torch::kFloat64);
  auto cost = [&](const torch::Tensor& q) {
    const Fk r = Forward(q);
    return (r.tcp_position * w_tcp).sum() + (r.sphere_centres * w_spheres).sum() +
           r.link_frames.pow(2).sum();
  };
  const torch::Tensor q = q0.clone().requires_grad_(true);
  const torch::Tensor gradient = torch::autograd::grad({cost(q)}, {q})[0];
  const double h = 1e-6;
  for (int64_t b = 0; b < 4; ++b) {
    for (int64_t j = 0; j < 7; ++j) {
      torch::Tensor plus = q0.clone(), minus = q0.clone();
      plus[b][j] += h;
      minus[b][j] -= h;
      const double numeric = (cost(plus).item<double>() - cost(minus).item<double>()) / (2 * h);
      EXPECT_NEAR(gradient[b][j].item<double>(), numeric, 1e-6 * std::max(1.0, std::abs(numeric)))
          << "b " << b << " j " << j;
    }
  }
}

TEST_F(ForwardKinematicsTest, TcpVjpIsTheTcpsJacobianTransposed) {
  // The written-out product against autograd through the same FK, in float64.
  const torch::Tensor q0 = RandomQ(6, 5);
  torch::manual_seed(6);
  const torch::Tensor g = torch::randn({6, 3}, torch::kFloat64);
  const torch::Tensor q = q0.clone().requires_grad_(true);
  const torch::Tensor expected = torch::autograd::grad({(fk_.Tcp(q) * g).sum()}, {q})[0];
  const torch::Tensor written = jit::Call(fk_.module(), "tcp_vjp", {q0, g}).toTensor();
  EXPECT_LT((written - expected).abs().max().item<double>(), 1e-12);
}

TEST_F(ForwardKinematicsTest, SpheresVjpIsTheSpheresJacobianTransposed) {
  // A gradient on some of the 5 S centres (rows, in any order), zero on the rest: the written-out product
  // equals autograd's of the dense sum.
  const torch::Tensor q0 = RandomQ(5, 8);
  torch::manual_seed(9);
  const int64_t S = fk_.num_spheres();
  const torch::Tensor rows = torch::randperm(5 * S, torch::kInt64).slice(0, 0, 2 * S);
  const torch::Tensor g = torch::randn({2 * S, 3}, torch::kFloat64);
  const torch::Tensor dense = torch::zeros({5 * S, 3}, torch::kFloat64).index_copy(0, rows, g).view({5, S, 3});
  const torch::Tensor q = q0.clone().requires_grad_(true);
  const torch::Tensor expected = torch::autograd::grad({(fk_.SphereCentres(q) * dense).sum()}, {q})[0];
  const auto poses = jit::Call(fk_.module(), "spheres", {q0}).toTuple()->elements();
  const torch::Tensor written =
      jit::Call(fk_.module(), "spheres_vjp", {poses[0], poses[1], poses[2], rows, g}).toTensor();
  EXPECT_LT((written - expected).abs().max().item<double>(), 1e-12);
  EXPECT_GT(expected.abs().max().item<double>(), 0.1);
}

TEST(PointRobot, IsItsOwnTcpAndSphere) {
  const Robot disc(PointRobot("disc", 2, 0.05, 0.0, 1.0));
  const torch::Tensor q = torch::tensor({{0.2, 0.3}, {0.9, 0.1}}, torch::kFloat64);
  EXPECT_TRUE(torch::equal(disc.Tcp(q), q));
  const torch::Tensor spheres = jit::Call(disc.module(), "collision_spheres", {q}).toTensor();
  EXPECT_EQ(spheres.sizes(), torch::IntArrayRef({2, 1, 3}));
  EXPECT_EQ(spheres[1][0][2].item<double>(), 0.05);
  geometry::SceneRows scene;
  scene.insert("spheres", torch::tensor({{0.2, 0.5, 0.1}}, torch::kFloat64));
  EXPECT_NEAR(disc.Clearance(q, scene)[0][0].item<double>(), 0.2 - 0.1 - 0.05, 1e-12);
  EXPECT_TRUE(torch::equal(disc.InverseTcp(q).q, q));
}

TEST_F(ForwardKinematicsTest, InverseTcpReachesTargetsAsTheMujocoSolverDoes) {
  // Targets over the whole box the reach data set draws its points from, reachable or not. The planner's IK
  // (the script's) and the data generator's (MuJoCo's Jacobians) run the same damped least squares from home;
  // they must agree on which targets they reach and on the configurations they find.
  torch::manual_seed(6);
  const torch::Tensor lo = torch::tensor({0.35, -0.5, 0.15}, torch::kFloat64);
  const torch::Tensor hi = torch::tensor({0.75, 0.5, 0.75}, torch::kFloat64);
  const torch::Tensor targets = lo + (hi - lo) * torch::rand({36, 3}, torch::kFloat64);
  const IkSolution solution = fk_.InverseTcp(targets);
  sim::MjDataPtr d = sim::MakeData(model_.mj());
  int reached = 0;
  for (int64_t n = 0; n < targets.size(0); ++n) {
    const Eigen::Vector3d target(targets[n][0].item<double>(), targets[n][1].item<double>(), targets[n][2].item<double>());
    const sim::IkResult reference = sim::SolveTcpIk(model_, *d, target, sim::FrankaReadyPose());
    ASSERT_EQ(solution.converged[n].item<bool>(), reference.converged) << "target " << target.transpose();
    if (!reference.converged) continue;
    ++reached;
    sim::JointVector q;
    for (int j = 0; j < 7; ++j) q[j] = solution.q[n][j].item<double>();
    EXPECT_LT((reference.q - q).cwiseAbs().maxCoeff(), 1e-9) << "target " << target.transpose();
    const sim::FrankaPose pose = sim::FrankaForwardKinematics(model_, *d, q);
    EXPECT_LT((pose.tcp_position - target).norm(), 1e-5);  // the solvers' tolerance
    EXPECT_LT((pose.tcp_rotation - sim::DownwardTcpRotation()).norm(), 2e-4);  // gripper down, as at home
  }
  // Both kinds of target are compared (with this seed 23 of the 36 are reachable with the gripper down).
  EXPECT_GE(reached, 18);
  EXPECT_LT(reached, 36);
  // Seeded at its own solution, the solver stays there.
  const torch::Tensor ok = solution.converged;
  const IkSolution again = fk_.InverseTcp(targets.index({ok}), solution.q.index({ok}));
  EXPECT_TRUE(torch::equal(again.q, solution.q.index({ok})));
  const IkSolution far = fk_.InverseTcp(torch::tensor({{2.0, 0.0, 0.5}}, torch::kFloat64));
  EXPECT_FALSE(far.converged.any().item<bool>());
  EXPECT_GT(far.position_error[0].item<double>(), 1.0);
}

TEST_F(ForwardKinematicsTest, ShapesAreCheckedAtEntry) {
  EXPECT_THAT([&] { fk_.Tcp(torch::zeros({3, 6}, torch::kFloat64)); },
              ::testing::ThrowsMessage<Error>(HasSubstr("tcp: q: expected (..., 7), got [3, 6]")));
  EXPECT_THAT([&] { fk_.SphereCentres(torch::zeros({6}, torch::kFloat64)); },
              ::testing::ThrowsMessage<Error>(HasSubstr("sphere_centres: q: expected (..., 7), got [6]")));
  EXPECT_EQ(fk_.Tcp(torch::zeros({4, 2, 7})).sizes(), torch::IntArrayRef({4, 2, 3}));
  EXPECT_THAT([&] { fk_.InverseTcp(torch::zeros({2, 2}, torch::kFloat64)); },
              ::testing::ThrowsMessage<Error>(HasSubstr("IK: targets: expected (M, 3), got (2, 2)")));
}

}  // namespace
}  // namespace flowplan::kinematics
