#include "trainer/training_batch.h"

#include "core/error.h"
#include "models/trajectory_net.h"

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

}  // namespace flowplan::trainer
