#pragma once

#include <torch/torch.h>

#include <memory>

namespace flowplan::models {

/// Every network of the zoo: trained by an objective (objectives/), saved in
/// checkpoints, averaged by the EMA. Networks know nothing of robots, files,
/// objectives or samplers; each kind has its own interface below this one
/// (TrajectoryNet, StateVae).
class Network : public torch::nn::Module {
 public:
  ~Network() override = default;
};

using NetworkPtr = std::shared_ptr<Network>;

}  // namespace flowplan::models
