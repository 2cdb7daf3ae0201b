#include "objectives/trajectory_loss.h"

#include "core/error.h"

namespace flowplan::objectives {

models::TrajectoryNet& AsTrajectoryNet(models::Network& net, const char* objective) {
  auto* trajectory = dynamic_cast<models::TrajectoryNet*>(&net);
  if (trajectory == nullptr) {
    throw Error(std::string("objective.name: ") + objective +
                " trains a trajectory network (model.name unet1d or transformer)");
  }
  return *trajectory;
}

torch::Tensor TrajectoryRegressionLoss(models::TrajectoryNet& net, const torch::Tensor& x1, torch::Tensor input,
                                       const torch::Tensor& time, const torch::Tensor& target,
                                       models::Conditioning conditioning) {
  const int64_t T = x1.size(1);
  const torch::Tensor start = x1.select(1, 0), goal = x1.select(1, T - 1);
  if (conditioning == models::Conditioning::kInpaint) {
    input = models::Inpaint(input, start, goal);
    const torch::Tensor output = net.Forward(input, time, torch::Tensor());
    return torch::mse_loss(output.slice(1, 1, T - 1), target.slice(1, 1, T - 1));
  }
  const torch::Tensor output = net.Forward(input, time, models::ConditionVector(conditioning, start, goal));
  return torch::mse_loss(output, target);
}

}  // namespace flowplan::objectives
