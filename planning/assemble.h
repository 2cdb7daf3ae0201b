#pragma once

// The one place that assembles a learned planner from its parts: which
// sampler samples which objective, the robot, the guide and the settings.

#include <memory>
#include <string>

#include "guidance/guide.h"
#include "kinematics/trajectory_info.h"
#include "models/network.h"
#include "models/normalizer.h"
#include "objectives/objective.h"
#include "planning/learned_planner.h"
#include "planning/sampler_config.h"

namespace flowplan::planning {

/// What a learned planner is made of.
struct PlannerParts {
  models::NetworkPtr net;                 // trained weights (EMA); copied into the planner
  models::MinMaxNormalizer normalizer;
  objectives::ObjectiveConfig objective;  // what trained the network, with its conditioning
  SamplerConfig sampler;
  guidance::GuidanceConfig guidance;
  kinematics::TrajectoryInfo trajectory;  // what it plans: horizon, states, robot, dt
  std::string config_yaml;                // the run's resolved config, kept with the planner
};

/// The planner that samples `parts.objective` (flow matching: FlowSampler;
/// DDPM: DdpmSampler; VAE: LatentSampler), on the network's device.
/// @throws flowplan::Error if the network does not fit the objective, the
///   horizon or the states (D = 2J: positions, then velocities), or naming
///   guidance.user_cost if that file does not compile.
std::unique_ptr<LearnedPlanner> AssemblePlanner(const PlannerParts& parts);

}  // namespace flowplan::planning
