#pragma once

// Private to flowplan_spheres: a small 3-vector and the exact point–triangle
// kernels (closest point, signed solid angle) that mesh.cc's brute-force
// queries and MeshIndex's accelerated ones share, so both give the same numbers.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace flowplan::spheres {
struct Mesh;
}

namespace flowplan::spheres::internal {

/// A number for an error message: up to 9 significant digits ("0.004", "nan").
inline std::string NumberText(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", value);
  return text;
}

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;

  Vec3() = default;
  Vec3(double x_in, double y_in, double z_in) : x(x_in), y(y_in), z(z_in) {}
  explicit Vec3(const std::array<double, 3>& a) : x(a[0]), y(a[1]), z(a[2]) {}
  std::array<double, 3> array() const { return {x, y, z}; }
  double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
};

inline Vec3 operator+(const Vec3& a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(const Vec3& a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator-(const Vec3& a) { return {-a.x, -a.y, -a.z}; }
inline Vec3 operator*(const Vec3& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 operator*(double s, const Vec3& a) { return {a.x * s, a.y * s, a.z * s}; }
inline double Dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double SquaredNorm(const Vec3& a) { return Dot(a, a); }
inline double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }
inline double SquaredDistance(const Vec3& a, const Vec3& b) { return SquaredNorm(a - b); }
inline double Distance(const Vec3& a, const Vec3& b) { return std::sqrt(SquaredNorm(a - b)); }
inline Vec3 Min(const Vec3& a, const Vec3& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
inline Vec3 Max(const Vec3& a, const Vec3& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

/// The point of segment [a, b] nearest to p (a if the segment has length zero).
inline Vec3 ClosestPointOnSegment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = SquaredNorm(ab);
  if (!(len2 > 0.0)) return a;
  const double t = std::clamp(Dot(p - a, ab) / len2, 0.0, 1.0);
  return a + ab * t;
}

/// The point of triangle (a, b, c) nearest to p: Ericson, Real-Time Collision
/// Detection §5.1.5, by Voronoi regions; a degenerate (collinear or repeated
/// corners) triangle is treated as its three edges.
inline Vec3 ClosestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a;
  const double area2 = SquaredNorm(Cross(ab, ac));
  const double scale2 = std::max(SquaredNorm(ab), SquaredNorm(ac));
  if (!(area2 > 1e-24 * scale2 * scale2)) {
    const Vec3 candidates[3] = {ClosestPointOnSegment(p, a, b), ClosestPointOnSegment(p, b, c),
                                ClosestPointOnSegment(p, c, a)};
    int best = 0;
    for (int i = 1; i < 3; ++i) {
      if (SquaredDistance(p, candidates[i]) < SquaredDistance(p, candidates[best])) best = i;
    }
    return candidates[best];
  }
  const Vec3 ap = p - a;
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Vec3 bp = p - b;
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

/// The signed solid angle (sr) that triangle (a, b, c) subtends at p, positive
/// when p sees the triangle's back (counter-clockwise corners wind away from p):
/// Van Oosterom & Strackee (1983). Zero when p lies in the triangle's plane
/// (on the triangle itself the sign would be arbitrary).
inline double SolidAngle(const Vec3& p, const Vec3& a_in, const Vec3& b_in, const Vec3& c_in) {
  const Vec3 a = a_in - p, b = b_in - p, c = c_in - p;
  const double la = Norm(a), lb = Norm(b), lc = Norm(c);
  const double numerator = Dot(a, Cross(b, c));
  const double denominator = la * lb * lc + Dot(a, b) * lc + Dot(a, c) * lb + Dot(b, c) * la;
  if (numerator == 0.0) return 0.0;
  return 2.0 * std::atan2(numerator, denominator);
}

/// Squared distance from p to the axis-aligned box [lo, hi] (0 inside).
inline double SquaredDistanceToBox(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  const double dx = std::max({lo.x - p.x, 0.0, p.x - hi.x});
  const double dy = std::max({lo.y - p.y, 0.0, p.y - hi.y});
  const double dz = std::max({lo.z - p.z, 0.0, p.z - hi.z});
  return dx * dx + dy * dy + dz * dz;
}

/// Area-weighted random points on the mesh's triangles, about area / spacing²
/// of them, drawn from Rng(seed); `triangle` (if not null) receives the index
/// of the triangle each point lies on. The mesh must be valid (ValidateMesh).
/// @throws flowplan::Error if spacing is not positive or would give too many points.
std::vector<std::array<double, 3>> RandomSurfacePoints(const Mesh& mesh, double spacing, uint64_t seed,
                                                       std::vector<int>* triangle);

/// The signed divergence-theorem volume (positive for an outward closed mesh).
double SignedVolume(const Mesh& mesh);

}  // namespace flowplan::spheres::internal
