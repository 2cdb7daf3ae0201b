#include "objectives/flow_matching.h"

#include "objectives/trajectory_loss.h"

namespace flowplan::objectives {

torch::Tensor InterpolateOt(const torch::Tensor& x0, const torch::Tensor& x1, const torch::Tensor& t) {
  const torch::Tensor tb = t.view({-1, 1, 1});
  return tb * x1 + (1.0 - tb) * x0;
}

ObjectiveBatch FlowMatchingObjective::Draw(const torch::Tensor& x1, at::Generator& generator) const {
  ObjectiveBatch batch;
  batch.x1 = x1;
  batch.noise = torch::randn(x1.sizes(), generator, x1.options());
  batch.time = torch::rand({x1.size(0)}, generator, x1.options());
  return batch;
}

torch::Tensor FlowMatchingObjective::Loss(models::Network& net, const ObjectiveBatch& batch,
                                          models::Conditioning conditioning) const {
  return TrajectoryRegressionLoss(AsTrajectoryNet(net, "flow_matching"), batch.x1,
                                  InterpolateOt(batch.noise, batch.x1, batch.time), batch.time,
                                  batch.x1 - batch.noise, conditioning);
}

}  // namespace flowplan::objectives
