// `flowplan plan`: the planner of --ckpt, --planner or --rrt-connect, and the
// settings of the call.

#include <filesystem>

#include "classical/rrt_connect.h"
#include "core/error.h"
#include "datasets/generate_config.h"
#include "experiment/command_line.h"
#include "experiment/plan.h"
#include "experiment/trained_planner.h"
#include "hybrid/hybrid_planner.h"
#include "planning/learned_planner.h"
#include "robotfiles/robot_folder.h"

namespace flowplan::experiment {
namespace fs = std::filesystem;
namespace {

/// The per-call settings of `planner` that `config` sets: every number the
/// planner takes (by its key), the guidance schedule and where it guides.
planning::PlanSettings CallSettings(const planning::LearnedPlanner& planner, const ExperimentConfig& config) {
  std::map<std::string, double> numbers;
  for (const auto& entry : config::ListNumbers(config.guidance, "guidance")) numbers.insert(entry);
  for (const auto& entry : config::ListNumbers(config.sampler, "sampler")) numbers.insert(entry);
  planning::PlanSettings settings;
  for (const auto& [key, value] : planner.settings()) {
    const auto found = numbers.find(key);
    if (found != numbers.end() && found->second != value) settings.values[key] = found->second;
  }
  const std::string schedule = config::EnumName(config.guidance.schedule);
  if (schedule != planner.schedule()) settings.schedule = schedule;
  const std::string guide_at = config::EnumName(config.sampler.guide_at);
  if (guide_at != planner.guide_at()) settings.guide_at = guide_at;
  return settings;
}

PlanSubject FromFile(const PlanArgs& args) {
  PlanSubject subject;
  std::unique_ptr<planning::LearnedPlanner> planner = planning::LearnedPlanner::Load(args.planner_file);
  const std::string where = args.planner_file + " (its config)";
  const ExperimentConfig exported = LoadExperimentText(planner->config_yaml(), where, "", {});
  // The file's weights with flowplan's native kernels, unless the call asks for the file's own code.
  ExperimentConfig native = exported;
  native.sampler.network_kernels = models::Kernels::kNative;
  native.guidance.distance_kernels = models::Kernels::kNative;
  subject.config = LoadExperimentText(ToYaml(native), where, args.overlay_path, args.overrides);
  CheckExportedKeys(exported, subject.config, args.planner_file);
  if (subject.config.sampler.network_kernels != exported.sampler.network_kernels ||
      subject.config.guidance.distance_kernels != exported.guidance.distance_kernels) {
    ExperimentConfig kernels = exported;
    kernels.sampler.network_kernels = subject.config.sampler.network_kernels;
    kernels.guidance.distance_kernels = subject.config.guidance.distance_kernels;
    bool assembled = false;
    planner = AssembleOrKeep(std::move(planner), kernels, &assembled);
    if (!assembled) {  // the report says what plans
      subject.config.sampler.network_kernels = exported.sampler.network_kernels;
      subject.config.guidance.distance_kernels = exported.guidance.distance_kernels;
    }
  }
  subject.settings = CallSettings(*planner, subject.config);
  subject.trajectory = planner->info();
  subject.source = args.planner_file;
  subject.planner = std::move(planner);
  return subject;
}

PlanSubject FromCheckpoint(const PlanArgs& args) {
  PlanSubject subject;
  TrainedPlanner loaded = LoadTrainedPlanner(args.ckpt, args.overlay_path, args.overrides);
  subject.config = loaded.config;
  subject.trajectory = loaded.planner->info();
  subject.source = loaded.checkpoint;
  subject.planner = std::move(loaded.planner);
  return subject;
}

/// A planner without a network (RRT-Connect) needs a robot and the trajectories
/// to time its paths to: those the config's data generator makes (generate.*,
/// and robot: or --robot), no data file.
PlanSubject FromConfig(const PlanArgs& args, const std::string& kind) {
  if (args.overlay_path.empty()) {
    // Without one the config's defaults would plan for the 2-D particle, which is never what was meant.
    throw Error("plan --planner-kind " + kind + " (--rrt-connect): expected --config FILE, whose generate.* names the robot and the trajectories "
                "to time the paths to (e.g. --config configs/franka_joint.yaml)");
  }
  PlanSubject subject;
  subject.config = LoadExperiment(args.overlay_path, args.overrides);
  if (!args.robot.empty()) subject.config.robot = args.robot;
  const std::string folder = subject.config.robot;  // what executing the plans simulates, too
  subject.source = kind;
  if (subject.config.generate.dataset == datasets::DatasetKind::kRobotJoint) {
    // The trajectories of the folder's robot_joint data, without building its simulator.
    if (folder.empty()) throw Error("generate.dataset: robot_joint plans for a robot folder: set robot: DIR or --robot DIR");
    subject.trajectory = datasets::RobotJointLayout(robotfiles::LoadRobot(folder), subject.config.generate.robot_joint).info;
    return subject;
  }
  subject.trajectory = datasets::MakeTask(subject.config.generate)->Layout().info;
  if (!folder.empty()) {
    // The folder's robot, planned over the config's horizon and time step, with velocities when its data has them.
    kinematics::TrajectoryInfo& t = subject.trajectory;
    const bool velocities = t.state_dim() == 2 * t.robot.num_joints;
    t.robot = robotfiles::LoadRobot(folder);
    t.env = "robot folder " + folder;
    t.state_labels.clear();
    for (int j = 0; j < t.robot.num_joints; ++j) t.state_labels.push_back("q" + std::to_string(j + 1));
    for (int j = 0; velocities && j < t.robot.num_joints; ++j) t.state_labels.push_back("dq" + std::to_string(j + 1));
  }
  return subject;
}

/// --hybrid: the learned planner of `subject` proposes, RRT-Connect (rrt_connect.*) falls back, the plan checker
/// (check.*) decides.
void MakeHybrid(PlanSubject& subject) {
  std::unique_ptr<planning::LearnedPlanner> proposer(dynamic_cast<planning::LearnedPlanner*>(subject.planner.release()));
  FLOWPLAN_DEMAND(proposer != nullptr);
  auto fallback = std::make_unique<classical::RrtConnectPlanner>(subject.trajectory, subject.config.rrt_connect,
                                                                 subject.config.check);
  subject.planner = std::make_unique<hybrid::HybridPlanner>(std::move(proposer), std::move(fallback),
                                                            MakePlanChecker(subject), subject.config.hybrid);
  subject.source = "hybrid(" + subject.source + ", rrt_connect)";
}

/// The kind the command line names: --planner-kind, or the flag that stands for one, or the learned planner.
const PlannerKind& ChosenKind(const PlanArgs& args) {
  const std::string flag = args.rrt_connect ? "rrt_connect" : args.hybrid ? "hybrid" : "";
  if (args.rrt_connect && args.hybrid) {
    throw Error("--hybrid: a learned planner (--ckpt or --planner) proposes; RRT-Connect is the fallback");
  }
  if (!args.kind.empty() && !flag.empty() && flag != args.kind) {
    throw Error("--planner-kind " + args.kind + ": contradicts --" + (args.rrt_connect ? "rrt-connect" : "hybrid"));
  }
  return FindPlannerKind(!args.kind.empty() ? args.kind : !flag.empty() ? flag : "learned");
}

}  // namespace

const std::vector<PlannerKind>& PlannerKinds() {
  static const std::vector<PlannerKind> kinds = {
      {"learned", "the trained planner of --ckpt or --planner, guided around the scene (guidance.*)", true,
       {"guidance", "splitting"}, [](PlanSubject&) {}},
      {"rrt_connect", "RRT-Connect (rrt_connect.*, valid by check.*) for the robot and trajectories of --config", false,
       {"rrt_connect"},
       [](PlanSubject& subject) {
         subject.planner = std::make_unique<classical::RrtConnectPlanner>(subject.trajectory, subject.config.rrt_connect,
                                                                          subject.config.check);
       }},
      {"hybrid",
       "the trained planner proposes hybrid.proposals plans, the plan checker (check.*) keeps the valid ones, "
       "RRT-Connect (rrt_connect.*) plans when none is valid",
       true, {"guidance", "splitting", "rrt_connect", "hybrid"}, MakeHybrid},
  };
  return kinds;
}

const PlannerKind& FindPlannerKind(const std::string& name) {
  std::string names;
  for (const PlannerKind& kind : PlannerKinds()) {
    if (kind.name == name) return kind;
    names += (names.empty() ? "" : ", ") + kind.name;
  }
  throw Error("--planner-kind: expected one of " + names + ", got \"" + name + "\"");
}

PlanSubject LoadPlanSubject(const PlanArgs& args) {
  const PlannerKind& kind = ChosenKind(args);
  const int files = !args.ckpt.empty() + !args.planner_file.empty();
  if (kind.network && files != 1) {
    throw Error("plan: expected one of --ckpt RUN_DIR or --planner FILE (or --rrt-connect, which needs neither)");
  }
  if (!kind.network && files != 0) {
    throw Error("plan: --planner-kind " + kind.name + " plans without a trained network; leave out --ckpt and --planner");
  }
  if (!args.robot.empty() && kind.network) {
    throw Error("--robot: only with --rrt-connect (a planner without a network); a learned planner plans for the "
                "robot it was trained for");
  }
  for (const std::string& override : args.overrides) {
    if (kind.network && override.rfind("robot=", 0) == 0) {
      throw Error(override + ": a learned planner plans for the robot it was trained for (robot: names the robot of "
                  "generate and --rrt-connect)");
    }
  }
  PlanSubject subject = !args.planner_file.empty() ? FromFile(args)
                        : !args.ckpt.empty()       ? FromCheckpoint(args)
                                                   : FromConfig(args, kind.name);
  subject.kind = &kind;
  subject.trajectory.robot = ResolveRobot(subject.trajectory.robot);
  subject.robot = kinematics::MakeRobot(subject.trajectory.robot, subject.source + ": robot");
  kind.make(subject);
  return subject;
}

}  // namespace flowplan::experiment
