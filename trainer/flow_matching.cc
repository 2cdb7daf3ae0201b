#include "trainer/flow_matching.h"

#include "core/error.h"

namespace flowplan::trainer {

torch::Tensor SplitHalves(const torch::Tensor& x) {
  const int64_t T = x.size(1);
  if (T % 2 != 0) throw Error("trajectory splitting: expected an even horizon, got " + std::to_string(T));
  return torch::cat({x.slice(1, 0, T / 2), x.slice(1, T / 2, T)}, 0);
}

torch::Tensor InterpolateOt(const torch::Tensor& x0, const torch::Tensor& x1, const torch::Tensor& t) {
  const torch::Tensor tb = t.view({-1, 1, 1});
  return tb * x1 + (1.0 - tb) * x0;
}

torch::Tensor FlowMatchingLoss(models::VelocityNet& net, const torch::Tensor& x1,
                               planning::Conditioning conditioning, at::Generator& generator) {
  const int64_t B = x1.size(0), T = x1.size(1);
  const torch::Tensor x0 = torch::randn(x1.sizes(), generator, x1.options());
  const torch::Tensor t = torch::rand({B}, generator, x1.options());
  torch::Tensor xt = InterpolateOt(x0, x1, t);
  const torch::Tensor target = x1 - x0;
  const torch::Tensor start = x1.select(1, 0), goal = x1.select(1, T - 1);
  if (conditioning == planning::Conditioning::kInpaint) {
    xt = planning::Inpaint(xt, start, goal);
    const torch::Tensor v = net.Forward(xt, t, torch::Tensor());
    return torch::mse_loss(v.slice(1, 1, T - 1), target.slice(1, 1, T - 1));
  }
  const torch::Tensor v = net.Forward(xt, t, planning::ConditionVector(conditioning, start, goal));
  return torch::mse_loss(v, target);
}

}  // namespace flowplan::trainer
