#include "kernels/unet1d_kernel.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "kernels/mish_math.h"

namespace flowplan::kernels {
namespace {

// ---------------------------------------------------------------------------
// The packed parameters. Walk() visits the UNet's layers in the order the
// forward pass reads them; PackUNet1D writes them in that order and
// UNet1DForward reads them back with a cursor. Layouts:
//   vector (n):               as is
//   linear (O, I) + bias:     W row-major (O, I), then b (O)
//   conv (O, I, K) + bias:    W as [K][I][O] (a tap's (I, O) matrix, output channels contiguous), then b (O)
//   transposed (I, O, K):     W as [K][I][O], then b (O)
//   group norm (C):           gamma (C), then beta (C)
// A residual block (in -> out): conv0 (out, in, K), norm0, film (2 out, E + C),
// conv1 (out, out, K), norm1, and a 1x1 residual conv (out, in, 1) when in != out.

int64_t Levels(const UNet1DShape& s) { return static_cast<int64_t>(s.down_dims.size()); }

/// dims[0] = D, dims[1..] = down_dims.
std::vector<int64_t> Dims(const UNet1DShape& s) {
  std::vector<int64_t> dims = {s.state_dim};
  dims.insert(dims.end(), s.down_dims.begin(), s.down_dims.end());
  return dims;
}

template <class Visitor>
void VisitBlock(const UNet1DShape& s, const std::string& name, int64_t in, int64_t out, Visitor& v) {
  const int64_t k = s.kernel_size, feature = s.time_embed_dim + s.cond_dim;
  v.Conv(name + ".block0.conv", out, in, k);
  v.Norm(name + ".block0.norm", out);
  v.Linear(name + ".film", 2 * out, feature);
  v.Conv(name + ".block1.conv", out, out, k);
  v.Norm(name + ".block1.norm", out);
  if (in != out) v.Conv(name + ".residual", out, in, 1);
}

template <class Visitor>
void Walk(const UNet1DShape& s, Visitor& v) {
  const int64_t e = s.time_embed_dim, levels = Levels(s);
  const std::vector<int64_t> dims = Dims(s);
  v.Vector("frequencies", e / 2);
  v.Linear("time_in", 4 * e, e);
  v.Linear("time_out", e, 4 * e);
  for (int64_t i = 0; i < levels; ++i) {
    const std::string name = "down" + std::to_string(i);
    VisitBlock(s, name + "_block0", dims[i], dims[i + 1], v);
    VisitBlock(s, name + "_block1", dims[i + 1], dims[i + 1], v);
    if (i + 1 < levels) v.Conv(name + "_down", dims[i + 1], dims[i + 1], 3);
  }
  VisitBlock(s, "mid0", dims.back(), dims.back(), v);
  VisitBlock(s, "mid1", dims.back(), dims.back(), v);
  for (int64_t i = levels - 1; i >= 1; --i) {
    const std::string name = "up" + std::to_string(levels - 1 - i);
    VisitBlock(s, name + "_block0", 2 * dims[i + 1], dims[i], v);
    VisitBlock(s, name + "_block1", dims[i], dims[i], v);
    v.Transposed(name + "_up", dims[i], dims[i], 4);
  }
  v.Conv("final_block.conv", dims[1], dims[1], s.kernel_size);
  v.Norm("final_block.norm", dims[1]);
  v.Conv("final_conv", s.state_dim, dims[1], 1);
}

struct Counter {
  int64_t n = 0;
  void Vector(const std::string&, int64_t size) { n += size; }
  void Linear(const std::string&, int64_t out, int64_t in) { n += out * in + out; }
  void Conv(const std::string&, int64_t out, int64_t in, int64_t k) { n += k * in * out + out; }
  void Transposed(const std::string&, int64_t in, int64_t out, int64_t k) { n += k * in * out + out; }
  void Norm(const std::string&, int64_t c) { n += 2 * c; }
};

struct Packer {
  const std::function<torch::Tensor(const std::string&)>& parameter;
  std::vector<float> out;

