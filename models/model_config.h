#pragma once

#include <cstdint>

#include "core/config.h"
#include "models/network.h"
#include "models/state_vae.h"
#include "models/trajectory_net.h"
#include "models/transformer.h"
#include "models/unet1d.h"

namespace flowplan::models {

enum class Architecture {
  kUNet1D,       // trajectory network: temporal UNet (SPEC section 2)
  kTransformer,  // trajectory network: pre-norm transformer encoder
  kStateVae,     // VAE over single states (the latent-space planning baseline)
};

inline const config::EnumNames<Architecture>& EnumEntries(Architecture) {
  static const config::EnumNames<Architecture> names = {{Architecture::kUNet1D, "unet1d"},
                                                        {Architecture::kTransformer, "transformer"},
                                                        {Architecture::kStateVae, "state_vae"}};
  return names;
}

/// The `model` section of an experiment config.
struct ModelConfig {
  Architecture architecture = Architecture::kUNet1D;
  UNetConfig unet;
  TransformerConfig transformer;
  StateVaeConfig vae;

  template <class V>
  void Visit(V& v) {
    v.Field("name", architecture, "network");
    v.Field("unet", unet, "unet1d settings");
    v.Field("transformer", transformer, "transformer settings");
    v.Field("vae", vae, "state_vae settings");
  }
};

/// Builds the network of `config` for states of size `state_dim` and, for
/// trajectory networks, a global condition of size `cond_dim` (0 for none).
/// @throws flowplan::Error naming the model.* key of an invalid setting.
NetworkPtr MakeNetwork(const ModelConfig& config, int64_t state_dim, int64_t cond_dim);

/// MakeNetwork() for a trajectory network.
/// @throws flowplan::Error if model.name is not one.
TrajectoryNetPtr MakeTrajectoryNet(const ModelConfig& config, int64_t state_dim, int64_t cond_dim);

/// Copies every parameter and buffer of `from` into `to` (same architecture).
void CopyWeights(const torch::nn::Module& from, torch::nn::Module& to);

/// Number of trainable scalars.
int64_t CountParameters(const torch::nn::Module& module);

}  // namespace flowplan::models
