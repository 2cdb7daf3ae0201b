#include "kinematics/arm_kinematics.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"

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
  tcp_ancestors_ = torch::zeros({J}, torch::kFloat64);
  for (int64_t l = tcp_link_; l >= 0; l = parents_[l]) {
    if (joints_[l] >= 0) tcp_ancestors_[joints_[l]] = 1.0;
  }
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

torch::Tensor ArmKinematics::TcpFrame(const std::vector<torch::Tensor>& frames, const torch::Tensor& q) const {
  return torch::matmul(frames[tcp_link_], tcp_.to(q.options()));
}

torch::Tensor ArmKinematics::TcpFrom(const std::vector<torch::Tensor>& frames, const torch::Tensor& q) const {
  return TcpFrame(frames, q).index({Slice(), Slice(0, 3), 3});
}

namespace {

// Settings of the damped-least-squares solver, as sim/franka_ik.h's defaults.
constexpr int kIkIterations = 300;
constexpr double kIkDamping = 0.05;
constexpr double kIkMaxStep = 0.2;
constexpr double kIkLimitMargin = 0.01;
constexpr double kIkPostureGain = 0.1;

/// Rotation vectors (N, 3) of the rotations m (N, 3, 3): axis times angle.
torch::Tensor RotationVector(const torch::Tensor& m) {
  const torch::Tensor v = 0.5 * torch::stack({m.select(1, 2).select(1, 1) - m.select(1, 1).select(1, 2),
                                              m.select(1, 0).select(1, 2) - m.select(1, 2).select(1, 0),
                                              m.select(1, 1).select(1, 0) - m.select(1, 0).select(1, 1)},
                                             1);  // sin(θ) · axis
  const torch::Tensor cosine = 0.5 * (m.diagonal(0, 1, 2).sum(1) - 1.0);
  const torch::Tensor sine = v.norm(2, 1);
  const torch::Tensor angle = torch::atan2(sine, cosine);
  return v * (angle / sine.clamp_min(1e-12)).unsqueeze(1);
}

}  // namespace

