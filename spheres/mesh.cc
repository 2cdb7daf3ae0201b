#include "spheres/mesh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "core/error.h"
#include "core/random.h"
#include "spheres/internal_geometry.h"

namespace flowplan::spheres {
namespace {

using internal::NumberText;
using internal::Vec3;

Vec3 Corner(const Mesh& mesh, int triangle, int k) {
  return Vec3(mesh.vertices[static_cast<size_t>(mesh.triangles[static_cast<size_t>(triangle)][k])]);
}

void CheckPositive(const char* function, const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    throw Error(std::string(function) + ": " + name + ": expected a positive finite length (m), got " +
                NumberText(value));
  }
}

// Turns every triangle of a convex mesh around the origin to face away from
// it; degenerate triangles are left as they are.
void OrientOutward(Mesh& mesh) {
  for (auto& t : mesh.triangles) {
    const Vec3 a(mesh.vertices[t[0]]), b(mesh.vertices[t[1]]), c(mesh.vertices[t[2]]);
    if (Dot(Cross(b - a, c - a), a + b + c) < 0.0) std::swap(t[1], t[2]);
  }
}

}  // namespace

namespace internal {

double SignedVolume(const Mesh& mesh) {
  double six_volume = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int i = static_cast<int>(t);
    six_volume += Dot(Corner(mesh, i, 0), Cross(Corner(mesh, i, 1), Corner(mesh, i, 2)));
  }
  return six_volume / 6.0;
}

std::vector<std::array<double, 3>> RandomSurfacePoints(const Mesh& mesh, double spacing, uint64_t seed,
                                                       std::vector<int>* triangle) {
  if (!(std::isfinite(spacing) && spacing > 0.0)) {
    throw Error("surface samples: spacing: expected a positive finite length (m), got " + NumberText(spacing));
  }
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int i = static_cast<int>(t);
    total += 0.5 * Norm(Cross(Corner(mesh, i, 1) - Corner(mesh, i, 0), Corner(mesh, i, 2) - Corner(mesh, i, 0)));
    cumulative[t] = total;
  }
  const double wanted = total / (spacing * spacing);
  constexpr double kMaxPoints = 5e7;
  if (wanted > kMaxPoints) {
    throw Error("surface samples: spacing " + NumberText(spacing) + " m on " + NumberText(total) +
                " m^2 of surface asks for " + NumberText(wanted) + " points (at most 5e7); use a larger spacing");
  }
  const auto count = static_cast<size_t>(std::llround(wanted));
  std::vector<std::array<double, 3>> points;
  points.reserve(count);
  if (triangle != nullptr) {
    triangle->clear();
    triangle->reserve(count);
  }
  if (total <= 0.0) return points;
  Rng rng(seed);
  for (size_t n = 0; n < count; ++n) {
    const double u = rng.Uniform() * total;
    size_t t = static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), u) - cumulative.begin());
    t = std::min(t, cumulative.size() - 1);
    const double r1 = std::sqrt(rng.Uniform()), r2 = rng.Uniform();
    const int i = static_cast<int>(t);
    const Vec3 p = Corner(mesh, i, 0) * (1.0 - r1) + Corner(mesh, i, 1) * (r1 * (1.0 - r2)) +
                   Corner(mesh, i, 2) * (r1 * r2);
    points.push_back(p.array());
    if (triangle != nullptr) triangle->push_back(i);
  }
  return points;
}

}  // namespace internal

void ValidateMesh(const Mesh& mesh) {
  if (mesh.triangles.empty()) throw Error("mesh: no triangles");
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    for (double x : mesh.vertices[v]) {
      if (!std::isfinite(x)) {
        throw Error("mesh: vertex " + std::to_string(v) + ": coordinate " + NumberText(x) + " is not finite");
      }
    }
  }
  const auto count = static_cast<int64_t>(mesh.vertices.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int index : mesh.triangles[t]) {
      if (index < 0 || index >= count) {
        throw Error("mesh: triangle " + std::to_string(t) + ": vertex index " + std::to_string(index) +
                    " outside 0.." + std::to_string(count - 1));
      }
    }
  }
}

Mesh BoxMesh(double lx, double ly, double lz) {
  CheckPositive("BoxMesh", "lx", lx);
  CheckPositive("BoxMesh", "ly", ly);
  CheckPositive("BoxMesh", "lz", lz);
  Mesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices.push_back({(i & 1 ? 0.5 : -0.5) * lx, (i & 2 ? 0.5 : -0.5) * ly, (i & 4 ? 0.5 : -0.5) * lz});
  }
  // Each face as a quad of vertex bits: fixed axis bit set or not.
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    mesh.triangles.push_back({f[0], f[1], f[2]});
    mesh.triangles.push_back({f[0], f[2], f[3]});
  }
  OrientOutward(mesh);
  return mesh;
}

