// Registers the native shape distances (kernels/shape_distance_kernel.h) as
// the TorchScript operator flowplan::shape_distance, beside flowplan::unet1d
// (kernels/unet1d_op.cc says how the library is loaded).

#include <torch/library.h>

#include <stdexcept>

#include "kernels/shape_distance_kernel.h"

namespace flowplan::kernels {
namespace {

std::tuple<torch::Tensor, torch::Tensor> ShapeDistanceOp(const std::string& kind, const torch::Tensor& points,
                                                         const torch::Tensor& params, bool with_gradient) {
  try {
    return ShapeDistance(kind, points, params, with_gradient);
  } catch (const std::runtime_error& e) {
    TORCH_CHECK(false, e.what());
  }
}

}  // namespace

TORCH_LIBRARY_FRAGMENT(flowplan, m) {
  m.def("shape_distance(str kind, Tensor points, Tensor params, bool with_gradient) -> (Tensor, Tensor)");
}

// A CPU kernel only, with no derivative: ShapeDistance refuses inputs that require a gradient.
TORCH_LIBRARY_IMPL(flowplan, CPU, m) { m.impl("shape_distance", ShapeDistanceOp); }

}  // namespace flowplan::kernels
