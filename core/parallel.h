#pragma once

#include <functional>

namespace flowplan {

/// Number of worker threads for a config value: `requested` > 0 is used as is,
/// 0 means every hardware thread.
int ResolveThreadCount(int requested);

/// Runs `body(worker, index)` for every index in [0, count) on `threads` workers
/// (worker in [0, threads)). Indices are handed out dynamically, so results must
/// depend only on `index` (seed per-index randomness with StreamSeed). The first
/// exception thrown by a body stops the hand-out and is rethrown here.
void ParallelFor(int count, int threads, const std::function<void(int worker, int index)>& body);

}  // namespace flowplan
