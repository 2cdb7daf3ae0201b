#include "planning/time_parametrize.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::planning {
namespace {

/// The rest-to-rest profile over normalised time τ in [0, 1]: the path travelled (in time at full speed, σ)
/// and the speed (a share of full speed) at τ.
struct Profile {
  double total = 0.0;     // σ of the whole path
  double duration = 1.0;  // s
  double ramp = 0.0;      // 0: the smooth cubic; else the trapezoid's ramp share of the duration
  double cruise = 0.0;    // the trapezoid's cruise speed

  double Travel(double tau) const {
    tau = std::clamp(tau, 0.0, 1.0);
    if (ramp <= 0.0) return total * (3.0 * tau * tau - 2.0 * tau * tau * tau);
    const double scale = cruise * duration;
    if (tau < ramp) return scale * tau * tau / (2.0 * ramp);
    if (tau > 1.0 - ramp) return total - scale * (1.0 - tau) * (1.0 - tau) / (2.0 * ramp);
    return scale * (tau - 0.5 * ramp);
  }
  double Speed(double tau) const {
    tau = std::clamp(tau, 0.0, 1.0);
    if (ramp <= 0.0) return total * 6.0 * tau * (1.0 - tau) / duration;
    if (tau < ramp) return cruise * tau / ramp;
    if (tau > 1.0 - ramp) return cruise * (1.0 - tau) / ramp;
    return cruise;
  }
};

}  // namespace

