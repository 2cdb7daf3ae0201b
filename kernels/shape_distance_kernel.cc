#include "kernels/shape_distance_kernel.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace flowplan::kernels {
namespace {

// Each shape below follows its script line by line (geometry/<shape>.py):
// `Distance` returns the signed distance of one point to one shape and, when
// `gradient` is not null, writes the gradient (W numbers) there. Rows are read
// in geometry/scene.py's layout; a rotated shape's rotation matrix R (local to
// world, row-major) sits after its own columns (prepared rows).

/// x >= 0: +1, else -1 (geometry/frames.py sign_of).
template <class S>
S SignOf(S x) {
  return x < S(0) ? S(-1) : S(1);
}

/// R^T (p - c): the point in a rotated shape's frame, as geometry/frames.py's
/// to_local computes it, p^T R - c^T R. (Where a point lies on a rotated
/// shape's plane of symmetry, the last bit of that difference, and so the
/// side sign_of takes, depends on how each side's products round; exactly
/// only for unrotated shapes.)
template <class S, int W>
void ToLocal(const S* p, const S* centre, const S* R, S* local) {
  for (int j = 0; j < W; ++j) {
    S point = 0, shift = 0;
    for (int i = 0; i < W; ++i) {
      point += p[i] * R[i * W + j];
      shift += centre[i] * R[i * W + j];
    }
    local[j] = point - shift;
  }
}

/// R v: a direction from a shape's frame to the world (geometry/frames.py to_world).
template <class S, int W>
void ToWorld(const S* R, const S* v, S* out) {
  for (int i = 0; i < W; ++i) {
    S total = 0;
    for (int j = 0; j < W; ++j) total += R[i * W + j] * v[j];
    out[i] = total;
  }
}

/// Rows (W + 1): centre, radius (geometry/sphere.py).
template <class S, int W>
struct Sphere {
  static constexpr int kColumns = W + 1;
  static S Distance(const S* p, const S* row, S* gradient) {
    S offset[W], total = 0;
    for (int i = 0; i < W; ++i) {
      offset[i] = p[i] - row[i];
      total += offset[i] * offset[i];
    }
    const S length = std::sqrt(total);
    if (gradient != nullptr) {
      const S inverse = S(1) / std::max(length, S(1e-30));  // at the centre offset is 0, and so is the gradient
      for (int i = 0; i < W; ++i) gradient[i] = offset[i] * inverse;
    }
    return length - row[W];
  }
};

/// Prepared rows: centre (W), full side lengths (W), orientation (4 or 1), R (W W) (geometry/box.py).
template <class S, int W>
struct Box {
  static constexpr int kTurn = W == 3 ? 4 : 1;
  static constexpr int kColumns = 2 * W + kTurn + W * W;
  static S Distance(const S* p, const S* row, S* gradient) {
    const S* R = row + 2 * W + kTurn;
    S local[W], gap[W], outside[W];
    ToLocal<S, W>(p, row, R, local);
    S squares = 0, largest = 0;
    int face = 0;  // the axis of the first largest gap (torch.argmax)
    for (int i = 0; i < W; ++i) {
      gap[i] = std::abs(local[i]) - S(0.5) * row[W + i];
      outside[i] = std::max(gap[i], S(0));
      squares += outside[i] * outside[i];
      if (i == 0 || gap[i] > largest) {
        largest = gap[i];
        face = i;
      }
    }
    const S outside_length = std::sqrt(squares);
    if (gradient != nullptr) {
      S direction[W];
      for (int i = 0; i < W; ++i) {
        const S towards = outside_length > S(0) ? outside[i] / outside_length : S(i == face ? 1 : 0);
        direction[i] = towards * SignOf(local[i]);
      }
      ToWorld<S, W>(R, direction, gradient);
    }
    return outside_length + std::min(largest, S(0));
  }
};

/// Prepared rows: centre (W), radius, height, orientation (4 or 1), R (W W); the axis is local
/// coordinate W - 1 (geometry/cylinder.py).
template <class S, int W>
struct Cylinder {
  static constexpr int kTurn = W == 3 ? 4 : 1;
  static constexpr int kColumns = W + 2 + kTurn + W * W;
  static S Distance(const S* p, const S* row, S* gradient) {
    const S* R = row + W + 2 + kTurn;
    S local[W];
    ToLocal<S, W>(p, row, R, local);
    S squares = 0;
    for (int i = 0; i + 1 < W; ++i) squares += local[i] * local[i];
    const S radial = std::sqrt(squares), along = local[W - 1];
    const S side = radial - row[W], cap = std::abs(along) - S(0.5) * row[W + 1];
    const S outside_side = std::max(side, S(0)), outside_cap = std::max(cap, S(0));
    const S outside_length = std::sqrt(outside_side * outside_side + outside_cap * outside_cap);
    if (gradient != nullptr) {
      const bool outside = outside_length > S(0);
      const S radial_weight = outside ? outside_side / outside_length : S(side >= cap ? 1 : 0);
      const S axial_weight = outside ? outside_cap / outside_length : S(side < cap ? 1 : 0);
      S direction[W];
      for (int i = 0; i + 1 < W; ++i) {
        // On the axis the radial direction is local x.
        const S unit = radial <= S(0) ? S(i == 0 ? 1 : 0) : local[i] / radial;
        direction[i] = unit * radial_weight;
      }
      direction[W - 1] = SignOf(along) * axial_weight;
      ToWorld<S, W>(R, direction, gradient);
    }
    return outside_length + std::min(std::max(side, cap), S(0));
  }
};

/// Rows (2W + 1): a (W), b (W), radius: the points within radius of the segment a-b (geometry/capsule.py).
template <class S, int W>
struct Capsule {
  static constexpr int kColumns = 2 * W + 1;
  static S Distance(const S* p, const S* row, S* gradient) {
    S segment[W], offset[W];
    S length2 = 0, dot = 0;
    for (int i = 0; i < W; ++i) {
      segment[i] = row[W + i] - row[i];
      offset[i] = p[i] - row[i];
      length2 += segment[i] * segment[i];
      dot += offset[i] * segment[i];
    }
    const S along = std::min(std::max(dot / (length2 > S(0) ? length2 : S(1)), S(0)), S(1));
    S away[W], squares = 0;
    for (int i = 0; i < W; ++i) {
      away[i] = offset[i] - along * segment[i];
      squares += away[i] * away[i];
    }
    const S length = std::sqrt(squares);
    if (gradient != nullptr) {
      const S safe = std::max(length, S(1e-30));  // on the segment away is 0, and so is the gradient
      for (int i = 0; i < W; ++i) gradient[i] = away[i] / safe;
    }
    return length - row[2 * W];
  }
};

template <template <class, int> class Shape, class S, int W>
void Run(const std::string& kind, const torch::Tensor& points, const torch::Tensor& params, bool with_gradient,
         torch::Tensor& distance, torch::Tensor& gradient) {
  using Kernel = Shape<S, W>;
  if (params.size(1) != Kernel::kColumns) {
    throw std::runtime_error("shape_distance: " + kind + ": expected (K, " + std::to_string(Kernel::kColumns) +
                             ") rows" + (kind == "boxes" || kind == "cylinders" ? " (prepared_scene)" : "") +
                             ", got (" + std::to_string(params.size(0)) + ", " + std::to_string(params.size(1)) + ")");
  }
  const int64_t M = points.size(0), K = params.size(0);
  const S* p = points.data_ptr<S>();
  const S* rows = params.data_ptr<S>();
  S* d = distance.data_ptr<S>();
  S* g = with_gradient ? gradient.data_ptr<S>() : nullptr;
  at::parallel_for(0, M, 256, [&](int64_t begin, int64_t end) {
    for (int64_t m = begin; m < end; ++m) {
      for (int64_t k = 0; k < K; ++k) {
        d[m * K + k] = Kernel::Distance(p + m * W, rows + k * Kernel::kColumns, g == nullptr ? nullptr : g + (m * K + k) * W);
      }
    }
  });
}

template <class S, int W>
void Dispatch(const std::string& kind, const torch::Tensor& points, const torch::Tensor& params, bool with_gradient,
              torch::Tensor& distance, torch::Tensor& gradient) {
  if (kind == "spheres") return Run<Sphere, S, W>(kind, points, params, with_gradient, distance, gradient);
  if (kind == "boxes") return Run<Box, S, W>(kind, points, params, with_gradient, distance, gradient);
  if (kind == "cylinders") return Run<Cylinder, S, W>(kind, points, params, with_gradient, distance, gradient);
  if (kind == "capsules") return Run<Capsule, S, W>(kind, points, params, with_gradient, distance, gradient);
  throw std::runtime_error("shape_distance: unknown shape kind " + kind);
}

}  // namespace

