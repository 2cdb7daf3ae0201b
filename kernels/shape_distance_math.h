#pragma once

// The signed distance of one point to one obstacle shape, and its gradient:
// the native form of the TorchScript distances of geometry/sphere.py,
// box.py, cylinder.py and capsule.py, the one definition behind the
// operators flowplan::shape_distance (kernels/shape_distance_kernel.h) and
// flowplan::arm_collision (kernels/arm_collision_kernel.h). Files that use it
// are compiled with -fno-trapping-math.

#include <algorithm>
#include <cmath>

namespace flowplan::kernels::shapes {

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

}  // namespace flowplan::kernels::shapes
