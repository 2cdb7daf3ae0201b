#pragma once

// A robot folder as a MuJoCo model, for simulating it (`flowplan generate`):
// the kinematic tree of robot.yaml with its planned joints (hinges and slides
// with their limits), held joints welded at their values, each link's mass and
// inertia, one torque (or force) motor per planned joint limited to the joint's
// effort limit, and a site "tcp" at the TCP. No geometry: rollouts do not
// collide; configurations are checked against the robot's spheres instead.
// For executing plans among obstacles (`flowplan plan --execute`), the same
// model with the robot's collision geometry and the obstacles as geoms.

#include <string>
#include <vector>

#include "geometry/scene.h"
#include "robotfiles/robot_folder.h"
#include "sim/arm_execution.h"
#include "sim/mujoco_util.h"

namespace flowplan::robotfiles {

/// What robot.yaml does not say about the drives, the same for every planned joint.
struct DriveSettings {
  double armature = 0.1;  // kg·m² (kg for a slide): rotor inertia reflected through the gearbox
  double damping = 1.0;   // N·m·s/rad (N·s/m): viscous joint friction
};

/// The MJCF text of `file`'s robot; `where` names it in errors. Planned joint
/// j is the joint "q<j>" and actuator j; bodies are named after the links.
/// @throws flowplan::Error naming `where` and the link if a moving link carries
///   no mass (a robot folder imported from a model without inertials), or the
///   file has no effort limits.
std::string SimulationXml(const RobotFile& file, const DriveSettings& drives, const std::string& where);

/// The compiled model of SimulationXml and where the planned joints are in it.
struct SimulationModel {
  sim::MjModelPtr model;
  std::vector<int> qpos;  // (J,) index into qpos of planned joint j
  std::vector<int> dof;   // (J,) index into qvel, qfrc_*, the mass matrix of planned joint j (nv = J)
  int tcp_site = -1;      // the site "tcp"
};

/// Compiles SimulationXml(file, drives, where).
/// @throws flowplan::Error as SimulationXml, or if MuJoCo rejects the model.
SimulationModel LoadSimulationModel(const RobotFile& file, const DriveSettings& drives, const std::string& where);

/// The robot of the folder `dir` (robot.yaml read as `file`) among the obstacles of `scene` (3-D), for
/// sim::ArmExecutor: SimulationXml(file, drives)'s model, physics at 1 / config.control_hz s, with each link's
/// collision geometry (robot.yaml's geometry: primitives as MuJoCo's own shapes, meshes as their convex hulls; a
/// link with spheres but no geometry carries its spheres) colliding with the obstacles ("obstacle0", … as
/// sim::ObstacleGeomsXml numbers them) and not with itself; contacts reported within sim::kMeasuredDistance, forces
/// only on overlaps. Links welded to the world (the base) are static in MuJoCo, which checks no static geom against
/// another: they never touch an obstacle there.
struct ExecutionModel {
  sim::MjModelPtr model;
  sim::ExecutionDrives drives;  // the planned joints, driven by the computed-torque law (execute.stiffness, .damping_ratio)
};

/// @throws flowplan::Error naming `where` as SimulationXml does, a mesh file that cannot be read, or MuJoCo's refusal.
ExecutionModel LoadExecutionModel(const RobotFile& file, const std::string& dir, const geometry::Scene& scene,
                                  const DriveSettings& drives, const sim::ExecutionConfig& config,
                                  const std::string& where);

}  // namespace flowplan::robotfiles
