#include "problems/blocked_problems.h"

#include "geometry/scene_rows.h"

#include <cmath>

#include "core/error.h"
#include "core/random.h"

namespace flowplan::problems {
namespace {

constexpr int kAttempts = 10000;

using Point = std::vector<double>;

double Distance(const Point& a, const Point& b) {
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(sum);
}

void CheckConfig(const BlockedProblemsConfig& c) {
  if (c.min_spheres > c.max_spheres) throw Error("min_spheres: larger than max_spheres");
  if (c.min_radius > c.max_radius) throw Error("min_radius: larger than max_radius");
  if (c.lower.size() != 3 || c.upper.size() != 3) throw Error("lower, upper: expected 3 values each");
  for (int i = 0; i < 3; ++i) {
    if (!(c.lower[i] < c.upper[i])) throw Error("lower[" + std::to_string(i) + "]: not below upper");
  }
}

/// Whether both TCP points and every collision sphere of both postures q (2, J)
/// keep `clearance` from `sphere`.
bool Clear(const kinematics::Robot& robot, const torch::Tensor& q, const torch::Tensor& tcp,
           const geometry::SphereObstacle& sphere, double clearance) {
  geometry::Scene scene;
  scene.spheres.push_back(sphere);
  const geometry::SceneRows rows = geometry::Rows(scene, 3, "blocked problems");
  return kinematics::Robot::PointClearance(tcp, rows).min().item<double>() >= clearance &&
         robot.Clearance(q, rows).min().item<double>() >= clearance;
}

}  // namespace

ProblemSet MakeBlockedProblems(const kinematics::Robot& arm, const BlockedProblemsConfig& config, uint64_t seed) {
  CheckConfig(config);
  if (!arm.is_arm() || arm.workspace_dim() != 3) throw Error("blocked problems: expected an arm in a 3-D workspace");
  ProblemSet set;
  set.seed = static_cast<int64_t>(seed);
  set.source = "blocked: " + config::ToYaml(config);  // how they were drawn
  for (char& c : set.source) {
    if (c == '\n') c = ' ';
  }
  for (int i = 0; i < config.count; ++i) {
    Rng rng(StreamSeed(seed, static_cast<uint64_t>(i)));
    bool found = false;
    for (int attempt = 0; attempt < kAttempts && !found; ++attempt) {
      Problem problem;
      problem.name = "blocked/" + std::to_string(i);
      for (Point* p : {&problem.start_tcp, &problem.goal_tcp}) {
        for (int k = 0; k < 3; ++k) p->push_back(rng.Uniform(config.lower[k], config.upper[k]));
      }
      if (Distance(problem.start_tcp, problem.goal_tcp) < config.min_length) continue;
      const torch::Tensor both = torch::cat({torch::tensor(problem.start_tcp, torch::kFloat64).view({1, 3}),
                                             torch::tensor(problem.goal_tcp, torch::kFloat64).view({1, 3})});
      const kinematics::IkSolution ik = arm.InverseTcp(both);
      if (!ik.converged.all().item<bool>()) continue;

      const int spheres = config.min_spheres +
                          static_cast<int>(rng.Below(static_cast<uint64_t>(config.max_spheres - config.min_spheres + 1)));
      // The first sphere is centred on the straight TCP path, in its middle part.
      geometry::SphereObstacle blocker;
      const double u = rng.Uniform(0.3, 0.7);
      for (int k = 0; k < 3; ++k) {
        blocker.centre.push_back(problem.start_tcp[k] + u * (problem.goal_tcp[k] - problem.start_tcp[k]));
      }
      blocker.radius = rng.Uniform(config.min_radius, config.max_radius);
      if (!Clear(arm, ik.q, both, blocker, config.clearance)) continue;
      problem.scene.spheres.push_back(blocker);
      // The others near the path: a point of the segment, moved by up to two largest radii.
      for (int s = 1; s < spheres; ++s) {
        for (int tries = 0; tries < 100; ++tries) {
          geometry::SphereObstacle other;
          const double v = rng.Uniform(0.0, 1.0);
          for (int k = 0; k < 3; ++k) {
            other.centre.push_back(problem.start_tcp[k] + v * (problem.goal_tcp[k] - problem.start_tcp[k]) +
                                   rng.Uniform(-2.0, 2.0) * config.max_radius);
          }
          other.radius = rng.Uniform(config.min_radius, config.max_radius);
          if (Clear(arm, ik.q, both, other, config.clearance)) {
            problem.scene.spheres.push_back(other);
            break;
          }
        }
      }
      for (int j = 0; j < ik.q.size(1); ++j) {
        problem.start_q.push_back(ik.q[0][j].item<double>());
        problem.goal_q.push_back(ik.q[1][j].item<double>());
      }
      const Point start_tcp = problem.start_tcp, goal_tcp = problem.goal_tcp;  // the drawn points
      DescribeEnds(arm, problem);  // the clearances (and the TCPs of the IK, within its tolerance)
      problem.start_tcp = start_tcp;
      problem.goal_tcp = goal_tcp;
      set.problems.push_back(std::move(problem));
      found = true;
    }
    if (!found) {
      throw Error("blocked problems: no problem " + std::to_string(i) + " in " + std::to_string(kAttempts) +
                  " attempts (is the box reachable, min_length short enough, the spheres small enough?)");
    }
  }
  return set;
}

}  // namespace flowplan::problems
