#pragma once

// Scenes: the obstacles a planning call avoids. A scene is a YAML file (or the
// `scene` section of an experiment config) listing spheres in world units:
//
//   spheres:
//     - {centre: [0.5, 0.0, 0.2], radius: 0.1}   # Franka: metres in the base frame
//     - {centre: [0.5, 0.5], radius: 0.08}       # particle: a disc in the unit square
//
// Obstacles are inputs to a planning call, never constants of a planner.

#include <torch/torch.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/config.h"

namespace flowplan::guidance {

struct SphereObstacle {
  std::vector<double> centre;  // (W,) world units (m)
  double radius = NAN;         // world units (m); NaN: not given

  template <class V>
  void Visit(V& v) {
    v.Field("centre", centre, "centre in world coordinates (W values)");
    v.Field("radius", radius, "radius (>= 0)", config::NonNegative());
  }
};

struct Scene {
  std::vector<SphereObstacle> spheres;  // (K,)

  template <class V>
  void Visit(V& v) {
    v.Field("spheres", spheres, "spherical obstacles: [{centre: [x, y, z], radius: r}, ...]");
  }

  int64_t size() const { return static_cast<int64_t>(spheres.size()); }

  /// @throws flowplan::Error "<where>: spheres[1].centre: expected 3 values (the robot's
  ///   workspace is 3-D), got 2" for a wrong dimension, a missing radius or centre.
  void Validate(int workspace_dim, const std::string& where) const;

  /// The obstacles as planners take them: (K, W+1) float32 rows [centre, radius].
  /// @throws flowplan::Error as Validate.
  torch::Tensor Obstacles(int workspace_dim, const std::string& where) const;
};

/// Reads a scene file. @throws flowplan::Error naming the file and the entry at fault.
Scene LoadScene(const std::string& path);

/// Checks an obstacle tensor (K, W+1): finite centres, non-negative radii.
/// @throws flowplan::Error naming `where`, the row and the value.
void CheckObstacles(const torch::Tensor& obstacles, int workspace_dim, const std::string& where);

}  // namespace flowplan::guidance
