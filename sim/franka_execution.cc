#include "sim/franka_execution.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/error.h"
#include "sim/arm_xml.h"

namespace flowplan::sim {
namespace {

constexpr int kStateDim = 2 * kFrankaJoints;

std::string Number(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

void ReplaceOnce(std::string& text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  FLOWPLAN_DEMAND(at != std::string::npos);
  text.replace(at, from.size(), to);
}

/// Distance from point p to the segment [a, b].

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


FrankaModel MakeFrankaScene(const geometry::Scene& scene, double timestep) {
  scene.Validate(3, "execution scene");
  InstallExactConvexOverlaps();  // the margin below would make cylinders overlap what they do not touch
  std::string xml = FrankaModelXml();
  // Room for contacts of every capsule with several obstacles.
  ReplaceOnce(xml, "njmax=\"64\"", "njmax=\"2000\"");
  ReplaceOnce(xml, "nconmax=\"16\"", "nconmax=\"1000\"");
  // Contacts are detected within kMeasuredDistance (margin) and act only on overlaps (gap = margin).
  const std::string common = "margin=\"" + Number(kMeasuredDistance) + "\" gap=\"" + Number(kMeasuredDistance) +
                             "\" group=\"4\" contype=\"0\" conaffinity=\"1\" rgba=\"0.8 0.2 0.2 0.5\"";
  ReplaceOnce(xml, "<worldbody>", "<worldbody>\n" + ObstacleGeomsXml(scene, common));
  FrankaModel model(xml, "Franka scene with " + std::to_string(scene.size()) + " obstacles");
  model.SetPhysics(timestep, Integrator::kEuler);
  model.EnableObstacleContacts();
  return model;
}

std::vector<double> SmoothPlan(const std::vector<double>& plan, int64_t T, PlanSmoothing smoothing, int window) {
  if (smoothing == PlanSmoothing::kNone || window <= 1) return plan;
  std::vector<double> out = plan;
  const int half = window / 2;
  for (int64_t t = 1; t + 1 < T; ++t) {
    // A window that shrinks at the ends stays centred; the ends themselves are kept.
    const int m = static_cast<int>(std::min<int64_t>({half, t, T - 1 - t}));
    for (int i = 0; i < kStateDim; ++i) {
      double sum = 0.0;
      for (int k = -m; k <= m; ++k) {
        const double w = smoothing == PlanSmoothing::kMovingAverage ? 1.0 / (2 * m + 1)
                         : m == 0                                    ? 1.0
                                                                     : SavitzkyGolayWeight(m, k);
        sum += w * plan[(t + k) * kStateDim + i];
      }
      out[t * kStateDim + i] = sum;
    }
  }
  return out;
}

FrankaExecutor::FrankaExecutor(const FrankaModel& scene, int num_obstacles, const ExecutionConfig& config)
    : scene_(scene), num_obstacles_(num_obstacles), config_(config), data_(MakeData(scene.mj())) {
  config_.Validate();
  const mjModel& m = scene.mj();
  FLOWPLAN_DEMAND(std::abs(m.opt.timestep - 1.0 / config.control_hz) < 1e-12);
  for (int k = 0; k < num_obstacles; ++k) {
    const std::string name = "obstacle" + std::to_string(k);
    const int g = mj_name2id(&m, mjOBJ_GEOM, name.c_str());
    FLOWPLAN_DEMAND(g >= 0);
    obstacle_geoms_.push_back(g);
  }
}

ExecutionResult FrankaExecutor::Execute(const std::vector<double>& input, int64_t T, double dt,
                                        const Eigen::Vector3d& goal_tcp) {
  FLOWPLAN_DEMAND(static_cast<int64_t>(input.size()) == T * kStateDim && T >= 2 && dt > 0.0);
  const std::vector<double> plan = SmoothPlan(input, T, config_.smoothing, config_.smoothing_window);
  const mjModel& m = scene_.mj();
  mjData& d = *data_;
  mj_resetData(&m, &d);
  for (int j = 0; j < kFrankaJoints; ++j) {
    d.qpos[j] = plan[j];
    d.qvel[j] = plan[kFrankaJoints + j];
  }
  const double duration = (T - 1) * dt;
  ExecutionResult result;
  result.num_states = T + static_cast<int64_t>(std::llround(config_.settle_time / dt));
  result.states.assign(static_cast<size_t>(result.num_states * kStateDim), 0.0);
  result.tcp.assign(static_cast<size_t>(result.num_states * 3), 0.0);
  result.min_distance.assign(static_cast<size_t>(num_obstacles_), kMeasuredDistance);
  const JointVector& torque_limit = scene_.limits().torque;
  const int site = scene_.tcp_site();
  const double h = m.opt.timestep;
  const int64_t steps = std::llround((result.num_states - 1) * dt / h);
  std::map<std::pair<int, int>, ContactEvent> contacts;  // (arm geom, obstacle) -> event

  // Reference at time t: cubic Hermite between the planned states (q, q̇), then the last state at rest.
  auto reference = [&](double t, JointVector* q_ref, JointVector* v_ref) {
    if (t >= duration) {
      for (int j = 0; j < kFrankaJoints; ++j) {
        (*q_ref)[j] = plan[(T - 1) * kStateDim + j];
        (*v_ref)[j] = 0.0;
      }
      return;
    }
    const int64_t i = std::min<int64_t>(static_cast<int64_t>(t / dt), T - 2);
    const double s = (t - i * dt) / dt;
    const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s;
    const double h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
    const double d00 = (6 * s * s - 6 * s) / dt, d10 = 3 * s * s - 4 * s + 1;
    const double d01 = (-6 * s * s + 6 * s) / dt, d11 = 3 * s * s - 2 * s;
    for (int j = 0; j < kFrankaJoints; ++j) {
      const double q0 = plan[i * kStateDim + j], q1 = plan[(i + 1) * kStateDim + j];
      const double v0 = plan[i * kStateDim + kFrankaJoints + j], v1 = plan[(i + 1) * kStateDim + kFrankaJoints + j];
      (*q_ref)[j] = h00 * q0 + h10 * dt * v0 + h01 * q1 + h11 * dt * v1;
      (*v_ref)[j] = d00 * q0 + d10 * v0 + d01 * q1 + d11 * v1;
    }
  };

  int64_t recorded = 0;
  JointVector q_ref, v_ref;
  for (int64_t k = 0; k <= steps; ++k) {
    const double t = k * h;
    mj_step1(&m, &d);
    if (recorded < result.num_states && t + 0.5 * h >= recorded * dt) {
      for (int j = 0; j < kFrankaJoints; ++j) {
        result.states[recorded * kStateDim + j] = d.qpos[j];
        result.states[recorded * kStateDim + kFrankaJoints + j] = d.qvel[j];
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
    reference(t, &q_ref, &v_ref);
    for (int j = 0; j < kFrankaJoints; ++j) {
      const double error = q_ref[j] - d.qpos[j];
      result.max_tracking_error = std::max(result.max_tracking_error, std::abs(error));
      const double torque = config_.kp[j] * error + config_.kd[j] * (v_ref[j] - d.qvel[j]) + d.qfrc_bias[j];
      d.ctrl[j] = std::clamp(torque, -torque_limit[j], torque_limit[j]);
    }
    mj_step2(&m, &d);
  }
  for (auto& [key, event] : contacts) result.contacts.push_back(event);
  const Eigen::Vector3d tcp(d.site_xpos[3 * site], d.site_xpos[3 * site + 1], d.site_xpos[3 * site + 2]);
  result.goal_distance = (tcp - goal_tcp).norm();
  result.warnings = WarningCount(d);
  return result;
}

}  // namespace flowplan::sim
