#pragma once

// Planning problems in joint space: a start and a goal configuration of the
// arm and the scene around them, as `flowplan scenes import` (MoveIt files),
// `flowplan problems --family NAME` (procedural scenes) and `flowplan problems`
// (random blocked problems) write them, and `flowplan plan --problems` plans
// them. A problem file is YAML:
//
//   source: "moveit import" | "family shelf" | "blocked: count: 100 ..." | ...
//   seed: 7                      # what drew a procedural set (0 for imports)
//   problems:
//     - name: scene0001
//       start_q: [...]           # (J,) rad
//       goal_q: [...]            # (J,) rad
//       start_tcp: [x, y, z]     # TCP of start_q (m)
//       goal_tcp: [x, y, z]      # TCP of goal_q (m)
//       start_clearance: 0.04    # smallest distance of the start's collision spheres to the scene (m)
//       goal_clearance: 0.01
//       obstacle_names: [...]    # (K,) in the scene's numbering; may be empty
//       left_out: [...]          # obstacles of the source not in `scene` (the grasped object)
//       scene: {boxes: [...], cylinders: [...], spheres: [...]}
//

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/config.h"
#include "geometry/scene.h"
#include "kinematics/robot.h"

namespace flowplan::problems {

struct Problem {
  std::string name;
  std::vector<double> start_q, goal_q;      // (J,) rad
  std::vector<double> start_tcp, goal_tcp;  // (W,) m
  double start_clearance = 0.0;             // m, whole arm (collision spheres) against the scene
  double goal_clearance = 0.0;              // m
  std::vector<std::string> obstacle_names;  // (K,) or empty
  std::vector<std::string> left_out;
  geometry::Scene scene;

  template <class V>
  void Visit(V& v) {
    v.Field("name", name, "name of the problem");
    v.Field("start_q", start_q, "start joints (rad)");
    v.Field("goal_q", goal_q, "goal joints (rad)");
    v.Field("start_tcp", start_tcp, "TCP of the start (m)");
    v.Field("goal_tcp", goal_tcp, "TCP of the goal (m)");
    const config::Bounds any{-INFINITY, INFINITY, false, false, "a number or .inf (no obstacles)", true};
    v.Field("start_clearance", start_clearance, "whole-arm clearance of the start from the scene (m)", any);
    v.Field("goal_clearance", goal_clearance, "whole-arm clearance of the goal from the scene (m)", any);
    v.Field("obstacle_names", obstacle_names, "names of the obstacles, in the scene's numbering");
    v.Field("left_out", left_out, "obstacles of the source left out of the scene");
    v.Field("scene", scene, "the obstacles");
  }
};

struct ProblemSet {
  std::string source;
  int64_t seed = 0;
  std::vector<Problem> problems;

  template <class V>
  void Visit(V& v) {
    v.Field("source", source, "what made the problems");
    v.Field("seed", seed, "seed a procedural set was drawn from", config::NonNegative());
    v.Field("problems", problems, "the problems");
  }
};

/// Sets start_tcp, goal_tcp, start_clearance and goal_clearance from start_q,
/// goal_q and the scene (clearances .inf when there is no obstacle).
void DescribeEnds(const kinematics::Robot& arm, Problem& problem);

/// The YAML text of a problem set, or of one scene (a `--scene` file). Fields
/// left unset are left out (a 3-D box has no `angle`), so the text reads back
/// to the same values.
std::string ProblemSetYaml(const ProblemSet& set);
std::string SceneYaml(const geometry::Scene& scene);

/// Reads a problem file. @throws flowplan::Error naming the file and the entry at fault.
ProblemSet LoadProblemSet(const std::string& path);

}  // namespace flowplan::problems
