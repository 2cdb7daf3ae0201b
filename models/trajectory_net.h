#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <memory>
#include <string>

#include "jit/script_writer.h"
#include "models/kernels.h"
#include "models/network.h"

namespace flowplan::models {

/// A network that maps a whole noisy trajectory to a trajectory-shaped output:
/// the flow velocity under flow matching, the noise under DDPM. It knows
/// nothing of robots, files, objectives or samplers: states are normalized
/// vectors, time is whatever the objective uses (flow time, diffusion step),
/// and an optional global condition vector (for direct conditioning) is just
/// C numbers per sample.
class TrajectoryNet : public Network {
 public:
  /// @param x     (B, T, D) normalized noisy trajectories
  /// @param t     (B,) the objective's time (flow time in [0, 1]; diffusion step)
  /// @param cond  (B, C) global condition, or an undefined tensor when C = 0
  /// @returns     (B, T, D) the objective's target (velocity; noise)
  virtual torch::Tensor Forward(const torch::Tensor& x, const torch::Tensor& t,
                                const torch::Tensor& cond) = 0;

  /// @throws flowplan::Error if the network cannot take horizon `horizon`.
  virtual void CheckHorizon(int64_t horizon) const = 0;

  /// Mirrors Forward() as TorchScript. Reads the variables `x` (B, T, D), `t` (B,)
  /// and `cond` (Optional[Tensor], (B, C)) and returns the name of the variable
  /// holding the velocity (B, T, D).
  virtual std::string WriteScript(jit::ScriptWriter& writer) const = 0;

  /// Writes, before WriteScript's lines, an early return through a native
  /// operator (kernels/) for the inputs that operator takes, reading the same
  /// variables; a network without one writes nothing. The other inputs fall
  /// through to WriteScript's code.
  virtual void WriteNativeKernel(jit::ScriptWriter& writer) const {}

  virtual int64_t state_dim() const = 0;
  virtual int64_t cond_dim() const = 0;
};

using TrajectoryNetPtr = std::shared_ptr<TrajectoryNet>;

/// The network as a TorchScript module with one method,
///   forward(x (B, T, D), t (B,), cond: Optional[Tensor] (B, C)) -> (B, T, D),
/// its parameters copied into buffers (what planners and exported files run).
torch::jit::Module ScriptNetwork(const TrajectoryNet& net, Kernels kernels);

/// The inverse of ScriptNetwork: loads into `net` (made from the same model
/// config) the weights of `scripted`, a module ScriptNetwork wrote of a network
/// like it, with either kernels. ScriptNetwork only rearranges weights
/// (reshapes, concatenations, transposes), so writing `net` with every element
/// set to its own index shows where each element went; an element that
/// ScriptNetwork computes from several cannot be read back, and is an error.
/// @throws flowplan::Error naming `where` if a weight is missing, of another
///   shape, not a rearrangement, or never written.
void ReadScriptedWeights(TrajectoryNet& net, const torch::jit::Module& scripted, const std::string& where);

/// Checks x (B, T, D), t (B,) and cond (B, C) against a network's dimensions.
/// @throws flowplan::Error "expected (B, T, 4), got (…)" style messages.
void CheckTrajectoryInputs(const torch::Tensor& x, const torch::Tensor& t, const torch::Tensor& cond,
                         int64_t state_dim, int64_t cond_dim);

/// Throws, naming `what` (e.g. "objective.split_prob > 0 trains on"), if `net` cannot
/// take the halves (T/2 states) of a horizon-T trajectory.
void CheckHalfHorizon(const TrajectoryNet& net, int64_t horizon, const std::string& what);

/// "(2, 64, 4)"
std::string ShapeString(const torch::Tensor& tensor);

}  // namespace flowplan::models
