#include "collision/body_model.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>

#include "core/error.h"

namespace flowplan::collision {
namespace {

double Norm(const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/// The rotation matrix (row-major) of a (w, x, y, z) quaternion, normalised first.
void RotationOf(const std::array<double, 4>& quat, double* R) {
  const double n = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
  const double w = quat[0] / n, x = quat[1] / n, y = quat[2] / n, z = quat[3] / n;
  R[0] = 1 - 2 * (y * y + z * z);
  R[1] = 2 * (x * y - w * z);
  R[2] = 2 * (x * z + w * y);
  R[3] = 2 * (x * y + w * z);
  R[4] = 1 - 2 * (x * x + z * z);
  R[5] = 2 * (y * z - w * x);
  R[6] = 2 * (x * z - w * y);
  R[7] = 2 * (y * z + w * x);
  R[8] = 1 - 2 * (x * x + y * y);
}

/// out = a ∘ b.
void Compose(const Frame& a, const Frame& b, Frame& out) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      out.R[3 * i + j] = a.R[3 * i] * b.R[j] + a.R[3 * i + 1] * b.R[3 + j] + a.R[3 * i + 2] * b.R[6 + j];
    }
    out.p[i] = a.R[3 * i] * b.p[0] + a.R[3 * i + 1] * b.p[1] + a.R[3 * i + 2] * b.p[2] + a.p[i];
  }
}

/// x -> R x + p of a point.
void Apply(const Frame& f, const double* x, double* out) {
  for (int i = 0; i < 3; ++i) out[i] = f.R[3 * i] * x[0] + f.R[3 * i + 1] * x[1] + f.R[3 * i + 2] * x[2] + f.p[i];
}

}  // namespace

kinematics::RobotDescription WithHeld(const kinematics::RobotDescription& robot,
                                      const std::map<std::string, double>& held) {
  kinematics::RobotDescription out = robot;
  for (const auto& [name, value] : held) {
    bool found = false;
    for (kinematics::RobotLink& link : out.links) {
      if (link.joint_name != name) continue;
      if (link.joint >= 0) {
        throw Error("held joint " + name + ": robot \"" + robot.name + "\" plans it; only joints it does not plan are held");
      }
      if (!std::isfinite(value)) throw Error("held joint " + name + ": expected a finite value");
      link.offset = value;
      found = true;
    }
    if (!found) throw Error("held joint " + name + ": robot \"" + robot.name + "\" has no such joint");
  }
  return out;
}

