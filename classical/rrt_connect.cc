#include "classical/rrt_connect.h"

#include <ompl/base/MotionValidator.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "core/random.h"
#include "planning/time_parametrize.h"

namespace flowplan::classical {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

/// OMPL's uniform sampler with a seed of our own (OMPL seeds every RNG from one global sequence otherwise).
class SeededSampler : public ob::RealVectorStateSampler {
 public:
  SeededSampler(const ob::StateSpace* space, uint64_t seed) : ob::RealVectorStateSampler(space) {
    rng_.setLocalSeed(static_cast<std::uint_fast32_t>(seed));
  }
};

/// RRT-Connect whose own random choices draw from a seed of ours.
class SeededRrtConnect : public og::RRTConnect {
 public:
  SeededRrtConnect(const ob::SpaceInformationPtr& si, uint64_t seed) : og::RRTConnect(si) {
    rng_.setLocalSeed(static_cast<std::uint_fast32_t>(seed));
  }
};

torch::Tensor ToTensor(const ob::State* state, int64_t J) {
  auto* values = state->as<ob::RealVectorStateSpace::StateType>()->values;
  return torch::from_blob(values, {J}, torch::kFloat64).clone();
}

/// The n + 1 states (n + 1, J) of the motion from a to b (J,) a motion check looks at: a, n − 1 between, b.
torch::Tensor MotionStates(const torch::Tensor& a, const torch::Tensor& b, int64_t n) {
  const torch::Tensor s = torch::linspace(0.0, 1.0, n + 1, torch::kFloat64).unsqueeze(1);
  return a + s * (b - a);
}

/// Whether each motion from[p] → to[p] ((P, J) float64) is valid, every motion checked at the states the motion
/// validator checks it at, all of them in one call of `valid` ((M, J) float64 -> (M,) bool): (P) flags.
std::vector<bool> MotionsValid(const ob::StateSpacePtr& space, const torch::Tensor& from, const torch::Tensor& to,
                               const std::function<torch::Tensor(const torch::Tensor&)>& valid) {
  const int64_t P = from.size(0), J = from.size(1);
  std::vector<torch::Tensor> states;
  std::vector<int64_t> counts;
  ob::ScopedState<> s1(space), s2(space);
  const auto fa = from.accessor<double, 2>(), ta = to.accessor<double, 2>();
  for (int64_t p = 0; p < P; ++p) {
    for (int64_t j = 0; j < J; ++j) {
      s1[static_cast<unsigned>(j)] = fa[p][j];
      s2[static_cast<unsigned>(j)] = ta[p][j];
    }
    const int64_t n = std::max<int64_t>(1, space->validSegmentCount(s1.get(), s2.get()));
    states.push_back(MotionStates(from[p], to[p], n));
    counts.push_back(n + 1);
  }
  std::vector<bool> ok(static_cast<size_t>(P), true);
  if (P == 0) return ok;
  const torch::Tensor flags = valid(torch::cat(states));
  const auto f = flags.accessor<bool, 1>();
  int64_t at = 0;
  for (int64_t p = 0; p < P; ++p) {
    for (int64_t k = 0; k < counts[static_cast<size_t>(p)]; ++k) ok[static_cast<size_t>(p)] = ok[static_cast<size_t>(p)] && f[at + k];
    at += counts[static_cast<size_t>(p)];
  }
  return ok;
}

/// Checks a whole motion with one batched validity call over its interpolated states.
class BatchedMotionValidator : public ob::MotionValidator {
 public:
  using ValidFn = std::function<torch::Tensor(const torch::Tensor&)>;  // (M, J) float64 -> (M,) bool
  BatchedMotionValidator(ob::SpaceInformation* si, ValidFn check) : ob::MotionValidator(si), check_(std::move(check)) {}

  bool checkMotion(const ob::State* s1, const ob::State* s2) const override {
    const torch::Tensor ok = Along(s1, s2);
    const bool all = ok.all().item<bool>();
    if (all) ++valid_; else ++invalid_;
    return all;
  }

