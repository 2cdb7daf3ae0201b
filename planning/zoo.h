#pragma once

// Planners of trained networks, made from what a checkpoint holds: the one
// place that knows which planner samples which objective.

#include <memory>

#include "guidance/guide.h"
#include "models/normalizer.h"
#include "models/network.h"
#include "objectives/objective.h"
#include "planning/flow_planner.h"
#include "planning/planner.h"

namespace flowplan::planning {

/// What a learned planner is made of.
struct LearnedPlannerParts {
  models::NetworkPtr net;                 // trained weights (EMA)
  models::MinMaxNormalizer normalizer;
  objectives::ObjectiveConfig objective;  // what trained the network, with its conditioning
  int64_t horizon = 0;                    // T
  SamplerConfig sampler;
  GuidanceSetup guidance;
};

/// The planner that samples `parts.objective` (flow matching: FlowPlanner;
/// DDPM: DdpmPlanner; VAE: LatentPlanner).
/// @throws flowplan::Error if the network does not fit the objective or the horizon.
std::unique_ptr<Planner> MakeLearnedPlanner(const LearnedPlannerParts& parts);

}  // namespace flowplan::planning
