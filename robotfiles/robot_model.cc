#include "robotfiles/robot_model.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <sstream>

#include "core/error.h"
#include "sim/arm_xml.h"

namespace flowplan::robotfiles {
namespace {

std::string Number(double value) { return config::internal::FormatDouble(value); }

template <size_t N>
std::string Numbers(const std::array<double, N>& values) {
  std::string text;
  for (size_t i = 0; i < N; ++i) text += (i ? " " : "") + Number(values[i]);
  return text;
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

  sim::ArmXmlOptions options;
  options.compiler = "angle=\"radian\" inertiafromgeom=\"false\" balanceinertia=\"true\"";
  options.effort_limit = file.effort_limit;
  options.armature = drives.armature;
  options.damping = drives.damping;
  for (const auto& [name, in] : inertia) {
    if (!(in->mass > 0.0)) continue;
    bool fixed = false;
    const std::array<double, 6> moments = SimulatedInertia(*in, &fixed);
    if (fixed) {
      spdlog::warn("{}: inertia of link \"{}\" [{}] is not positive definite; simulated as {} kg m^2 about every axis",
                   where, name, Numbers(in->inertia), Number(moments[0]));
    }
    options.body_elements[name] = "      <inertial pos=\"" + Numbers(in->com) + "\" mass=\"" + Number(in->mass) +
                                  "\" fullinertia=\"" + Numbers(moments) + "\"/>\n";
  }
  return sim::ArmXml(d, options);
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
