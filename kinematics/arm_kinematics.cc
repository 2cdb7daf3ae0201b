#include "kinematics/arm_kinematics.h"

#include <cmath>

#include "core/error.h"

namespace flowplan::kinematics {
namespace {

using torch::indexing::Slice;

/// 4×4 pose from a position and a unit quaternion (w, x, y, z), float64.
torch::Tensor Pose(const std::array<double, 3>& pos, const std::array<double, 4>& quat) {
  const double n = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
  const double w = quat[0] / n, x = quat[1] / n, y = quat[2] / n, z = quat[3] / n;
  // Row-major rotation matrix of the quaternion.
  const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  torch::Tensor pose = torch::eye(4, torch::kFloat64);
  auto a = pose.accessor<double, 2>();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) a[i][j] = r[3 * i + j];
    a[i][3] = pos[i];
  }
  return pose;
}

std::array<double, 3> Unit(const std::array<double, 3>& axis) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  return {axis[0] / n, axis[1] / n, axis[2] / n};
}

/// [axis]× padded to 4×4.
torch::Tensor CrossMatrix(const std::array<double, 3>& axis) {
  const auto [x, y, z] = Unit(axis);
  torch::Tensor k = torch::zeros({4, 4}, torch::kFloat64);
  auto a = k.accessor<double, 2>();
  a[0][1] = -z;
  a[0][2] = y;
  a[1][0] = z;
  a[1][2] = -x;
  a[2][0] = -y;
  a[2][1] = x;
  return k;
}

}  // namespace

ArmKinematics::ArmKinematics(const RobotDescription& description) : Robot(description) {
  description.Validate("kinematics");
  if (description.kind != RobotKind::kArm) throw Error("kinematics: robot \"" + description.name + "\" is not an arm");
  const int64_t L = static_cast<int64_t>(description.links.size());
  const int64_t J = description.num_joints;
  std::vector<torch::Tensor> fixed, cross, cross_sq;
  joint_links_ = torch::empty({J}, torch::kInt64);
  joint_axes_ = torch::empty({J, 3}, torch::kFloat64);
  for (int64_t l = 0; l < L; ++l) {
    const RobotLink& link = description.links[l];
    link_names_.push_back(link.name);
    parents_.push_back(link.parent);
    joints_.push_back(link.joint);
    fixed.push_back(Pose(link.pos, link.quat));
    const torch::Tensor k = CrossMatrix(link.axis);
    cross.push_back(k);
    cross_sq.push_back(k.matmul(k));
    if (link.joint >= 0) {
      joint_links_[link.joint] = l;
      const auto axis = Unit(link.axis);
      for (int i = 0; i < 3; ++i) joint_axes_[link.joint][i] = axis[i];
    }
  }
  tcp_link_ = description.tcp_link;
  fixed_ = torch::stack(fixed);
  axis_cross_ = torch::stack(cross);
  axis_cross_sq_ = torch::stack(cross_sq);
  tcp_ = Pose(description.tcp_pos, description.tcp_quat);

  const int64_t S = static_cast<int64_t>(description.spheres.size());
  sphere_links_ = torch::empty({S}, torch::kInt64);
  sphere_local_ = torch::empty({S, 3}, torch::kFloat64);
  ancestors_ = torch::zeros({J, S}, torch::kFloat64);
  for (int64_t s = 0; s < S; ++s) {
    const RobotSphere& sphere = description.spheres[s];
    sphere_links_[s] = static_cast<int64_t>(sphere.link);
    for (int i = 0; i < 3; ++i) sphere_local_[s][i] = sphere.centre[i];
    for (int64_t l = sphere.link; l >= 0; l = parents_[l]) {
      if (joints_[l] >= 0) ancestors_[joints_[l]][s] = 1.0;
    }
  }
}

