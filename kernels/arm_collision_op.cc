// Registers the native whole-arm collision hinge (kernels/arm_collision_kernel.h)
// as the TorchScript operator flowplan::arm_collision, beside flowplan::unet1d
// and flowplan::shape_distance (kernels/unet1d_op.cc says how the library is
// loaded).

#include <torch/library.h>

#include <stdexcept>

#include "kernels/arm_collision_kernel.h"

namespace flowplan::kernels {
namespace {

std::tuple<torch::Tensor, torch::Tensor> ArmCollisionOp(
    const torch::Tensor& q, const torch::Tensor& fixed, const torch::Tensor& fixed_cross,
    const torch::Tensor& fixed_cross_sq, const torch::Tensor& link_joint, const torch::Tensor& link_turns,
    c10::IntArrayRef parents, const torch::Tensor& frame_points, const torch::Tensor& ancestors,
    const torch::Tensor& reach, const std::vector<std::string>& kinds, const std::vector<torch::Tensor>& rows,
    bool with_gradient) {
  const ArmTables arm{fixed, fixed_cross, fixed_cross_sq, link_joint, link_turns, parents.vec(), frame_points,
                      ancestors};
  try {
    return ArmCollision(q, arm, reach, kinds, rows, with_gradient);
  } catch (const std::runtime_error& e) {
    TORCH_CHECK(false, e.what());
  }
}

}  // namespace

TORCH_LIBRARY_FRAGMENT(flowplan, m) {
  m.def(
      "arm_collision(Tensor q, Tensor fixed, Tensor fixed_cross, Tensor fixed_cross_sq, Tensor link_joint, "
      "Tensor link_turns, int[] parents, Tensor frame_points, Tensor ancestors, Tensor reach, str[] kinds, "
      "Tensor[] rows, bool with_gradient) -> (Tensor, Tensor)");
}

// A CPU kernel only, with no derivative: ArmCollision refuses inputs that require a gradient.
TORCH_LIBRARY_IMPL(flowplan, CPU, m) { m.impl("arm_collision", ArmCollisionOp); }

}  // namespace flowplan::kernels
