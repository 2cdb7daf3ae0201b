#include "sim/arm_execution.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>

#include "core/error.h"
#include "sim/joint_motion.h"

namespace flowplan::sim {
namespace {

/// Centred quadratic Savitzky–Golay smoothing weight of offset k in a window of half-width m.
double SavitzkyGolayWeight(int m, int k) {
  return (3.0 * (3.0 * m * m + 3.0 * m - 1.0) - 15.0 * k * k) / ((2.0 * m + 3.0) * (2.0 * m + 1.0) * (2.0 * m - 1.0));
}

}  // namespace

void ExecutionConfig::Validate() const {
  if (smoothing_window % 2 == 0) {
    throw Error("execute.smoothing_window: expected an odd number of states, got " + std::to_string(smoothing_window));
  }
}

void ExecutionDrives::UseComputedTorque(const ExecutionConfig& config) {
  law = Law::kComputedTorque;
  stiffness = config.stiffness;
  damping = 2.0 * config.damping_ratio * std::sqrt(config.stiffness);
}

std::vector<double> SmoothPlan(const std::vector<double>& plan, int64_t T, int64_t D, PlanSmoothing smoothing,
                               int window) {
  if (smoothing == PlanSmoothing::kNone || window <= 1) return plan;
  std::vector<double> out = plan;
  const int half = window / 2;
  for (int64_t t = 1; t + 1 < T; ++t) {
    // A window that shrinks at the ends stays centred; the ends themselves are kept.
    const int m = static_cast<int>(std::min<int64_t>({half, t, T - 1 - t}));
    for (int64_t i = 0; i < D; ++i) {
      double sum = 0.0;
      for (int k = -m; k <= m; ++k) {
        const double w = smoothing == PlanSmoothing::kMovingAverage ? 1.0 / (2 * m + 1)
                         : m == 0                                    ? 1.0
                                                                     : SavitzkyGolayWeight(m, k);
        sum += w * plan[(t + k) * D + i];
      }
      out[t * D + i] = sum;
    }
  }
  return out;
}

ArmExecutor::ArmExecutor(const mjModel& scene, ExecutionDrives drives, int num_obstacles, const ExecutionConfig& config)
    : scene_(scene), drives_(std::move(drives)), num_obstacles_(num_obstacles), config_(config), data_(MakeData(scene)) {
  config_.Validate();
  const size_t J = drives_.qpos.size();
  FLOWPLAN_DEMAND(drives_.dof.size() == J && drives_.effort_limit.size() == J && scene.nu >= static_cast<int>(J) &&
                  drives_.tcp_site >= 0);
  FLOWPLAN_DEMAND(drives_.law == ExecutionDrives::Law::kComputedTorque ||
                  (drives_.kp.size() == J && drives_.kd.size() == J));
  FLOWPLAN_DEMAND(std::abs(scene.opt.timestep - 1.0 / config.control_hz) < 1e-12);
  for (int k = 0; k < num_obstacles; ++k) {
    const std::string name = "obstacle" + std::to_string(k);
    const int g = mj_name2id(&scene, mjOBJ_GEOM, name.c_str());
    FLOWPLAN_DEMAND(g >= 0);
    obstacle_geoms_.push_back(g);
  }
}

ExecutionResult ArmExecutor::Execute(const std::vector<double>& input, int64_t T, double dt,
                                     const Eigen::Vector3d& goal_tcp) {
  const int J = num_joints();
  const int D = 2 * J;
  FLOWPLAN_DEMAND(static_cast<int64_t>(input.size()) == T * D && T >= 2 && dt > 0.0);
  const std::vector<double> plan = SmoothPlan(input, T, D, config_.smoothing, config_.smoothing_window);
  const mjModel& m = scene_;
  mjData& d = *data_;
  mj_resetData(&m, &d);
  for (int j = 0; j < J; ++j) {
    d.qpos[drives_.qpos[j]] = plan[j];
    d.qvel[drives_.dof[j]] = plan[J + j];
  }
  const double duration = (T - 1) * dt;
  ExecutionResult result;
  result.num_states = T + static_cast<int64_t>(std::llround(config_.settle_time / dt));
  result.states.assign(static_cast<size_t>(result.num_states * D), 0.0);
  result.tcp.assign(static_cast<size_t>(result.num_states * 3), 0.0);
  result.min_distance.assign(static_cast<size_t>(num_obstacles_), kMeasuredDistance);
  const int site = drives_.tcp_site;
  const double h = m.opt.timestep;
  const int64_t steps = std::llround((result.num_states - 1) * dt / h);
  std::map<std::pair<int, int>, ContactEvent> contacts;  // (arm geom, obstacle) -> event

  // Reference at time t: cubic Hermite between the planned states (q, q̇), then the last state at rest.
  Eigen::VectorXd q_ref(J), v_ref(J), a_ref(J);
  auto reference = [&](double t) {
    if (t >= duration) {
      for (int j = 0; j < J; ++j) {
        q_ref[j] = plan[(T - 1) * D + j];
        v_ref[j] = 0.0;
        a_ref[j] = 0.0;
      }
      return;
    }
    const int64_t i = std::min<int64_t>(static_cast<int64_t>(t / dt), T - 2);
    const double s = (t - i * dt) / dt;
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
    const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
    const double d00 = (6 * s * s - 6 * s) / dt, d10 = 3 * s * s - 4 * s + 1;
    const double d01 = (-6 * s * s + 6 * s) / dt, d11 = 3 * s * s - 2 * s;
    const double e00 = (12 * s - 6) / (dt * dt), e10 = (6 * s - 4) / dt;
    const double e01 = (6 - 12 * s) / (dt * dt), e11 = (6 * s - 2) / dt;
    for (int j = 0; j < J; ++j) {
      const double q0 = plan[i * D + j], q1 = plan[(i + 1) * D + j];
      const double v0 = plan[i * D + J + j], v1 = plan[(i + 1) * D + J + j];
      q_ref[j] = h00 * q0 + h10 * dt * v0 + h01 * q1 + h11 * dt * v1;
      v_ref[j] = d00 * q0 + d10 * v0 + d01 * q1 + d11 * v1;
      a_ref[j] = e00 * q0 + e10 * v0 + e01 * q1 + e11 * v1;
    }
  };

  const bool computed_torque = drives_.law == ExecutionDrives::Law::kComputedTorque;
  Eigen::MatrixXd full_mass(computed_torque ? m.nv : 0, computed_torque ? m.nv : 0), mass(J, J);
  Eigen::VectorXd q(J), qdot(J), bias(J), passive(J), torque(J);
  int64_t recorded = 0;
  for (int64_t k = 0; k <= steps; ++k) {
    const double t = k * h;
    mj_step1(&m, &d);
    if (recorded < result.num_states && t + 0.5 * h >= recorded * dt) {
      for (int j = 0; j < J; ++j) {
        result.states[recorded * D + j] = d.qpos[drives_.qpos[j]];
        result.states[recorded * D + J + j] = d.qvel[drives_.dof[j]];
      }
      for (int i = 0; i < 3; ++i) result.tcp[recorded * 3 + i] = d.site_xpos[3 * site + i];
      ++recorded;
    }
    // MuJoCo's contacts: every arm–obstacle pair within kMeasuredDistance, with its signed distance.
    for (int c = 0; c < d.ncon; ++c) {
      const mjContact& contact = d.contact[c];
      int arm = contact.geom1, obstacle = contact.geom2;
      if (m.geom_bodyid[arm] == 0) std::swap(arm, obstacle);
      const auto it = std::find(obstacle_geoms_.begin(), obstacle_geoms_.end(), obstacle);
      if (it == obstacle_geoms_.end()) continue;
      const int index = static_cast<int>(it - obstacle_geoms_.begin());
      result.min_distance[index] = std::min(result.min_distance[index], contact.dist);
      if (contact.dist >= 0.0) continue;  // near, not touching
      ContactEvent& event = contacts[{arm, index}];
      if (event.steps == 0) {
        event.arm_geom = mj_id2name(&m, mjOBJ_GEOM, arm) ? mj_id2name(&m, mjOBJ_GEOM, arm) : std::to_string(arm);
        event.obstacle = index;
        event.first_time = t;
      }
      event.last_time = t;
      event.max_depth = std::max(event.max_depth, -contact.dist);
      ++event.steps;
    }
    if (k == steps) break;
    reference(t);
    for (int j = 0; j < J; ++j) {
      q[j] = d.qpos[drives_.qpos[j]];
      qdot[j] = d.qvel[drives_.dof[j]];
      bias[j] = d.qfrc_bias[drives_.dof[j]];
      result.max_tracking_error = std::max(result.max_tracking_error, std::abs(q_ref[j] - q[j]));
    }
    if (computed_torque) {
      mj_fullM(&m, full_mass.data(), d.qM);  // symmetric: storage order is moot
      for (int a = 0; a < J; ++a) {
        passive[a] = d.qfrc_passive[drives_.dof[a]];
        for (int b = 0; b < J; ++b) mass(a, b) = full_mass(drives_.dof[a], drives_.dof[b]);
      }
      torque = ComputedTorque<Eigen::VectorXd>(q_ref, v_ref, a_ref, q, qdot, mass, bias, passive, drives_.stiffness,
                                               drives_.damping);
    } else {
      for (int j = 0; j < J; ++j) {
        torque[j] = drives_.kp[j] * (q_ref[j] - q[j]) + drives_.kd[j] * (v_ref[j] - qdot[j]) + bias[j];
      }
    }
    for (int j = 0; j < J; ++j) d.ctrl[j] = std::clamp(torque[j], -drives_.effort_limit[j], drives_.effort_limit[j]);
    mj_step2(&m, &d);
  }
  for (auto& [key, event] : contacts) result.contacts.push_back(event);
  const Eigen::Vector3d tcp(d.site_xpos[3 * site], d.site_xpos[3 * site + 1], d.site_xpos[3 * site + 2]);
  result.goal_distance = (tcp - goal_tcp).norm();
  result.warnings = WarningCount(d);
  return result;
}

}  // namespace flowplan::sim
