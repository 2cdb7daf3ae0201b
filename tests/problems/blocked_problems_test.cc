// Random blocked problems, checked with plain geometry.

#include "problems/blocked_problems.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "core/error.h"
#include "sim/franka_model.h"

namespace flowplan::problems {
namespace {

const kinematics::Robot& Franka() {
  static const kinematics::Robot arm(sim::LoadFrankaModel().description());
  return arm;
}

/// Distance from point c to the segment [a, b], by plain geometry.
double DistanceToSegment(const std::vector<double>& a, const std::vector<double>& b, const std::vector<double>& c) {
  double ab2 = 0.0, t = 0.0;
  for (int k = 0; k < 3; ++k) {
    ab2 += (b[k] - a[k]) * (b[k] - a[k]);
    t += (c[k] - a[k]) * (b[k] - a[k]);
  }
  t = std::clamp(t / ab2, 0.0, 1.0);
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double p = a[k] + t * (b[k] - a[k]);
    d2 += (c[k] - p) * (c[k] - p);
  }
  return std::sqrt(d2);
}

double Distance(const std::vector<double>& a, const std::vector<double>& b) {
  double d2 = 0.0;
  for (int k = 0; k < 3; ++k) d2 += (a[k] - b[k]) * (a[k] - b[k]);
  return std::sqrt(d2);
}

TEST(BlockedProblemsTest, TheStraightPathIsBlockedAndStartAndGoalAreFreeAndReached) {
  BlockedProblemsConfig config;
  config.count = 6;
  const ProblemSet set = MakeBlockedProblems(Franka(), config, 3);
  ASSERT_EQ(set.problems.size(), 6u);
  size_t many = 0;
  for (const Problem& p : set.problems) {
    EXPECT_EQ(p.name.rfind("blocked/", 0), 0u);
    EXPECT_GE(std::min(p.start_clearance, p.goal_clearance), config.clearance - 1e-9);
    const auto& spheres = p.scene.spheres;
    ASSERT_GE(spheres.size(), 1u);
    ASSERT_LE(spheres.size(), 8u);
    many += spheres.size() > 1;
    EXPECT_GE(Distance(p.start_tcp, p.goal_tcp), config.min_length);
    EXPECT_LT(DistanceToSegment(p.start_tcp, p.goal_tcp, spheres[0].centre), spheres[0].radius);
    for (const geometry::SphereObstacle& s : spheres) {
      EXPECT_GE(s.radius, config.min_radius);
      EXPECT_LE(s.radius, config.max_radius);
      EXPECT_GE(Distance(p.start_tcp, s.centre), s.radius + config.clearance);
      EXPECT_GE(Distance(p.goal_tcp, s.centre), s.radius + config.clearance);
    }
    // The joints reach the TCP points (IK), and every collision sphere of both postures is clear.
    const torch::Tensor q = torch::tensor(p.start_q, torch::kFloat64).view({1, 7});
    const torch::Tensor both = torch::cat({q, torch::tensor(p.goal_q, torch::kFloat64).view({1, 7})});
    const torch::Tensor tcp = Franka().Tcp(both);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(tcp[0][k].item<double>(), p.start_tcp[k], 1e-4);
      EXPECT_NEAR(tcp[1][k].item<double>(), p.goal_tcp[k], 1e-4);
    }
    const torch::Tensor centres = Franka().SphereCentres(both), radii = Franka().SphereRadii();
    for (const geometry::SphereObstacle& s : spheres) {
      const torch::Tensor gap = (centres - torch::tensor(s.centre, torch::kFloat64)).norm(2, -1) - radii - s.radius;
      EXPECT_GE(gap.min().item<double>(), config.clearance - 1e-9);
    }
  }
  EXPECT_GT(many, 0u);  // 1 to 8 spheres: not all single ones
}

TEST(BlockedProblemsTest, ProblemIDependsOnlyOnTheSeedAndI) {
  BlockedProblemsConfig config;
  config.count = 3;
  const ProblemSet three_set = MakeBlockedProblems(Franka(), config, 9);
  const std::string three = config::ToYaml(three_set.problems);
  config.count = 4;
  ProblemSet four = MakeBlockedProblems(Franka(), config, 9);
  four.problems.pop_back();
  EXPECT_EQ(config::ToYaml(four.problems), three);
  EXPECT_NE(config::ToYaml(MakeBlockedProblems(Franka(), config, 10).problems.front()),
            config::ToYaml(four.problems.front()));
  // The file reads back as the problem file every planner takes (`flowplan plan --problems`).
  const std::string path = ::testing::TempDir() + "/blocked_problems.yaml";
  std::ofstream(path) << ProblemSetYaml(three_set);
  const ProblemSet back = LoadProblemSet(path);
  EXPECT_EQ(ProblemSetYaml(back), ProblemSetYaml(three_set));
  EXPECT_THAT(back.source, ::testing::HasSubstr("min_spheres: 1"));
}