BodyModel::BodyModel(const kinematics::RobotDescription& robot, const std::string& where) : robot_(robot) {
  robot_.Validate(where);
  J_ = robot_.num_joints;
  W_ = robot_.workspace_dim;
  if (robot_.kind == kinematics::RobotKind::kPoint) {
    point_ = true;
    L_ = 1;
    S_ = 1;
    radius_ = {robot_.point_radius};
    sphere_link_ = {0};
    first_sphere_ = {0, 1};
    first_cluster_ = {0, 1};
    first_in_cluster_ = {0, 1};
    cluster_local_ = {0.0, 0.0, 0.0};
    cluster_radius_ = {robot_.point_radius};
    original_ = {0};
    sphere_name_ = {"the robot"};
    link_name_ = {"the robot"};
    bound_local_ = {0.0, 0.0, 0.0};
    bound_radius_ = {robot_.point_radius};
    sphere_travel_.assign(static_cast<size_t>(J_), 1.0);
    bound_travel_ = sphere_travel_;
    floor_checked_ = {1};
    ancestors_ = {J_ >= 64 ? ~uint64_t{0} : (uint64_t{1} << J_) - 1};
    joint_revolute_.assign(static_cast<size_t>(J_), 0);  // a point's coordinates slide
    return;
  }
  L_ = static_cast<int>(robot_.links.size());
  S_ = static_cast<int>(robot_.spheres.size());
  fixed_.resize(static_cast<size_t>(L_));
  for (int l = 0; l < L_; ++l) {
    const kinematics::RobotLink& link = robot_.links[static_cast<size_t>(l)];
    std::array<double, 3> pos;
    std::array<double, 4> quat;
    kinematics::FixedPose(link, pos, quat);
    RotationOf(quat, fixed_[static_cast<size_t>(l)].R);
    for (int i = 0; i < 3; ++i) fixed_[static_cast<size_t>(l)].p[i] = pos[i];
    parent_.push_back(link.parent);
    joint_.push_back(link.joint);
    const double n = Norm(link.axis);
    axis_.push_back({link.axis[0] / n, link.axis[1] / n, link.axis[2] / n});
    prismatic_.push_back(link.type == kinematics::JointType::kPrismatic ? 1 : 0);
    link_name_.push_back(link.name);
  }
  // Spheres sorted by link, and within a link into clusters of at most kClusterSize spheres near each other: a
  // link's spheres halved along the longest extent of their centres until the parts are small enough.
  std::vector<int> order(static_cast<size_t>(S_));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return robot_.spheres[a].link < robot_.spheres[b].link; });
  std::vector<std::pair<int, int>> clusters;  // [begin, end) into order
  std::function<void(int, int)> split = [&](int begin, int end) {
    if (end - begin <= kClusterSize) {
      clusters.emplace_back(begin, end);
      return;
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = begin; i < end; ++i) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], robot_.spheres[order[i]].centre[k]);
        hi[k] = std::max(hi[k], robot_.spheres[order[i]].centre[k]);
      }
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k) {
      if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    }
    const int middle = begin + (end - begin) / 2;
    std::stable_sort(order.begin() + begin, order.begin() + end, [&](int a, int b) {
      return robot_.spheres[a].centre[axis] < robot_.spheres[b].centre[axis];
    });
    split(begin, middle);
    split(middle, end);
  };
  for (int begin = 0; begin < S_;) {
    int end = begin;
    while (end < S_ && robot_.spheres[order[end]].link == robot_.spheres[order[begin]].link) ++end;
    split(begin, end);
    begin = end;
  }
  first_sphere_.assign(static_cast<size_t>(L_) + 1, 0);
  for (int s : order) {
    const kinematics::RobotSphere& sphere = robot_.spheres[static_cast<size_t>(s)];
    local_.insert(local_.end(), sphere.centre.begin(), sphere.centre.end());
    radius_.push_back(sphere.radius);
    sphere_link_.push_back(sphere.link);
    original_.push_back(s);
    sphere_name_.push_back("sphere " + std::to_string(s) + " (" + (sphere.geom.empty() ? link_name_[sphere.link] : sphere.geom) + ")");
    ++first_sphere_[static_cast<size_t>(sphere.link) + 1];
  }
  for (int l = 0; l < L_; ++l) first_sphere_[l + 1] += first_sphere_[l];
  // The clusters' bounding spheres, link by link.
  first_cluster_.assign(static_cast<size_t>(L_) + 1, 0);
  first_in_cluster_.clear();
  for (const auto& [begin, end] : clusters) {
    first_in_cluster_.push_back(begin);
    ++first_cluster_[static_cast<size_t>(sphere_link_[begin]) + 1];
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int s = begin; s < end; ++s) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], local_[3 * s + k]);
        hi[k] = std::max(hi[k], local_[3 * s + k]);
      }
    }
    double centre[3], radius = 0.0;
    for (int k = 0; k < 3; ++k) centre[k] = 0.5 * (lo[k] + hi[k]);
    for (int s = begin; s < end; ++s) {
      double d2 = 0.0;
      for (int k = 0; k < 3; ++k) d2 += (local_[3 * s + k] - centre[k]) * (local_[3 * s + k] - centre[k]);
      radius = std::max(radius, std::sqrt(d2) + radius_[s]);
    }
    cluster_local_.insert(cluster_local_.end(), centre, centre + 3);
    cluster_radius_.push_back(radius);
  }
  first_in_cluster_.push_back(S_);
  for (int l = 0; l < L_; ++l) first_cluster_[l + 1] += first_cluster_[l];

  // Each link's bounding sphere: centred on the box around its spheres' centres.
  bound_local_.assign(static_cast<size_t>(3 * L_), 0.0);
  bound_radius_.assign(static_cast<size_t>(L_), -1.0);  // no spheres: nothing to check
  for (int l = 0; l < L_; ++l) {
    const int a = first_sphere_[l], b = first_sphere_[l + 1];
    if (a == b) continue;
    for (int i = 0; i < 3; ++i) {
      double lo = INFINITY, hi = -INFINITY;
      for (int s = a; s < b; ++s) {
        lo = std::min(lo, local_[3 * s + i]);
        hi = std::max(hi, local_[3 * s + i]);
      }
      bound_local_[3 * l + i] = 0.5 * (lo + hi);
    }
    double radius = 0.0;
    for (int s = a; s < b; ++s) {
      double d2 = 0.0;
      for (int i = 0; i < 3; ++i) d2 += (local_[3 * s + i] - bound_local_[3 * l + i]) * (local_[3 * s + i] - bound_local_[3 * l + i]);
      radius = std::max(radius, std::sqrt(d2) + radius_[s]);
    }
    bound_radius_[l] = radius;
  }

  // Travel bounds: walking up from a point's link, `reach` bounds the distance from the current link's origin
  // (where its joint's axis passes) to the point; a prismatic joint below adds its longest extension.
  auto travel = [&](int link, const double* point, double* out) {
    std::fill(out, out + J_, 0.0);
    double reach = std::sqrt(point[0] * point[0] + point[1] * point[1] + point[2] * point[2]);
    for (int l = link; l >= 0; l = parent_[l]) {
      const int j = joint_[l];
      if (j >= 0) {
        if (prismatic_[l]) {
          out[j] = 1.0;
          reach += std::max(std::abs(robot_.joint_lower[j]), std::abs(robot_.joint_upper[j]));
        } else {
          out[j] = reach;
        }
      }
      const Frame& f = fixed_[static_cast<size_t>(l)];
      reach += std::sqrt(f.p[0] * f.p[0] + f.p[1] * f.p[1] + f.p[2] * f.p[2]);
    }
  };
  sphere_travel_.assign(static_cast<size_t>(S_) * J_, 0.0);
  bound_travel_.assign(static_cast<size_t>(L_) * J_, 0.0);
  for (int s = 0; s < S_; ++s) travel(sphere_link_[s], &local_[3 * s], &sphere_travel_[static_cast<size_t>(s) * J_]);
  for (int l = 0; l < L_; ++l) travel(l, &bound_local_[3 * l], &bound_travel_[static_cast<size_t>(l) * J_]);
  for (int j = 0; j < J_; ++j) {
    const bool prismatic_joint = std::any_of(robot_.links.begin(), robot_.links.end(), [&](const auto& link) {
      return link.joint == j && link.type == kinematics::JointType::kPrismatic;
    });
    if (prismatic_joint && !(std::isfinite(robot_.joint_lower[j]) && std::isfinite(robot_.joint_upper[j]))) {
      throw Error(where + ": robot \"" + robot_.name + "\": prismatic joint " + robot_.JointName(j) +
                  " needs finite limits");
    }
  }

  if (J_ > 64) throw Error(where + ": robot \"" + robot_.name + "\": more than 64 planned joints");
  ancestors_.assign(static_cast<size_t>(L_), 0);
  joint_revolute_.assign(static_cast<size_t>(J_), 1);
  for (int l = 0; l < L_; ++l) {
    if (joint_[l] >= 0 && prismatic_[l]) joint_revolute_[static_cast<size_t>(joint_[l])] = 0;
  }
  for (int l = 0; l < L_; ++l) {
    for (int a = l; a >= 0; a = parent_[a]) {
      if (joint_[a] >= 0) ancestors_[static_cast<size_t>(l)] |= uint64_t{1} << joint_[a];
    }
  }
  joint_link_.assign(static_cast<size_t>(J_), -1);
  for (int l = 0; l < L_; ++l) {
    if (joint_[l] >= 0) joint_link_[static_cast<size_t>(joint_[l])] = l;
  }
  chain_.assign(static_cast<size_t>(L_), {});
  for (int l = 0; l < L_; ++l) {
    for (int a = l; a >= 0; a = parent_[a]) {
      const int j = joint_[a];
      if (j < 0) continue;
      const double reach = prismatic_[a] ? 1.0 : bound_travel_[static_cast<size_t>(l) * J_ + j] + std::max(bound_radius_[l], 0.0);
      chain_[static_cast<size_t>(l)].emplace_back(j, reach);
    }
  }
  // Self-collision: every pair of links with spheres, less the ignored ones.
  if (robot_.self_collision) {
    std::vector<std::vector<uint8_t>> ignored(static_cast<size_t>(L_), std::vector<uint8_t>(static_cast<size_t>(L_), 0));
    for (const auto& pair : robot_.self_collision_ignore) {
      const int a = robot_.FindLink(pair[0]), b = robot_.FindLink(pair[1]);
      ignored[a][b] = ignored[b][a] = 1;
    }
    for (int a = 0; a < L_; ++a) {
      for (int b = a + 1; b < L_; ++b) {
        if (bound_radius_[a] >= 0 && bound_radius_[b] >= 0 && !ignored[a][b]) self_pairs_.push_back({a, b});
      }
    }
  }
  floor_checked_.assign(static_cast<size_t>(L_), 1);
  for (const std::string& name : robot_.floor_exempt) floor_checked_[robot_.FindLink(name)] = 0;
  RotationOf(robot_.tcp_quat, tcp_.R);
  for (int i = 0; i < 3; ++i) tcp_.p[i] = robot_.tcp_pos[i];
}

