#include "guidance/smoothness_cost.h"

#include <cmath>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::guidance {

SmoothnessCost::SmoothnessCost(int64_t num_joints, double dt, double sigma) : J_(num_joints), dt_(dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) throw Error("smoothness cost: dt: expected a positive value");
  if (!(sigma > 0.0) || !std::isfinite(sigma)) throw Error("guidance.smoothness_sigma: expected a positive value");
  const double s2 = sigma * sigma;
  a_ = 12.0 / (dt * dt * dt * s2);
  b_ = -6.0 / (dt * dt * s2);
  c_ = 4.0 / (dt * s2);
}

void SmoothnessCost::Check(const torch::Tensor& x) const {
  if (!x.defined() || x.dim() != 3 || x.size(2) < 2 * J_ || x.size(1) < 2) {
    throw Error("smoothness cost: x: expected (B, T >= 2, D >= " + std::to_string(2 * J_) +
                ") holding positions then velocities, got " +
                (x.defined() ? ShapeText(x.sizes().vec()) : std::string("(undefined)")));
  }
}

torch::Tensor SmoothnessCost::Value(const torch::Tensor& x, const torch::Tensor&) const {
  Check(x);
  const int64_t T = x.size(1);
  const torch::Tensor q = x.slice(2, 0, J_), v = x.slice(2, J_, 2 * J_);
  const torch::Tensor e_q = q.slice(1, 1, T) - q.slice(1, 0, T - 1) - dt_ * v.slice(1, 0, T - 1);  // (B, T-1, J)
  const torch::Tensor e_v = v.slice(1, 1, T) - v.slice(1, 0, T - 1);
  return (a_ * e_q * e_q + 2.0 * b_ * e_q * e_v + c_ * e_v * e_v).sum({1, 2});
}

CostAndGradient SmoothnessCost::ValueAndGradient(const torch::Tensor& x, const torch::Tensor&) const {
  Check(x);
  const int64_t B = x.size(0), T = x.size(1), D = x.size(2);
  const torch::Tensor q = x.slice(2, 0, J_), v = x.slice(2, J_, 2 * J_);
  const torch::Tensor e_q = q.slice(1, 1, T) - q.slice(1, 0, T - 1) - dt_ * v.slice(1, 0, T - 1);
  const torch::Tensor e_v = v.slice(1, 1, T) - v.slice(1, 0, T - 1);
  const torch::Tensor value = (a_ * e_q * e_q + 2.0 * b_ * e_q * e_v + c_ * e_v * e_v).sum({1, 2});
  // ∂C/∂e_q = 2(a e_q + b e_v), ∂C/∂e_v = 2(b e_q + c e_v); e_q_i depends on q_{i+1} (+1), q_i (−1),
  // v_i (−dt); e_v_i on v_{i+1} (+1), v_i (−1).
  const torch::Tensor g_q = 2.0 * (a_ * e_q + b_ * e_v);  // (B, T-1, J)
  const torch::Tensor g_v = 2.0 * (b_ * e_q + c_ * e_v);
  const torch::Tensor zero = torch::zeros({B, 1, J_}, x.options());
  const torch::Tensor grad_q = torch::cat({zero, g_q}, 1) - torch::cat({g_q, zero}, 1);
  const torch::Tensor grad_v = torch::cat({zero, g_v}, 1) - torch::cat({dt_ * g_q + g_v, zero}, 1);
  std::vector<torch::Tensor> parts = {grad_q, grad_v};
  if (D > 2 * J_) parts.push_back(torch::zeros({B, T, D - 2 * J_}, x.options()));
  return {value, torch::cat(parts, 2)};
}

void SmoothnessCost::WriteScript(jit::ScriptModule& module, const std::string& name) const {
  const std::string J = std::to_string(J_), J2 = std::to_string(2 * J_);
  const std::string a = jit::ScriptFloat(a_), b = jit::ScriptFloat(b_), c = jit::ScriptFloat(c_);
  const std::string dt = jit::ScriptFloat(dt_);
  module.Define("def " + name + R"PY((self, x: Tensor, obstacles: Tensor) -> Tuple[Tensor, Tensor]:
    B = x.size(0)
    T = x.size(1)
    q = x[:, :, 0:)PY" + J + R"PY(]
    v = x[:, :, )PY" + J + ":" + J2 + R"PY(]
    e_q = q[:, 1:T] - q[:, 0:T - 1] - )PY" + dt + R"PY( * v[:, 0:T - 1]
    e_v = v[:, 1:T] - v[:, 0:T - 1]
    value = ()PY" + a + " * e_q * e_q + 2.0 * " + b + " * e_q * e_v + " + c + R"PY( * e_v * e_v).sum([1, 2])
    g_q = 2.0 * ()PY" + a + " * e_q + " + b + R"PY( * e_v)
    g_v = 2.0 * ()PY" + b + " * e_q + " + c + R"PY( * e_v)
    zero = torch.zeros([B, 1, )PY" + J + R"PY(], dtype=x.dtype, device=x.device)
    grad_q = torch.cat([zero, g_q], 1) - torch.cat([g_q, zero], 1)
    grad_v = torch.cat([zero, g_v], 1) - torch.cat([)PY" + dt + R"PY( * g_q + g_v, zero], 1)
    gradient = torch.cat([grad_q, grad_v], 2)
    if x.size(2) > )PY" + J2 + R"PY(:
        gradient = torch.cat([gradient, torch.zeros([B, T, x.size(2) - )PY" + J2 + R"PY(], dtype=x.dtype, device=x.device)], 2)
    return value, gradient
)PY");
}

}  // namespace flowplan::guidance
