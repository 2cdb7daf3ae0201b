// `flowplan plan`: scores of the plans, the files it writes (HDF5 and JSON),
// and the figure.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
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

}  // namespace

std::string DescribeObstacles(const PlanInputs& inputs) {
  const std::vector<std::string> names = inputs.scene.Names();  // the rows' order
  std::string out;
  size_t n = 0;
  for (const auto& entry : inputs.rows) {
    for (int64_t k = 0; k < entry.value().size(0); ++k) {
      out += (out.empty() ? ": " : ", ") + names[n++] + " " + Numbers(entry.value()[k]);
    }
  }
  return out.empty() ? out : out + " from " + inputs.scene_source;
}

std::string SettingsJson(const PlanArgs&, const PlanSubject& subject) {
  std::string out;
  for (const std::string& section : subject.kind->report_sections) {
    std::string value;
    if (section == "guidance") value = config::ToJson(subject.config.guidance);
    if (section == "splitting") value = JsonString(config::EnumName(subject.config.sampler.splitting));
    if (section == "rrt_connect") value = config::ToJson(subject.config.rrt_connect);
    if (section == "hybrid") value = config::ToJson(subject.config.hybrid);
    FLOWPLAN_DEMAND(!value.empty());
    out += "\"" + section + "\": " + value + ", ";
  }
  return out + "\"check\": " + config::ToJson(subject.config.check);
}