  bool checkMotion(const ob::State* s1, const ob::State* s2, std::pair<ob::State*, double>& last_valid) const override {
    const torch::Tensor ok = Along(s1, s2);
    const int64_t n = ok.size(0) - 1;  // segments
    const torch::Tensor bad = (~ok).nonzero();
    if (bad.size(0) == 0) {
      ++valid_;
      return true;
    }
    const int64_t first_bad = bad[0][0].item<int64_t>();
    const double fraction = static_cast<double>(std::max<int64_t>(first_bad - 1, 0)) / static_cast<double>(n);
    if (last_valid.first != nullptr) si_->getStateSpace()->interpolate(s1, s2, fraction, last_valid.first);
    last_valid.second = fraction;
    ++invalid_;
    return false;
  }

 private:
  /// Validity of s1, the interpolated states and s2: (n + 1,) bool.
  torch::Tensor Along(const ob::State* s1, const ob::State* s2) const {
    const auto space = si_->getStateSpace();
    const int64_t J = space->getDimension();
    const int64_t n = std::max<int64_t>(1, space->validSegmentCount(s1, s2));
    return check_(MotionStates(ToTensor(s1, J), ToTensor(s2, J), n));
  }
  ValidFn check_;
};

using MotionCheck = std::function<std::vector<bool>(const torch::Tensor&, const torch::Tensor&)>;

/// Deterministic shortcutting of a valid polyline (M, J): from each kept point, jump to the farthest later point
/// the motion to which is valid. The candidates are checked farthest first, in calls of 1, 2, 4, ... of them.
torch::Tensor Shortcut(const torch::Tensor& points, const MotionCheck& motions) {
  const int64_t M = points.size(0);
  if (M < 3) return points;
  std::vector<int64_t> kept = {0};
  int64_t i = 0;
  while (i + 1 < M) {
    int64_t next = i + 1;  // the motion to the next point is valid: the polyline is
    for (int64_t top = M - 1, chunk = 1; top > i + 1 && next == i + 1; top -= chunk, chunk *= 2) {
      const int64_t bottom = std::max(i + 2, top - chunk + 1);  // candidates top, top − 1, ..., bottom
      const torch::Tensor to = points.slice(0, bottom, top + 1).flip(0).contiguous();
      const std::vector<bool> ok = motions(points[i].expand_as(to).contiguous(), to);
      for (size_t c = 0; c < ok.size(); ++c) {
        if (ok[c]) {
          next = top - static_cast<int64_t>(c);
          break;
        }
      }
    }
    kept.push_back(next);
    i = next;
  }
  return points.index({torch::tensor(kept, torch::kInt64)});
}

/// The polyline (M, J) with `parts` − 1 evenly spaced points inserted in every segment: (parts (M − 1) + 1, J).
torch::Tensor Subdivide(const torch::Tensor& points, int64_t parts) {
  const int64_t M = points.size(0);
  if (M < 2) return points;
  const torch::Tensor u = torch::arange(parts, torch::kFloat64).div(static_cast<double>(parts)).view({1, parts, 1});
  const torch::Tensor a = points.slice(0, 0, M - 1).unsqueeze(1), b = points.slice(0, 1, M).unsqueeze(1);
  return torch::cat({(a + u * (b - a)).flatten(0, 1), points.slice(0, M - 1)});
}

/// Shortcutting again through points along the segments, `passes` times: each pass subdivides every segment in
/// four and shortcuts, so the path can leave a vertex part way along a segment and draws tighter around obstacles.
torch::Tensor Tighten(torch::Tensor points, const MotionCheck& motions, int passes) {
  for (int p = 0; p < passes; ++p) points = Shortcut(Subdivide(points, 4), motions);
  return points;
}

/// Chaikin's corner cutting, `iterations` times, of a polyline (M, J): every segment's points at 1/4 and 3/4
/// replace the inner vertices (the first segment's 1/4 point and the last one's 3/4 point are left out); the ends
/// stay. It converges to the quadratic B-spline of the points.
torch::Tensor CutCorners(torch::Tensor points, int iterations) {
  for (int k = 0; k < iterations && points.size(0) > 2; ++k) {
    const int64_t M = points.size(0);
    const torch::Tensor a = points.slice(0, 0, M - 1), b = points.slice(0, 1, M);
    const torch::Tensor inner = torch::stack({0.75 * a + 0.25 * b, 0.25 * a + 0.75 * b}, 1).flatten(0, 1);  // (2(M−1), J)
    points = torch::cat({points.slice(0, 0, 1), inner.slice(0, 1, inner.size(0) - 1), points.slice(0, M - 1)});
  }
  return points;
}

/// The valid polyline (M, J) with its corners rounded: Chaikin's corner cutting with the most iterations, of
/// kSmoothing down to one, whose polyline is valid as a whole (checked in one call each); the polyline itself if none.
torch::Tensor RoundCorners(const torch::Tensor& points, const MotionCheck& motions) {
  constexpr int kSmoothing = 4;
  if (points.size(0) < 3) return points;
  for (int iterations = kSmoothing; iterations >= 1; --iterations) {
    const torch::Tensor rounded = CutCorners(points, iterations);
    const int64_t M = rounded.size(0);
    const std::vector<bool> ok = motions(rounded.slice(0, 0, M - 1).contiguous(), rounded.slice(0, 1, M).contiguous());
    if (std::all_of(ok.begin(), ok.end(), [](bool v) { return v; })) return rounded;
  }
  return points;
}

void QuietOmpl() {
  static std::once_flag once;
  std::call_once(once, [] { ompl::msg::setLogLevel(ompl::msg::LOG_WARN); });
}

}  // namespace

