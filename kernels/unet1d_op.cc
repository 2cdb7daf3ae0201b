// Registers the inference UNet as the TorchScript operator flowplan::unet1d.
// Loading this library (linked into flowplan; in Python,
// torch.ops.load_library("libflowplan_kernels.so"); a C++ program links it
// with -Wl,--no-as-needed, since it calls nothing in it) makes
// torch.ops.flowplan.unet1d callable from scripts; a planner exported with
// native kernels (docs/export.md) needs it loaded before torch.jit.load.

#include <torch/library.h>

#include <stdexcept>

#include "kernels/unet1d_kernel.h"

namespace flowplan::kernels {
namespace {

torch::Tensor UNet1DOp(const torch::Tensor& x, const torch::Tensor& t, const c10::optional<torch::Tensor>& cond,
                       const torch::Tensor& packed, c10::IntArrayRef down_dims, int64_t kernel_size, int64_t groups,
                       int64_t time_embed_dim, double time_scale, double norm_eps) {
  UNet1DShape shape;
  shape.state_dim = x.dim() == 3 ? x.size(2) : 0;
  shape.cond_dim = cond.has_value() ? cond->size(-1) : 0;
  shape.down_dims = down_dims.vec();
  shape.kernel_size = kernel_size;
  shape.groups = groups;
  shape.time_embed_dim = time_embed_dim;
  shape.time_scale = time_scale;
  shape.norm_eps = norm_eps;
  try {
    return UNet1DForward(x, t, cond.has_value() ? *cond : torch::Tensor(), packed, shape);
  } catch (const std::runtime_error& e) {
    TORCH_CHECK(false, e.what());
  }
}

}  // namespace

TORCH_LIBRARY(flowplan, m) {
  m.def(
      "unet1d(Tensor x, Tensor t, Tensor? cond, Tensor packed, int[] down_dims, int kernel_size, int groups, "
      "int time_embed_dim, float time_scale, float norm_eps) -> Tensor");
}

// A CPU kernel only, with no derivative: UNet1DForward refuses any input
// that requires a gradient, so a gradient through the network is an error,
// never silently missing (the scripted network sends such inputs to
// LibTorch's operators).
TORCH_LIBRARY_IMPL(flowplan, CPU, m) { m.impl("unet1d", UNet1DOp); }

}  // namespace flowplan::kernels
