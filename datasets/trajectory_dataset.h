#pragma once

// The in-memory form of a flowplan trajectory file and its HDF5 reader/writer.
// The file layout is documented in docs/dataset_format.md; h5py reads it as is.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "kinematics/trajectory_info.h"

namespace flowplan::datasets {

/// The file format this build writes; readers accept exactly this version.
inline constexpr int kDatasetFormatVersion = 2;  // 2: the robot description
inline constexpr const char* kDatasetFormatName = "flowplan.trajectories";

/// A row-major float array with its shape.
struct FloatArray {
  std::vector<int64_t> shape;
  std::vector<float> values;
};

/// Start/goal conditioning states for evaluation, stored with the dataset because
/// only the task side knows which pairs the training data connects.
struct EvalPairs {
  std::vector<float> start;  // (P, D) full states
  std::vector<float> goal;   // (P, D) full states
  std::vector<std::string> names;  // (P,) e.g. "(0,0)->(1,0)"
  int64_t count() const { return static_cast<int64_t>(names.size()); }
};

/// Episodes of one environment: N episodes of T states of dimension D.
struct TrajectoryDataset {
  kinematics::TrajectoryInfo info;        // env, dt, T, state labels (D), robot
  int64_t num_episodes = 0;               // N
  std::vector<float> states;              // (N, T, D)
  int64_t point_dim = 0;                  // P: size of a commanded start/goal point
  std::vector<double> commanded_start;    // (N, W)
  std::vector<double> commanded_goal;     // (N, W)
  std::vector<int32_t> family;            // (N,) index of the start/goal family, -1 if none
  std::map<std::string, FloatArray> extras;  // per-episode arrays, (N, ...) each
  EvalPairs train_pairs;                  // pairs that training episodes connect
  EvalPairs test_pairs;                   // pairs that no training episode connects
  std::string config_yaml;                // the resolved config that generated the data
  uint64_t seed = 0;
  int64_t first_episode = 0;              // episode indices [first_episode, end_episode) were rolled out
  int64_t end_episode = 0;                // (a shard holds part of a dataset's index range)
  int64_t total_episodes = 0;             // episodes of the whole dataset the file belongs to
  int64_t rejected_episodes = 0;          // unstable/failed rollouts left out
  int64_t simulator_warnings = 0;         // simulator warnings over all kept episodes

  /// Throws flowplan::Error (prefixed by `where`) if array sizes disagree with the header.
  void CheckConsistent(const std::string& where) const;
};

/// Writes `dataset` to `path` atomically (temporary name, then rename).
/// @throws flowplan::Error if the folder does not exist or is not writable.
void WriteDataset(const std::string& path, const TrajectoryDataset& dataset);

/// Reads and validates a file written by WriteDataset.
/// @throws flowplan::Error naming the file and the dataset/attribute at fault for
/// missing files, foreign files, other format versions and inconsistent shapes.
TrajectoryDataset ReadDataset(const std::string& path);

/// Reads the header, the evaluation pairs and the states of the episodes
/// `episodes` (ascending) only: num_episodes is their count, states (n, T, D)
/// theirs; the per-episode commands, families and extras are left empty. For
/// a process of a data-parallel job that trains on part of a large file.
/// @throws flowplan::Error as ReadDataset, and for episodes out of range.
TrajectoryDataset ReadDatasetEpisodes(const std::string& path, const std::vector<int64_t>& episodes);

/// A 64-bit FNV-1a hash, as 16 hex digits, of everything a model learns from
/// or is evaluated on: states, labels, dt, robot, evaluation pairs, horizon.
/// Checkpoints record it, so that a resumed run notices a changed data file.
std::string DatasetFingerprint(const TrajectoryDataset& dataset);

/// Joins the shards of one dataset in the order given: episodes are
/// concatenated, counters summed; header, config and evaluation pairs must
/// agree, and the shards' episode ranges must cover the whole dataset in order,
/// without gap or overlap.
/// @throws flowplan::Error naming the first shard that disagrees.
TrajectoryDataset MergeDatasets(const std::vector<TrajectoryDataset>& shards,
                                const std::vector<std::string>& names);

}  // namespace flowplan::datasets
