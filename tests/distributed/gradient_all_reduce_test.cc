#include "distributed/gradient_all_reduce.h"

#include <gtest/gtest.h>

#include <vector>

namespace flowplan::distributed {
namespace {

/// Stands for a job of `copies` ranks that all hold the same tensors: a sum is
/// a multiplication; counts the collective calls and their tensors.
class IdenticalRanks final : public Communicator {
 public:
  explicit IdenticalRanks(int copies) : copies_(copies) {}
  int rank() const override { return 0; }
  int size() const override { return copies_; }
  void AllReduceSum(std::vector<torch::Tensor>& tensors) override {
    ++calls;
    for (auto& t : tensors) {
      sizes.push_back(t.numel());
      t.mul_(copies_);
    }
  }
  torch::Tensor AllGather(const torch::Tensor& tensor) override {
    return tensor.unsqueeze(0).expand({copies_, tensor.numel()}).clone();
  }
  void Barrier() override {}
  int calls = 0;
  std::vector<int64_t> sizes;

 private:
  int copies_;
};

TEST(GradientAllReduceTest, SumsEveryGradientAndScalarInBucketsOfTheGivenSize) {
  std::vector<torch::Tensor> params = {torch::zeros({10}), torch::zeros({3, 4}), torch::zeros({30}), torch::zeros({2})};
  for (auto& p : params) p.set_requires_grad(true);
  std::vector<torch::Tensor> grads;
  for (size_t i = 0; i < params.size(); ++i) {
    grads.push_back(torch::arange(params[i].numel(), torch::kFloat32).reshape(params[i].sizes()) + 100.0 * i);
    if (i != 3) params[i].mutable_grad() = grads[i].clone();  // the last one has no gradient
  }
  // 88 bytes per bucket: [10 + 12] floats, then [30] alone (over the limit on its own), then [2].
  GradientAllReduce reduce(params, 88);
  EXPECT_EQ(reduce.buckets(), 3u);
  IdenticalRanks ranks(3);
  std::vector<double> scalars{0.5, 1.0};
  reduce.Run(ranks, scalars);
  EXPECT_EQ(ranks.calls, 1);  // one call, all buckets and the scalars reduced concurrently
  EXPECT_EQ(ranks.sizes, (std::vector<int64_t>{22, 30, 2, 2}));
  for (size_t i = 0; i < 3; ++i) EXPECT_TRUE(torch::equal(params[i].grad(), grads[i] * 3)) << i;
  EXPECT_TRUE(torch::equal(params[3].grad(), torch::zeros({2})));
  EXPECT_EQ(scalars, (std::vector<double>{1.5, 3.0}));
  // The gradients are the parameters' own tensors afterwards, not views into a shared bucket.
  params[0].mutable_grad().zero_();
  EXPECT_FALSE(torch::equal(params[1].grad(), torch::zeros({3, 4})));
}

/// Rank 0 of two, where rank 1's buckets hold 1000, 1001, 1002, ... element by element.
class OtherRankCounts final : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 2; }
  void AllReduceSum(std::vector<torch::Tensor>& tensors) override {
    for (auto& t : tensors) t.add_(torch::arange(t.numel(), t.options()) + 1000);
  }
  torch::Tensor AllGather(const torch::Tensor& tensor) override { return torch::stack({tensor, tensor}); }
  void Barrier() override {}
};

TEST(GradientAllReduceTest, EveryElementComesBackToItsOwnParameterAndPlace) {
  std::vector<torch::Tensor> params = {torch::zeros({2, 3}), torch::zeros({4}), torch::zeros({5})};
  for (auto& p : params) {
    p.set_requires_grad(true);
    p.mutable_grad() = torch::full_like(p, 0.5);
  }
  GradientAllReduce reduce(params, 40);  // buckets [6 + 4 floats], [5 floats]
  ASSERT_EQ(reduce.buckets(), 2u);
  OtherRankCounts ranks;
  std::vector<double> scalars{2.0};
  reduce.Run(ranks, scalars);
  EXPECT_TRUE(torch::equal(params[0].grad(), torch::arange(6).reshape({2, 3}).to(torch::kFloat32) + 1000.5));
  EXPECT_TRUE(torch::equal(params[1].grad(), torch::arange(6, 10).to(torch::kFloat32) + 1000.5));
  EXPECT_TRUE(torch::equal(params[2].grad(), torch::arange(5).to(torch::kFloat32) + 1000.5));
  EXPECT_EQ(scalars, (std::vector<double>{1002.0}));
}

}  // namespace
}  // namespace flowplan::distributed
