#include "kernels/arm_guidance_kernel.h"

#include <cmath>
#include <stdexcept>

namespace flowplan::kernels {
namespace {

void Check(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("arm_guidance: " + what);
}

/// max(v, 0) with a NaN kept, as torch.relu.
template <class S>
S Relu(S v) {
  return v < S(0) ? S(0) : v;
}

/// One plan's term gradients: `raw` (T, D) the plan's raw states, `out` (T, D) the term's [dC/dq, dC/dqd],
/// zeroed by the caller, each written out as its script writes it.
template <class S>
struct PlanTerms {
  int64_t T, J, D;
  double dt_seconds;  // the script's dt, from which its coefficients are taken in double
  S dt;               // dt as the script's products with tensors round it

  /// guidance/smoothness.py: e_q = q_{i+1} - q_i - dt qd_i, e_v = qd_{i+1} - qd_i.
  void Smoothness(const S* raw, double sigma, S* out) const {
    const double s2 = sigma * sigma, dtd = dt_seconds;
    const S a = static_cast<S>(12.0 / (dtd * dtd * dtd * s2)), b = static_cast<S>(-6.0 / (dtd * dtd * s2)),
            c = static_cast<S>(4.0 / (dtd * s2));
    for (int64_t j = 0; j < J; ++j) {
      S g_q_before = 0, g_v_before = 0;  // the terms of the segment ending at state t
      for (int64_t t = 0; t < T; ++t) {
        S g_q = 0, g_v = 0, from_here_q = 0, from_here_v = 0;
        const bool segment = t + 1 < T;
        if (segment) {
          const S* now = raw + t * D;
          const S* next = raw + (t + 1) * D;
          const S e_q = next[j] - now[j] - dt * now[J + j];
          const S e_v = next[J + j] - now[J + j];
          g_q = S(2) * (a * e_q + b * e_v);
          g_v = S(2) * (b * e_q + c * e_v);
          from_here_q = g_q;
          from_here_v = dt * g_q + g_v;
        }
        out[t * D + j] = g_q_before - from_here_q;
        out[t * D + J + j] = g_v_before - from_here_v;
        g_q_before = g_q;
        g_v_before = g_v;
      }
    }
  }

  /// guidance/joint_limit.py: relu(lower + m - q) + relu(q - upper + m); the gradient's sign per joint.
  void JointLimit(const S* raw, const S* lower, const S* upper, S margin, S* out) const {
    for (int64_t t = 0; t < T; ++t) {
      for (int64_t j = 0; j < J; ++j) {
        const S q = raw[t * D + j];
        const S below = Relu(lower[j] + margin - q), above = Relu(q - upper[j] + margin);
        out[t * D + j] = static_cast<S>(above > S(0)) - static_cast<S>(below > S(0));
      }
    }
  }

