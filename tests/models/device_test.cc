#include "models/device.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/cuda.h>

#include "core/error.h"

namespace flowplan::models {
namespace {

using ::testing::HasSubstr;

std::string ErrorOf(const std::string& text) {
  try {
    ParseDevice(text, "device");
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(DeviceTest, ParsesTheCpuAndRejectsWhatIsNoDevice) {
  EXPECT_TRUE(ParseDevice("cpu", "device").is_cpu());
  for (const std::string bad : {"gpu", "CPU", "cuda:", "cuda:x", "cuda:-1", "cpu:0", ""}) {
    EXPECT_THAT(ErrorOf(bad), HasSubstr("device=" + bad + ": expected cpu, cuda or cuda:N")) << bad;
  }
}

TEST(DeviceTest, CudaIsRefusedWithAReasonWhenThisLibTorchHasNone) {
  if (torch::cuda::is_available()) {
    EXPECT_TRUE(ParseDevice("cuda", "device").is_cuda());
    EXPECT_THAT(ErrorOf("cuda:999"), HasSubstr("device=cuda:999: there are"));
  } else {
    EXPECT_THAT(ErrorOf("cuda"), HasSubstr("device=cuda: this LibTorch has no CUDA support"));
    EXPECT_THAT(ErrorOf("cuda:1"), HasSubstr("device=cuda:1: this LibTorch has no CUDA support"));
  }
}

TEST(DeviceTest, DeviceOfAModuleIsWhereItsParametersAre) {
  torch::nn::Linear linear(2, 3);
  EXPECT_TRUE(DeviceOf(*linear).is_cpu());
  torch::nn::Sequential empty;
  EXPECT_TRUE(DeviceOf(*empty).is_cpu());
}

}  // namespace
}  // namespace flowplan::models
