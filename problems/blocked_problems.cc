#include "problems/blocked_problems.h"

#include "geometry/scene_rows.h"

#include <spdlog/spdlog.h>

#include <cmath>

#include "collision/body_model.h"
#include "collision/checker.h"
#include "core/error.h"
#include "core/random.h"

namespace flowplan::problems {
namespace {

constexpr int kAttempts = 10000;
constexpr double kFloorHeight = 0.0;  // m: the problems' arm stands on a floor at z = 0

using Point = std::vector<double>;

double Distance(const Point& a, const Point& b) {
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(sum);
}

void CheckConfig(const BlockedProblemsConfig& c) {
  if (c.min_spheres > c.max_spheres) throw Error("min_spheres: larger than max_spheres");
  if (c.min_radius > c.max_radius) throw Error("min_radius: larger than max_radius");
  if (c.min_boxes > c.max_boxes) throw Error("min_boxes: larger than max_boxes");
  if (c.min_box_side > c.max_box_side) throw Error("min_box_side: larger than max_box_side");
  if (c.lower.size() != 3 || c.upper.size() != 3) throw Error("lower, upper: expected 3 values each");
  for (int i = 0; i < 3; ++i) {
    if (!(c.lower[i] < c.upper[i])) throw Error("lower[" + std::to_string(i) + "]: not below upper");
  }
}

/// Whether both TCP points and every collision sphere of both postures q (2, J)
/// keep `clearance` from every obstacle of `scene`.
bool Clear(const kinematics::Robot& robot, const torch::Tensor& q, const torch::Tensor& tcp,
           const geometry::Scene& scene, double clearance) {
  const geometry::SceneRows rows = geometry::Rows(scene, 3, "blocked problems");
  return kinematics::Robot::PointClearance(tcp, rows).min().item<double>() >= clearance &&
         robot.Clearance(q, rows).min().item<double>() >= clearance;
}

/// The scene of one obstacle.
geometry::Scene SceneOf(const geometry::SphereObstacle& sphere) {
  geometry::Scene scene;
  scene.spheres.push_back(sphere);
  return scene;
}
geometry::Scene SceneOf(const geometry::BoxObstacle& box) {
  geometry::Scene scene;
  scene.boxes.push_back(box);
  return scene;
}

/// A point of the straight TCP segment, moved by up to `reach` along each axis.
std::vector<double> NearSegment(Rng& rng, const Point& start, const Point& goal, double reach) {
  const double v = rng.Uniform(0.0, 1.0);
  std::vector<double> out;
  for (int k = 0; k < 3; ++k) out.push_back(start[k] + v * (goal[k] - start[k]) + rng.Uniform(-1.0, 1.0) * reach);
  return out;
}

/// A uniformly random rotation (w, x, y, z) (Shoemake's method).
std::vector<double> RandomQuaternion(Rng& rng) {
  const double u1 = rng.Uniform(0.0, 1.0), u2 = rng.Uniform(0.0, 2.0 * M_PI), u3 = rng.Uniform(0.0, 2.0 * M_PI);
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  return {b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3)};
}

}  // namespace

ProblemSet MakeBlockedProblems(const kinematics::Robot& arm, const BlockedProblemsConfig& config, uint64_t seed) {
  CheckConfig(config);
  if (!arm.is_arm() || arm.workspace_dim() != 3) throw Error("blocked problems: expected an arm in a 3-D workspace");
  const auto body_model = std::make_shared<const collision::BodyModel>(arm.description(), "blocked problems: robot");
  const collision::BodyModel& body = *body_model;
  // The robot on its own, on the problems' floor: a start or goal must be valid before any obstacle is placed.
  collision::Floor floor;
  floor.present = true;
  floor.height = kFloorHeight;
  const collision::Checker alone(body_model, std::make_shared<const collision::World>(geometry::Scene{}, 3, floor), {});
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
      if (!Clear(arm, ik.q, both, SceneOf(blocker), config.clearance)) continue;
      problem.scene.spheres.push_back(blocker);
      // The others near the path: a point of the segment, moved by up to two largest radii.
      for (int s = 1; s < spheres; ++s) {
        for (int tries = 0; tries < 100; ++tries) {
          geometry::SphereObstacle other;
          other.centre = NearSegment(rng, problem.start_tcp, problem.goal_tcp, 2.0 * config.max_radius);
          other.radius = rng.Uniform(config.min_radius, config.max_radius);
          if (Clear(arm, ik.q, both, SceneOf(other), config.clearance)) {
            problem.scene.spheres.push_back(other);
            break;
          }
        }
      }
      // Boxes near the path as well, after the spheres (a set without boxes draws nothing more).
      const int boxes = config.max_boxes == 0 ? 0 : config.min_boxes + static_cast<int>(rng.Below(
                                                        static_cast<uint64_t>(config.max_boxes - config.min_boxes + 1)));
      for (int b = 0; b < boxes; ++b) {
        for (int tries = 0; tries < 100; ++tries) {
          geometry::BoxObstacle box;
          box.centre = NearSegment(rng, problem.start_tcp, problem.goal_tcp, config.max_box_side);
          for (int k = 0; k < 3; ++k) box.size.push_back(rng.Uniform(config.min_box_side, config.max_box_side));
          box.quaternion = RandomQuaternion(rng);
          if (Clear(arm, ik.q, both, SceneOf(box), config.clearance)) {
            problem.scene.boxes.push_back(box);
            break;
          }
        }
      }
      // Checked last, after every draw of the attempt, so that a robot whose postures are all valid on their own
      // (the Franka in its reach box) draws the problems it drew before this check existed.
      const torch::Tensor postures = ik.q.to(torch::kFloat64).contiguous();
      if (!alone.Valid(postures[0].data_ptr<double>()) || !alone.Valid(postures[1].data_ptr<double>())) {
        spdlog::debug("blocked problem {}: attempt {} drawn again, its start or goal not valid for the robot alone", i,
                      attempt);
        continue;
      }
      for (int j = 0; j < ik.q.size(1); ++j) {
        problem.start_q.push_back(ik.q[0][j].item<double>());
        problem.goal_q.push_back(ik.q[1][j].item<double>());
      }
      const Point start_tcp = problem.start_tcp, goal_tcp = problem.goal_tcp;  // the drawn points
      problem.floor_height = kFloorHeight;
      DescribeEnds(body, problem);  // the clearances (and the TCPs of the IK, within its tolerance)
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