  /// guidance/joint_speed.py: relu(|q_{i+1} - q_i| / (dt v) - rho)^2.
  void JointSpeed(const S* raw, const S* step_limit, S ratio, S* out) const {
    for (int64_t j = 0; j < J; ++j) {
      S g_before = 0;
      for (int64_t t = 0; t < T; ++t) {
        S g = 0;
        if (t + 1 < T) {
          const S step = raw[(t + 1) * D + j] - raw[t * D + j];
          const S excess = Relu(std::abs(step) / step_limit[j] - ratio);
          const S sign = static_cast<S>((S(0) < step) - (step < S(0)));
          g = S(2) * excess * sign / step_limit[j];
        }
        out[t * D + j] = g_before - g;
        g_before = g;
      }
    }
  }
};

/// guidance/cost_chain.py: total += weight * term, each state's term capped at norm `clip` (0: no cap).
template <class S>
void Accumulate(const std::vector<S>& term, double weight, double clip, int64_t states, int64_t D,
                std::vector<S>& total) {
  const S w = static_cast<S>(weight), cap = static_cast<S>(clip);
  for (int64_t i = 0; i < states; ++i) {
    const S* g = term.data() + i * D;
    S* sum = total.data() + i * D;
    S divisor = 1;
    const bool capped = !(clip <= 0);  // as clip_states: a NaN cap caps
    if (capped) {
      S squares = 0;
      for (int64_t d = 0; d < D; ++d) squares += g[d] * g[d];
      const S norm = std::sqrt(squares);
      divisor = (norm < cap ? cap : norm) / cap;
    }
    for (int64_t d = 0; d < D; ++d) sum[d] = sum[d] + w * (capped ? g[d] / divisor : g[d]);
  }
}

/// A 1-D float32 or float64 tensor's values, each rounded to S as .to(dtype) rounds it.
template <class S>
std::vector<S> Values(const torch::Tensor& t) {
  const torch::Tensor c = t.contiguous();
  std::vector<S> out(static_cast<size_t>(c.numel()));
  if (c.scalar_type() == torch::kFloat32) {
    std::copy_n(c.data_ptr<float>(), out.size(), out.begin());
  } else {
    const torch::Tensor d = c.scalar_type() == torch::kFloat64 ? c : c.to(torch::kFloat64);
    for (size_t i = 0; i < out.size(); ++i) out[i] = static_cast<S>(d.data_ptr<double>()[i]);
  }
  return out;
}

/// `factor` (hi - lo) in the normalizer's dtype R (models/normalizer.py), then rounded to S.
template <class S, class R>
std::vector<S> Scaled(const torch::Tensor& lo, const torch::Tensor& hi, R factor) {
  const std::vector<R> l = Values<R>(lo), h = Values<R>(hi);
  std::vector<S> out(l.size());
  for (size_t d = 0; d < l.size(); ++d) out[d] = static_cast<S>(factor * (h[d] - l[d]));
  return out;
}

template <class S>
std::vector<S> Scaled(const torch::Tensor& lo, const torch::Tensor& hi, double factor) {
  return lo.scalar_type() == torch::kFloat64 ? Scaled<S, double>(lo, hi, factor)
                                             : Scaled<S, float>(lo, hi, static_cast<float>(factor));
}

template <class S>
torch::Tensor Run(const torch::Tensor& x_in, const torch::Tensor& lo, const torch::Tensor& hi, const ArmTables& arm,
                  const ArmLimits& limits, double dt, const std::vector<std::string>& kinds,
                  const std::vector<torch::Tensor>& rows, const GuidanceTerms& terms) {
  const torch::Tensor x = x_in.contiguous();
  const int64_t B = x.size(0), T = x.size(1), D = x.size(2), J = D / 2, states = B * T;
  const auto options = x.options();
  // guidance/guide.py through models/normalizer.py: raw = (x + 1) 0.5 (hi - lo) + lo, the gradient times
  // 0.5 (hi - lo), both ranges taken in the normalizer's dtype.
  const std::vector<S> range = Scaled<S>(lo, hi, 1.0), per_normalized = Scaled<S>(lo, hi, 0.5), low = Values<S>(lo);
  const S* xs = x.data_ptr<S>();
  torch::Tensor raw_tensor = torch::empty({B, T, D}, options);
  S* raw = raw_tensor.data_ptr<S>();
  for (int64_t i = 0; i < states * D; ++i) raw[i] = (xs[i] + S(1)) * S(0.5) * range[i % D] + low[i % D];

  std::vector<S> total(static_cast<size_t>(states * D), S(0)), term(static_cast<size_t>(states * D));
  const PlanTerms<S> plan{T, J, D, dt, static_cast<S>(dt)};
  auto each_plan = [&](auto&& fill) {
    std::fill(term.begin(), term.end(), S(0));
    for (int64_t b = 0; b < B; ++b) fill(raw + b * T * D, term.data() + b * T * D);
  };
  // The chain's order: its last term first.
  if (terms.joint_speed_weight != 0.0) {
    std::vector<S> step_limit = Values<S>(limits.velocity_limit);  // the largest |q_{i+1} - q_i|
    for (S& v : step_limit) v = v * static_cast<S>(dt);
    each_plan([&](const S* r, S* out) {
      plan.JointSpeed(r, step_limit.data(), static_cast<S>(terms.joint_speed_ratio), out);
    });
    Accumulate(term, terms.joint_speed_weight, terms.clip, states, D, total);
  }
  if (terms.joint_limit_weight != 0.0) {
    const std::vector<S> lower = Values<S>(limits.lower), upper = Values<S>(limits.upper);
    each_plan([&](const S* r, S* out) {
      plan.JointLimit(r, lower.data(), upper.data(), static_cast<S>(terms.joint_limit_margin), out);
    });
    Accumulate(term, terms.joint_limit_weight, terms.clip, states, D, total);
  }
  if (terms.smoothness_weight != 0.0) {
    each_plan([&](const S* r, S* out) { plan.Smoothness(r, terms.smoothness_sigma, out); });
    Accumulate(term, terms.smoothness_weight, terms.clip, states, D, total);
  }
  if (terms.collision_weight != 0.0) {
    std::vector<S> reaches = Values<S>(limits.sphere_radii);
    for (S& r : reaches) r = r + static_cast<S>(terms.margin);
    const torch::Tensor reach = torch::from_blob(reaches.data(), {static_cast<int64_t>(reaches.size())}, options);
    const torch::Tensor q = raw_tensor.view({states, D}).slice(1, 0, J).contiguous();
    torch::Tensor grad_q;
    try {
      grad_q = std::get<1>(ArmCollision(q, arm, reach, kinds, rows, true)).contiguous();
    } catch (const std::runtime_error& e) {  // "arm_collision: ..." named as this operator's
      const std::string what = e.what();
      throw std::runtime_error("arm_guidance: " + what.substr(what.find(": ") == std::string::npos ? 0 : what.find(": ") + 2));
    }
    const S* g = grad_q.data_ptr<S>();
    std::fill(term.begin(), term.end(), S(0));
    for (int64_t i = 0; i < states; ++i) {
      for (int64_t j = 0; j < J; ++j) term[i * D + j] = g[i * J + j];
    }
    Accumulate(term, terms.collision_weight, terms.clip, states, D, total);
  }
  torch::Tensor gradient = torch::empty({B, T, D}, options);
  S* out = gradient.data_ptr<S>();
  for (int64_t i = 0; i < states * D; ++i) out[i] = total[i] * per_normalized[i % D];
  return gradient;
}

}  // namespace

const std::vector<std::string>& ArmGuidanceWeightKeys() {
  static const std::vector<std::string> keys = {"guidance.collision_weight", "guidance.smoothness_weight",
                                                "guidance.joint_limit_weight", "guidance.joint_speed_weight"};
  return keys;
}

torch::Tensor ArmGuidance(const torch::Tensor& x, const torch::Tensor& lo, const torch::Tensor& hi,
                          const ArmTables& arm, const ArmLimits& limits, double dt,
                          const std::vector<std::string>& kinds, const std::vector<torch::Tensor>& rows,
                          const GuidanceTerms& terms) {
  Check(x.dim() == 3, "expected x (B, T, D)");
  const auto dtype = x.scalar_type();
  Check(dtype == torch::kFloat32 || dtype == torch::kFloat64, "expected float32 or float64 x");
  Check(x.device().is_cpu() && lo.device().is_cpu() && hi.device().is_cpu() && limits.sphere_radii.device().is_cpu() &&
            limits.lower.device().is_cpu() && limits.upper.device().is_cpu() && limits.velocity_limit.device().is_cpu(),
        "expected tensors on the CPU");
  Check(!x.requires_grad() && !lo.requires_grad() && !hi.requires_grad(), "no autograd (the scripts have it)");
  const int64_t D = x.size(2), J = arm.ancestors.dim() == 2 ? arm.ancestors.size(0) : -1;
  Check(D == 2 * J, "expected D = 2 J = " + std::to_string(2 * J) + " (positions and velocities), got " +
                        std::to_string(D));
  Check(lo.dim() == 1 && lo.size(0) == D && hi.sizes() == lo.sizes(),
        "expected the normalizer's lo and hi (" + std::to_string(D) + ")");
  Check(lo.scalar_type() == hi.scalar_type() && lo.is_floating_point(), "expected lo and hi of one floating dtype");
  for (const torch::Tensor* t : {&limits.lower, &limits.upper, &limits.velocity_limit}) {
    Check(t->dim() == 1 && t->size(0) == J, "expected lower, upper and velocity_limit (" + std::to_string(J) + ")");
  }
  Check(dt > 0, "expected a positive dt");
  Check(terms.smoothness_weight == 0.0 || terms.smoothness_sigma > 0, "expected a positive guidance.smoothness_sigma");
  if (dtype == torch::kFloat32) return Run<float>(x, lo, hi, arm, limits, dt, kinds, rows, terms);
  return Run<double>(x, lo, hi, arm, limits, dt, kinds, rows, terms);
}

}  // namespace flowplan::kernels
