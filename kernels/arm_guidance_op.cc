// Registers the native guidance gradient of an arm (kernels/arm_guidance_kernel.h)
// as the TorchScript operator flowplan::arm_guidance, beside flowplan::arm_collision
// (kernels/unet1d_op.cc says how the library is loaded).

#include <torch/library.h>

#include <stdexcept>

#include "kernels/arm_guidance_kernel.h"

namespace flowplan::kernels {
namespace {

/// The terms' settings from a call's settings, by their config names.
GuidanceTerms Terms(const c10::Dict<std::string, double>& opts) {
  auto get = [&](const char* key) {
    const auto found = opts.find(key);
    if (found == opts.end()) throw std::runtime_error(std::string("arm_guidance: opts: no setting ") + key);
    return found->value();
  };
  GuidanceTerms terms;
  terms.collision_weight = get("guidance.collision_weight");
  terms.margin = get("guidance.margin");
  terms.smoothness_weight = get("guidance.smoothness_weight");
  terms.smoothness_sigma = get("guidance.smoothness_sigma");
  terms.joint_limit_weight = get("guidance.joint_limit_weight");
  terms.joint_limit_margin = get("guidance.joint_limit_margin");
  terms.joint_speed_weight = get("guidance.joint_speed_weight");
  terms.joint_speed_ratio = get("guidance.joint_speed_ratio");
  terms.clip = get("guidance.clip");
  return terms;
}

torch::Tensor ArmGuidanceOp(const torch::Tensor& x, const torch::Tensor& lo, const torch::Tensor& hi,
                            const torch::Tensor& fixed, const torch::Tensor& fixed_cross,
                            const torch::Tensor& fixed_cross_sq, const torch::Tensor& link_joint,
                            const torch::Tensor& link_turns, c10::IntArrayRef parents,
                            const torch::Tensor& frame_points, const torch::Tensor& ancestors,
                            const torch::Tensor& sphere_radii, const torch::Tensor& lower, const torch::Tensor& upper,
                            const torch::Tensor& velocity_limit, double dt, const std::vector<std::string>& kinds,
                            const std::vector<torch::Tensor>& rows, const c10::Dict<std::string, double>& opts) {
  const ArmTables arm{fixed, fixed_cross, fixed_cross_sq, link_joint, link_turns, parents.vec(), frame_points,
                      ancestors};
  try {
    return ArmGuidance(x, lo, hi, arm, ArmLimits{sphere_radii, lower, upper, velocity_limit}, dt, kinds, rows,
                       Terms(opts));
  } catch (const std::runtime_error& e) {
    TORCH_CHECK(false, e.what());
  }
}

}  // namespace

TORCH_LIBRARY_FRAGMENT(flowplan, m) {
  m.def(
      "arm_guidance(Tensor x, Tensor lo, Tensor hi, Tensor fixed, Tensor fixed_cross, Tensor fixed_cross_sq, "
      "Tensor link_joint, Tensor link_turns, int[] parents, Tensor frame_points, Tensor ancestors, "
      "Tensor sphere_radii, Tensor lower, Tensor upper, Tensor velocity_limit, float dt, str[] kinds, "
      "Tensor[] rows, Dict(str, float) opts) -> Tensor");
}

// A CPU kernel only, with no derivative: ArmGuidance refuses inputs that require a gradient.
TORCH_LIBRARY_IMPL(flowplan, CPU, m) { m.impl("arm_guidance", ArmGuidanceOp); }

}  // namespace flowplan::kernels
