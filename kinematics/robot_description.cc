#include "kinematics/robot_description.h"

#include "core/error.h"

namespace flowplan::kinematics {

int RobotDescription::FindLink(const std::string& link_name) const {
  for (size_t i = 0; i < links.size(); ++i) {
    if (links[i].name == link_name) return static_cast<int>(i);
  }
  return -1;
}

int RobotDescription::FindJoint(const std::string& joint_name) const {
  for (const RobotLink& link : links) {
    if (link.joint >= 0 && link.joint_name == joint_name) return link.joint;
  }
  return -1;
}

std::string RobotDescription::JointName(int j) const {
  for (const RobotLink& link : links) {
    if (link.joint == j && !link.joint_name.empty()) return link.joint_name;
  }
  return "joint " + std::to_string(j + 1);
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
    if (!std::isfinite(link.offset)) throw Error(prefix + "link \"" + link.name + "\": offset is not finite");
    if (link.joint >= 0) {
      if (joint_used[link.joint]) {
        throw Error(prefix + "joint " + std::to_string(link.joint) + " turns more than one link");
      }
      joint_used[link.joint] = true;
    }
    const auto& a = link.axis;
    if (link.moves() && !(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] > 0.0)) {
      throw Error(prefix + "link \"" + link.name + "\": its joint axis is zero");
    }
  }
  for (size_t j = 0; j < J; ++j) {
    if (!joint_used[j]) throw Error(prefix + "joint " + std::to_string(j) + " turns no link");
  }
  for (const auto& pair : self_collision_ignore) {
    for (const std::string& link_name : pair) {
      if (FindLink(link_name) < 0) throw Error(prefix + "self_collision_ignore: no link called \"" + link_name + "\"");
    }
  }
  for (const std::string& link_name : floor_exempt) {
    if (FindLink(link_name) < 0) throw Error(prefix + "floor_exempt: no link called \"" + link_name + "\"");
  }
  if (tcp_link < 0 || tcp_link >= L) throw Error(prefix + "the TCP is on no link");
  for (size_t s = 0; s < spheres.size(); ++s) {
    if (spheres[s].link < 0 || spheres[s].link >= L) {
      throw Error(prefix + "sphere " + std::to_string(s) + " (" + spheres[s].geom + ") is on no link");
    }
  }
}

void FixedPose(const RobotLink& link, std::array<double, 3>& pos, std::array<double, 4>& quat) {
  pos = link.pos;
  quat = link.quat;
  if (link.joint >= 0 || link.offset == 0.0) return;
  const auto& a = link.axis;
  const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double u[3] = {a[0] / n, a[1] / n, a[2] / n};
  const double qn = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
  const double w = quat[0] / qn, x = quat[1] / qn, y = quat[2] / qn, z = quat[3] / qn;
  if (link.type == JointType::kPrismatic) {
    // pos + R(quat) u offset, with R v = v + 2 w (r x v) + 2 r x (r x v) for r = (x, y, z).
    const double r[3] = {x, y, z};
    const double c1[3] = {r[1] * u[2] - r[2] * u[1], r[2] * u[0] - r[0] * u[2], r[0] * u[1] - r[1] * u[0]};
    const double c2[3] = {r[1] * c1[2] - r[2] * c1[1], r[2] * c1[0] - r[0] * c1[2], r[0] * c1[1] - r[1] * c1[0]};
    for (int i = 0; i < 3; ++i) pos[i] += (u[i] + 2.0 * w * c1[i] + 2.0 * c2[i]) * link.offset;
    return;
  }
  // quat ⊗ (cos(θ/2), sin(θ/2) u).
  const double h = 0.5 * link.offset, c = std::cos(h), s = std::sin(h);
  const double b[4] = {c, s * u[0], s * u[1], s * u[2]};
  quat = {w * b[0] - x * b[1] - y * b[2] - z * b[3], w * b[1] + x * b[0] + y * b[3] - z * b[2],
          w * b[2] - x * b[3] + y * b[0] + z * b[1], w * b[3] + x * b[2] - y * b[1] + z * b[0]};
}

void ApplyCollisionBody(const CollisionBody& body, RobotDescription& robot, const std::string& source) {
  auto link_index = [&](const std::string& name, const std::string& entry) {
    const int l = robot.FindLink(name);
    if (l < 0) throw Error(source + ": " + entry + ": robot \"" + robot.name + "\" has no link \"" + name + "\"");
    return l;
  };
  robot.spheres.clear();
  for (size_t i = 0; i < body.spheres.size(); ++i) {
    const NamedSphere& s = body.spheres[i];
    const int l = link_index(s.link, "collision.spheres[" + std::to_string(i) + "].link");
    robot.spheres.push_back({l, s.centre, s.radius, s.link + "_" + std::to_string(i)});
  }
  robot.self_collision = body.self_collision;
  robot.self_collision_ignore.clear();
  for (size_t i = 0; i < body.self_collision_ignore.size(); ++i) {
    for (const std::string& name : body.self_collision_ignore[i].links) {
      link_index(name, "collision.self_collision_ignore[" + std::to_string(i) + "]");
    }
    robot.self_collision_ignore.push_back(body.self_collision_ignore[i].links);
  }
  for (size_t i = 0; i < body.floor_exempt.size(); ++i) {
    link_index(body.floor_exempt[i], "collision.floor_exempt[" + std::to_string(i) + "]");
  }
  robot.floor_exempt = body.floor_exempt;
}

CollisionBody CollisionBodyOf(const RobotDescription& robot) {
  CollisionBody body;
  for (const RobotSphere& s : robot.spheres) body.spheres.push_back({robot.links[s.link].name, s.centre, s.radius});
  body.self_collision = robot.self_collision;
  for (const auto& pair : robot.self_collision_ignore) body.self_collision_ignore.push_back({pair, ""});
  body.floor_exempt = robot.floor_exempt;
  return body;
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