std::vector<torch::Tensor> ArmKinematics::LinkFrames(const torch::Tensor& q) const {
  const auto options = q.options();
  const torch::Tensor fixed = fixed_.to(options);
  const torch::Tensor cross = axis_cross_.to(options);
  const torch::Tensor cross_sq = axis_cross_sq_.to(options);
  const torch::Tensor identity = torch::eye(4, options);
  const torch::Tensor sin_q = torch::sin(q).unsqueeze(-1).unsqueeze(-1);  // (B, J, 1, 1)
  const torch::Tensor one_minus_cos = (1.0 - torch::cos(q)).unsqueeze(-1).unsqueeze(-1);

  std::vector<torch::Tensor> frames;
  frames.reserve(parents_.size());
  for (size_t l = 0; l < parents_.size(); ++l) {
    torch::Tensor local;
    if (joints_[l] >= 0) {
      // Rodrigues: R = I + sin(q) [a]× + (1 − cos(q)) [a]×², as a 4×4 pose.
      const int64_t j = joints_[l];
      const torch::Tensor rotation =
          identity + sin_q.select(1, j) * cross[l] + one_minus_cos.select(1, j) * cross_sq[l];  // (B, 4, 4)
      local = torch::matmul(fixed[l], rotation);
    } else {
      local = fixed[l].expand({q.size(0), 4, 4});
    }
    frames.push_back(parents_[l] >= 0 ? torch::matmul(frames[parents_[l]], local) : local);
  }
  return frames;
}

torch::Tensor ArmKinematics::TcpFrom(const std::vector<torch::Tensor>& frames, const torch::Tensor& q) const {
  const torch::Tensor tcp = torch::matmul(frames[tcp_link_], tcp_.to(q.options()));
  return tcp.index({Slice(), Slice(0, 3), 3});
}

FkResult ArmKinematics::Forward(const torch::Tensor& q) const {
  CheckJoints(q);
  const std::vector<torch::Tensor> frames = LinkFrames(q);
  FkResult result;
  result.link_frames = torch::stack(frames, 1);  // (B, L, 4, 4)
  result.tcp_position = TcpFrom(frames, q);
  const torch::Tensor carriers = result.link_frames.index_select(1, sphere_links_.to(q.device()));  // (B, S, 4, 4)
  const torch::Tensor rotation = carriers.index({"...", Slice(0, 3), Slice(0, 3)});
  const torch::Tensor origin = carriers.index({"...", Slice(0, 3), 3});
  result.sphere_centres =
      torch::matmul(rotation, sphere_local_.to(q.options()).unsqueeze(-1)).squeeze(-1) + origin;  // (B, S, 3)
  const torch::Tensor turned = result.link_frames.index_select(1, joint_links_.to(q.device()));  // (B, J, 4, 4)
  result.joint_axes =
      torch::matmul(turned.index({"...", Slice(0, 3), Slice(0, 3)}), joint_axes_.to(q.options()).unsqueeze(-1))
          .squeeze(-1);                                                   // (B, J, 3)
  result.joint_origins = turned.index({"...", Slice(0, 3), 3});          // (B, J, 3)
  return result;
}

torch::Tensor ArmKinematics::Tcp(const torch::Tensor& q) const {
  CheckJoints(q);
  return TcpFrom(LinkFrames(q), q);
}

SpherePoses ArmKinematics::Spheres(const torch::Tensor& q) const {
  FkResult r = Forward(q);
  return {r.sphere_centres, r.joint_axes, r.joint_origins};
}

torch::Tensor ArmKinematics::SpheresVjp(const SpherePoses& poses, const torch::Tensor& grad_centres) const {
  // ∂c_s/∂q_j = A[j, s] a_j × (c_s − p_j), so the product with g is
  // a_j · (Σ_s A[j, s] c_s × g_s − p_j × Σ_s A[j, s] g_s).
  const torch::Tensor ancestors = ancestors_.to(grad_centres.options());                         // (J, S)
  const torch::Tensor moments = torch::matmul(ancestors, torch::cross(poses.centres, grad_centres, -1));  // (N, J, 3)
  const torch::Tensor forces = torch::matmul(ancestors, grad_centres);                            // (N, J, 3)
  return (poses.joint_axes * (moments - torch::cross(poses.joint_origins, forces, -1))).sum(-1);  // (N, J)
}

