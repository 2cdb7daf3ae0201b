#include "kernels/arm_collision_kernel.h"

#include <ATen/Parallel.h>

#include <limits>
#include <stdexcept>
#include <type_traits>

#include "kernels/mish_math.h"  // FLOWPLAN_VECTOR_CLONES
#include "kernels/shape_distance_math.h"

namespace flowplan::kernels {
namespace {

constexpr int kW = 3;  // an arm's workspace

/// The hinge pass of n points, given as coordinates x, y, z, against one shape's prepared row: each point's
/// depth e_i = reach_i - d(p_i) written to `depth` and relu(e_i) added to `penetration` (NaN stays NaN);
/// returns how many are positive. One loop, no branches, that the compiler vectorises (built for AVX-512, AVX2 and plain
/// x86-64: FLOWPLAN_VECTOR_CLONES); a point's numbers do not depend on its neighbours.
template <class S>
using HingePass = int64_t (*)(const S* x, const S* y, const S* z, const S* reach, const S* row, S* depth,
                              S* penetration, int64_t n);

template <template <class, int> class Shape, class S>
inline __attribute__((always_inline)) int64_t HingeLoop(const S* __restrict x, const S* __restrict y,
                                                        const S* __restrict z, const S* __restrict reach,
                                                        const S* __restrict row, S* __restrict depth,
                                                        S* __restrict penetration, int64_t n) {
  int64_t active = 0;
  for (int64_t i = 0; i < n; ++i) {
    const S p[kW] = {x[i], y[i], z[i]};
    const S e = reach[i] - Shape<S, kW>::Distance(p, row, nullptr);
    depth[i] = e;
    penetration[i] += e > S(0) || e != e ? e : S(0);  // relu, and a NaN stays NaN as in the script
    active += e > S(0) ? 1 : 0;
  }
  return active;
}

/// Each shape's passes, per dtype: Passes<Shape, S>::Hinge().
template <template <class, int> class Shape, class S>
struct Passes;

// One clone set per shape and dtype (target_clones takes no templates), and its entry in Passes.
#define FLOWPLAN_ARM_PASSES(Shape, T)                                                                          \
  FLOWPLAN_VECTOR_CLONES int64_t Shape##Hinge_##T(const T* __restrict x, const T* __restrict y,                 \
                                                  const T* __restrict z, const T* __restrict reach,             \
                                                  const T* __restrict row, T* __restrict depth,                 \
                                                  T* __restrict penetration, int64_t n) {                       \
    return HingeLoop<shapes::Shape, T>(x, y, z, reach, row, depth, penetration, n);                             \
  }                                                                                                             \
  template <>                                                                                                   \
  struct Passes<shapes::Shape, T> {                                                                             \
    static HingePass<T> Hinge() { return &Shape##Hinge_##T; }                                                   \
  };
FLOWPLAN_ARM_PASSES(Sphere, float)
FLOWPLAN_ARM_PASSES(Box, float)
FLOWPLAN_ARM_PASSES(Cylinder, float)
FLOWPLAN_ARM_PASSES(Capsule, float)
FLOWPLAN_ARM_PASSES(Sphere, double)
FLOWPLAN_ARM_PASSES(Box, double)
FLOWPLAN_ARM_PASSES(Cylinder, double)
FLOWPLAN_ARM_PASSES(Capsule, double)
#undef FLOWPLAN_ARM_PASSES

/// One kind's obstacles: its distance (for a gradient), its vectorised pass, its rows.
template <class S>
struct Obstacles {
  S (*distance)(const S*, const S*, S*);
  HingePass<S> hinge;
  const S* rows;
  int64_t columns;
  int64_t count;
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
  return {&Kernel::Distance, Passes<Shape, S>::Hinge(), rows.data_ptr<S>(), Kernel::kColumns,
          rows.size(0)};
}

template <class S>
Obstacles<S> PrepareKind(const std::string& kind, const torch::Tensor& rows) {
  if (kind == "spheres") return Prepare<shapes::Sphere, S>(kind, rows);
  if (kind == "boxes") return Prepare<shapes::Box, S>(kind, rows);
  if (kind == "cylinders") return Prepare<shapes::Cylinder, S>(kind, rows);
  if (kind == "capsules") return Prepare<shapes::Capsule, S>(kind, rows);
  throw std::runtime_error("arm_collision: unknown shape kind " + kind);
}

/// An obstacle of any kind: its distance, its pass, its prepared row.
template <class S>
struct Obstacle {
  S (*distance)(const S*, const S*, S*);
  HingePass<S> hinge;
  const S* row;
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
        all.push_back({kind.distance, kind.hinge, kind.rows + k * kind.columns});
      }
    }
  }
};

