#pragma once

// Covering spheres for collision geometry: a set of spheres whose union
// contains every point of a mesh's surface (so a robot link colliding through
// them misses nothing its collision mesh would hit), each reaching at most
// about `overshoot` outside the geometry; and a report of how good a cover is.
// Plain C++ on double, deterministic for a seed, single-threaded.

#include <array>
#include <cstdint>
#include <vector>

#include "spheres/mesh.h"

namespace flowplan::spheres {

struct Sphere {
  std::array<double, 3> centre;  // m, in the mesh's frame
  double radius = 0.0;           // m
};

struct CoverSettings {
  /// m: how far a sphere may reach outside the geometry; larger = fewer, looser spheres.
  double overshoot = 0.01;
  /// m: the resolution of the surface the cover is computed on: it is cut
  /// into triangles no longer than min(spacing, overshoot / 2), each of which
  /// must lie in one sphere. The cover contains the whole surface at any
  /// spacing; a finer one gives slightly fewer or tighter spheres and costs
  /// time and memory in proportion to area / spacing².
  double spacing = 0.004;
  /// The most spheres a cover may have. When the overshoot asked for needs
  /// more, the overshoot is raised to the least value (within about 9 %)
  /// whose cover fits: coverage comes first, tightness gives way.
  int max_spheres = 64;
  /// Seeds the surface points the medial candidates start from and the grid's offset.
  uint64_t seed = 0;
};

/// Spheres whose union contains every point of every triangle of `mesh` —
/// hence every point of SurfaceSamples(mesh, spacing, seed) (checked before
/// returning) and of any denser sample. For a closed mesh, every sphere
/// reaches at most `overshoot` outside it, unless max_spheres forced a larger
/// overshoot (see CoverSettings::max_spheres).
/// Where a mesh has no inside (an open sheet) or a large hole, the spheres
/// there are centred on the surface with radius `overshoot`. At most
/// max_spheres spheres. The same mesh and settings give the same spheres, bit
/// for bit. Takes 0.3–0.6 s on one core for a 1000-triangle mesh 0.2 m
/// across at the defaults, about 3 times that when max_spheres forces a larger
/// overshoot; time grows with area / min(spacing, overshoot / 2)². Method: see
/// cover.cc.
/// @throws flowplan::Error naming the setting if overshoot or spacing is not
///   positive and finite or max_spheres < 1, or if the mesh is invalid or the
///   spacing would cut it into more than 4e6 pieces.
std::vector<Sphere> Cover(const Mesh& mesh, const CoverSettings& settings);

struct CoverReport {
  int spheres = 0;
  int64_t samples = 0;        // surface points checked
  int64_t uncovered = 0;      // of them, outside every sphere
  double largest_uncovered = 0.0;  // m, max over samples of (distance to the nearest sphere surface), 0 if all
                                   // covered (infinity without spheres)
  double mesh_volume = 0.0;        // m³, Monte Carlo with Inside (overlapping parts of a merged mesh count once)
  double union_volume = 0.0;       // m³, Monte Carlo: of the union of spheres
  double outside_volume = 0.0;     // m³, Monte Carlo: of the union of spheres, outside the mesh
  double overshoot_ratio = 0.0;    // outside_volume / mesh_volume (infinity for a mesh with no inside)
  double largest_outside = 0.0;    // m: how far any sphere reaches outside the surface at most, estimated
};

/// How well `spheres` cover `mesh`:
///  - coverage on SurfaceSamples(mesh, spacing, StreamSeed(seed, 1)), so that
///    passing the cover's own seed still gives points independent of the cover;
///    a sample is covered when its distance to some centre is <= the radius;
///  - volumes from `volume_samples` uniform points in the bounding box of the
///    spheres and the mesh (StreamSeed(seed, 2)), "inside" meaning Inside the
///    mesh (winding number); relative standard error about
///    sqrt((1 - f) / (f · volume_samples)) for a volume filling a fraction f of
///    the box. volume_samples = 0 skips them (all four volume figures NaN);
///  - largest_outside: the largest distance to the surface of a point outside
///    the mesh on some sphere's boundary, over 256 directions per sphere
///    (Fibonacci lattice) and the two along the line from its centre to the
///    nearest surface point (where a sphere centred inside reaches farthest
///    through a convex part); a lower estimate of the true maximum.
/// @throws flowplan::Error for an invalid mesh, spacing or volume_samples < 0,
///   or a sphere with a non-finite centre or a negative radius.
CoverReport CheckCover(const Mesh& mesh, const std::vector<Sphere>& spheres, double spacing, uint64_t seed,
                       int64_t volume_samples = 200000);

}  // namespace flowplan::spheres
