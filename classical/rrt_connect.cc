#include "classical/rrt_connect.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include <spdlog/fmt/fmt.h>

#include "core/error.h"
#include "core/random.h"
#include "planning/time_parametrize.h"

namespace flowplan::classical {
namespace {

using Clock = std::chrono::steady_clock;
using Config = std::vector<double>;  // (J) joint values
using Path = std::vector<Config>;

double Distance2(const double* a, const double* b, size_t J) {
  double total = 0.0;
  for (size_t j = 0; j < J; ++j) total += (a[j] - b[j]) * (a[j] - b[j]);
  return total;
}

/// One tree of configurations, each with its parent (-1 at the root), stored flat.
class Tree {
 public:
  explicit Tree(size_t J) : J_(J) {}
  size_t size() const { return parent_.size(); }
  const double* at(size_t i) const { return &values_[i * J_]; }
  size_t Add(const double* q, int64_t parent) {
    values_.insert(values_.end(), q, q + J_);
    parent_.push_back(parent);
    return parent_.size() - 1;
  }
  /// The node nearest to q (Euclidean in joint space); the first of a tie.
  size_t Nearest(const double* q) const {
    size_t best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < size(); ++i) {
      const double d = Distance2(at(i), q, J_);
      if (d < best_d) {
        best_d = d;
        best = i;
      }
    }
    return best;
  }
  /// The configurations from the root to node i.
  Path Branch(size_t i) const {
    Path out;
    for (int64_t n = static_cast<int64_t>(i); n >= 0; n = parent_[static_cast<size_t>(n)]) {
      out.emplace_back(at(static_cast<size_t>(n)), at(static_cast<size_t>(n)) + J_);
    }
    std::reverse(out.begin(), out.end());
    return out;
  }

 private:
  size_t J_;
  std::vector<double> values_;
  std::vector<int64_t> parent_;
};

/// What a search may spend: iterations, and the plan's wall-clock stop.
struct Budget {
  int64_t iterations;
  Clock::time_point deadline;
};

/// RRT-Connect between two valid configurations in one world.
class Search {
 public:
  Search(const collision::Checker& checker, const std::vector<double>& lower, const std::vector<double>& upper,
         double range)
      : checker_(checker), lower_(lower), upper_(upper), range_(range), J_(lower.size()) {}

  bool Motion(const double* a, const double* b) const { return checker_.MotionValid(a, b); }

  /// A path from `from` to `to`, or none within the budget.
  std::optional<Path> Connect(const Config& from, const Config& to, uint64_t seed, const Budget& budget) const {
    if (Motion(from.data(), to.data())) return Path{from, to};
    Rng rng(seed);
    Tree start(J_), goal(J_);
    start.Add(from.data(), -1);
    goal.Add(to.data(), -1);
    Tree* a = &start;
    Tree* b = &goal;
    Config sample(J_), step(J_);
    for (int64_t it = 0; it < budget.iterations; ++it) {
      if ((it & 63) == 0 && Clock::now() > budget.deadline) break;
      for (size_t j = 0; j < J_; ++j) sample[j] = rng.Uniform(lower_[j], upper_[j]);
      // Extend tree a by one step towards the sample.
      const size_t near = a->Nearest(sample.data());
      if (!Steer(a->at(near), sample.data(), step.data())) {
        std::swap(a, b);
        continue;
      }
      const size_t added = a->Add(step.data(), static_cast<int64_t>(near));
      // Connect tree b to the new node, step after step.
      size_t from_b = b->Nearest(step.data());
      const Config target(a->at(added), a->at(added) + J_);
      bool reached = false;
      Config next(J_);
      while (true) {
        const bool whole = Distance2(b->at(from_b), target.data(), J_) <= range_ * range_;
        if (whole) {
          next = target;
        } else {
          Toward(b->at(from_b), target.data(), next.data());
        }
        if (!checker_.Valid(next.data()) || !Motion(b->at(from_b), next.data())) break;
        if (whole) {
          reached = true;
          break;
        }
        from_b = b->Add(next.data(), static_cast<int64_t>(from_b));
      }
      if (reached) {
        // The start tree's branch to its meeting node, then the goal tree's from its meeting node to the goal.
        const bool a_is_start = a == &start;
        Path path = start.Branch(a_is_start ? added : from_b);
        Path to_goal = goal.Branch(a_is_start ? from_b : added);
        path.insert(path.end(), to_goal.rbegin(), to_goal.rend());
        return path;
      }
      std::swap(a, b);
    }
    return std::nullopt;
  }

