#pragma once

// MeshIndex: the exact queries of spheres/mesh.h (distance to the surface,
// generalized winding number) for many points on one mesh, in about
// O(log F) and O(√F log F) time per point instead of O(F).
//
// Distance: a bounding-volume hierarchy over the triangles (median splits),
// pruned by box distance. Winding number: the same hierarchy, where a node
// whose box does not contain the point is replaced by its "cap" (Jacobson et
// al. 2013, §3.3): the node's triangles and the fan over their boundary edges
// form a closed surface, whose winding number is 0 outside its convex hull, so
// the node contributes exactly what the fan does — and the fan has only as
// many triangles as the patch has boundary edges (none for a closed part).
// Corners at exactly the same position are merged first so that a mesh stored
// as separate triangles (STL, split normals) still has short boundaries.
// The results equal the brute-force functions' up to rounding.
//
// Immutable after construction; safe to query from several threads.

#include <array>
#include <cmath>
#include <vector>

#include "spheres/internal_geometry.h"
#include "spheres/mesh.h"

namespace flowplan::spheres {

class MeshIndex {
 public:
  /// Copies and indexes the mesh.
  /// @throws flowplan::Error if the mesh is invalid (ValidateMesh).
  explicit MeshIndex(const Mesh& mesh);

  /// The exact distance (m) from p to the surface, as DistanceToSurface.
  double Distance(const std::array<double, 3>& p) const;
  /// The point of the surface nearest to p.
  std::array<double, 3> ClosestPoint(const std::array<double, 3>& p) const;
  /// The generalized winding number at p, as spheres::WindingNumber.
  double WindingNumber(const std::array<double, 3>& p) const;
  /// |WindingNumber(p)| > 0.5, as spheres::Inside.
  bool Inside(const std::array<double, 3>& p) const { return std::abs(WindingNumber(p)) > 0.5; }

  /// The corners of the mesh's axis-aligned bounding box (m).
  std::array<double, 3> lower() const { return nodes_[0].lo.array(); }
  std::array<double, 3> upper() const { return nodes_[0].hi.array(); }
  int num_triangles() const { return static_cast<int>(triangles_.size()); }

  /// The same queries on internal::Vec3, for flowplan_spheres' own loops.
  /// `closest` (if not null) receives the nearest surface point.
  double DistanceTo(const internal::Vec3& p, internal::Vec3* closest = nullptr) const;
  double WindingNumberAt(const internal::Vec3& p) const;

 private:
  struct Node {
    internal::Vec3 lo, hi;  // bounding box of the node's triangles
    int first = 0;          // triangles first .. first + count - 1 of triangles_
    int count = 0;
    int left = -1, right = -1;  // children; -1 for a leaf
    int cap_first = 0;          // cap edges cap_first .. cap_first + cap_count - 1
    int cap_count = -1;         // -1: no cap (a leaf, or a boundary longer than the patch)
    int cap_apex = 0;           // the fan's apex, a vertex of the boundary
  };
  struct CapEdge {
    int a, b;    // the boundary edge a -> b, as the patch's triangles run along it
    int weight;  // how many more times a -> b occurs than b -> a
  };

  int Build(std::vector<int>& order, const std::vector<internal::Vec3>& centroids, int first, int count);
  void BuildCap(Node& node);

  std::vector<internal::Vec3> points_;
  std::vector<std::array<int, 3>> triangles_;  // in hierarchy order
  std::vector<Node> nodes_;                     // nodes_[0] is the root
  std::vector<CapEdge> cap_edges_;
};

}  // namespace flowplan::spheres
