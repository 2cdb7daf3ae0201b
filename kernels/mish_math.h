#pragma once

// Mish written as scalar float arithmetic the compiler vectorises: the one
// definition behind flowplan's training Mish (models/mish.cc) and the
// inference UNet kernel (kernels/unet1d_kernel.cc). Files that use it are
// compiled with -fno-trapping-math (the selects below become blends).

#include <cstdint>
#include <cstring>

// A loop marked FLOWPLAN_VECTOR_CLONES is built for AVX-512, AVX2 and plain
// x86-64 (whose floor is a call, so that one stays scalar), and the loader
// picks the best one this CPU runs.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define FLOWPLAN_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define FLOWPLAN_VECTOR_CLONES
#endif

namespace flowplan::kernels {

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

constexpr float kMishHigh = 20.0f;  // above: mish(x) = x and mish'(x) = 1 to float32 precision
constexpr float kMishLow = -87.0f;  // below: |mish(x)| < 1.5e-36 and |mish'(x)| < 1.5e-36, taken as 0

/// x clamped to [kMishLow, kMishHigh] as selects the vectoriser turns into
/// min/max; NaN goes to kMishLow (the callers' selects give NaN back), so Exp never sees it.
inline float MishClamp(float x) {
  const float low = !(x >= kMishLow) ? kMishLow : x;
  return low > kMishHigh ? kMishHigh : low;
}

/// mish(v) = v tanh(softplus(v)): with w = e^v and m = w (w + 2),
/// tanh(softplus(v)) = m / (m + 2). Huge and infinite inputs give v (or -0).
inline float MishValue(float v) {
  const float w = Exp(MishClamp(v));
  const float m = w * (w + 2.0f);
  const float inside = v * (m / (m + 2.0f));
  return v > kMishHigh ? v : (v < kMishLow ? -0.0f : inside);
}

/// d mish / dv = m / (m + 2) + 4 v w (w + 1) / (m + 2)^2 (1 above kMishHigh, 0 below kMishLow).
inline float MishDerivative(float v) {
  const float w = Exp(MishClamp(v));
  const float m = w * (w + 2.0f);
  const float inverse = 1.0f / (m + 2.0f);
  const float inside = m * inverse + 4.0f * v * w * (w + 1.0f) * inverse * inverse;
  return v > kMishHigh ? 1.0f : (v < kMishLow ? 0.0f : inside);
}

}  // namespace flowplan::kernels
