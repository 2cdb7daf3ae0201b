#include "validity/plan_check.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

PlanChecker::PlanChecker(std::shared_ptr<const kinematics::Robot> robot, double dt, CheckConfig config,
                         ConfigurationCheck self_check)
    : robot_(std::move(robot)),
      dt_(dt),
      config_(config),
      self_check_(std::move(self_check)),
      motion_bound_(robot_->MotionBound()) {
  if (!(dt > 0)) throw Error("check: dt: expected a positive sample spacing, got " + Num(dt));
  if (!(config.joint_tolerance > 0)) throw Error("check.joint_tolerance: expected a positive tolerance");
  if (!(config.max_speed_ratio > 0)) throw Error("check.max_speed_ratio: expected a positive ratio");
  if (!(config.margin >= 0)) throw Error("check.margin: expected a non-negative margin");
  if (!(config.resolution > 0)) throw Error("check.resolution: expected a positive resolution");
  if (!(config.self_resolution > 0)) throw Error("check.self_resolution: expected a positive resolution");
}

std::vector<PlanVerdict> PlanChecker::Check(const torch::Tensor& plans, const torch::Tensor& start,
                                            const torch::Tensor& goal, const geometry::SceneRows& scene,
                                            const torch::Tensor& found) const {
  const kinematics::RobotDescription& robot = robot_->description();
  const int64_t J = robot_->num_joints();
  if (!plans.defined() || plans.dim() != 3 || plans.size(2) < J) {
    throw Error("check: plans: expected (N, T, D) with D >= " + std::to_string(J) + ", got " +
                (plans.defined() ? ShapeText(plans.sizes().vec()) : "(undefined)"));
  }
  const int64_t N = plans.size(0), T = plans.size(1), D = plans.size(2), S = robot_->num_spheres();
  if (found.defined() && (found.dim() != 1 || found.size(0) != N)) {
    throw Error("check: found: expected (" + std::to_string(N) + "), got " + ShapeText(found.sizes().vec()));
  }
  const torch::Tensor q = plans.to(torch::kFloat64).slice(2, 0, J).contiguous();  // (N, T, J)
  const torch::Tensor start_q = Positions(start, N, J, D, "start"), goal_q = Positions(goal, N, J, D, "goal");
  std::vector<PlanVerdict> verdicts(static_cast<size_t>(N));
  auto fail = [&](int64_t n, Failure failure, const std::string& reason) {
    PlanVerdict& v = verdicts[static_cast<size_t>(n)];
    if (v.failure == Failure::kNone) {
      v.failure = failure;
      v.reason = reason;
    }
  };
  auto label = [&](int64_t j) { return "joint " + std::to_string(j + 1); };

  // Start, goal, joint limits, speeds: per plan, the first offence.
  const torch::Tensor start_error = (q.select(1, 0) - start_q).abs();     // (N, J)
  const torch::Tensor goal_error = (q.select(1, T - 1) - goal_q).abs();   // (N, J)
  const torch::Tensor lower = torch::tensor(robot.joint_lower, torch::kFloat64).view({1, 1, J});
  const torch::Tensor upper = torch::tensor(robot.joint_upper, torch::kFloat64).view({1, 1, J});
  const torch::Tensor outside = torch::max(lower - q, q - upper);        // (N, T, J) > 0 outside
  torch::Tensor speed_ratio = torch::zeros({N, std::max<int64_t>(T - 1, 0), J}, torch::kFloat64);
  if (!robot.velocity_limit.empty() && T > 1) {
    const torch::Tensor limit = torch::tensor(robot.velocity_limit, torch::kFloat64).view({1, 1, J});
    speed_ratio = (q.slice(1, 1, T) - q.slice(1, 0, T - 1)).abs() / dt_ / limit;
  }
  const auto se = start_error.accessor<double, 2>(), ge = goal_error.accessor<double, 2>();
  const auto out = outside.accessor<double, 3>(), sr = speed_ratio.accessor<double, 3>();
  const torch::Tensor finite = torch::isfinite(plans.to(torch::kFloat64)).flatten(1).all(1);  // (N,)
  for (int64_t n = 0; n < N; ++n) {
    if (found.defined() && !found[n].item<bool>()) fail(n, Failure::kNotFound, "the planner found no plan");
    if (!finite[n].item<bool>()) fail(n, Failure::kNotFinite, "a state holds NaN or an infinity");
    for (int64_t j = 0; j < J; ++j) {
      if (se[n][j] > config_.joint_tolerance) {
        fail(n, Failure::kStart, "state 0 is " + Num(se[n][j]) + " from the start at " + label(j));
      }
    }
    for (int64_t j = 0; j < J; ++j) {
      if (ge[n][j] > config_.joint_tolerance) {
        fail(n, Failure::kGoal, "state " + std::to_string(T - 1) + " is " + Num(ge[n][j]) + " from the goal at " +
                                    label(j));
      }
    }
    for (int64_t t = 0; t < T; ++t) {
      for (int64_t j = 0; j < J; ++j) {
        if (out[n][t][j] > 0) {
          fail(n, Failure::kJointLimit, "state " + std::to_string(t) + ": " + label(j) + " is " + Num(out[n][t][j]) +
                                            " outside its limits");
        }
      }
    }
    for (int64_t t = 0; t + 1 < T; ++t) {
      for (int64_t j = 0; j < J; ++j) {
        if (sr[n][t][j] > config_.max_speed_ratio) {
          fail(n, Failure::kSpeedLimit, "states " + std::to_string(t) + "-" + std::to_string(t + 1) + ": " + label(j) +
                                            " moves at " + Num(sr[n][t][j]) + " x its speed limit");
        }
      }
    }
  }

  // The configuration check at the states and at samples between them, for plans still valid.
  if (self_check_) {
    const auto qa = q.accessor<double, 3>();
    std::vector<double> c(static_cast<size_t>(J));
    auto at = [&](int64_t n, int64_t t, double u) {  // u in [0, 1] along segment t
      for (int64_t j = 0; j < J; ++j) {
        c[static_cast<size_t>(j)] = u == 0.0 ? qa[n][t][j] : qa[n][t][j] + u * (qa[n][t + 1][j] - qa[n][t][j]);
      }
      return self_check_(c);
    };
    for (int64_t n = 0; n < N; ++n) {
      if (!verdicts[static_cast<size_t>(n)].valid()) continue;
      for (int64_t t = 0; t < T && verdicts[static_cast<size_t>(n)].valid(); ++t) {
        const std::string objection = at(n, t, 0.0);
        if (!objection.empty()) {
          fail(n, Failure::kSelf, "state " + std::to_string(t) + ": " + objection);
          break;
        }
        if (t + 1 == T) break;
        double widest = 0.0;
        for (int64_t j = 0; j < J; ++j) widest = std::max(widest, std::abs(qa[n][t + 1][j] - qa[n][t][j]));
        const int64_t samples = static_cast<int64_t>(std::ceil(widest / config_.self_resolution));
        for (int64_t k = 1; k < samples; ++k) {
          const std::string between = at(n, t, static_cast<double>(k) / static_cast<double>(samples));
          if (!between.empty()) {
            fail(n, Failure::kSelf, "between states " + std::to_string(t) + " and " + std::to_string(t + 1) + ": " +
                                        between);
            break;
          }
        }
      }
    }
  }

  // Clearance at the states.
  const int64_t K = geometry::CountObstacles(scene);
  const std::vector<std::string> sphere_names = [&] {
    std::vector<std::string> names;
    for (int64_t s = 0; s < S; ++s) {
      names.push_back(robot.kind == kinematics::RobotKind::kPoint ? std::string("the robot")
                                                                  : "sphere " + std::to_string(s) + " (" +
                                                                        robot.spheres[static_cast<size_t>(s)].geom + ")");
    }
    return names;
  }();
  if (K == 0) {
    for (auto& v : verdicts) v.clearance = std::numeric_limits<double>::infinity();
    return verdicts;
  }
  const geometry::SceneRows prepared = geometry::PreparedRows(scene, static_cast<int>(robot_->workspace_dim()));
  const kinematics::SphereClearance at_states = robot_->NearestObstacles(q.view({N * T, J}), prepared);
  const torch::Tensor clearance = at_states.clearance.view({N, T, S}), obstacle = at_states.obstacle.view({N, T, S});
  const auto cl = clearance.accessor<double, 3>();
  const auto ob = obstacle.accessor<int64_t, 3>();
  for (int64_t n = 0; n < N; ++n) {
    double smallest = std::numeric_limits<double>::infinity();
    for (int64_t t = 0; t < T; ++t) {
      for (int64_t s = 0; s < S; ++s) {
        smallest = std::min(smallest, cl[n][t][s]);
        if (cl[n][t][s] < config_.margin) {
          fail(n, Failure::kCollision, "state " + std::to_string(t) + ": " + sphere_names[s] + " is " +
                                           Num(cl[n][t][s]) + " from obstacle " + std::to_string(ob[n][t][s]));
        }
      }
    }
    verdicts[static_cast<size_t>(n)].clearance = smallest;
  }

  // The motion between states, for plans that passed everything else: pieces
  // (plan, first state, ends, clearances at the ends), halved until certified.
  std::vector<int64_t> plan_of, segment_of;
  for (int64_t n = 0; n < N; ++n) {
    if (!verdicts[static_cast<size_t>(n)].valid()) continue;
    for (int64_t t = 0; t + 1 < T; ++t) {
      plan_of.push_back(n);
      segment_of.push_back(t);
    }
  }
  if (plan_of.empty()) return verdicts;
  const torch::Tensor plan_index = torch::tensor(plan_of, torch::kInt64), segment_index = torch::tensor(segment_of, torch::kInt64);
  torch::Tensor piece_plan = plan_index, piece_segment = segment_index;
  torch::Tensor qa = q.index({plan_index, segment_index}), qb = q.index({plan_index, segment_index + 1});  // (P, J)
  torch::Tensor da = clearance.index({plan_index, segment_index}), db = clearance.index({plan_index, segment_index + 1});
  const double margin = config_.margin;
  while (piece_plan.size(0) > 0) {
    const torch::Tensor travel = (qb - qa).abs().matmul(motion_bound_);  // (P, S): how far each sphere can move
    const torch::Tensor settled = ((da + db - travel) >= 2.0 * margin) | (travel < config_.resolution);
    const torch::Tensor open = ~settled.all(1);
    if (!open.any().item<bool>()) break;
    piece_plan = piece_plan.index({open});
    piece_segment = piece_segment.index({open});
    qa = qa.index({open});
    qb = qb.index({open});
    da = da.index({open});
    db = db.index({open});
    const torch::Tensor qm = 0.5 * (qa + qb);
    const kinematics::SphereClearance at_middle = robot_->NearestObstacles(qm, prepared);
    const torch::Tensor dm = at_middle.clearance;                          // (P, S)
    const auto [smallest, sphere] = dm.min(1);                             // (P,)
    const auto pp = piece_plan.accessor<int64_t, 1>(), ps = piece_segment.accessor<int64_t, 1>();
    const auto sm = smallest.accessor<double, 1>();
    const auto sp = sphere.accessor<int64_t, 1>();
    const auto mo = at_middle.obstacle.accessor<int64_t, 2>();
    std::vector<uint8_t> keep(static_cast<size_t>(piece_plan.size(0)), 1);
    for (int64_t p = 0; p < piece_plan.size(0); ++p) {
      PlanVerdict& v = verdicts[static_cast<size_t>(pp[p])];
      ++v.motion_checks;
      if (sm[p] < margin) {
        fail(pp[p], Failure::kMotion, "between states " + std::to_string(ps[p]) + " and " + std::to_string(ps[p] + 1) +
                                          ": " + sphere_names[sp[p]] + " passes " + Num(sm[p]) + " from obstacle " +
                                          std::to_string(mo[p][sp[p]]));
        v.clearance = std::min(v.clearance, sm[p]);
      }
    }
    for (int64_t p = 0; p < piece_plan.size(0); ++p) keep[static_cast<size_t>(p)] = verdicts[static_cast<size_t>(pp[p])].valid();
    const torch::Tensor alive = torch::tensor(std::vector<int64_t>(keep.begin(), keep.end()), torch::kInt64).to(torch::kBool);
    auto halves = [&](const torch::Tensor& first, const torch::Tensor& second) {
      return torch::cat({first.index({alive}), second.index({alive})});
    };
    const torch::Tensor qm_alive = qm.index({alive}), dm_alive = dm.index({alive});
    piece_plan = halves(piece_plan, piece_plan);
    piece_segment = halves(piece_segment, piece_segment);
    const torch::Tensor new_qa = torch::cat({qa.index({alive}), qm_alive}), new_qb = torch::cat({qm_alive, qb.index({alive})});
    const torch::Tensor new_da = torch::cat({da.index({alive}), dm_alive}), new_db = torch::cat({dm_alive, db.index({alive})});
    qa = new_qa;
    qb = new_qb;
    da = new_da;
    db = new_db;
  }
  return verdicts;
}

}  // namespace flowplan::validity