  /// Shortcutting of a valid polyline: from each kept point, jump to the farthest later point whose motion is valid.
  Path Shortcut(const Path& points) const {
    const size_t M = points.size();
    if (M < 3) return points;
    Path kept = {points[0]};
    size_t i = 0;
    while (i + 1 < M) {
      size_t next = i + 1;
      for (size_t candidate = M - 1; candidate > i + 1; --candidate) {
        if (Motion(points[i].data(), points[candidate].data())) {
          next = candidate;
          break;
        }
      }
      kept.push_back(points[next]);
      i = next;
    }
    return kept;
  }

  /// Shortcutting again through points along the segments, `passes` times: each pass subdivides every segment
  /// in four and shortcuts, so the path can leave a vertex part way along a segment and draws tighter.
  Path Tighten(Path points, int passes) const {
    for (int p = 0; p < passes; ++p) {
      if (points.size() < 3) break;
      Path dense = {points[0]};
      for (size_t k = 1; k < points.size(); ++k) {
        for (int part = 1; part <= 4; ++part) {
          Config c(J_);
          for (size_t j = 0; j < J_; ++j) c[j] = points[k - 1][j] + 0.25 * part * (points[k][j] - points[k - 1][j]);
          dense.push_back(part == 4 ? points[k] : c);
        }
      }
      points = Shortcut(dense);
    }
    return points;
  }

  /// The valid polyline with its corners rounded: Chaikin's corner cutting with the most iterations (of 4, down to
  /// 1) whose polyline is valid and has at most `max_points` points; the polyline itself if none.
  Path RoundCorners(const Path& points, size_t max_points) const {
    if (points.size() < 3) return points;
    for (int iterations = 4; iterations >= 1; --iterations) {
      Path rounded = points;
      for (int k = 0; k < iterations && rounded.size() > 2; ++k) {
        Path next = {rounded.front()};
        for (size_t m = 0; m + 1 < rounded.size(); ++m) {
          Config a(J_), b(J_);
          for (size_t j = 0; j < J_; ++j) {
            a[j] = 0.75 * rounded[m][j] + 0.25 * rounded[m + 1][j];
            b[j] = 0.25 * rounded[m][j] + 0.75 * rounded[m + 1][j];
          }
          if (m > 0) next.push_back(a);
          if (m + 2 < rounded.size()) next.push_back(b);
        }
        next.push_back(rounded.back());
        rounded = std::move(next);
      }
      if (rounded.size() > max_points) continue;
      bool ok = true;
      for (size_t m = 1; m + 1 < rounded.size() && ok; ++m) ok = checker_.Valid(rounded[m].data());
      for (size_t m = 0; m + 1 < rounded.size() && ok; ++m) ok = Motion(rounded[m].data(), rounded[m + 1].data());
      if (ok) return rounded;
    }
    return points;
  }

 private:
  /// `to` itself if within range of `from`, else the point at range along the way: written to out; whether
  /// that point is valid.
  bool Steer(const double* from, const double* to, double* out) const {
    if (Distance2(from, to, J_) <= range_ * range_) {
      std::copy(to, to + J_, out);
    } else {
      Toward(from, to, out);
    }
    return checker_.Valid(out) && Motion(from, out);
  }
  void Toward(const double* from, const double* to, double* out) const {
    const double scale = range_ / std::sqrt(Distance2(from, to, J_));
    for (size_t j = 0; j < J_; ++j) out[j] = from[j] + scale * (to[j] - from[j]);
  }

