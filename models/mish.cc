#include "models/mish.h"

#include <ATen/Parallel.h>

#include <cstdint>

#include "core/error.h"
#include "kernels/mish_math.h"
#include "models/precision.h"

namespace flowplan::models {
namespace {

// mish.cc is compiled without FMA contraction (models/CMakeLists.txt), so
// every clone, vector body and scalar tail of these loops computes the same bits.
FLOWPLAN_VECTOR_CLONES void MishForwardRange(const float* x, float* y, int64_t n) {
  for (int64_t i = 0; i < n; ++i) y[i] = kernels::MishValue(x[i]);
}

FLOWPLAN_VECTOR_CLONES void MishBackwardRange(const float* x, const float* g, float* out, int64_t n) {
  for (int64_t i = 0; i < n; ++i) out[i] = g[i] * kernels::MishDerivative(x[i]);
}

constexpr int64_t kGrain = 1 << 15;  // elements per parallel task

torch::Tensor MishForward(const torch::Tensor& x) {
  const torch::Tensor in = x.contiguous();
  torch::Tensor out = torch::empty_like(in);
  const float* src = in.data_ptr<float>();
  float* dst = out.data_ptr<float>();
  at::parallel_for(0, in.numel(), kGrain, [&](int64_t begin, int64_t end) {
    MishForwardRange(src + begin, dst + begin, end - begin);
  });
  return out;
}

torch::Tensor MishBackward(const torch::Tensor& x, const torch::Tensor& grad) {
  const torch::Tensor in = x.contiguous(), g = grad.contiguous();
  torch::Tensor out = torch::empty_like(in);
  const float* src = in.data_ptr<float>();
  const float* gs = g.data_ptr<float>();
  float* dst = out.data_ptr<float>();
  at::parallel_for(0, in.numel(), kGrain, [&](int64_t begin, int64_t end) {
    MishBackwardRange(src + begin, gs + begin, dst + begin, end - begin);
  });
  return out;
}

class MishFunction : public torch::autograd::Function<MishFunction> {
 public:
  static torch::Tensor forward(torch::autograd::AutogradContext* context, const torch::Tensor& x) {
    context->save_for_backward({x});
    return MishForward(x);
  }
  static torch::autograd::tensor_list backward(torch::autograd::AutogradContext* context,
                                               torch::autograd::tensor_list grads) {
    // The gradient is computed outside autograd: a second derivative would silently miss terms.
    if (torch::GradMode::is_enabled()) {
      throw Error("flowplan's Mish (models/mish.cc) has no second derivative (backward with create_graph)");
    }
    const torch::Tensor x = context->get_saved_variables()[0];
    return {MishBackward(x, grads[0])};
  }
};

}  // namespace

torch::Tensor Mish(const torch::Tensor& x) {
  const torch::Tensor wide = WidenBfloat16(x);
  if (wide.scalar_type() != torch::kFloat32 || !wide.device().is_cpu()) return torch::mish(wide);
  return MishFunction::apply(wide);
}

}  // namespace flowplan::models
