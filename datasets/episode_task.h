#pragma once

// The task side of dataset generation: an EpisodeTask describes what is
// recorded, and each generator thread owns an EpisodeWorker (its simulator
// workspace, scratch buffers) that rolls out one episode at a time.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "kinematics/trajectory_info.h"

namespace flowplan::datasets {

/// What a task records, identical for every episode.
struct EpisodeLayout {
  kinematics::TrajectoryInfo info;         // env (the file's "env" attribute), dt, T, state labels, robot
  int64_t point_dim = 0;                   // W: size of a commanded start/goal point
  std::map<std::string, int64_t> extras;   // name -> k for per-episode (T, k) arrays
};

/// A commanded start/goal pair that a family of training episodes shares.
struct Family {
  std::string name;           // e.g. "(0,0)->(1,1)"
  std::vector<double> start;  // (W,)
  std::vector<double> goal;   // (W,)
};

/// One rolled-out episode.
struct EpisodeRecord {
  std::vector<double> states;                        // (T, D)
  std::map<std::string, std::vector<double>> extras;  // name -> (T, k)
  std::vector<double> commanded_start;               // (W,)
  std::vector<double> commanded_goal;                // (W,)
  int32_t family = -1;                               // index into Families(), -1 if none
  int64_t simulator_warnings = 0;
  bool rejected = false;       // unstable or failed: counted, not kept
  std::string reject_reason;
};

/// A per-thread workspace. Not shared between threads.
class EpisodeWorker {
 public:
  virtual ~EpisodeWorker() = default;
  /// Rolls out episode `index`; every random draw comes from `seed` alone, so the
  /// result does not depend on the thread or on the order of calls.
  virtual EpisodeRecord Run(int64_t index, uint64_t seed) = 0;
  /// The noise-free rollout of a family: its first and last states are the
  /// conditioning states of the evaluation pairs.
  virtual EpisodeRecord RunNominal(int family) = 0;
};

class EpisodeTask {
 public:
  virtual ~EpisodeTask() = default;
  virtual EpisodeLayout Layout() const = 0;
  /// Start/goal families of a structured dataset (empty when starts and goals are random).
  virtual std::vector<Family> Families() const = 0;
  virtual std::unique_ptr<EpisodeWorker> MakeWorker() const = 0;
};

}  // namespace flowplan::datasets