namespace {

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

/// Plan i counted at its states by its TCP and by the whole robot (the sphere benchmarks' counts), and feasible.
struct StateCounts {
  bool tcp_collision, arm_collision, feasible, tcp_clear, arm_clear;
};

StateCounts CountAtStates(int64_t i, const PlanArgs& args, const PlanScores& scores) {
  StateCounts o{};
  const bool obstacles = scores.tcp_clearance.size(1) > 0;
  o.tcp_collision = obstacles && scores.tcp_clearance[i].min().item<double>() < 0;
  o.arm_collision = obstacles && scores.arm_clearance[i].min().item<double>() < 0;
  o.feasible = scores.speed_ratio[i].item<double>() <= args.max_speed_ratio;
  const bool reached = scores.goal_distance[i].item<double>() <= args.goal_tolerance && o.feasible;
  o.tcp_clear = reached && !o.tcp_collision;
  o.arm_clear = reached && !o.arm_collision;
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

std::string QualityJson(const validity::PlanQuality& q) {
  return "{\"joint_path_length\": " + JsonNumber(q.joint_path_length) +
         ", \"tcp_path_length\": " + JsonNumber(q.tcp_path_length) +
         ", \"max_speed_ratio\": " + JsonNumber(q.max_speed_ratio) +
         ", \"mean_squared_jerk\": " + JsonNumber(q.mean_squared_jerk) + ", \"duration_s\": " + JsonNumber(q.duration) +
         "}";
}

}  // namespace

PlanCounts& PlanCounts::operator+=(const PlanCounts& other) {
  success += other.success;
  executed += other.executed;
  tcp_clear += other.tcp_clear;
  arm_clear += other.arm_clear;
  return *this;
}

void WritePlansH5(datasets::h5::File& file, const std::string& group, const PlanSubject& subject,
                  const PlanInputs& inputs, const planning::PlanResult& result, const PlanScores& scores,
                  const std::vector<sim::ExecutionResult>& executed) {
  const kinematics::TrajectoryInfo& info = subject.trajectory;
  const int64_t N = result.plans.size(0), T = info.horizon, D = info.state_dim(), W = scores.tcp.size(2);
  const torch::Tensor plans = result.plans.contiguous(), tcp = scores.tcp.to(torch::kFloat32).contiguous();
  file.WriteFloat32(group + "plans", {N, T, D}, plans.data_ptr<float>());
  file.WriteFloat32(group + "tcp", {N, T, W}, tcp.data_ptr<float>());
  std::vector<int32_t> valid;
  for (const validity::PlanVerdict& verdict : scores.verdicts) valid.push_back(verdict.valid() ? 1 : 0);
  file.WriteInt32(group + "valid", {N}, valid.data());
  file.CreateGroup(group + "scene");
  for (const auto& entry : inputs.rows) {
    const torch::Tensor rows = entry.value().to(torch::kFloat64).contiguous();
    file.WriteFloat64(group + "scene/" + entry.key(), rows.sizes().vec(), rows.data_ptr<double>());
  }
  file.WriteFloat32(group + "start", {D}, inputs.start.contiguous().data_ptr<float>());
  file.WriteFloat32(group + "goal", {D}, inputs.goal.contiguous().data_ptr<float>());
  const torch::Tensor goal_tcp = inputs.goal_tcp.to(torch::kFloat32).contiguous();
  file.WriteFloat32(group + "goal_tcp", {W}, goal_tcp.data_ptr<float>());
  file.SetAttribute(group == "/" ? "/" : group.substr(0, group.size() - 1), "obstacle_names",
                    Join(inputs.scene.Names(), ","));
  if (!executed.empty()) {
    const int64_t Te = executed[0].num_states;
    std::vector<float> states, executed_tcp;
    for (const auto& e : executed) {
      states.insert(states.end(), e.states.begin(), e.states.end());
      executed_tcp.insert(executed_tcp.end(), e.tcp.begin(), e.tcp.end());
    }
    file.CreateGroup(group + "executed");
    file.WriteFloat32(group + "executed/states", {N, Te, 2 * subject.robot->num_joints()}, states.data());
    file.WriteFloat32(group + "executed/tcp", {N, Te, 3}, executed_tcp.data());
  }
}

PlanScores ScorePlans(const planning::PlanResult& result, const PlanSubject& subject, const PlanInputs& inputs) {
  const torch::Tensor& plans = result.plans;
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
  scores.quality = validity::MeasurePlans(plans, robot, subject.trajectory.dt, subject.config.check.joint_tolerance);
  scores.speed_ratio = torch::zeros({N}, torch::kFloat64);
  for (int64_t i = 0; i < N; ++i) scores.speed_ratio[i] = scores.quality[static_cast<size_t>(i)].max_speed_ratio;
  scores.verdicts =
      MakePlanChecker(subject).Check(plans, inputs.start, inputs.goal, inputs.rows, result.found, inputs.world);
  return scores;
}

std::string SamplesJson(const PlanArgs& args, const planning::PlanResult& result, const PlanScores& scores,
                        const std::vector<sim::ExecutionResult>& executed, PlanCounts* counts) {
  const int64_t N = result.plans.size(0);
  std::string samples;
  for (int64_t i = 0; i < N; ++i) {
    const size_t n = static_cast<size_t>(i);
    const StateCounts o = CountAtStates(i, args, scores);
    const validity::PlanVerdict& verdict = scores.verdicts[n];
    // Executed: tracked without contact to the goal, and valid as planned (a plan that fails the check is not
    // what the arm may be asked to track, however its execution ended).
    const bool executed_ok = !executed.empty() && executed[n].contacts.empty() &&
                             executed[n].goal_distance <= args.goal_tolerance && verdict.valid();
    counts->success += verdict.valid();
    counts->executed += executed_ok;
    counts->tcp_clear += o.tcp_clear;
    counts->arm_clear += o.arm_clear;
    // A plan the planner refused to search for (its start or goal is not valid) fails as "refused", for that reason.
    const bool refused = !result.refused.empty() && result.refused[n];
    std::string s = "{\"index\": " + std::to_string(i) + ", \"success\": " + Bool(verdict.valid()) +
                    ", \"failure\": " + JsonString(refused ? "refused" : config::EnumName(verdict.failure)) +
                    ", \"reason\": " + JsonString(refused ? result.failure[n] : verdict.reason) + ", \"clearance\": " + JsonNumber(verdict.clearance) +
                    ", \"motion_checks\": " + std::to_string(verdict.motion_checks) +
                    ", \"planning_time_s\": " + JsonNumber(result.call_seconds[n] / static_cast<double>(result.call_plans[n])) +
                    ", \"call_seconds\": " + JsonNumber(result.call_seconds[n]) +
                    ", \"plans_in_call\": " + std::to_string(result.call_plans[n]) +
                    (result.route.empty() ? std::string() : ", \"route\": " + JsonString(result.route[n])) +
                    (result.failure.empty() ? std::string()
                                            : ", \"planner_failure\": " + JsonString(result.failure[n]) +
                                                  ", \"refused\": " + Bool(result.refused[n])) +
                    ", \"found\": " + Bool(result.found[i].item<bool>()) +
                    ",\n      \"quality\": " + QualityJson(scores.quality[n]) +
                    ",\n      \"tcp_clearance\": " + Numbers(scores.tcp_clearance[i]) +
                    ", \"arm_clearance\": " + Numbers(scores.arm_clearance[i]) +
                    ", \"goal_distance\": " + JsonNumber(scores.goal_distance[i].item<double>()) +
                    ", \"speed_ratio\": " + JsonNumber(scores.speed_ratio[i].item<double>()) +
                    ", \"feasible\": " + Bool(o.feasible) + ", \"tcp_collision\": " + Bool(o.tcp_collision) +
                    ", \"arm_collision\": " + Bool(o.arm_collision) + ", \"tcp_clear\": " + Bool(o.tcp_clear) +
                    ", \"arm_clear\": " + Bool(o.arm_clear);
    if (!executed.empty()) s += ",\n      \"executed\": " + ExecutedJson(executed[n], executed_ok);
    samples += (i ? ",\n    " : "    ") + s + "}";
  }
  return "[\n" + samples + "\n  ]";
}

std::string TimingJson(const std::vector<const planning::PlanResult*>& results) {
  std::vector<double> per_plan;
  bool batched = false;
  for (const planning::PlanResult* r : results) {
    for (size_t i = 0; i < r->call_seconds.size(); ++i) {
      per_plan.push_back(r->call_seconds[i] / static_cast<double>(r->call_plans[i]));
      batched = batched || r->call_plans[i] > 1;
    }
  }
  std::sort(per_plan.begin(), per_plan.end());
  // The q-quantile by linear interpolation between order statistics (numpy's default).
  auto quantile = [&](double q) {
    if (per_plan.empty()) return std::nan("");
    const double at = q * static_cast<double>(per_plan.size() - 1);
    const size_t below = static_cast<size_t>(std::floor(at));
    const size_t above = std::min(below + 1, per_plan.size() - 1);
    return per_plan[below] + (at - static_cast<double>(below)) * (per_plan[above] - per_plan[below]);
  };
  return "{\"median\": " + JsonNumber(quantile(0.5)) + ", \"p95\": " + JsonNumber(quantile(0.95)) +
         ", \"plans\": " + std::to_string(per_plan.size()) +
         ", \"per\": " + JsonString(batched ? "plan, the wall time of a call divided by its plans (batched)"
                                                : "plan, the wall time of the call that made it") + "}";
}

PlanCounts WritePlanFiles(const std::string& h5_temp, const std::string& prefix, const PlanArgs& args,
                          const PlanSubject& subject, const PlanInputs& inputs, const planning::PlanResult& result,
                          const PlanScores& scores, const std::vector<sim::ExecutionResult>& executed,
                          double wall_seconds, int threads) {
  {
    const kinematics::TrajectoryInfo& info = subject.trajectory;
    auto file = datasets::h5::File::Create(h5_temp);
    WritePlansH5(file, "/", subject, inputs, result, scores, executed);
    file.SetAttribute("/", "env", info.env);
    file.SetAttribute("/", "dt", info.dt);
    file.SetAttribute("/", "state_labels", Join(info.state_labels, ","));
    file.SetAttribute("/", "robot", kinematics::RobotToYaml(info.robot));
    file.SetAttribute("/", "planner", subject.source);
    file.SetAttribute("/", "seed", args.seed);
    file.SetAttribute("/", "guidance_scale", subject.config.guidance.scale);
    file.SetAttribute("/", "goal_tolerance", args.goal_tolerance);
    file.Close();
  }
  const int64_t N = result.plans.size(0);
  PlanCounts counts;
  const std::string samples = SamplesJson(args, result, scores, executed, &counts);
  auto rate = [&](int64_t count) { return JsonNumber(static_cast<double>(count) / static_cast<double>(N)); };
  std::vector<std::string> names;
  for (const std::string& name : inputs.scene.Names()) names.push_back(JsonString(name));
  const std::string json =
      "{\"planner\": " + JsonString(subject.source) + ", \"env\": " + JsonString(subject.trajectory.env) +
      ", \"num_samples\": " + std::to_string(N) + ", \"seed\": " + std::to_string(args.seed) +
      ",\n  \"start\": " + Numbers(inputs.start) + ", \"goal\": " + Numbers(inputs.goal) +
      ", \"goal_tcp\": " + Numbers(inputs.goal_tcp) + ",\n  \"scene\": " + SceneJson(inputs.rows) +
      ", \"obstacles\": [" + Join(names, ", ") + "], \"goal_tolerance\": " + JsonNumber(args.goal_tolerance) +
      ", \"max_speed_ratio\": " + JsonNumber(args.max_speed_ratio) + ",\n  " + SettingsJson(args, subject) +
      ",\n  \"success_rate\": " + rate(counts.success) +
      (executed.empty() ? std::string() : ", \"success_rate_executed\": " + rate(counts.executed)) +
      ", \"tcp_clear_rate\": " + rate(counts.tcp_clear) + ", \"arm_clear_rate\": " + rate(counts.arm_clear) +
      ",\n  \"planning_time_s\": " + TimingJson({&result}) +
      ", \"wall_time_s\": " + JsonNumber(wall_seconds) + ", \"threads\": " + std::to_string(threads) +
      ",\n  \"samples\": " + samples + "}\n";
  WriteFileAtomically(prefix + ".json", json);
  return counts;
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
