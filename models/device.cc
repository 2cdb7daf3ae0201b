#include "models/device.h"

#include <torch/cuda.h>

#include "core/error.h"

namespace flowplan::models {

torch::Device ParseDevice(const std::string& text, const std::string& key) {
  const bool known = text == "cpu" || text == "cuda" ||
                     (text.rfind("cuda:", 0) == 0 && text.size() > 5 &&
                      text.find_first_not_of("0123456789", 5) == std::string::npos);
  if (!known) throw Error(key + "=" + text + ": expected cpu, cuda or cuda:N");
  const torch::Device device(text);
  if (device.is_cuda()) {
    if (!torch::cuda::is_available()) {
      throw Error(key + "=" + text +
                  ": this LibTorch has no CUDA support or sees no GPU (build against a CUDA LibTorch with "
                  "-DTorch_DIR=..., see docs/performance.md; or use cpu)");
    }
    const int64_t count = static_cast<int64_t>(torch::cuda::device_count());
    if (device.has_index() && device.index() >= count) {
      throw Error(key + "=" + text + ": there are " + std::to_string(count) + " GPU(s), cuda:0 to cuda:" +
                  std::to_string(count - 1));
    }
  }
  return device;
}

torch::Device DeviceOf(const torch::nn::Module& module) {
  const auto parameters = module.parameters();
  return parameters.empty() ? torch::Device(torch::kCPU) : parameters.front().device();
}

}  // namespace flowplan::models
