#include "kernels/arm_collision_kernel.h"

#include <ATen/Parallel.h>

#include <array>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "kernels/shape_distance_math.h"

namespace flowplan::kernels {
namespace {

constexpr int kW = 3;  // an arm's workspace

/// How far beyond a sphere's reach an obstacle's bounding ball must lie to be skipped, m: far more than the
/// rounding of a distance, so that no skipped pair is one the script would count.
constexpr double kSkipSlack = 1e-4;

/// One kind's obstacles: its distance, its rows, and each one's bounding ball (centre, radius).
template <class S>
struct Obstacles {
  S (*distance)(const S*, const S*, S*);
  const S* rows;
  int64_t columns;
  int64_t count;
  std::vector<S> bounds;  // (count, 4)
};

template <template <class, int> class Shape, class S>
Obstacles<S> Prepare(const std::string& kind, const torch::Tensor& rows) {
  using Kernel = Shape<S, kW>;
  if (rows.dim() != 2 || rows.size(1) != Kernel::kColumns) {
    throw std::runtime_error("arm_collision: " + kind + ": expected (K, " + std::to_string(Kernel::kColumns) +
                             ") rows" + (kind == "boxes" || kind == "cylinders" ? " (prepared_scene)" : "") +
                             ", got " + (rows.dim() == 2 ? "(" + std::to_string(rows.size(0)) + ", " +
                                                               std::to_string(rows.size(1)) + ")"
                                                         : std::to_string(rows.dim()) + " dimensions"));
  }
  Obstacles<S> obstacles{&Kernel::Distance, rows.data_ptr<S>(), Kernel::kColumns, rows.size(0), {}};
  obstacles.bounds.resize(static_cast<size_t>(4 * obstacles.count));
  for (int64_t k = 0; k < obstacles.count; ++k) {
    S* bound = obstacles.bounds.data() + 4 * k;
    bound[3] = Kernel::Bound(obstacles.rows + k * Kernel::kColumns, bound);
  }
  return obstacles;
}

template <class S>
Obstacles<S> PrepareKind(const std::string& kind, const torch::Tensor& rows) {
  if (kind == "spheres") return Prepare<shapes::Sphere, S>(kind, rows);
  if (kind == "boxes") return Prepare<shapes::Box, S>(kind, rows);
  if (kind == "cylinders") return Prepare<shapes::Cylinder, S>(kind, rows);
  if (kind == "capsules") return Prepare<shapes::Capsule, S>(kind, rows);
  throw std::runtime_error("arm_collision: unknown shape kind " + kind);
}

/// c = a b for rigid transforms as their top three rows (3 x 4, row-major; the bottom row 0 0 0 1).
template <class S>
void Multiply(const S* a, const S* b, S* c) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      S total = a[i * 4] * b[j] + a[i * 4 + 1] * b[4 + j] + a[i * 4 + 2] * b[8 + j];
      if (j == 3) total += a[i * 4 + 3];
      c[i * 4 + j] = total;
    }
  }
}

/// p = F x for a transform's top rows F (3 x 4) and a homogeneous x (4).
template <class S>
void Transform(const S* frame, const S* x, S* p) {
  for (int i = 0; i < kW; ++i) {
    p[i] = frame[i * 4] * x[0] + frame[i * 4 + 1] * x[1] + frame[i * 4 + 2] * x[2] + frame[i * 4 + 3] * x[3];
  }
}

