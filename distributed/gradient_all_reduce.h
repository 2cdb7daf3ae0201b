#pragma once

#include <torch/torch.h>

#include <vector>

#include "distributed/communicator.h"

namespace flowplan::distributed {

/// Sums the gradients of `parameters` over all ranks, together with a few
/// scalars (a loss, a stop flag), in flat buckets of at most `bucket_bytes`
/// each: a handful of collective calls per step instead of one per parameter.
/// Parameters without a gradient take part as zeros. The buckets are built
/// once; shapes and dtypes must be the same on every rank.
class GradientAllReduce {
 public:
  GradientAllReduce(std::vector<torch::Tensor> parameters, int64_t bucket_bytes);

  /// Replaces every parameter's .grad by its sum over ranks; `scalars` (float64) are summed too.
  void Run(Communicator& communicator, std::vector<double>& scalars);

  /// Number of buckets (the collective calls per step, besides the scalars').
  size_t buckets() const { return buckets_.size(); }

 private:
  struct Bucket {
    std::vector<size_t> members;  // indices into parameters_
    int64_t numel = 0;
    torch::ScalarType dtype = torch::kFloat32;
  };
  std::vector<torch::Tensor> parameters_;
  std::vector<Bucket> buckets_;
};

}  // namespace flowplan::distributed
