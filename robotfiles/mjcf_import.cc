#include "robotfiles/mjcf_import.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>

#include "core/error.h"
#include "robotfiles/collision_fit.h"
#include "sim/mujoco_util.h"

namespace flowplan::robotfiles {
namespace fs = std::filesystem;

namespace {

std::string Name(const mjModel& m, mjtObj type, int id) {
  const char* name = mj_id2name(&m, type, id);
  return name != nullptr && name[0] != '\0' ? std::string(name) : "#" + std::to_string(id);
}

std::array<double, 3> Vec3(const mjtNum* v) { return {v[0], v[1], v[2]}; }
std::array<double, 4> Quat(const mjtNum* v) { return {v[0], v[1], v[2], v[3]}; }
std::string Number(double v) { return config::internal::FormatDouble(v); }

}  // namespace

ImportResult ImportMjcf(const std::string& mjcf_path, const ImportOptions& options) {
  ImportResult result;
  // From the file itself, so that MuJoCo finds meshes and includes relative to it.
  char error[1000] = "";
  const sim::MjModelPtr model(mj_loadXML(mjcf_path.c_str(), nullptr, error, sizeof(error)));
  if (!model) throw Error(mjcf_path + ": MuJoCo cannot load the model: " + error);
  const mjModel& m = *model;
  // The base body and the bodies below it, parents first (MuJoCo numbers bodies parents first).
  int base = -1;
  if (options.base.empty()) {
    for (int b = 1; b < m.nbody && base < 0; ++b) {
      if (m.body_parentid[b] == 0) base = b;
    }
    if (base < 0) throw Error(mjcf_path + ": no body in the world");
  } else {
    base = mj_name2id(&m, mjOBJ_BODY, options.base.c_str());
    if (base <= 0) throw Error(mjcf_path + ": --base: no body \"" + options.base + "\"");
  }
  std::vector<int> bodies;
  std::map<int, int> link_of;  // body -> link index
  for (int b = base; b < m.nbody; ++b) {
    if (b == base || link_of.count(m.body_parentid[b])) {
      link_of[b] = static_cast<int>(bodies.size());
      bodies.push_back(b);
    }
  }
  auto joint_of = [&](int b) -> int {  // the body's joint, -1 if welded (the base is welded to the world)
    if (b == base || m.body_jntnum[b] == 0) return -1;
    if (m.body_jntnum[b] > 1) {
      throw Error(mjcf_path + ": body \"" + Name(m, mjOBJ_BODY, b) + "\": " + std::to_string(m.body_jntnum[b]) +
                  " joints; a robot link moves by one joint");
    }
    const int j = m.body_jntadr[b];
    const std::string name = Name(m, mjOBJ_JOINT, j);
    if (m.jnt_type[j] != mjJNT_HINGE && m.jnt_type[j] != mjJNT_SLIDE) {
      throw Error(mjcf_path + ": joint \"" + name + "\": a free or ball joint; a robot folder's joints are hinges and slides");
    }
    const mjtNum* anchor = m.jnt_pos + 3 * j;
    if (std::abs(anchor[0]) > 1e-12 || std::abs(anchor[1]) > 1e-12 || std::abs(anchor[2]) > 1e-12) {
      throw Error(mjcf_path + ": joint \"" + name + "\": pos " + Number(anchor[0]) + " " + Number(anchor[1]) + " " +
                  Number(anchor[2]) + ": expected the joint through its body's origin (move the body instead)");
    }
    if (m.qpos0[m.jnt_qposadr[j]] != 0.0) throw Error(mjcf_path + ": joint \"" + name + "\": ref: expected 0");
    return j;
  };
  for (const auto& [hold, value] : options.hold) {
    const int j = mj_name2id(&m, mjOBJ_JOINT, hold.c_str());
    if (j < 0 || !link_of.count(m.jnt_bodyid[j])) throw Error(mjcf_path + ": --hold: no joint \"" + hold + "\" below the base");
  }
  // The planned joints, in order.
  std::vector<int> planned;
  if (!options.joints.empty()) {
    for (const std::string& name : options.joints) {
      const int j = mj_name2id(&m, mjOBJ_JOINT, name.c_str());
      if (j < 0 || !link_of.count(m.jnt_bodyid[j]) || m.jnt_bodyid[j] == base) {
        throw Error(mjcf_path + ": --joints: no joint \"" + name + "\" below the base body");
      }
      joint_of(m.jnt_bodyid[j]);
      if (std::find(planned.begin(), planned.end(), j) != planned.end()) {
        throw Error(mjcf_path + ": --joints: joint \"" + name + "\" named twice");
      }
      planned.push_back(j);
    }
  } else if (!options.tip.empty()) {
    const int tip = mj_name2id(&m, mjOBJ_BODY, options.tip.c_str());
    if (tip < 0 || !link_of.count(tip)) throw Error(mjcf_path + ": --tip: no body \"" + options.tip + "\" below the base");
    for (int b = tip; b != base; b = m.body_parentid[b]) {
      const int j = joint_of(b);
      if (j >= 0 && !options.hold.count(Name(m, mjOBJ_JOINT, j))) planned.insert(planned.begin(), j);
    }
  } else {
    for (const int b : bodies) {
      const int j = joint_of(b);
      if (j >= 0 && !options.hold.count(Name(m, mjOBJ_JOINT, j))) planned.push_back(j);
    }
  }
  if (planned.empty()) throw Error(mjcf_path + ": no joint to plan below the base body");
  for (const int j : planned) {
    if (options.hold.count(Name(m, mjOBJ_JOINT, j))) {
      throw Error(mjcf_path + ": joint \"" + Name(m, mjOBJ_JOINT, j) + "\" is both planned and held");
    }
  }
  const int J = static_cast<int>(planned.size());

  // Speeds: given, or the model's numeric velocity_limit.
  std::vector<double> velocity = options.velocity_limit;
  if (velocity.empty()) {
    const int numeric = mj_name2id(&m, mjOBJ_NUMERIC, "velocity_limit");
    if (numeric < 0) {
      throw Error(mjcf_path + ": an MJCF gives no joint speed limits; pass --velocity-limit v1,...,v" + std::to_string(J) +
                  " or add <custom><numeric name=\"velocity_limit\" data=\"...\"/></custom>");
    }
    if (m.numeric_size[numeric] != J) {
      throw Error(mjcf_path + ": numeric velocity_limit: " + std::to_string(m.numeric_size[numeric]) + " values for " +
                  std::to_string(J) + " planned joints");
    }
    velocity.assign(m.numeric_data + m.numeric_adr[numeric], m.numeric_data + m.numeric_adr[numeric] + J);
  }
  if (velocity.size() != static_cast<size_t>(J)) {
    throw Error("--velocity-limit: " + std::to_string(velocity.size()) + " values for " + std::to_string(J) + " planned joints");
  }

  kinematics::RobotDescription& d = result.file.robot;
  d.name = fs::path(mjcf_path).stem().string();
  if (m.names != nullptr && m.names[0] != '\0') d.name = m.names;  // the <mujoco model="..."> name
  d.kind = kinematics::RobotKind::kArm;
  d.workspace_dim = 3;
  d.num_joints = J;
  d.joint_lower.assign(J, 0.0);
  d.joint_upper.assign(J, 0.0);
  d.velocity_limit.assign(J, 0.0);
  std::vector<double> effort(J, 0.0);
  auto limits = [&](int j) -> std::pair<double, double> {
    if (m.jnt_limited[j]) return {m.jnt_range[2 * j], m.jnt_range[2 * j + 1]};
    if (m.jnt_type[j] == mjJNT_SLIDE) throw Error(mjcf_path + ": joint \"" + Name(m, mjOBJ_JOINT, j) + "\": a slide without a range");
    result.notes.push_back("joint \"" + Name(m, mjOBJ_JOINT, j) + "\" has no range: planned within [-pi, pi]");
    return {-M_PI, M_PI};
  };
  for (int k = 0; k < J; ++k) {
    const int j = planned[static_cast<size_t>(k)];
    std::tie(d.joint_lower[k], d.joint_upper[k]) = limits(j);
    d.velocity_limit[k] = velocity[static_cast<size_t>(k)];
    if (!(d.velocity_limit[k] > 0.0)) {
      throw Error(mjcf_path + ": joint \"" + Name(m, mjOBJ_JOINT, j) + "\": speed limit " + Number(d.velocity_limit[k]) +
                  ": expected > 0");
    }
    for (int a = 0; a < m.nu; ++a) {
      if (m.actuator_trntype[a] != mjTRN_JOINT || m.actuator_trnid[2 * a] != j) continue;
      if (m.actuator_forcelimited[a]) {
        effort[k] = std::max(std::abs(m.actuator_forcerange[2 * a]), std::abs(m.actuator_forcerange[2 * a + 1]));
      } else if (m.actuator_ctrllimited[a] && m.actuator_gaintype[a] == mjGAIN_FIXED && m.actuator_biastype[a] == mjBIAS_NONE) {
        // A motor: its control is a force or torque (a position servo's control is a position, not an effort).
        effort[k] = std::abs(m.actuator_gear[6 * a]) *
                    std::max(std::abs(m.actuator_ctrlrange[2 * a]), std::abs(m.actuator_ctrlrange[2 * a + 1]));
      }
    }
  }
  if (std::all_of(effort.begin(), effort.end(), [](double e) { return e > 0.0; })) {
    result.file.effort_limit = effort;
  } else {
    result.notes.push_back("a planned joint has no limited actuator: effort_limit left out");
  }
  for (const int b : bodies) {
    kinematics::RobotLink link;
    link.name = Name(m, mjOBJ_BODY, b);
    if (b != base) {
      link.parent = link_of.at(m.body_parentid[b]);
      link.pos = Vec3(m.body_pos + 3 * b);
      link.quat = Quat(m.body_quat + 4 * b);
    }
    const int j = joint_of(b);
    if (j >= 0) {
      const std::string name = Name(m, mjOBJ_JOINT, j);
      link.joint_name = name;
      link.axis = Vec3(m.jnt_axis + 3 * j);
      link.type = m.jnt_type[j] == mjJNT_SLIDE ? kinematics::JointType::kPrismatic : kinematics::JointType::kRevolute;
      const auto found = std::find(planned.begin(), planned.end(), j);
      if (found != planned.end()) {
        link.joint = static_cast<int>(found - planned.begin());
      } else {
        const auto [lo, hi] = limits(j);
        link.offset = options.hold.count(name) ? options.hold.at(name) : std::clamp(0.0, lo, hi);
        result.notes.push_back("joint \"" + name + "\" is held at " + Number(link.offset));
      }
    }
    d.links.push_back(link);
    if (m.body_mass[b] > 0.0) {
      LinkInertia inertia;
      inertia.link = link.name;
      inertia.mass = m.body_mass[b];
      inertia.com = Vec3(m.body_ipos + 3 * b);
      const mjtNum* principal = m.body_inertia + 3 * b;
      inertia.inertia = RotateInertia({principal[0], principal[1], principal[2], 0.0, 0.0, 0.0}, Quat(m.body_iquat + 4 * b));
      result.file.inertia.push_back(inertia);
    }
  }
  d.home.assign(J, 0.0);
  for (int k = 0; k < J; ++k) d.home[k] = std::clamp(0.0, d.joint_lower[k], d.joint_upper[k]);
  int tip = options.tip.empty() ? m.jnt_bodyid[planned.back()] : mj_name2id(&m, mjOBJ_BODY, options.tip.c_str());
  if (tip < 0 || !link_of.count(tip)) throw Error(mjcf_path + ": --tip: no body \"" + options.tip + "\" below the base");
  d.tcp_link = link_of.at(tip);
  d.tcp_pos = options.tcp_offset;
  result.notes.push_back("TCP on body \"" + Name(m, mjOBJ_BODY, tip) + "\" at " + Number(d.tcp_pos[0]) + ", " +
                         Number(d.tcp_pos[1]) + ", " + Number(d.tcp_pos[2]));

  // Collision geometry: every geom that collides, in its body's frame.
  std::map<int, LinkGeometry> by_body;
  for (int g = 0; g < m.ngeom; ++g) {
    const int b = m.geom_bodyid[g];
    if (!link_of.count(b)) continue;
    if (options.collision_group >= 0 ? m.geom_group[g] != options.collision_group
                                     : m.geom_contype[g] == 0 && m.geom_conaffinity[g] == 0) {
      continue;
    }
    const std::string where = mjcf_path + ": geom \"" + Name(m, mjOBJ_GEOM, g) + "\" of body \"" + Name(m, mjOBJ_BODY, b) + "\"";
    CollisionGeometry entry;
    entry.link = Name(m, mjOBJ_BODY, b);
    entry.pos = Vec3(m.geom_pos + 3 * g);
    entry.quat = Quat(m.geom_quat + 4 * g);
    const mjtNum* size = m.geom_size + 3 * g;
    LinkGeometry& link = by_body[b];
    link.link = entry.link;
    spheres::Mesh mesh;
    switch (m.geom_type[g]) {
      case mjGEOM_SPHERE:
        entry.shape = "sphere";
        entry.size = {size[0], 0.0, 0.0};
        link.exact.push_back({entry.pos, size[0]});
        break;
      case mjGEOM_CAPSULE:
        entry.shape = "capsule";
        entry.size = {size[0], 2 * size[1], 0.0};
        mesh = spheres::CapsuleMesh(size[0], 2 * size[1]);
        break;
      case mjGEOM_BOX:
        entry.shape = "box";
        entry.size = {2 * size[0], 2 * size[1], 2 * size[2]};
        mesh = spheres::BoxMesh(2 * size[0], 2 * size[1], 2 * size[2]);
        break;
      case mjGEOM_CYLINDER:
        entry.shape = "cylinder";
        entry.size = {size[0], 2 * size[1], 0.0};
        mesh = spheres::CylinderMesh(size[0], 2 * size[1]);
        break;
      case mjGEOM_ELLIPSOID:
        entry.shape = "ellipsoid";
        entry.size = {size[0], size[1], size[2]};
        mesh = spheres::Transformed(spheres::SphereMesh(1.0), {0, 0, 0}, {1, 0, 0, 0}, {size[0], size[1], size[2]});
        break;
      case mjGEOM_MESH: {
        const int id = m.geom_dataid[g];
        for (int v = 0; v < m.mesh_vertnum[id]; ++v) {
          const float* p = m.mesh_vert + 3 * (m.mesh_vertadr[id] + v);
          mesh.vertices.push_back({p[0], p[1], p[2]});
        }
        for (int f = 0; f < m.mesh_facenum[id]; ++f) {
          const int* t = m.mesh_face + 3 * (m.mesh_faceadr[id] + f);
          mesh.triangles.push_back({t[0], t[1], t[2]});
        }
        entry.shape = "mesh";
        entry.mesh = "meshes/" + SafeFileName(entry.link) + "_" + std::to_string(g) + ".obj";
        result.mesh_files.push_back({entry.mesh, mesh});
        break;
      }
      default:
        throw Error(where + ": a plane or height field on a robot link cannot be covered by spheres");
    }
    if (!mesh.triangles.empty()) link.pieces.push_back(spheres::Transformed(mesh, entry.pos, entry.quat));
    result.file.geometry.push_back(entry);
  }
  for (int e = 0; e < m.neq; ++e) {
    if (m.eq_type[e] == mjEQ_JOINT) {
      result.notes.push_back("equality " + Name(m, mjOBJ_EQUALITY, e) + " couples joints \"" +
                             Name(m, mjOBJ_JOINT, m.eq_obj1id[e]) + "\" and \"" +
                             (m.eq_obj2id[e] >= 0 ? Name(m, mjOBJ_JOINT, m.eq_obj2id[e]) : std::string("-")) +
                             "\"; the robot folder does not couple them (plan one and hold the other)");
    }
  }
  std::vector<LinkGeometry> gathered;
  for (const int b : bodies) {
    if (by_body.count(b)) gathered.push_back(by_body.at(b));
  }
  FitCollisionBody(gathered, options, mjcf_path, result);
  result.file.source = fs::path(mjcf_path).filename().string();
  result.file.Description(mjcf_path);  // validates
  return result;
}

}  // namespace flowplan::robotfiles