void BodyModel::Tcp(const double* q, double* tcp) const {
  if (point_) {
    for (int i = 0; i < W_; ++i) tcp[i] = q[i];
    return;
  }
  std::vector<Frame> frames(static_cast<size_t>(L_));
  std::vector<double> centres(static_cast<size_t>(3 * S_));
  Place(q, frames.data(), centres.data());
  Apply(frames[static_cast<size_t>(robot_.tcp_link)], tcp_.p, tcp);
}

void BodyModel::Place(const double* q, Frame* frames, double* centres) const {
  if (point_) {
    for (int i = 0; i < W_; ++i) centres[i] = q[i];
    return;
  }
  PlaceFrames(q, frames);
  for (int s = 0; s < S_; ++s) Apply(frames[sphere_link_[s]], &local_[3 * s], centres + 3 * s);
}

void BodyModel::PlaceSpheres(const double* q, const Frame* frames, int c, double* centres) const {
  if (point_) {
    for (int i = 0; i < W_; ++i) centres[i] = q[i];
    return;
  }
  const int link = sphere_link_[first_in_cluster_[c]];
  for (int s = first_in_cluster_[c]; s < first_in_cluster_[c + 1]; ++s) {
    Apply(frames[link], &local_[3 * s], centres + 3 * s);
  }
}

