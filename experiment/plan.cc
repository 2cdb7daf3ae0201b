#include "experiment/plan.h"

#include <spdlog/spdlog.h>
#include <torch/torch.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/format.h"
#include "core/parallel.h"
#include "classical/rrt_connect.h"
#include "datasets/h5.h"
#include "datasets/trajectory_dataset.h"
#include "experiment/commands.h"
#include "guidance/collision_cost.h"
#include "kinematics/arm_kinematics.h"
#include "planning/script_planner.h"
#include "sim/franka_execution.h"

#ifndef FLOWPLAN_PYTHON
#define FLOWPLAN_PYTHON "/usr/bin/python3"
#endif
#ifndef FLOWPLAN_SOURCE_DIR
#define FLOWPLAN_SOURCE_DIR "."
#endif

namespace flowplan::experiment {
namespace fs = std::filesystem;

std::vector<double> ParseNumbers(const std::string& text, const std::string& option) {
  std::vector<double> values;
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(',', begin);
    const std::string field = text.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
    const std::string where = option + " value " + std::to_string(values.size() + 1) + " \"" + field + "\"";
    char* rest = nullptr;
    errno = 0;
    const double value = std::strtod(field.c_str(), &rest);
    if (field.empty() || rest != field.c_str() + field.size() || field.find_first_of(" \t") != std::string::npos) {
      throw Error(where + ": not a number (expected comma-separated numbers)");
    }
    if (errno == ERANGE || !std::isfinite(value)) throw Error(where + ": not a finite number");
    values.push_back(value);
    if (end == std::string::npos) break;
    begin = end + 1;
  }
  return values;
}

