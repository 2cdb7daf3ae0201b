#pragma once

// Timing a joint-space path as a plan: T states along a polyline, with the
// smooth rest-to-rest profile s(τ) = 3τ² − 2τ³ over the plan's (T − 1)·dt.
// RRT-Connect times its paths with it, and the hybrid planner re-times a
// proposal that is only too fast.
//
// Shapes: M polyline points, J joints, T states.

#include <torch/torch.h>

#include <cstdint>
#include <utility>

namespace flowplan::planning {

/// T states along the joint-space polyline `points` (M, J) float64, M >= 1, at arc length (Euclidean in joint
/// space) s(τ)·L for τ = i / (T − 1), timed over (T − 1)·dt: (T, J) positions and (T, J) velocities, float64.
/// The first and last states are the polyline's ends and every state lies on the polyline; the straight motion
/// between two consecutive states cuts the corner of any vertex between them. The largest speed along the path is
/// 1.5·L / ((T − 1)·dt).
std::pair<torch::Tensor, torch::Tensor> TimeAlongPath(const torch::Tensor& points, int64_t T, double dt);

/// TimeAlongPath as a plan's states: (T, D) float64, the positions (D = J) or the positions then the velocities
/// (D = 2J). @throws flowplan::Error for another D.
torch::Tensor TimedStates(const torch::Tensor& points, int64_t T, double dt, int64_t D);

}  // namespace flowplan::planning
