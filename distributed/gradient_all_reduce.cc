#include "distributed/gradient_all_reduce.h"

#include "core/error.h"

namespace flowplan::distributed {

GradientAllReduce::GradientAllReduce(std::vector<torch::Tensor> parameters, int64_t bucket_bytes)
    : parameters_(std::move(parameters)) {
  FLOWPLAN_DEMAND(bucket_bytes > 0);
  for (size_t i = 0; i < parameters_.size(); ++i) {
    const torch::Tensor& p = parameters_[i];
    const int64_t bytes = p.numel() * static_cast<int64_t>(p.element_size());
    const bool fits = !buckets_.empty() && buckets_.back().dtype == p.scalar_type() &&
                      (buckets_.back().numel * static_cast<int64_t>(p.element_size()) + bytes <= bucket_bytes);
    if (!fits) buckets_.push_back(Bucket{{}, 0, p.scalar_type()});
    buckets_.back().members.push_back(i);
    buckets_.back().numel += p.numel();
  }
}

void GradientAllReduce::Run(Communicator& communicator, std::vector<double>& scalars) {
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> flat;
  flat.reserve(buckets_.size() + 1);
  for (const Bucket& bucket : buckets_) {
    std::vector<torch::Tensor> pieces;
    pieces.reserve(bucket.members.size());
    for (size_t i : bucket.members) {
      const torch::Tensor& p = parameters_[i];
      pieces.push_back(p.grad().defined() ? p.grad().reshape({-1}) : torch::zeros({p.numel()}, p.options()));
    }
    flat.push_back(torch::cat(pieces));
  }
  // On the gradients' device: NCCL reduces CUDA tensors only.
  flat.push_back(torch::tensor(scalars, torch::kFloat64).to(parameters_.empty() ? torch::Device(torch::kCPU)
                                                                                : parameters_.front().device()));
  communicator.AllReduceSum(flat);
  for (size_t b = 0; b < buckets_.size(); ++b) {
    int64_t offset = 0;
    for (size_t i : buckets_[b].members) {
      torch::Tensor& p = parameters_[i];
      const int64_t n = p.numel();
      p.mutable_grad() = flat[b].slice(0, offset, offset + n).view(p.sizes()).clone();
      offset += n;
    }
  }
  const torch::Tensor reduced = flat.back();
  for (size_t i = 0; i < scalars.size(); ++i) scalars[i] = reduced[static_cast<int64_t>(i)].item<double>();
}

}  // namespace flowplan::distributed
