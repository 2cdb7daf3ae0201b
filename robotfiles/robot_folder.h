#pragma once

// A robot is a folder of data: DIR/robot.yaml (the kinematic tree, the
// planned and held joints with their limits, the TCP, the home posture, the
// collision spheres and the link pairs not checked against each other) and
// DIR/meshes/ (the collision meshes the spheres were fitted to). Written by
// `flowplan robot import` (robotfiles/urdf_import.h, mjcf_import.h), hand-editable, read by
// every command given `--robot DIR` (or `robot: DIR` in a config). Key by key
// in docs/robots.md.

#include <array>
#include <string>
#include <vector>

#include "core/config.h"
#include "kinematics/robot_description.h"

namespace flowplan::robotfiles {

/// One piece of a link's collision geometry, in the link's frame: what the
/// spheres were fitted to, kept so that they can be fitted again and checked.
struct CollisionGeometry {
  std::string link;                                // the link's name
  std::string shape;                               // sphere, box, cylinder, capsule, ellipsoid or mesh
  std::array<double, 3> size{0.0, 0.0, 0.0};       // sphere: (r, 0, 0); box: full sides; cylinder, capsule:
                                                   // (r, length, 0); ellipsoid: semi-axes
  std::string mesh;                                // mesh: file, relative to the robot folder
  std::array<double, 3> scale{1.0, 1.0, 1.0};      // mesh: scale applied to its vertices
  std::array<double, 3> pos{0.0, 0.0, 0.0};        // m, origin in the link frame
  std::array<double, 4> quat{1.0, 0.0, 0.0, 0.0};  // (w, x, y, z) in the link frame

  template <class V>
  void Visit(V& v) {
    v.Field("link", link, "link the geometry is fixed to");
    v.Field("shape", shape, "sphere, box, cylinder, capsule, ellipsoid or mesh");
    v.Field("size", size,
            "sphere: [r, 0, 0]; box: full side lengths; cylinder, capsule: [r, length, 0]; ellipsoid: semi-axes (m)");
    v.Field("mesh", mesh, "mesh: file relative to the robot folder (.stl or .obj)");
    v.Field("scale", scale, "mesh: scale of its vertices");
    v.Field("pos", pos, "origin in the link frame (m)");
    v.Field("quat", quat, "orientation in the link frame (w, x, y, z)");
  }
};

/// How well a link's spheres cover its collision geometry (spheres::CheckCover).
struct LinkCover {
  std::string link;
  int spheres = 0;
  int64_t samples = 0;             // surface points checked
  double largest_uncovered = 0.0;  // m: the farthest any surface sample lies outside every sphere (0: all covered)
  double largest_outside = 0.0;    // m: how far the spheres reach outside the surface at most
  double overshoot_ratio = 0.0;    // volume of the spheres outside the geometry / the geometry's volume

  template <class V>
  void Visit(V& v) {
    v.Field("link", link, "link name");
    v.Field("spheres", spheres, "spheres on the link");
    v.Field("samples", samples, "surface points checked");
    v.Field("largest_uncovered", largest_uncovered, "m: farthest surface sample outside every sphere (0: all covered)");
    v.Field("largest_outside", largest_outside, "m: how far the spheres reach outside the surface");
    v.Field("overshoot_ratio", overshoot_ratio, "volume of the spheres outside the geometry / its volume");
  }
};

/// A link's mass and inertia, in the link's frame: what simulating the robot
/// (`generate`, robotfiles/robot_model.h) needs, not planning.
struct LinkInertia {
  std::string link;                                      // the link's name
  double mass = 0.0;                                     // kg
  std::array<double, 3> com{0.0, 0.0, 0.0};              // m, centre of mass in the link frame
  std::array<double, 6> inertia{0.0, 0.0, 0.0, 0.0, 0.0, 0.0};  // kg·m² about the com, link axes:
                                                              // (ixx, iyy, izz, ixy, ixz, iyz)

  template <class V>
  void Visit(V& v) {
    v.Field("link", link, "link the mass belongs to");
    v.Field("mass", mass, "mass (kg)", config::NonNegative());
    v.Field("com", com, "centre of mass in the link frame (m)");
    v.Field("inertia", inertia, "inertia about the centre of mass along the link axes: [ixx, iyy, izz, ixy, ixz, iyz] (kg m^2)");
  }
};

/// `inertia` (ixx, iyy, izz, ixy, ixz, iyz) given along axes turned by `quat`
/// (w, x, y, z) from the link's, expressed along the link's axes: R I Rᵀ.
std::array<double, 6> RotateInertia(const std::array<double, 6>& inertia, const std::array<double, 4>& quat);

/// What DIR/robot.yaml holds.
struct RobotFile {
  std::string source;                      // the file it was imported from
  kinematics::RobotDescription robot;      // the tree, joints, limits, TCP, home; spheres come from `collision`
  std::vector<double> effort_limit;        // (J,) N·m or N per planned joint
  kinematics::CollisionBody collision;     // spheres by link name, pairs not checked, links standing on the floor
  std::vector<CollisionGeometry> geometry; // the collision geometry the spheres cover
  std::vector<LinkCover> cover;            // how well they cover it, link by link
  std::vector<LinkInertia> inertia;        // mass and inertia per link (links without mass left out)

  template <class V>
  void Visit(V& v) {
    v.Field("source", source, "the model file the robot was imported from");
    v.Field("robot", robot, "kinematic tree, planned joints and their limits, TCP, home posture");
    v.Field("effort_limit", effort_limit, "torque (N·m) or force (N) limit per planned joint", config::Positive());
    v.Field("collision", collision, "collision spheres and the link pairs not checked against each other");
    v.Field("geometry", geometry, "the collision geometry the spheres cover, per link");
    v.Field("cover", cover, "how well the spheres cover the geometry, per link");
    v.Field("inertia", inertia, "mass and inertia per link, for simulating the robot (`generate`)");
  }

  /// The robot as planned and checked: `robot` with the collision body applied.
  /// @throws flowplan::Error prefixed by `where` if the two do not fit together.
  kinematics::RobotDescription Description(const std::string& where) const;
};

/// Reads DIR/robot.yaml (DIR may also name the file itself).
/// @throws flowplan::Error naming the file and key at fault.
RobotFile LoadRobotFile(const std::string& dir);

/// The robot a `--robot DIR` names, ready to plan with.
kinematics::RobotDescription LoadRobot(const std::string& dir);

/// Writes `file` as DIR/robot.yaml (through a temporary file renamed into place), with a header saying what it is.
void WriteRobotFile(const RobotFile& file, const std::string& dir);

}  // namespace flowplan::robotfiles