  torch::Tensor Get(const std::string& name, std::vector<int64_t> sizes) {
    const torch::Tensor p = parameter(name);
    if (!p.defined() || p.sizes().vec() != sizes) {
      std::string want = "(";
      for (size_t i = 0; i < sizes.size(); ++i) want += (i ? ", " : "") + std::to_string(sizes[i]);
      throw std::runtime_error("UNet1D kernel: parameter " + name + ": expected " + want + ")" +
                               (p.defined() ? ", got " + std::to_string(p.numel()) + " numbers of another shape"
                                            : ", missing"));
    }
    return p.detach().to(torch::kCPU, torch::kFloat32).contiguous();
  }
  void Append(const torch::Tensor& t) {
    const float* p = t.data_ptr<float>();
    out.insert(out.end(), p, p + t.numel());
  }
  void Vector(const std::string& name, int64_t size) { Append(Get(name, {size})); }
  void Linear(const std::string& name, int64_t o, int64_t i) {
    Append(Get(name + ".weight", {o, i}));
    Append(Get(name + ".bias", {o}));
  }
  void Conv(const std::string& name, int64_t o, int64_t i, int64_t k) {
    Append(Get(name + ".weight", {o, i, k}).permute({2, 1, 0}).contiguous());  // [K][I][O]
    Append(Get(name + ".bias", {o}));
  }
  void Transposed(const std::string& name, int64_t i, int64_t o, int64_t k) {
    Append(Get(name + ".weight", {i, o, k}).permute({2, 0, 1}).contiguous());  // [K][I][O]
    Append(Get(name + ".bias", {o}));
  }
  void Norm(const std::string& name, int64_t c) {
    Append(Get(name + ".weight", {c}));
    Append(Get(name + ".bias", {c}));
  }
};

// ---------------------------------------------------------------------------
// Activations are (T, C) row-major (channels contiguous, as x (B, T, D)
// already is), with P zero rows before and after so that a convolution reads
// its padding without branches.

struct Rows {
  float* data = nullptr;
  int64_t T = 0, C = 0, P = 0;
  float* Row(int64_t r) const { return data + (r + P) * C; }
};

/// Scratch memory of one thread, kept between calls (no allocation once warm).
class Arena {
 public:
  void Reset() { next_ = 0; }
  float* Floats(int64_t n) {
    if (next_ == blocks_.size()) blocks_.emplace_back();
    std::vector<float>& block = blocks_[next_++];
    if (static_cast<int64_t>(block.size()) < n) block.resize(n);
    return block.data();
  }
  Rows Take(int64_t T, int64_t C, int64_t P) {
    Rows r{Floats((T + 2 * P) * C), T, C, P};
    std::memset(r.data, 0, sizeof(float) * P * C);
    std::memset(r.Row(T), 0, sizeof(float) * P * C);
    return r;
  }

