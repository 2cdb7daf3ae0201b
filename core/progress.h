#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace flowplan {

/// Logs "label: done/total (rate unit/s, ETA m:ss)" at most once per interval.
/// Thread-safe only if Update() is called from one thread.
class ProgressMeter {
 public:
  ProgressMeter(std::string label, int64_t total, std::string unit, double interval_s = 5.0);

  /// `done` items finished so far (monotone). Logs when the interval has passed
  /// or when done == total.
  void Update(int64_t done);
  /// Items per second since construction.
  double Rate(int64_t done) const;
  double ElapsedSeconds() const;

 private:
  std::string label_;
  int64_t total_;
  std::string unit_;
  double interval_s_;
  int64_t start_done_ = -1;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_log_;
};

/// "1:05" or "1:02:03".
std::string FormatDuration(double seconds);

}  // namespace flowplan
