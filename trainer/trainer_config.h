#pragma once

#include <cstdint>

#include "core/config.h"
#include "models/precision.h"

namespace flowplan::trainer {

/// The `train` section: optimizer, schedule, logging and checkpointing.
struct TrainerConfig {
  int64_t steps = 2000;
  int batch_size = 256;
  double lr = 2e-4;
  double weight_decay = 0.01;
  double ema_decay = 0.995;       // with warm-up: min(ema_decay, (1 + n) / (10 + n))
  double grad_clip = 0.0;         // max global gradient norm, 0: off
  int64_t log_every = 50;
  int64_t eval_every = 500;       // validation loss and stitching error, 0: only at the end
  int64_t checkpoint_every = 500;
  int keep_checkpoints = 3;       // older periodic checkpoints are deleted
  int val_batch_size = 256;
  int shards = 4;                 // gradient shards per batch, spread over the worker threads
  int data_parts = 1;             // disjoint parts of the training episodes, one generator each
  models::Precision precision = models::Precision::kFp32;  // arithmetic of the forward and backward passes

  template <class V>
  void Visit(V& v) {
    v.Field("steps", steps, "optimizer steps in total", config::Positive());
    v.Field("batch_size", batch_size, "trajectories per step", config::Positive());
    v.Field("lr", lr, "peak learning rate (cosine schedule to 0)", config::Positive());
    v.Field("weight_decay", weight_decay, "AdamW weight decay", config::NonNegative());
    v.Field("ema_decay", ema_decay, "EMA decay (warm-up (1+n)/(10+n))", config::InRange(0.0, 1.0));
    v.Field("grad_clip", grad_clip, "max gradient norm, 0 for none", config::NonNegative());
    v.Field("log_every", log_every, "steps between progress lines and metrics rows", config::Positive());
    v.Field("eval_every", eval_every, "steps between validation/stitching evaluations, 0: at the end only",
            config::NonNegative());
    v.Field("checkpoint_every", checkpoint_every, "steps between checkpoints", config::Positive());
    v.Field("keep_checkpoints", keep_checkpoints, "periodic checkpoints kept on disk", config::Positive());
    v.Field("val_batch_size", val_batch_size, "trajectories per validation batch", config::Positive());
    v.Field("shards", shards,
            "gradient shards per batch; threads work on shards in parallel, so results depend on this, "
            "not on the thread count",
            config::Positive());
    v.Field("data_parts", data_parts,
            "disjoint parts of the training episodes (episode i in part i mod Q), each drawing its share of "
            "every batch with its own generator; a data-parallel job of R processes gives each Q/R parts, so "
            "results depend on this, not on the number of processes",
            config::Positive());
    v.Field("precision", precision,
            "arithmetic of the training forward and backward passes: fp32, or bf16 (CPU autocast: convolutions, "
            "linear layers and matrix products in bfloat16; weights, optimizer state, EMA, validation and "
            "planning stay float32)");
  }
};

}  // namespace flowplan::trainer
