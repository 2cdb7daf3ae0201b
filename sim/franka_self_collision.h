#pragma once

// Self-collision and floor checks of the Franka through MuJoCo's own collision
// detection on the arm's collision capsules (geom group kCollisionGeomGroup of
// franka_panda.xml): the task-side check of the franka_joint data set.
//
// Bodies next to each other in the chain are not checked (MuJoCo's parent
// filter: the hand and fingers, welded to link7, count as link7), nor two
// more pairs whose capsules overlap at every configuration: link0–link1
// (link0 is welded to the world, which the parent filter leaves out) and
// link5–link7 (across the short link6). The floor is the plane
// z = floor_height; the base (link0) and link1, which stand on it, are not
// checked against it.

#include <mujoco/mujoco.h>

#include <functional>
#include <string>
#include <vector>

#include "sim/franka_model.h"
#include "sim/mujoco_util.h"

namespace flowplan::sim {

/// The arm model with its collision capsules colliding with each other.
/// Immutable once built; share it `const&` between threads.
class FrankaCollisionModel {
 public:
  /// `floor_height`: z (m) of the floor plane; -.inf for none.
  explicit FrankaCollisionModel(double floor_height = 0.0);

  const mjModel& mj() const { return *model_; }
  double floor_height() const { return floor_height_; }

 private:
  MjModelPtr model_;
  double floor_height_;
};

/// A per-thread checker (owns its mjData).
class FrankaCollisionChecker {
 public:
  explicit FrankaCollisionChecker(const FrankaCollisionModel& model);

  /// The first collision of configuration q (rad): "link5-hand" for two of the
  /// arm's bodies whose capsules overlap, "floor-hand" for a body below the
  /// floor; empty when there is none.
  std::string FirstCollision(const JointVector& q);

 private:
  const FrankaCollisionModel& model_;
  MjDataPtr data_;
  int link0_, link1_, link5_, link7_;
};

/// The check as one function that any thread may call (each thread keeps a
/// checker of its own): the first collision of the configuration `q` (7
/// joint positions, rad), or empty. What validity::PlanChecker and
/// RRT-Connect take as their configuration check for the Franka.
std::function<std::string(const std::vector<double>& q)> FrankaConfigurationCheck(double floor_height = 0.0);

}  // namespace flowplan::sim
