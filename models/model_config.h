#pragma once

#include <cstdint>

#include "core/config.h"
#include "models/unet1d.h"
#include "models/velocity_net.h"

namespace flowplan::models {

enum class Architecture { kUNet1D };

inline const config::EnumNames<Architecture>& EnumEntries(Architecture) {
  static const config::EnumNames<Architecture> names = {{Architecture::kUNet1D, "unet1d"}};
  return names;
}

/// The `model` section of an experiment config.
struct ModelConfig {
  Architecture architecture = Architecture::kUNet1D;
  UNetConfig unet;

  template <class V>
  void Visit(V& v) {
    v.Field("architecture", architecture, "velocity network");
    v.Field("unet", unet, "UNet1D settings");
  }
};

/// Builds the network of `config` for states of size `state_dim` and a global
/// condition of size `cond_dim` (0 for none).
/// @throws flowplan::Error naming the model.* key of an invalid setting.
VelocityNetPtr MakeVelocityNet(const ModelConfig& config, int64_t state_dim, int64_t cond_dim);

/// Copies every parameter and buffer of `from` into `to` (same architecture).
void CopyWeights(const torch::nn::Module& from, torch::nn::Module& to);

/// Number of trainable scalars.
int64_t CountParameters(const torch::nn::Module& module);

}  // namespace flowplan::models