RrtConnectPlanner::RrtConnectPlanner(const kinematics::TrajectoryInfo& trajectory, RrtConnectConfig config,
                                     validity::ConfigurationCheck configuration_check)
    : robot_(kinematics::MakeRobot(trajectory.robot, "rrt_connect: robot")),
      horizon_(trajectory.horizon),
      state_dim_(trajectory.state_dim()),
      dt_(trajectory.dt),
      config_(config),
      configuration_check_(std::move(configuration_check)) {
  const int64_t J = robot_->num_joints();
  if (state_dim_ != J && state_dim_ != 2 * J) {
    throw Error("rrt_connect: states of " + std::to_string(state_dim_) + " dimensions; expected J = " +
                std::to_string(J) + " positions or 2J = " + std::to_string(2 * J) + " positions and velocities");
  }
  if (horizon_ < 2) throw Error("rrt_connect: expected a horizon of at least 2 states");
  if (!(dt_ > 0.0)) throw Error("rrt_connect: expected a positive dt");
  const auto& d = robot_->description();
  for (int64_t j = 0; j < J; ++j) {
    if (!std::isfinite(d.joint_lower[j]) || !std::isfinite(d.joint_upper[j]) || d.joint_lower[j] >= d.joint_upper[j]) {
      throw Error("rrt_connect: joint " + std::to_string(j) + " of robot \"" + d.name +
                  "\" has no finite range to sample in");
    }
  }
  QuietOmpl();
}

torch::Tensor RrtConnectPlanner::Valid(const torch::Tensor& q, const geometry::SceneRows& scene) const {
  const int64_t M = q.size(0), J = q.size(1);
  torch::Tensor valid =
      geometry::CountObstacles(scene) == 0
          ? torch::ones({M}, torch::kBool)
          : std::get<0>(robot_->NearestObstacles(q, scene).clearance.min(1)) >= config_.margin;
  if (configuration_check_) {
    const torch::Tensor q64 = q.to(torch::kFloat64).contiguous();
    const double* values = q64.data_ptr<double>();
    for (int64_t m = 0; m < M; ++m) {
      if (valid[m].item<bool>() && !configuration_check_(std::vector<double>(values + m * J, values + (m + 1) * J)).empty()) {
        valid[m] = false;
      }
    }
  }
  return valid;
}

planning::PlanResult RrtConnectPlanner::Plan(const planning::PlanRequest& request) const {
  return PlanAlong(request, torch::Tensor());
}

