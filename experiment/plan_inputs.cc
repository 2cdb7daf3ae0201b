// `flowplan plan`: the scene, start and goal of the command line, checked
// against the robot.

#include <spdlog/spdlog.h>

#include <cmath>
#include <tuple>

#include "core/error.h"
#include "core/format.h"
#include "experiment/command_line.h"
#include "experiment/plan.h"

namespace flowplan::experiment {
namespace {

/// The config's scene or --scene's, with the obstacles of --sphere, --box, --cylinder and --capsule added and
/// --radius applied.
geometry::Scene ResolveScene(const PlanArgs& args, const PlanSubject& subject, std::string* where) {
  geometry::Scene scene = subject.config.scene;
  *where = args.planner_file.empty() ? "scene (config)" : "the scene baked into " + args.planner_file;
  if (!args.scene.empty()) {
    scene = geometry::LoadScene(args.scene);
    *where = args.scene;
  }
  const bool shapes = !args.spheres.empty() || !args.boxes.empty() || !args.cylinders.empty() || !args.capsules.empty();
  if (shapes) *where = scene.size() == 0 ? std::string("the command line") : *where + " and the command line";
  const int W = static_cast<int>(subject.robot->workspace_dim());
  const std::tuple<const char*, const char*, const std::vector<std::string>*> options[] = {
      {"spheres", "--sphere", &args.spheres},
      {"boxes", "--box", &args.boxes},
      {"cylinders", "--cylinder", &args.cylinders},
      {"capsules", "--capsule", &args.capsules}};
  for (const auto& [kind, option_name, texts] : options) {
    const std::string option = option_name;
    for (const std::string& text : *texts) {
      geometry::AddObstacle(scene, kind, ParseNumbers(text, option), W, option + " \"" + text + "\"");
    }
  }
  for (const std::string& text : args.radii) {
    const size_t equals = text.find('=');
    const std::vector<double> value =
        ParseNumbers(equals == std::string::npos ? text : text.substr(equals + 1), "--radius");
    if (value.size() != 1 || value[0] < 0) throw Error("--radius \"" + text + "\": expected one non-negative radius");
    if (equals == std::string::npos) {
      for (auto& sphere : scene.spheres) sphere.radius = value[0];
      continue;
    }
    const std::vector<double> index = ParseNumbers(text.substr(0, equals), "--radius");
    const double k = index.size() == 1 ? index[0] : -1;
    if (k < 0 || k != std::floor(k) || k >= static_cast<double>(scene.spheres.size())) {
      throw Error("--radius \"" + text + "\": expected K=R with K the index of one of the scene's " +
                  std::to_string(scene.spheres.size()) + " spheres");
    }
    scene.spheres[static_cast<size_t>(k)].radius = value[0];
  }
  return scene;
}

/// A raw state (D,) from --start/--goal or --start-tcp/--goal-tcp (the robot's own IK, from its home posture).
torch::Tensor ResolveState(const std::string& name, const std::string& values, const std::string& tcp,
                           const PlanSubject& subject) {
  const kinematics::RobotDescription& robot = subject.robot->description();
  const int64_t J = robot.num_joints, D = subject.trajectory.state_dim();
  if (values.empty() == tcp.empty()) {
    throw Error("plan: give the " + name + " either as --" + name + " (positions) or as --" + name + "-tcp (a TCP point)");
  }
  std::vector<double> q;
  if (!values.empty()) {
    q = ParseNumbers(values, "--" + name);
    if (q.size() != static_cast<size_t>(J) && q.size() != static_cast<size_t>(D)) {
      throw Error("--" + name + ": expected " + std::to_string(J) + " positions or " + std::to_string(D) +
                  " state values (" + Join(subject.trajectory.state_labels) + "), got " + std::to_string(q.size()));
    }
  } else {
    const std::vector<double> point = ParseNumbers(tcp, "--" + name + "-tcp");
    if (point.size() != static_cast<size_t>(robot.workspace_dim)) {
      throw Error("--" + name + "-tcp: expected " + std::to_string(robot.workspace_dim) + " coordinates, got " +
                  std::to_string(point.size()));
    }
    const kinematics::IkSolution ik = subject.robot->InverseTcp(torch::tensor(point, torch::kFloat64).view({1, -1}));
    if (!ik.converged[0].item<bool>()) {
      const double miss = ik.position_error[0].item<double>();
      std::string text;
      for (double v : point) text += (text.empty() ? "" : ", ") + JsonNumber(v);
      throw Error("--" + name + "-tcp: target (" + text + ") is unreachable with the TCP orientation of the home posture (" +
                  (miss >= kinematics::kIkPositionTolerance
                       ? "closest " + JsonNumber(miss) + " m away"
                       : "orientation off by " + JsonNumber(ik.orientation_error[0].item<double>()) + " rad") +
                  ")");
    }
    for (int64_t j = 0; j < J; ++j) q.push_back(ik.q[0][j].item<double>());
  }
  for (int64_t j = 0; j < J; ++j) {
    if (q[j] < robot.joint_lower[j] || q[j] > robot.joint_upper[j]) {
      throw Error("--" + name + ": " + subject.trajectory.state_labels[j] + " = " + JsonNumber(q[j]) + " is outside [" +
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
void CheckOutsideObstacles(const std::string& name, const torch::Tensor& state, const PlanSubject& subject,
                           const PlanInputs& inputs) {
  if (geometry::CountObstacles(inputs.rows) == 0) return;
  const int64_t J = subject.robot->num_joints();
  const torch::Tensor q = state.slice(0, 0, J).view({1, J}).to(torch::kFloat64);
  const torch::Tensor tcp_clearance = kinematics::Robot::PointClearance(subject.robot->Tcp(q), inputs.rows)[0];  // (K,)
  const torch::Tensor arm_clearance = subject.robot->Clearance(q, inputs.rows)[0];                               // (K,)
  // A point robot is its one sphere: it is refused as soon as that touches.
  const bool point = !subject.robot->is_arm();
  const std::vector<std::string> names = inputs.scene.Names();
  for (int64_t k = 0; k < tcp_clearance.size(0); ++k) {
    const double c = tcp_clearance[k].item<double>(), a = arm_clearance[k].item<double>();
    if (c < 0 || (point && a < 0)) {
      throw Error("plan: the " + name + " is inside obstacle " + names[k] + " (" +
                  (point ? "the robot reaches " + JsonNumber(-a) : "its TCP lies " + JsonNumber(-c)) +
                  " deep in it); move the " + name + " or the obstacle");
    }
    if (a < 0) {
      spdlog::warn("plan: the {}'s collision spheres reach {:.4g} into obstacle {} (its TCP is clear): no plan can "
                   "succeed counted by the whole arm", name, -a, names[k]);
    }
  }
}

}  // namespace

std::string RefusalOf(const std::string& name, const torch::Tensor& state, const PlanSubject& subject,
                      const geometry::SceneRows& rows, const collision::WorldOptions& world) {
  const validity::PlanChecker checker = MakePlanChecker(subject);
  const int64_t J = subject.robot->num_joints();
  const torch::Tensor q = state.slice(0, 0, J).to(torch::kFloat64).contiguous();
  return checker.Refusal(name, std::vector<double>(q.data_ptr<double>(), q.data_ptr<double>() + J),
                         checker.ConfigurationChecker(rows, world));
}

PlanInputs ResolvePlanInputs(const PlanArgs& args, const PlanSubject& subject) {
  PlanInputs inputs;
  const int W = static_cast<int>(subject.robot->workspace_dim());
  inputs.scene = ResolveScene(args, subject, &inputs.scene_source);
  inputs.rows = geometry::Rows(inputs.scene, W, inputs.scene_source);
  inputs.start = ResolveState("start", args.start, args.start_tcp, subject);
  inputs.goal = ResolveState("goal", args.goal, args.goal_tcp, subject);
  CheckOutsideObstacles("start", inputs.start, subject, inputs);
  CheckOutsideObstacles("goal", inputs.goal, subject, inputs);
  const int64_t J = subject.robot->num_joints();
  inputs.goal_tcp = args.goal_tcp.empty()
                        ? subject.robot->Tcp(inputs.goal.slice(0, 0, J).view({1, J}).to(torch::kFloat64)).view({W})
                        : torch::tensor(ParseNumbers(args.goal_tcp, "--goal-tcp"), torch::kFloat64);
  return inputs;
}

}  // namespace flowplan::experiment
