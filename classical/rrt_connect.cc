#include "classical/rrt_connect.h"

#include <ompl/base/MotionValidator.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ProblemDefinition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

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
    const torch::Tensor a = ToTensor(s1, J), b = ToTensor(s2, J);
    const torch::Tensor s = torch::linspace(0.0, 1.0, n + 1, torch::kFloat64).unsqueeze(1);
    return check_(a + s * (b - a));
  }
  ValidFn check_;
};

/// Deterministic shortcutting: from each kept state, jump to the farthest later state in view.
void Shortcut(og::PathGeometric& path, const ob::SpaceInformationPtr& si) {
  std::vector<ob::State*>& states = path.getStates();
  if (states.size() < 3) return;
  std::vector<ob::State*> kept = {states.front()};
  size_t i = 0;
  std::vector<bool> keep(states.size(), false);
  keep[0] = true;
  while (i + 1 < states.size()) {
    size_t j = states.size() - 1;
    while (j > i + 1 && !si->checkMotion(states[i], states[j])) --j;
    keep[j] = true;
    i = j;
  }
  std::vector<ob::State*> reduced;
  for (size_t k = 0; k < states.size(); ++k) {
    if (keep[k]) {
      reduced.push_back(states[k]);
    } else {
      si->freeState(states[k]);
    }
  }
  states = reduced;
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
  torch::Tensor valid = geometry::CountObstacles(scene) == 0 ? torch::ones({M}, torch::kBool)
                                                             : (robot_->Clearance(q, scene) >= config_.margin).all(1);
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
        // Whether the motion from line[k] to line[k + 1] is valid; only the motions up to the first invalid one
        // from either end are checked.
        auto joins = [&](size_t k) { return si->checkMotion(state(line[k]).get(), state(line[k + 1]).get()); };
        size_t first_gap = 0, last_gap = M - 1;
        while (first_gap + 1 < M && joins(first_gap)) ++first_gap;
        if (first_gap + 1 < M) {
          while (last_gap > first_gap + 1 && joins(last_gap - 1)) --last_gap;
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
        if (config_.simplify) {
          Shortcut(*path, si);
          og::PathSimplifier(si).smoothBSpline(*path, 5);
        }
        std::vector<torch::Tensor> rows;
        for (const ob::State* s : path->getStates()) rows.push_back(ToTensor(s, J));
        points = torch::stack(rows);
        result.found[b] = true;
      }
    }
    auto [q, v] = planning::TimeAlongPath(points, T, dt_);
    result.plans[b] = (state_dim_ == J ? q : torch::cat({q, v}, 1)).to(torch::kFloat32);
    result.call_seconds[static_cast<size_t>(b)] =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  }
  return result;
}

}  // namespace flowplan::classical
