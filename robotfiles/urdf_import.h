#pragma once

// `flowplan robot import`: a robot folder (robotfiles/robot_folder.h) from a
// URDF, read with liburdfdom (Debian's URDF parser, the one ROS uses: it keeps
// every joint's velocity and effort limits, which MuJoCo's URDF reader drops,
// and it leaves the kinematic tree as the file gives it, where MuJoCo's fuses
// links joined by fixed joints).
//
// What is planned: the joints named by `joints`, in that order; without them
// the movable joints on the chain from `base` to `tip`; without a tip every
// movable joint below the base. Every other movable joint is held, at its
// `hold` value or else at 0 moved into its limits (a mimic joint at its
// leader's held value times the multiplier plus the offset).
//
// The collision spheres cover each link's collision geometry (primitives and
// STL/OBJ meshes, `package://` paths resolved through `package_dir`): a
// URDF sphere is kept as it is, everything else is covered by
// spheres::Cover at `overshoot`, and the cover is checked on a surface sample
// 2 mm apart (robot.yaml's `cover`). The link pairs not checked for
// self-collision are the SRDF's `disable_collisions` when one is given, else
// collision::StudySelfPairs' adjacent, default (touching at home) and always
// (touching at more than 95 % of `pair_samples` random configurations) pairs.
// Links whose height no joint changes (every joint from the base fixed, held or
// turning about the vertical) and that reach below z = 0 at home stand on the
// floor (floor_exempt).

#include <array>
#include <map>
#include <string>
#include <vector>

#include "robotfiles/robot_folder.h"
#include "spheres/mesh.h"

namespace flowplan::robotfiles {

struct ImportOptions {
  std::string package_dir;                  // where package://NAME/… resolves: DIR/NAME/… (or DIR/… )
  std::string srdf;                         // an SRDF whose disable_collisions list the pairs not checked
  std::string base;                         // the link fixed to the world (default: the URDF's root)
  std::string tip;                          // the link carrying the TCP (default: the last planned joint's link)
  std::array<double, 3> tcp_offset{0.0, 0.0, 0.0};  // m, TCP origin in the tip's frame
  std::vector<std::string> joints;          // planned joints in order (default: see above)
  std::map<std::string, double> hold;       // joints held at a value (rad or m)
  double overshoot = 0.01;                  // m: how far spheres may reach outside the geometry
  int max_spheres = 64;                     // per link
  double surface_spacing = 0.004;           // m: the resolution the cover is computed on (spheres::CoverSettings)
  int64_t pair_samples = 10000;             // random configurations for the self-collision pairs
  std::vector<double> velocity_limit;       // MJCF: the planned joints' speed limits, which an MJCF does not hold
  int collision_group = -1;                 // MJCF: the geom group that is the collision geometry (-1: geoms that collide)
  uint64_t seed = 0;
};

struct ImportResult {
  RobotFile file;
  std::vector<std::pair<std::string, std::string>> meshes;  // (source path, path in the folder) to copy
  std::vector<std::pair<std::string, spheres::Mesh>> mesh_files;  // (path in the folder, mesh) to write as OBJ
  std::vector<std::string> notes;                          // what the import decided, one line each
};

/// Reads `urdf_path` and fits the collision body, writing nothing.
/// @throws flowplan::Error naming the file and the element at fault: a
///   malformed URDF, a revolute or prismatic joint without limits, a
///   base, tip or joint that does not exist, a collision mesh that is missing
///   or in a format other than STL or OBJ, a floating or planar joint.
ImportResult ImportUrdf(const std::string& urdf_path, const ImportOptions& options);

/// ImportUrdf (a .urdf file) or ImportMjcf (robotfiles/mjcf_import.h; a .xml
/// file), then the folder written: DIR/meshes/ first, DIR/robot.yaml last.
/// @throws flowplan::Error for another extension, and as the importer does.
ImportResult ImportRobot(const std::string& model_path, const ImportOptions& options, const std::string& dir);

}  // namespace flowplan::robotfiles
