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
//       floor_height: -.inf      # the floor's z (m), -.inf: no floor
//       held: [{joint: panda_finger_joint1, value: 0.065}]   # joints not planned, held at a value
//       base_pose: [x, y, z, qw, qx, qy, qz]   # where the robot's base stood in the source's world; the
//                                # obstacles above are in the base frame (empty: the source's world is it)
//       status: ok | refused     # refused: no plan can start or end where this one does
//       reason: "..."            # why it was refused
//       notes: ["..."]           # what the import changed (a value within tolerance of a limit, clamped onto it)
//

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "collision/body_model.h"
#include "collision/world.h"
#include "core/config.h"
#include "geometry/scene.h"
#include "kinematics/robot.h"

namespace flowplan::problems {

/// A joint that is not planned, held at a value for a problem (a gripper's fingers).
struct HeldJoint {
  std::string joint;
  double value = 0.0;

  template <class V>
  void Visit(V& v) {
    v.Field("joint", joint, "the joint's name");
    v.Field("value", value, "its value (rad or m)");
  }
};

struct Problem {
  std::string name;
  std::vector<double> start_q, goal_q;      // (J,) rad
  std::vector<double> start_tcp, goal_tcp;  // (W,) m
  double start_clearance = 0.0;             // m, whole arm (collision spheres) against the scene
  double goal_clearance = 0.0;              // m
  std::vector<std::string> obstacle_names;  // (K,) or empty
  std::vector<std::string> left_out;
  geometry::Scene scene;
  double floor_height = -INFINITY;          // m, -inf: no floor
  std::vector<HeldJoint> held;
  std::vector<double> base_pose;            // (7) or empty
  std::string status = "ok";                // "ok" or "refused"
  std::string reason;                       // why it was refused
  std::vector<std::string> notes;           // what the import changed

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
    v.Field("floor_height", floor_height, "the floor's height (m), -.inf for none",
            config::Bounds{-INFINITY, INFINITY, false, false, "a number or -.inf", true});
    v.Field("held", held, "joints that are not planned, held at a value: [{joint, value}]");
    v.Field("base_pose", base_pose, "the robot base's pose in the source's world (x y z qw qx qy qz); the obstacles "
                                    "are given in the base frame");
    v.Field("status", status, "ok, or refused when no plan can start or end where this problem does");
    v.Field("reason", reason, "why the problem was refused");
    v.Field("notes", notes, "what the import changed");
  }

  /// The floor and held joints as a planning call takes them.
  collision::WorldOptions World() const;
  bool refused() const { return status == "refused"; }
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
/// goal_q and the scene (clearances .inf when there is no obstacle), with the
/// problem's held joints. @throws flowplan::Error for a held joint `body` lacks.
void DescribeEnds(const collision::BodyModel& body, Problem& problem);

/// The YAML text of a problem set, or of one scene (a `--scene` file). Fields
/// left unset are left out (a 3-D box has no `angle`), so the text reads back
/// to the same values.
std::string ProblemSetYaml(const ProblemSet& set);
std::string SceneYaml(const geometry::Scene& scene);

/// Reads a problem file. @throws flowplan::Error naming the file and the entry at fault.
ProblemSet LoadProblemSet(const std::string& path);

}  // namespace flowplan::problems
