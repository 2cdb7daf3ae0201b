#include "robotfiles/robot_model.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>

#include "core/error.h"
#include "sim/arm_xml.h"
#include "spheres/mesh.h"

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


/// SimulationXml's options: the drives and each link's inertial.
sim::ArmXmlOptions SimulationOptions(const RobotFile& file, const DriveSettings& drives, const std::string& where) {
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
  return options;
}

/// The joints of `model` named "q<j>" (SimulationXml's), into `qpos` and `dof`, and its site "tcp".
void FindJoints(const mjModel& m, int J, std::vector<int>* qpos, std::vector<int>* dof, int* tcp_site) {
  FLOWPLAN_DEMAND(m.nv == J && m.nu == J);
  for (int j = 0; j < J; ++j) {
    const int id = mj_name2id(&m, mjOBJ_JOINT, ("q" + std::to_string(j)).c_str());
    FLOWPLAN_DEMAND(id >= 0);
    qpos->push_back(m.jnt_qposadr[id]);
    dof->push_back(m.jnt_dofadr[id]);
  }
  *tcp_site = mj_name2id(&m, mjOBJ_SITE, "tcp");
  FLOWPLAN_DEMAND(*tcp_site >= 0);
}

/// The <geom> of one piece of collision geometry in its link's body; meshes add their <mesh> asset to `assets`.
std::string CollisionGeomXml(const CollisionGeometry& g, const std::string& dir, const std::string& name,
                             const std::string& attributes, std::string* assets, const std::string& where) {
  const std::string placed = "pos=\"" + Numbers(g.pos) + "\" quat=\"" + Numbers(g.quat) + "\"";
  std::string shape;
  if (g.shape == "sphere") {
    shape = "type=\"sphere\" size=\"" + Number(g.size[0]) + "\"";
  } else if (g.shape == "box") {
    shape = "type=\"box\" size=\"" + Number(0.5 * g.size[0]) + " " + Number(0.5 * g.size[1]) + " " +
            Number(0.5 * g.size[2]) + "\"";
  } else if (g.shape == "capsule" && !(g.size[1] > 0.0)) {
    shape = "type=\"sphere\" size=\"" + Number(g.size[0]) + "\"";  // MuJoCo needs a capsule of non-zero length
  } else if (g.shape == "cylinder" || g.shape == "capsule") {
    shape = "type=\"" + g.shape + "\" size=\"" + Number(g.size[0]) + " " + Number(0.5 * g.size[1]) + "\"";
  } else if (g.shape == "ellipsoid") {
    shape = "type=\"ellipsoid\" size=\"" + Numbers(g.size) + "\"";
  } else if (g.shape == "mesh") {
    // Read by flowplan's own mesh reader (the one the spheres were fitted with), given to MuJoCo as vertices:
    // MuJoCo collides with their convex hull.
    const spheres::Mesh mesh = spheres::LoadMesh((std::filesystem::path(dir) / g.mesh).string());
    std::string vertices;
    for (const auto& v : mesh.vertices) {
      for (int i = 0; i < 3; ++i) vertices += (vertices.empty() ? "" : " ") + Number(v[i] * g.scale[i]);
    }
    *assets += "    <mesh name=\"" + sim::XmlEscaped(name) + "\" vertex=\"" + vertices + "\"/>\n";
    shape = "type=\"mesh\" mesh=\"" + sim::XmlEscaped(name) + "\"";
  } else {
    throw Error(where + ": geometry: link \"" + g.link + "\": unknown shape \"" + g.shape + "\"");
  }
  return "      <geom name=\"" + sim::XmlEscaped(name) + "\" " + shape + " " + placed + " " + attributes + "/>\n";
}

}  // namespace

std::string SimulationXml(const RobotFile& file, const DriveSettings& drives, const std::string& where) {
  return sim::ArmXml(file.Description(where), SimulationOptions(file, drives, where));
}

SimulationModel LoadSimulationModel(const RobotFile& file, const DriveSettings& drives, const std::string& where) {
  SimulationModel out;
  out.model = sim::LoadModelFromXml(SimulationXml(file, drives, where), where);
  FindJoints(*out.model, file.robot.num_joints, &out.qpos, &out.dof, &out.tcp_site);
  return out;
}