namespace {

/// The planner a plan command runs, with what scoring and execution need.
struct Subject {
  std::unique_ptr<planning::Planner> owned;
  ExperimentConfig config;
  std::shared_ptr<const kinematics::Robot> robot;
  double dt = 0.0;
  std::string env;
  std::vector<std::string> state_labels;
  std::string source;      // what was loaded, for the report
  std::string run_folder;  // default output folder
};

Subject LoadSubject(const PlanCommand& command) {
  Subject subject;
  if (!command.planner_file.empty()) {
    auto planner = std::make_unique<planning::ScriptPlanner>(command.planner_file);
    const std::string where = command.planner_file + " (its config)";
    const ExperimentConfig exported = LoadExperimentText(planner->config_yaml(), where, "", {});
    subject.config = LoadExperimentText(planner->config_yaml(), where, command.overlay_path, command.overrides);
    // What is compiled into the file cannot change; what a call takes can.
    const auto before = config::ListKeys(exported), after = config::ListKeys(subject.config);
    for (size_t i = 0; i < before.size(); ++i) {
      const std::string& key = before[i].key;
      const bool per_call = key == "threads" || key == "guidance.scale" || key.rfind("scene.", 0) == 0 ||
                            key.rfind("execute.", 0) == 0;
      if (!per_call && before[i].default_value != after[i].default_value) {
        throw Error(key + ": is compiled into " + command.planner_file + " (" + before[i].default_value +
                    "); an exported planner takes only threads, guidance.scale, scene.* and execute.* per call "
                    "(plan from the run folder with --ckpt, or export again with the setting)");
      }
    }
    subject.robot = kinematics::MakeRobot(planner->robot(), command.planner_file);
    subject.dt = planner->dt();
    subject.env = planner->env();
    subject.state_labels = planner->state_labels();
    subject.source = command.planner_file;
    const fs::path parent = fs::path(command.planner_file).parent_path();
    subject.run_folder = parent.empty() ? "." : parent.string();
    subject.owned = std::move(planner);
    return subject;
  }
  if (command.rrt_connect) {
    if (command.overlay_path.empty()) {
      throw Error("--rrt-connect: expected --config FILE (its data.path names the robot, horizon and dt to plan for)");
    }
    subject.config = LoadExperiment(command.overlay_path, command.overrides);
    const datasets::TrajectoryDataset data = datasets::ReadDataset(subject.config.data.path);
    subject.robot = kinematics::MakeRobot(data.robot, subject.config.data.path);
    subject.dt = data.dt;
    subject.env = data.env;
    subject.state_labels = data.state_labels;
    subject.source = "rrt_connect";
    subject.run_folder = subject.config.run_dir;
    subject.owned = std::make_unique<classical::RrtConnectPlanner>(subject.robot, data.horizon, data.state_dim,
                                                                   data.dt, subject.config.rrt_connect);
    return subject;
  }
  if (command.ckpt.empty()) throw Error("plan: expected --ckpt RUN_DIR, --planner FILE or --rrt-connect");
  LoadedPlanner loaded = LoadPlanner(command.ckpt, command.overlay_path, command.overrides);
  subject.config = loaded.config;
  subject.robot = loaded.robot;
  subject.dt = loaded.dt;
  subject.env = loaded.env;
  subject.state_labels = loaded.state_labels;
  subject.source = loaded.checkpoint;
  const fs::path folder = fs::path(loaded.checkpoint).parent_path();
  subject.run_folder = folder.filename() == "checkpoints" ? folder.parent_path().string() : folder.string();
  if (subject.run_folder.empty()) subject.run_folder = ".";
  subject.owned = std::move(loaded.planner);
  return subject;
}

guidance::Scene ResolveScene(const PlanCommand& command, const Subject& subject, std::string* where) {
  guidance::Scene scene = subject.config.scene;
  *where = "scene (config)";
  if (!command.scene.empty()) {
    scene = guidance::LoadScene(command.scene);
    *where = command.scene;
  }
  const int W = static_cast<int>(subject.robot->workspace_dim());
  for (const std::string& text : command.spheres) {
    const std::vector<double> values = ParseNumbers(text, "--sphere");
    if (values.size() != static_cast<size_t>(W + 1)) {
      throw Error("--sphere \"" + text + "\": expected " + std::to_string(W + 1) + " numbers (centre and radius; the " +
                  "robot's workspace is " + std::to_string(W) + "-D), got " + std::to_string(values.size()));
    }
    if (values.back() < 0) throw Error("--sphere \"" + text + "\": expected a non-negative radius");
    scene.spheres.push_back({std::vector<double>(values.begin(), values.end() - 1), values.back()});
  }
  for (const std::string& text : command.radii) {
    const size_t equals = text.find('=');
    const std::string value_text = equals == std::string::npos ? text : text.substr(equals + 1);
    const std::vector<double> value = ParseNumbers(value_text, "--radius");
    if (value.size() != 1 || value[0] < 0) throw Error("--radius \"" + text + "\": expected one non-negative radius");
    if (equals == std::string::npos) {
      for (auto& sphere : scene.spheres) sphere.radius = value[0];
    } else {
      const std::vector<double> index = ParseNumbers(text.substr(0, equals), "--radius");
      const double k = index.size() == 1 ? index[0] : -1;
      if (k < 0 || k != std::floor(k) || k >= static_cast<double>(scene.spheres.size())) {
        throw Error("--radius \"" + text + "\": expected K=R with K the index of one of the scene's " +
                    std::to_string(scene.spheres.size()) + " spheres");
      }
      scene.spheres[static_cast<size_t>(k)].radius = value[0];
    }
  }
  return scene;
}

/// The built-in Franka, after checking that it is the robot the planner was trained on.
const sim::FrankaModel& BuiltInFranka(const kinematics::Robot& robot, const std::string& what) {
  static const sim::FrankaModel model = sim::LoadFrankaModel();
  // IK and execution need the same kinematics and geometry; limits may differ.
  auto geometry = [](kinematics::RobotDescription d) {
    d.velocity_limit.clear();
    return kinematics::RobotToYaml(d);
  };
  if (geometry(model.description()) != geometry(robot.description())) {
    throw Error(what + " needs the robot to be the built-in Franka, but the planner's robot is \"" +
                robot.description().name + "\"" +
                (robot.description().name == "franka_panda" ? " with other kinematics" : ""));
  }
  return model;
}

/// A raw state (D,) from --start/--goal or --start-tcp/--goal-tcp.
torch::Tensor ResolveState(const std::string& name, const std::string& values, const std::string& tcp,
                           const Subject& subject, int64_t D) {
  const kinematics::RobotDescription& robot = subject.robot->description();
  const int64_t J = robot.num_joints;
  if (values.empty() == tcp.empty()) {
    throw Error("plan: give the " + name + " either as --" + name + " (positions) or as --" + name + "-tcp (a TCP point)");
  }
  std::vector<double> q;
  if (!values.empty()) {
    q = ParseNumbers(values, "--" + name);
    if (q.size() != static_cast<size_t>(J) && q.size() != static_cast<size_t>(D)) {
      throw Error("--" + name + ": expected " + std::to_string(J) + " positions or " + std::to_string(D) +
                  " state values (" + Join(subject.state_labels) + "), got " + std::to_string(q.size()));
    }
  } else {
    const std::vector<double> point = ParseNumbers(tcp, "--" + name + "-tcp");
    if (point.size() != static_cast<size_t>(robot.workspace_dim)) {
      throw Error("--" + name + "-tcp: expected " + std::to_string(robot.workspace_dim) + " coordinates, got " +
                  std::to_string(point.size()));
    }
    if (robot.kind == kinematics::RobotKind::kPoint) {
      q = point;
    } else {
      // The robot's own inverse kinematics (the exported planner's `ik`), from its home posture.
      const auto& arm = dynamic_cast<const kinematics::ArmKinematics&>(*subject.robot);
      const kinematics::IkSolution solution = arm.InverseTcp(torch::tensor(point, torch::kFloat64).view({1, 3}));
      if (!solution.converged[0].item<bool>()) {
        const double miss = solution.position_error[0].item<double>();
        throw Error("--" + name + "-tcp: target (" + Join({JsonNumber(point[0]), JsonNumber(point[1]), JsonNumber(point[2])}) +
                    ") is unreachable with the TCP orientation of the home posture (" +
                    (miss >= kinematics::kIkPositionTolerance
                         ? "closest " + JsonNumber(miss) + " m away"
                         : "orientation off by " + JsonNumber(solution.orientation_error[0].item<double>()) + " rad") +
                    ")");
      }
      for (int64_t j = 0; j < J; ++j) q.push_back(solution.q[0][j].item<double>());
    }
  }
  for (int64_t j = 0; j < J; ++j) {
    if (q[j] < robot.joint_lower[j] || q[j] > robot.joint_upper[j]) {
      throw Error("--" + name + ": " + subject.state_labels[j] + " = " + JsonNumber(q[j]) + " is outside [" +
                  JsonNumber(robot.joint_lower[j]) + ", " + JsonNumber(robot.joint_upper[j]) + "]");
    }
  }
  torch::Tensor state = torch::zeros({D}, torch::kFloat64);
  for (size_t i = 0; i < q.size(); ++i) state[static_cast<int64_t>(i)] = q[i];
  return state.to(torch::kFloat32);
}

// A start or goal whose TCP lies inside an obstacle is refused: no plan can
// succeed, however it is counted. One whose TCP is clear but whose other
// collision spheres touch an obstacle is planned (the paper counts only the
// TCP) with a warning: no plan of it can succeed counted by the whole arm.
void CheckOutsideObstacles(const std::string& name, const torch::Tensor& state, const Subject& subject,
                           const torch::Tensor& obstacles) {
  if (obstacles.size(0) == 0) return;
  const torch::Tensor o = obstacles.to(torch::kFloat64);                      // (K, W+1)
  const int64_t J = subject.robot->num_joints(), W = subject.robot->workspace_dim();
  const torch::Tensor tcp = subject.robot->Tcp(state.slice(0, 0, J).view({1, J}).to(torch::kFloat64)).view({1, W});
  const torch::Tensor tcp_clearance = (tcp - o.slice(1, 0, W)).norm(2, -1) - o.select(1, W);  // (K,)
  const torch::Tensor arm_clearance =
      guidance::SphereClearance(*subject.robot, state.view({1, 1, -1}).to(torch::kFloat64), o).view({-1});  // (K,)
  // A point robot is its one sphere: it is refused as soon as that touches.
  const bool point = subject.robot->description().kind == kinematics::RobotKind::kPoint;
  for (int64_t k = 0; k < o.size(0); ++k) {
    const double c = tcp_clearance[k].item<double>(), a = arm_clearance[k].item<double>();
    if (c < 0 || (point && a < 0)) {
      throw Error("plan: the " + name + " is inside obstacle " + std::to_string(k) + " (" +
                  (point ? "the robot reaches " + JsonNumber(-a) : "its TCP lies " + JsonNumber(-c)) +
                  " deep in it); move the " + name + " or the obstacle");
    }
    if (a < 0) {
      spdlog::warn("plan: the {}'s collision spheres reach {:.4g} into obstacle {} (its TCP is clear): no plan can "
                   "succeed counted by the whole arm", name, -a, k);
    }
  }
}

std::string Numbers(const torch::Tensor& values) {
  const torch::Tensor v = values.to(torch::kFloat64).contiguous();
  std::string out = "[";
  for (int64_t i = 0; i < v.numel(); ++i) out += (i ? ", " : "") + JsonNumber(v.data_ptr<double>()[i]);
  return out + "]";
}

}  // namespace

