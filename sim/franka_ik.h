#pragma once

// Inverse kinematics of the Franka TCP (sim/arm_ik.h on the built-in model),
// for a TCP position with a fixed orientation (by default the gripper pointing
// down), with joint limits and a null-space posture.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <string>

#include "sim/arm_ik.h"
#include "sim/franka_model.h"

namespace flowplan::sim {

struct IkOptions : IkSettings {
  JointVector posture = FrankaReadyPose();  // rad
  Eigen::Matrix3d tcp_rotation = DownwardTcpRotation();  // target TCP orientation in the world
};

struct IkResult {
  bool converged = false;
  JointVector q = JointVector::Zero();  // rad; the closest configuration found if not converged
  double position_error = 0.0;          // m, |target - TCP| at q
  double orientation_error = 0.0;       // rad
  int iterations = 0;                   // iteration at which q was reached
};

/// Solves for a configuration whose TCP is at `target` (m, world frame) with
/// the orientation options.tcp_rotation, starting from `seed` and, if that
/// fails, from options.posture. Joints stay options.limit_margin inside their
/// limits. Deterministic: the same inputs give the same q. Uses `d` as scratch.
IkResult SolveTcpIk(const FrankaModel& model, mjData& d, const Eigen::Vector3d& target,
                    const JointVector& seed, const IkOptions& options = {});

/// As SolveTcpIk, but an unconverged solve is an error.
/// @throws flowplan::Error "franka IK: target (2.0, 0.0, 0.5) is unreachable (closest 0.61 m away)".
JointVector SolveTcpIkOrThrow(const FrankaModel& model, mjData& d, const Eigen::Vector3d& target,
                              const JointVector& seed, const IkOptions& options = {});

/// The Franka's joints and TCP site in `model`, for SolveArmIk.
ArmIkModel FrankaIkModel(const FrankaModel& model);

/// "(0.5, -0.3, 0.2)": a point as written in messages and dataset names.
std::string FormatPoint(const Eigen::Vector3d& p);

}  // namespace flowplan::sim
