#include "robotfiles/robot_folder.h"

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace flowplan::robotfiles {
namespace fs = std::filesystem;

namespace {

std::string RobotYamlPath(const std::string& dir) {
  const fs::path path(dir);
  if (fs::is_directory(path)) return (path / "robot.yaml").string();
  return path.string();
}

}  // namespace

std::array<double, 6> RotateInertia(const std::array<double, 6>& inertia, const std::array<double, 4>& quat) {
  const double n = std::sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
  const double w = quat[0] / n, x = quat[1] / n, y = quat[2] / n, z = quat[3] / n;
  const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  const double I[3][3] = {{inertia[0], inertia[3], inertia[4]},
                          {inertia[3], inertia[1], inertia[5]},
                          {inertia[4], inertia[5], inertia[2]}};
  double out[3][3] = {};
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      for (int k = 0; k < 3; ++k) {
        for (int l = 0; l < 3; ++l) out[a][b] += R[a][k] * I[k][l] * R[b][l];
      }
    }
  }
  return {out[0][0], out[1][1], out[2][2], out[0][1], out[0][2], out[1][2]};
}

kinematics::RobotDescription RobotFile::Description(const std::string& where) const {
  kinematics::RobotDescription d = robot;
  if (d.kind != kinematics::RobotKind::kArm) throw Error(where + ": robot.kind: a robot folder describes an arm");
  kinematics::ApplyCollisionBody(collision, d, where);
  d.Validate(where);
  if (!effort_limit.empty() && effort_limit.size() != static_cast<size_t>(d.num_joints)) {
    throw Error(where + ": effort_limit: expected " + std::to_string(d.num_joints) + " values, one per planned joint, got " +
                std::to_string(effort_limit.size()));
  }
  return d;
}

RobotFile LoadRobotFile(const std::string& dir) {
  const std::string path = RobotYamlPath(dir);
  if (!fs::exists(path)) throw Error(path + ": no such file (a robot folder holds robot.yaml; `flowplan robot import` writes one)");
  RobotFile file;
  config::Apply(config::ParseYamlFile(path), file, path);
  file.Description(path);  // validates
  return file;
}

kinematics::RobotDescription LoadRobot(const std::string& dir) {
  return LoadRobotFile(dir).Description(RobotYamlPath(dir));
}

void WriteRobotFile(const RobotFile& file, const std::string& dir) {
  fs::create_directories(dir);
  const fs::path path = fs::path(dir) / "robot.yaml";
  const fs::path partial = fs::path(dir) / "robot.yaml.partial";
  {
    std::ofstream out(partial);
    if (!out) throw Error(partial.string() + ": cannot write");
    out << "# The robot \"" << file.robot.name << "\" for flowplan, imported from " << file.source << ".\n"
        << "# Hand-editable; every key is described in docs/robots.md. Planned joints are the links with\n"
        << "# joint >= 0 (their order is the state's), held joints have joint: -1 and their value in offset.\n"
        << config::ToYaml(file, /*skip_unset=*/true);
    if (!out) throw Error(partial.string() + ": write failed");
  }
  fs::rename(partial, path);
}

}  // namespace flowplan::robotfiles