template <class S>
S SquaredDistance(const S* a, const S* b) {
  const S dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

/// An obstacle of any kind: its distance, its prepared row, its bounding ball (centre (3), radius).
template <class S>
struct Obstacle {
  S (*distance)(const S*, const S*, S*);
  const S* row;
  const S* bound;
};

/// A scene's obstacles in the kinds' order, then the rows' (the scene's numbering), in dtype S.
template <class S>
struct SceneObstacles {
  std::vector<torch::Tensor> rows;  // kept alive: the obstacles point into them
  std::vector<Obstacles<S>> kinds;
  std::vector<Obstacle<S>> all;

  SceneObstacles(const std::vector<std::string>& kind_names, const std::vector<torch::Tensor>& rows_in,
                 const torch::TensorOptions& options) {
    for (size_t i = 0; i < kind_names.size(); ++i) {
      rows.push_back(rows_in[i].to(options).contiguous());
      kinds.push_back(PrepareKind<S>(kind_names[i], rows.back()));
    }
    for (const Obstacles<S>& kind : kinds) {
      for (int64_t k = 0; k < kind.count; ++k) {
        all.push_back({kind.distance, kind.rows + k * kind.columns, kind.bounds.data() + 4 * k});
      }
    }
  }
};

/// An arm's kinematics in dtype S, from its tables: the frames of its links and the points fixed in them
/// (Arm.link_frames and Arm.fixed_points). The tables are read as float64 (the Arm's buffers are; no copy
/// then) and each number rounded to S, as the script's .to(q.dtype) does.
template <class S>
class ArmKinematics {
 public:
  ArmKinematics(const ArmTables& arm, int64_t J, int64_t S_) : L(arm.fixed.size(0)), J(J), S_(S_), C(S_ + 2 * J) {
    const auto as_double = torch::TensorOptions().dtype(torch::kFloat64);
    const torch::Tensor fixed = arm.fixed.to(as_double).contiguous();
    const torch::Tensor fixed_cross = arm.fixed_cross.to(as_double).contiguous();
    const torch::Tensor fixed_cross_sq = arm.fixed_cross_sq.to(as_double).contiguous();
    const torch::Tensor link_turns = arm.link_turns.to(as_double).contiguous();
    const torch::Tensor link_joint = arm.link_joint.to(torch::kInt64).contiguous();
    const torch::Tensor frame_points = arm.frame_points.to(as_double).contiguous();
    const torch::Tensor ancestors = arm.ancestors.to(as_double).contiguous();
    // The links' three matrices, top rows side by side (L, 3, 12); a welded link (turns 0) is its fixed pose.
    link_tables.resize(static_cast<size_t>(36 * L));
    turns.resize(static_cast<size_t>(L));
    parents = arm.parents;
    turned_by.assign(link_joint.data_ptr<int64_t>(), link_joint.data_ptr<int64_t>() + L);
    for (int64_t l = 0; l < L; ++l) {
      const double* tables[3] = {fixed.data_ptr<double>() + 16 * l, fixed_cross.data_ptr<double>() + 16 * l,
                                 fixed_cross_sq.data_ptr<double>() + 16 * l};
      for (int t = 0; t < 3; ++t) {
        for (int e = 0; e < 16; ++e) {
          const double expected = e < 12 ? tables[t][e] : (t == 0 && e == 15 ? 1.0 : 0.0);
          if (tables[t][e] != expected) {
            throw std::runtime_error("arm_collision: link " + std::to_string(l) +
                                     ": expected rigid transforms (bottom rows 0 0 0 1, and 0 0 0 0 in "
                                     "fixed_cross and fixed_cross_sq)");
          }
          if (e < 12) link_tables[36 * l + 12 * t + e] = static_cast<S>(tables[t][e]);
        }
      }
      turns[l] = static_cast<S>(link_turns.data_ptr<double>()[l]);
    }
    // Each frame point lies in one link's block of frame_points (the rows of every other link are zero): its
    // link and its four homogeneous coordinates.
    column_link.assign(static_cast<size_t>(C), -1);
    column_point.assign(static_cast<size_t>(4 * C), S(0));
    const double* fp = frame_points.data_ptr<double>();
    for (int64_t c = 0; c < C; ++c) {
      for (int64_t l = 0; l < L && column_link[c] < 0; ++l) {
        for (int r = 0; r < 4; ++r) {
          if (fp[(4 * l + r) * C + c] != 0.0) column_link[c] = l;
        }
      }
      if (column_link[c] < 0) continue;  // the zero vector
      for (int r = 0; r < 4; ++r) column_point[4 * c + r] = static_cast<S>(fp[(4 * column_link[c] + r) * C + c]);
    }
    moves.resize(static_cast<size_t>(J * S_));
    for (int64_t i = 0; i < J * S_; ++i) moves[i] = static_cast<S>(ancestors.data_ptr<double>()[i]);
  }

  /// The link frames (L, 3, 4) and the frame points in the world (C, 3) of joint angles `angles` (J).
  void Place(const S* angles, S* frames, S* points) const {
    std::array<S, 12> local{};
    for (int64_t l = 0; l < L; ++l) {
      // F + sin F[a]x + (1 - cos) F[a]x^2.
      const S* table = link_tables.data() + 36 * l;
      if (turns[l] == S(0)) {
        std::copy(table, table + 12, local.begin());
      } else {
        const S angle = angles[turned_by[l]] * turns[l];
        const S sine = std::sin(angle), versine = S(1) - std::cos(angle);
        for (int e = 0; e < 12; ++e) local[e] = table[e] + sine * table[12 + e] + versine * table[24 + e];
      }
      const int64_t parent = parents[static_cast<size_t>(l)];
      if (parent < 0) {
        std::copy(local.begin(), local.end(), frames + 12 * l);
      } else {
        Multiply(frames + 12 * parent, local.data(), frames + 12 * l);
      }
    }
    for (int64_t c = 0; c < C; ++c) {
      const int64_t l = column_link[c];
      S* p = points + kW * c;
      if (l < 0) {
        p[0] = p[1] = p[2] = 0;
      } else {
        Transform(frames + 12 * l, column_point.data() + 4 * c, p);
      }
    }
  }

  const int64_t L, J, S_, C;
  std::vector<S> link_tables, turns, column_point, moves;  // moves: the ancestors (J, S)
  std::vector<int64_t> turned_by, parents, column_link;
};

template <class S>
void RunHinge(const torch::Tensor& q, const ArmTables& arm, const torch::Tensor& reach_in,
              const std::vector<std::string>& kinds, const std::vector<torch::Tensor>& rows_in, torch::Tensor& value,
              torch::Tensor* gradient) {
  const torch::Tensor reach = reach_in.to(q.options()).contiguous();
  const ArmKinematics<S> kinematics(arm, q.size(1), reach.size(0));
  const int64_t M = q.size(0), J = kinematics.J, L = kinematics.L, S_ = kinematics.S_, C = kinematics.C;
  const S* reaches = reach.data_ptr<S>();

  // The spheres link by link, each link's in a ball (in its frame: centre, and radius with the spheres' reach)
  // that an obstacle's bounding ball must meet for any of them to touch it. Spheres on no link (a zero column)
  // sit at the origin, checked on their own.
  std::vector<std::vector<int64_t>> link_spheres(static_cast<size_t>(L));
  std::vector<int64_t> loose;
  for (int64_t s = 0; s < S_; ++s) {
    if (kinematics.column_link[s] >= 0) {
      link_spheres[kinematics.column_link[s]].push_back(s);
    } else {
      loose.push_back(s);
    }
  }
  std::vector<S> link_balls(static_cast<size_t>(5 * L), S(0));  // homogeneous centre (4), radius
  for (int64_t l = 0; l < L; ++l) {
    const auto& members = link_spheres[l];
    if (members.empty()) continue;
    const S* local = kinematics.column_point.data();
    double centre[3] = {0, 0, 0};
    for (int64_t s : members) {
      for (int i = 0; i < kW; ++i) centre[i] += local[4 * s + i] / static_cast<double>(members.size());
    }
    double radius = 0;
    for (int64_t s : members) {
      double squares = 0;
      for (int i = 0; i < kW; ++i) squares += (local[4 * s + i] - centre[i]) * (local[4 * s + i] - centre[i]);
      radius = std::max(radius, std::sqrt(squares) + static_cast<double>(reaches[s]));
    }
    for (int i = 0; i < kW; ++i) link_balls[5 * l + i] = static_cast<S>(centre[i]);
    link_balls[5 * l + 3] = S(1);
    link_balls[5 * l + 4] = static_cast<S>(radius + 1e-6 * (1.0 + radius));  // its own rounding covered
  }
  const SceneObstacles<S> scene(kinds, rows_in, q.options());

  const S* qs = q.data_ptr<S>();
  S* out_value = value.data_ptr<S>();
  S* out_gradient = gradient == nullptr ? nullptr : gradient->data_ptr<S>();
  const S slack = static_cast<S>(kSkipSlack);

  at::parallel_for(0, M, 4, [&](int64_t begin, int64_t end) {
    std::vector<S> frames(static_cast<size_t>(12 * L)), points(static_cast<size_t>(kW * C)),
        pushes(static_cast<size_t>(kW * S_));
    std::vector<char> pushed(static_cast<size_t>(S_));
    std::vector<const Obstacle<S>*> near;
    near.reserve(scene.all.size());
    for (int64_t m = begin; m < end; ++m) {
      kinematics.Place(qs + m * J, frames.data(), points.data());
      // The hinge of every sphere against every obstacle, and the sum of the active distances' gradients.
      S total = 0;
      auto hinge = [&](int64_t s, const std::vector<const Obstacle<S>*>& candidates) {
        const S* centre = points.data() + kW * s;
        S* push = pushes.data() + kW * s;
        S penetration = 0;
        for (const Obstacle<S>* obstacle : candidates) {
          const S beyond = reaches[s] + slack + obstacle->bound[3];
          if (SquaredDistance(centre, obstacle->bound) >= beyond * beyond) continue;
          const S depth = reaches[s] - obstacle->distance(centre, obstacle->row, nullptr);
          if (!(depth > S(0))) continue;
          penetration += depth;
          if (out_gradient != nullptr) {
            S normal[kW];
            obstacle->distance(centre, obstacle->row, normal);
            for (int i = 0; i < kW; ++i) push[i] -= normal[i];
            pushed[s] = 1;
          }
        }
        total += penetration;
      };
      std::fill(pushes.begin(), pushes.end(), S(0));
      std::fill(pushed.begin(), pushed.end(), 0);
      for (int64_t l = 0; l < L; ++l) {
        if (link_spheres[l].empty()) continue;
        S ball[kW];
        Transform(frames.data() + 12 * l, link_balls.data() + 5 * l, ball);
        near.clear();
        for (const Obstacle<S>& obstacle : scene.all) {
          const S beyond = link_balls[5 * l + 4] + slack + obstacle.bound[3];
          if (SquaredDistance(ball, obstacle.bound) < beyond * beyond) near.push_back(&obstacle);
        }
        if (near.empty()) continue;
        for (int64_t s : link_spheres[l]) hinge(s, near);
      }
      if (!loose.empty()) {
        near.clear();
        for (const Obstacle<S>& obstacle : scene.all) near.push_back(&obstacle);
        for (int64_t s : loose) hinge(s, near);
      }
      out_value[m] = total;
      if (out_gradient == nullptr) continue;
      // dC/dq_j = a_j . (sum_s A[j, s] c_s x g_s - p_j x sum_s A[j, s] g_s) (Arm.spheres_vjp).
      const S* axes = points.data() + kW * S_;
      const S* origins = points.data() + kW * (S_ + J);
      for (int64_t j = 0; j < J; ++j) {
        S moment[kW] = {0, 0, 0}, force[kW] = {0, 0, 0};
        for (int64_t s = 0; s < S_; ++s) {
          const S weight = kinematics.moves[j * S_ + s];
          if (!pushed[s] || weight == S(0)) continue;
          const S* c = points.data() + kW * s;
          const S* g = pushes.data() + kW * s;
          moment[0] += weight * (c[1] * g[2] - c[2] * g[1]);
          moment[1] += weight * (c[2] * g[0] - c[0] * g[2]);
          moment[2] += weight * (c[0] * g[1] - c[1] * g[0]);
          for (int i = 0; i < kW; ++i) force[i] += weight * g[i];
        }
        const S* a = axes + kW * j;
        const S* p = origins + kW * j;
        const S lever[kW] = {moment[0] - (p[1] * force[2] - p[2] * force[1]),
                             moment[1] - (p[2] * force[0] - p[0] * force[2]),
                             moment[2] - (p[0] * force[1] - p[1] * force[0])};
        out_gradient[m * J + j] = a[0] * lever[0] + a[1] * lever[1] + a[2] * lever[2];
      }
    }
  });
}

template <class S>
void RunNearest(const torch::Tensor& q, const ArmTables& arm, const torch::Tensor& radii_in,
                const std::vector<std::string>& kinds, const std::vector<torch::Tensor>& rows_in,
                torch::Tensor& clearance, torch::Tensor& index) {
  const torch::Tensor radii = radii_in.to(q.options()).contiguous();
  const ArmKinematics<S> kinematics(arm, q.size(1), radii.size(0));
  const int64_t M = q.size(0), J = kinematics.J, L = kinematics.L, S_ = kinematics.S_, C = kinematics.C;
  const SceneObstacles<S> scene(kinds, rows_in, q.options());
  const S* qs = q.data_ptr<S>();
  const S* radius = radii.data_ptr<S>();
  S* out_clearance = clearance.data_ptr<S>();
  int64_t* out_index = index.data_ptr<int64_t>();
  const int64_t K = static_cast<int64_t>(scene.all.size());
  // An obstacle whose bounding ball is farther than the nearest distance so far by more than this cannot be
  // nearer, nor tie with it (a distance rounds by far less).
  const S slack = std::is_same<S, float>::value ? S(1e-4) : S(1e-9);

  at::parallel_for(0, M, 4, [&](int64_t begin, int64_t end) {
    std::vector<S> frames(static_cast<size_t>(12 * L)), points(static_cast<size_t>(kW * C));
    for (int64_t m = begin; m < end; ++m) {
      kinematics.Place(qs + m * J, frames.data(), points.data());
      for (int64_t s = 0; s < S_; ++s) {
        const S* centre = points.data() + kW * s;
        S nearest = std::numeric_limits<S>::infinity();
        int64_t which = -1;
        for (int64_t k = 0; k < K; ++k) {
          const Obstacle<S>& obstacle = scene.all[k];
          if (which >= 0) {
            // Skip when |c - o| - R > nearest + slack; both sides compared squared when the left is positive.
            const S beyond = nearest + slack + obstacle.bound[3];
            if (beyond > S(0) && SquaredDistance(centre, obstacle.bound) > beyond * beyond) continue;
          }
          const S distance = obstacle.distance(centre, obstacle.row, nullptr);
          if (std::isnan(distance)) {  // torch.min's: a NaN is the minimum
            nearest = distance;
            which = k;
            break;
          }
          if (which < 0 || distance < nearest) {  // ties: the first, as torch.min
            nearest = distance;
            which = k;
          }
        }
        out_clearance[m * S_ + s] = K == 0 ? nearest : nearest - radius[s];
        out_index[m * S_ + s] = which;
      }
    }
  });
}

void Check(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("arm_collision: " + what);
}

/// The checks both entry points make of q (M, J), the tables and S spheres (`per_sphere`: reach or radii).
void CheckArm(const torch::Tensor& q, const ArmTables& arm, const torch::Tensor& per_sphere, const char* name,
              const std::vector<std::string>& kinds, const std::vector<torch::Tensor>& rows) {
  Check(q.dim() == 2, "expected q (M, J)");
  const auto dtype = q.scalar_type();
  Check(dtype == torch::kFloat32 || dtype == torch::kFloat64, "expected float32 or float64 q");
  Check(q.device().is_cpu(), "expected q on the CPU");
  Check(!q.requires_grad() && !per_sphere.requires_grad(), "no autograd (the scripts have it)");
  const int64_t J = q.size(1);
  Check(arm.fixed.dim() == 3 && arm.fixed.size(1) == 4 && arm.fixed.size(2) == 4, "expected fixed (L, 4, 4)");
  const int64_t L = arm.fixed.size(0);
  Check(arm.fixed_cross.sizes() == arm.fixed.sizes() && arm.fixed_cross_sq.sizes() == arm.fixed.sizes(),
        "expected fixed_cross and fixed_cross_sq (L, 4, 4) as fixed");
  Check(arm.link_joint.numel() == L && arm.link_turns.numel() == L && static_cast<int64_t>(arm.parents.size()) == L,
        "expected link_joint, link_turns and parents of one entry per link (" + std::to_string(L) + ")");
  Check(per_sphere.dim() == 1, std::string("expected ") + name + " (S,)");
  const int64_t S = per_sphere.size(0);
  Check(arm.ancestors.dim() == 2 && arm.ancestors.size(0) == J && arm.ancestors.size(1) == S,
        "expected ancestors (J, S) = (" + std::to_string(J) + ", " + std::to_string(S) + ")");
  Check(arm.frame_points.dim() == 2 && arm.frame_points.size(0) == 4 * L && arm.frame_points.size(1) == S + 2 * J,
        "expected frame_points (4 L, S + 2 J) = (" + std::to_string(4 * L) + ", " + std::to_string(S + 2 * J) + ")");
  const torch::Tensor link_joint = arm.link_joint.to(torch::kInt64).contiguous();
  for (int64_t l = 0; l < L; ++l) {
    const int64_t joint = link_joint.data_ptr<int64_t>()[l];
    Check(joint >= 0 && joint < J, "link_joint: expected joints in [0, " + std::to_string(J) + "), link " +
                                       std::to_string(l) + " has " + std::to_string(joint));
    const int64_t parent = arm.parents[static_cast<size_t>(l)];
    Check(parent < l, "parents: expected every link after its parent, link " + std::to_string(l));
  }
  Check(kinds.size() == rows.size(), "expected one rows tensor per kind");
  for (const torch::Tensor& r : rows) Check(!r.requires_grad(), "no autograd (the scripts have it)");
}

}  // namespace

