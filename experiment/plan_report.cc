// `flowplan plan`: scores of the plans, the files it writes (HDF5 and JSON),
// and the figure.

#include <spdlog/spdlog.h>

#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/format.h"
#include "datasets/h5.h"
#include "experiment/plan.h"

#ifndef FLOWPLAN_PYTHON
#define FLOWPLAN_PYTHON "/usr/bin/python3"
#endif
#ifndef FLOWPLAN_SOURCE_DIR
#define FLOWPLAN_SOURCE_DIR "."
#endif

namespace flowplan::experiment {
namespace fs = std::filesystem;
namespace {

std::string Numbers(const torch::Tensor& values) {
  const torch::Tensor v = values.to(torch::kFloat64).contiguous();
  std::string out = "[";
  for (int64_t i = 0; i < v.numel(); ++i) out += (i ? ", " : "") + JsonNumber(v.data_ptr<double>()[i]);
  return out + "]";
}

std::string Bool(bool value) { return value ? "true" : "false"; }

/// {"spheres": [[…], …], …}: the scene's rows.
std::string SceneJson(const geometry::SceneRows& rows) {
  std::string out;
  for (const auto& entry : rows) {
    std::string list;
    for (int64_t k = 0; k < entry.value().size(0); ++k) list += (k ? ", " : "") + Numbers(entry.value()[k]);
    out += (out.empty() ? "" : ", ") + JsonString(entry.key()) + ": [" + list + "]";
  }
  return "{" + out + "}";
}

/// Whether plan i succeeds counted by its TCP, by the whole robot, and as executed.
struct Outcome {
  bool tcp_collision, arm_collision, feasible, success_tcp, success_arm, success_executed;
};

Outcome Judge(int64_t i, const PlanArgs& args, const PlanScores& scores, const std::vector<sim::ExecutionResult>& executed) {
  Outcome o{};
  const bool obstacles = scores.tcp_clearance.size(1) > 0;
  o.tcp_collision = obstacles && scores.tcp_clearance[i].min().item<double>() < 0;
  o.arm_collision = obstacles && scores.arm_clearance[i].min().item<double>() < 0;
  o.feasible = scores.speed_ratio[i].item<double>() <= args.max_speed_ratio;
  const bool reached = scores.goal_distance[i].item<double>() <= args.goal_tolerance && o.feasible;
  o.success_tcp = reached && !o.tcp_collision;
  o.success_arm = reached && !o.arm_collision;
  // The plan itself must be feasible too: an infeasible plan is not what the arm tracked, however its execution ended.
  o.success_executed = !executed.empty() && executed[i].contacts.empty() &&
                       executed[i].goal_distance <= args.goal_tolerance && o.feasible;
  return o;
}

std::string ExecutedJson(const sim::ExecutionResult& e, bool success) {
  std::string contacts;
  for (const auto& c : e.contacts) {
    contacts += std::string(contacts.empty() ? "" : ", ") + "{\"arm_geom\": " + JsonString(c.arm_geom) +
                ", \"obstacle\": " + std::to_string(c.obstacle) + ", \"first_time_s\": " + JsonNumber(c.first_time) +
                ", \"last_time_s\": " + JsonNumber(c.last_time) + ", \"max_depth\": " + JsonNumber(c.max_depth) + "}";
  }
  return "{\"goal_distance\": " + JsonNumber(e.goal_distance) + ", \"min_distance\": " +
         Numbers(torch::tensor(e.min_distance, torch::kFloat64)) + ", \"contacts\": [" + contacts + "]" +
         ", \"max_tracking_error\": " + JsonNumber(e.max_tracking_error) +
         ", \"simulator_warnings\": " + std::to_string(e.warnings) + ", \"success\": " + Bool(success) + "}";
}

void WriteH5(const std::string& path, const PlanArgs& args, const PlanSubject& subject, const PlanInputs& inputs,
             const planning::PlanResult& result, const PlanScores& scores,
             const std::vector<sim::ExecutionResult>& executed) {
  const kinematics::TrajectoryInfo& info = subject.trajectory;
  const int64_t N = result.plans.size(0), T = info.horizon, D = info.state_dim(), W = scores.tcp.size(2);
  auto file = datasets::h5::File::Create(path);
  const torch::Tensor plans = result.plans.contiguous(), tcp = scores.tcp.to(torch::kFloat32).contiguous();
  file.WriteFloat32("/plans", {N, T, D}, plans.data_ptr<float>());
  file.WriteFloat32("/tcp", {N, T, W}, tcp.data_ptr<float>());
  file.CreateGroup("/scene");
  for (const auto& entry : inputs.rows) {
    const torch::Tensor rows = entry.value().to(torch::kFloat64).contiguous();
    file.WriteFloat64("/scene/" + entry.key(), rows.sizes().vec(), rows.data_ptr<double>());
  }
  file.WriteFloat32("/start", {D}, inputs.start.contiguous().data_ptr<float>());
  file.WriteFloat32("/goal", {D}, inputs.goal.contiguous().data_ptr<float>());
  const torch::Tensor goal_tcp = inputs.goal_tcp.to(torch::kFloat32).contiguous();
  file.WriteFloat32("/goal_tcp", {W}, goal_tcp.data_ptr<float>());
  file.SetAttribute("/", "env", info.env);
  file.SetAttribute("/", "dt", info.dt);
  file.SetAttribute("/", "state_labels", Join(info.state_labels, ","));
  file.SetAttribute("/", "robot", kinematics::RobotToYaml(info.robot));
  file.SetAttribute("/", "planner", subject.source);
  file.SetAttribute("/", "seed", args.seed);
  file.SetAttribute("/", "guidance_scale", subject.config.guidance.scale);
  file.SetAttribute("/", "goal_tolerance", args.goal_tolerance);
  file.SetAttribute("/", "obstacle_names", Join(inputs.scene.Names(), ","));
  if (!executed.empty()) {
    const int64_t Te = executed[0].num_states;
    std::vector<float> states, executed_tcp;
    for (const auto& e : executed) {
      states.insert(states.end(), e.states.begin(), e.states.end());
      executed_tcp.insert(executed_tcp.end(), e.tcp.begin(), e.tcp.end());
    }
    file.CreateGroup("/executed");
    file.WriteFloat32("/executed/states", {N, Te, 2 * subject.robot->num_joints()}, states.data());
    file.WriteFloat32("/executed/tcp", {N, Te, 3}, executed_tcp.data());
  }
  file.Close();
}

}  // namespace

PlanScores ScorePlans(const torch::Tensor& plans, const PlanSubject& subject, const PlanInputs& inputs) {
  const kinematics::Robot& robot = *subject.robot;
  const int64_t N = plans.size(0), T = plans.size(1), J = robot.num_joints(), W = robot.workspace_dim();
  const int64_t K = geometry::CountObstacles(inputs.rows);
  const torch::Tensor q = plans.to(torch::kFloat64).slice(2, 0, J).reshape({N * T, J});
  PlanScores scores;
  scores.tcp = robot.Tcp(q).view({N, T, W});
  scores.tcp_clearance = torch::zeros({N, 0}, torch::kFloat64);
  scores.arm_clearance = torch::zeros({N, 0}, torch::kFloat64);
  if (K > 0) {
    scores.tcp_clearance = std::get<0>(
        kinematics::Robot::PointClearance(scores.tcp.view({N * T, W}), inputs.rows).view({N, T, K}).min(1));
    scores.arm_clearance = std::get<0>(robot.Clearance(q, inputs.rows).view({N, T, K}).min(1));
  }
  scores.goal_distance = (scores.tcp.select(1, T - 1) - inputs.goal_tcp.view({1, W})).norm(2, -1);
  // Joint speeds the positions imply between consecutive states, relative to the limits.
  scores.speed_ratio = torch::zeros({N}, torch::kFloat64);
  const auto& limits = robot.description().velocity_limit;
  if (!limits.empty()) {
    const torch::Tensor positions = q.view({N, T, J});
    const torch::Tensor speed = (positions.slice(1, 1, T) - positions.slice(1, 0, T - 1)).abs() / subject.trajectory.dt;
    scores.speed_ratio =
        std::get<0>((speed / torch::tensor(limits, torch::kFloat64).view({1, 1, J})).flatten(1).max(1));
  }
  return scores;
}

PlanCounts WritePlanFiles(const std::string& h5_temp, const std::string& prefix, const PlanArgs& args,
                    const PlanSubject& subject, const PlanInputs& inputs, const planning::PlanResult& result,
                    const PlanScores& scores, const std::vector<sim::ExecutionResult>& executed, double wall_seconds,
                    int threads) {
  WriteH5(h5_temp, args, subject, inputs, result, scores, executed);
  const int64_t N = result.plans.size(0);
  int64_t tcp_ok = 0, arm_ok = 0, exec_ok = 0;
  std::string samples;
  for (int64_t i = 0; i < N; ++i) {
    const Outcome o = Judge(i, args, scores, executed);
    tcp_ok += o.success_tcp;
    arm_ok += o.success_arm;
    exec_ok += o.success_executed;
    std::string s = "{\"index\": " + std::to_string(i) + ", \"tcp_clearance\": " + Numbers(scores.tcp_clearance[i]) +
                    ", \"arm_clearance\": " + Numbers(scores.arm_clearance[i]) +
                    ", \"goal_distance\": " + JsonNumber(scores.goal_distance[i].item<double>()) +
                    ", \"speed_ratio\": " + JsonNumber(scores.speed_ratio[i].item<double>()) +
                    ", \"feasible\": " + Bool(o.feasible) + ", \"tcp_collision\": " + Bool(o.tcp_collision) +
                    ", \"arm_collision\": " + Bool(o.arm_collision) + ", \"success_tcp\": " + Bool(o.success_tcp) +
                    ", \"success_arm\": " + Bool(o.success_arm) +
                    ", \"planning_time_s\": " + JsonNumber(result.call_seconds[static_cast<size_t>(i)]) +
                    ", \"plans_in_call\": " + std::to_string(result.call_plans[static_cast<size_t>(i)]) +
                    ", \"found\": " + (result.found[i].item<bool>() ? "true" : "false");
    if (!executed.empty()) s += ", \"executed\": " + ExecutedJson(executed[i], o.success_executed);
    samples += (i ? ",\n    " : "    ") + s + "}";
  }
  auto rate = [&](int64_t count) { return JsonNumber(static_cast<double>(count) / static_cast<double>(N)); };
  std::vector<std::string> names;
  for (const std::string& name : inputs.scene.Names()) names.push_back(JsonString(name));
  const std::string settings =
      args.rrt_connect ? "\"rrt_connect\": " + JsonString(config::ToYaml(subject.config.rrt_connect))
                       : "\"guidance\": " + JsonString(config::ToYaml(subject.config.guidance)) +
                             ", \"splitting\": " + JsonString(config::EnumName(subject.config.sampler.splitting));
  const std::string json =
      "{\"planner\": " + JsonString(subject.source) + ", \"env\": " + JsonString(subject.trajectory.env) +
      ", \"num_samples\": " + std::to_string(N) + ", \"seed\": " + std::to_string(args.seed) +
      ",\n  \"start\": " + Numbers(inputs.start) + ", \"goal\": " + Numbers(inputs.goal) +
      ", \"goal_tcp\": " + Numbers(inputs.goal_tcp) + ",\n  \"scene\": " + SceneJson(inputs.rows) +
      ", \"obstacles\": [" + Join(names, ", ") + "], \"goal_tolerance\": " + JsonNumber(args.goal_tolerance) +
      ", \"max_speed_ratio\": " + JsonNumber(args.max_speed_ratio) + ",\n  " + settings +
      ",\n  \"success_rate_tcp\": " + rate(tcp_ok) + ", \"success_rate_arm\": " + rate(arm_ok) +
      (executed.empty() ? std::string() : ", \"success_rate_executed\": " + rate(exec_ok)) +
      ", \"wall_time_s\": " + JsonNumber(wall_seconds) + ", \"threads\": " + std::to_string(threads) +
      ",\n  \"samples\": [\n" + samples + "\n  ]}\n";
  WriteFileAtomically(prefix + ".json", json);
  return {tcp_ok, arm_ok, exec_ok};
}

std::string DrawPlanFigure(const std::string& prefix) {
  // Installed: <prefix>/bin/flowplan and <prefix>/share/flowplan/plot.py; in a build tree, the source's script.
  std::error_code error;
  const fs::path binary = fs::read_symlink("/proc/self/exe", error);
  const fs::path candidates[] = {binary.parent_path().parent_path() / "share" / "flowplan" / "plot.py",
                                 fs::path(FLOWPLAN_SOURCE_DIR) / "scripts" / "plot.py"};
  fs::path script;
  for (const fs::path& candidate : candidates) {
    if (script.empty() && fs::is_regular_file(candidate, error)) script = candidate;
  }
  const std::string png = prefix + ".png";
  if (script.empty()) return "not drawn (no plot.py next to the binary or in the source tree)";
  spdlog::debug("drawing {} with {}", png, script.string());
  const std::string call =
      std::string(FLOWPLAN_PYTHON) + " '" + script.string() + "' scene '" + prefix + ".h5' --out '" + png + "'";
  if (std::system(call.c_str()) != 0) return "not drawn (" + call + " failed)";
  return png;
}

}  // namespace flowplan::experiment