void ArmKinematics::WriteScript(jit::ScriptModule& module) const {
  module.Buffer("robot_fixed", fixed_);
  module.Buffer("robot_cross", axis_cross_);
  module.Buffer("robot_cross_sq", axis_cross_sq_);
  module.Buffer("robot_tcp_pose", tcp_);
  module.Buffer("robot_sphere_links", sphere_links_);
  module.Buffer("robot_sphere_local", sphere_local_);
  module.Buffer("robot_joint_links", joint_links_);
  module.Buffer("robot_joint_axes", joint_axes_);
  module.Buffer("robot_ancestors", ancestors_);
  // The link frames, unrolled link by link exactly as LinkFrames() computes them.
  std::string s = R"PY(
def robot_link_frames(self, q: Tensor) -> Tensor:
    fixed = self.robot_fixed.to(q.dtype)
    cross = self.robot_cross.to(q.dtype)
    cross_sq = self.robot_cross_sq.to(q.dtype)
    identity = torch.eye(4, dtype=q.dtype, device=q.device)
    sin_q = torch.sin(q).unsqueeze(-1).unsqueeze(-1)
    one_minus_cos = (1.0 - torch.cos(q)).unsqueeze(-1).unsqueeze(-1)
)PY";
  std::string frames;
  for (size_t l = 0; l < parents_.size(); ++l) {
    const std::string L = std::to_string(l);
    std::string local;
    if (joints_[l] >= 0) {
      const std::string j = std::to_string(joints_[l]);
      s += "    local" + L + " = torch.matmul(fixed[" + L + "], identity + sin_q[:, " + j + "] * cross[" + L +
           "] + one_minus_cos[:, " + j + "] * cross_sq[" + L + "])\n";
    } else {
      s += "    local" + L + " = fixed[" + L + "].expand(q.size(0), 4, 4)\n";
    }
    s += "    f" + L + " = " +
         (parents_[l] >= 0 ? "torch.matmul(f" + std::to_string(parents_[l]) + ", local" + L + ")" : "local" + L) +
         "\n";
    frames += (l ? ", f" : "f") + L;
  }
  s += "    return torch.stack([" + frames + "], 1)\n";
  s += R"PY(
def robot_tcp(self, q: Tensor) -> Tensor:
    frames = self.robot_link_frames(q)
    tcp = torch.matmul(frames[:, )PY" + std::to_string(tcp_link_) + R"PY(], self.robot_tcp_pose.to(q.dtype))
    return tcp[:, 0:3, 3]

def robot_spheres(self, q: Tensor) -> Tuple[Tensor, Tensor, Tensor]:
    frames = self.robot_link_frames(q)
    carriers = frames.index_select(1, self.robot_sphere_links.to(q.device))
    centres = torch.matmul(carriers[:, :, 0:3, 0:3], self.robot_sphere_local.to(q.dtype).unsqueeze(-1)).squeeze(-1) + carriers[:, :, 0:3, 3]
    turned = frames.index_select(1, self.robot_joint_links.to(q.device))
    axes = torch.matmul(turned[:, :, 0:3, 0:3], self.robot_joint_axes.to(q.dtype).unsqueeze(-1)).squeeze(-1)
    return centres, axes, turned[:, :, 0:3, 3]

def robot_spheres_vjp(self, centres: Tensor, axes: Tensor, origins: Tensor, g: Tensor) -> Tensor:
    ancestors = self.robot_ancestors.to(g.dtype)
    moments = torch.matmul(ancestors, torch.cross(centres, g, -1))
    forces = torch.matmul(ancestors, g)
    return (axes * (moments - torch.cross(origins, forces, -1))).sum(-1)
)PY";
  module.Define(s);
  WritePublicScript(module);
}

}  // namespace flowplan::kinematics
