#pragma once

// Inverse kinematics of any arm's TCP in a MuJoCo model: damped least squares
// on MuJoCo's site Jacobians, for a TCP position with a fixed orientation,
// with joint limits and a null-space posture. The Franka's IK
// (sim/franka_ik.h) and the scene families of any robot
// (problems/scene_families.h) both solve with it.
//
// Shapes: J planned joints.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace flowplan::sim {

/// Where an arm's planned joints and TCP are in a compiled MuJoCo model.
struct ArmIkModel {
  const mjModel* model = nullptr;
  std::vector<int> qpos;  // (J,) index into qpos of planned joint j
  std::vector<int> dof;   // (J,) index into the Jacobian's columns (qvel) of planned joint j
  int tcp_site = -1;
  Eigen::VectorXd lower, upper;  // (J,) rad (m for a slide): the joint limits
};

/// The solver's settings, the same for every arm.
struct IkSettings {
  int max_iterations = 300;
  double position_tolerance = 1e-5;     // m
  double orientation_tolerance = 1e-4;  // rad
  double damping = 0.05;                // damped-least-squares λ (m, rad)
  double max_step = 0.2;                // rad (m for a slide), largest joint change per iteration
  double limit_margin = 0.01;           // rad (m for a slide) kept from every joint limit
  double posture_gain = 0.1;            // pull towards the posture in the task's null space
  int restarts = 0;                     // further solves from seeds drawn uniformly within the limits
  uint64_t restart_seed = 0;            // seeds the draw of those restarts (the same draw for every target)
};

struct ArmIkResult {
  bool converged = false;
  Eigen::VectorXd q;               // (J,); the closest configuration found if not converged
  double position_error = 0.0;     // m, |target - TCP| at q
  double orientation_error = 0.0;  // rad
  int iterations = 0;              // iteration at which q was reached
};

/// Solves for a configuration (J,) whose TCP is at `target` (m, world frame)
/// with the orientation `rotation` (world frame), from `seed` (J,), pulled
/// towards `posture` (J,) in the null space of the task; if that does not
/// converge, once more from `posture`, then from each of settings.restarts
/// configurations drawn within the limits (Rng(settings.restart_seed)), the
/// first that converges returned, else the one of smallest position error. Joints stay
/// settings.limit_margin inside their limits. Deterministic. Uses `d` (data of arm.model) as scratch:
/// only the planned joints' qpos are written.
ArmIkResult SolveArmIk(const ArmIkModel& arm, mjData& d, const Eigen::Vector3d& target,
                       const Eigen::Matrix3d& rotation, const Eigen::VectorXd& seed, const Eigen::VectorXd& posture,
                       const IkSettings& settings = {});

}  // namespace flowplan::sim