 private:
  std::vector<std::vector<float>> blocks_;
  size_t next_ = 0;
};

typedef float Vec __attribute__((vector_size(64)));  // 16 floats; one AVX-512 register
constexpr int64_t kLanes = 16;

/// One tap of a convolution: its (I, O) weights and the input row it reads
/// relative to the output row's base (r * in_step + offset).
struct Tap {
  const float* w;
  int64_t offset;
};

/// TB output rows × NV·16 output channels, accumulated in registers over every
/// tap and input channel.
template <int TB, int NV>
__attribute__((always_inline)) inline void Tile(const Rows& x, const Tap* taps, int ntaps, int64_t in_step, int64_t r0,
                                                int64_t O, int64_t o0, const float* bias, float* y, int64_t out_step,
                                                int64_t out_off) {
  const int64_t I = x.C;
  Vec acc[TB][NV];
  for (int n = 0; n < NV; ++n) {
    Vec b;
    std::memcpy(&b, bias + o0 + n * kLanes, sizeof b);
    for (int j = 0; j < TB; ++j) acc[j][n] = b;
  }
  for (int a = 0; a < ntaps; ++a) {
    const float* w = taps[a].w + o0;
    const float* xr[TB];
    for (int j = 0; j < TB; ++j) xr[j] = x.Row((r0 + j) * in_step + taps[a].offset);
    for (int64_t i = 0; i < I; ++i) {
      Vec wv[NV];
      for (int n = 0; n < NV; ++n) std::memcpy(&wv[n], w + i * O + n * kLanes, sizeof(Vec));
      for (int j = 0; j < TB; ++j) {
        const float s = xr[j][i];
        for (int n = 0; n < NV; ++n) acc[j][n] += s * wv[n];
      }
    }
  }
  for (int j = 0; j < TB; ++j) {
    float* out = y + ((r0 + j) * out_step + out_off) * O + o0;
    for (int n = 0; n < NV; ++n) std::memcpy(out + n * kLanes, &acc[j][n], sizeof(Vec));
  }
}

template <int NV>
__attribute__((always_inline)) inline void TileRows(const Rows& x, const Tap* taps, int ntaps, int64_t in_step,
                                                    int64_t R, int64_t O, int64_t o0, const float* bias, float* y,
                                                    int64_t out_step, int64_t out_off) {
  int64_t r = 0;
  for (; r + 4 <= R; r += 4) Tile<4, NV>(x, taps, ntaps, in_step, r, O, o0, bias, y, out_step, out_off);
  for (; r < R; ++r) Tile<1, NV>(x, taps, ntaps, in_step, r, O, o0, bias, y, out_step, out_off);
}

/// y row (r * out_step + out_off), r < R, channel o = bias[o] + sum over taps
/// and input channels i of x.Row(r * in_step + tap.offset)[i] * tap.w[i * O + o].
/// y points at row 0 of an output with O channels per row.
FLOWPLAN_VECTOR_CLONES void ConvRows(const Rows& x, const Tap* taps, int ntaps, int64_t in_step, int64_t R, int64_t O,
                                     const float* bias, float* y, int64_t out_step, int64_t out_off) {
  if (O % kLanes != 0) {
    for (int64_t r = 0; r < R; ++r) {
      float* out = y + (r * out_step + out_off) * O;
      for (int64_t o = 0; o < O; ++o) out[o] = bias[o];
      for (int a = 0; a < ntaps; ++a) {
        const float* in = x.Row(r * in_step + taps[a].offset);
        for (int64_t i = 0; i < x.C; ++i) {
          const float s = in[i];
          const float* w = taps[a].w + i * O;
          for (int64_t o = 0; o < O; ++o) out[o] += s * w[o];
        }
      }
    }
    return;
  }
  int64_t o0 = 0;
  for (; o0 + 4 * kLanes <= O; o0 += 4 * kLanes) TileRows<4>(x, taps, ntaps, in_step, R, O, o0, bias, y, out_step, out_off);
  for (; o0 + 2 * kLanes <= O; o0 += 2 * kLanes) TileRows<2>(x, taps, ntaps, in_step, R, O, o0, bias, y, out_step, out_off);
  for (; o0 + kLanes <= O; o0 += kLanes) TileRows<1>(x, taps, ntaps, in_step, R, O, o0, bias, y, out_step, out_off);
}

/// y (T, C) in place: GroupNorm (G groups, biased variance over T and the
/// group's channels, two passes), Mish, then the FiLM y * scale + shift if
/// scale is given, then + residual (T, C) if given. work: 4 C floats.
FLOWPLAN_VECTOR_CLONES void NormMish(float* y, int64_t T, int64_t C, int64_t G, const float* gamma, const float* beta,
                                     float eps, const float* scale, const float* shift, const float* residual,
                                     float* work) {
  float* sum = work;
  float* mean = work + C;
  float* a = work + 2 * C;
  float* b = work + 3 * C;
  const int64_t per = C / G;
  const float count = static_cast<float>(T * per);
  for (int64_t c = 0; c < C; ++c) sum[c] = 0.0f;
  for (int64_t t = 0; t < T; ++t) {
    const float* row = y + t * C;
    for (int64_t c = 0; c < C; ++c) sum[c] += row[c];
  }
  for (int64_t g = 0; g < G; ++g) {
    float s = 0.0f;
    for (int64_t c = g * per; c < (g + 1) * per; ++c) s += sum[c];
    for (int64_t c = g * per; c < (g + 1) * per; ++c) mean[c] = s / count;
  }
  for (int64_t c = 0; c < C; ++c) sum[c] = 0.0f;
  for (int64_t t = 0; t < T; ++t) {
    const float* row = y + t * C;
    for (int64_t c = 0; c < C; ++c) {
      const float d = row[c] - mean[c];
      sum[c] += d * d;
    }
  }
  for (int64_t g = 0; g < G; ++g) {
    float s = 0.0f;
    for (int64_t c = g * per; c < (g + 1) * per; ++c) s += sum[c];
    const float inverse = 1.0f / std::sqrt(s / count + eps);
    for (int64_t c = g * per; c < (g + 1) * per; ++c) {
      a[c] = gamma[c] * inverse;
      b[c] = beta[c] - mean[c] * a[c];
    }
  }
  for (int64_t t = 0; t < T; ++t) {
    float* row = y + t * C;
    for (int64_t c = 0; c < C; ++c) row[c] = MishValue(row[c] * a[c] + b[c]);
  }
  if (scale != nullptr) {
    for (int64_t t = 0; t < T; ++t) {
      float* row = y + t * C;
      for (int64_t c = 0; c < C; ++c) row[c] = row[c] * scale[c] + shift[c];
    }
  }
  if (residual != nullptr) {
    for (int64_t i = 0; i < T * C; ++i) y[i] += residual[i];
  }
}

/// y (O) = W (O, I) x (I) + b.
void Linear(const float* w, const float* bias, const float* x, int64_t O, int64_t I, float* y) {
  for (int64_t o = 0; o < O; ++o) {
    const float* row = w + o * I;
    float s = 0.0f;
    for (int64_t i = 0; i < I; ++i) s += row[i] * x[i];
    y[o] = s + bias[o];
  }
}

class Cursor {
 public:
  Cursor(const float* begin, int64_t size) : p_(begin), end_(begin + size) {}
  const float* Take(int64_t n) {
    if (p_ + n > end_) throw std::runtime_error("flowplan::unet1d: the packed parameters are shorter than the shape needs");
    const float* q = p_;
    p_ += n;
    return q;
  }

