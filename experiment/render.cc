// `flowplan render`: one plan of a plan file (`flowplan plan`, or one problem
// of `flowplan plan --problems`) drawn by MuJoCo's renderer among its scene's
// shapes, offscreen: PREFIX.gif, frame by frame at the plan's rate with the
// TCP's trail, and PREFIX.png, the arm at four states of the plan, one picture
// each, with the planned TCP path. The built-in Franka's plan is executed in
// MuJoCo first and the gif shows the execution; so is a robot folder's, given
// its folder (--robot); any other arm (drawn by its collision spheres) is
// shown as planned.

#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>
#include <optional>

#include "core/error.h"
#include "core/format.h"
#include "datasets/h5.h"
#include "experiment/command_line.h"
#include "experiment/commands.h"
#include "experiment/experiment_config.h"
#include "experiment/plan.h"
#include "experiment/robot_kinds.h"
#include "kinematics/robot.h"
#include "render/arm_renderer.h"
#include "render/image_files.h"

namespace flowplan::experiment {

Rendered Render(const RenderArgs& args) {
  const ExperimentConfig config = LoadExperiment(args.config_path, args.overrides);
  config.execute.Validate();
  const auto file = datasets::h5::File::OpenReadOnly(args.plans);
  const std::string group = args.problem.empty() ? "/" : ProblemGroup(args.problem) + "/";
  if (!file.Exists(group + "plans")) {
    std::string hint;
    if (file.Exists("/problems")) hint = "; this is a --problems file: give --problem NAME, one of " + Join(file.ListGroup("/problems"));
    throw Error(args.plans + ": no plans" + (args.problem.empty() ? "" : " of problem \"" + args.problem + "\"") + hint);
  }
  const std::string where = args.plans + ":" + group;
  const kinematics::RobotDescription robot =
      ResolveRobot(kinematics::RobotFromYaml(file.GetStringAttribute("/", "robot"), args.plans + ": robot"));
  if (robot.kind != kinematics::RobotKind::kArm) throw Error(args.plans + ": robot: render draws arms, not a point robot");
  const int64_t J = robot.num_joints;
  std::vector<int64_t> shape;
  const std::vector<float> plans = file.ReadFloat32(group + "plans", &shape);
  const int64_t N = shape[0], T = shape[1], D = shape[2];
  if (args.index < 0 || args.index >= N) {
    throw Error("--index: expected a plan index in [0, " + std::to_string(N) + "), got " + std::to_string(args.index));
  }
  if (D < J) throw Error(where + "plans: expected at least the robot's " + std::to_string(J) + " joints, got " + std::to_string(D));
  geometry::SceneRows rows;
  for (const std::string& kind : geometry::ObstacleKinds()) {
    if (!file.Exists(group + "scene/" + kind)) continue;
    std::vector<int64_t> rows_shape;
    const std::vector<double> values = file.ReadFloat64(group + "scene/" + kind, &rows_shape);
    rows.insert(kind, torch::tensor(values, torch::kFloat64).view(rows_shape));
  }
  const geometry::Scene scene = geometry::SceneOf(rows, 3, where + "scene");
  std::vector<int64_t> goal_shape;
  const std::vector<float> goal = file.ReadFloat32(group + "goal_tcp", &goal_shape);
  const double dt = file.GetDoubleAttribute("/", "dt");

  const std::vector<double> plan(plans.begin() + args.index * T * D, plans.begin() + (args.index + 1) * T * D);
  const kinematics::Robot kinematics(robot, args.plans + ": robot");
  const torch::Tensor q = torch::tensor(plan, torch::kFloat64).view({T, D}).slice(1, 0, J);
  const torch::Tensor tcp = kinematics.Tcp(q);
  std::vector<Eigen::Vector3d> path;
  for (int64_t t = 0; t < T; ++t) path.emplace_back(tcp[t][0].item<double>(), tcp[t][1].item<double>(), tcp[t][2].item<double>());
  auto joints = [J](const double* state) { return std::vector<double>(state, state + J); };
  // The camera: framing the scene, the arm at the plan's first and last states and its TCP path, unless render.frame
  // is off.
  render::RenderConfig camera = config.render;
  if (camera.frame) {
    std::vector<Eigen::Vector3d> shown = path;
    for (const int64_t t : {int64_t{0}, T - 1}) {
      const torch::Tensor centres = kinematics.SphereCentres(q[t]);
      for (int64_t s = 0; s < centres.size(0); ++s) {
        shown.emplace_back(centres[s][0].item<double>(), centres[s][1].item<double>(), centres[s][2].item<double>());
      }
    }
    camera = render::Framed(camera, scene, shown);
  }

  // A robot that a kind of RobotKinds() simulates (the built-in Franka; a robot folder given by --robot) is executed
  // in MuJoCo and the execution drawn; any other is drawn by its collision spheres as planned.
  const std::unique_ptr<RobotSimulator> simulator = FindSimulator(robot, args.robot, config);
  if (simulator && D != 2 * J) {
    throw Error(where + "plans: executing needs positions and velocities (" + std::to_string(2 * J) + " values a "
                "state), got " + std::to_string(D));
  }
  const Eigen::Vector3d target(goal[0], goal[1], goal[2]);
  std::optional<sim::ExecutionResult> executed;
  std::unique_ptr<render::ArmRenderer> renderer;
  if (simulator) {
    const std::unique_ptr<SimulatedScene> world = simulator->Scene(scene, {});
    executed = world->Executor()->Execute(plan, T, dt, target);
    renderer = simulator->Renderer(scene, camera);
  } else {
    renderer = std::make_unique<render::ArmRenderer>(robot, scene, camera);
  }
  // One frame a state: the executed states (T_exec, 2J) and their TCPs, or the plan's (T, D) and the planned path.
  std::vector<render::Image> frames;
  std::vector<Eigen::Vector3d> trail;
  const int64_t shown_states = executed ? executed->num_states : T;
  for (int64_t t = 0; t < shown_states; ++t) {
    trail.push_back(executed ? Eigen::Vector3d(executed->tcp[3 * t], executed->tcp[3 * t + 1], executed->tcp[3 * t + 2])
                             : path[static_cast<size_t>(t)]);
    frames.push_back(renderer->Render(
        joints(executed ? &executed->states[static_cast<size_t>(t * 2 * J)] : &plan[static_cast<size_t>(t * D)]),
        trail));
  }
  std::string shown;
  if (executed) {
    shown = fmt::format("the plan executed in MuJoCo: {} contact{}, goal {:.3g} m away", executed->contacts.size(),
                        executed->contacts.size() == 1 ? "" : "s", executed->goal_distance);
    shown += "; the " + robot.name + " drawn by " + simulator->drawn_by();
  } else {
    shown = "the plan as planned, the " + robot.name + " drawn by its collision spheres (--robot DIR executes it)";
  }
  const std::string prefix =
      !args.out.empty() ? args.out
                        : (std::filesystem::path(args.plans).replace_extension("").string() +
                           (args.problem.empty() ? "" : "_" + args.problem) + "_" + std::to_string(args.index));
  EnsureParentFolder(prefix);
  render::WriteGif(prefix + ".gif", frames, dt);
  // Four pictures of one arm each (start, a third, two thirds, goal), two to a row, with the whole planned path:
  // arms drawn over each other at once hide each other.
  std::vector<render::Image> stills;
  constexpr int kPoses = 4;
  for (int k = 0; k < kPoses; ++k) {
    const int64_t t = k * (T - 1) / (kPoses - 1);
    stills.push_back(renderer->Render(joints(&plan[static_cast<size_t>(t * D)]), path));
  }
  render::WritePng(prefix + ".png", render::Tile(stills, 2));
  spdlog::info("wrote {}.gif ({} frames of {} x {}, {}) and {}.png (the plan at {} states, two to a row)", prefix,
               frames.size(), config.render.width, config.render.height, shown, prefix, kPoses);
  return {prefix + ".gif", prefix + ".png", static_cast<int64_t>(frames.size()), shown};
}

Command AddRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* command = app.add_subcommand(
      "render", "draw one plan of a plan file among its scene's shapes (the built-in Franka's, and with --robot a "
                "robot folder's, executed in MuJoCo first): PREFIX.gif (a video, offscreen through OSMesa) and PREFIX.png (the plan at four states, two to a "
                "row) (render.*, execute.*)");
  command->add_option("plans", args->plans, "a plan file of `flowplan plan` (PREFIX.h5)")->required()->check(CLI::ExistingFile);
  command->add_option("--problem", args->problem, "the problem, in a file of `flowplan plan --problems`");
  command->add_option("--index", args->index, "which plan of the file (or of the problem)")->capture_default_str();
  command->add_option("--out", args->out, "output prefix (default: the plan file's, with the problem and index)");
  command->add_option("--config", args->config_path, "YAML with render.* and execute.* settings")->check(CLI::ExistingFile);
  command->add_option("--robot", args->robot,
                      "the robot folder of the plans (`flowplan robot import`), to execute them in MuJoCo first")
      ->check(CLI::ExistingDirectory);
  command->add_option("overrides", args->overrides, kOverrideHelp);
  return {command, [args] { Render(*args); }};
}

}  // namespace flowplan::experiment
