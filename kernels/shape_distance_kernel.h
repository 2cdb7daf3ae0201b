#pragma once

// Signed distances from points to obstacle shapes, and their gradients, as
// one native loop per shape kind: what the TorchScript distances of
// geometry/sphere.py, box.py, cylinder.py and capsule.py compute (the same
// formulas, the same conventions at ties and on axes; on a rotated shape's
// plane of symmetry either side may round differently), for the guidance
// steps of a plan, where a shape's script takes some twenty LibTorch
// operators per distance pass and their per-operator cost is most of the
// pass (docs/performance.md, "Native distances"). Registered as the
// TorchScript operator `flowplan::shape_distance` (kernels/shape_distance_op.cc);
// geometry/native_distances.py calls it. Tested against the scripts
// (tests/kernels/shape_distance_kernel_test.cc).

#include <torch/torch.h>

#include <string>
#include <tuple>
#include <vector>

namespace flowplan::kernels {

/// The shape kinds ShapeDistance computes (geometry/scene.py's names).
const std::vector<std::string>& NativeShapeKinds();

/// The width of a kind's prepared rows in W dimensions (what ShapeDistance
/// takes), or -1 for a kind it does not know.
int64_t PreparedShapeColumns(const std::string& kind, int W);

/// Signed distance (negative inside) from points (M, W) to the K shapes of
/// one kind, W = 2 or 3: (M, K); and, if `with_gradient`, its gradient with
/// respect to the points (M, K, W), else an empty tensor. `params` are the
/// kind's rows in geometry/scene.py's layout, boxes and cylinders prepared
/// (their rotation matrices appended, prepared_scene), converted to the
/// points' dtype (float32 or float64). Points run in parallel on LibTorch's
/// intra-op threads, each on its own, so the result does not depend on the
/// thread count. No autograd. Throws std::runtime_error naming the kind and
/// what is wrong (an unknown kind, rows of the wrong width, a dtype).
std::tuple<torch::Tensor, torch::Tensor> ShapeDistance(const std::string& kind, const torch::Tensor& points,
                                                       const torch::Tensor& params, bool with_gradient);

}  // namespace flowplan::kernels
