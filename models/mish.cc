#include "models/mish.h"

#include <ATen/Parallel.h>

#include <cstdint>
#include <cstring>

#include "models/precision.h"

namespace flowplan::models {
namespace {

// The loops below are written so that the compiler vectorises them (no calls,
// no branches); each is built for AVX-512, AVX2 and plain x86-64, and the
// loader picks the best one this CPU runs.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FLOWPLAN_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define FLOWPLAN_VECTOR_CLONES
#endif

/// e^x for x in [-87, 20] (the callers clamp): Cody–Waite reduction x = k ln 2 + r,
/// |r| ≤ ln 2 / 2, a degree-7 polynomial for e^r (Cephes' expf), and 2^k
/// written into the exponent bits. About 1 ulp.
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

/// x clamped to [-87, 20] as selects the vectoriser turns into min/max (NaN stays NaN).
inline float Clamp(float x) {
  const float low = x < -87.0f ? -87.0f : x;
  return low > 20.0f ? 20.0f : low;
}

// With w = e^x and n = w (w + 2): tanh(softplus(x)) = n / (n + 2), and
// d mish / dx = n / (n + 2) + 4 x w (w + 1) / (n + 2)^2. Above x = 20,
// n / (n + 2) is 1 in float32 and the second term vanishes; below -87, e^x is
// 0 to float32 precision.
FLOWPLAN_VECTOR_CLONES void MishForwardRange(const float* x, float* y, int64_t n) {
  for (int64_t i = 0; i < n; ++i) {
    const float w = Exp(Clamp(x[i]));
    const float m = w * (w + 2.0f);
    y[i] = x[i] * (m / (m + 2.0f));
  }
}

FLOWPLAN_VECTOR_CLONES void MishBackwardRange(const float* x, const float* g, float* out, int64_t n) {
  for (int64_t i = 0; i < n; ++i) {
    const float w = Exp(Clamp(x[i]));
    const float m = w * (w + 2.0f);
    const float inverse = 1.0f / (m + 2.0f);
    out[i] = g[i] * (m * inverse + 4.0f * x[i] * w * (w + 1.0f) * inverse * inverse);
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
