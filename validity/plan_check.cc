#include "validity/plan_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <spdlog/fmt/fmt.h>

#include "core/error.h"
#include "core/format.h"

namespace flowplan::validity {
namespace {

/// (N, J) float64 positions of a state (D,) or states (N, D) named `name`.
torch::Tensor Positions(const torch::Tensor& state, int64_t N, int64_t J, int64_t D, const std::string& name) {
  const bool one = state.dim() == 1 && state.size(0) == D;
  const bool each = state.dim() == 2 && state.size(0) == N && state.size(1) == D;
  if (!one && !each) {
    throw Error("check: " + name + ": expected (" + std::to_string(D) + ") or (" + std::to_string(N) + ", " +
                std::to_string(D) + "), got " + ShapeText(state.sizes().vec()));
  }
  const torch::Tensor q = state.to(torch::kFloat64).slice(-1, 0, J);
  return one ? q.view({1, J}).expand({N, J}) : q;
}

/// A number in a reason: 4 significant digits.
std::string Num(double v) { return fmt::format("{:.4g}", v); }

}  // namespace

PlanChecker::PlanChecker(std::shared_ptr<const kinematics::Robot> robot, double dt, CheckConfig config)
    : robot_(std::move(robot)),
      body_(std::make_shared<const collision::BodyModel>(robot_->description(), "check: robot")),
      dt_(dt),
      config_(config) {
  if (!(dt > 0)) throw Error("check: dt: expected a positive sample spacing, got " + Num(dt));
  if (!(config.joint_tolerance > 0)) throw Error("check.joint_tolerance: expected a positive tolerance");
  if (!(config.max_speed_ratio > 0)) throw Error("check.max_speed_ratio: expected a positive ratio");
  if (!(config.margin >= 0)) throw Error("check.margin: expected a non-negative margin");
  if (!(config.resolution > 0)) throw Error("check.resolution: expected a positive resolution");
  if (!(config.limit_tolerance >= 0)) throw Error("check.limit_tolerance: expected a non-negative tolerance");
}

collision::Checker PlanChecker::ConfigurationChecker(const geometry::SceneRows& scene,
                                                     const collision::WorldOptions& options,
                                                     std::vector<std::string> names) const {
  const double height = options.floor_height.value_or(config_.floor_height);
  collision::Floor floor;
  floor.present = std::isfinite(height);
  floor.height = floor.present ? height : 0.0;
  auto world = std::make_shared<const collision::World>(scene, static_cast<int>(robot_->workspace_dim()), floor,
                                                        std::move(names), "check: scene");
  auto body = options.held.empty() ? body_
                                   : std::make_shared<const collision::BodyModel>(
                                         collision::WithHeld(robot_->description(), options.held), "check: robot");
  return collision::Checker(std::move(body), std::move(world), {config_.margin, config_.resolution});
}

std::string PlanChecker::Refusal(const std::string& what, const std::vector<double>& q,
                                 const collision::Checker& checker) const {
  const kinematics::RobotDescription& d = robot_->description();
  for (size_t j = 0; j < q.size(); ++j) {
    if (!std::isfinite(q[j])) return what + ": " + d.JointName(static_cast<int>(j)) + " is not a finite number";
    const double below = d.joint_lower[j] - q[j], above = q[j] - d.joint_upper[j];
    if (below > config_.limit_tolerance || above > config_.limit_tolerance) {
      const bool low = below > 0;
      return what + ": " + d.JointName(static_cast<int>(j)) + " = " + fmt::format("{:.7g}", q[j]) + " is " +
             Num(low ? below : above) + " past its " + (low ? "lower" : "upper") + " limit " +
             fmt::format("{:.7g}", low ? d.joint_lower[j] : d.joint_upper[j]);
    }
  }
  // Within the tolerance of a limit: judged on the limit.
  std::vector<double> at = q;
  for (size_t j = 0; j < q.size(); ++j) at[j] = std::clamp(q[j], d.joint_lower[j], d.joint_upper[j]);
  const collision::Contact contact = checker.FirstContact(at.data());
  return contact.found() ? what + ": " + checker.Describe(contact) : std::string();
}

std::vector<PlanVerdict> PlanChecker::Check(const torch::Tensor& plans, const torch::Tensor& start,
                                            const torch::Tensor& goal, const geometry::SceneRows& scene,
                                            const torch::Tensor& found, const collision::WorldOptions& world,
                                            bool measure_clearance) const {
  return CheckIn(ConfigurationChecker(scene, world), plans, start, goal, found, measure_clearance);
}

std::vector<PlanVerdict> PlanChecker::CheckIn(const collision::Checker& checker, const torch::Tensor& plans,
                                              const torch::Tensor& start, const torch::Tensor& goal,
                                              const torch::Tensor& found, bool measure_clearance) const {
  const kinematics::RobotDescription& robot = robot_->description();
  const int64_t J = robot_->num_joints();
  if (!plans.defined() || plans.dim() != 3 || plans.size(2) < J) {
    throw Error("check: plans: expected (N, T, D) with D >= " + std::to_string(J) + ", got " +
                (plans.defined() ? ShapeText(plans.sizes().vec()) : "(undefined)"));
  }
  const int64_t N = plans.size(0), T = plans.size(1), D = plans.size(2);
  if (found.defined() && (found.dim() != 1 || found.size(0) != N)) {
    throw Error("check: found: expected (" + std::to_string(N) + "), got " + ShapeText(found.sizes().vec()));
  }
  const torch::Tensor q = plans.to(torch::kFloat64).slice(2, 0, J).contiguous();  // (N, T, J)
  const torch::Tensor start_q = Positions(start, N, J, D, "start").contiguous();
  const torch::Tensor goal_q = Positions(goal, N, J, D, "goal").contiguous();
  const torch::Tensor finite = torch::isfinite(plans.to(torch::kFloat64)).flatten(1).all(1);  // (N,)
  const torch::Tensor found_cpu = found.defined() ? found.to(torch::kCPU, torch::kBool).contiguous() : torch::Tensor();
  const double* qa = q.data_ptr<double>();
  const double* sa = start_q.data_ptr<double>();
  const double* ga = goal_q.data_ptr<double>();
  const bool* fa = finite.data_ptr<bool>();
  std::vector<PlanVerdict> verdicts(static_cast<size_t>(N));
  auto label = [&](int64_t j) { return robot.JointName(static_cast<int>(j)); };
  const double tolerance = config_.limit_tolerance;
  for (int64_t n = 0; n < N; ++n) {
    PlanVerdict& v = verdicts[static_cast<size_t>(n)];
    auto fail = [&](Failure failure, const std::string& reason) {
      if (v.failure == Failure::kNone) {
        v.failure = failure;
        v.reason = reason;
      }
    };
    const double* plan = qa + n * T * J;
    auto at = [&](int64_t t, int64_t j) { return plan[t * J + j]; };
    if (found_cpu.defined() && !found_cpu.data_ptr<bool>()[n]) fail(Failure::kNotFound, "the planner found no plan");
    if (!fa[n]) fail(Failure::kNotFinite, "a state holds NaN or an infinity");
    for (int64_t j = 0; j < J; ++j) {
      const double e = std::abs(at(0, j) - sa[n * J + j]);
      if (e > config_.joint_tolerance) fail(Failure::kStart, "state 0 is " + Num(e) + " from the start at " + label(j));
    }
    for (int64_t j = 0; j < J; ++j) {
      const double e = std::abs(at(T - 1, j) - ga[n * J + j]);
      if (e > config_.joint_tolerance) {
        fail(Failure::kGoal, "state " + std::to_string(T - 1) + " is " + Num(e) + " from the goal at " + label(j));
      }
    }
    for (int64_t t = 0; t < T; ++t) {
      for (int64_t j = 0; j < J; ++j) {
        const double outside = std::max(robot.joint_lower[j] - at(t, j), at(t, j) - robot.joint_upper[j]);
        if (outside > tolerance) {
          fail(Failure::kJointLimit, "state " + std::to_string(t) + ": " + label(j) + " is " + Num(outside) +
                                         " outside its limits");
        }
      }
    }
    if (!robot.velocity_limit.empty()) {
      for (int64_t t = 0; t + 1 < T; ++t) {
        for (int64_t j = 0; j < J; ++j) {
          const double ratio = std::abs(at(t + 1, j) - at(t, j)) / dt_ / robot.velocity_limit[j];
          if (ratio > config_.max_speed_ratio) {
            fail(Failure::kSpeedLimit, "states " + std::to_string(t) + "-" + std::to_string(t + 1) + ": " + label(j) +
                                           " moves at " + Num(ratio) + " x its speed limit");
          }
        }
      }
    }
    if (!fa[n]) {
      v.clearance = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    // The states, each judged at its nearest point within the limits (a state within limit_tolerance of a
    // limit is at it), then the motions between them.
    std::vector<double> states(static_cast<size_t>(T * J));
    for (int64_t t = 0; t < T; ++t) {
      for (int64_t j = 0; j < J; ++j) {
        states[static_cast<size_t>(t * J + j)] = std::clamp(at(t, j), robot.joint_lower[j], robot.joint_upper[j]);
      }
    }
    double smallest = std::numeric_limits<double>::infinity();
    for (int64_t t = 0; t < T && measure_clearance; ++t) {
      smallest = std::min(smallest, checker.Clearance(&states[static_cast<size_t>(t * J)]));
    }
    v.clearance = measure_clearance ? smallest : std::numeric_limits<double>::quiet_NaN();
    if (!v.valid()) continue;
    const collision::PathVerdict path = checker.CheckPath(states.data(), static_cast<int>(T));
    v.motion_checks += path.checks;
    if (path.state >= 0) {
      const collision::Contact& contact = path.state_contact;
      const Failure failure = contact.kind == collision::Contact::Kind::kSelf    ? Failure::kSelf
                              : contact.kind == collision::Contact::Kind::kFloor ? Failure::kFloor
                                                                                  : Failure::kCollision;
      fail(failure, "state " + std::to_string(path.state) + ": " + checker.Describe(contact));
    } else if (path.motion >= 0) {
      fail(Failure::kMotion, "between states " + std::to_string(path.motion) + " and " +
                                 std::to_string(path.motion + 1) + ": " +
                                 checker.Describe(path.motion_verdict.contact));
    }
  }
  return verdicts;
}

}  // namespace flowplan::validity
