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
    if (dataset.num_episodes > 0) flowplan::datasets::ReadDatasetEpisodes(path, {0, dataset.num_episodes - 1});
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