void RunPlan(const PlanCommand& command) {
  if (command.num_samples < 1) throw Error("-n: expected at least one plan, got " + std::to_string(command.num_samples));
  if (!(command.goal_tolerance > 0)) throw Error("--goal-tolerance: expected a positive distance");
  if (!(command.max_speed_ratio > 0)) throw Error("--max-speed-ratio: expected a positive ratio");
  Subject subject = LoadSubject(command);
  const planning::Planner& planner = *subject.owned;
  const int threads = ConfigureThreads(subject.config);
  const int64_t D = planner.state_dim(), T = planner.horizon(), J = subject.robot->num_joints();
  const int W = static_cast<int>(subject.robot->workspace_dim());

  std::string scene_where;
  const guidance::Scene scene = ResolveScene(command, subject, &scene_where);
  const torch::Tensor obstacles = scene.Obstacles(W, scene_where);  // (K, W+1)
  const int64_t K = obstacles.size(0);
  const torch::Tensor start = ResolveState("start", command.start, command.start_tcp, subject, D);
  const torch::Tensor goal = ResolveState("goal", command.goal, command.goal_tcp, subject, D);
  CheckOutsideObstacles("start", start, subject, obstacles);
  CheckOutsideObstacles("goal", goal, subject, obstacles);
  torch::Tensor goal_tcp = subject.robot->Tcp(goal.slice(0, 0, J).view({1, J}).to(torch::kFloat64)).view({W});
  if (!command.goal_tcp.empty()) goal_tcp = torch::tensor(ParseNumbers(command.goal_tcp, "--goal-tcp"), torch::kFloat64);
  if (command.execute && subject.robot->description().kind != kinematics::RobotKind::kArm) {
    throw Error("--execute: execution in MuJoCo needs the Franka; this planner's robot is \"" +
                subject.robot->description().name + "\"");
  }
  if (command.execute) BuiltInFranka(*subject.robot, "--execute");

  const std::string prefix = command.out.empty() ? subject.run_folder + "/plan" : command.out;
  const fs::path parent = fs::path(prefix).parent_path();
  if (!parent.empty()) MakeDirectories(parent.string());
  AtomicFile h5_file(prefix + ".h5");  // fails before any work if the output cannot be written

  planning::PlanRequest request;
  request.start = start.unsqueeze(0).expand({command.num_samples, D}).contiguous();
  request.goal = goal.unsqueeze(0).expand({command.num_samples, D}).contiguous();
  request.obstacles = obstacles;
  request.seed = static_cast<uint64_t>(command.seed);
  request.guidance = subject.config.guidance;
  const std::string settings = command.rrt_connect
                                   ? fmt::format("margin {}, {} iterations", subject.config.rrt_connect.margin,
                                                 subject.config.rrt_connect.max_iterations)
                                   : fmt::format("guidance scale {}, splitting {}", subject.config.guidance.scale,
                                                 config::EnumName(subject.config.sampler.splitting));
  spdlog::info("planning {} samples with {} around {} obstacle{} ({})", command.num_samples, subject.source, K,
               K == 1 ? "" : "s", settings);
  const auto started = std::chrono::steady_clock::now();
  const planning::PlanResult result = planning::PlanInChunks(planner, request, threads);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();

  // Scoring: TCP and whole-robot clearances, goal distance.
  const torch::Tensor plans = result.plans.to(torch::kFloat64);                                      // (N, T, D)
  const int64_t N = plans.size(0);
  const torch::Tensor tcp = subject.robot->Tcp(plans.slice(2, 0, J).reshape({N * T, J})).view({N, T, W});
  torch::Tensor tcp_clearance = torch::full({N, K}, INFINITY, torch::kFloat64);
  torch::Tensor arm_clearance = torch::full({N, K}, INFINITY, torch::kFloat64);
  if (K > 0) {
    const torch::Tensor o = obstacles.to(torch::kFloat64);
    tcp_clearance = std::get<0>(((tcp.unsqueeze(2) - o.slice(1, 0, W).view({1, 1, K, W})).norm(2, -1) -
                                 o.select(1, W).view({1, 1, K}))
                                    .min(1));                                                         // (N, K)
    arm_clearance = std::get<0>(guidance::SphereClearance(*subject.robot, plans, o).min(1));        // (N, K)
  }
  const torch::Tensor goal_distance = (tcp.select(1, T - 1) - goal_tcp.view({1, W})).norm(2, -1);  // (N,)
  // Joint speeds the positions imply between consecutive states, relative to the limits.
  torch::Tensor speed_ratio = torch::zeros({N}, torch::kFloat64);
  const auto& limits = subject.robot->description().velocity_limit;
  if (!limits.empty()) {
    const torch::Tensor q = plans.slice(2, 0, J);
    const torch::Tensor speed = (q.slice(1, 1, T) - q.slice(1, 0, T - 1)).abs() / subject.dt;  // (N, T-1, J)
    speed_ratio = std::get<0>((speed / torch::tensor(limits, torch::kFloat64).view({1, 1, J})).flatten(1).max(1));
  }

  // Execution in MuJoCo.
  std::vector<sim::ExecutionResult> executed;
  if (command.execute) {
    std::vector<sim::ObstacleSphere> spheres;
    for (int64_t k = 0; k < K; ++k) {
      spheres.push_back({Eigen::Vector3d(obstacles[k][0].item<double>(), obstacles[k][1].item<double>(),
                                         obstacles[k][2].item<double>()),
                         obstacles[k][3].item<double>()});
    }
    const sim::FrankaModel world = sim::MakeFrankaScene(spheres, 1.0 / subject.config.execute.control_hz);
    std::vector<std::unique_ptr<sim::FrankaExecutor>> workers;
    for (int w = 0; w < threads; ++w) {
      workers.push_back(std::make_unique<sim::FrankaExecutor>(world, static_cast<int>(K), subject.config.execute));
    }
    executed.resize(static_cast<size_t>(N));
    const Eigen::Vector3d target(goal_tcp[0].item<double>(), goal_tcp[1].item<double>(), goal_tcp[2].item<double>());
    const torch::Tensor arm_states = plans.slice(2, 0, 2 * J).contiguous();
    ParallelFor(static_cast<int>(N), threads, [&](int worker, int i) {
      const double* p = arm_states[i].data_ptr<double>();
      executed[i] = workers[worker]->Execute(std::vector<double>(p, p + T * 2 * J), T, subject.dt, target);
    });
  }

  // The plans, their TCP paths, the scene and the executions as HDF5.
  {
    auto file = datasets::h5::File::Create(h5_file.temp_path());
    const torch::Tensor plans_f = result.plans.contiguous(), tcp_f = tcp.to(torch::kFloat32).contiguous();
    const torch::Tensor obstacles_f = obstacles.contiguous();
    file.WriteFloat32("/plans", {N, T, D}, plans_f.data_ptr<float>());
    file.WriteFloat32("/tcp", {N, T, W}, tcp_f.data_ptr<float>());
    file.WriteFloat32("/obstacles", {K, W + 1}, obstacles_f.data_ptr<float>());
    file.WriteFloat32("/start", {D}, start.contiguous().data_ptr<float>());
    file.WriteFloat32("/goal", {D}, goal.contiguous().data_ptr<float>());
    const torch::Tensor goal_tcp_f = goal_tcp.to(torch::kFloat32).contiguous();
    file.WriteFloat32("/goal_tcp", {W}, goal_tcp_f.data_ptr<float>());
    file.SetAttribute("/", "env", subject.env);
    file.SetAttribute("/", "dt", subject.dt);
    file.SetAttribute("/", "state_labels", Join(subject.state_labels, ","));
    file.SetAttribute("/", "robot", kinematics::RobotToYaml(subject.robot->description()));
    file.SetAttribute("/", "planner", subject.source);
    file.SetAttribute("/", "seed", command.seed);
    file.SetAttribute("/", "guidance_scale", subject.config.guidance.scale);
    file.SetAttribute("/", "goal_tolerance", command.goal_tolerance);
    if (!executed.empty()) {
      const int64_t Te = executed[0].num_states;
      std::vector<float> states, executed_tcp;
      for (const auto& e : executed) {
        states.insert(states.end(), e.states.begin(), e.states.end());
        executed_tcp.insert(executed_tcp.end(), e.tcp.begin(), e.tcp.end());
      }
      file.CreateGroup("/executed");
      file.WriteFloat32("/executed/states", {N, Te, 2 * J}, states.data());
      file.WriteFloat32("/executed/tcp", {N, Te, 3}, executed_tcp.data());
    }
    file.Close();
  }
  h5_file.Commit();

  // The report.
  const double tolerance = command.goal_tolerance;
  int64_t tcp_ok = 0, arm_ok = 0, exec_ok = 0;
  std::string samples;
  for (int64_t i = 0; i < N; ++i) {
    const double goal_i = goal_distance[i].item<double>();
    const bool tcp_collision = K > 0 && tcp_clearance[i].min().item<double>() < 0;
    const bool arm_collision = K > 0 && arm_clearance[i].min().item<double>() < 0;
    const bool feasible = speed_ratio[i].item<double>() <= command.max_speed_ratio;
    const bool reached = goal_i <= tolerance && feasible;
    tcp_ok += reached && !tcp_collision;
    arm_ok += reached && !arm_collision;
    std::string s = "{\"index\": " + std::to_string(i) + ", \"tcp_clearance\": " + Numbers(tcp_clearance[i]) +
                    ", \"arm_clearance\": " + Numbers(arm_clearance[i]) + ", \"goal_distance\": " + JsonNumber(goal_i) +
                    ", \"speed_ratio\": " + JsonNumber(speed_ratio[i].item<double>()) +
                    ", \"feasible\": " + (feasible ? "true" : "false") +
                    ", \"tcp_collision\": " + (tcp_collision ? "true" : "false") +
                    ", \"arm_collision\": " + (arm_collision ? "true" : "false") +
                    ", \"success_tcp\": " + (reached && !tcp_collision ? "true" : "false") +
                    ", \"success_arm\": " + (reached && !arm_collision ? "true" : "false") +
                    ", \"planning_time_s\": " + JsonNumber(result.seconds[i]);
    if (!executed.empty()) {
      const sim::ExecutionResult& e = executed[i];
      // The plan itself must be feasible too: an infeasible plan is not what the arm
      // tracked, however its execution ended.
      const bool success = e.contacts.empty() && e.goal_distance <= tolerance && feasible;
      exec_ok += success;
      std::string contacts;
      for (const auto& c : e.contacts) {
        contacts += std::string(contacts.empty() ? "" : ", ") + "{\"arm_geom\": " + JsonString(c.arm_geom) +
                    ", \"obstacle\": " + std::to_string(c.obstacle) + ", \"first_time_s\": " + JsonNumber(c.first_time) +
                    ", \"last_time_s\": " + JsonNumber(c.last_time) + ", \"max_depth\": " + JsonNumber(c.max_depth) + "}";
      }
      s += ", \"executed\": {\"goal_distance\": " + JsonNumber(e.goal_distance) + ", \"min_distance\": " +
           Numbers(torch::tensor(e.min_distance, torch::kFloat64)) + ", \"contacts\": [" + contacts + "]" +
           ", \"max_tracking_error\": " + JsonNumber(e.max_tracking_error) +
           ", \"simulator_warnings\": " + std::to_string(e.warnings) + ", \"success\": " + (success ? "true" : "false") +
           "}";
    }
    samples += (i ? ",\n    " : "    ") + s + "}";
  }
  auto rate = [&](int64_t count) { return JsonNumber(static_cast<double>(count) / static_cast<double>(N)); };
  std::string json = "{\"planner\": " + JsonString(subject.source) + ", \"env\": " + JsonString(subject.env) +
                     ", \"num_samples\": " + std::to_string(N) + ", \"seed\": " + std::to_string(command.seed) +
                     ",\n  \"start\": " + Numbers(start) + ", \"goal\": " + Numbers(goal) + ", \"goal_tcp\": " +
                     Numbers(goal_tcp) + ",\n  \"obstacles\": " + Numbers(obstacles.view({-1})) +
                     ", \"goal_tolerance\": " + JsonNumber(tolerance) +
                     ", \"max_speed_ratio\": " + JsonNumber(command.max_speed_ratio) +
                     (command.rrt_connect
                          ? ",\n  \"rrt_connect\": " + JsonString(config::ToYaml(subject.config.rrt_connect))
                          : ",\n  \"guidance\": " + JsonString(config::ToYaml(subject.config.guidance)) +
                                ", \"splitting\": " + JsonString(config::EnumName(subject.config.sampler.splitting))) +
                     ",\n  \"success_rate_tcp\": " + rate(tcp_ok) + ", \"success_rate_arm\": " + rate(arm_ok) +
                     (executed.empty() ? std::string() : ", \"success_rate_executed\": " + rate(exec_ok)) +
                     ", \"wall_time_s\": " + JsonNumber(wall) + ", \"threads\": " + std::to_string(threads) +
                     ",\n  \"samples\": [\n" + samples + "\n  ]}\n";
  WriteFileAtomically(prefix + ".json", json);

  std::string figure = "not drawn (--no-plot)";
  if (command.plot) {
    const std::string script = std::string(FLOWPLAN_SOURCE_DIR) + "/scripts/plot.py";
    const std::string png = prefix + ".png";
    const std::string call = std::string(FLOWPLAN_PYTHON) + " '" + script + "' scene '" + prefix + ".h5' --out '" + png + "'";
    if (!fs::exists(script) || std::system(call.c_str()) != 0) {
      spdlog::warn("could not draw {} ({}); the plans and report are written", png, call);
      figure = "not drawn";
    } else {
      figure = png;
    }
  }
  spdlog::info("{} plans in {:.2f} s: success {}/{} (TCP clear, goal within {} m), {}/{} (whole robot clear){}; "
               "wrote {}.h5, {}.json, {}",
               N, wall, tcp_ok, N, tolerance, arm_ok, N,
               executed.empty() ? std::string() : fmt::format(", executed {}/{} (feasible, no contact, goal reached)", exec_ok, N),
               prefix, prefix, figure);
}

}  // namespace flowplan::experiment
