#pragma once

#include <torch/torch.h>

#include "models/conditioning.h"
#include "models/network.h"
#include "models/trajectory_net.h"

namespace flowplan::objectives {

/// `net` as the trajectory network an objective needs.
/// @throws flowplan::Error "objective.name: flow_matching trains a trajectory network (model.name …)".
models::TrajectoryNet& AsTrajectoryNet(models::Network& net, const char* objective);

/// The loss every objective that regresses a trajectory network shares, with
/// the conditioning handled once: under inpainting, states 0 and T−1 of the
/// input are the data's first and last states and the loss covers the T − 2
/// interior states only (the ends are overwritten at sampling time, so their
/// prediction carries no signal); under direct conditioning the data's
/// [start, goal] is the network's condition vector. Mean squared error.
/// x1, input, target: (B, T, D); time: (B,) -> scalar.
torch::Tensor TrajectoryRegressionLoss(models::TrajectoryNet& net, const torch::Tensor& x1, torch::Tensor input,
                                       const torch::Tensor& time, const torch::Tensor& target,
                                       models::Conditioning conditioning);

}  // namespace flowplan::objectives
