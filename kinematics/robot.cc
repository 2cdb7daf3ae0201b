#include "kinematics/robot.h"

#include <algorithm>

#include <cmath>

#include "core/error.h"
#include "core/format.h"
#include "jit/library.h"
#include "kernels/shape_distance_kernel.h"

namespace flowplan::kinematics {
namespace {

torch::Tensor Doubles(const std::vector<double>& values) {
  return torch::tensor(values, torch::kFloat64).view({static_cast<int64_t>(values.size())});
}

/// 4×4 poses (n, 4, 4) from positions (n, 3) and quaternions (n, 4) (w, x, y, z).
torch::Tensor Poses(const torch::Tensor& positions, const torch::Tensor& quaternions) {
  const torch::Tensor rotations = jit::CallFunction("rotation_matrices", {quaternions}).toTensor();  // (n, 3, 3)
  torch::Tensor poses = torch::eye(4, torch::kFloat64).repeat({positions.size(0), 1, 1});
  poses.slice(1, 0, 3).slice(2, 0, 3).copy_(rotations);
  poses.slice(1, 0, 3).select(2, 3).copy_(positions);
  return poses;
}

/// The unit vector (3,) along `axis`.
torch::Tensor UnitAxis(const std::array<double, 3>& axis) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  return torch::tensor({axis[0] / n, axis[1] / n, axis[2] / n}, torch::kFloat64);
}

/// [a]× padded to 4×4, of the unit axis a.
torch::Tensor CrossMatrix(const std::array<double, 3>& axis) {
  const torch::Tensor unit = UnitAxis(axis);
  const double x = unit[0].item<double>(), y = unit[1].item<double>(), z = unit[2].item<double>();
  return torch::tensor({0.0, -z, y, 0.0, z, 0.0, -x, 0.0, -y, x, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, torch::kFloat64)
      .view({4, 4});
}

/// Buffers and attributes every robot class has.
void AddCommon(jit::ModuleBuilder& builder, const RobotDescription& d) {
  const int64_t J = d.num_joints;
  torch::Tensor radii = torch::empty({d.num_spheres()}, torch::kFloat64);
  if (d.kind == RobotKind::kPoint) {
    radii[0] = d.point_radius;
  } else {
    for (int64_t s = 0; s < d.num_spheres(); ++s) radii[s] = d.spheres[static_cast<size_t>(s)].radius;
  }
  builder.Buffer("sphere_radii", radii)
      .Buffer("lower", Doubles(d.joint_lower))
      .Buffer("upper", Doubles(d.joint_upper))
      .Buffer("velocity_limit", d.velocity_limit.empty() ? torch::full({J}, INFINITY, torch::kFloat64)
                                                         : Doubles(d.velocity_limit))
      .Attribute("num_joints", J)
      .Attribute("workspace_dim", static_cast<int64_t>(d.workspace_dim))
      .Attribute("num_spheres", static_cast<int64_t>(d.num_spheres()))
      .Attribute("description", RobotToYaml(d));
}

torch::jit::Module BuildArm(const RobotDescription& d) {
  const int64_t L = static_cast<int64_t>(d.links.size()), J = d.num_joints;
  const int64_t S = static_cast<int64_t>(d.spheres.size());
  torch::Tensor positions = torch::empty({L + 1, 3}, torch::kFloat64), quaternions = torch::empty({L + 1, 4}, torch::kFloat64);
  std::vector<torch::Tensor> cross, cross_sq;
  c10::List<int64_t> parents, joints;
  torch::Tensor link_joint = torch::zeros({L}, torch::kInt64), link_turns = torch::zeros({L}, torch::kFloat64);
  // Prismatic joints: a link slid by v along its unit axis a is F · Trans(v a) = F + v F [0 a; 0 0].
  torch::Tensor link_slides = torch::zeros({L}, torch::kFloat64), slide_axes = torch::zeros({L, 4, 4}, torch::kFloat64);
  torch::Tensor joint_slides = torch::zeros({J}, torch::kFloat64);
  bool has_slides = false;
  // Points fixed in the links, in homogeneous coordinates in the rows of their link's block: the collision
  // spheres' centres (S), the hinge axes (J, directions) and a point on each hinge (J, its link's origin).
  torch::Tensor frame_points = torch::zeros({4 * L, S + 2 * J}, torch::kFloat64);
  for (int64_t l = 0; l < L; ++l) {
    const RobotLink& link = d.links[static_cast<size_t>(l)];
    std::array<double, 3> pos;
    std::array<double, 4> quat;
    FixedPose(link, pos, quat);  // a held link welded at its offset
    for (int i = 0; i < 3; ++i) positions[l][i] = pos[i];
    for (int i = 0; i < 4; ++i) quaternions[l][i] = quat[i];
    const torch::Tensor k = CrossMatrix(link.axis);
    cross.push_back(k);
    cross_sq.push_back(k.matmul(k));
    parents.push_back(link.parent);
    joints.push_back(link.joint);
    if (link.joint >= 0) {
      link_joint[l] = static_cast<int64_t>(link.joint);
      const torch::Tensor axis = UnitAxis(link.axis);
      if (link.type == JointType::kPrismatic) {
        link_slides[l] = 1.0;
        joint_slides[link.joint] = 1.0;
        has_slides = true;
        for (int i = 0; i < 3; ++i) slide_axes[l][i][3] = axis[i];
      } else {
        link_turns[l] = 1.0;
      }
      for (int i = 0; i < 3; ++i) frame_points[4 * l + i][S + link.joint] = axis[i];
      frame_points[4 * l + 3][S + J + link.joint] = 1.0;
    }
  }
  for (int i = 0; i < 3; ++i) positions[L][i] = d.tcp_pos[i];
  for (int i = 0; i < 4; ++i) quaternions[L][i] = d.tcp_quat[i];
  const torch::Tensor poses = Poses(positions, quaternions);  // links, then the TCP
  torch::Tensor ancestors = torch::zeros({J, S}, torch::kFloat64), tcp_ancestors = torch::zeros({J}, torch::kFloat64);
  for (int64_t l = d.tcp_link; l >= 0; l = parents[static_cast<size_t>(l)]) {
    if (joints[static_cast<size_t>(l)] >= 0) tcp_ancestors[joints[static_cast<size_t>(l)]] = 1.0;
  }
  for (int64_t s = 0; s < S; ++s) {
    const RobotSphere& sphere = d.spheres[static_cast<size_t>(s)];
    for (int i = 0; i < 3; ++i) frame_points[4 * sphere.link + i][s] = sphere.centre[i];
    frame_points[4 * sphere.link + 3][s] = 1.0;
    for (int64_t l = sphere.link; l >= 0; l = parents[static_cast<size_t>(l)]) {
      if (joints[static_cast<size_t>(l)] >= 0) ancestors[joints[static_cast<size_t>(l)]][s] = 1.0;
    }
  }
  const IkSettings ik;
  jit::ModuleBuilder builder("Arm");
  AddCommon(builder, d);
  const torch::Tensor fixed = poses.slice(0, 0, L);
  builder.Buffer("fixed", fixed)
      .Buffer("fixed_cross", torch::matmul(fixed, torch::stack(cross)))
      .Buffer("fixed_cross_sq", torch::matmul(fixed, torch::stack(cross_sq)))
      .Buffer("link_joint", link_joint)
      .Buffer("link_turns", link_turns)
      .Buffer("link_slides", link_slides)
      .Buffer("fixed_slide", torch::matmul(fixed, slide_axes))
      .Buffer("joint_slides", joint_slides)
      .Buffer("joint_turns", 1.0 - joint_slides)
      .Attribute("has_slides", has_slides)
      .Buffer("tcp_pose", poses[L])
      .Buffer("frame_points", frame_points)
      .Buffer("ancestors", ancestors)
      .Buffer("tcp_ancestors", tcp_ancestors)
      .Buffer("home", d.home.empty() ? torch::zeros({J}, torch::kFloat64) : Doubles(d.home))
      .Attribute("parents", parents)
      .Attribute("joints", joints)
      .Attribute("tcp_link", static_cast<int64_t>(d.tcp_link))
      .Attribute("num_links", L)
      .Attribute("ik_iterations", ik.iterations)
      .Attribute("ik_damping", ik.damping)
      .Attribute("ik_max_step", ik.max_step)
      .Attribute("ik_limit_margin", ik.limit_margin)
      .Attribute("ik_posture_gain", ik.posture_gain)
      .Attribute("ik_position_tolerance", ik.position_tolerance)
      .Attribute("ik_orientation_tolerance", ik.orientation_tolerance)
      .Methods("kinematics/arm.py");
  return builder.Build();
}

torch::jit::Module BuildPoint(const RobotDescription& d) {
  jit::ModuleBuilder builder("Point");
  AddCommon(builder, d);
  return builder.Methods("kinematics/point.py").Build();
}

}  // namespace

Robot::Robot(const RobotDescription& description, const std::string& where) : description_(description) {
  description_.Validate(where);
  module_ = description_.kind == RobotKind::kPoint ? BuildPoint(description_) : BuildArm(description_);
}

torch::Tensor Robot::SphereRadii() const { return module_.attr("sphere_radii").toTensor(); }

torch::Tensor Robot::Tcp(const torch::Tensor& q) const { return jit::Call(module_, "tcp", {q}).toTensor(); }

torch::Tensor Robot::SphereCentres(const torch::Tensor& q) const {
  return jit::Call(module_, "sphere_centres", {q}).toTensor();
}

torch::Tensor Robot::Clearance(const torch::Tensor& q, const geometry::SceneRows& scene) const {
  const torch::Tensor q64 = q.to(torch::kFloat64);
  const torch::Tensor centres = SphereCentres(q64);
  return jit::CallFunction("sphere_clearance", {centres, SphereRadii(), scene}).toTensor();
}

torch::Tensor Robot::PointClearance(const torch::Tensor& points, const geometry::SceneRows& scene) {
  return jit::CallFunction("scene_distance_only", {points.to(torch::kFloat64), scene}).toTensor();
}

IkSolution Robot::InverseTcp(const torch::Tensor& targets, const torch::Tensor& seed) const {
  const int64_t W = workspace_dim(), J = num_joints();
  if (!targets.defined() || targets.dim() != 2 || targets.size(1) != W) {
    throw Error("IK: targets: expected (M, " + std::to_string(W) + "), got " +
                (targets.defined() ? ShapeText(targets.sizes().vec()) : "(undefined)"));
  }
  if (is_arm() && description_.home.empty()) {
    throw Error("kinematics: robot \"" + description_.name + "\" has no home posture to solve IK from");
  }
  torch::Tensor start = seed.defined() ? seed.to(torch::kFloat64) : targets.to(torch::kFloat64);
  if (!seed.defined() && is_arm()) start = module_.attr("home").toTensor().view({1, J}).expand({targets.size(0), J});
  const auto out = jit::Call(module_, "ik_solve", {targets.to(torch::kFloat64), start}).toTuple();
  return {out->elements()[0].toTensor(), out->elements()[1].toTensor(), out->elements()[2].toTensor(),
          out->elements()[3].toTensor()};
}

std::shared_ptr<const Robot> MakeRobot(const RobotDescription& description, const std::string& where) {
  return std::make_shared<Robot>(description, where);
}

}  // namespace flowplan::kinematics
