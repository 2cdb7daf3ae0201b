#pragma once

#include "core/config.h"

namespace flowplan::models {

/// Which code a scripted network runs.
enum class NetworkKernels {
  kNative,    // the network's native operator where it has one (flowplan::unet1d), LibTorch's operators otherwise;
              // a file saved with it loads where libflowplan_kernels is loaded
  kPortable,  // LibTorch's operators only: a saved file needs nothing but PyTorch
};

inline const config::EnumNames<NetworkKernels>& EnumEntries(NetworkKernels) {
  static const config::EnumNames<NetworkKernels> names = {{NetworkKernels::kNative, "native"},
                                                          {NetworkKernels::kPortable, "portable"}};
  return names;
}

}  // namespace flowplan::models
