#pragma once

// The one interface every planner implements (the learned planners, and
// RRT-Connect): start and goal states, a scene and a seed in, plans and timing
// out. Evaluation, `flowplan plan` and the benchmarks use planners only
// through it.
//
// Shapes: B plans, T states, D state dims.

#include <torch/torch.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "collision/world.h"
#include "geometry/scene_rows.h"

namespace flowplan::planning {

/// Settings of one call that differ from the planner's: numbers by their
/// config key (e.g. "guidance.scale", "guidance.clip", "sampler.steps"), the
/// guidance schedule and (flow planner) where it guides, by name. A planner
/// rejects a key it does not take.
struct PlanSettings {
  std::map<std::string, double> values;
  std::optional<std::string> schedule;
  std::optional<std::string> guide_at;  // sampler.guide_at
  bool empty() const { return values.empty() && !schedule && !guide_at; }
};

/// One planning call: B start/goal pairs in one scene.
struct PlanRequest {
  torch::Tensor start;          // (B, D) raw states
  torch::Tensor goal;           // (B, D) raw states
  geometry::SceneRows scene;    // the obstacles; empty: free space
  uint64_t seed = 0;            // every random draw of the call derives from it
  PlanSettings settings;        // this call's settings (default: the planner's)
  collision::WorldOptions world;  // the floor and held joints, when the request sets them (checks and RRT-Connect
                                 // heed them; guidance does not)
};

struct PlanResult {
  torch::Tensor plans;  // (B, T, D) raw
  torch::Tensor found;  // (B,) bool: a plan was found (sampling planners always find one)
  /// (B,) wall time of the call that made each plan, and how many plans that
  /// call made: a learned planner makes a batch in one call; RRT-Connect times
  /// each plan on its own (call_plans 1), adding to each an equal share of
  /// what its call prepares once for all its plans (the scene's collision
  /// world). call_seconds / call_plans is the time per plan.
  std::vector<double> call_seconds;
  std::vector<int64_t> call_plans;
  /// (B,) how each plan was made, for planners with more than one way (the
  /// hybrid: "proposal 3 of 8", "proposal 1 of 1 unguided retimed", "rrt_connect"; RRT-Connect seeded by guides:
  /// "seeded", "unseeded"); empty otherwise.
  std::vector<std::string> route;
  /// (B) whether plan b was refused (its start or goal cannot be planned from or to), and why a plan was not
  /// found ("" when found); empty for planners that always find one.
  std::vector<bool> refused;
  std::vector<std::string> failure;
};

class Planner {
 public:
  virtual ~Planner() = default;

  /// Plans; does not change the planner, and may be called from several threads at once.
  /// @throws flowplan::Error on shape mismatches, bad obstacles and unknown settings.
  virtual PlanResult Plan(const PlanRequest& request) const = 0;

  virtual int64_t horizon() const = 0;    // T
  virtual int64_t state_dim() const = 0;  // D
};

/// Splits `request` into fixed chunks of `chunk` plans, planned by `threads`
/// workers; chunk c draws from StreamSeed(request.seed, c), so the result does
/// not depend on the thread count. Call with LibTorch's intra-op threads at 1.
PlanResult PlanInChunks(const Planner& planner, const PlanRequest& request, int threads, int64_t chunk = 16);

/// Checks start and goal (B, D) of a request. @throws flowplan::Error naming the argument.
void CheckEnds(const torch::Tensor& start, const torch::Tensor& goal, int64_t state_dim, const std::string& where);

}  // namespace flowplan::planning
