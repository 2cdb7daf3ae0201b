#include "objectives/ddpm.h"

#include "objectives/trajectory_loss.h"

namespace flowplan::objectives {

ObjectiveBatch DdpmObjective::Draw(const torch::Tensor& x1, at::Generator& generator) const {
  ObjectiveBatch batch;
  batch.x1 = x1;
  batch.noise = torch::randn(x1.sizes(), generator, x1.options());
  batch.time = torch::randint(schedule_.steps, {x1.size(0)}, generator, torch::kInt64).to(x1.options());
  return batch;
}

torch::Tensor DdpmObjective::Loss(models::Network& net, const ObjectiveBatch& batch,
                                  models::Conditioning conditioning) const {
  const torch::Tensor alpha_bar =
      schedule_.alpha_bars.to(batch.x1.options()).index_select(0, batch.time.to(torch::kInt64)).view({-1, 1, 1});
  const torch::Tensor noisy = alpha_bar.sqrt() * batch.x1 + (1.0 - alpha_bar).sqrt() * batch.noise;
  return TrajectoryRegressionLoss(AsTrajectoryNet(net, "ddpm"), batch.x1, noisy, batch.time, batch.noise,
                                  conditioning);
}

}  // namespace flowplan::objectives
