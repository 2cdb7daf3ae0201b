// The smallest network configs the unit tests train and compare: every
// architecture at a size that runs in milliseconds.
#pragma once

#include "models/model_config.h"

namespace flowplan::testing {

/// `architecture` with a two-level UNet (16, 32), a 32-wide two-head transformer
/// and a state VAE of two 32-wide layers and a 4-dimensional latent.
inline models::ModelConfig TinyModelConfig(models::Architecture architecture) {
  models::ModelConfig config;
  config.architecture = architecture;
  config.unet.down_dims = {16, 32};
  config.transformer.d_model = 32;
  config.transformer.heads = 2;
  config.vae.hidden = {32, 32};
  config.vae.latent = 4;
  return config;
}

}  // namespace flowplan::testing