planning::PlanResult RrtConnectPlanner::PlanAlong(const planning::PlanRequest& request,
                                                  const torch::Tensor& guides) const {
  planning::CheckEnds(request.start, request.goal, state_dim_, "plan");
  const int64_t B = request.start.size(0), J = robot_->num_joints(), T = horizon_;
  if (guides.defined() && (guides.dim() != 3 || guides.size(0) != B || guides.size(1) < 2 ||
                           guides.size(2) != state_dim_)) {
    std::ostringstream shape;
    shape << guides.sizes();
    throw Error("rrt_connect: guide paths of shape " + shape.str() + "; expected (" + std::to_string(B) +
                ", T >= 2, " + std::to_string(state_dim_) + ")");
  }
  geometry::CheckRows(request.scene, static_cast<int>(robot_->workspace_dim()), "plan");
  geometry::SceneRows scene;
  for (const auto& entry : request.scene) scene.insert(entry.key(), entry.value().to(torch::kFloat64));
  scene = geometry::PreparedRows(scene, static_cast<int>(robot_->workspace_dim()));  // once for every check
  torch::NoGradGuard no_grad;
  const auto& d = robot_->description();
  planning::PlanResult result;
  result.plans = torch::empty({B, T, state_dim_}, torch::kFloat32);
  result.found = torch::zeros({B}, torch::kBool);
  result.call_seconds.assign(static_cast<size_t>(B), 0.0);
  result.call_plans.assign(static_cast<size_t>(B), 1);
  if (guides.defined()) result.route.assign(static_cast<size_t>(B), "unseeded");
  // Ends exactly at a limit can round to just outside it in float32: clamp them onto the limits.
  const torch::Tensor lower = torch::tensor(d.joint_lower, torch::kFloat64).slice(0, 0, J);
  const torch::Tensor upper = torch::tensor(d.joint_upper, torch::kFloat64).slice(0, 0, J);
  const torch::Tensor start_q = torch::max(torch::min(request.start.slice(1, 0, J).to(torch::kFloat64), upper), lower);
  const torch::Tensor goal_q = torch::max(torch::min(request.goal.slice(1, 0, J).to(torch::kFloat64), upper), lower);
  for (int64_t b = 0; b < B; ++b) {
    const auto began = std::chrono::steady_clock::now();
    const uint64_t seed = StreamSeed(request.seed, static_cast<uint64_t>(b));
    auto space = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned>(J));
    ob::RealVectorBounds bounds(static_cast<unsigned>(J));
    for (int64_t j = 0; j < J; ++j) {
      bounds.setLow(static_cast<unsigned>(j), d.joint_lower[j]);
      bounds.setHigh(static_cast<unsigned>(j), d.joint_upper[j]);
    }
    space->setBounds(bounds);
    space->setStateSamplerAllocator(
        [seed](const ob::StateSpace* s) { return std::make_shared<SeededSampler>(s, StreamSeed(seed, 1)); });
    auto si = std::make_shared<ob::SpaceInformation>(space);
    auto valid = [this, scene](const torch::Tensor& q) { return Valid(q, scene); };
    si->setStateValidityChecker([&](const ob::State* s) {
      return space->satisfiesBounds(s) && valid(ToTensor(s, J).unsqueeze(0))[0].item<bool>();
    });
    si->setStateValidityCheckingResolution(config_.resolution);
    si->setMotionValidator(std::make_shared<BatchedMotionValidator>(si.get(), valid));
    si->setup();
    const MotionCheck motions = [&](const torch::Tensor& from, const torch::Tensor& to) {
      return MotionsValid(space, from, to, valid);
    };

    torch::Tensor points = torch::stack({start_q[b], goal_q[b]});  // the straight line unless a path is found
    const torch::Tensor ends_valid = valid(points);
    if (ends_valid.all().item<bool>()) {
      auto state = [&](const torch::Tensor& q) {  // (J,) float64
        ob::ScopedState<> s(space);
        for (int64_t j = 0; j < J; ++j) s[static_cast<unsigned>(j)] = q[j].item<double>();
        return s;
      };
      // The stretches of the guide kept at either end: head[0] = start, tail.back() = goal; RRT-Connect joins
      // head.back() to tail.front().
      std::vector<torch::Tensor> head = {start_q[b]}, tail = {goal_q[b]};
      if (guides.defined() && torch::isfinite(guides[b]).all().item<bool>()) {
        const torch::Tensor g = torch::max(torch::min(guides[b].slice(1, 0, J).to(torch::kFloat64), upper), lower);
        std::vector<torch::Tensor> line = {start_q[b]};
        for (int64_t k = 1; k + 1 < g.size(0); ++k) line.push_back(g[k]);
        line.push_back(goal_q[b]);
        const size_t M = line.size();
        // Whether the motion from line[k] to line[k + 1] is valid, for every k in one call; the guide is kept up
        // to its first invalid motion from either end.
        const torch::Tensor polyline = torch::stack(line);
        const std::vector<bool> joins = motions(polyline.slice(0, 0, static_cast<int64_t>(M) - 1).contiguous(),
                                                polyline.slice(0, 1, static_cast<int64_t>(M)).contiguous());
        size_t first_gap = 0, last_gap = M - 1;
        while (first_gap + 1 < M && joins[first_gap]) ++first_gap;
        if (first_gap + 1 < M) {
          while (last_gap > first_gap + 1 && joins[last_gap - 1]) --last_gap;
        }
        if (first_gap + 1 == M) {  // the whole polyline is valid: nothing to join
          head = line;
          tail.clear();
        } else {
          head.assign(line.begin(), line.begin() + static_cast<std::ptrdiff_t>(first_gap) + 1);
          tail.assign(line.begin() + static_cast<std::ptrdiff_t>(last_gap), line.end());
        }
      }
      // RRT-Connect from `from` to `to` (J,), within max_iterations and what is left of the plan's time_limit.
      auto search = [&](const torch::Tensor& from, const torch::Tensor& to) -> std::optional<og::PathGeometric> {
        auto problem = std::make_shared<ob::ProblemDefinition>(si);
        problem->setStartAndGoalStates(state(from), state(to));
        auto planner = std::make_shared<SeededRrtConnect>(si, StreamSeed(seed, 2));
        if (config_.range > 0.0) planner->setRange(config_.range);
        planner->setProblemDefinition(problem);
        planner->setup();
        int64_t calls = 0;
        const ob::PlannerTerminationCondition stop([&] {
          return ++calls > config_.max_iterations ||
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count() > config_.time_limit;
        });
        if (planner->solve(stop) != ob::PlannerStatus::EXACT_SOLUTION) return std::nullopt;
        return *problem->getSolutionPath()->as<og::PathGeometric>();
      };
      std::optional<og::PathGeometric> path;
      bool seeded = head.size() > 1 || tail.size() != 1;  // something of the guide is kept
      if (tail.empty()) {
        path.emplace(si);
        for (const torch::Tensor& q : head) path->append(state(q).get());
      } else if (const auto found = search(head.back(), tail.front())) {
        path.emplace(si);
        for (size_t k = 0; k + 1 < head.size(); ++k) path->append(state(head[k]).get());
        for (unsigned k = 0; k < found->getStateCount(); ++k) path->append(found->getState(k));
        for (size_t k = 1; k < tail.size(); ++k) path->append(state(tail[k]).get());
      } else if (seeded) {
        // The guide's ends can lead into places hard to leave (a narrow gap the guide pushed into): search from
        // the start to the goal as unseeded.
        seeded = false;
        path = search(start_q[b], goal_q[b]);
      }
      if (guides.defined()) result.route[static_cast<size_t>(b)] = seeded ? "seeded" : "unseeded";
      if (path) {
        std::vector<torch::Tensor> rows;
        for (const ob::State* s : path->getStates()) rows.push_back(ToTensor(s, J));
        points = torch::stack(rows);
        if (config_.simplify) points = RoundCorners(Tighten(Shortcut(points, motions), motions, 2), motions);
        result.found[b] = true;
      }
    }
    result.plans[b] = planning::TimedStates(points, T, dt_, state_dim_).to(torch::kFloat32);
    result.call_seconds[static_cast<size_t>(b)] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  }
  return result;
}

}  // namespace flowplan::classical