 private:
  const float* p_;
  const float* end_;
};

/// One batch element's forward pass.
class Pass {
 public:
  Pass(const UNet1DShape& s, Cursor cursor, Arena& arena)
      : s_(s), cursor_(cursor), arena_(arena), P_(std::max<int64_t>(s.kernel_size / 2, 1)) {}

  void Run(const float* x, float t, const float* cond, int64_t T, float* out) {
    arena_.Reset();
    Feature(t, cond);
    const int64_t levels = Levels(s_);
    const std::vector<int64_t> dims = Dims(s_);
    Rows h = arena_.Take(T, s_.state_dim, P_);
    std::memcpy(h.Row(0), x, sizeof(float) * T * s_.state_dim);
    std::vector<Rows> skips;
    for (int64_t i = 0; i < levels; ++i) {
      h = Block(h, dims[i + 1]);
      h = Block(h, dims[i + 1]);
      skips.push_back(h);
      if (i + 1 < levels) h = Down(h);
    }
    h = Block(h, dims.back());
    h = Block(h, dims.back());
    for (int64_t i = levels - 1; i >= 1; --i) {
      h = Concat(h, skips.back());
      skips.pop_back();
      h = Block(h, dims[i]);
      h = Block(h, dims[i]);
      h = Up(h);
    }
    h = BlockConv(h, dims[1]);  // the final conv block
    FinishNorm(h, nullptr, nullptr, nullptr);
    PointwiseConv(h, s_.state_dim, out);  // the final 1x1 convolution writes the output (T, D) directly
  }

 private:
  /// The time feature and the cond after it, (E + C), and its Mish, which
  /// every FiLM layer reads.
  void Feature(float t, const float* cond) {
    const int64_t e = s_.time_embed_dim, half = e / 2, c = s_.cond_dim;
    const float* frequencies = cursor_.Take(half);
    float* embedding = arena_.Floats(e);
    const float scaled = t * static_cast<float>(s_.time_scale);
    for (int64_t k = 0; k < half; ++k) {
      const float angle = scaled * frequencies[k];
      embedding[k] = std::sin(angle);
      embedding[half + k] = std::cos(angle);
    }
    const float* w_in = cursor_.Take(4 * e * e);
    const float* b_in = cursor_.Take(4 * e);
    float* hidden = arena_.Floats(4 * e);
    Linear(w_in, b_in, embedding, 4 * e, e, hidden);
    for (int64_t i = 0; i < 4 * e; ++i) hidden[i] = MishValue(hidden[i]);
    const float* w_out = cursor_.Take(e * 4 * e);
    const float* b_out = cursor_.Take(e);
    float* feature = arena_.Floats(e + c);
    Linear(w_out, b_out, hidden, e, 4 * e, feature);
    for (int64_t i = 0; i < c; ++i) feature[e + i] = cond[i];
    for (int64_t i = 0; i < e + c; ++i) feature[i] = MishValue(feature[i]);
    feature_ = feature;
  }

