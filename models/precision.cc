#include "models/precision.h"

#include <ATen/autocast_mode.h>

#include <fstream>
#include <set>
#include <sstream>

namespace flowplan::models {

AutocastScope::AutocastScope(Precision precision) {
  if (precision == Precision::kFp32) return;
  active_ = true;
  was_enabled_ = at::autocast::is_cpu_enabled();
  previous_dtype_ = at::autocast::get_autocast_cpu_dtype();
  at::autocast::set_autocast_cpu_dtype(at::kBFloat16);
  at::autocast::set_cpu_enabled(true);
  at::autocast::increment_nesting();
}

AutocastScope::~AutocastScope() {
  if (!active_) return;
  if (at::autocast::decrement_nesting() == 0) at::autocast::clear_cache();
  at::autocast::set_cpu_enabled(was_enabled_);
  at::autocast::set_autocast_cpu_dtype(previous_dtype_);
}

namespace {

std::set<std::string> CpuFlags() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("flags", 0) != 0) continue;
    std::istringstream words(line.substr(line.find(':') + 1));
    std::set<std::string> flags;
    for (std::string word; words >> word;) flags.insert(word);
    return flags;
  }
  return {};
}

}  // namespace

std::string DescribeBf16Kernels() {
  const std::set<std::string> flags = CpuFlags();
  const auto has = [&](const char* flag) { return flags.count(flag) > 0; };
  if (flags.empty()) {
    return "CPU flags unknown (no x86 flags line in /proc/cpuinfo): bfloat16 kernels depend on what oneDNN finds";
  }
  if (has("amx_bf16") && has("avx512_bf16")) {
    return "AMX-BF16 and AVX512-BF16: oneDNN runs bfloat16 convolutions and matrix products on AMX tiles";
  }
  if (has("avx512_bf16")) return "AVX512-BF16: oneDNN runs bfloat16 convolutions and matrix products natively";
  if (has("avx512bw") && has("avx512vl") && has("avx512dq")) {
    return "AVX-512 without BF16 instructions: oneDNN converts bfloat16 to float32 around float32 arithmetic, "
           "expect little or no gain";
  }
  return "no AVX-512: LibTorch falls back to slow reference bfloat16 kernels, expect bf16 training to be slower "
         "than fp32";
}

}  // namespace flowplan::models
