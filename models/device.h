#pragma once

#include <torch/torch.h>

#include <string>

namespace flowplan::models {

/// The device a config names ("cpu", "cuda", "cuda:N"). Networks, optimizer
/// state and training batches live there; random draws are made on the CPU
/// (so the same seed gives the same numbers on every device) and moved.
/// @throws flowplan::Error naming `key` and `text` for anything else, for CUDA
///   in a LibTorch build without it or without a visible GPU, and for N past the last GPU.
torch::Device ParseDevice(const std::string& text, const std::string& key);

/// Where a module's parameters are (the CPU for a module without any).
torch::Device DeviceOf(const torch::nn::Module& module);

}  // namespace flowplan::models
