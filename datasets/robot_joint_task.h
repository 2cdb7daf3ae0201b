#pragma once

// The robot_joint data set: joint-space motions between random configurations
// of any robot folder (robotfiles/), tracked in MuJoCo by a computed-torque
// controller with per-joint torque noise scaled to each joint's effort limit.
// The general data set of the Franka (franka_joint) for any arm.

#include <cmath>
#include <memory>
#include <string>

#include "core/config.h"
#include "datasets/episode_task.h"
#include "robotfiles/robot_folder.h"
#include "robotfiles/robot_model.h"
#include "sim/joint_rollout.h"

namespace flowplan::collision {
class Checker;
}

namespace flowplan::datasets {

/// The `generate.robot_joint` config section.
struct RobotJointTaskConfig {
  sim::JointRolloutConfig rollout;
  // Starts and goals are uniform within the joint limits shrunk by joint_margin
  // (revolute joints, rad) or slide_margin (prismatic joints, m), free of
  // self-collision and above the floor, and every control step of the episode
  // stays so.
  double joint_margin = 0.1;
  double slide_margin = 0.01;
  double floor_height = 0.0;  // m, z of the floor the arm stands on (-.inf: none)
  int max_draws = 100;        // rollouts tried per episode; 100 x this many configurations drawn at most
  robotfiles::DriveSettings drives;
  sim::JointMotionConfig joint_motion;

  template <class V>
  void Visit(V& v) {
    rollout.Visit(v);
    v.Field("joint_margin", joint_margin, "starts and goals keep this far inside a revolute joint's limits (rad)",
            config::NonNegative());
    v.Field("slide_margin", slide_margin, "starts and goals keep this far inside a prismatic joint's limits (m)",
            config::NonNegative());
    const config::Bounds height{-INFINITY, INFINITY, false, false, "a height in m, or -.inf for no floor", true};
    v.Field("floor_height", floor_height, "z of the floor no collision sphere may go below (m; -.inf: none)", height);
    v.Field("max_draws", max_draws,
            "rollouts tried until an episode stays clear (and 100 x this many configurations drawn at most)",
            config::Positive());
    v.Field("armature", drives.armature,
            "rotor inertia added to every joint in simulation (kg m^2, or kg for a slide; the built-in Franka's: 0.1)",
            config::NonNegative());
    v.Field("damping", drives.damping, "viscous friction of every joint in simulation (N m s/rad, or N s/m)",
            config::NonNegative());
    v.Field("joint_motion", joint_motion, "the reference motion and its tracking controller");
  }
};

/// What robot_joint data of `robot` holds: env "robot_joint", the rollout's
/// dt and horizon, states q1..qJ, dq1..dqJ, P = J, extras tcp and torques.
EpisodeLayout RobotJointLayout(const kinematics::RobotDescription& robot, const RobotJointTaskConfig& config);

/// Episodes of a robot folder's robot: a start configuration drawn until it is
/// free of self-collision and above the floor, then a goal until it is too and
/// the motion to it leaves min_hold seconds at the goal; a pair whose
/// noise-free reference collides, or whose rollout does, is drawn again, up to
/// max_draws rollouts. State [q (J), q̇ (J)], P = J (the start and goal configurations),
/// extras "tcp" (T, 3) m and "torques" (T, J) applied in the physics step
/// after each state. The data's robot is the folder's (its description, with
/// the collision spheres), so what is trained on it plans for that robot.
class RobotJointTask : public EpisodeTask {
 public:
  /// Loads `folder`'s robot and its simulation model and checks `config`
  /// (`where` is its config key, for messages).
  /// @throws flowplan::Error naming the file or key at fault.
  RobotJointTask(const std::string& folder, const RobotJointTaskConfig& config,
                 const std::string& where = "generate.robot_joint");
  ~RobotJointTask() override;

  EpisodeLayout Layout() const override;
  std::vector<Family> Families() const override { return {}; }
  std::unique_ptr<EpisodeWorker> MakeWorker() const override;

 private:
  RobotJointTaskConfig config_;
  robotfiles::RobotFile file_;
  kinematics::RobotDescription robot_;
  std::shared_ptr<const robotfiles::SimulationModel> model_;
  std::shared_ptr<const collision::Checker> checker_;
};

}  // namespace flowplan::datasets
