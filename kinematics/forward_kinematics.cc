#include "kinematics/forward_kinematics.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::kinematics {
namespace {

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

/// [axis]× padded to 4×4.
torch::Tensor CrossMatrix(const std::array<double, 3>& axis) {
  const double n = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  const double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n;
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

ForwardKinematics::ForwardKinematics(const sim::KinematicDescription& description)
    : num_joints_(description.num_joints), tcp_link_(description.tcp_link) {
  const int64_t L = static_cast<int64_t>(description.links.size());
  std::vector<torch::Tensor> fixed, cross, cross_sq;
  for (int64_t l = 0; l < L; ++l) {
    const sim::KinematicLink& link = description.links[l];
    if (link.parent >= l || link.parent < -1) {
      throw Error("kinematics: link \"" + link.name + "\": its parent must come before it");
    }
    if (link.joint >= num_joints_ || link.joint < -1) {
      throw Error("kinematics: link \"" + link.name + "\": joint index " + std::to_string(link.joint) +
                  " outside [0, " + std::to_string(num_joints_) + ")");
    }
    link_names_.push_back(link.name);
    parents_.push_back(link.parent);
    joints_.push_back(link.joint);
    fixed.push_back(Pose(link.pos, link.quat));
    const torch::Tensor k = CrossMatrix(link.axis);
    cross.push_back(k);
    cross_sq.push_back(k.matmul(k));
  }
  if (tcp_link_ < 0 || tcp_link_ >= L) throw Error("kinematics: the TCP is on no link");
  fixed_ = torch::stack(fixed);
  axis_cross_ = torch::stack(cross);
  axis_cross_sq_ = torch::stack(cross_sq);
  tcp_ = Pose(description.tcp_pos, description.tcp_quat);

  const int64_t S = static_cast<int64_t>(description.spheres.size());
  sphere_links_ = torch::empty({S}, torch::kInt64);
  sphere_local_ = torch::empty({S, 3}, torch::kFloat64);
  sphere_radii_ = torch::empty({S}, torch::kFloat64);
  for (int64_t s = 0; s < S; ++s) {
    const sim::CollisionSphere& sphere = description.spheres[s];
    if (sphere.link < 0 || sphere.link >= L) throw Error("kinematics: sphere of \"" + sphere.geom + "\" is on no link");
    sphere_links_[s] = static_cast<int64_t>(sphere.link);
    for (int i = 0; i < 3; ++i) sphere_local_[s][i] = sphere.centre[i];
    sphere_radii_[s] = sphere.radius;
  }
}

void ForwardKinematics::CheckJoints(const torch::Tensor& q) const {
  if (!q.defined() || q.dim() != 2 || q.size(1) != num_joints_) {
    throw Error("kinematics: q: expected (B, " + std::to_string(num_joints_) + "), got " +
                (q.defined() ? ShapeText(q.sizes().vec()) : std::string("an undefined tensor")));
  }
  if (q.scalar_type() != torch::kFloat32 && q.scalar_type() != torch::kFloat64) {
    throw Error(std::string("kinematics: q: expected float32 or float64, got ") + c10::toString(q.scalar_type()));
  }
}

std::vector<torch::Tensor> ForwardKinematics::LinkFrames(const torch::Tensor& q) const {
  const auto options = q.options();
  const torch::Tensor fixed = fixed_.to(options);
  const torch::Tensor cross = axis_cross_.to(options);
  const torch::Tensor cross_sq = axis_cross_sq_.to(options);
  const torch::Tensor identity = torch::eye(4, options);
  const torch::Tensor sin_q = torch::sin(q).unsqueeze(-1).unsqueeze(-1);        // (B, J, 1, 1)
  const torch::Tensor one_minus_cos = (1 - torch::cos(q)).unsqueeze(-1).unsqueeze(-1);

  std::vector<torch::Tensor> frames;
  frames.reserve(parents_.size());
  for (size_t l = 0; l < parents_.size(); ++l) {
    torch::Tensor local = fixed[l];  // (4, 4)
    if (joints_[l] >= 0) {
      // Rodrigues: R = I + sin(q) [a]× + (1 − cos(q)) [a]×², as a 4×4 pose.
      const int64_t j = joints_[l];
      const torch::Tensor rotation =
          identity + sin_q.select(1, j) * cross[l] + one_minus_cos.select(1, j) * cross_sq[l];  // (B, 4, 4)
      local = torch::matmul(local, rotation);
    } else {
      local = local.expand({q.size(0), 4, 4});
    }
    frames.push_back(parents_[l] >= 0 ? torch::matmul(frames[parents_[l]], local) : local);
  }
  return frames;
}

FkResult ForwardKinematics::Forward(const torch::Tensor& q) const {
  CheckJoints(q);
  const std::vector<torch::Tensor> frames = LinkFrames(q);
  FkResult result;
  result.link_frames = torch::stack(frames, 1);  // (B, L, 4, 4)
  const torch::Tensor tcp = torch::matmul(frames[tcp_link_], tcp_.to(q.options()));
  result.tcp_position = tcp.index({torch::indexing::Slice(), torch::indexing::Slice(0, 3), 3});
  const torch::Tensor carriers = result.link_frames.index_select(1, sphere_links_.to(q.device()));  // (B, S, 4, 4)
  const torch::Tensor rotation = carriers.index({"...", torch::indexing::Slice(0, 3), torch::indexing::Slice(0, 3)});
  const torch::Tensor origin = carriers.index({"...", torch::indexing::Slice(0, 3), 3});
  result.sphere_centres =
      torch::matmul(rotation, sphere_local_.to(q.options()).unsqueeze(-1)).squeeze(-1) + origin;  // (B, S, 3)
  return result;
}

torch::Tensor ForwardKinematics::TcpPosition(const torch::Tensor& q) const {
  CheckJoints(q);
  const std::vector<torch::Tensor> frames = LinkFrames(q);
  const torch::Tensor tcp = torch::matmul(frames[tcp_link_], tcp_.to(q.options()));
  return tcp.index({torch::indexing::Slice(), torch::indexing::Slice(0, 3), 3});
}

torch::Tensor ForwardKinematics::SphereCentres(const torch::Tensor& q) const { return Forward(q).sphere_centres; }

torch::Tensor ForwardKinematics::SphereRadii(torch::ScalarType dtype) const { return sphere_radii_.to(dtype); }

}  // namespace flowplan::kinematics
