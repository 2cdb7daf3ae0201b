#pragma once

// The world a robot moves in, as plain arrays: the obstacles of a scene (each
// shape's prepared row, as geometry/scene.py lays it out, and a box around
// it) and the floor, if there is one. Immutable; safe to share between threads.
//
// Distances are the shapes' of kernels/shape_distance_math.h, the one native
// definition guidance's operators use too.

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "geometry/scene.h"
#include "geometry/scene_rows.h"

namespace flowplan::collision {

enum class ShapeKind { kSphere, kBox, kCylinder, kCapsule };

struct Obstacle {
  ShapeKind kind = ShapeKind::kSphere;
  std::vector<double> row;         // prepared row (geometry/<shape>.py's columns and the rotation matrix)
  double lo[3] = {0, 0, 0};        // an axis-aligned box around the shape (W entries used)
  double hi[3] = {0, 0, 0};
  std::string name;                // "boxes[1]" or the name it had in its file ("shelf_top")
};

/// What a problem or a planning call sets of the world beyond its obstacles;
/// what it leaves unset comes from the planner's settings and its robot.
struct WorldOptions {
  std::optional<double> floor_height;   // the floor's height (z; y in 2-D), -inf for none; unset: check.floor_height
  std::map<std::string, double> held;   // joints that are not planned, by name, held at these values (a gripper's
                                        // fingers); unset: as the robot holds them
  bool empty() const { return !floor_height && held.empty(); }
};

/// Whether there is a floor, and where.
struct Floor {
  bool present = false;
  double height = 0.0;  // z of the floor plane (W = 3) or y (W = 2), world units
};

class World {
 public:
  World() = default;
  /// The obstacles of `rows` (either form, geometry/scene_rows.h), numbered as
  /// the scene numbers them; `names` (K) or empty for the scene's own names.
  /// @throws flowplan::Error naming `where` for rows the scene check refuses.
  World(const geometry::SceneRows& rows, int workspace_dim, Floor floor = {},
        std::vector<std::string> names = {}, const std::string& where = "scene");
  /// The same, from a scene.
  World(const geometry::Scene& scene, int workspace_dim, Floor floor = {}, std::vector<std::string> names = {},
        const std::string& where = "scene");

  int size() const { return static_cast<int>(obstacles_.size()); }  // K
  int workspace_dim() const { return W_; }
  const Obstacle& obstacle(int k) const { return obstacles_[static_cast<size_t>(k)]; }
  const Floor& floor() const { return floor_; }

  /// Signed distance of point p (W) to obstacle k (negative inside).
  double Distance(int k, const double* p) const;
  /// A lower bound on Distance(k, p), cheap: the distance to the box around it (-inf inside that box).
  double LowerBound(int k, const double* p) const;
  /// LowerBound(k, p) - radius for every obstacle k, into out (K): one loop over the boxes, side by side.
  void LowerBounds(const double* p, double radius, double* out) const;
  /// Signed distance of p above the floor (+inf without one).
  double FloorDistance(const double* p) const {
    return floor_.present ? p[W_ - 1] - floor_.height : INFINITY;
  }

 private:
  int W_ = 3;
  std::vector<Obstacle> obstacles_;
  std::vector<double> lo_[3], hi_[3];  // the boxes around the obstacles, axis by axis (K each)
  Floor floor_;
};

}  // namespace flowplan::collision
