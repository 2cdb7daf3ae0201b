#pragma once

// Procedural scene families for any arm, in the spirit of MotionBenchMaker:
// scenes of boxes and cylinders around the arm with joint-space starts and
// goals (`flowplan problems --family NAME`, docs/planning.md):
//
//   table        clutter (3-7 boxes and cans) on a table top; start and goal
//                above it among the clutter, gripper down
//   shelf        a bookcase of 2-4 shelves in front of the arm; the goal between
//                two shelves, the gripper horizontal and pointing in; the start
//                in front of the bookcase
//   box          an open box on a table; the goal inside it from above, the
//                start above and beside it
//   cage         a frame of bars (posts, top and bottom rings, a front bar);
//                the goal inside, reached through a window, gripper horizontal;
//                the start outside
//   under_table  a table top at 0.35-0.5 m on four legs; the goal under it,
//                gripper horizontal; the start above it, gripper down
//
// Every scene stands on the floor (z = 0) in front of the arm (the direction
// its TCP lies in at home), turned by up to ±0.6 rad about the world's z axis
// through the origin. The dimensions above
// are the Franka's; for another arm every length of the scene and of the TCP
// poses drawn in it is multiplied by FamilyScale (the arm's reach over the
// Franka's), and the scene stands farther out by as much as the arm's base
// (its links that never turn) is wider than the Franka's scaled base
// (FamilyShift). The TCP's z axis is the gripper's approach direction ("gripper
// down": TCP z along world -z, TCP x along the scene's x). Starts and goals are
// inverse-kinematics solutions (sim/arm_ik.h on the arm's MuJoCo model, with
// the family's TCP orientation), inside the joint limits, and their whole arm
// (flowplan's collision spheres) keeps `clearance` from every obstacle, from
// itself and from the floor. Problem i depends only on (arm, seed, family, i)
// and the clearance.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kinematics/robot_description.h"
#include "problems/problem.h"
#include "sim/arm_ik.h"
#include "sim/franka_model.h"

namespace flowplan::problems {

/// The family names, in the order above.
const std::vector<std::string>& SceneFamilies();

/// The arm a family's problems are drawn for.
struct FamilyArm {
  kinematics::RobotDescription robot;  // its kinematics, limits and collision body: what the problems are judged by
  sim::ArmIkModel ik;                  // its planned joints and TCP in a MuJoCo model
  std::shared_ptr<const void> model;   // owns ik.model
  Eigen::VectorXd home;                // (J,) the first IK seed, and the posture IK keeps to
  double scale = 1.0;                  // FamilyScale(robot)
  double shift = 0.0;                  // m, FamilyShift(robot, scale)
  double facing = 0.0;                 // rad, FamilyFacing(robot)
};

/// The built-in Franka (its MJCF for IK); scale 1.
FamilyArm FrankaFamilyArm();

/// The robot folder `dir` (robot.yaml, and its simulation model for IK; robotfiles/robot_model.h).
/// @throws flowplan::Error naming DIR/robot.yaml if it cannot be read or simulated, has no home posture or is not
///   an arm.
FamilyArm FolderFamilyArm(const std::string& dir);

/// How far the TCP of `robot` (an arm) reaches from the world's z axis, over
/// the Franka's: the largest horizontal distance over 4,096 configurations
/// drawn uniformly within the limits (a fixed draw), one arm's over the
/// other's. Exactly 1 for the Franka.
double FamilyScale(const kinematics::RobotDescription& robot);

/// How much farther out (m) a scene stands for `robot` than for the Franka scaled by `scale`: by how much the
/// links that never turn (the base; a lift's column) reach farther from the world's z axis than the Franka's base
/// scaled by `scale` does (their spheres at home), or 0. 0 for the Franka.
double FamilyShift(const kinematics::RobotDescription& robot, double scale);

/// The direction (rad about the world's z axis) the arm faces: its TCP's azimuth at home (0 if the TCP is within
/// 1 cm of the z axis there). Scenes stand in that direction. The Franka's family arm faces 0 by definition (its
/// ready pose's TCP is on the x axis).
double FamilyFacing(const kinematics::RobotDescription& robot);

/// Problem `index` of `family`: its scene, start and goal.
/// @throws flowplan::Error for an unknown family, or if no valid problem is
///   found in 2,000 draws (a clearance too large for the family, or an arm
///   that cannot reach into it).
Problem MakeFamilyProblem(const FamilyArm& arm, const std::string& family, uint64_t seed, int index,
                          double clearance);

/// Problems 0 .. count-1 of `family`, on `threads` workers (the result does
/// not depend on the thread count).
ProblemSet MakeFamilyProblems(const FamilyArm& arm, const std::string& family, uint64_t seed, int count,
                              double clearance, int threads = 1);

}  // namespace flowplan::problems
