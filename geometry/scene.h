#pragma once

// Scenes: the obstacles a planning call avoids, in world units (the Franka:
// metres in its base frame; the particle: the unit square). A scene file (or
// the `scene` section of an experiment config) lists any of four primitive
// shapes; every list is optional:
//
//   spheres:   [{centre: [x, y, z], radius: r}]
//   boxes:     [{centre: [x, y, z], size: [lx, ly, lz], quaternion: [w, x, y, z]}]   # full side lengths
//   cylinders: [{centre: [x, y, z], radius: r, height: h, quaternion: [w, x, y, z]}] # axis = local z
//   capsules:  [{a: [x, y, z], b: [x, y, z], radius: r}]
//
// A quaternion defaults to the identity and need not be unit (it is
// normalised). In a 2-D workspace the shapes are discs, rotated rectangles
// (`angle` in rad instead of a quaternion), side views of cylinders (a
// rectangle 2r wide along local x and h long along local y, rotated by
// `angle`) and stadiums.
//
// Planning calls, costs and checks take a scene as rows of tensors
// (geometry/scene_rows.h). Obstacles are numbered in the order spheres, boxes,
// cylinders, capsules, entry by entry. This header is plain data (no LibTorch).

#include <cmath>
#include <string>
#include <vector>

#include "core/config.h"

namespace flowplan::geometry {

struct SphereObstacle {
  std::vector<double> centre;  // (W,)
  double radius = NAN;

  template <class V>
  void Visit(V& v) {
    v.Field("centre", centre, "centre (W values)");
    v.Field("radius", radius, "radius (>= 0)", config::NonNegative());
  }
};

struct BoxObstacle {
  std::vector<double> centre;      // (W,)
  std::vector<double> size;        // (W,) full side lengths along the box's own axes
  std::vector<double> quaternion;  // (4,) (w, x, y, z), 3-D; empty: identity
  double angle = NAN;              // rad, 2-D; NaN: 0

  template <class V>
  void Visit(V& v) {
    v.Field("centre", centre, "centre (W values)");
    v.Field("size", size, "full side lengths along the box's axes (W values, >= 0)", config::NonNegative());
    v.Field("quaternion", quaternion, "orientation (w, x, y, z), 3-D; default identity");
    v.Field("angle", angle, "orientation (rad), 2-D; default 0");
  }
};

struct CylinderObstacle {
  std::vector<double> centre;  // (W,)
  double radius = NAN;
  double height = NAN;         // full length along the axis (local z; 2-D: local y)
  std::vector<double> quaternion;
  double angle = NAN;

  template <class V>
  void Visit(V& v) {
    v.Field("centre", centre, "centre of the axis (W values)");
    v.Field("radius", radius, "radius (>= 0)", config::NonNegative());
    v.Field("height", height, "length along the axis, local z (>= 0)", config::NonNegative());
    v.Field("quaternion", quaternion, "orientation (w, x, y, z), 3-D; default identity");
    v.Field("angle", angle, "orientation (rad), 2-D; default 0");
  }
};

struct CapsuleObstacle {
  std::vector<double> a;  // (W,) one end of the axis segment
  std::vector<double> b;  // (W,) the other
  double radius = NAN;

  template <class V>
  void Visit(V& v) {
    v.Field("a", a, "one end of the axis (W values)");
    v.Field("b", b, "the other end (W values)");
    v.Field("radius", radius, "radius (>= 0)", config::NonNegative());
  }
};

struct Scene {
  std::vector<SphereObstacle> spheres;
  std::vector<BoxObstacle> boxes;
  std::vector<CylinderObstacle> cylinders;
  std::vector<CapsuleObstacle> capsules;

  template <class V>
  void Visit(V& v) {
    v.Field("spheres", spheres, "spheres (discs): [{centre, radius}, ...]");
    v.Field("boxes", boxes, "boxes (rectangles): [{centre, size, quaternion | angle}, ...]");
    v.Field("cylinders", cylinders, "cylinders: [{centre, radius, height, quaternion | angle}, ...]");
    v.Field("capsules", capsules, "capsules (stadiums): [{a, b, radius}, ...]");
  }

  /// K, the number of obstacles.
  int64_t size() const;

  /// "spheres[0]", "boxes[1]", ...: every obstacle in numbering order (K,).
  std::vector<std::string> Names() const;

  /// @throws flowplan::Error "<where>: boxes[1].size: expected 3 values (the robot's
  ///   workspace is 3-D), got 2" for a wrong dimension, a missing value, a zero
  ///   quaternion, or an orientation of the other dimension (`angle` in 3-D,
  ///   `quaternion` in 2-D).
  void Validate(int workspace_dim, const std::string& where) const;
};

/// Reads a scene file. @throws flowplan::Error naming the file and the entry at fault.
Scene LoadScene(const std::string& path);

/// The kinds of obstacle, in numbering order: spheres, boxes, cylinders, capsules.
const std::vector<std::string>& ObstacleKinds();

/// Adds one obstacle given as the numbers of its row (the command line's
/// `--box cx,cy,cz,lx,ly,lz[,qw,qx,qy,qz]`); the orientation may be left out.
/// @throws flowplan::Error naming `where` for a wrong count or value.
void AddObstacle(Scene& scene, const std::string& kind, const std::vector<double>& values, int workspace_dim,
                 const std::string& where);

}  // namespace flowplan::geometry
