// An HDF5 data set (`flowplan train`'s data.path, datasets::ReadDataset), and
// the rows of it a process of a data-parallel job reads
// (datasets::ReadDatasetEpisodes). HDF5 itself is not instrumented: a bad read
// inside it shows only if it crashes.

#include "datasets/trajectory_dataset.h"
#include "fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  try {
    const std::string path = flowplan::fuzz::AsFile(data, size, ".h5");
    const flowplan::datasets::TrajectoryDataset dataset = flowplan::datasets::ReadDataset(path);
    // The first and the last episode (ascending, as the reader requires; one index for a one-episode file).
    const int64_t n = dataset.num_episodes;
    if (n == 1) flowplan::datasets::ReadDatasetEpisodes(path, {0});
    if (n > 1) flowplan::datasets::ReadDatasetEpisodes(path, {0, n - 1});
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