  Rows Block(const Rows& x, int64_t out) {
    // The packed order: conv0, norm0, film, conv1, norm1, residual; each
    // norm is applied (FinishNorm) once what follows it in the block is known.
    Rows h = BlockConv(x, out);
    const int64_t f = s_.time_embed_dim + s_.cond_dim;
    const float* w_film = cursor_.Take(2 * out * f);
    const float* b_film = cursor_.Take(2 * out);
    float* film = arena_.Floats(2 * out);
    Linear(w_film, b_film, feature_, 2 * out, f, film);
    FinishNorm(h, film, film + out, nullptr);
    Rows h2 = BlockConv(h, out);
    Rows skip = x;
    if (x.C != out) {
      skip = arena_.Take(x.T, out, P_);
      PointwiseConv(x, out, skip.Row(0));
    }
    FinishNorm(h2, nullptr, nullptr, &skip);
    return h2;
  }

  /// The convolution of a conv block (K taps, same padding) -> (T, O); its
  /// norm's parameters, read next, are kept for FinishNorm.
  Rows BlockConv(const Rows& x, int64_t O) {
    const int64_t K = s_.kernel_size;
    const float* w = cursor_.Take(K * x.C * O);
    const float* bias = cursor_.Take(O);
    std::vector<Tap> taps(static_cast<size_t>(K));
    for (int64_t k = 0; k < K; ++k) taps[static_cast<size_t>(k)] = Tap{w + k * x.C * O, k - K / 2};
    Rows y = arena_.Take(x.T, O, P_);
    ConvRows(x, taps.data(), static_cast<int>(K), 1, x.T, O, bias, y.Row(0), 1, 0);
    gamma_ = cursor_.Take(O);
    beta_ = cursor_.Take(O);
    return y;
  }

  /// y in place: the last BlockConv's GroupNorm, Mish, then the FiLM and the residual if given.
  void FinishNorm(const Rows& y, const float* scale, const float* shift, const Rows* residual) {
    NormMish(y.Row(0), y.T, y.C, s_.groups, gamma_, beta_, static_cast<float>(s_.norm_eps), scale, shift,
             residual ? residual->Row(0) : nullptr, arena_.Floats(4 * y.C));
  }

  /// A 1x1 convolution of x to O channels, written to T rows of O at y.
  void PointwiseConv(const Rows& x, int64_t O, float* y) {
    const float* w = cursor_.Take(x.C * O);
    const float* bias = cursor_.Take(O);
    const Tap tap{w, 0};
    ConvRows(x, &tap, 1, 1, x.T, O, bias, y, 1, 0);
  }

  /// Conv1d(C, C, 3, stride 2, padding 1): T -> T / 2.
  Rows Down(const Rows& x) {
    const int64_t C = x.C;
    const float* w = cursor_.Take(3 * C * C);
    const float* bias = cursor_.Take(C);
    const Tap taps[3] = {{w, -1}, {w + C * C, 0}, {w + 2 * C * C, 1}};
    Rows y = arena_.Take(x.T / 2, C, P_);
    ConvRows(x, taps, 3, 2, y.T, C, bias, y.Row(0), 1, 0);
    return y;
  }

  /// ConvTranspose1d(C, C, 4, stride 2, padding 1): T -> 2 T. Output row 2m
  /// reads taps 1 (row m) and 3 (row m - 1); row 2m + 1 taps 0 (row m + 1) and 2 (row m).
  Rows Up(const Rows& x) {
    const int64_t C = x.C;
    const float* w = cursor_.Take(4 * C * C);
    const float* bias = cursor_.Take(C);
    const Tap even[2] = {{w + C * C, 0}, {w + 3 * C * C, -1}};
    const Tap odd[2] = {{w, 1}, {w + 2 * C * C, 0}};
    Rows y = arena_.Take(2 * x.T, C, P_);
    ConvRows(x, even, 2, 1, x.T, C, bias, y.Row(0), 2, 0);
    ConvRows(x, odd, 2, 1, x.T, C, bias, y.Row(0), 2, 1);
    return y;
  }

  /// cat([a, b], channels).
  Rows Concat(const Rows& a, const Rows& b) {
    Rows y = arena_.Take(a.T, a.C + b.C, P_);
    for (int64_t t = 0; t < a.T; ++t) {
      std::memcpy(y.Row(t), a.Row(t), sizeof(float) * a.C);
      std::memcpy(y.Row(t) + a.C, b.Row(t), sizeof(float) * b.C);
    }
    return y;
  }

