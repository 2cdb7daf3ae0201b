#pragma once

// The one interface every planner implements (the flow planner, and the
// baselines): start and goal states, a scene and a seed in, plans and timing
// out. Evaluation, `flowplan plan` and the benchmarks use planners only
// through it.
//
// Shapes: B plans, T states, D state dims, K obstacles, W workspace dims.

#include <torch/torch.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "guidance/guide.h"
#include "jit/script_writer.h"

namespace flowplan::planning {

/// One planning call: B start/goal pairs in one scene.
struct PlanRequest {
  torch::Tensor start;      // (B, D) raw states
  torch::Tensor goal;       // (B, D) raw states
  torch::Tensor obstacles;  // (K, W+1) rows [centre, radius], world units; undefined or K = 0: free space
  uint64_t seed = 0;        // every random draw of the call derives from it
  std::optional<guidance::GuidanceConfig> guidance;  // this call's guidance settings (default: the planner's)
};

struct PlanResult {
  torch::Tensor plans;  // (B, T, D) raw
  torch::Tensor found;  // (B,) bool: a plan was found (sampling planners always find one)
  std::vector<double> seconds;  // (B,) wall time of the call that made each plan, shared by its plans
};

class Planner {
 public:
  virtual ~Planner() = default;

  /// Plans; does not change the planner, and may be called from several threads at once.
  /// @throws flowplan::Error on shape mismatches and bad obstacles.
  virtual PlanResult Plan(const PlanRequest& request) const = 0;

  virtual int64_t horizon() const = 0;    // T
  virtual int64_t state_dim() const = 0;  // D

  /// Writes the planner as TorchScript into `module` (methods plan, sample and
  /// the rest of docs/export.md).
  /// @throws flowplan::Error if this kind of planner cannot be exported.
  virtual void WriteScript(jit::ScriptModule& module) const;
};

/// Splits `request` into fixed chunks of `chunk` plans, planned by `threads`
/// workers; chunk c draws from StreamSeed(request.seed, c), so the result does
/// not depend on the thread count. Call with LibTorch's intra-op threads at 1.
PlanResult PlanInChunks(const Planner& planner, const PlanRequest& request, int threads, int64_t chunk = 16);

/// Checks start and goal (B, D) of a request. @throws flowplan::Error naming the argument.
void CheckEnds(const torch::Tensor& start, const torch::Tensor& goal, int64_t state_dim, const std::string& where);

}  // namespace flowplan::planning
