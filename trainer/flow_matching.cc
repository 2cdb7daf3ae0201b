#include "trainer/flow_matching.h"

#include "core/error.h"
#include "core/format.h"

namespace flowplan::trainer {

torch::Tensor SplitHalves(const torch::Tensor& x) {
  if (x.dim() != 3) throw Error("trajectory splitting: expected (B, T, D), got " + models::ShapeString(x));
  const int64_t T = x.size(1);
  if (T % 2 != 0) throw Error("trajectory splitting: expected an even horizon, got " + std::to_string(T));
  return torch::cat({x.slice(1, 0, T / 2), x.slice(1, T / 2, T)}, 0);
}

torch::Tensor DrawTrainingTrajectories(const torch::Tensor& data, int64_t batch_size, double split_prob,
                                       at::Generator& generator) {
  const torch::Tensor index = torch::randint(data.size(0), {batch_size}, generator, torch::kInt64);
  torch::Tensor x1 = data.index_select(0, index);  // (B, T, D)
  if (torch::rand({1}, generator).item<double>() < split_prob) x1 = SplitHalves(x1);
  return x1;
}

torch::Tensor InterpolateOt(const torch::Tensor& x0, const torch::Tensor& x1, const torch::Tensor& t) {
  const torch::Tensor tb = t.view({-1, 1, 1});
  return tb * x1 + (1.0 - tb) * x0;
}

FlowMatchingBatch FlowMatchingBatch::Slice(int64_t begin, int64_t end) const {
  return {x1.slice(0, begin, end), x0.slice(0, begin, end), t.slice(0, begin, end)};
}

FlowMatchingBatch DrawFlowMatchingBatch(const torch::Tensor& x1, at::Generator& generator) {
  FlowMatchingBatch batch;
  batch.x1 = x1;
  batch.x0 = torch::randn(x1.sizes(), generator, x1.options());
  batch.t = torch::rand({x1.size(0)}, generator, x1.options());
  return batch;
}

torch::Tensor FlowMatchingLoss(models::VelocityNet& net, const FlowMatchingBatch& batch,
                               models::Conditioning conditioning) {
  const int64_t T = batch.x1.size(1);
  torch::Tensor xt = InterpolateOt(batch.x0, batch.x1, batch.t);
  const torch::Tensor target = batch.x1 - batch.x0;
  const torch::Tensor start = batch.x1.select(1, 0), goal = batch.x1.select(1, T - 1);
  if (conditioning == models::Conditioning::kInpaint) {
    xt = models::Inpaint(xt, start, goal);
    const torch::Tensor v = net.Forward(xt, batch.t, torch::Tensor());
    return torch::mse_loss(v.slice(1, 1, T - 1), target.slice(1, 1, T - 1));
  }
  const torch::Tensor v = net.Forward(xt, batch.t, models::ConditionVector(conditioning, start, goal));
  return torch::mse_loss(v, target);
}

torch::Tensor FlowMatchingLoss(models::VelocityNet& net, const torch::Tensor& x1,
                               models::Conditioning conditioning, at::Generator& generator) {
  return FlowMatchingLoss(net, DrawFlowMatchingBatch(x1, generator), conditioning);
}

}  // namespace flowplan::trainer