const std::vector<std::string>& NativeShapeKinds() {
  static const std::vector<std::string> kinds = {"spheres", "boxes", "cylinders", "capsules"};
  return kinds;
}

std::tuple<torch::Tensor, torch::Tensor> ShapeDistance(const std::string& kind, const torch::Tensor& points_in,
                                                       const torch::Tensor& params_in, bool with_gradient) {
  if (points_in.dim() != 2 || (points_in.size(1) != 2 && points_in.size(1) != 3)) {
    throw std::runtime_error("shape_distance: " + kind + ": expected points (M, 2) or (M, 3)");
  }
  if (params_in.dim() != 2) throw std::runtime_error("shape_distance: " + kind + ": expected rows (K, columns)");
  const auto dtype = points_in.scalar_type();
  if (dtype != torch::kFloat32 && dtype != torch::kFloat64) {
    throw std::runtime_error("shape_distance: " + kind + ": expected float32 or float64 points");
  }
  if (points_in.requires_grad() || params_in.requires_grad()) {
    throw std::runtime_error("shape_distance: " + kind + ": no autograd (use geometry/scene.py's scene_distance)");
  }
  const torch::Tensor points = points_in.contiguous();
  const torch::Tensor params = params_in.to(dtype).contiguous();
  const int64_t M = points.size(0), K = params.size(0), W = points.size(1);
  torch::Tensor distance = torch::empty({M, K}, points.options());
  torch::Tensor gradient = with_gradient ? torch::empty({M, K, W}, points.options()) : torch::empty({0}, points.options());
  if (dtype == torch::kFloat32) {
    if (W == 3) Dispatch<float, 3>(kind, points, params, with_gradient, distance, gradient);
    else Dispatch<float, 2>(kind, points, params, with_gradient, distance, gradient);
  } else {
    if (W == 3) Dispatch<double, 3>(kind, points, params, with_gradient, distance, gradient);
    else Dispatch<double, 2>(kind, points, params, with_gradient, distance, gradient);
  }
  return {distance, gradient};
}

}  // namespace flowplan::kernels
