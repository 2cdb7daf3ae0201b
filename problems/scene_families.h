#pragma once

// Procedural scene families for the Franka, in the spirit of MotionBenchMaker:
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
// Every scene stands in front of the arm, turned by up to ±0.6 rad about the
// base's z axis. Starts and goals are inverse-kinematics solutions (MuJoCo,
// with the family's TCP orientation), inside the joint limits, and their whole
// arm (flowplan's collision spheres) keeps `clearance` from every obstacle.
// Problem i depends only on (seed, family, i) and the clearance.

#include <cstdint>
#include <string>
#include <vector>

#include "kinematics/robot.h"
#include "problems/problem.h"
#include "sim/franka_model.h"

namespace flowplan::problems {

/// The family names, in the order above.
const std::vector<std::string>& SceneFamilies();

/// Problem `index` of `family`: its scene, start and goal.
/// @throws flowplan::Error for an unknown family, or if no valid problem is
///   found in 2,000 draws (a clearance too large for the family).
Problem MakeFamilyProblem(const kinematics::Robot& arm, const sim::FrankaModel& model, const std::string& family,
                          uint64_t seed, int index, double clearance);

/// Problems 0 .. count-1 of `family`, on `threads` workers (the result does
/// not depend on the thread count).
ProblemSet MakeFamilyProblems(const kinematics::Robot& arm, const std::string& family, uint64_t seed, int count,
                              double clearance, int threads = 1);

}  // namespace flowplan::problems
