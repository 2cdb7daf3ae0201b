#include "robotfiles/robot_model.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>

#include "core/error.h"

namespace flowplan::robotfiles {
namespace {

std::string Number(double value) { return config::internal::FormatDouble(value); }

template <size_t N>
std::string Numbers(const std::array<double, N>& values) {
  std::string text;
  for (size_t i = 0; i < N; ++i) text += (i ? " " : "") + Number(values[i]);
  return text;
}

/// XML attribute text: the characters XML reserves, escaped.
std::string Escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

/// An inertia MuJoCo accepts: `inertia` (ixx, iyy, izz, ixy, ixz, iyz) if it is positive definite, else (a URDF's
/// placeholder, such as a finger's "ixx=0.002, iyy=izz=0") its mean moment about every axis, at least 1e-6 kg m^2
/// per kg; `fixed` says which.
std::array<double, 6> SimulatedInertia(const LinkInertia& link, bool* fixed) {
  const auto& I = link.inertia;
  const double a = I[0], b = I[1], c = I[2], xy = I[3], xz = I[4], yz = I[5];
  const double minor2 = a * b - xy * xy;
  const double det = a * (b * c - yz * yz) - xy * (xy * c - yz * xz) + xz * (xy * yz - b * xz);
  const double tiny = 1e-9 * std::max(1.0, a + b + c);
  *fixed = !(a > tiny && minor2 > tiny * tiny && det > tiny * tiny * tiny);
  if (!*fixed) return I;
  const double mean = std::max((a + b + c) / 3.0, 1e-6 * link.mass);
  return {mean, mean, mean, 0.0, 0.0, 0.0};
}

}  // namespace

std::string SimulationXml(const RobotFile& file, const DriveSettings& drives, const std::string& where) {
  const kinematics::RobotDescription d = file.Description(where);
  const int L = static_cast<int>(d.links.size());
  const int J = d.num_joints;
  if (file.effort_limit.size() != static_cast<size_t>(J)) {
    throw Error(where + ": effort_limit: simulating the robot needs a torque or force limit per planned joint (" +
                std::to_string(J) + " values)");
  }
  std::map<std::string, const LinkInertia*> inertia;
  for (const LinkInertia& entry : file.inertia) {
    if (d.FindLink(entry.link) < 0) throw Error(where + ": inertia: no link \"" + entry.link + "\"");
    if (!inertia.emplace(entry.link, &entry).second) throw Error(where + ": inertia: link \"" + entry.link + "\" twice");
  }
  // A link that moves must carry mass somewhere below it, or MuJoCo cannot accelerate it.
  std::vector<double> subtree_mass(static_cast<size_t>(L), 0.0);
  for (int l = L - 1; l >= 0; --l) {
    const auto found = inertia.find(d.links[l].name);
    if (found != inertia.end()) subtree_mass[l] += found->second->mass;
    if (d.links[l].parent >= 0) subtree_mass[d.links[l].parent] += subtree_mass[l];
  }
  for (int l = 0; l < L; ++l) {
    if (d.links[l].joint >= 0 && !(subtree_mass[l] > 0.0)) {
      throw Error(where + ": inertia: the links moved by joint \"" + d.JointName(d.links[l].joint) +
                  "\" (from link \"" + d.links[l].name + "\" on) have no mass; simulating the robot needs each link's "
                  "mass and inertia (import from a model with <inertial> elements, or add them under inertia:)");
    }
  }

  std::vector<std::vector<int>> children(static_cast<size_t>(L));
  std::vector<int> roots;
  for (int l = 0; l < L; ++l) (d.links[l].parent < 0 ? roots : children[d.links[l].parent]).push_back(l);
  std::ostringstream xml;
  xml << "<mujoco model=\"" << Escaped(d.name) << "\">\n"
      << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"true\"/>\n"
      << "  <option gravity=\"0 0 -9.81\"/>\n"
      << "  <worldbody>\n";
  std::function<void(int, int)> body = [&](int l, int depth) {
    const kinematics::RobotLink& link = d.links[l];
    const std::string indent(static_cast<size_t>(2 * depth + 4), ' ');
    std::array<double, 3> pos = link.pos;
    std::array<double, 4> quat = link.quat;
    if (link.joint < 0) kinematics::FixedPose(link, pos, quat);  // a held joint is welded at its value
    xml << indent << "<body name=\"" << Escaped(link.name) << "\" pos=\"" << Numbers(pos) << "\" quat=\""
        << Numbers(quat) << "\">\n";
    const auto found = inertia.find(link.name);
    if (found != inertia.end() && found->second->mass > 0.0) {
      const LinkInertia& in = *found->second;
      bool fixed = false;
      const std::array<double, 6> inertia = SimulatedInertia(in, &fixed);
      if (fixed) {
        spdlog::warn("{}: inertia of link \"{}\" [{}] is not positive definite; simulated as {} kg m^2 about every axis",
                     where, link.name, Numbers(in.inertia), Number(inertia[0]));
      }
      xml << indent << "  <inertial pos=\"" << Numbers(in.com) << "\" mass=\"" << Number(in.mass)
          << "\" fullinertia=\"" << Numbers(inertia) << "\"/>\n";
    }
    if (link.joint >= 0) {
      const int j = link.joint;
      const bool slide = link.type == kinematics::JointType::kPrismatic;
      xml << indent << "  <joint name=\"q" << j << "\" type=\"" << (slide ? "slide" : "hinge") << "\" axis=\""
          << Numbers(link.axis) << "\"";
      if (std::isfinite(d.joint_lower[j]) && std::isfinite(d.joint_upper[j])) {
        xml << " limited=\"true\" range=\"" << Number(d.joint_lower[j]) << " " << Number(d.joint_upper[j]) << "\"";
      }
      xml << " armature=\"" << Number(drives.armature) << "\" damping=\"" << Number(drives.damping) << "\"/>\n";
    }
    if (l == d.tcp_link) {
      xml << indent << "  <site name=\"tcp\" pos=\"" << Numbers(d.tcp_pos) << "\" quat=\"" << Numbers(d.tcp_quat)
          << "\"/>\n";
    }
    for (const int c : children[l]) body(c, depth + 1);
    xml << indent << "</body>\n";
  };
  for (const int r : roots) body(r, 0);
  xml << "  </worldbody>\n  <actuator>\n";
  for (int j = 0; j < J; ++j) {
    xml << "    <motor name=\"q" << j << "\" joint=\"q" << j << "\" ctrllimited=\"true\" ctrlrange=\""
        << Number(-file.effort_limit[j]) << " " << Number(file.effort_limit[j]) << "\"/>\n";
  }
  xml << "  </actuator>\n</mujoco>\n";
  return xml.str();
}

SimulationModel LoadSimulationModel(const RobotFile& file, const DriveSettings& drives, const std::string& where) {
  SimulationModel out;
  out.model = sim::LoadModelFromXml(SimulationXml(file, drives, where), where);
  const mjModel& m = *out.model;
  const int J = file.robot.num_joints;
  FLOWPLAN_DEMAND(m.njnt == J && m.nv == J && m.nu == J);
  for (int j = 0; j < J; ++j) {
    const int id = mj_name2id(&m, mjOBJ_JOINT, ("q" + std::to_string(j)).c_str());
    FLOWPLAN_DEMAND(id >= 0);
    out.qpos.push_back(m.jnt_qposadr[id]);
    out.dof.push_back(m.jnt_dofadr[id]);
  }
  out.tcp_site = mj_name2id(&m, mjOBJ_SITE, "tcp");
  FLOWPLAN_DEMAND(out.tcp_site >= 0);
  return out;
}

}  // namespace flowplan::robotfiles