void BodyModel::JointAxes(const Frame* frames, double* axes, double* points) const {
  for (int j = 0; j < J_; ++j) {
    const int l = point_ ? -1 : joint_link_[static_cast<size_t>(j)];
    if (l < 0) {
      for (int i = 0; i < 3; ++i) axes[3 * j + i] = points[3 * j + i] = 0.0;
      continue;
    }
    const Frame& f = frames[l];
    const auto& a = axis_[static_cast<size_t>(l)];
    for (int i = 0; i < 3; ++i) {
      axes[3 * j + i] = f.R[3 * i] * a[0] + f.R[3 * i + 1] * a[1] + f.R[3 * i + 2] * a[2];
      points[3 * j + i] = f.p[i];
    }
  }
}

double BodyModel::Travel(int l, uint64_t joints, const double* dq, const double* axes, const double* points,
                         const double* centre) const {
  return Travel(l, joints, dq, axes, points, centre, bound_radius_[static_cast<size_t>(l)]);
}

double BodyModel::Travel(int l, uint64_t joints, const double* dq, const double* axes, const double* points,
                         const double* centre, double sphere_radius) const {
  if (point_) {
    double total = 0.0;
    for (int j = 0; j < J_; ++j) total += dq[j];
    return total;
  }
  // The static bound (reach_j, for any point within the link's bounding sphere) holds for any part of the link.
  const double radius = std::max(sphere_radius, 0.0);
  double local = 0.0, deeper = 0.0, bound = 0.0;
  for (const auto& [j, reach] : chain_[static_cast<size_t>(l)]) {
    if (!(joints & (uint64_t{1} << j))) continue;
    bound += reach * dq[j];
    if (!joint_revolute_[static_cast<size_t>(j)]) {
      local += dq[j];
    } else {
      // The centre's distance from the axis now, plus the radius, plus what the joints below can add.
      const double* a = axes + 3 * j;
      const double r[3] = {centre[0] - points[3 * j], centre[1] - points[3 * j + 1], centre[2] - points[3 * j + 2]};
      const double c[3] = {r[1] * a[2] - r[2] * a[1], r[2] * a[0] - r[0] * a[2], r[0] * a[1] - r[1] * a[0]};
      local += dq[j] * (std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) + radius + deeper);
    }
    deeper += reach * dq[j];
  }
  return std::min(local, bound);
}

