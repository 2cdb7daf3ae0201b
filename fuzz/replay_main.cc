// Runs a fuzz target's entry point on files, without libFuzzer: how the
// default test run replays the kept inputs (fuzz/corpus/TARGET), and how an
// input a fuzzer reported is looked at under a debugger.
//
//   TARGET_fuzz FILE_OR_FOLDER...
//
// Exits 0 when every input ends without a finding (see fuzz_input.h); a
// finding aborts, naming nothing but the input being run, printed first.

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <unistd.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const fs::path path = argv[i];
    if (fs::is_directory(path)) {
      for (const auto& entry : fs::directory_iterator(path)) {
        if (entry.is_regular_file()) inputs.push_back(entry.path());
      }
    } else {
      inputs.push_back(path);
    }
  }
  std::sort(inputs.begin(), inputs.end());
  if (inputs.empty()) {
    std::fprintf(stderr, "usage: %s FILE_OR_FOLDER... (no input found)\n", argv[0]);
    return 1;
  }
  for (const fs::path& path : inputs) {
    std::fprintf(stderr, "input %s\n", path.c_str());
    std::ifstream in(path, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  }
  // The files the entry points wrote their inputs to (fuzz_input.h).
  for (const auto& entry : fs::directory_iterator("/tmp")) {
    if (entry.path().filename().string().rfind("flowplan_fuzz_" + std::to_string(::getpid()), 0) == 0) {
      fs::remove(entry.path());
    }
  }
  std::fprintf(stderr, "%zu inputs, no finding\n", inputs.size());
  return 0;
}
