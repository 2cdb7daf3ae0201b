#include "distributed/communicator.h"

#include <torch/csrc/distributed/c10d/PrefixStore.hpp>
#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>
#ifdef FLOWPLAN_WITH_NCCL
#include <c10/cuda/CUDAFunctions.h>
#include <torch/csrc/distributed/c10d/ProcessGroupNCCL.hpp>
#endif

#include <chrono>
#include <exception>
#include <functional>
#include <utility>

#include "core/error.h"

namespace flowplan::distributed {
namespace {

/// The first line of an exception text (c10 errors append a C++ backtrace).
std::string FirstLine(const std::string& text) { return text.substr(0, text.find('\n')); }

bool IsLoopback(const std::string& host) {
  return host == "localhost" || host.rfind("127.", 0) == 0 || host == "::1";
}

class C10dCommunicator final : public Communicator {
 public:
  /// `device`: where the group's collectives take their tensors (the CPU for
  /// Gloo, this process's GPU for NCCL); tensors elsewhere are moved there and back.
  C10dCommunicator(const World& world, c10::intrusive_ptr<c10d::ProcessGroup> group, double timeout_s,
                   torch::Device device)
      : world_(world), group_(std::move(group)), timeout_s_(timeout_s), device_(device) {}

  int rank() const override { return world_.rank; }
  int size() const override { return world_.size; }

  void AllReduceSum(std::vector<torch::Tensor>& tensors) override {
    Guarded("all-reduce", [&] {
      std::vector<torch::Tensor> moved;
      std::vector<c10::intrusive_ptr<c10d::Work>> pending;
      for (auto& tensor : tensors) {
        moved.push_back(tensor.device() == device_ ? tensor : tensor.to(device_));
        std::vector<torch::Tensor> one{moved.back()};
        pending.push_back(group_->allreduce(one));
      }
      for (auto& work : pending) work->wait();
      for (size_t i = 0; i < tensors.size(); ++i) {
        if (!moved[i].is_same(tensors[i])) tensors[i].copy_(moved[i]);
      }
    });
  }

  torch::Tensor AllGather(const torch::Tensor& tensor) override {
    const torch::Tensor input = tensor.to(device_).contiguous();
    std::vector<std::vector<torch::Tensor>> outputs(1);
    for (int r = 0; r < world_.size; ++r) outputs[0].push_back(torch::empty_like(input));
    std::vector<torch::Tensor> inputs{input};
    Guarded("all-gather", [&] { group_->allgather(outputs, inputs)->wait(); });
    return torch::stack(outputs[0]).to(tensor.device());
  }

  void Barrier() override {
    Guarded("barrier", [&] { group_->barrier()->wait(); });
  }

 private:
  void Guarded(const char* operation, const std::function<void()>& body) {
    try {
      body();
    } catch (const std::exception& e) {
      throw Error("rank " + std::to_string(world_.rank) + " of " + std::to_string(world_.size) + ": " + operation +
                  " failed: a peer exited or did not answer within distributed.timeout_s=" +
                  std::to_string(static_cast<int64_t>(timeout_s_)) + " (" + FirstLine(e.what()) + ")");
    }
  }

  World world_;
  c10::intrusive_ptr<c10d::ProcessGroup> group_;
  double timeout_s_;
  torch::Device device_;
};

}  // namespace

std::string ResolveBackend(const DistributedConfig& config, const std::string& device_type) {
  std::string backend = config.backend;
  if (backend == "auto") backend = device_type == "cuda" ? "nccl" : "gloo";
  if (backend != "gloo" && backend != "nccl") {
    throw Error("distributed.backend=" + config.backend + ": expected gloo, nccl or auto");
  }
#ifndef FLOWPLAN_WITH_NCCL
  if (backend == "nccl") {
    throw Error("distributed.backend=" + config.backend + ": this build links a LibTorch without CUDA/NCCL; use gloo");
  }
#endif
  return backend;
}

std::unique_ptr<Communicator> Connect(const World& world, const DistributedConfig& config,
                                      const std::string& device_type) {
  const auto timeout = std::chrono::milliseconds(static_cast<int64_t>(config.timeout_s * 1000.0));
  const std::string backend = ResolveBackend(config, device_type);
  const std::string where = world.master_addr + ":" + std::to_string(world.master_port);
  c10::intrusive_ptr<c10d::Store> store;
  try {
    c10d::TCPStoreOptions options;
    options.port = static_cast<uint16_t>(world.master_port);
    options.isServer = world.rank == 0 && !world.agent_hosts_store;
    options.numWorkers = static_cast<size_t>(world.size);
    options.waitWorkers = false;
    options.timeout = timeout;
    store = c10::make_intrusive<c10d::TCPStore>(world.master_addr, options);
  } catch (const std::exception& e) {
    throw Error("rank " + std::to_string(world.rank) + " of " + std::to_string(world.size) +
                ": cannot reach the rendezvous store at " + where + " (" + world.source +
                " job; MASTER_ADDR/MASTER_PORT): " + FirstLine(e.what()));
  }
  // The group's own keys live under a prefix, so that the store can serve other clients (torchrun's agent).
  auto prefixed = c10::make_intrusive<c10d::PrefixStore>("flowplan", store);
  try {
    c10::intrusive_ptr<c10d::ProcessGroup> group;
    torch::Device device = torch::kCPU;
#ifdef FLOWPLAN_WITH_NCCL
    if (backend == "nccl") {
      // Without this NCCL waits on a lost peer forever instead of failing after the timeout.
      setenv("NCCL_ASYNC_ERROR_HANDLING", "1", 0);
      device = torch::Device(torch::kCUDA, static_cast<c10::DeviceIndex>(world.local_rank));
      c10::cuda::set_device(device.index());
      auto options = c10d::ProcessGroupNCCL::Options::create();
      options->timeout = timeout;
      group = c10::make_intrusive<c10d::ProcessGroupNCCL>(prefixed, world.rank, world.size, options);
    }
#endif
    if (!group) {
      auto options = c10d::ProcessGroupGloo::Options::create(timeout);
      if (const char* interface = std::getenv("GLOO_SOCKET_IFNAME"); interface != nullptr && *interface != '\0') {
        options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForInterface(interface));
      } else if (IsLoopback(world.master_addr)) {
        options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1"));
      } else {
        options->devices.push_back(c10d::ProcessGroupGloo::createDefaultDevice());
      }
      options->threads = 2;
      group = c10::make_intrusive<c10d::ProcessGroupGloo>(prefixed, world.rank, world.size, options);
    }
    auto communicator = std::make_unique<C10dCommunicator>(world, group, config.timeout_s, device);
    communicator->Barrier();  // every rank is here: a missing one ends the job now, not at the first step
    return communicator;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error("rank " + std::to_string(world.rank) + " of " + std::to_string(world.size) +
                ": rendezvous at " + where + " failed: not every rank joined within distributed.timeout_s=" +
                std::to_string(static_cast<int64_t>(config.timeout_s)) + " (" + FirstLine(e.what()) + ")");
  }
}

}  // namespace flowplan::distributed
