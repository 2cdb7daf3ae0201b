#pragma once

#include <string>

#include "core/config.h"

namespace flowplan::distributed {

/// The `distributed` section: how the ranks of a data-parallel job talk. The
/// ranks themselves come from the environment (see WorldFromEnvironment).
struct DistributedConfig {
  double timeout_s = 1800.0;  // a collective or the rendezvous waiting longer than this ends the job
  double bucket_mb = 25.0;    // gradients are all-reduced in flat buckets of at most this size
  std::string backend = "auto";  // gloo, nccl, or auto (nccl for CUDA devices, else gloo); checked by CheckBackend

  template <class V>
  void Visit(V& v) {
    v.Field("timeout_s", timeout_s,
            "seconds a rank waits for its peers (rendezvous, every collective) before the job ends with an "
            "error; must exceed the longest evaluation rank 0 runs between steps",
            config::InRange(0.001, 1e6));
    v.Field("bucket_mb", bucket_mb, "largest flat gradient bucket all-reduced in one call, in MiB",
            config::Positive());
    v.Field("backend", backend, "collective backend: gloo, nccl (CUDA builds) or auto");
  }
};

}  // namespace flowplan::distributed
