#include "collision/world.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "kernels/shape_distance_math.h"

namespace flowplan::collision {
namespace {

namespace shapes = kernels::shapes;

/// The rotation, local to world, row-major, of a quaternion (w, x, y, z) of any non-zero norm (W = 3) or an
/// angle (W = 2): geometry/frames.py's rotation_matrices.
std::vector<double> Rotation(const double* turn, int W) {
  if (W == 2) {
    const double c = std::cos(turn[0]), s = std::sin(turn[0]);
    return {c, -s, s, c};
  }
  const double w = turn[0], x = turn[1], y = turn[2], z = turn[3];
  const double n = w * w + x * x + y * y + z * z;
  return {(w * w + x * x - y * y - z * z) / n, 2 * (x * y - w * z) / n,         2 * (x * z + w * y) / n,
          2 * (x * y + w * z) / n,         (w * w - x * x + y * y - z * z) / n, 2 * (y * z - w * x) / n,
          2 * (x * z - w * y) / n,         2 * (y * z + w * x) / n,         (w * w - x * x - y * y + z * z) / n};
}

int GivenColumns(ShapeKind kind, int W) {
  const int turn = W == 3 ? 4 : 1;
  switch (kind) {
    case ShapeKind::kSphere: return W + 1;
    case ShapeKind::kBox: return 2 * W + turn;
    case ShapeKind::kCylinder: return W + 2 + turn;
    case ShapeKind::kCapsule: return 2 * W + 1;
  }
  return 0;
}

/// The box around an obstacle: its extent along each world axis.
void Bounds(Obstacle& o, int W) {
  const std::vector<double>& r = o.row;
  double centre[3] = {0, 0, 0}, half[3] = {0, 0, 0};
  switch (o.kind) {
    case ShapeKind::kSphere:
      for (int i = 0; i < W; ++i) centre[i] = r[i], half[i] = r[W];
      break;
    case ShapeKind::kBox: {
      const double* R = &r[2 * W + (W == 3 ? 4 : 1)];
      for (int i = 0; i < W; ++i) {
        centre[i] = r[i];
        for (int j = 0; j < W; ++j) half[i] += std::abs(R[i * W + j]) * 0.5 * r[W + j];
      }
      break;
    }
    case ShapeKind::kCylinder: {
      const double* R = &r[W + 2 + (W == 3 ? 4 : 1)];
      const double radius = r[W], half_height = 0.5 * r[W + 1];
      for (int i = 0; i < W; ++i) {
        centre[i] = r[i];
        // The axis is local coordinate W - 1 (column W - 1 of R); across it the disc's extent.
        const double a = R[i * W + (W - 1)];
        half[i] = std::abs(a) * half_height + radius * std::sqrt(std::max(0.0, 1.0 - a * a));
      }
      break;
    }
    case ShapeKind::kCapsule:
      for (int i = 0; i < W; ++i) {
        centre[i] = 0.5 * (r[i] + r[W + i]);
        half[i] = 0.5 * std::abs(r[i] - r[W + i]) + r[2 * W];
      }
      break;
  }
  for (int i = 0; i < W; ++i) {
    o.lo[i] = centre[i] - half[i];
    o.hi[i] = centre[i] + half[i];
  }
}

void Prepare(Obstacle& o, int W) {
  const int turn = W == 3 ? 4 : 1;
  if (o.kind == ShapeKind::kBox || o.kind == ShapeKind::kCylinder) {
    const int at = o.kind == ShapeKind::kBox ? 2 * W : W + 2;
    const std::vector<double> R = Rotation(&o.row[at], W);
    o.row.resize(static_cast<size_t>(at + turn));
    o.row.insert(o.row.end(), R.begin(), R.end());
  }
  Bounds(o, W);
}

}  // namespace

World::World(const geometry::SceneRows& rows, int workspace_dim, Floor floor, std::vector<std::string> names,
             const std::string& where)
    : W_(workspace_dim), floor_(floor) {
  if (W_ != 2 && W_ != 3) throw Error(where + ": expected a 2-D or 3-D workspace, got " + std::to_string(W_));
  const std::pair<const char*, ShapeKind> kinds[] = {{"spheres", ShapeKind::kSphere},
                                                     {"boxes", ShapeKind::kBox},
                                                     {"cylinders", ShapeKind::kCylinder},
                                                     {"capsules", ShapeKind::kCapsule}};
  for (const auto& entry : rows) {
    bool known = false;
    for (const auto& [name, kind] : kinds) known = known || entry.key() == name;
    if (!known) throw Error(where + ": unknown obstacle kind \"" + entry.key() + "\"");
  }
  for (const auto& [name, kind] : kinds) {
    if (!rows.contains(name)) continue;
    const torch::Tensor t = rows.at(name).to(torch::kCPU, torch::kFloat64).contiguous();
    const int given = GivenColumns(kind, W_);
    if (t.dim() != 2 || t.size(1) < given) {
      throw Error(where + ": " + name + ": expected (K, " + std::to_string(given) + ") rows");
    }
    const double* data = t.data_ptr<double>();
    for (int64_t k = 0; k < t.size(0); ++k) {
      Obstacle o;
      o.kind = kind;
      o.row.assign(data + k * t.size(1), data + k * t.size(1) + given);
      for (double v : o.row) {
        if (!std::isfinite(v)) throw Error(where + ": " + name + ": row " + std::to_string(k) + ": not finite");
      }
      o.name = std::string(name) + "[" + std::to_string(k) + "]";
      Prepare(o, W_);
      obstacles_.push_back(std::move(o));
    }
  }
  if (!names.empty()) {
    if (names.size() != obstacles_.size()) {
      throw InternalError(where + ": " + std::to_string(names.size()) + " names for " +
                          std::to_string(obstacles_.size()) + " obstacles");
    }
    for (size_t k = 0; k < names.size(); ++k) obstacles_[k].name = names[k];
  }
  for (int i = 0; i < 3; ++i) {
    for (const Obstacle& o : obstacles_) {
      lo_[i].push_back(i < W_ ? o.lo[i] : 0.0);
      hi_[i].push_back(i < W_ ? o.hi[i] : 0.0);
    }
  }
}

World::World(const geometry::Scene& scene, int workspace_dim, Floor floor, std::vector<std::string> names,
             const std::string& where)
    : World(geometry::Rows(scene, workspace_dim, where), workspace_dim, floor, std::move(names), where) {}

double World::Distance(int k, const double* p) const {
  const Obstacle& o = obstacles_[static_cast<size_t>(k)];
  const double* row = o.row.data();
  if (W_ == 3) {
    switch (o.kind) {
      case ShapeKind::kSphere: return shapes::Sphere<double, 3>::Distance(p, row, nullptr);
      case ShapeKind::kBox: return shapes::Box<double, 3>::Distance(p, row, nullptr);
      case ShapeKind::kCylinder: return shapes::Cylinder<double, 3>::Distance(p, row, nullptr);
      case ShapeKind::kCapsule: return shapes::Capsule<double, 3>::Distance(p, row, nullptr);
    }
  }
  switch (o.kind) {
    case ShapeKind::kSphere: return shapes::Sphere<double, 2>::Distance(p, row, nullptr);
    case ShapeKind::kBox: return shapes::Box<double, 2>::Distance(p, row, nullptr);
    case ShapeKind::kCylinder: return shapes::Cylinder<double, 2>::Distance(p, row, nullptr);
    case ShapeKind::kCapsule: return shapes::Capsule<double, 2>::Distance(p, row, nullptr);
  }
  return NAN;
}

void World::LowerBounds(const double* p, double radius, double* out) const {
  const int K = size();
  const double x = p[0], y = p[1], z = W_ == 3 ? p[2] : 0.0;
  const double *lx = lo_[0].data(), *ly = lo_[1].data(), *lz = lo_[2].data();
  const double *hx = hi_[0].data(), *hy = hi_[1].data(), *hz = hi_[2].data();
  for (int k = 0; k < K; ++k) {
    const double dx = std::max(std::max(lx[k] - x, x - hx[k]), 0.0);
    const double dy = std::max(std::max(ly[k] - y, y - hy[k]), 0.0);
    const double dz = std::max(std::max(lz[k] - z, z - hz[k]), 0.0);
    const double squares = dx * dx + dy * dy + dz * dz;
    // Inside the box the obstacle may hold the point: no bound.
    out[k] = (squares > 0.0 ? std::sqrt(squares) : -INFINITY) - radius;
  }
}

double World::LowerBound(int k, const double* p) const {
  const Obstacle& o = obstacles_[static_cast<size_t>(k)];
  double squares = 0.0;
  bool inside = true;
  for (int i = 0; i < W_; ++i) {
    const double below = o.lo[i] - p[i], above = p[i] - o.hi[i];
    const double out = std::max(std::max(below, above), 0.0);
    inside = inside && out == 0.0;
    squares += out * out;
  }
  return inside ? -INFINITY : std::sqrt(squares);
}

}  // namespace flowplan::collision
