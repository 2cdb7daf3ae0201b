#pragma once

#include <torch/torch.h>

#include "core/config.h"

namespace flowplan::models {

/// How the start and goal states reach the network (SPEC section 2).
enum class Conditioning {
  kInpaint,  // local: overwrite state 0 and state T-1, before every call and after every step
  kDirect,   // global: [start, goal] fed to the network as a condition vector, no overwrite
};

inline const config::EnumNames<Conditioning>& EnumEntries(Conditioning) {
  static const config::EnumNames<Conditioning> names = {{Conditioning::kInpaint, "inpaint"},
                                                        {Conditioning::kDirect, "direct"}};
  return names;
}

/// Size of the network's global condition vector for `conditioning` and D = state_dim.
inline int64_t ConditionDim(Conditioning conditioning, int64_t state_dim) {
  return conditioning == Conditioning::kDirect ? 2 * state_dim : 0;
}

/// Returns x with state 0 replaced by `start` and state T-1 by `goal` (out of place,
/// so gradients flow to the interior states).
/// x: (B, T, D); start, goal: (B, D).
torch::Tensor Inpaint(const torch::Tensor& x, const torch::Tensor& start, const torch::Tensor& goal);

/// The network's condition: (B, 2D) = [start, goal] for direct conditioning,
/// an undefined tensor for inpainting.
torch::Tensor ConditionVector(Conditioning conditioning, const torch::Tensor& start, const torch::Tensor& goal);

}  // namespace flowplan::models
