#pragma once

#include "core/config.h"

namespace flowplan::models {

/// Which code a part of a planner's script runs (the network: sampler.network_kernels; the
/// collision cost's obstacle distances: guidance.distance_kernels).
enum class Kernels {
  kNative,    // flowplan's native operators where the part has them (flowplan::unet1d, flowplan::shape_distance),
              // LibTorch's operators otherwise; a file saved with it loads where libflowplan_kernels is loaded
  kPortable,  // LibTorch's operators only: a saved file needs nothing but PyTorch
};

inline const config::EnumNames<Kernels>& EnumEntries(Kernels) {
  static const config::EnumNames<Kernels> names = {{Kernels::kNative, "native"}, {Kernels::kPortable, "portable"}};
  return names;
}

}  // namespace flowplan::models
