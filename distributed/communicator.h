#pragma once

#include <torch/torch.h>

#include <memory>
#include <string>
#include <vector>

#include "distributed/distributed_config.h"
#include "distributed/world.h"

namespace flowplan::distributed {

/// The collectives a data-parallel training run needs. Every call is
/// collective: all ranks make it, in the same order, with tensors of the same
/// shapes. A peer that is gone, or silent for longer than the timeout, ends the
/// call with flowplan::Error naming this rank and the operation.
class Communicator {
 public:
  virtual ~Communicator() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  /// Sums each tensor (contiguous, same shape and dtype on every rank) over all
  /// ranks in place; the tensors are reduced concurrently.
  virtual void AllReduceSum(std::vector<torch::Tensor>& tensors) = 0;
  /// (n) on every rank -> (size, n): row r is rank r's tensor.
  virtual torch::Tensor AllGather(const torch::Tensor& tensor) = 0;
  /// Waits until every rank has arrived.
  virtual void Barrier() = 0;
};

/// One process: every collective is the identity.
class SingleProcess final : public Communicator {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  void AllReduceSum(std::vector<torch::Tensor>&) override {}
  torch::Tensor AllGather(const torch::Tensor& tensor) override { return tensor.unsqueeze(0).clone(); }
  void Barrier() override {}
};

/// The backend `config.backend` names for a job on `device_type` ("cpu", "cuda").
/// @throws flowplan::Error for anything but gloo, nccl and auto, and for nccl without CUDA.
std::string ResolveBackend(const DistributedConfig& config, const std::string& device_type);

/// Joins the job `world` describes through PyTorch's c10d: a TCPStore at
/// MASTER_ADDR:MASTER_PORT (served by rank 0, or by torchrun's agent) and a
/// Gloo process group (NCCL when `config.backend` asks for it and the build
/// links a CUDA LibTorch). Waits at most `config.timeout_s` for all ranks.
/// @throws flowplan::Error if the rendezvous fails or times out, naming the address and the ranks.
std::unique_ptr<Communicator> Connect(const World& world, const DistributedConfig& config,
                                      const std::string& device_type);

}  // namespace flowplan::distributed