  const collision::Checker& checker_;
  const std::vector<double>& lower_;
  const std::vector<double>& upper_;
  double range_;
  size_t J_;
};

}  // namespace

RrtConnectPlanner::RrtConnectPlanner(const kinematics::TrajectoryInfo& trajectory, RrtConnectConfig config,
                                     validity::CheckConfig check)
    : horizon_(trajectory.horizon),
      state_dim_(trajectory.state_dim()),
      dt_(trajectory.dt),
      config_(config),
      checker_(kinematics::MakeRobot(trajectory.robot, "rrt_connect: robot"), trajectory.dt, check) {
  body_ = checker_.body();
  const int64_t J = checker_.robot().num_joints();
  if (state_dim_ != J && state_dim_ != 2 * J) {
    throw Error("rrt_connect: states of " + std::to_string(state_dim_) + " dimensions; expected J = " +
                std::to_string(J) + " positions or 2J = " + std::to_string(2 * J) + " positions and velocities");
  }
  if (horizon_ < 2) throw Error("rrt_connect: expected a horizon of at least 2 states");
  const auto& d = checker_.robot().description();
  double diagonal = 0.0;
  for (int64_t j = 0; j < J; ++j) {
    if (!std::isfinite(d.joint_lower[j]) || !std::isfinite(d.joint_upper[j]) || d.joint_lower[j] >= d.joint_upper[j]) {
      throw Error("rrt_connect: joint " + d.JointName(static_cast<int>(j)) + " of robot \"" + d.name +
                  "\" has no finite range to sample in");
    }
    diagonal += (d.joint_upper[j] - d.joint_lower[j]) * (d.joint_upper[j] - d.joint_lower[j]);
  }
  range_ = config_.range > 0.0 ? config_.range : 0.2 * std::sqrt(diagonal);
}

planning::PlanResult RrtConnectPlanner::Plan(const planning::PlanRequest& request) const {
  return PlanAlong(request, torch::Tensor());
}

