#include "problems/problem.h"

#include <yaml-cpp/yaml.h>

#include <limits>
#include <memory>

#include "collision/checker.h"
#include "geometry/scene_rows.h"

namespace flowplan::problems {
namespace {

template <class T>
std::string Text(const T& value) {
  return config::ToYaml(value, /*skip_unset=*/true);  // a 3-D box has no `angle`
}

}  // namespace

collision::WorldOptions Problem::World() const {
  collision::WorldOptions world;
  world.floor_height = floor_height;
  for (const HeldJoint& h : held) world.held[h.joint] = h.value;
  return world;
}

void DescribeEnds(const collision::BodyModel& body, Problem& problem) {
  const collision::WorldOptions world_options = problem.World();
  auto held = world_options.held.empty()
                  ? std::shared_ptr<const collision::BodyModel>(std::shared_ptr<const collision::BodyModel>(), &body)
                  : std::make_shared<const collision::BodyModel>(collision::WithHeld(body.description(), world_options.held),
                                                                 "problem " + problem.name);
  const int W = held->workspace_dim();
  problem.start_tcp.assign(static_cast<size_t>(W), 0.0);
  problem.goal_tcp.assign(static_cast<size_t>(W), 0.0);
  held->Tcp(problem.start_q.data(), problem.start_tcp.data());
  held->Tcp(problem.goal_q.data(), problem.goal_tcp.data());
  auto world = std::make_shared<const collision::World>(problem.scene, W, collision::Floor{}, std::vector<std::string>{},
                                                        "problem " + problem.name);
  const collision::Checker checker(held, world, {});
  problem.start_clearance = checker.Clearance(problem.start_q.data());
  problem.goal_clearance = checker.Clearance(problem.goal_q.data());
}

std::string ProblemSetYaml(const ProblemSet& set) { return Text(set); }

std::string SceneYaml(const geometry::Scene& scene) { return Text(scene); }

ProblemSet LoadProblemSet(const std::string& path) {
  ProblemSet set;
  config::Apply(config::ParseYamlFile(path), set, path);
  for (size_t i = 0; i < set.problems.size(); ++i) {
    const Problem& p = set.problems[i];
    const std::string entry = path + ": problems[" + std::to_string(i) + "]";
    p.scene.Validate(3, entry + ".scene");
    if (p.status != "ok" && p.status != "refused") {
      throw Error(entry + ".status: expected ok or refused, got \"" + p.status + "\"");
    }
    if (!p.base_pose.empty() && p.base_pose.size() != 7) {
      throw Error(entry + ".base_pose: expected 7 values (x y z qw qx qy qz) or none, got " +
                  std::to_string(p.base_pose.size()));
    }
  }
  return set;
}

}  // namespace flowplan::problems
