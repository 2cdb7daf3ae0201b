#pragma once

// The Franka Panda model: the MJCF built into the library (sim/assets/
// franka_panda.xml), its limits, its plain kinematic description and forward
// kinematics through MuJoCo.

#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/config.h"
#include "kinematics/robot_description.h"
#include "sim/mujoco_util.h"

namespace flowplan::sim {

inline constexpr int kFrankaJoints = 7;  // J

/// Joint-space vector of the arm, (J,) = (7,).
using JointVector = Eigen::Matrix<double, kFrankaJoints, 1>;

/// The ready pose q = [0, -pi/4, 0, -3pi/4, 0, pi/2, pi/4] (rad): TCP pointing down.
JointVector FrankaReadyPose();

/// The TCP orientation "gripper pointing down": TCP z along world -z, hand x
/// along world +x, i.e. diag(1, -1, -1) (the ready pose's TCP orientation).
Eigen::Matrix3d DownwardTcpRotation();

/// Physics integrators that support the split mj_step1/mj_step2 step.
enum class Integrator { kEuler, kImplicit };

inline const config::EnumNames<Integrator>& EnumEntries(Integrator) {
  static const config::EnumNames<Integrator> names = {{Integrator::kEuler, "euler"},
                                                      {Integrator::kImplicit, "implicit"}};
  return names;
}

/// Per-joint limits, read from the model.
struct FrankaLimits {
  JointVector q_lower;   // rad
  JointVector q_upper;   // rad
  JointVector velocity;  // rad/s, |q̇| limit
  JointVector torque;    // N·m, |τ| limit
};

/// Extracts the robot description (kinematics/robot_description.h) of `m`,
/// named `name`: the kinematic tree (every body but the world), the TCP site
/// `tcp_site` and collision spheres from the sphere and capsule geoms of geom
/// group `collision_group`. A sphere geom gives one sphere. A capsule of radius
/// r and half-length h gives n = ceil(2h / r) + 1 spheres spaced s = 2h / (n - 1)
/// along its axis with radius sqrt(r² + s²/4), so that their union contains the
/// capsule (it overestimates the radius by at most 12 %).
/// @throws flowplan::Error if a body has more than one joint, a joint is not a
///   hinge through its body origin with qpos0 = 0, the site is missing, or a
///   collision geom is neither a sphere nor a capsule.
kinematics::RobotDescription DescribeKinematics(const mjModel& m, const std::string& tcp_site,
                                        int collision_group);

/// Completes the Franka's description from DescribeKinematics with what the
/// MJCF does not say: the joints' MoveIt names (panda_joint1..7), the fingers
/// as prismatic joints held closed (panda_finger_joint1/2, opened by a
/// problem's held values), the self-collision pairs to ignore and the links
/// that stand on a floor.
void DescribeFrankaCollisions(kinematics::RobotDescription& description);

/// The geom group of the collision capsules and spheres in franka_panda.xml.
inline constexpr int kCollisionGeomGroup = 3;

/// The compiled Franka model with the indices and data flowplan needs. Heavy and
/// move-only; share it `const&` between threads (each thread owns its mjData).
class FrankaModel {
 public:
  /// Compiles `xml` and checks that it is the arm flowplan expects: 7 hinge
  /// joints with limits, 7 torque motors (gear 1, limited), sites "tcp" and
  /// "flange", a body "hand" and a 7-value custom numeric "velocity_limit".
  /// @throws flowplan::Error naming `source` and what is missing or wrong.
  FrankaModel(const std::string& xml, const std::string& source);
  /// Takes over a compiled model and checks it as above.
  FrankaModel(MjModelPtr model, std::string source);

  FrankaModel(FrankaModel&&) = default;
  FrankaModel& operator=(FrankaModel&&) = default;
  FrankaModel(const FrankaModel&) = delete;
  FrankaModel& operator=(const FrankaModel&) = delete;

  /// A deep copy (a new mjModel).
  FrankaModel Clone() const;

  const mjModel& mj() const { return *model_; }
  const FrankaLimits& limits() const { return limits_; }
  /// Kinematic tree and collision spheres, for the LibTorch kinematics.
  const kinematics::RobotDescription& description() const { return description_; }
  const std::string& source() const { return source_; }
  int tcp_site() const { return tcp_site_; }
  int flange_site() const { return flange_site_; }
  int hand_body() const { return hand_body_; }

  /// Sets the physics timestep (s) and integrator, and disables collision
  /// detection (nothing collides in rollouts). Call before sharing the model.
  /// @throws flowplan::Error if timestep is not positive.
  void SetPhysics(double timestep, Integrator integrator);

  /// Lets the arm's collision geoms (group kCollisionGeomGroup) collide with
  /// static world geoms (obstacles), and nothing else, and turns collision
  /// detection on. Call after SetPhysics and before sharing the model.
  void EnableObstacleContacts();

 private:
  MjModelPtr model_;
  std::string source_;
  FrankaLimits limits_;
  kinematics::RobotDescription description_;
  int tcp_site_ = -1;
  int flange_site_ = -1;
  int hand_body_ = -1;
};

/// The MJCF text compiled into the library.
const std::string& FrankaModelXml();

/// The built-in model (from FrankaModelXml(); no file is read).
FrankaModel LoadFrankaModel();

/// A model from an MJCF file, e.g. sim/assets/franka_panda.xml.
/// @throws flowplan::Error naming the file if it is missing or not a valid arm model.
FrankaModel LoadFrankaModelFile(const std::string& path);

/// Poses in the world frame (the robot base frame), in metres.
struct FrankaPose {
  Eigen::Vector3d tcp_position;      // m
  Eigen::Matrix3d tcp_rotation;      // columns: TCP axes in the world
  Eigen::Vector3d flange_position;   // m
  Eigen::Matrix3d flange_rotation;
};

/// Forward kinematics through MuJoCo (mj_kinematics on `d`).
FrankaPose FrankaForwardKinematics(const FrankaModel& model, mjData& d, const JointVector& q);

/// Forward kinematics with a temporary workspace, for one-off queries
/// (`flowplan fk`). `q` holds 7 joint angles in rad.
/// @throws flowplan::Error "q: expected 7 joint values, got N" for a wrong size.
FrankaPose FrankaForwardKinematics(const FrankaModel& model, const std::vector<double>& q);

}  // namespace flowplan::sim
