#pragma once

// The samplers of learned planners, one per file (flow_sampler.cc, …): each
// builds its TorchScript module (planning/*_sampler.py) from the parts.
// AssemblePlanner (assemble.cc) registers them, one line each.

#include <torch/script.h>

#include "planning/assemble.h"

namespace flowplan::planning {

/// What every sampler is built from: the parts, and modules already built for them.
struct SamplerContext {
  const PlannerParts& parts;
  torch::jit::Module normalizer;  // Normalizer
  torch::jit::Module robot;       // Arm or Point
  torch::jit::Module guide;       // Guide
};

torch::jit::Module BuildFlowSampler(const SamplerContext& context);
torch::jit::Module BuildDdpmSampler(const SamplerContext& context);
torch::jit::Module BuildLatentSampler(const SamplerContext& context);

}  // namespace flowplan::planning