/// An arm's kinematic tables in dtype S, as the placement of a chunk of configurations (PlaceChunkLoop)
/// reads them (Arm.link_frames and Arm.fixed_points). The tables are read as float64 (the Arm's buffers are;
/// no copy then) and each number rounded to S, as the script's .to(q.dtype) does.
template <class S>
class ArmKinematics {
 public:
  ArmKinematics(const ArmTables& arm, int64_t J, int64_t S_) : L(arm.fixed.size(0)), J(J), S_(S_), C(S_ + 2 * J) {
    const auto as_double = torch::TensorOptions().dtype(torch::kFloat64).device(torch::kCPU);
    const torch::Tensor fixed = arm.fixed.to(as_double).contiguous();
    const torch::Tensor fixed_cross = arm.fixed_cross.to(as_double).contiguous();
    const torch::Tensor fixed_cross_sq = arm.fixed_cross_sq.to(as_double).contiguous();
    const torch::Tensor link_turns = arm.link_turns.to(as_double).contiguous();
    const torch::Tensor link_joint = arm.link_joint.to(torch::kCPU, torch::kInt64).contiguous();
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

  const int64_t L, J, S_, C;
  std::vector<S> link_tables, turns, column_point, moves;  // moves: the ancestors (J, S)
  std::vector<int64_t> turned_by, parents, column_link;
};

/// The link frames (L, 12, count) and the frame points in the world (C, 3, count) of `count` configurations
/// q (count, J), configurations side by side (the last index) so that every step is a loop over them that the
/// compiler vectorises: F + sin F[a]x + (1 - cos) F[a]x^2 for each link, its parent's frame times that, and
/// the points as the frames times their homogeneous coordinates. `sines` (2 count) is scratch. Each configuration's numbers come from its own angles alone.
template <class S>
inline __attribute__((always_inline)) void PlaceChunkLoop(const ArmKinematics<S>& arm, const S* __restrict q,
                                                          int64_t count, S* __restrict frames,
                                                          S* __restrict points, S* __restrict sines) {
  const int64_t J = arm.J;
  S* __restrict versines = sines + count;
  for (int64_t l = 0; l < arm.L; ++l) {
    const S* table = arm.link_tables.data() + 36 * l;
    S* __restrict F = frames + 12 * count * l;
    const int64_t parent = arm.parents[static_cast<size_t>(l)];
    const bool turned = arm.turns[l] != S(0);
    if (turned) {
      const S turn = arm.turns[l];
      const int64_t joint = arm.turned_by[l];
      for (int64_t m = 0; m < count; ++m) {  // not vectorised (the library's sin and cos)
        const S angle = q[m * J + joint] * turn;
        sines[m] = std::sin(angle);
        versines[m] = S(1) - std::cos(angle);
      }
    }
    // The link's pose in its parent, into F, then (with a parent) the product with the parent's, in place
    // column by column of the result: column j of P L needs column j of L alone.
    for (int e = 0; e < 12; ++e) {
      for (int64_t m = 0; m < count; ++m) {
        F[e * count + m] = turned ? table[e] + sines[m] * table[12 + e] + versines[m] * table[24 + e] : table[e];
      }
    }
    if (parent < 0) continue;
    const S* __restrict P = frames + 12 * count * parent;
    for (int j = 0; j < 4; ++j) {
      for (int64_t m = 0; m < count; ++m) {
        const S l0 = F[j * count + m], l1 = F[(4 + j) * count + m], l2 = F[(8 + j) * count + m];
        for (int i = 0; i < 3; ++i) {
          S total = P[(i * 4) * count + m] * l0 + P[(i * 4 + 1) * count + m] * l1 + P[(i * 4 + 2) * count + m] * l2;
          if (j == 3) total += P[(i * 4 + 3) * count + m];
          F[(i * 4 + j) * count + m] = total;
        }
      }
    }
  }
  for (int64_t c = 0; c < arm.C; ++c) {
    const int64_t l = arm.column_link[c];
    const S* x = arm.column_point.data() + 4 * c;
    for (int i = 0; i < kW; ++i) {
      S* __restrict out = points + (kW * c + i) * count;
      if (l < 0) {
        for (int64_t m = 0; m < count; ++m) out[m] = S(0);
        continue;
      }
      const S* __restrict F = frames + 12 * count * l;
      for (int64_t m = 0; m < count; ++m) {
        out[m] = F[(i * 4) * count + m] * x[0] + F[(i * 4 + 1) * count + m] * x[1] + F[(i * 4 + 2) * count + m] * x[2] +
                 F[(i * 4 + 3) * count + m] * x[3];
      }
    }
  }
}

FLOWPLAN_VECTOR_CLONES void PlaceChunkFloat(const ArmKinematics<float>& arm, const float* q, int64_t count,
                                            float* frames, float* points, float* sines) {
  PlaceChunkLoop<float>(arm, q, count, frames, points, sines);
}
FLOWPLAN_VECTOR_CLONES void PlaceChunkDouble(const ArmKinematics<double>& arm, const double* q, int64_t count,
                                             double* frames, double* points, double* sines) {
  PlaceChunkLoop<double>(arm, q, count, frames, points, sines);
}
inline void PlaceChunk(const ArmKinematics<float>& arm, const float* q, int64_t count, float* frames, float* points,
                       float* sines) {
  PlaceChunkFloat(arm, q, count, frames, points, sines);
}
inline void PlaceChunk(const ArmKinematics<double>& arm, const double* q, int64_t count, double* frames,
                       double* points, double* sines) {
  PlaceChunkDouble(arm, q, count, frames, points, sines);
}

/// A chunk of `count` configurations placed (PlaceChunk): the frame points (C, 3, count), and the sphere
/// centres' coordinates as three arrays of n = S count (index s count + m), what the passes take.
template <class S>
struct PlacedChunk {
  std::vector<S> points, x, y, z;

