// `flowplan robot import`: a robot folder from a URDF or an MJCF (robotfiles/urdf_import.h, mjcf_import.h).

#include <spdlog/spdlog.h>

#include <filesystem>
#include <map>
#include <memory>

#include "core/error.h"
#include "experiment/commands.h"
#include "robotfiles/urdf_import.h"

namespace flowplan::experiment {
namespace {

struct RobotImportArgs {
  std::string model;
  std::string out;
  std::string srdf, package_dir, base, tip, tcp_offset;
  std::vector<std::string> joints, hold;
  std::string velocity_limit;
  int collision_group = -1;
  double overshoot = 0.01;
  int max_spheres = 64;
  int64_t pair_samples = 10000;
  bool force = false;
};

void RunRobotImport(const RobotImportArgs& args) {
  robotfiles::ImportOptions options;
  options.srdf = args.srdf;
  options.package_dir = args.package_dir;
  options.base = args.base;
  options.tip = args.tip;
  if (!args.tcp_offset.empty()) {
    const std::vector<double> v = ParseNumbers(args.tcp_offset, "--tcp-offset");
    if (v.size() != 3) throw Error("--tcp-offset: expected x,y,z, got \"" + args.tcp_offset + "\"");
    options.tcp_offset = {v[0], v[1], v[2]};
  }
  for (const std::string& list : args.joints) {
    std::string name;
    for (const char c : list + ",") {
      if (c != ',') {
        name += c;
      } else if (!name.empty()) {
        options.joints.push_back(name);
        name.clear();
      }
    }
  }
  for (const std::string& item : args.hold) {
    const size_t eq = item.find('=');
    if (eq == std::string::npos || eq == 0) throw Error("--hold: expected NAME=VALUE, got \"" + item + "\"");
    const std::vector<double> v = ParseNumbers(item.substr(eq + 1), "--hold " + item.substr(0, eq));
    if (v.size() != 1) throw Error("--hold: expected one value for " + item.substr(0, eq) + ", got \"" + item + "\"");
    options.hold[item.substr(0, eq)] = v[0];
  }
  if (!args.velocity_limit.empty()) options.velocity_limit = ParseNumbers(args.velocity_limit, "--velocity-limit");
  options.collision_group = args.collision_group;
  options.overshoot = args.overshoot;
  options.max_spheres = args.max_spheres;
  options.pair_samples = args.pair_samples;
  ImportRobotFolder(args.model, options, args.out, args.force);
}

}  // namespace

robotfiles::ImportResult ImportRobotFolder(const std::string& model, const robotfiles::ImportOptions& options,
                                           const std::string& out, bool force) {
  const std::filesystem::path robot_yaml = std::filesystem::path(out) / "robot.yaml";
  if (std::filesystem::exists(robot_yaml) && !force) {
    throw Error(robot_yaml.string() + " exists (--force replaces it)");
  }
  robotfiles::ImportResult result = robotfiles::ImportRobot(model, options, out);
  for (const std::string& note : result.notes) spdlog::info("{}", note);
  const kinematics::RobotDescription& d = result.file.robot;
  std::string joints;
  for (int j = 0; j < d.num_joints; ++j) joints += (j ? ", " : "") + d.JointName(j);
  spdlog::info("planned joints ({}): {}", d.num_joints, joints);
  for (const robotfiles::LinkCover& c : result.file.cover) {
    if (c.samples == 0) {
      spdlog::info("link {}: {} spheres, the URDF's own", c.link, c.spheres);
      continue;
    }
    spdlog::info("link {}: {} spheres; of {} surface samples the farthest lies {:.2f} mm outside every sphere; the spheres "
                 "reach {:.1f} mm outside the geometry and add {:.0f} % of its volume",
                 c.link, c.spheres, c.samples, c.largest_uncovered * 1e3, c.largest_outside * 1e3, c.overshoot_ratio * 100);
  }
  spdlog::info("wrote {}: {} links, {} collision spheres, {} link pairs not checked, {} meshes", robot_yaml.string(),
               d.links.size(), result.file.collision.spheres.size(), result.file.collision.self_collision_ignore.size(),
               result.meshes.size() + result.mesh_files.size());
  return result;
}


Command AddRobotCommand(CLI::App& app) {
  auto args = std::make_shared<RobotImportArgs>();
  CLI::App* robot = app.add_subcommand("robot", "robots as data: import a URDF or an MJCF into a robot folder (robot.yaml)");
  robot->require_subcommand(1);
  CLI::App* import = robot->add_subcommand(
      "import", "read a URDF or an MJCF and write DIR/robot.yaml (joints, limits, TCP, collision spheres fitted to the collision "
                "geometry, link pairs not checked) and DIR/meshes/");
  import->add_option("model", args->model, "the robot's URDF (.urdf) or MJCF (.xml)")->required()->check(CLI::ExistingFile);
  import->add_option("--out", args->out, "robot folder to write")->required();
  import->add_option("--srdf", args->srdf, "SRDF whose disable_collisions are the link pairs not checked")
      ->check(CLI::ExistingFile);
  import->add_option("--package-dir", args->package_dir, "folder that package://NAME/... paths resolve in");
  import->add_option("--base", args->base, "link fixed to the world (default: the URDF's root link)");
  import->add_option("--tip", args->tip, "link carrying the TCP; without --joints, the joints from base to tip are planned");
  import->add_option("--tcp-offset", args->tcp_offset, "x,y,z: the TCP in the tip link's frame (m)");
  import->add_option("--joints", args->joints, "NAME,...: the planned joints in order (default: see --tip)");
  import->add_option("--hold", args->hold, "NAME=VALUE,...: joints held at a value (rad or m); repeatable")
      ->delimiter(',');
  import->add_option("--overshoot", args->overshoot, "m: how far a sphere may reach outside the collision geometry")
      ->check(CLI::PositiveNumber);
  import->add_option("--max-spheres", args->max_spheres, "most spheres per link")->check(CLI::PositiveNumber);
  import->add_option("--pair-samples", args->pair_samples,
                     "random configurations that decide which link pairs always touch (without --srdf)")
      ->check(CLI::PositiveNumber);
  import->add_option("--velocity-limit", args->velocity_limit,
                     "v1,...: MJCF: the planned joints' speed limits (rad/s or m/s), which an MJCF does not hold "
                     "(default: the model's <numeric name=\"velocity_limit\">)");
  import->add_option("--collision-group", args->collision_group,
                     "MJCF: the geom group holding the collision geometry (default: every geom whose contype or "
                     "conaffinity is set)");
  import->add_flag("--force", args->force, "replace DIR/robot.yaml if it exists");
  return {import, [args] { RunRobotImport(*args); }};
}

}  // namespace flowplan::experiment
