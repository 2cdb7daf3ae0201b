// `flowplan scenes import`: MoveIt planning scenes and motion-plan requests
// (MotionBenchMaker's format) into a flowplan problem file, and optionally one
// scene file per problem (problems/moveit_import.h, docs/planning.md).

#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"
#include "experiment/commands.h"
#include "experiment/plan.h"
#include "collision/body_model.h"
#include "problems/moveit_import.h"
#include "robotfiles/robot_folder.h"
#include "sim/franka_model.h"

namespace flowplan::experiment {
namespace {

std::string Stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

}  // namespace

void ImportScenes(const SceneImport& args) {
  CheckOutputFree(args.out, args.force);
  std::vector<std::pair<std::string, std::string>> pairs;
  if (!args.folder.empty()) {
    if (!args.files.empty()) throw Error("scenes import: give --dir or SCENE REQUEST pairs, not both");
    pairs = problems::FindMoveItPairs(args.folder);
  } else {
    if (args.files.empty() || args.files.size() % 2 != 0) {
      throw Error("scenes import: expected SCENE REQUEST pairs (got " + std::to_string(args.files.size()) +
                  " files) or --dir FOLDER");
    }
    for (size_t i = 0; i < args.files.size(); i += 2) pairs.emplace_back(args.files[i], args.files[i + 1]);
  }
  const kinematics::RobotDescription robot =
      args.robot.empty() ? sim::LoadFrankaModel().description() : robotfiles::LoadRobot(args.robot);
  const collision::BodyModel body(robot, args.robot.empty() ? "the Franka" : args.robot);
  problems::MoveItImportOptions options;
  if (args.robot.empty()) {
    options.joint_names = problems::FrankaJointNames();
  } else {
    // A robot folder's joints by their names in its URDF, which MoveIt uses; its base is its root link.
    for (int j = 0; j < robot.num_joints; ++j) options.joint_names.push_back({robot.JointName(j)});
    options.base_frames = {robot.links.front().name};
  }
  for (const kinematics::RobotLink& link : body.description().links) {
    if (link.joint < 0 && !link.joint_name.empty()) options.held_names.push_back(link.joint_name);
  }
  if (!args.frames.empty()) options.base_frames = args.frames;
  bool known = false;
  for (const auto& [rule, name] : problems::EnumEntries(problems::GraspRule{})) {
    if (args.grasp == name) {
      options.grasp = rule;
      known = true;
    }
  }
  if (!known) throw Error("--grasped: \"" + args.grasp + "\" is not one of touching-tcp, none");
  options.grasp_margin = args.grasp_margin;
  options.limit_tolerance = args.limit_tolerance;

  problems::ProblemSet set;
  set.source = "moveit import";
  int refused = 0, clamped = 0;
  // Every pair is read before anything is written. A pair that cannot be planned is a refused problem; a pair
  // whose files are not MoveIt files ends the import with the error naming the file.
  for (const auto& [scene, request] : pairs) {
    const std::string name = Stem(scene);  // scene0001: a name that no YAML reader takes for a number
    for (const problems::Problem& earlier : set.problems) {
      if (earlier.name == name) {
        throw Error("scenes import: two scenes are called " + name + " (" + scene +
                    "); their problems and scene files would share the name");
      }
    }
    set.problems.push_back(problems::ImportMoveItProblem(body, scene, request, name, options));
    const problems::Problem& p = set.problems.back();
    if (!p.left_out.empty()) {
      std::string list;
      for (const auto& id : p.left_out) list += (list.empty() ? "" : ", ") + id;
      spdlog::debug("{}: left out {} (the goal's TCP is in or within {} m of it)", scene, list, options.grasp_margin);
    }
    for (const std::string& note : p.notes) spdlog::info("{}: {}", request, note);
    clamped += !p.notes.empty();
    if (p.refused()) {
      ++refused;
      spdlog::warn("{}: refused: {}", request, p.reason);
    }
  }
  if (!args.scenes_dir.empty()) {
    for (const problems::Problem& p : set.problems) {
      CheckOutputFree((std::filesystem::path(args.scenes_dir) / (p.name + ".yaml")).string(), args.force);
    }
    MakeDirectories(args.scenes_dir);
    for (const problems::Problem& p : set.problems) {
      WriteFileAtomically((std::filesystem::path(args.scenes_dir) / (p.name + ".yaml")).string(),
                          problems::SceneYaml(p.scene));
    }
  }
  EnsureParentFolder(args.out);
  WriteFileAtomically(args.out, problems::ProblemSetYaml(set));
  size_t obstacles = 0;
  for (const auto& p : set.problems) obstacles += static_cast<size_t>(p.scene.size());
  spdlog::info("wrote {}: {} problems ({} refused, {} with a value moved onto a joint limit), {} obstacles{}", args.out,
               set.problems.size(), refused, clamped, obstacles,
               args.scenes_dir.empty() ? "" : ", their scenes in " + args.scenes_dir);
}

Command AddScenesCommand(CLI::App& app) {
  auto args = std::make_shared<SceneImport>();
  CLI::App* scenes = app.add_subcommand("scenes", "scenes from elsewhere");
  scenes->require_subcommand(1);
  CLI::App* import = scenes->add_subcommand(
      "import", "MoveIt planning scenes and motion-plan requests (YAML) into a flowplan problem file");
  import->add_option("files", args->files, "SCENE.yaml REQUEST.yaml pairs");
  import->add_option("--dir", args->folder, "a folder of sceneNNNN.yaml / requestNNNN.yaml pairs (MotionBenchMaker)");
  import->add_option("--out", args->out, "problem file to write (YAML)")->required();
  import->add_flag("--force", args->force, "replace the --out file and the --scenes-dir files if they exist");
  import->add_option("--scenes-dir", args->scenes_dir, "also write each problem's scene as DIR/NAME.yaml");
  import->add_option("--robot", args->robot,
                     "robot folder (`flowplan robot import`) whose joints, by name, the requests set (default: the "
                     "built-in Franka)")
      ->check(CLI::ExistingPath);
  import->add_option("--frame", args->frames,
                     "frame ids that are the robot's base (default: panda_link0 and base_link for the Franka, a robot "
                     "folder's root link)");
  import->add_option("--grasped", args->grasp,
                     "obstacles a goal grasps, left out: touching-tcp (the goal's TCP is in or near it) or none");
  import->add_option("--grasp-margin", args->grasp_margin, "m: how near the goal's TCP counts as touching")
      ->check(CLI::NonNegativeNumber);
  import->add_option("--limit-tolerance", args->limit_tolerance,
                     "rad: a start or goal past a joint limit by at most this is moved onto it; by more, the problem "
                     "is refused")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  return {import, [args] { ImportScenes(*args); }};
}

}  // namespace flowplan::experiment
