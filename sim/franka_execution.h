#pragma once

// Executing planned joint trajectories on the simulated Franka among obstacles
// that are real collision bodies: the Franka's scene model and its drives for
// the one tracking loop of sim/arm_execution.h (joint PD with gravity
// compensation, libfranka's gains, execute.kp and execute.kd).

#include "geometry/scene.h"
#include "sim/arm_execution.h"
#include "sim/franka_model.h"

namespace flowplan::sim {

/// The Franka of FrankaModelXml() with the obstacles of `scene` (3-D) as
/// static geoms of their own shape ("obstacle0", … in the scene's numbering:
/// spheres, boxes, cylinders, capsules) that the arm's collision capsules
/// collide with (the arm does not collide with itself), contacts enabled,
/// physics at `timestep` s. MuJoCo reports every arm–obstacle pair closer than
/// kMeasuredDistance (margin) but exerts contact forces only on overlaps (gap).
/// @throws flowplan::Error if MuJoCo rejects the model.
FrankaModel MakeFrankaScene(const geometry::Scene& scene, double timestep);

/// The Franka's 7 joints in MakeFrankaScene's model, driven by joint PD with execute.kp and execute.kd (or, with
/// execute.controller: computed_torque, by the computed-torque law).
ExecutionDrives FrankaDrives(const FrankaModel& scene, const ExecutionConfig& config);

/// Tracks plans (T, 14) of the Franka in one scene of MakeFrankaScene(obstacles, 1 / config.control_hz) with
/// `num_obstacles` obstacles; owns its mjData (one per worker thread).
class FrankaExecutor : public ArmExecutor {
 public:
  FrankaExecutor(const FrankaModel& scene, int num_obstacles, const ExecutionConfig& config)
      : ArmExecutor(scene.mj(), FrankaDrives(scene, config), num_obstacles, config) {}
};

}  // namespace flowplan::sim
