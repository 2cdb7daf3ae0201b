#include "kinematics/robot_description.h"

#include "core/error.h"

namespace flowplan::kinematics {

int RobotDescription::FindLink(const std::string& link_name) const {
  for (size_t i = 0; i < links.size(); ++i) {
    if (links[i].name == link_name) return static_cast<int>(i);
  }
  return -1;
}

void RobotDescription::Validate(const std::string& where) const {
  const std::string prefix = where + ": robot \"" + name + "\": ";
  const size_t J = static_cast<size_t>(num_joints);
  if (joint_lower.size() != J || joint_upper.size() != J) {
    throw Error(prefix + "expected " + std::to_string(J) + " lower and upper limits, got " +
                std::to_string(joint_lower.size()) + " and " + std::to_string(joint_upper.size()));
  }
  for (size_t j = 0; j < J; ++j) {
    if (!(joint_lower[j] < joint_upper[j])) {
      throw Error(prefix + "joint " + std::to_string(j) + ": expected lower < upper limit");
    }
  }
  if (!velocity_limit.empty() && velocity_limit.size() != J) {
    throw Error(prefix + "expected " + std::to_string(J) + " velocity limits or none, got " +
                std::to_string(velocity_limit.size()));
  }
  if (!home.empty() && home.size() != J) {
    throw Error(prefix + "expected " + std::to_string(J) + " home joint values or none, got " +
                std::to_string(home.size()));
  }
  for (size_t j = 0; j < home.size(); ++j) {
    if (home[j] < joint_lower[j] || home[j] > joint_upper[j]) {
      throw Error(prefix + "home joint " + std::to_string(j) + " is outside its limits");
    }
  }
  if (kind == RobotKind::kPoint) {
    if (num_joints != workspace_dim) {
      throw Error(prefix + "a point robot's num_joints must equal its workspace_dim (" +
                  std::to_string(workspace_dim) + "), got " + std::to_string(num_joints));
    }
    if (!links.empty() || !spheres.empty()) throw Error(prefix + "a point robot has no links or spheres");
    return;
  }
  if (workspace_dim != 3) throw Error(prefix + "an arm moves in 3-D (workspace_dim 3)");
  const int L = static_cast<int>(links.size());
  std::vector<bool> joint_used(J, false);
  for (int l = 0; l < L; ++l) {
    const RobotLink& link = links[l];
    if (link.parent >= l || link.parent < -1) {
      throw Error(prefix + "link \"" + link.name + "\": its parent must come before it");
    }
    if (link.joint >= num_joints || link.joint < -1) {
      throw Error(prefix + "link \"" + link.name + "\": joint index " + std::to_string(link.joint) +
                  " outside [0, " + std::to_string(num_joints) + ")");
    }
    if (link.joint >= 0) {
      if (joint_used[link.joint]) {
        throw Error(prefix + "joint " + std::to_string(link.joint) + " turns more than one link");
      }
      joint_used[link.joint] = true;
      const auto& a = link.axis;
      if (!(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] > 0.0)) {
        throw Error(prefix + "link \"" + link.name + "\": its hinge axis is zero");
      }
    }
  }
  for (size_t j = 0; j < J; ++j) {
    if (!joint_used[j]) throw Error(prefix + "joint " + std::to_string(j) + " turns no link");
  }
  if (tcp_link < 0 || tcp_link >= L) throw Error(prefix + "the TCP is on no link");
  for (size_t s = 0; s < spheres.size(); ++s) {
    if (spheres[s].link < 0 || spheres[s].link >= L) {
      throw Error(prefix + "sphere " + std::to_string(s) + " (" + spheres[s].geom + ") is on no link");
    }
  }
}

std::string RobotToYaml(const RobotDescription& robot) { return config::ToYaml(robot); }

RobotDescription RobotFromYaml(const std::string& yaml, const std::string& source) {
  RobotDescription robot;
  config::Apply(config::ParseYamlText(yaml, source), robot, source);
  robot.Validate(source);
  return robot;
}

RobotDescription PointRobot(const std::string& name, int workspace_dim, double radius, double lower, double upper) {
  RobotDescription robot;
  robot.name = name;
  robot.kind = RobotKind::kPoint;
  robot.workspace_dim = workspace_dim;
  robot.num_joints = workspace_dim;
  robot.joint_lower.assign(static_cast<size_t>(workspace_dim), lower);
  robot.joint_upper.assign(static_cast<size_t>(workspace_dim), upper);
  robot.point_radius = radius;
  return robot;
}

}  // namespace flowplan::kinematics
