#pragma once

#include <torch/torch.h>

#include <functional>
#include <vector>

#include "models/network.h"
#include "objectives/objective.h"

namespace flowplan::trainer {

/// The loss of a network on (part of) a batch.
using BatchLoss = std::function<torch::Tensor(models::Network& net, const objectives::ObjectiveBatch& batch)>;

/// The gradient of a batch's loss, computed on fixed shards of the batch by
/// worker threads that each own a replica of the network and run LibTorch
/// single-threaded, then summed in shard order. The result depends on the
/// number of shards, never on the number of threads: the same seed gives the
/// same weights on 1 or N cores. Workers compute independent shards, which
/// also scales better on a few cores than splitting each small convolution.
class ShardedGradient {
 public:
  /// @param master        the network whose .grad receives the gradient
  /// @param make_replica  builds a network of the master's architecture
  /// @param shards        fixed number of shards per batch (>= 1)
  /// @param threads       worker threads (>= 1); at most `shards` are used
  ShardedGradient(models::Network& master, const std::function<models::NetworkPtr()>& make_replica, int shards,
                  int threads);

  /// Sets master's gradients to those of the batch's mean loss and returns the loss.
  /// Call with LibTorch's intra-op threads set to 1 (see at::set_num_threads).
  double Compute(const objectives::ObjectiveBatch& batch, const BatchLoss& loss);

 private:
  models::Network& master_;
  std::vector<models::NetworkPtr> replicas_;             // one per worker
  std::vector<std::vector<torch::Tensor>> shard_grads_;  // [shard][parameter]
  std::vector<double> shard_losses_;
  int shards_;
};

}  // namespace flowplan::trainer