/// Signed distance from point c to a box (centre, full sizes, quaternion w, x, y, z), by plain geometry.
double DistanceToBox(const geometry::BoxObstacle& box, const std::vector<double>& c) {
  const double w = box.quaternion[0], x = box.quaternion[1], y = box.quaternion[2], z = box.quaternion[3];
  const double n = std::sqrt(w * w + x * x + y * y + z * z);
  const double a = w / n, b = x / n, cc = y / n, d = z / n;
  const double R[3][3] = {{1 - 2 * (cc * cc + d * d), 2 * (b * cc - a * d), 2 * (b * d + a * cc)},
                          {2 * (b * cc + a * d), 1 - 2 * (b * b + d * d), 2 * (cc * d - a * b)},
                          {2 * (b * d - a * cc), 2 * (cc * d + a * b), 1 - 2 * (b * b + cc * cc)}};
  double outside = 0.0, inside = -1e9;
  for (int j = 0; j < 3; ++j) {
    double local = 0.0;
    for (int i = 0; i < 3; ++i) local += R[i][j] * (c[i] - box.centre[i]);
    const double gap = std::abs(local) - 0.5 * box.size[j];
    outside += std::max(gap, 0.0) * std::max(gap, 0.0);
    inside = std::max(inside, gap);
  }
  return std::sqrt(outside) + std::min(inside, 0.0);
}

TEST(BlockedProblemsTest, BoxesNearThePathKeepClearOfStartAndGoalAndLeaveTheRestAsItWas) {
  BlockedProblemsConfig config;
  config.count = 6;
  const ProblemSet spheres_only = MakeBlockedProblems(Franka(), config, 4);
  config.min_boxes = 1;
  config.max_boxes = 3;
  const ProblemSet with_boxes = MakeBlockedProblems(Franka(), config, 4);
  ASSERT_EQ(with_boxes.problems.size(), 6u);
  size_t boxes = 0;
  for (size_t i = 0; i < 6; ++i) {
    const Problem& p = with_boxes.problems[i];
    const Problem& before = spheres_only.problems[i];
    // The boxes are drawn last: ends and spheres are those of the set without boxes.
    EXPECT_EQ(p.start_q, before.start_q);
    EXPECT_EQ(config::ToYaml(p.scene.spheres), config::ToYaml(before.scene.spheres));
    EXPECT_TRUE(before.scene.boxes.empty());
    EXPECT_LE(p.scene.boxes.size(), 3u);
    boxes += p.scene.boxes.size();
    const torch::Tensor both = torch::cat({torch::tensor(p.start_q, torch::kFloat64).view({1, 7}),
                                           torch::tensor(p.goal_q, torch::kFloat64).view({1, 7})});
    const torch::Tensor centres = Franka().SphereCentres(both), radii = Franka().SphereRadii();
    for (const geometry::BoxObstacle& box : p.scene.boxes) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(box.size[k], config.min_box_side);
        EXPECT_LE(box.size[k], config.max_box_side);
      }
      EXPECT_GE(DistanceToBox(box, p.start_tcp), config.clearance - 1e-9);
      EXPECT_GE(DistanceToBox(box, p.goal_tcp), config.clearance - 1e-9);
      for (int64_t m = 0; m < 2; ++m) {
        for (int64_t s = 0; s < centres.size(1); ++s) {
          const torch::Tensor c = centres[m][s];
          const double gap = DistanceToBox(box, {c[0].item<double>(), c[1].item<double>(), c[2].item<double>()}) -
                             radii[s].item<double>();
          EXPECT_GE(gap, config.clearance - 1e-9) << p.name << " sphere " << s;
        }
      }
    }
    EXPECT_GE(std::min(p.start_clearance, p.goal_clearance), config.clearance - 1e-9);
  }
  EXPECT_GE(boxes, 6u);  // one to three per problem, unless a box found no free place in 100 tries
}

TEST(BlockedProblemsTest, InconsistentSettingsAreNamed) {
  BlockedProblemsConfig config;
  config.min_spheres = 3;
  config.max_spheres = 2;
  EXPECT_THAT([&] { MakeBlockedProblems(Franka(), config, 0); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("min_spheres")));
  config = BlockedProblemsConfig{};
  config.min_boxes = 2;
  config.max_boxes = 1;
  EXPECT_THAT([&] { MakeBlockedProblems(Franka(), config, 0); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("min_boxes")));
  config = BlockedProblemsConfig{};
  config.lower = {0.35, -0.5};
  EXPECT_THAT([&] { MakeBlockedProblems(Franka(), config, 0); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("lower")));
  config = BlockedProblemsConfig{};
  config.lower = {2.0, 2.0, 2.0};  // out of reach
  config.upper = {2.1, 2.1, 2.1};
  config.count = 1;
  EXPECT_THAT([&] { MakeBlockedProblems(Franka(), config, 0); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("no problem 0")));
}

}  // namespace
}  // namespace flowplan::problems
