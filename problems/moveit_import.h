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
// Joints are matched by name; names the robot does not have are ignored, and
// joints the robot holds still (a gripper's fingers) take the start state's
// values for the problem (Problem::held). The robot's base stands where the
// virtual joint puts it (multi_dof_joint_state of the request's start_state,
// else of the scene's robot_state; the identity without one): every obstacle
// is moved into the base frame, and the base's pose in the world is kept
// (Problem::base_pose). An object's frame is the robot's base, the world
// (world_frames), or one of the scene's fixed_frame_transforms. An all-zero
// orientation (an unset ROS pose) is the identity, as in MoveIt. Only the
// first goal constraint is read, and only its joint constraints. Without a
// start_state the scene's robot_state is the start.
//
// A problem that cannot be planned is still imported, with status "refused"
// and the reason: a start or goal past a joint limit by more than
// limit_tolerance (compared in float64), or not valid by flowplan's
// validity check (collision/checker.h: the robot's spheres in an obstacle, in
// itself, or below a floor). A value past a limit by no more than the
// tolerance is moved onto the limit, and a note says so.

#include <string>
#include <vector>

#include "geometry/scene.h"
#include "collision/body_model.h"
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
  /// Frames that are the robot's base (its root link).
  std::vector<std::string> base_frames = {"panda_link0", "base_link"};
  /// Frames that are the world the virtual joint places the base in.
  std::vector<std::string> world_frames = {"world", "/world", ""};
  /// Accepted names of each robot joint (J lists), e.g. {"panda_joint1", "joint1"}.
  std::vector<std::vector<std::string>> joint_names;
  /// Joints the robot holds still, whose values the start state sets for the problem.
  std::vector<std::string> held_names;
  GraspRule grasp = GraspRule::kTouchingTcp;
  double grasp_margin = 0.01;      // m
  double limit_tolerance = 0.002;  // rad (m): past a limit by at most this, a value is moved onto it
  double floor_height = -INFINITY; // the problems' floor (m), -inf: none (MoveIt scenes have none)
  double margin = 0.0;             // clearance a start and goal keep from the obstacles to be plannable (check.margin)
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
/// grasped one, by options.grasp) in the base frame, start and goal, held
/// joints, their TCPs and clearances, and its status (refused, with the
/// reason, when it cannot be planned).
/// @throws flowplan::Error naming the file and the entry at fault for a file
///   that is not a MoveIt scene or request.
Problem ImportMoveItProblem(const collision::BodyModel& body, const std::string& scene_path,
                            const std::string& request_path, const std::string& name,
                            const MoveItImportOptions& options);

/// Pairs sceneNNNN.yaml with requestNNNN.yaml in `folder` (MotionBenchMaker's
/// layout), sorted by NNNN; other files are ignored.
/// @throws flowplan::Error for a scene without its request, or the reverse, or no pair at all.
std::vector<std::pair<std::string, std::string>> FindMoveItPairs(const std::string& folder);

}  // namespace flowplan::problems
