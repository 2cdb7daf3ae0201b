#pragma once

// Reading MoveIt planning scenes and motion-plan requests (YAML), the format
// the MotionBenchMaker problem sets are published in, into flowplan problems.
//
// A scene file:
//
//   world:
//     collision_objects:
//       - id: shelf_top
//         header: {frame_id: panda_link0}
//         pose: {position: ..., orientation: ...}   # optional, MoveIt 2: primitives are relative to it
//         primitives:
//           - {type: box, dimensions: [x, y, z]}     # full side lengths
//           - {type: cylinder, dimensions: [height, radius]}
//           - {type: sphere, dimensions: [radius]}
//         primitive_poses:
//           - position: [x, y, z]                    # or {x: , y: , z: }
//             orientation: [x, y, z, w]              # or {x: , y: , z: , w: }
//
// `type` may also be SolidPrimitive's number (1 box, 2 sphere, 3 cylinder).
// A request file is a MotionPlanRequest (at the top, or under `request:` or
// `motion_plan_request:`):
//
//   start_state: {joint_state: {name: [panda_joint1, ...], position: [...]}}
//   goal_constraints:
//     - joint_constraints:
//         - {joint_name: panda_joint1, position: 0.1, tolerance_above: 0.001, tolerance_below: 0.001}
//
// Joints are matched by name; names the robot does not have (the fingers) are
// ignored. The world frame is taken to be the robot's base frame: a virtual
// joint (multi_dof_joint_state, in the scene's robot_state or the request's
// start_state) must be the identity, as in MotionBenchMaker's Panda sets;
// any other transform is an error naming it. An all-zero
// orientation (an unset ROS pose) is the identity, as in MoveIt. Only the first goal constraint is read, and only its joint
// constraints. Without a start_state the scene's robot_state is the start.

#include <string>
#include <vector>

#include "geometry/scene.h"
#include "kinematics/robot.h"
#include "problems/problem.h"

namespace flowplan::problems {

/// A scene file's obstacles with their names ("id", or "id[i]" for the i-th
/// primitive of an object of several), in the scene's numbering.
struct NamedScene {
  geometry::Scene scene;
  std::vector<std::string> names;  // (K,)
};

/// Which obstacle a goal grasps, and so is left out of the problem's scene.
enum class GraspRule {
  kNone,         // keep every obstacle
  kTouchingTcp,  // leave out every obstacle that the goal's TCP lies in or is within `grasp_margin` of
};

inline const config::EnumNames<GraspRule>& EnumEntries(GraspRule) {
  static const config::EnumNames<GraspRule> names = {{GraspRule::kNone, "none"},
                                                     {GraspRule::kTouchingTcp, "touching-tcp"}};
  return names;
}

struct MoveItImportOptions {
  /// Frames taken as the robot's base frame; an object in any other is an error.
  std::vector<std::string> base_frames = {"panda_link0", "world", "/world", "base_link", ""};
  /// Accepted names of each robot joint (J lists), e.g. {"panda_joint1", "joint1"}.
  std::vector<std::vector<std::string>> joint_names;
  GraspRule grasp = GraspRule::kTouchingTcp;
  double grasp_margin = 0.01;  // m
};

/// The names the Franka's joints go by in MoveIt (panda_jointK) and in
/// flowplan's MuJoCo model (jointK).
std::vector<std::vector<std::string>> FrankaJointNames();

/// Reads the collision objects of a MoveIt scene file.
/// @throws flowplan::Error "FILE: world.collision_objects[3] (shelf_top).primitives[0].dimensions:
///   a box needs 3 values (x, y, z), got 2", and the like for every malformed entry.
NamedScene ReadMoveItScene(const std::string& path, const MoveItImportOptions& options);

/// Start and goal joint positions (J,) of a MoveIt request, in the order of
/// options.joint_names; `scene_path` supplies the start when the request has none.
/// @throws flowplan::Error naming the file and the entry (a missing joint, a
///   goal without joint constraints, a length mismatch).
void ReadMoveItRequest(const std::string& request_path, const std::string& scene_path,
                       const MoveItImportOptions& options, std::vector<double>& start_q,
                       std::vector<double>& goal_q);

/// One problem from a scene file and a request file: the obstacles (less the
/// grasped one, by options.grasp), start and goal, their TCPs and clearances.
/// @throws flowplan::Error naming the file at fault, also for a start or goal
///   outside the arm's joint limits.
Problem ImportMoveItProblem(const kinematics::Robot& arm, const std::string& scene_path,
                            const std::string& request_path, const std::string& name,
                            const MoveItImportOptions& options);

/// Pairs sceneNNNN.yaml with requestNNNN.yaml in `folder` (MotionBenchMaker's
/// layout), sorted by NNNN; other files are ignored.
/// @throws flowplan::Error for a scene without its request, or the reverse, or no pair at all.
std::vector<std::pair<std::string, std::string>> FindMoveItPairs(const std::string& folder);

}  // namespace flowplan::problems
