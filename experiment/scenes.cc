// `flowplan scenes import`: MoveIt planning scenes and motion-plan requests
// (MotionBenchMaker's format) into a flowplan problem file, and optionally one
// scene file per problem (problems/moveit_import.h, docs/planning.md).

#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>

#include "core/atomic_file.h"
#include "core/error.h"
#include "experiment/commands.h"
#include "kinematics/robot.h"
#include "problems/moveit_import.h"
#include "sim/franka_model.h"

namespace flowplan::experiment {
namespace {

struct ImportArgs {
  std::vector<std::string> files;  // SCENE REQUEST pairs
  std::string folder;              // --dir
  std::string out;
  std::string scenes_dir;
  std::vector<std::string> frames;
  std::string grasp = "touching-tcp";
  double grasp_margin = 0.01;
};

std::string Stem(const std::string& path) { return std::filesystem::path(path).stem().string(); }

void RunImport(const ImportArgs& args) {
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
  problems::MoveItImportOptions options;
  options.joint_names = problems::FrankaJointNames();
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

  const kinematics::Robot arm(sim::LoadFrankaModel().description(), "the Franka");
  problems::ProblemSet set;
  set.source = "moveit import";
  // Every pair is read before anything is written: a bad file leaves no output.
  for (const auto& [scene, request] : pairs) {
    const std::string name = Stem(scene);  // scene0001: a name that no YAML reader takes for a number
    for (const problems::Problem& earlier : set.problems) {
      if (earlier.name == name) {
        throw Error("scenes import: two scenes are called " + name + " (" + scene +
                    "); their problems and scene files would share the name");
      }
    }
    set.problems.push_back(problems::ImportMoveItProblem(arm, scene, request, name, options));
    const problems::Problem& p = set.problems.back();
    if (!p.left_out.empty()) {
      std::string list;
      for (const auto& id : p.left_out) list += (list.empty() ? "" : ", ") + id;
      spdlog::info("{}: left out {} (the goal's TCP is in or within {} m of it)", scene, list, options.grasp_margin);
    }
    for (const auto& [what, clearance] : {std::pair{"start", p.start_clearance}, std::pair{"goal", p.goal_clearance}}) {
      if (clearance < 0.0) {
        spdlog::warn("{}: the {}'s collision spheres overlap the scene by {:.3f} m (flowplan's spheres are "
                     "coarser than MoveIt's meshes)", request, what, -clearance);
      }
    }
  }
  if (!args.scenes_dir.empty()) {
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
  spdlog::info("wrote {}: {} problems, {} obstacles{}", args.out, set.problems.size(), obstacles,
               args.scenes_dir.empty() ? "" : ", their scenes in " + args.scenes_dir);
}

}  // namespace

Command AddScenesCommand(CLI::App& app) {
  auto args = std::make_shared<ImportArgs>();
  CLI::App* scenes = app.add_subcommand("scenes", "scenes from elsewhere");
  scenes->require_subcommand(1);
  CLI::App* import = scenes->add_subcommand(
      "import", "MoveIt planning scenes and motion-plan requests (YAML) into a flowplan problem file");
  import->add_option("files", args->files, "SCENE.yaml REQUEST.yaml pairs");
  import->add_option("--dir", args->folder, "a folder of sceneNNNN.yaml / requestNNNN.yaml pairs (MotionBenchMaker)");
  import->add_option("--out", args->out, "problem file to write (YAML)")->required();
  import->add_option("--scenes-dir", args->scenes_dir, "also write each problem's scene as DIR/NAME.yaml");
  import->add_option("--frame", args->frames,
                     "frame ids taken as the robot's base (default: panda_link0, world, base_link, empty)");
  import->add_option("--grasped", args->grasp,
                     "obstacles a goal grasps, left out: touching-tcp (the goal's TCP is in or near it) or none");
  import->add_option("--grasp-margin", args->grasp_margin, "m: how near the goal's TCP counts as touching")
      ->check(CLI::NonNegativeNumber);
  return {import, [args] { RunImport(*args); }};
}

}  // namespace flowplan::experiment