std::tuple<torch::Tensor, torch::Tensor> ArmCollision(const torch::Tensor& q_in, const ArmTables& arm,
                                                      const torch::Tensor& reach,
                                                      const std::vector<std::string>& kinds,
                                                      const std::vector<torch::Tensor>& rows, bool with_gradient) {
  CheckArm(q_in, arm, reach, "reach", kinds, rows);
  const torch::Tensor q = q_in.contiguous();
  torch::Tensor value = torch::empty({q.size(0)}, q.options());
  torch::Tensor gradient = with_gradient ? torch::empty({q.size(0), q.size(1)}, q.options()) : torch::empty({0}, q.options());
  if (q.scalar_type() == torch::kFloat32) {
    RunHinge<float>(q, arm, reach, kinds, rows, value, with_gradient ? &gradient : nullptr);
  } else {
    RunHinge<double>(q, arm, reach, kinds, rows, value, with_gradient ? &gradient : nullptr);
  }
  return {value, gradient};
}

std::tuple<torch::Tensor, torch::Tensor> ArmNearestObstacles(const torch::Tensor& q_in, const ArmTables& arm,
                                                             const torch::Tensor& radii,
                                                             const std::vector<std::string>& kinds,
                                                             const std::vector<torch::Tensor>& rows) {
  CheckArm(q_in, arm, radii, "radii", kinds, rows);
  const torch::Tensor q = q_in.contiguous();
  const int64_t M = q.size(0), S = radii.size(0);
  torch::Tensor clearance = torch::empty({M, S}, q.options());
  torch::Tensor index = torch::empty({M, S}, q.options().dtype(torch::kInt64));
  if (q.scalar_type() == torch::kFloat32) {
    RunNearest<float>(q, arm, radii, kinds, rows, clearance, index);
  } else {
    RunNearest<double>(q, arm, radii, kinds, rows, clearance, index);
  }
  return {clearance, index};
}

}  // namespace flowplan::kernels
