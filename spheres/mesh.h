#pragma once

// Triangle meshes of collision geometry, in metres: read from Wavefront OBJ and
// STL files or built from the URDF/MJCF collision primitives (box, cylinder,
// sphere, capsule), moved into place, merged, and queried exactly (distance to
// the surface, generalized winding number, random surface points). Plain C++
// on double: no LibTorch, no MuJoCo.
//
// A mesh is "valid" when it has at least one triangle, every coordinate is
// finite and every triangle refers to existing vertices; every function below
// checks this and throws flowplan::Error otherwise. Triangles are
// counter-clockwise seen from outside ("outward") for the meshes built here;
// the queries do not depend on it unless said so.
//
// These free functions are exact and O(triangles) per query; for many queries
// on one mesh use MeshIndex (spheres/mesh_index.h).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace flowplan::spheres {

struct Mesh {
  std::vector<std::array<double, 3>> vertices;  // (V, 3) m
  std::vector<std::array<int, 3>> triangles;    // (F, 3) indices into vertices, 0-based
};

/// Reads a triangle mesh, its format chosen by the extension (case-insensitive):
///  - `.obj` (Wavefront): `v x y z [w]` lines (w, and r g b colours after it, are
///    ignored) and `f` lines of 3 or more vertex references `i`, `i/t`, `i//n`
///    or `i/t/n` (1-based; negative = relative to the last vertex read so far);
///    polygons are fan-triangulated; every other line is ignored.
///  - `.stl`, binary or ASCII: a file whose size is 84 + 50·n, n being the
///    triangle count in bytes 80..83, is binary even if it starts with "solid";
///    otherwise a text file starting with "solid" is ASCII. Corners at exactly
///    the same position are merged into one vertex.
/// @throws flowplan::Error with one line naming the file and the line (OBJ,
///   ASCII STL) or byte offset and triangle (binary STL) at fault, e.g.
///   `link1.obj:17: f: vertex index 205 outside 1..200`: a missing or unreadable
///   file, an unknown extension, a malformed line, a non-finite number, a
///   truncated binary STL, or a mesh without triangles.
Mesh LoadMesh(const std::string& path);

/// A box with full side lengths lx, ly, lz (m), centred at the origin and
/// aligned with the axes: 8 vertices, 12 outward triangles.
/// @throws flowplan::Error unless every length is positive and finite.
Mesh BoxMesh(double lx, double ly, double lz);

/// A cylinder of the given radius and length (m) along z, centred at the
/// origin: a regular `segments`-gon prism (inscribed in the true cylinder) with
/// fan-triangulated caps.
/// @throws flowplan::Error unless radius and length are positive and finite and segments >= 3.
Mesh CylinderMesh(double radius, double length, int segments = 48);

/// A sphere of the given radius (m) centred at the origin: an icosahedron whose
/// triangles are split in four `subdivisions` times (20·4^subdivisions
/// triangles), its vertices on the sphere (so the mesh is inscribed).
/// @throws flowplan::Error unless radius is positive and finite and 0 <= subdivisions <= 8.
Mesh SphereMesh(double radius, int subdivisions = 3);

/// A capsule along z centred at the origin: a cylinder of the given radius and
/// `length` (m, between the two hemisphere centres; may be 0) closed by two
/// hemispheres, `segments` around the axis and segments / 4 (at least 2)
/// latitude bands per hemisphere; vertices on the true surface.
/// @throws flowplan::Error unless radius > 0, length >= 0 (both finite) and segments >= 3.
Mesh CapsuleMesh(double radius, double length, int segments = 48);

/// `mesh` scaled per axis (in its own frame), then rotated by the quaternion
/// (w, x, y, z; normalised here), then translated: x -> R (s ∘ x) + t. A scale
/// with an odd number of negative factors mirrors the mesh; its triangles are
/// then reversed so that an outward mesh stays outward.
/// @throws flowplan::Error if the mesh is invalid, the quaternion is zero or a
///   number is not finite, or a scale factor is zero.
Mesh Transformed(const Mesh& mesh, const std::array<double, 3>& translation,
                 const std::array<double, 4>& quaternion_wxyz,
                 const std::array<double, 3>& scale = {1.0, 1.0, 1.0});

/// All meshes in one (vertices appended in order, indices shifted); empty
/// input meshes are skipped.
/// @throws flowplan::Error if the result has no triangles or a mesh is invalid.
Mesh Merged(const std::vector<Mesh>& meshes);

/// @throws flowplan::Error naming the first problem: no triangles, a
///   non-finite coordinate, an index outside 0..V-1.
void ValidateMesh(const Mesh& mesh);

/// The enclosed volume (m³) by the divergence theorem, |Σ a·(b×c)| / 6 over the
/// triangles: exact for a closed, consistently oriented mesh (either way round).
double MeshVolume(const Mesh& mesh);

/// The total area (m²) of the triangles.
double MeshArea(const Mesh& mesh);

/// The exact distance (m) from p to the nearest point of any triangle.
double DistanceToSurface(const Mesh& mesh, const std::array<double, 3>& p);

/// The generalized winding number at p (Jacobson et al. 2013): the sum of the
/// triangles' signed solid angles seen from p, over 4π. 1 inside and 0 outside
/// a closed outward mesh (-1 inside an inward one), and close to that for a
/// mesh with small holes or a few flipped triangles; 0.5 on a flat part of the surface.
double WindingNumber(const Mesh& mesh, const std::array<double, 3>& p);

/// Whether p is inside the mesh: |WindingNumber| > 0.5. The absolute value
/// makes a mesh whose triangles all face inward (a mirrored export) still
/// enclose its inside; a point on the surface is not inside.
bool Inside(const Mesh& mesh, const std::array<double, 3>& p);

/// Random points on the surface, area-weighted: every vertex used by a
/// triangle (once, in index order), then round(area / spacing²) points drawn
/// uniformly over the area from Rng(seed). The same seed gives the same points.
/// @throws flowplan::Error if spacing is not positive and finite or asks for
///   more than 5e7 points, or the mesh is invalid.
std::vector<std::array<double, 3>> SurfaceSamples(const Mesh& mesh, double spacing, uint64_t seed);

}  // namespace flowplan::spheres