  PlacedChunk(const ArmKinematics<S>& arm, const S* q, int64_t count)
      : points(static_cast<size_t>(kW * arm.C * count)),
        x(static_cast<size_t>(arm.S_ * count)),
        y(x.size()),
        z(x.size()) {
    std::vector<S> frames(static_cast<size_t>(12 * arm.L * count)), sines(static_cast<size_t>(2 * count));
    PlaceChunk(arm, q, count, frames.data(), points.data(), sines.data());
    for (int64_t s = 0; s < arm.S_; ++s) {
      std::copy_n(points.begin() + (kW * s) * count, count, x.begin() + s * count);
      std::copy_n(points.begin() + (kW * s + 1) * count, count, y.begin() + s * count);
      std::copy_n(points.begin() + (kW * s + 2) * count, count, z.begin() + s * count);
    }
  }
};

template <class S>
void RunHinge(const torch::Tensor& q, const ArmTables& arm, const torch::Tensor& reach_in,
              const std::vector<std::string>& kinds, const std::vector<torch::Tensor>& rows_in, torch::Tensor& value,
              torch::Tensor* gradient) {
  const torch::Tensor reach = reach_in.to(q.options()).contiguous();
  const ArmKinematics<S> kinematics(arm, q.size(1), reach.size(0));
  const int64_t M = q.size(0), J = kinematics.J, S_ = kinematics.S_;
  const S* reaches = reach.data_ptr<S>();
  const SceneObstacles<S> scene(kinds, rows_in, q.options());
  const S* qs = q.data_ptr<S>();
  S* out_value = value.data_ptr<S>();
  S* out_gradient = gradient == nullptr ? nullptr : gradient->data_ptr<S>();

  // Configurations in chunks: the chunk's sphere centres side by side (n = configurations x S), each obstacle's
  // hinge over all of them in one vectorised pass, then the gradients of the few active pairs. Every number of
  // configuration m comes from its own centres in a fixed order, whatever the chunk, so the result does not
  // depend on the thread count.
  at::parallel_for(0, M, 16, [&](int64_t begin, int64_t end) {
    const int64_t count = end - begin, n = count * S_;
    const PlacedChunk<S> chunk(kinematics, qs + begin * J, count);
    const std::vector<S>&points = chunk.points, &x = chunk.x, &y = chunk.y, &z = chunk.z;
    std::vector<S> chunk_reach(n), depth(n), penetration(n, S(0)), pushes(3 * n, S(0));
    std::vector<char> pushed(n, 0);
    for (int64_t s = 0; s < S_; ++s) std::fill_n(chunk_reach.begin() + s * count, count, reaches[s]);
    for (const Obstacle<S>& obstacle : scene.all) {
      const int64_t active = obstacle.hinge(x.data(), y.data(), z.data(), chunk_reach.data(), obstacle.row,
                                            depth.data(), penetration.data(), n);
      if (active == 0 || out_gradient == nullptr) continue;
      for (int64_t i = 0; i < n; ++i) {
        if (!(depth[i] > S(0))) continue;
        const S p[kW] = {x[i], y[i], z[i]};
        S normal[kW];
        obstacle.distance(p, obstacle.row, normal);
        for (int k = 0; k < kW; ++k) pushes[3 * i + k] -= normal[k];
        pushed[i] = 1;
      }
    }
    auto point = [&](int64_t c, int64_t m, int i) { return points[(kW * c + i) * count + m]; };
    for (int64_t m = 0; m < count; ++m) {
      S total = 0;
      for (int64_t s = 0; s < S_; ++s) total += penetration[s * count + m];
      out_value[begin + m] = total;
      if (out_gradient == nullptr) continue;
      if (total == S(0)) {  // no sphere within reach of any obstacle: no push
        for (int64_t j = 0; j < J; ++j) out_gradient[(begin + m) * J + j] = S(0);
        continue;
      }
      // dC/dq_j = a_j . (sum_s A[j, s] c_s x g_s - p_j x sum_s A[j, s] g_s) (Arm.spheres_vjp).
      for (int64_t j = 0; j < J; ++j) {
        S moment[kW] = {0, 0, 0}, force[kW] = {0, 0, 0};
        for (int64_t s = 0; s < S_; ++s) {
          const S weight = kinematics.moves[j * S_ + s];
          const int64_t i = s * count + m;
          if (!pushed[i] || weight == S(0)) continue;
          const S c[kW] = {x[i], y[i], z[i]};
          const S* g = pushes.data() + 3 * i;
          moment[0] += weight * (c[1] * g[2] - c[2] * g[1]);
          moment[1] += weight * (c[2] * g[0] - c[0] * g[2]);
          moment[2] += weight * (c[0] * g[1] - c[1] * g[0]);
          for (int k = 0; k < kW; ++k) force[k] += weight * g[k];
        }
        const S a[kW] = {point(S_ + j, m, 0), point(S_ + j, m, 1), point(S_ + j, m, 2)};
        const S p[kW] = {point(S_ + J + j, m, 0), point(S_ + J + j, m, 1), point(S_ + J + j, m, 2)};
        const S lever[kW] = {moment[0] - (p[1] * force[2] - p[2] * force[1]),
                             moment[1] - (p[2] * force[0] - p[0] * force[2]),
                             moment[2] - (p[0] * force[1] - p[1] * force[0])};
        out_gradient[(begin + m) * J + j] = a[0] * lever[0] + a[1] * lever[1] + a[2] * lever[2];
      }
    }
  });
}

void Check(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("arm_collision: " + what);
}

/// The checks of q (M, J), the tables and S spheres (`per_sphere`: their reach).
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
  const torch::Tensor link_joint = arm.link_joint.to(torch::kCPU, torch::kInt64).contiguous();
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

const std::vector<std::string>& ArmCollisionKinds() {
  static const std::vector<std::string> kinds = {"spheres", "boxes", "cylinders", "capsules"};  // PrepareKind's
  return kinds;
}

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

}  // namespace flowplan::kernels