planning::PlanResult RrtConnectPlanner::PlanAlong(const planning::PlanRequest& request, const torch::Tensor& guides,
                                                  int64_t max_iterations) const {
  const auto called = Clock::now();
  const int64_t iterations = max_iterations > 0 ? max_iterations : config_.max_iterations;
  planning::CheckEnds(request.start, request.goal, state_dim_, "plan");
  const int64_t B = request.start.size(0), J = checker_.robot().num_joints(), T = horizon_;
  if (guides.defined() && (guides.dim() != 3 || guides.size(0) != B || guides.size(1) < 2 ||
                           guides.size(2) != state_dim_)) {
    std::ostringstream shape;
    shape << guides.sizes();
    throw Error("rrt_connect: guide paths of shape " + shape.str() + "; expected (" + std::to_string(B) +
                ", T >= 2, " + std::to_string(state_dim_) + ")");
  }
  geometry::CheckRows(request.scene, static_cast<int>(checker_.robot().workspace_dim()), "plan");
  const collision::Checker world = checker_.ConfigurationChecker(request.scene, request.world);
  const auto& d = checker_.robot().description();
  const std::vector<double>& lower = d.joint_lower;
  const std::vector<double>& upper = d.joint_upper;
  const Search search(world, lower, upper, range_);
  planning::PlanResult result;
  result.plans = torch::empty({B, T, state_dim_}, torch::kFloat32);
  result.found = torch::zeros({B}, torch::kBool);
  result.call_seconds.assign(static_cast<size_t>(B), 0.0);
  result.call_plans.assign(static_cast<size_t>(B), 1);
  result.refused.assign(static_cast<size_t>(B), false);
  result.failure.assign(static_cast<size_t>(B), "");
  if (guides.defined()) result.route.assign(static_cast<size_t>(B), "unseeded");
  const torch::Tensor starts = request.start.slice(1, 0, J).to(torch::kFloat64).contiguous();
  const torch::Tensor goals = request.goal.slice(1, 0, J).to(torch::kFloat64).contiguous();
  const torch::Tensor guide_q =
      guides.defined() ? guides.slice(2, 0, J).to(torch::kFloat64).contiguous() : torch::Tensor();
  auto clamp = [&](Config q) {
    for (int64_t j = 0; j < J; ++j) q[j] = std::clamp(q[j], lower[j], upper[j]);
    return q;
  };
  const size_t max_points = static_cast<size_t>(std::max<int64_t>(2, (T + 1) / 2));
  // Each plan's time counts an equal share of this preparation, as a batch's plans share a learned planner's call.
  const double prepared =
      std::chrono::duration<double>(Clock::now() - called).count() / static_cast<double>(std::max<int64_t>(B, 1));
  for (int64_t b = 0; b < B; ++b) {
    const auto began = Clock::now();
    const Budget budget{iterations,
                        began + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(config_.time_limit))};
    const uint64_t seed = StreamSeed(request.seed, static_cast<uint64_t>(b));
    const Config start_raw(starts.data_ptr<double>() + b * J, starts.data_ptr<double>() + (b + 1) * J);
    const Config goal_raw(goals.data_ptr<double>() + b * J, goals.data_ptr<double>() + (b + 1) * J);
    // Ends within limit_tolerance of a limit are planned from the limit.
    const Config start = clamp(start_raw), goal = clamp(goal_raw);
    Path points = {start, goal};  // the straight line unless a path is found
    std::string refusal = checker_.Refusal("start", start_raw, world);
    if (refusal.empty()) refusal = checker_.Refusal("goal", goal_raw, world);
    std::optional<Path> path;
    bool seeded = false;
    if (!refusal.empty()) {
      result.refused[static_cast<size_t>(b)] = true;
      result.failure[static_cast<size_t>(b)] = refusal;
    } else {
      // The stretches of the guide kept at either end: head[0] = start, tail.back() = goal; RRT-Connect joins
      // head.back() to tail.front().
      Path head = {start}, tail = {goal};
      if (guide_q.defined() && torch::isfinite(guide_q[b]).all().item<bool>()) {
        const int64_t G = guide_q.size(1);
        const double* g = guide_q.data_ptr<double>() + b * G * J;
        Path line = {start};
        for (int64_t k = 1; k + 1 < G; ++k) line.push_back(clamp(Config(g + k * J, g + (k + 1) * J)));
        line.push_back(goal);
        const size_t M = line.size();
        std::vector<bool> valid_point(M, true);
        for (size_t k = 1; k + 1 < M; ++k) valid_point[k] = world.Valid(line[k].data());
        auto joins = [&](size_t k) {  // the motion line[k] -> line[k + 1], both ends valid
          return valid_point[k] && valid_point[k + 1] && search.Motion(line[k].data(), line[k + 1].data());
        };
        size_t first_gap = 0;
        while (first_gap + 1 < M && joins(first_gap)) ++first_gap;
        if (first_gap + 1 == M) {  // the whole polyline is valid: nothing to join
          head = line;
          tail.clear();
        } else {
          size_t last_gap = M - 1;
          while (last_gap > first_gap + 1 && joins(last_gap - 1)) --last_gap;
          head.assign(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(first_gap) + 1);
          tail.assign(line.begin() + static_cast<std::ptrdiff_t>(last_gap), line.end());
        }
      }
      seeded = head.size() > 1 || tail.size() != 1;  // something of the guide is kept
      if (tail.empty()) {
        path = head;
      } else if (const auto joined = search.Connect(head.back(), tail.front(), StreamSeed(seed, 2), budget)) {
        Path whole(head.begin(), head.end() - 1);
        whole.insert(whole.end(), joined->begin(), joined->end());
        whole.insert(whole.end(), tail.begin() + 1, tail.end());
        path = std::move(whole);
      } else if (seeded) {
        // The guide's ends can lead into places hard to leave: search from the start to the goal as unseeded.
        seeded = false;
        path = search.Connect(start, goal, StreamSeed(seed, 2), budget);
      }
      if (!path) {
        result.failure[static_cast<size_t>(b)] =
            "RRT-Connect found no path within " + std::to_string(iterations) + " iterations or " +
            fmt::format("{:g} s", config_.time_limit);
        if (config_.attempts > 1) {
          result.failure[static_cast<size_t>(b)] += " (" + std::to_string(iterations) + " iterations in each of up to " +
                                                    std::to_string(config_.attempts) + " searches)";
        }
      }
    }
    if (guides.defined()) result.route[static_cast<size_t>(b)] = seeded ? "seeded" : "unseeded";
    torch::Tensor states;
    // Simplified, then timed; the plan is found when the plan checker passes it as returned (float32). A rounded
    // path that fails (a state that grazes an obstacle within the motion check's resolution) falls back to the path
    // before rounding. Whether one of the path's candidates passed; `why` says why not.
    auto time_and_check = [&](const Path& found_path, std::string& why) {
      std::vector<Path> candidates;
      if (config_.simplify) {
        const Path tight = search.Tighten(search.Shortcut(found_path), 2);
        candidates.push_back(search.RoundCorners(tight, max_points));
        candidates.push_back(tight);
      }
      candidates.push_back(found_path);
      // Each path timed smoothly first; then, if a motion between states cut a corner of it, with its corners on
      // states.
      for (const Path& candidate : candidates) {
        std::vector<double> flat;
        for (const Config& q : candidate) flat.insert(flat.end(), q.begin(), q.end());
        for (const bool snap : {false, true}) {
          const planning::TimedPath timed = planning::TimePath(flat, J, T, dt_, d.velocity_limit, snap);
          if (snap && !timed.corners_on_states) continue;
          states = planning::StatesOf(timed, J, T, state_dim_).to(torch::kFloat32);
          const validity::PlanVerdict verdict =
              checker_.CheckIn(world, states.unsqueeze(0), request.start[b], request.goal[b], {},
                               /*measure_clearance=*/false)[0];
          if (verdict.valid()) return true;
          if (why.empty()) why = "the timed path fails the plan check: " + verdict.reason;
        }
      }
      return false;
    };
    if (path) {
      std::string why;
      result.found[b] = time_and_check(*path, why);
      result.failure[static_cast<size_t>(b)] = result.found[b].item<bool>() ? "" : why;
    }
    // Further searches, unseeded, each with its own seed and the whole iteration budget, while the time lasts.
    for (int64_t attempt = 1; refusal.empty() && attempt < config_.attempts && !result.found[b].item<bool>() &&
                              Clock::now() < budget.deadline;
         ++attempt) {
      const auto again = search.Connect(start, goal, StreamSeed(seed, 2 + static_cast<uint64_t>(attempt)), budget);
      if (!again) continue;
      std::string why;
      result.found[b] = time_and_check(*again, why);
      path = again;  // the plan returned is this path's, and so is the reason given
      result.failure[static_cast<size_t>(b)] = result.found[b].item<bool>() ? "" : why;
      // A plan found by a further search is unseeded. When none is found, the route stays: a seeded call that
      // fails tells the hybrid to search from the start to the goal without the guide (seed 2, which the further
      // searches here do not use).
      if (guides.defined() && result.found[b].item<bool>()) result.route[static_cast<size_t>(b)] = "unseeded";
    }
    if (!result.found[b].item<bool>()) {
      std::vector<double> flat;
      for (const Config& q : points) flat.insert(flat.end(), q.begin(), q.end());
      if (!path) states = planning::StatesOf(planning::TimePath(flat, J, T, dt_, d.velocity_limit), J, T, state_dim_).to(torch::kFloat32);
    }
    result.plans[b] = states;
    result.call_seconds[static_cast<size_t>(b)] =
        prepared + std::chrono::duration<double>(Clock::now() - began).count();
  }
  return result;
}

}  // namespace flowplan::classical
