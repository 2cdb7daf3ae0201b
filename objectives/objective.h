#pragma once

// Training objectives. An objective draws what one batch of normalized data
// needs (noise, times) and computes a network's loss on it; the trainer, the
// split-batch mixing of the data and the gradient sharding are the same for
// every objective. A network knows nothing of the objective that trains it.
//
// Shapes: B trajectories, T states, D state dims.

#include <torch/torch.h>

#include <memory>
#include <string>

#include "core/config.h"
#include "models/conditioning.h"
#include "models/model_config.h"
#include "models/network.h"
#include "objectives/ddpm_schedule.h"

namespace flowplan::objectives {

enum class ObjectiveKind {
  kFlowMatching,  // the Flow Planner: conditional OT flow matching, velocity target
  kDdpm,          // Motion Planning Diffusion: DDPM with ε-prediction
  kVae,           // "Reaching Through Latent Space": a VAE over single states
};

inline const config::EnumNames<ObjectiveKind>& EnumEntries(ObjectiveKind) {
  static const config::EnumNames<ObjectiveKind> names = {
      {ObjectiveKind::kFlowMatching, "flow_matching"}, {ObjectiveKind::kDdpm, "ddpm"}, {ObjectiveKind::kVae, "vae"}};
  return names;
}

/// The VAE objective's settings.
struct VaeObjectiveConfig {
  double beta = 0.01;  // weight of the KL term against the reconstruction (per state)

  template <class V>
  void Visit(V& v) {
    v.Field("beta", beta, "weight of the KL divergence against the reconstruction error", config::NonNegative());
  }
};

/// The `objective` section of an experiment config.
struct ObjectiveConfig {
  ObjectiveKind name = ObjectiveKind::kFlowMatching;
  models::Conditioning conditioning = models::Conditioning::kInpaint;
  double split_prob = 0.5;  // chance per batch of training on trajectory halves instead
  DdpmConfig ddpm;
  VaeObjectiveConfig vae;

  template <class V>
  void Visit(V& v) {
    v.Field("name", name, "training objective");
    v.Field("conditioning", conditioning, "how start and goal reach a trajectory network");
    v.Field("split_prob", split_prob, "probability per batch of training on the two halves of every trajectory",
            config::Probability());
    v.Field("ddpm", ddpm, "ddpm: noise schedule");
    v.Field("vae", vae, "vae: loss weights");
  }
};

/// One batch: the data and what the objective drew for it.
struct ObjectiveBatch {
  torch::Tensor x1;     // (B, T, D) normalized data
  torch::Tensor noise;  // objective-specific noise, first dimension B
  torch::Tensor time;   // (B,) objective-specific times (flow time, diffusion step), or undefined

  int64_t size() const { return x1.size(0); }
  /// Rows [begin, end) of every tensor.
  ObjectiveBatch Slice(int64_t begin, int64_t end) const;
  /// Every tensor on `device` (the batch itself when it is there already).
  ObjectiveBatch To(const torch::Device& device) const;
};

class Objective {
 public:
  virtual ~Objective() = default;

  /// Draws noise and times for data x1 (B, T, D), normalized, from `generator`
  /// (one generator for the whole batch, so that the draws do not depend on
  /// how the batch is later sharded).
  virtual ObjectiveBatch Draw(const torch::Tensor& x1, at::Generator& generator) const = 0;

  /// The mean loss of `net` on `batch`, with `conditioning` for trajectory networks.
  /// @throws flowplan::Error if `net` is not the kind of network the objective trains.
  virtual torch::Tensor Loss(models::Network& net, const ObjectiveBatch& batch,
                             models::Conditioning conditioning) const = 0;
};

/// The objective of `config` for the network of `model` (the VAE's latent size).
/// @throws flowplan::Error naming the objective.* key of a bad setting.
std::unique_ptr<Objective> MakeObjective(const ObjectiveConfig& config, const models::ModelConfig& model);

}  // namespace flowplan::objectives
