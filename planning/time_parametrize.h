#pragma once

// Timing a joint-space path as a plan: T states along a polyline, rest to
// rest over the plan's (T − 1)·dt, within the joints' speed limits where the
// path allows it. RRT-Connect times its paths with it, and the hybrid planner
// re-times a proposal that is only too fast.
//
// The path is measured in time at full speed: a segment takes
// σ = max_j |Δq_j| / v_j (v_j the joint's speed limit; with no limits, the
// Euclidean length). The profile σ(t) is the smooth s(τ) = 3τ² − 2τ³ of the
// whole when its peak speed (1.5 σ_total / duration) stays within
// `speed_share` of the limits; else a trapezoid (constant acceleration, a
// cruise at the speed that fits, constant deceleration) with ramps as long as
// the limits allow. Every state lies on the polyline; the straight motion
// between two consecutive states can cut a corner between them. With
// `snap_corners`, every corner (a vertex where the path turns by more than
// 0.2 rad) falls on a state instead, when there are no more corners than
// states, so that no motion between states cuts one; the states between
// corners keep the profile's timing, warped to reach each corner on a state
// (corners a state or two apart make the speed uneven there).
//
// Shapes: M polyline points, J joints, T states.

#include <torch/torch.h>

#include <cstdint>
#include <utility>
#include <vector>

namespace flowplan::planning {

struct TimedPath {
  std::vector<double> q;    // (T, J) positions
  std::vector<double> v;    // (T, J) velocities of the timing
  double peak_ratio = 0.0;  // the largest |Δq_j| / (dt v_j) between consecutive states (0 without limits)
  bool corners_on_states = false;  // every corner of the polyline (a turn of more than 0.2 rad) is a state
};

/// Times the polyline `points` (M × J, row-major, M >= 1) as T >= 2 states dt apart. `velocity_limit` (J, or
/// empty for none) and `speed_share` (0, 1] set the speed the profile aims within.
/// @throws flowplan::Error for bad sizes.
TimedPath TimePath(const std::vector<double>& points, int64_t J, int64_t T, double dt,
                   const std::vector<double>& velocity_limit, bool snap_corners = false, double speed_share = 0.95);

/// TimePath of a polyline (M, J) float64 tensor: (T, J) positions and (T, J) velocities, float64.
std::pair<torch::Tensor, torch::Tensor> TimeAlongPath(const torch::Tensor& points, int64_t T, double dt,
                                                      const std::vector<double>& velocity_limit = {});

/// TimeAlongPath as a plan's states: (T, D) float64, the positions (D = J) or the positions then the velocities
/// (D = 2J). @throws flowplan::Error for another D.
torch::Tensor TimedStates(const torch::Tensor& points, int64_t T, double dt, int64_t D,
                          const std::vector<double>& velocity_limit = {});

/// TimedPath's states as a plan (T, D) float64, D = J or 2J.
torch::Tensor StatesOf(const TimedPath& path, int64_t J, int64_t T, int64_t D);

}  // namespace flowplan::planning