Mesh CylinderMesh(double radius, double length, int segments) {
  CheckPositive("CylinderMesh", "radius", radius);
  CheckPositive("CylinderMesh", "length", length);
  if (segments < 3) throw Error("CylinderMesh: segments: expected at least 3, got " + std::to_string(segments));
  Mesh mesh;
  const double half = 0.5 * length;
  for (int side = 0; side < 2; ++side) {
    for (int i = 0; i < segments; ++i) {
      const double angle = 2.0 * M_PI * i / segments;
      mesh.vertices.push_back({radius * std::cos(angle), radius * std::sin(angle), side == 0 ? -half : half});
    }
  }
  const int bottom_centre = 2 * segments, top_centre = 2 * segments + 1;
  mesh.vertices.push_back({0.0, 0.0, -half});
  mesh.vertices.push_back({0.0, 0.0, half});
  for (int i = 0; i < segments; ++i) {
    const int j = (i + 1) % segments;
    mesh.triangles.push_back({i, j, segments + j});
    mesh.triangles.push_back({i, segments + j, segments + i});
    mesh.triangles.push_back({bottom_centre, j, i});
    mesh.triangles.push_back({top_centre, segments + i, segments + j});
  }
  OrientOutward(mesh);
  return mesh;
}

Mesh SphereMesh(double radius, int subdivisions) {
  CheckPositive("SphereMesh", "radius", radius);
  if (subdivisions < 0 || subdivisions > 8) {
    throw Error("SphereMesh: subdivisions: expected 0..8, got " + std::to_string(subdivisions));
  }
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> points = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                              {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                              {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (auto& p : points) p = p * (1.0 / Norm(p));
  std::vector<std::array<int, 3>> triangles = {
      {0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
      {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<int, int>, int> midpoint;
    auto middle = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto found = midpoint.find(key);
      if (found != midpoint.end()) return found->second;
      const Vec3 m = points[a] + points[b];
      points.push_back(m * (1.0 / Norm(m)));
      const int index = static_cast<int>(points.size()) - 1;
      midpoint.emplace(key, index);
      return index;
    };
    std::vector<std::array<int, 3>> finer;
    finer.reserve(4 * triangles.size());
    for (const auto& t : triangles) {
      const int ab = middle(t[0], t[1]), bc = middle(t[1], t[2]), ca = middle(t[2], t[0]);
      finer.push_back({t[0], ab, ca});
      finer.push_back({t[1], bc, ab});
      finer.push_back({t[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    triangles = std::move(finer);
  }
  Mesh mesh;
  mesh.vertices.reserve(points.size());
  for (const auto& p : points) mesh.vertices.push_back((p * radius).array());
  mesh.triangles = std::move(triangles);
  OrientOutward(mesh);
  return mesh;
}

Mesh CapsuleMesh(double radius, double length, int segments) {
  CheckPositive("CapsuleMesh", "radius", radius);
  if (!(std::isfinite(length) && length >= 0.0)) {
    throw Error("CapsuleMesh: length: expected a finite length >= 0 (m), got " + NumberText(length));
  }
  if (segments < 3) throw Error("CapsuleMesh: segments: expected at least 3, got " + std::to_string(segments));
  const int bands = std::max(2, segments / 4);
  const double half = 0.5 * length;
  // Rings from the top pole down: the top hemisphere's latitudes (the equator
  // last), then the bottom one's (its equator first, shared when length is 0).
  std::vector<std::pair<double, double>> rings;  // (ring radius, z)
  for (int i = 1; i <= bands; ++i) {
    const double polar = 0.5 * M_PI * i / bands;
    rings.emplace_back(radius * std::sin(polar), half + radius * std::cos(polar));
  }
  for (int i = length > 0.0 ? bands : bands - 1; i >= 1; --i) {
    const double polar = 0.5 * M_PI * i / bands;
    rings.emplace_back(radius * std::sin(polar), -half - radius * std::cos(polar));
  }
  Mesh mesh;
  mesh.vertices.push_back({0.0, 0.0, half + radius});
  for (const auto& [ring_radius, z] : rings) {
    for (int j = 0; j < segments; ++j) {
      const double angle = 2.0 * M_PI * j / segments;
      mesh.vertices.push_back({ring_radius * std::cos(angle), ring_radius * std::sin(angle), z});
    }
  }
  mesh.vertices.push_back({0.0, 0.0, -half - radius});
  const int top = 0, bottom = static_cast<int>(mesh.vertices.size()) - 1;
  const int ring_count = static_cast<int>(rings.size());
  auto at = [&](int ring, int j) { return 1 + ring * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) {
    mesh.triangles.push_back({top, at(0, j), at(0, j + 1)});
    for (int ring = 0; ring + 1 < ring_count; ++ring) {
      mesh.triangles.push_back({at(ring, j), at(ring + 1, j), at(ring + 1, j + 1)});
      mesh.triangles.push_back({at(ring, j), at(ring + 1, j + 1), at(ring, j + 1)});
    }
    mesh.triangles.push_back({bottom, at(ring_count - 1, j + 1), at(ring_count - 1, j)});
  }
  OrientOutward(mesh);
  return mesh;
}

Mesh Transformed(const Mesh& mesh, const std::array<double, 3>& translation,
                 const std::array<double, 4>& quaternion_wxyz, const std::array<double, 3>& scale) {
  ValidateMesh(mesh);
  double norm2 = 0.0;
  for (double q : quaternion_wxyz) {
    if (!std::isfinite(q)) throw Error("Transformed: quaternion: component " + NumberText(q) + " is not finite");
    norm2 += q * q;
  }
  if (!(norm2 > 0.0)) throw Error("Transformed: quaternion: expected a non-zero quaternion, got [0, 0, 0, 0]");
  for (double t : translation) {
    if (!std::isfinite(t)) throw Error("Transformed: translation: component " + NumberText(t) + " is not finite");
  }
  int mirrors = 0;
  for (double s : scale) {
    if (!std::isfinite(s) || s == 0.0) {
      throw Error("Transformed: scale: expected finite non-zero factors, got " + NumberText(s));
    }
    if (s < 0.0) ++mirrors;
  }
  const double inv = 1.0 / std::sqrt(norm2);
  const double w = quaternion_wxyz[0] * inv, x = quaternion_wxyz[1] * inv, y = quaternion_wxyz[2] * inv,
               z = quaternion_wxyz[3] * inv;
  const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  Mesh out;
  out.vertices.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices) {
    const double s[3] = {v[0] * scale[0], v[1] * scale[1], v[2] * scale[2]};
    std::array<double, 3> p;
    for (int r = 0; r < 3; ++r) p[r] = R[r][0] * s[0] + R[r][1] * s[1] + R[r][2] * s[2] + translation[r];
    out.vertices.push_back(p);
  }
  out.triangles = mesh.triangles;
  if (mirrors % 2 == 1) {
    for (auto& t : out.triangles) std::swap(t[1], t[2]);
  }
  return out;
}

Mesh Merged(const std::vector<Mesh>& meshes) {
  Mesh out;
  for (size_t m = 0; m < meshes.size(); ++m) {
    const Mesh& mesh = meshes[m];
    if (mesh.triangles.empty() && mesh.vertices.empty()) continue;
    try {
      ValidateMesh(mesh);
    } catch (const Error& e) {
      throw Error("Merged: mesh " + std::to_string(m) + ": " + e.what());
    }
    const int offset = static_cast<int>(out.vertices.size());
    out.vertices.insert(out.vertices.end(), mesh.vertices.begin(), mesh.vertices.end());
    for (const auto& t : mesh.triangles) out.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  }
  if (out.triangles.empty()) throw Error("Merged: no triangles in any of the " + std::to_string(meshes.size()) + " meshes");
  return out;
}

double MeshVolume(const Mesh& mesh) {
  ValidateMesh(mesh);
  return std::abs(internal::SignedVolume(mesh));
}

double MeshArea(const Mesh& mesh) {
  ValidateMesh(mesh);
  double area = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int i = static_cast<int>(t);
    area += 0.5 * Norm(Cross(Corner(mesh, i, 1) - Corner(mesh, i, 0), Corner(mesh, i, 2) - Corner(mesh, i, 0)));
  }
  return area;
}

double DistanceToSurface(const Mesh& mesh, const std::array<double, 3>& p) {
  ValidateMesh(mesh);
  const Vec3 q(p);
  double best = INFINITY;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int i = static_cast<int>(t);
    const Vec3 closest = internal::ClosestPointOnTriangle(q, Corner(mesh, i, 0), Corner(mesh, i, 1), Corner(mesh, i, 2));
    best = std::min(best, SquaredDistance(q, closest));
  }
  return std::sqrt(best);
}

double WindingNumber(const Mesh& mesh, const std::array<double, 3>& p) {
  ValidateMesh(mesh);
  const Vec3 q(p);
  double total = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int i = static_cast<int>(t);
    total += internal::SolidAngle(q, Corner(mesh, i, 0), Corner(mesh, i, 1), Corner(mesh, i, 2));
  }
  return total / (4.0 * M_PI);
}

bool Inside(const Mesh& mesh, const std::array<double, 3>& p) { return std::abs(WindingNumber(mesh, p)) > 0.5; }

std::vector<std::array<double, 3>> SurfaceSamples(const Mesh& mesh, double spacing, uint64_t seed) {
  ValidateMesh(mesh);
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const auto& t : mesh.triangles) {
    for (int index : t) used[static_cast<size_t>(index)] = 1;
  }
  std::vector<std::array<double, 3>> samples;
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (used[v]) samples.push_back(mesh.vertices[v]);
  }
  const auto random = internal::RandomSurfacePoints(mesh, spacing, seed, nullptr);
  samples.insert(samples.end(), random.begin(), random.end());
  return samples;
}

}  // namespace flowplan::spheres