IkSolution ArmKinematics::InverseTcp(const torch::Tensor& targets) const {
  const RobotDescription& d = description();
  if (d.home.empty()) throw Error("kinematics: robot \"" + d.name + "\" has no home posture to solve IK from");
  if (!targets.defined() || targets.dim() != 2 || targets.size(1) != 3) {
    throw Error("IK: targets: expected (N, 3), got " + (targets.defined() ? ShapeText(targets.sizes().vec()) : "(undefined)"));
  }
  const int64_t N = targets.size(0), J = num_joints();
  const auto options = torch::TensorOptions().dtype(torch::kFloat64);
  const torch::Tensor target = targets.to(torch::kFloat64);
  const torch::Tensor home = torch::tensor(d.home, options).view({1, J});
  const torch::Tensor lower = torch::tensor(d.joint_lower, options).view({1, J}) + kIkLimitMargin;
  const torch::Tensor upper = torch::tensor(d.joint_upper, options).view({1, J}) - kIkLimitMargin;
  const torch::Tensor goal_rotation =
      TcpFrame(LinkFrames(home), home).index({Slice(), Slice(0, 3), Slice(0, 3)});  // (1, 3, 3)
  const torch::Tensor moves_tcp = tcp_ancestors_.view({1, J, 1});
  const torch::Tensor identity = torch::eye(J, options).unsqueeze(0);
  const torch::Tensor damping = kIkDamping * kIkDamping * torch::eye(6, options).unsqueeze(0);
  torch::Tensor q = torch::max(torch::min(home.expand({N, J}), upper), lower);
  IkSolution out;
  for (int iteration = 0;; ++iteration) {
    const std::vector<torch::Tensor> frames = LinkFrames(q);
    const torch::Tensor tcp = TcpFrame(frames, q);
    const torch::Tensor position = tcp.index({Slice(), Slice(0, 3), 3});
    const torch::Tensor rotation = tcp.index({Slice(), Slice(0, 3), Slice(0, 3)});
    const torch::Tensor error = torch::cat(
        {target - position, RotationVector(torch::matmul(goal_rotation, rotation.transpose(1, 2)))}, 1);  // (N, 6)
    out.position_error = error.slice(1, 0, 3).norm(2, 1);
    out.orientation_error = error.slice(1, 3, 6).norm(2, 1);
    out.converged = (out.position_error < kIkPositionTolerance) & (out.orientation_error < kIkOrientationTolerance);
    if (iteration == kIkIterations || out.converged.all().item<bool>()) break;
    // Geometric Jacobian (N, 6, J): a_j × (p − o_j) and a_j for the joints that move the TCP.
    const torch::Tensor turned = torch::stack(frames, 1).index_select(1, joint_links_);  // (N, J, 4, 4)
    const torch::Tensor axes = torch::matmul(turned.index({"...", Slice(0, 3), Slice(0, 3)}),
                                             joint_axes_.to(options).unsqueeze(-1)).squeeze(-1) * moves_tcp;
    const torch::Tensor origins = turned.index({"...", Slice(0, 3), 3});
    const torch::Tensor linear = torch::cross(axes, position.unsqueeze(1) - origins, -1);
    const torch::Tensor jacobian = torch::cat({linear, axes}, 2).transpose(1, 2);  // (N, 6, J)
    const torch::Tensor jt = jacobian.transpose(1, 2);
    torch::Tensor step = torch::matmul(
        jt, torch::linalg::solve(torch::matmul(jacobian, jt) + damping, error.unsqueeze(-1), true)).squeeze(-1);
    // The pull towards home acts in the exact null space of the task.
    const torch::Tensor null_space = identity - torch::matmul(torch::linalg::pinv(jacobian), jacobian);
    step = step + kIkPostureGain * torch::matmul(null_space, (home - q).unsqueeze(-1)).squeeze(-1);
    const torch::Tensor largest = step.abs().amax(1, true);
    step = step * (kIkMaxStep / largest.clamp_min(kIkMaxStep));
    // Converged configurations stay where they are.
    step = step * (~out.converged).to(torch::kFloat64).unsqueeze(1);
    q = torch::max(torch::min(q + step, upper), lower);
  }
  out.q = q;
  return out;
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

torch::Tensor ArmKinematics::TcpVjp(const torch::Tensor& q, const torch::Tensor& g) const {
  // ∂p/∂q_j = a_j × (p − o_j) for the joints that move the TCP: the product with g is a_j · ((p − o_j) × g).
  const FkResult r = Forward(q);
  const torch::Tensor arm = r.tcp_position.unsqueeze(1) - r.joint_origins;  // (N, J, 3)
  return (r.joint_axes * torch::cross(arm, g.unsqueeze(1).expand_as(arm), -1)).sum(-1) *
         tcp_ancestors_.to(q.options()).unsqueeze(0);
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
  module.Buffer("robot_tcp_ancestors", tcp_ancestors_);
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

def robot_tcp_vjp(self, q: Tensor, g: Tensor) -> Tensor:
    frames = self.robot_link_frames(q)
    position = torch.matmul(frames[:, )PY" + std::to_string(tcp_link_) + R"PY(], self.robot_tcp_pose.to(q.dtype))[:, 0:3, 3]
    turned = frames.index_select(1, self.robot_joint_links.to(q.device))
    axes = torch.matmul(turned[:, :, 0:3, 0:3], self.robot_joint_axes.to(q.dtype).unsqueeze(-1)).squeeze(-1)
    arm = position.unsqueeze(1) - turned[:, :, 0:3, 3]
    return (axes * torch.cross(arm, g.unsqueeze(1).expand_as(arm), -1)).sum(-1) * self.robot_tcp_ancestors.to(q.dtype).unsqueeze(0)

def robot_spheres_vjp(self, centres: Tensor, axes: Tensor, origins: Tensor, g: Tensor) -> Tensor:
    ancestors = self.robot_ancestors.to(g.dtype)
    moments = torch.matmul(ancestors, torch.cross(centres, g, -1))
    forces = torch.matmul(ancestors, g)
    return (axes * (moments - torch.cross(origins, forces, -1))).sum(-1)
)PY";
  if (!description().home.empty()) {
    const RobotDescription& d = description();
    const std::string J = std::to_string(num_joints());
    module.Buffer("robot_home", torch::tensor(d.home, torch::kFloat64));
    module.Buffer("robot_lower", torch::tensor(d.joint_lower, torch::kFloat64));
    module.Buffer("robot_upper", torch::tensor(d.joint_upper, torch::kFloat64));
    // The solver of InverseTcp, op for op.
    s += R"PY(
def robot_rotation_vector(self, m: Tensor) -> Tensor:
    v = 0.5 * torch.stack([m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]], 1)
    cosine = 0.5 * (torch.diagonal(m, 0, 1, 2).sum(1) - 1.0)
    sine = torch.norm(v, 2, 1)
    angle = torch.atan2(sine, cosine)
    return v * (angle / sine.clamp_min(1e-12)).unsqueeze(1)

def ik(self, tcp: Tensor) -> Tensor:
    assert tcp.dim() >= 1 and tcp.size(-1) == 3, "ik: tcp: expected (..., 3), TCP positions in m"
    shape = tcp.shape[:-1]
    target = tcp.reshape(-1, 3).double()
    N = target.size(0)
    home = self.robot_home.view(1, )PY" + J + R"PY()
    lower = self.robot_lower.view(1, )PY" + J + ") + " + jit::ScriptFloat(kIkLimitMargin) + R"PY(
    upper = self.robot_upper.view(1, )PY" + J + ") - " + jit::ScriptFloat(kIkLimitMargin) + R"PY(
    goal_rotation = torch.matmul(self.robot_link_frames(home)[:, )PY" + std::to_string(tcp_link_) + R"PY(], self.robot_tcp_pose)[:, 0:3, 0:3]
    moves_tcp = self.robot_tcp_ancestors.view(1, )PY" + J + R"PY(, 1)
    identity = torch.eye()PY" + J + R"PY(, dtype=target.dtype).unsqueeze(0)
    damping = )PY" + jit::ScriptFloat(kIkDamping * kIkDamping) + R"PY( * torch.eye(6, dtype=target.dtype).unsqueeze(0)
    q = torch.max(torch.min(home.expand(N, )PY" + J + R"PY(), upper), lower)
    converged = torch.zeros([N], dtype=target.dtype) > 1.0
    for iteration in range()PY" + std::to_string(kIkIterations + 1) + R"PY():
        frames = self.robot_link_frames(q)
        tcp_frame = torch.matmul(frames[:, )PY" + std::to_string(tcp_link_) + R"PY(], self.robot_tcp_pose)
        position = tcp_frame[:, 0:3, 3]
        rotation = tcp_frame[:, 0:3, 0:3]
        error = torch.cat([target - position, self.robot_rotation_vector(torch.matmul(goal_rotation, rotation.transpose(1, 2)))], 1)
        converged = (torch.norm(error[:, 0:3], 2, 1) < )PY" + jit::ScriptFloat(kIkPositionTolerance) +
         ") & (torch.norm(error[:, 3:6], 2, 1) < " + jit::ScriptFloat(kIkOrientationTolerance) + R"PY()
        if iteration == )PY" + std::to_string(kIkIterations) + R"PY( or bool(converged.all()):
            break
        turned = frames.index_select(1, self.robot_joint_links)
        axes = torch.matmul(turned[:, :, 0:3, 0:3], self.robot_joint_axes.unsqueeze(-1)).squeeze(-1) * moves_tcp
        origins = turned[:, :, 0:3, 3]
        linear = torch.cross(axes, position.unsqueeze(1) - origins, -1)
        jacobian = torch.cat([linear, axes], 2).transpose(1, 2)
        jt = jacobian.transpose(1, 2)
        step = torch.matmul(jt, torch.linalg_solve(torch.matmul(jacobian, jt) + damping, error.unsqueeze(-1))).squeeze(-1)
        null_space = identity - torch.matmul(torch.linalg_pinv(jacobian), jacobian)
        step = step + )PY" + jit::ScriptFloat(kIkPostureGain) + R"PY( * torch.matmul(null_space, (home - q).unsqueeze(-1)).squeeze(-1)
        largest = step.abs().amax(1, True)
        step = step * ()PY" + jit::ScriptFloat(kIkMaxStep) + " / largest.clamp_min(" + jit::ScriptFloat(kIkMaxStep) + R"PY())
        step = step * torch.logical_not(converged).double().unsqueeze(1)
        q = torch.max(torch.min(q + step, upper), lower)
    assert bool(converged.all()), "ik: a target is out of reach with the TCP orientation of the home posture"
    return q.reshape(shape + [)PY" + J + R"PY(]).to(tcp.dtype)
)PY";
  }
  module.Define(s);
  WritePublicScript(module);
}

}  // namespace flowplan::kinematics
