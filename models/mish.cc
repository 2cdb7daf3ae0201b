#include "models/mish.h"

#include <ATen/Parallel.h>

#include <cstdint>
#include <cstring>

#include "core/error.h"
#include "models/precision.h"

namespace flowplan::models {
namespace {

// The loops below are written so that the compiler vectorises them (selects,
// no branches); each is built for AVX-512, AVX2 and plain x86-64 (whose floor
// is a call, so that one stays scalar), and the loader picks the best one this
// CPU runs. mish.cc is compiled without FMA contraction (models/CMakeLists.txt),
// so every clone, vector body and scalar tail computes the same bits.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FLOWPLAN_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define FLOWPLAN_VECTOR_CLONES
#endif

/// e^x for x in [-87, 20] (the callers clamp): Cody–Waite reduction x = k ln 2 + r,
/// |r| ≤ ln 2 / 2, a degree-7 polynomial for e^r (Cephes' expf), and 2^k
/// (k in [-126, 29], a normal exponent) written into the exponent bits. About 1 ulp.
inline float Exp(float x) {
  const float k = __builtin_floorf(x * 1.44269504088896341f + 0.5f);
  const float r = (x - k * 0.693359375f) + k * 2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  const int32_t bits = (static_cast<int32_t>(k) + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}

constexpr float kHigh = 20.0f;  // above: mish(x) = x and mish'(x) = 1 to float32 precision
constexpr float kLow = -87.0f;  // below: |mish(x)| < 1.5e-36 and |mish'(x)| < 1.5e-36, taken as 0

/// x clamped to [kLow, kHigh] as selects the vectoriser turns into min/max;
/// NaN goes to kLow (the callers' selects give NaN back), so Exp never sees it.
inline float Clamp(float x) {
  const float low = !(x >= kLow) ? kLow : x;
  return low > kHigh ? kHigh : low;
}

// With w = e^x and m = w (w + 2): tanh(softplus(x)) = m / (m + 2), and
// d mish / dx = m / (m + 2) + 4 x w (w + 1) / (m + 2)^2. Outside [kLow, kHigh]
// the values are selected, so huge and infinite inputs give x (or -0) and 1
// (or 0), never overflow.
FLOWPLAN_VECTOR_CLONES void MishForwardRange(const float* x, float* y, int64_t n) {
  for (int64_t i = 0; i < n; ++i) {
    const float v = x[i];
    const float w = Exp(Clamp(v));
    const float m = w * (w + 2.0f);
    const float inside = v * (m / (m + 2.0f));
    y[i] = v > kHigh ? v : (v < kLow ? -0.0f : inside);
  }
}

FLOWPLAN_VECTOR_CLONES void MishBackwardRange(const float* x, const float* g, float* out, int64_t n) {
  for (int64_t i = 0; i < n; ++i) {
    const float v = x[i], c = Clamp(v);
    const float w = Exp(c);
    const float m = w * (w + 2.0f);
    const float inverse = 1.0f / (m + 2.0f);
    const float inside = m * inverse + 4.0f * v * w * (w + 1.0f) * inverse * inverse;
    out[i] = g[i] * (v > kHigh ? 1.0f : (v < kLow ? 0.0f : inside));
  }
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
