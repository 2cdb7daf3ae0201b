#include "objectives/vae.h"

#include "core/error.h"
#include "models/state_vae.h"

namespace flowplan::objectives {

ObjectiveBatch VaeObjective::Draw(const torch::Tensor& x1, at::Generator& generator) const {
  ObjectiveBatch batch;
  batch.x1 = x1;
  batch.noise = torch::randn({x1.size(0), x1.size(1), latent_dim_}, generator, x1.options());
  return batch;
}

torch::Tensor VaeObjective::Loss(models::Network& net, const ObjectiveBatch& batch, models::Conditioning) const {
  auto* vae = dynamic_cast<models::StateVae*>(&net);
  if (vae == nullptr) throw Error("objective.name: vae trains a state VAE (model.name state_vae)");
  const torch::Tensor states = batch.x1.reshape({-1, batch.x1.size(2)});  // (B·T, D)
  const models::StateVae::Encoding encoding = vae->Encode(states);
  const torch::Tensor z = encoding.mean + (0.5 * encoding.log_var).exp() * batch.noise.reshape({-1, latent_dim_});
  const torch::Tensor reconstruction = (vae->Decode(z) - states).pow(2).sum(1).mean();
  const torch::Tensor kl =
      (0.5 * (encoding.mean.pow(2) + encoding.log_var.exp() - 1.0 - encoding.log_var)).sum(1).mean();
  return reconstruction + config_.beta * kl;
}

}  // namespace flowplan::objectives
