#pragma once

#include <torch/torch.h>

#include <memory>
#include <string>

#include "jit/script_writer.h"

namespace flowplan::models {

/// A network that predicts the flow velocity of a whole trajectory. It knows
/// nothing of robots, files or samplers: states are normalized vectors, time is
/// the flow time, and an optional global condition vector (for direct
/// conditioning) is just C numbers per sample.
class VelocityNet : public torch::nn::Module {
 public:
  /// @param x     (B, T, D) normalized noisy trajectories
  /// @param t     (B,) flow time in [0, 1] (0 noise, 1 data)
  /// @param cond  (B, C) global condition, or an undefined tensor when C = 0
  /// @returns     (B, T, D) predicted velocity
  virtual torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& t,
                                const torch::Tensor& cond) = 0;

  /// @throws flowplan::Error if the network cannot take horizon `horizon`.
  virtual void CheckHorizon(int64_t horizon) const = 0;

  /// Mirrors Forward() as TorchScript. Reads the variables `x` (B, T, D), `t` (B,)
  /// and `cond` (Optional[Tensor], (B, C)) and returns the name of the variable
  /// holding the velocity (B, T, D).
  virtual std::string WriteScript(jit::ScriptWriter& writer) const = 0;

  virtual int64_t state_dim() const = 0;
  virtual int64_t cond_dim() const = 0;
};

using VelocityNetPtr = std::shared_ptr<VelocityNet>;

/// Checks x (B, T, D), t (B,) and cond (B, C) against a network's dimensions.
/// @throws flowplan::Error "expected (B, T, 4), got (…)" style messages.
void CheckVelocityInputs(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond,
                         int64_t state_dim, int64_t cond_dim);

/// Throws, naming `what` (e.g. "flow.split_prob > 0 trains on"), if `net` cannot
/// take the halves (T/2 states) of a horizon-T trajectory.
void CheckHalfHorizon(const VelocityNet& net, int64_t horizon, const std::string& what);

/// "(2, 64, 4)"
std::string ShapeString(const torch::Tensor& tensor);

}  // namespace flowplan::models
