#include "trainer/sharded_gradient.h"

#include <algorithm>

#include "core/error.h"
#include "core/parallel.h"
#include "models/model_config.h"

namespace flowplan::trainer {

ShardedGradient::ShardedGradient(models::Network& master, const std::function<models::NetworkPtr()>& make_replica,
                                 int shards, int threads)
    : master_(master), shards_(shards) {
  FLOWPLAN_DEMAND(shards >= 1 && threads >= 1);
  const int workers = std::min(shards, threads);
  for (int w = 0; w < workers; ++w) replicas_.push_back(make_replica());
  shard_grads_.resize(static_cast<size_t>(shards));
  shard_losses_.resize(static_cast<size_t>(shards));
}

double ShardedGradient::Compute(const objectives::ObjectiveBatch& batch, const BatchLoss& batch_loss) {
  for (auto& replica : replicas_) models::CopyWeights(master_, *replica);
  const int64_t B = batch.size();
  ParallelFor(shards_, static_cast<int>(replicas_.size()), [&](int worker, int shard) {
    const int64_t begin = B * shard / shards_, end = B * (shard + 1) / shards_;
    shard_grads_[shard].clear();
    shard_losses_[shard] = 0.0;
    if (end == begin) return;
    models::Network& replica = *replicas_[worker];
    replica.zero_grad();
    // Weighted by the shard's share of the batch: the shard losses add up to the batch mean.
    const torch::Tensor loss = batch_loss(replica, batch.Slice(begin, end)) *
                               (static_cast<double>(end - begin) / static_cast<double>(B));
    loss.backward();
    shard_losses_[shard] = loss.item<double>();
    for (const auto& p : replica.parameters()) {
      shard_grads_[shard].push_back(p.grad().defined() ? p.grad().clone() : torch::zeros_like(p));
    }
  });
  torch::NoGradGuard no_grad;
  auto params = master_.parameters();
  double loss = 0.0;
  for (size_t i = 0; i < params.size(); ++i) {
    torch::Tensor sum;
    for (int s = 0; s < shards_; ++s) {
      if (shard_grads_[s].empty()) continue;
      sum = sum.defined() ? sum.add_(shard_grads_[s][i]) : shard_grads_[s][i].clone();
    }
    params[i].mutable_grad() = sum;
  }
  for (int s = 0; s < shards_; ++s) loss += shard_losses_[s];
  return loss;
}

}  // namespace flowplan::trainer