TimedPath TimePath(const std::vector<double>& points, int64_t J, int64_t T, double dt,
                   const std::vector<double>& velocity_limit, bool snap_corners, double speed_share) {
  if (J < 1 || points.empty() || points.size() % static_cast<size_t>(J) != 0) {
    throw Error("time_path: points: expected M x " + std::to_string(J) + " values, got " + std::to_string(points.size()));
  }
  if (T < 2 || !(dt > 0)) throw Error("time_path: expected T >= 2 states and a positive dt");
  if (!velocity_limit.empty() && velocity_limit.size() != static_cast<size_t>(J)) {
    throw Error("time_path: expected " + std::to_string(J) + " speed limits, got " + std::to_string(velocity_limit.size()));
  }
  if (!(speed_share > 0.0 && speed_share <= 1.0)) throw Error("time_path: speed_share: expected a share in (0, 1]");
  // The points without repeats.
  std::vector<const double*> p;
  for (size_t m = 0; m < points.size() / static_cast<size_t>(J); ++m) {
    const double* row = &points[m * static_cast<size_t>(J)];
    bool same = !p.empty();
    for (int64_t j = 0; j < J && same; ++j) same = row[j] == p.back()[j];
    if (!same) p.push_back(row);
  }
  if (p.size() == 1 && points.size() > static_cast<size_t>(J)) p.push_back(&points[points.size() - static_cast<size_t>(J)]);
  const int64_t M = static_cast<int64_t>(p.size());
  TimedPath out;
  out.q.assign(static_cast<size_t>(T * J), 0.0);
  out.v.assign(static_cast<size_t>(T * J), 0.0);
  // Each segment's time at full speed, and the running total.
  std::vector<double> cumulative(static_cast<size_t>(M), 0.0), segment(static_cast<size_t>(std::max<int64_t>(M - 1, 0)));
  for (int64_t k = 0; k + 1 < M; ++k) {
    double sigma = 0.0;
    for (int64_t j = 0; j < J; ++j) {
      const double d = std::abs(p[k + 1][j] - p[k][j]);
      sigma = velocity_limit.empty() ? sigma + d * d : std::max(sigma, d / velocity_limit[static_cast<size_t>(j)]);
    }
    segment[static_cast<size_t>(k)] = velocity_limit.empty() ? std::sqrt(sigma) : sigma;
    cumulative[static_cast<size_t>(k + 1)] = cumulative[static_cast<size_t>(k)] + segment[static_cast<size_t>(k)];
  }
  const double total = cumulative.back();
  if (M == 1 || total == 0.0) {
    for (int64_t i = 0; i < T; ++i) std::copy(p[0], p[0] + J, &out.q[static_cast<size_t>(i * J)]);
    out.corners_on_states = true;
    return out;
  }
  Profile profile;
  profile.total = total;
  profile.duration = static_cast<double>(T - 1) * dt;
  // Speeds are shares of full speed only with limits; without, the cubic is the whole profile.
  if (!velocity_limit.empty() && 1.5 * total / profile.duration > speed_share) {
    profile.ramp = std::clamp(1.0 - total / (profile.duration * speed_share), 0.02, 1.0 / 3.0);
    profile.cruise = total / (profile.duration * (1.0 - profile.ramp));
  }
  const double last = static_cast<double>(T - 1);
  // The continuous state index at which the profile reaches travel s.
  auto index_of = [&](double s) {
    double lo = 0.0, hi = last;
    for (int it = 0; it < 100; ++it) {
      const double mid = 0.5 * (lo + hi);
      (profile.Travel(mid / last) < s ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  // Corners: interior points where the path turns by more than kCornerAngle. (A rounded path turns by small
  // angles at many points; the chords across those stay within a fraction of a step of it.)
  constexpr double kCornerAngle = 0.2;  // rad
  std::vector<int64_t> corner_points = {0};
  for (int64_t k = 1; k + 1 < M; ++k) {
    double dot = 0.0, a2 = 0.0, b2 = 0.0;
    for (int64_t j = 0; j < J; ++j) {
      const double a = p[k][j] - p[k - 1][j], b = p[k + 1][j] - p[k][j];
      dot += a * b;
      a2 += a * a;
      b2 += b * b;
    }
    if (dot < std::cos(kCornerAngle) * std::sqrt(a2 * b2)) corner_points.push_back(k);
  }
  corner_points.push_back(M - 1);
  // Snap points: (state index, continuous index, polyline point).
  std::vector<int64_t> snap_state = {0};
  std::vector<double> snap_index = {0.0};
  std::vector<int64_t> snap_point = {0};
  const int64_t C = static_cast<int64_t>(corner_points.size());
  if (snap_corners && C <= T) {
    std::vector<double> u(static_cast<size_t>(C));
    std::vector<int64_t> n(static_cast<size_t>(C));
    for (int64_t c = 0; c < C; ++c) {
      u[static_cast<size_t>(c)] = c == 0 ? 0.0 : c == C - 1 ? last : index_of(cumulative[static_cast<size_t>(corner_points[c])]);
      n[static_cast<size_t>(c)] = static_cast<int64_t>(std::llround(u[static_cast<size_t>(c)]));
    }
    n.front() = 0;
    n.back() = T - 1;
    for (int64_t c = 1; c < C; ++c) n[c] = std::max(n[c], n[c - 1] + 1);
    for (int64_t c = C - 2; c >= 0; --c) n[c] = std::min(n[c], n[c + 1] - 1);
    bool ok = n.front() == 0;
    for (int64_t c = 1; c < C; ++c) ok = ok && n[c] > n[c - 1];
    if (ok) {
      snap_state = n;
      snap_index = u;
      snap_point = corner_points;
      out.corners_on_states = true;
    }
  }
  if (C == 2) out.corners_on_states = true;  // a straight path has none
  if (snap_state.size() == 1) {
    snap_state = {0, T - 1};
    snap_index = {0.0, last};
    snap_point = {0, M - 1};
  }
  int64_t bracket = 0, k = 0;
  for (int64_t i = 0; i < T; ++i) {
    while (bracket + 2 < static_cast<int64_t>(snap_state.size()) && snap_state[bracket + 1] <= i) ++bracket;
    double* qi = &out.q[static_cast<size_t>(i * J)];
    double* vi = &out.v[static_cast<size_t>(i * J)];
    if (snap_state[bracket] == i || snap_state[bracket + 1] == i) {
      const int64_t at = snap_state[bracket] == i ? snap_point[bracket] : snap_point[bracket + 1];
      std::copy(p[at], p[at] + J, qi);
      // The path turns at a corner: its velocity there is the mean of the segments' it joins (0 at the ends).
      const double speed = profile.Speed((snap_state[bracket] == i ? snap_index[bracket] : snap_index[bracket + 1]) / last);
      if (at > 0 && at + 1 < M && segment[static_cast<size_t>(at - 1)] > 0.0 && segment[static_cast<size_t>(at)] > 0.0) {
        const double in = segment[static_cast<size_t>(at - 1)], out = segment[static_cast<size_t>(at)];
        for (int64_t j = 0; j < J; ++j) {
          vi[j] = 0.5 * speed * ((p[at][j] - p[at - 1][j]) / in + (p[at + 1][j] - p[at][j]) / out);
        }
      }
      continue;
    }
    const double n0 = static_cast<double>(snap_state[bracket]), n1 = static_cast<double>(snap_state[bracket + 1]);
    const double warp = (snap_index[bracket + 1] - snap_index[bracket]) / (n1 - n0);
    const double u = snap_index[bracket] + (static_cast<double>(i) - n0) * warp;
    const double s = profile.Travel(u / last);
    k = std::max<int64_t>(k, snap_point[bracket]);
    while (k + 1 < snap_point[bracket + 1] && cumulative[static_cast<size_t>(k + 1)] < s) ++k;
    const double length = segment[static_cast<size_t>(k)];
    const double f = length > 0.0 ? std::clamp((s - cumulative[static_cast<size_t>(k)]) / length, 0.0, 1.0) : 0.0;
    const double speed = profile.Speed(u / last) * warp;
    for (int64_t j = 0; j < J; ++j) {
      qi[j] = p[k][j] + f * (p[k + 1][j] - p[k][j]);
      if (length > 0.0) vi[j] = speed * (p[k + 1][j] - p[k][j]) / length;
    }
  }
  // Speeds between states: σ is time at full speed only with limits.
  const double time_scale = velocity_limit.empty() ? 0.0 : 1.0;
  for (int64_t i = 0; i + 1 < T && time_scale > 0.0; ++i) {
    for (int64_t j = 0; j < J; ++j) {
      const double d = std::abs(out.q[static_cast<size_t>((i + 1) * J + j)] - out.q[static_cast<size_t>(i * J + j)]);
      out.peak_ratio = std::max(out.peak_ratio, d / (dt * velocity_limit[static_cast<size_t>(j)]));
    }
  }
  return out;
}

torch::Tensor StatesOf(const TimedPath& path, int64_t J, int64_t T, int64_t D) {
  if (D != J && D != 2 * J) {
    throw Error("timed_states: states of " + std::to_string(D) + " dimensions for a path of " + std::to_string(J) +
                " joints (expected " + std::to_string(J) + " or " + std::to_string(2 * J) + ")");
  }
  const torch::Tensor q = torch::tensor(path.q, torch::kFloat64).view({T, J});
  if (D == J) return q;
  return torch::cat({q, torch::tensor(path.v, torch::kFloat64).view({T, J})}, 1);
}

std::pair<torch::Tensor, torch::Tensor> TimeAlongPath(const torch::Tensor& points, int64_t T, double dt,
                                                      const std::vector<double>& velocity_limit) {
  if (!points.defined() || points.dim() != 2 || points.size(0) < 1 || points.scalar_type() != torch::kFloat64) {
    throw Error("time_along_path: points: expected (M, J) float64 with M >= 1, got " +
                (points.defined() ? ShapeText(points.sizes().vec()) + " " + std::string(c10::toString(points.scalar_type()))
                                  : std::string("(undefined)")));
  }
  const torch::Tensor c = points.contiguous();
  const int64_t J = c.size(1);
  const TimedPath path =
      TimePath(std::vector<double>(c.data_ptr<double>(), c.data_ptr<double>() + c.numel()), J, T, dt, velocity_limit);
  return {torch::tensor(path.q, torch::kFloat64).view({T, J}), torch::tensor(path.v, torch::kFloat64).view({T, J})};
}

torch::Tensor TimedStates(const torch::Tensor& points, int64_t T, double dt, int64_t D,
                          const std::vector<double>& velocity_limit) {
  auto [q, v] = TimeAlongPath(points, T, dt, velocity_limit);
  const int64_t J = q.size(1);
  if (D != J && D != 2 * J) {
    throw Error("timed_states: states of " + std::to_string(D) + " dimensions for a path of " + std::to_string(J) +
                " joints (expected " + std::to_string(J) + " or " + std::to_string(2 * J) + ")");
  }
  return D == J ? q : torch::cat({q, v}, 1);
}

}  // namespace flowplan::planning
