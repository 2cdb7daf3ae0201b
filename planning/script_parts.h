#pragma once

// Pieces of TorchScript that every planner of a trajectory network writes the
// same way (flow matching, DDPM): its network methods, the planning support
// (normalizer, robot, guide, inpainting) and the checked start of plan().

#include <cstdint>
#include <string>
#include <vector>

#include "jit/script_writer.h"
#include "models/conditioning.h"
#include "models/normalizer.h"
#include "models/trajectory_net.h"

namespace flowplan::planning {

struct GuidanceSetup;

/// Adds `network(self, x, t, cond)` (the network, unchecked) and
/// `<checked>(self, x, t, cond)`, which checks x (B, T, D), t (B,) and cond
/// against `conditioning` and calls it.
void WriteTrajectoryNetwork(jit::ScriptModule& module, const models::TrajectoryNet& net,
                            models::Conditioning conditioning, int64_t horizon, const std::string& checked);

/// Adds the normalizer's, the robot's and the guide's methods and
/// `inpaint(self, x, start, goal)`.
/// @throws flowplan::Error if `guidance` has no robot.
void WritePlanningSupport(jit::ScriptModule& module, const models::MinMaxNormalizer& normalizer,
                          const GuidanceSetup& guidance);

/// The first lines of `plan(self, start, goal, noise, renoise, obstacles, scale)`:
/// checks start, goal (B, D) and noise (B, T, D) and the obstacles (K, W + 1),
/// and sets `guidance_scale`, `guided` (the float32 obstacles, or None when
/// unguided), `start`, `goal` (float32) and their normalized `s`, `g`.
std::string PlanPreamble(int64_t state_dim, int64_t horizon, int64_t workspace_dim);

/// Registers the attributes noise_shape and renoise_shape: the shapes after B
/// of plan()'s noise and renoise (renoise empty: None), which a caller draws in
/// this order from a standard normal (as every in-process planner's Plan()).
void WriteNoiseShapes(jit::ScriptModule& module, const std::vector<int64_t>& noise,
                      const std::vector<int64_t>& renoise);

/// `sample(self, start, goal, num_samples, obstacles, scale)`, drawing plan()'s
/// noise and renoise of the shapes after num_samples given as TorchScript
/// lists (e.g. "[64, 14]"; renoise empty: None) from the global generator.
std::string SampleMethod(const std::string& noise_shape, const std::string& renoise_shape);

}  // namespace flowplan::planning
