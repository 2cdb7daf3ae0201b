#include "sim/franka_model.h"

#include <cmath>

#include "core/error.h"

namespace flowplan::sim {

// Defined in the build folder, generated from sim/assets/franka_panda.xml.
namespace internal {
extern const char* const kFrankaPandaXml;
extern const char* const kFrankaCollisionYaml;
}  // namespace internal

namespace {

std::string Name(const mjModel& m, mjtObj type, int id) {
  const char* name = mj_id2name(&m, type, id);
  return name != nullptr ? std::string(name) : "#" + std::to_string(id);
}

int RequireId(const mjModel& m, mjtObj type, const char* name, const char* what,
              const std::string& source) {
  const int id = mj_name2id(&m, type, name);
  if (id < 0) throw Error(source + ": expected a " + what + " named \"" + name + "\", found none");
  return id;
}

std::array<double, 3> Vec3(const mjtNum* v) { return {v[0], v[1], v[2]}; }
std::array<double, 4> Quat(const mjtNum* v) { return {v[0], v[1], v[2], v[3]}; }

void AddCapsuleSpheres(const mjModel& m, int geom, int link, std::vector<kinematics::RobotSphere>& out) {
  const double radius = m.geom_size[3 * geom];
  const double half_length = m.geom_size[3 * geom + 1];
  const int n = half_length > 0.0 ? static_cast<int>(std::ceil(2.0 * half_length / radius)) + 1 : 1;
  const double spacing = n > 1 ? 2.0 * half_length / (n - 1) : 0.0;
  const double covering_radius = std::sqrt(radius * radius + 0.25 * spacing * spacing);
  // The capsule axis is the geom's local z axis.
  mjtNum axis[3];
  const mjtNum z[3] = {0.0, 0.0, 1.0};
  mju_rotVecQuat(axis, z, m.geom_quat + 4 * geom);
  for (int k = 0; k < n; ++k) {
    const double offset = n > 1 ? -half_length + k * spacing : 0.0;
    kinematics::RobotSphere sphere;
    sphere.link = link;
    for (int i = 0; i < 3; ++i) sphere.centre[i] = m.geom_pos[3 * geom + i] + offset * axis[i];
    sphere.radius = covering_radius;
    sphere.geom = Name(m, mjOBJ_GEOM, geom);
    out.push_back(sphere);
  }
}

}  // namespace

void DescribeFrankaCollisions(kinematics::RobotDescription& d) {
  for (kinematics::RobotLink& link : d.links) {
    if (link.joint >= 0) link.joint_name = "panda_joint" + std::to_string(link.joint + 1);
    // The fingers slide along their y axes (the right finger's is turned to face the left's), held closed.
    if (link.name == "left_finger" || link.name == "right_finger") {
      link.type = kinematics::JointType::kPrismatic;
      link.axis = {0.0, 1.0, 0.0};
      link.joint_name = link.name == "left_finger" ? "panda_finger_joint1" : "panda_finger_joint2";
    }
  }
  // The collision body: spheres covering the published collision meshes, and the pairs not checked.
  const std::string source = "robots/franka_panda/collision.yaml";
  kinematics::CollisionBody body;
  config::Apply(config::ParseYamlText(internal::kFrankaCollisionYaml, source), body, source);
  kinematics::ApplyCollisionBody(body, d, source);
}

JointVector FrankaReadyPose() {
  JointVector q;
  q << 0.0, -M_PI / 4, 0.0, -3 * M_PI / 4, 0.0, M_PI / 2, M_PI / 4;
  return q;
}

Eigen::Matrix3d DownwardTcpRotation() { return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(); }

kinematics::RobotDescription DescribeKinematics(const mjModel& m, const std::string& name,
                                               const std::string& tcp_site, int collision_group) {
  kinematics::RobotDescription out;
  out.name = name;
  out.kind = kinematics::RobotKind::kArm;
  out.workspace_dim = 3;
  for (int body = 1; body < m.nbody; ++body) {
    kinematics::RobotLink link;
    link.name = Name(m, mjOBJ_BODY, body);
    link.parent = m.body_parentid[body] - 1;
    link.pos = Vec3(m.body_pos + 3 * body);
    link.quat = Quat(m.body_quat + 4 * body);
    if (m.body_jntnum[body] > 1) {
      throw Error("model: body \"" + link.name + "\": expected at most one joint, got " +
                  std::to_string(m.body_jntnum[body]));
    }
    if (m.body_jntnum[body] == 1) {
      const int j = m.body_jntadr[body];
      const std::string joint = Name(m, mjOBJ_JOINT, j);
      if (m.jnt_type[j] != mjJNT_HINGE) throw Error("model: joint \"" + joint + "\": expected a hinge");
      const mjtNum* anchor = m.jnt_pos + 3 * j;
      if (anchor[0] != 0.0 || anchor[1] != 0.0 || anchor[2] != 0.0) {
        throw Error("model: joint \"" + joint + "\": expected its axis through the body origin");
      }
      const int adr = m.jnt_qposadr[j];
      if (m.qpos0[adr] != 0.0) throw Error("model: joint \"" + joint + "\": expected qpos0 = 0");
      link.joint = adr;
      link.axis = Vec3(m.jnt_axis + 3 * j);
    }
    out.links.push_back(link);
  }
  out.num_joints = m.nq;
  out.joint_lower.assign(m.nq, -INFINITY);
  out.joint_upper.assign(m.nq, INFINITY);
  for (int j = 0; j < m.njnt; ++j) {
    if (!m.jnt_limited[j]) continue;
    out.joint_lower[m.jnt_qposadr[j]] = m.jnt_range[2 * j];
    out.joint_upper[m.jnt_qposadr[j]] = m.jnt_range[2 * j + 1];
  }
  const int site = mj_name2id(&m, mjOBJ_SITE, tcp_site.c_str());
  if (site < 0) throw Error("model: expected a site named \"" + tcp_site + "\", found none");
  out.tcp_link = m.site_bodyid[site] - 1;
  out.tcp_pos = Vec3(m.site_pos + 3 * site);
  out.tcp_quat = Quat(m.site_quat + 4 * site);
  for (int geom = 0; geom < m.ngeom; ++geom) {
    if (m.geom_group[geom] != collision_group) continue;
    const int link = m.geom_bodyid[geom] - 1;
    if (link < 0) continue;  // world geometry is scenery, not robot
    if (m.geom_type[geom] == mjGEOM_SPHERE) {
      out.spheres.push_back({link, Vec3(m.geom_pos + 3 * geom), m.geom_size[3 * geom],
                             Name(m, mjOBJ_GEOM, geom)});
    } else if (m.geom_type[geom] == mjGEOM_CAPSULE) {
      AddCapsuleSpheres(m, geom, link, out.spheres);
    } else {
      throw Error("model: geom \"" + Name(m, mjOBJ_GEOM, geom) +
                  "\": collision geoms must be spheres or capsules");
    }
  }
  return out;
}

FrankaModel::FrankaModel(const std::string& xml, const std::string& source)
    : FrankaModel(LoadModelFromXml(xml, source), source) {}

FrankaModel::FrankaModel(MjModelPtr model, std::string source)
    : model_(std::move(model)), source_(std::move(source)) {
  const mjModel& m = *model_;
  if (m.nq != kFrankaJoints || m.nv != kFrankaJoints || m.njnt != kFrankaJoints) {
    throw Error(source_ + ": expected an arm with 7 hinge joints, got nq = " + std::to_string(m.nq) +
                ", njnt = " + std::to_string(m.njnt));
  }
  if (m.nu != kFrankaJoints) {
    throw Error(source_ + ": expected 7 motors, got " + std::to_string(m.nu));
  }
  tcp_site_ = RequireId(m, mjOBJ_SITE, "tcp", "site", source_);
  flange_site_ = RequireId(m, mjOBJ_SITE, "flange", "site", source_);
  hand_body_ = RequireId(m, mjOBJ_BODY, "hand", "body", source_);
  const int numeric = RequireId(m, mjOBJ_NUMERIC, "velocity_limit", "custom numeric", source_);
  if (m.numeric_size[numeric] != kFrankaJoints) {
    throw Error(source_ + ": velocity_limit: expected 7 values, got " +
                std::to_string(m.numeric_size[numeric]));
  }
  for (int j = 0; j < kFrankaJoints; ++j) {
    const std::string joint = Name(m, mjOBJ_JOINT, j);
    if (m.jnt_type[j] != mjJNT_HINGE || m.jnt_qposadr[j] != j || !m.jnt_limited[j]) {
      throw Error(source_ + ": joint \"" + joint + "\": expected a limited hinge joint");
    }
    limits_.q_lower[j] = m.jnt_range[2 * j];
    limits_.q_upper[j] = m.jnt_range[2 * j + 1];
    limits_.velocity[j] = m.numeric_data[m.numeric_adr[numeric] + j];
    if (!(limits_.velocity[j] > 0.0)) {
      throw Error(source_ + ": velocity_limit[" + std::to_string(j) + "]: expected a positive value");
    }
    // Motor j must drive joint j directly (gear 1) within a symmetric range.
    const std::string motor = Name(m, mjOBJ_ACTUATOR, j);
    if (m.actuator_trntype[j] != mjTRN_JOINT || m.actuator_trnid[2 * j] != j ||
        m.actuator_gear[6 * j] != 1.0 || m.actuator_gaintype[j] != mjGAIN_FIXED ||
        m.actuator_gainprm[mjNGAIN * j] != 1.0 || m.actuator_biastype[j] != mjBIAS_NONE ||
        !m.actuator_ctrllimited[j] || m.actuator_ctrlrange[2 * j] != -m.actuator_ctrlrange[2 * j + 1] ||
        !(m.actuator_ctrlrange[2 * j + 1] > 0.0)) {
      throw Error(source_ + ": actuator \"" + motor + "\": expected a torque motor on joint \"" +
                  joint + "\" with gear 1 and a symmetric ctrlrange");
    }
    limits_.torque[j] = m.actuator_ctrlrange[2 * j + 1];
  }
  description_ = DescribeKinematics(m, "franka_panda", "tcp", kCollisionGeomGroup);
  DescribeFrankaCollisions(description_);
  description_.velocity_limit.assign(limits_.velocity.data(), limits_.velocity.data() + kFrankaJoints);
  const JointVector ready = FrankaReadyPose();  // gripper pointing down
  description_.home.assign(ready.data(), ready.data() + kFrankaJoints);
  description_.Validate(source_);
}

FrankaModel FrankaModel::Clone() const { return FrankaModel(CopyModel(*model_), source_); }

void FrankaModel::SetPhysics(double timestep, Integrator integrator) {
  if (!(timestep > 0.0) || !std::isfinite(timestep)) {
    throw Error(source_ + ": physics timestep: expected a positive value, got " + std::to_string(timestep));
  }
  model_->opt.timestep = timestep;
  model_->opt.integrator = integrator == Integrator::kEuler ? mjINT_EULER : mjINT_IMPLICIT;
  // The arm's geoms never collide (contype 0); skipping collision detection
  // saves its broad phase.
  model_->opt.disableflags |= mjDSBL_CONTACT;
}

void FrankaModel::EnableObstacleContacts() {
  mjModel& m = *model_;
  for (int g = 0; g < m.ngeom; ++g) {
    const bool on_arm = m.geom_bodyid[g] > 0;
    if (on_arm && m.geom_group[g] == kCollisionGeomGroup) {
      m.geom_contype[g] = 1;  // touches what has conaffinity 1: the obstacles
      m.geom_conaffinity[g] = 0;
    } else if (!on_arm) {
      m.geom_contype[g] = 0;
      m.geom_conaffinity[g] = 1;
    }
  }
  m.opt.disableflags &= ~mjDSBL_CONTACT;
}

const std::string& FrankaModelXml() {
  static const std::string xml = internal::kFrankaPandaXml;
  return xml;
}

FrankaModel LoadFrankaModel() { return FrankaModel(FrankaModelXml(), "built-in franka_panda.xml"); }

FrankaModel LoadFrankaModelFile(const std::string& path) {
  return FrankaModel(LoadModelFromFile(path), path);
}

FrankaPose FrankaForwardKinematics(const FrankaModel& model, mjData& d, const JointVector& q) {
  const mjModel& m = model.mj();
  for (int j = 0; j < kFrankaJoints; ++j) d.qpos[j] = q[j];
  mj_kinematics(&m, &d);
  FrankaPose pose;
  const int tcp = model.tcp_site(), flange = model.flange_site();
  pose.tcp_position = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * tcp);
  pose.flange_position = Eigen::Map<const Eigen::Vector3d>(d.site_xpos + 3 * flange);
  // MuJoCo stores rotation matrices row-major.
  pose.tcp_rotation = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.site_xmat + 9 * tcp);
  pose.flange_rotation =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(d.site_xmat + 9 * flange);
  return pose;
}

FrankaPose FrankaForwardKinematics(const FrankaModel& model, const std::vector<double>& q) {
  if (q.size() != kFrankaJoints) {
    throw Error("q: expected 7 joint values, got " + std::to_string(q.size()));
  }
  MjDataPtr d = MakeData(model.mj());
  return FrankaForwardKinematics(model, *d, Eigen::Map<const JointVector>(q.data()));
}

}  // namespace flowplan::sim
