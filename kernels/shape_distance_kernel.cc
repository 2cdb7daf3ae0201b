#include "kernels/shape_distance_kernel.h"

#include <ATen/Parallel.h>

#include <stdexcept>

#include "kernels/shape_distance_math.h"

namespace flowplan::kernels {
namespace {

using shapes::Box;
using shapes::Capsule;
using shapes::Cylinder;
using shapes::Sphere;

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

int64_t PreparedShapeColumns(const std::string& kind, int W) {
  if (kind == "spheres") return W == 3 ? Sphere<float, 3>::kColumns : Sphere<float, 2>::kColumns;
  if (kind == "boxes") return W == 3 ? Box<float, 3>::kColumns : Box<float, 2>::kColumns;
  if (kind == "cylinders") return W == 3 ? Cylinder<float, 3>::kColumns : Cylinder<float, 2>::kColumns;
  if (kind == "capsules") return W == 3 ? Capsule<float, 3>::kColumns : Capsule<float, 2>::kColumns;
  return -1;
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