double BodyModel::StaticTravel(int l, uint64_t joints, const double* dq) const {
  if (point_) {
    double total = 0.0;
    for (int j = 0; j < J_; ++j) total += dq[j];
    return total;
  }
  double bound = 0.0;
  for (const auto& [j, reach] : chain_[static_cast<size_t>(l)]) {
    if (joints & (uint64_t{1} << j)) bound += reach * dq[j];
  }
  return bound;
}

void BodyModel::PlaceFrames(const double* q, Frame* frames) const {
  if (point_) return;
  for (int l = 0; l < L_; ++l) {
    const Frame& fixed = fixed_[static_cast<size_t>(l)];
    Frame local;
    const int j = joint_[l];
    if (j < 0) {
      local = fixed;
    } else if (prismatic_[l]) {
      local = fixed;
      const auto& a = axis_[static_cast<size_t>(l)];
      const double v = q[j];
      for (int i = 0; i < 3; ++i) local.p[i] += (fixed.R[3 * i] * a[0] + fixed.R[3 * i + 1] * a[1] + fixed.R[3 * i + 2] * a[2]) * v;
    } else {
      // Rodrigues: Rot(a, v) = I + sin v [a]x + (1 - cos v) [a]x^2.
      const auto& a = axis_[static_cast<size_t>(l)];
      const double s = std::sin(q[j]), c = 1.0 - std::cos(q[j]);
      const double K[9] = {0, -a[2], a[1], a[2], 0, -a[0], -a[1], a[0], 0};
      double M[9];
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) {
          const double k2 = K[3 * r] * K[k] + K[3 * r + 1] * K[3 + k] + K[3 * r + 2] * K[6 + k];
          M[3 * r + k] = (r == k ? 1.0 : 0.0) + s * K[3 * r + k] + c * k2;
        }
      }
      for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) {
          local.R[3 * r + k] = fixed.R[3 * r] * M[k] + fixed.R[3 * r + 1] * M[3 + k] + fixed.R[3 * r + 2] * M[6 + k];
        }
        local.p[r] = fixed.p[r];
      }
    }
    if (parent_[l] < 0) {
      frames[l] = local;
    } else {
      Compose(frames[parent_[l]], local, frames[l]);
    }
  }
}

void BodyModel::PlaceBounds(const double* q, const Frame* frames, double* bound_centres,
                            double* cluster_centres) const {
  if (point_) {
    for (int i = 0; i < W_; ++i) bound_centres[i] = cluster_centres[i] = q[i];
    return;
  }
  for (int l = 0; l < L_; ++l) Apply(frames[l], &bound_local_[3 * l], bound_centres + 3 * l);
  for (int l = 0; l < L_; ++l) {
    for (int c = first_cluster_[l]; c < first_cluster_[l + 1]; ++c) {
      Apply(frames[l], &cluster_local_[3 * c], cluster_centres + 3 * c);
    }
  }
}

}  // namespace flowplan::collision