ExecutionModel LoadExecutionModel(const RobotFile& file, const std::string& dir, const geometry::Scene& scene,
                                  const DriveSettings& drive_settings, const sim::ExecutionConfig& config,
                                  const std::string& where) {
  if (config.controller == sim::TrackingLaw::kJointPd) {
    throw Error("execute.controller: joint_pd tracks with execute.kp and execute.kd, the Franka's gains; " + where +
                "'s arm tracks with computed_torque");
  }
  scene.Validate(3, "execution scene");
  sim::InstallExactConvexOverlaps();  // the margin below would make cylinders overlap what they do not touch
  const kinematics::RobotDescription d = file.Description(where);
  sim::ArmXmlOptions options = SimulationOptions(file, drive_settings, where);
  // The arm's geoms touch what has conaffinity 1 (the obstacles), not each other; they carry no mass.
  const std::string arm = "contype=\"1\" conaffinity=\"0\" group=\"3\" mass=\"0\" rgba=\"0.7 0.7 0.7 1\"";
  std::string assets;
  std::map<std::string, int> pieces;  // per link, geoms so far
  for (const CollisionGeometry& g : file.geometry) {
    if (d.FindLink(g.link) < 0) throw Error(where + ": geometry: no link \"" + g.link + "\"");
    const std::string name = g.link + "_g" + std::to_string(pieces[g.link]++);
    options.body_elements[g.link] += CollisionGeomXml(g, dir, name, arm, &assets, where);
  }
  std::map<int, int> spheres;  // per link without geometry, its spheres so far
  for (const kinematics::RobotSphere& sphere : d.spheres) {
    const std::string& link = d.links[static_cast<size_t>(sphere.link)].name;
    if (pieces.count(link)) continue;
    const std::string name = link + "_s" + std::to_string(spheres[sphere.link]++);
    options.body_elements[link] += "      <geom name=\"" + sim::XmlEscaped(name) + "\" type=\"sphere\" pos=\"" +
                                   Numbers(sphere.centre) + "\" size=\"" + Number(sphere.radius) + "\" " + arm + "/>\n";
  }
  // Contacts are detected within kMeasuredDistance (margin) and act only on overlaps (gap = margin).
  const std::string obstacle = "margin=\"" + Number(sim::kMeasuredDistance) + "\" gap=\"" +
                               Number(sim::kMeasuredDistance) + "\" contype=\"0\" conaffinity=\"1\" group=\"4\" "
                               "rgba=\"0.8 0.2 0.2 0.5\"";
  options.world_elements = sim::ObstacleGeomsXml(scene, obstacle);
  // Room for every arm geom near every obstacle, several contacts each (MuJoCo drops what does not fit).
  int arm_geoms = 0;
  for (const auto& [link, count] : pieces) arm_geoms += count;
  for (const auto& [link, count] : spheres) arm_geoms += count;
  const int contacts = std::max(1000, 4 * arm_geoms * static_cast<int>(std::max<size_t>(scene.size(), 1)));
  options.model_elements = "  <size njmax=\"" + std::to_string(2 * contacts) + "\" nconmax=\"" +
                           std::to_string(contacts) + "\"/>\n" +
                           (assets.empty() ? std::string() : "  <asset>\n" + assets + "  </asset>\n");
  ExecutionModel out;
  out.model = sim::LoadModelFromXml(sim::ArmXml(d, options), where + " among " + std::to_string(scene.size()) +
                                                                 " obstacles");
  mjModel& m = *out.model;
  m.opt.timestep = 1.0 / config.control_hz;
  m.opt.integrator = mjINT_EULER;
  sim::ExecutionDrives& drives = out.drives;
  FindJoints(m, d.num_joints, &drives.qpos, &drives.dof, &drives.tcp_site);
  drives.effort_limit = file.effort_limit;
  drives.UseComputedTorque(config);
  return out;
}

}  // namespace flowplan::robotfiles
