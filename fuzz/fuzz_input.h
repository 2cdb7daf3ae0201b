#pragma once

// What every fuzz target shares: the input as a file (for the readers that
// take a path), and the rule that bad input ends in one flowplan::Error whose
// message is one line naming what is wrong. Any other exception escapes the
// target, and libFuzzer (or the replay driver) reports it as a finding.

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <unistd.h>

#include "core/error.h"

namespace flowplan::fuzz {

/// The input written to a file of this process (the same path on every call), ending in `extension`.
inline std::string AsFile(const uint8_t* data, size_t size, const std::string& extension) {
  const std::string path = "/tmp/flowplan_fuzz_" + std::to_string(::getpid()) + extension;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

/// Aborts (a finding) unless `message` is one non-empty line.
inline void ExpectOneLine(const flowplan::Error& error) {
  const std::string message = error.what();
  if (message.empty() || message.find('\n') != std::string::npos) {
    std::fprintf(stderr, "flowplan::Error that is not one line: [%s]\n", message.c_str());
    std::abort();
  }
}

}  // namespace flowplan::fuzz
