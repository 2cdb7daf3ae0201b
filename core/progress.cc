#include "core/progress.h"

#include <spdlog/spdlog.h>

#include <cmath>

namespace flowplan {

std::string FormatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  const int64_t total = static_cast<int64_t>(std::llround(seconds));
  const int64_t h = total / 3600, m = (total / 60) % 60, s = total % 60;
  char buffer[32];
  if (h > 0) {
    std::snprintf(buffer, sizeof(buffer), "%lld:%02lld:%02lld", static_cast<long long>(h),
                  static_cast<long long>(m), static_cast<long long>(s));
  } else {
    std::snprintf(buffer, sizeof(buffer), "%lld:%02lld", static_cast<long long>(m),
                  static_cast<long long>(s));
  }
  return buffer;
}

ProgressMeter::ProgressMeter(std::string label, int64_t total, std::string unit, double interval_s)
    : label_(std::move(label)),
      total_(total),
      unit_(std::move(unit)),
      interval_s_(interval_s),
      start_(std::chrono::steady_clock::now()),
      last_log_(start_) {}

double ProgressMeter::ElapsedSeconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double ProgressMeter::Rate(int64_t done) const {
  const double elapsed = ElapsedSeconds();
  const int64_t base = start_done_ < 0 ? 0 : start_done_;
  return elapsed > 0 ? static_cast<double>(done - base) / elapsed : 0.0;
}

void ProgressMeter::Update(int64_t done) {
  if (start_done_ < 0) {
    // The first update fixes the baseline (a resumed run starts above zero).
    start_done_ = done;
    start_ = last_log_ = std::chrono::steady_clock::now();
    return;
  }
  const auto now = std::chrono::steady_clock::now();
  if (done < total_ && std::chrono::duration<double>(now - last_log_).count() < interval_s_) return;
  last_log_ = now;
  const double rate = Rate(done);
  const double eta = rate > 0 ? static_cast<double>(total_ - done) / rate : NAN;
  spdlog::info("{}: {}/{} ({:.1f} {}/s, elapsed {}, ETA {})", label_, done, total_, rate, unit_,
               FormatDuration(ElapsedSeconds()), FormatDuration(eta));
}

}  // namespace flowplan