  const UNet1DShape& s_;
  Cursor cursor_;
  Arena& arena_;
  const int64_t P_;
  const float* feature_ = nullptr;
  const float* gamma_ = nullptr;
  const float* beta_ = nullptr;
};

void CheckShape(const UNet1DShape& s) {
  if (s.state_dim <= 0 || s.cond_dim < 0 || s.down_dims.empty() || s.time_embed_dim < 4 || s.time_embed_dim % 2 ||
      s.kernel_size % 2 == 0 || s.groups <= 0) {
    throw std::runtime_error("flowplan::unet1d: the shape is not a UNet1D's (state_dim " + std::to_string(s.state_dim) +
                             ", kernel_size " + std::to_string(s.kernel_size) + ")");
  }
  for (int64_t d : s.down_dims) {
    if (d <= 0 || d % s.groups != 0) {
      throw std::runtime_error("flowplan::unet1d: a width of " + std::to_string(d) + " is not a multiple of the " +
                               std::to_string(s.groups) + " groups");
    }
  }
}

}  // namespace

int64_t UNet1DShape::PackedSize() const {
  Counter counter;
  Walk(*this, counter);
  return counter.n;
}

torch::Tensor PackUNet1D(const UNet1DShape& shape, const std::function<torch::Tensor(const std::string&)>& parameter) {
  CheckShape(shape);
  Packer packer{parameter, {}};
  Walk(shape, packer);
  return torch::tensor(packer.out, torch::kFloat32);
}

torch::Tensor UNet1DForward(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond,
                            const torch::Tensor& packed, const UNet1DShape& shape) {
  CheckShape(shape);
  auto fail = [](const std::string& what) { throw std::runtime_error("flowplan::unet1d: " + what); };
  if (x.dim() != 3 || x.size(2) != shape.state_dim || x.scalar_type() != torch::kFloat32 || !x.device().is_cpu()) {
    fail("x: expected (B, T, " + std::to_string(shape.state_dim) + ") float32 on the CPU");
  }
  const int64_t B = x.size(0), T = x.size(1), factor = int64_t{1} << (shape.down_dims.size() - 1);
  if (T < factor || T % factor != 0) fail("x: the horizon " + std::to_string(T) + " is not a multiple of " + std::to_string(factor));
  if (t.dim() != 1 || t.size(0) != B) fail("t: expected (B,) with the B of x");
  if (shape.cond_dim > 0 && (!cond.defined() || cond.dim() != 2 || cond.size(0) != B || cond.size(1) != shape.cond_dim)) {
    fail("cond: expected (B, " + std::to_string(shape.cond_dim) + ")");
  }
  if (shape.cond_dim == 0 && cond.defined()) fail("cond: this network takes no condition");
  if (packed.dim() != 1 || packed.numel() != shape.PackedSize() || packed.scalar_type() != torch::kFloat32) {
    fail("packed: expected " + std::to_string(shape.PackedSize()) + " float32 numbers for this shape, got " +
         std::to_string(packed.numel()));
  }
  if (x.requires_grad() || (cond.defined() && cond.requires_grad()) || t.requires_grad() || packed.requires_grad()) {
    fail("computes no gradient, and an input requires one");
  }
  const torch::Tensor xs = x.contiguous();
  const torch::Tensor ts = t.to(torch::kFloat32).contiguous();
  const torch::Tensor cs = cond.defined() ? cond.to(torch::kFloat32).contiguous() : cond;
  const torch::Tensor ps = packed.contiguous();
  torch::Tensor out = torch::empty({B, T, shape.state_dim}, torch::kFloat32);
  const float* xp = xs.data_ptr<float>();
  const float* tp = ts.data_ptr<float>();
  const float* cp = cs.defined() ? cs.data_ptr<float>() : nullptr;
  const float* pp = ps.data_ptr<float>();
  float* op = out.data_ptr<float>();
  const int64_t size = ps.numel(), per = T * shape.state_dim;
  at::parallel_for(0, B, 1, [&](int64_t begin, int64_t end) {
    thread_local Arena arena;
    for (int64_t b = begin; b < end; ++b) {
      Pass pass(shape, Cursor(pp, size), arena);
      pass.Run(xp + b * per, tp[b], cp ? cp + b * shape.cond_dim : nullptr, T, op + b * per);
    }
  });
  return out;
}

}  // namespace flowplan::kernels
