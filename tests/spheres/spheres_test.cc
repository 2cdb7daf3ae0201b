// flowplan_spheres: mesh files, primitive meshes, exact geometry queries and
// the sphere cover, against closed forms and independent references.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/random.h"
#include "spheres/cover.h"
#include "spheres/mesh.h"
#include "spheres/mesh_index.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::spheres {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using Point = std::array<double, 3>;

// ---- helpers -------------------------------------------------------------------

std::string WriteFile(const std::string& name, const std::string& bytes) {
  const std::string path = (testing::ScratchDir() / name).string();
  std::ofstream out(path, std::ios::binary);
  out << bytes;
  return path;
}

// The message of the Error LoadMesh throws, or "(no error)".
std::string LoadError(const std::string& path) {
  try {
    LoadMesh(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

// Each triangle as its three corners' coordinates, in order.
std::vector<std::array<Point, 3>> Soup(const Mesh& mesh) {
  std::vector<std::array<Point, 3>> soup;
  for (const auto& t : mesh.triangles) soup.push_back({mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]});
  return soup;
}

void PutU32(std::string& out, uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xff));
}

void PutF32(std::string& out, float f) {
  uint32_t bits;
  std::memcpy(&bits, &f, sizeof(bits));
  PutU32(out, bits);
}

// A binary STL of the mesh's triangles; the 80-byte header starts with `header`.
std::string BinaryStl(const Mesh& mesh, const std::string& header) {
  std::string out = header;
  out.resize(80, ' ');
  PutU32(out, static_cast<uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) PutF32(out, 0.0f);  // normal, ignored
    for (int c : t) {
      for (int k = 0; k < 3; ++k) PutF32(out, static_cast<float>(mesh.vertices[c][k]));
    }
    out.push_back('\0');
    out.push_back('\0');
  }
  return out;
}

std::string AsciiStl(const Mesh& mesh) {
  std::string out = "solid pyramid\n";
  char line[128];
  for (const auto& t : mesh.triangles) {
    out += "  facet normal 0 0 0\n    outer loop\n";
    for (int c : t) {
      std::snprintf(line, sizeof(line), "      vertex %.9g %.9g %.9g\n", mesh.vertices[c][0], mesh.vertices[c][1],
                    mesh.vertices[c][2]);
      out += line;
    }
    out += "    endloop\n  endfacet\n";
  }
  return out + "endsolid pyramid\n";
}

// A square pyramid: base 1 x 1 at z = 0, apex (0.5, 0.5, 1), outward.
Mesh Pyramid() {
  Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}};
  // The OBJ below writes the base as the quad 4 3 2 1 (fanned from 4) and the sides as triangles.
  mesh.triangles = {{3, 2, 1}, {3, 1, 0}, {0, 1, 4}, {1, 2, 4}, {3, 4, 2}, {3, 0, 4}};
  return mesh;
}

Point Add(const Point& a, const Point& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
double Norm(const Point& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

Point RandomPoint(Rng& rng, double half) {
  return {rng.Uniform(-half, half), rng.Uniform(-half, half), rng.Uniform(-half, half)};
}

// The largest h such that the convex, outward `mesh` contains the capsule of
// radius h around segment [a, b] (a = b: the ball): the least, over faces, of
// the face plane's offset minus the farther endpoint's height above it.
double InscribedRadius(const Mesh& mesh, const Point& a, const Point& b) {
  double h = INFINITY;
  for (const auto& t : mesh.triangles) {
    const Point& p = mesh.vertices[t[0]];
    const Point& q = mesh.vertices[t[1]];
    const Point& r = mesh.vertices[t[2]];
    const Point u = {q[0] - p[0], q[1] - p[1], q[2] - p[2]}, v = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
    Point n = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double length = Norm(n);
    if (length == 0.0) continue;
    for (double& x : n) x /= length;
    const double offset = n[0] * p[0] + n[1] * p[1] + n[2] * p[2];
    const double height = std::max(n[0] * a[0] + n[1] * a[1] + n[2] * a[2], n[0] * b[0] + n[1] * b[1] + n[2] * b[2]);
    h = std::min(h, offset - height);
  }
  return h;
}

// Every directed edge of a closed, consistently oriented mesh occurs once, and its reverse once.
bool ClosedAndConsistent(const Mesh& mesh) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++count[{t[k], t[(k + 1) % 3]}];
  }
  for (const auto& [edge, n] : count) {
    const auto reverse = count.find({edge.second, edge.first});
    if (n != 1 || reverse == count.end() || reverse->second != 1) return false;
  }
  return true;
}

// ---- LoadMesh ------------------------------------------------------------------

TEST(LoadMeshTest, ObjAsciiStlAndBinaryStlOfOneMeshReadToTheSameTriangles) {
  const std::string obj =
      "# a square pyramid\n"
      "o pyramid\n"
      "mtllib pyramid.mtl\n"
      "v 0 0 0\n"
      "v 1 0 0\n"
      "v 1 1 0 1.0\n"                  // with w
      "v 0 1 0\r\n"                    // a CRLF line
      "v 0.5 +0.5 1 0.2 0.3 0.4\n"     // with a colour
      "vt 0 0\n"
      "vn 0 0 1\n"
      "usemtl stone\n"
      "s off\n"
      "f 4/1/1 3/1/1 2/1/1 1/1/1\n"    // the base as a quad, i/t/n
      "f 1//1 2//1 5//1   # i//n\n"
      "f 2/1 3/1 5/1\n"                // i/t
      "f -2 -1 -3\n"                   // relative: 4 5 3
      "f 4 1 5\n";
  const Mesh from_obj = LoadMesh(WriteFile("pyramid.obj", obj));
  const Mesh from_ascii = LoadMesh(WriteFile("pyramid_ascii.STL", AsciiStl(Pyramid())));
  // A binary STL whose header starts with "solid", as many exporters write.
  const Mesh from_binary = LoadMesh(WriteFile("pyramid_binary.stl", BinaryStl(Pyramid(), "solid pyramid (binary)")));

  EXPECT_EQ(from_obj.vertices, Pyramid().vertices);
  EXPECT_EQ(from_obj.triangles, Pyramid().triangles);
  EXPECT_EQ(Soup(from_ascii), Soup(Pyramid()));
  EXPECT_EQ(Soup(from_binary), Soup(Pyramid()));
  // STL corners at one position are one vertex.
  EXPECT_EQ(from_ascii.vertices.size(), 5u);
  EXPECT_EQ(from_binary.vertices.size(), 5u);
  EXPECT_NEAR(MeshVolume(from_binary), 1.0 / 3.0, 1e-12);
}

TEST(LoadMeshTest, MalformedFilesGiveOneErrorNamingTheFileAndTheLineOrByte) {
  const std::string three = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  std::string truncated = BinaryStl(Pyramid(), "solid but binary");
  truncated.resize(84 + 50 + 20);  // triangle 1 cut short
  std::string binary_nan = BinaryStl(Pyramid(), "binary");
  const float nan = NAN;
  std::memcpy(&binary_nan[84 + 50 + 12 + 4], &nan, sizeof(nan));  // triangle 1, corner 0, y
  std::string binary_empty(80, ' ');
  PutU32(binary_empty, 0);
  const std::string facet_head = "solid s\n facet normal 0 0 1\n  outer loop\n";
  struct Case {
    std::string file, content, message;
  };
  const std::vector<Case> cases = {
      {"bad_index.obj", three + "\nf 1 2 9\n", "bad_index.obj:5: f: vertex index 9 outside 1..3"},
      {"bad_relative.obj", three + "f -1 -2 -5\n", "bad_relative.obj:4: f: relative vertex index -5 outside -1..-3"},
      {"zero_index.obj", three + "f 0 1 2\n", "zero_index.obj:4: f: vertex index 0"},
      {"missing_coordinate.obj", "v 0 0 0\nv 1 2\n", "missing_coordinate.obj:2: v: expected x y z [w], got 2 numbers"},
      {"nan.obj", three + "v 1 nan 2\nf 1 2 3\n", "nan.obj:4: v: coordinate nan is not finite"},
      {"inf.obj", "v 1 2 -inf\n", "inf.obj:1: v: coordinate -inf is not finite"},
      {"word.obj", "v 1 x 2\n", "word.obj:1: v: 'x' is not a number"},
      {"comma.obj", "v 1,5 0 2\n", "comma.obj:1: v: '1,5' is not a number"},
      {"two_corners.obj", three + "f 1 2\n", "two_corners.obj:4: f: expected at least 3 vertices, got 2"},
      {"bad_reference.obj", three + "f 1 a/1 3\n", "bad_reference.obj:4: f: 'a/1' is not a vertex reference"},
      {"empty.obj", three, "empty.obj: no triangles"},
      {"missing_coordinate.stl", facet_head + "   vertex 0 0 0\n   vertex 1 2\n",
       "missing_coordinate.stl:5: vertex: expected 3 coordinates, got 2"},
      {"nan.stl", facet_head + "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 NaN 0\n",
       "nan.stl:6: vertex: coordinate NaN is not finite"},
      {"short_loop.stl", facet_head + "   vertex 0 0 0\n   vertex 1 0 0\n  endloop\n",
       "short_loop.stl:6: expected 'vertex x y z', got '  endloop'"},
      {"unfinished.stl", facet_head + "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n",
       "unfinished.stl:6: the file ends inside a facet"},
      {"no_facets.stl", "solid s\nendsolid s\n", "no_facets.stl: ASCII STL without facets"},
      {"truncated.stl", truncated, "truncated.stl: byte 134: triangle 1 of 6 is truncated"},
      {"binary_nan.stl", binary_nan, "binary_nan.stl: byte 150 (triangle 1, corner 0): coordinate nan is not finite"},
      {"binary_empty.stl", binary_empty, "binary_empty.stl: binary STL without triangles"},
      {"tiny.stl", "abc", "tiny.stl: 3 bytes: too short for a binary STL"},
      {"mesh.ply", "ply\n", "mesh.ply: unknown mesh format '.ply' (expected .obj or .stl)"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const std::string path = WriteFile(c.file, c.content);
    EXPECT_THAT([&] { LoadMesh(path); }, ThrowsMessage<Error>(HasSubstr(c.message)));
    const std::string message = LoadError(path);
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_THAT(message, HasSubstr(path));
  }
  const std::string missing = (testing::ScratchDir() / "nowhere.obj").string();
  EXPECT_THAT([&] { LoadMesh(missing); }, ThrowsMessage<Error>(HasSubstr(missing + ": cannot open the mesh file")));
}

TEST(LoadMeshTest, ObjFacesMayReferToVerticesDefinedLater) {
  const Mesh mesh = LoadMesh(WriteFile("forward.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"));
  ASSERT_EQ(mesh.triangles.size(), 1u);
  EXPECT_NEAR(MeshArea(mesh), 0.5, 1e-15);
}

// ---- primitives, transforms, volume and area -------------------------------------

TEST(PrimitiveMeshTest, PrimitivesAreClosedAndOutward) {
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"box", BoxMesh(0.1, 0.2, 0.3)},       {"cylinder", CylinderMesh(0.05, 0.2, 24)},
      {"sphere", SphereMesh(0.1, 2)},         {"capsule", CapsuleMesh(0.05, 0.1, 24)},
      {"flat capsule", CapsuleMesh(0.05, 0.0, 16)}};
  for (const auto& [name, mesh] : meshes) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(ClosedAndConsistent(mesh));
    EXPECT_NEAR(WindingNumber(mesh, {0, 0, 0}), 1.0, 1e-12);  // outward: +1 inside
    EXPECT_NEAR(WindingNumber(mesh, {1, 1, 1}), 0.0, 1e-12);
  }
}

TEST(PrimitiveMeshTest, BoxVolumeAndAreaAreExact) {
  const Mesh box = BoxMesh(0.1, 0.2, 0.3);
  EXPECT_EQ(box.triangles.size(), 12u);
  EXPECT_NEAR(MeshVolume(box), 0.1 * 0.2 * 0.3, 1e-15);
  EXPECT_NEAR(MeshArea(box), 2 * (0.1 * 0.2 + 0.2 * 0.3 + 0.1 * 0.3), 1e-15);
}

TEST(PrimitiveMeshTest, CylinderIsTheInscribedPrismAndNearTheClosedForm) {
  const double r = 0.05, L = 0.2;
  const int n = 48;
  const Mesh cylinder = CylinderMesh(r, L, n);
  const double polygon = 0.5 * n * r * r * std::sin(2 * M_PI / n);
  EXPECT_NEAR(MeshVolume(cylinder), polygon * L, 1e-15);
  EXPECT_NEAR(MeshArea(cylinder), 2 * polygon + n * 2 * r * std::sin(M_PI / n) * L, 1e-14);
  // The discretisation error of an inscribed 48-gon: 1 - sin(2π/n) n / (2π) = 0.29 %.
  const double error = 1 - std::sin(2 * M_PI / n) * n / (2 * M_PI);
  EXPECT_NEAR(MeshVolume(cylinder), M_PI * r * r * L, 1.01 * error * M_PI * r * r * L);
  EXPECT_LT(MeshVolume(cylinder), M_PI * r * r * L);
  EXPECT_NEAR(MeshArea(cylinder), 2 * M_PI * r * r + 2 * M_PI * r * L, 0.01 * (2 * M_PI * r * (r + L)));
}

TEST(PrimitiveMeshTest, SphereAndCapsuleLieBetweenTheirInscribedAndTrueShapes) {
  const double r = 0.1;
  const Mesh sphere = SphereMesh(r, 3);
  EXPECT_EQ(sphere.triangles.size(), 20u * 64u);
  const double h = InscribedRadius(sphere, {0, 0, 0}, {0, 0, 0});
  EXPECT_GT(h, 0.99 * r);
  // A convex mesh between the balls of radius h and r has volume and area between theirs.
  EXPECT_GE(MeshVolume(sphere), 4.0 / 3.0 * M_PI * h * h * h);
  EXPECT_LE(MeshVolume(sphere), 4.0 / 3.0 * M_PI * r * r * r);
  EXPECT_GE(MeshArea(sphere), 4 * M_PI * h * h);
  EXPECT_LE(MeshArea(sphere), 4 * M_PI * r * r);
  EXPECT_NEAR(MeshVolume(sphere), 4.0 / 3.0 * M_PI * r * r * r, 0.02 * 4.0 / 3.0 * M_PI * r * r * r);

  const double L = 0.15;
  const Mesh capsule = CapsuleMesh(r, L, 48);
  const double hc = InscribedRadius(capsule, {0, 0, -L / 2}, {0, 0, L / 2});
  EXPECT_GT(hc, 0.99 * r);
  auto capsule_volume = [&](double radius) { return M_PI * radius * radius * L + 4.0 / 3.0 * M_PI * std::pow(radius, 3); };
  EXPECT_GE(MeshVolume(capsule), capsule_volume(hc));
  EXPECT_LE(MeshVolume(capsule), capsule_volume(r));
}

TEST(PrimitiveMeshTest, BadDimensionsNameTheFunctionAndTheValue) {
  EXPECT_THAT([] { BoxMesh(0.1, -1, 0.1); }, ThrowsMessage<Error>(HasSubstr("BoxMesh: ly: expected a positive")));
  EXPECT_THAT([] { CylinderMesh(NAN, 0.1); }, ThrowsMessage<Error>(HasSubstr("CylinderMesh: radius")));
  EXPECT_THAT([] { CylinderMesh(0.1, 0.1, 2); }, ThrowsMessage<Error>(HasSubstr("segments: expected at least 3, got 2")));
  EXPECT_THAT([] { SphereMesh(0.1, 9); }, ThrowsMessage<Error>(HasSubstr("SphereMesh: subdivisions: expected 0..8")));
  EXPECT_THAT([] { CapsuleMesh(0.1, -0.1); }, ThrowsMessage<Error>(HasSubstr("CapsuleMesh: length")));
}

TEST(TransformTest, ScalesThenRotatesThenTranslates) {
  Mesh mesh;
  mesh.vertices = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 1, 2}};
  const double s = std::sqrt(0.5);
  // 90° about z, not normalised (it is normalised inside).
  const Mesh moved = Transformed(mesh, {1, 2, 3}, {2 * s, 0, 0, 2 * s}, {2, 3, 4});
  const std::vector<Point> expected = {{1, 4, 3}, {-2, 2, 3}, {1, 2, 7}};
  for (int v = 0; v < 3; ++v) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(moved.vertices[v][k], expected[v][k], 1e-15);
  }
  EXPECT_THAT([&] { Transformed(mesh, {0, 0, 0}, {0, 0, 0, 0}); },
              ThrowsMessage<Error>(HasSubstr("Transformed: quaternion: expected a non-zero quaternion")));
  EXPECT_THAT([&] { Transformed(mesh, {0, 0, 0}, {1, 0, 0, 0}, {1, 0, 1}); },
              ThrowsMessage<Error>(HasSubstr("Transformed: scale")));
}

TEST(TransformTest, VolumeScalesByTheScalesAndAMirroredMeshStaysOutward) {
  const Mesh box = BoxMesh(0.1, 0.2, 0.3);
  const Mesh moved = Transformed(box, {1, -2, 0.5}, {0.3, -0.2, 0.6, 0.1}, {2, 0.5, 3});
  EXPECT_NEAR(MeshVolume(moved), 3 * MeshVolume(box), 1e-14);
  EXPECT_NEAR(WindingNumber(moved, {1, -2, 0.5}), 1.0, 1e-12);
  const Mesh mirrored = Transformed(box, {1, 0, 0}, {1, 0, 0, 0}, {-1, 1, 1});
  EXPECT_NEAR(WindingNumber(mirrored, {1, 0, 0}), 1.0, 1e-12);
  EXPECT_TRUE(ClosedAndConsistent(mirrored));
}

TEST(TransformTest, MergedKeepsEveryTriangleWithShiftedIndices) {
  const Mesh a = BoxMesh(0.1, 0.1, 0.1);
  const Mesh b = Transformed(SphereMesh(0.05, 1), {1, 0, 0}, {1, 0, 0, 0});
  const Mesh merged = Merged({a, Mesh{}, b});
  EXPECT_EQ(merged.vertices.size(), a.vertices.size() + b.vertices.size());
  EXPECT_EQ(merged.triangles.size(), a.triangles.size() + b.triangles.size());
  EXPECT_NEAR(MeshVolume(merged), MeshVolume(a) + MeshVolume(b), 1e-15);
  EXPECT_EQ(Soup(merged).back(), Soup(b).back());
  EXPECT_THAT([] { Merged({}); }, ThrowsMessage<Error>(HasSubstr("Merged: no triangles")));
  Mesh broken = a;
  broken.triangles[3][1] = 8;
  EXPECT_THAT([&] { Merged({a, broken}); },
              ThrowsMessage<Error>(HasSubstr("Merged: mesh 1: mesh: triangle 3: vertex index 8 outside 0..7")));
}

// ---- queries -------------------------------------------------------------------

TEST(QueryTest, DistanceToSurfaceMatchesTheClosedFormForABox) {
  const Point half = {0.05, 0.1, 0.15};
  const Mesh box = BoxMesh(2 * half[0], 2 * half[1], 2 * half[2]);
  Rng rng(11);
  for (int i = 0; i < 2000; ++i) {
    const Point p = RandomPoint(rng, 0.3);
    double outside2 = 0.0, inside = INFINITY;
    for (int k = 0; k < 3; ++k) {
      const double q = std::abs(p[k]) - half[k];
      outside2 += q > 0 ? q * q : 0.0;
      inside = std::min(inside, -q);
    }
    const double expected = outside2 > 0.0 ? std::sqrt(outside2) : inside;
    ASSERT_NEAR(DistanceToSurface(box, p), expected, 1e-14) << p[0] << " " << p[1] << " " << p[2];
  }
}

TEST(QueryTest, InsideMatchesTheAnalyticInsideOfABoxASphereAndACylinder) {
  const double r = 0.1, L = 0.25;
  const int n = 32;
  const Mesh sphere = SphereMesh(r, 3);
  const Mesh cylinder = CylinderMesh(r, L, n);
  // A box turned about (1, 1, 0) by 30° and moved: the analytic test runs in its own frame.
  const double angle = M_PI / 6, s = std::sin(angle / 2) / std::sqrt(2.0);
  const std::array<double, 4> q = {std::cos(angle / 2), s, s, 0};
  const Point t = {0.02, -0.01, 0.03}, half = {0.05, 0.08, 0.11};
  const Mesh box = Transformed(BoxMesh(2 * half[0], 2 * half[1], 2 * half[2]), t, q);
  auto box_frame = [&](const Point& p) {  // R^T (p - t)
    const double w = q[0], x = q[1], y = q[2], z = q[3];
    const double R[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                            {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                            {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    Point local;
    for (int c = 0; c < 3; ++c) local[c] = R[0][c] * (p[0] - t[0]) + R[1][c] * (p[1] - t[1]) + R[2][c] * (p[2] - t[2]);
    return local;
  };
  const double h_sphere = InscribedRadius(sphere, {0, 0, 0}, {0, 0, 0});
  const double h_cylinder = r * std::cos(M_PI / n);
  Rng rng(5);
  int inside_count[3] = {0, 0, 0};
  for (int i = 0; i < 3000; ++i) {
    const Point p = RandomPoint(rng, 0.2);
    const double radial = std::hypot(p[0], p[1]), centre = Norm(p);
    // Sphere (skipping the band between the inscribed and the true sphere).
    if (centre < h_sphere || centre > r) {
      const bool expected = centre < h_sphere;
      ASSERT_EQ(Inside(sphere, p), expected);
      ASSERT_NEAR(WindingNumber(sphere, p), expected ? 1.0 : 0.0, 1e-9);
      inside_count[0] += expected;
    }
    if ((radial < h_cylinder || radial > r) && std::abs(std::abs(p[2]) - L / 2) > 1e-9) {
      const bool expected = radial < h_cylinder && std::abs(p[2]) < L / 2;
      ASSERT_EQ(Inside(cylinder, p), expected);
      inside_count[1] += expected;
    }
    const Point local = box_frame(p);
    const bool in_box = std::abs(local[0]) < half[0] && std::abs(local[1]) < half[1] && std::abs(local[2]) < half[2];
    ASSERT_EQ(Inside(box, p), in_box);
    inside_count[2] += in_box;
  }
  // The random points did test both sides of every shape.
  for (int c : inside_count) {
    EXPECT_GT(c, 100);
    EXPECT_LT(c, 2900);
  }
}

TEST(QueryTest, WindingNumberToleratesASmallHoleAndAFewFlippedTriangles) {
  const double r = 0.1;
  Mesh damaged = SphereMesh(r, 3);
  damaged.triangles.erase(damaged.triangles.begin() + 100);  // a hole
  for (int t : {7, 400, 900}) std::swap(damaged.triangles[t][1], damaged.triangles[t][2]);
  Rng rng(8);
  for (int i = 0; i < 500; ++i) {
    const Point p = RandomPoint(rng, 0.2);
    const double centre = Norm(p);
    if (centre < 0.8 * r) {
      ASSERT_TRUE(Inside(damaged, p));
      ASSERT_NEAR(WindingNumber(damaged, p), 1.0, 0.1);
    } else if (centre > 1.2 * r) {
      ASSERT_FALSE(Inside(damaged, p));
      ASSERT_NEAR(WindingNumber(damaged, p), 0.0, 0.1);
    }
  }
  // A mesh whose triangles all face inward still has its inside.
  const Mesh inverted = Transformed(BoxMesh(0.1, 0.1, 0.1), {0, 0, 0}, {1, 0, 0, 0}, {-1, -1, -1});
  Mesh flipped = BoxMesh(0.1, 0.1, 0.1);
  for (auto& t : flipped.triangles) std::swap(t[1], t[2]);
  EXPECT_NEAR(WindingNumber(flipped, {0.01, 0, 0}), -1.0, 1e-12);
  EXPECT_TRUE(Inside(flipped, {0.01, 0, 0}));
  EXPECT_TRUE(Inside(inverted, {0.01, 0, 0}));
}

TEST(QueryTest, MeshIndexAgreesWithTheBruteForceQueries) {
  // Meshes with and without boundaries, overlapping parts and corners stored once per triangle.
  const Mesh cylinder = CylinderMesh(0.05, 0.2, 16);
  Mesh open_cylinder = cylinder;  // the side only: CylinderMesh writes 2 side and 2 cap triangles per segment
  open_cylinder.triangles.clear();
  for (size_t t = 0; t < cylinder.triangles.size(); ++t) {
    if (t % 4 < 2) open_cylinder.triangles.push_back(cylinder.triangles[t]);
  }
  Mesh separate;                        // three corners of its own per triangle, as in an STL
  const Mesh sphere = SphereMesh(0.1, 2);
  for (const auto& t : sphere.triangles) {
    const int base = static_cast<int>(separate.vertices.size());
    for (int c : t) separate.vertices.push_back(sphere.vertices[c]);
    separate.triangles.push_back({base, base + 1, base + 2});
  }
  const std::vector<std::pair<std::string, Mesh>> meshes = {
      {"capsule", Transformed(CapsuleMesh(0.04, 0.1, 24), {0.01, 0, 0}, {0.9, 0.1, 0.3, 0.2})},
      {"open cylinder", open_cylinder},
      {"separate corners", separate},
      {"overlapping boxes", Merged({BoxMesh(0.2, 0.05, 0.05), Transformed(BoxMesh(0.05, 0.2, 0.05), {0.05, 0.05, 0}, {1, 0, 0, 0})})}};
  Rng rng(21);
  for (const auto& [name, mesh] : meshes) {
    SCOPED_TRACE(name);
    const MeshIndex index(mesh);
    for (int i = 0; i < 400; ++i) {
      const Point p = RandomPoint(rng, i % 2 == 0 ? 0.08 : 0.3);
      const double distance = DistanceToSurface(mesh, p);
      ASSERT_NEAR(index.Distance(p), distance, 1e-14);
      ASSERT_NEAR(Norm(Add(index.ClosestPoint(p), {-p[0], -p[1], -p[2]})), distance, 1e-14);
      ASSERT_NEAR(index.WindingNumber(p), WindingNumber(mesh, p), 1e-9);
      ASSERT_EQ(index.Inside(p), Inside(mesh, p));
    }
  }
}

TEST(QueryTest, SurfaceSamplesAreOnTheSurfaceAreaWeightedAndSeeded) {
  const Mesh box = BoxMesh(0.2, 0.1, 0.05);
  const double spacing = 0.005;
  const auto samples = SurfaceSamples(box, spacing, 3);
  EXPECT_EQ(samples.size(), 8 + static_cast<size_t>(std::llround(MeshArea(box) / (spacing * spacing))));
  for (int v = 0; v < 8; ++v) EXPECT_EQ(samples[v], box.vertices[v]);  // every vertex first
  int on_top = 0;
  for (const auto& p : samples) {
    ASSERT_LT(DistanceToSurface(box, p), 1e-15);
    on_top += std::abs(p[2] - 0.025) < 1e-15;
  }
  // The top face holds 0.02 of the 0.07 m² area.
  EXPECT_NEAR(on_top / static_cast<double>(samples.size()), 0.02 / 0.07, 0.03);
  EXPECT_EQ(SurfaceSamples(box, spacing, 3), samples);
  EXPECT_NE(SurfaceSamples(box, spacing, 4), samples);
  EXPECT_THAT([&] { SurfaceSamples(box, 0.0, 3); }, ThrowsMessage<Error>(HasSubstr("spacing")));
}

// ---- covers ----------------------------------------------------------------------

// An L of two overlapping boxes: 0.12 x 0.04 along x and 0.04 x 0.12 along y, 0.04 thick.
Mesh LShape() {
  return Merged({Transformed(BoxMesh(0.12, 0.04, 0.04), {0.04, 0, 0}, {1, 0, 0, 0}),
                 Transformed(BoxMesh(0.04, 0.12, 0.04), {0, 0.04, 0}, {1, 0, 0, 0})});
}

struct CoverRun {
  std::vector<Sphere> spheres;
  CoverReport report;
  double seconds;
};

CoverRun CoverAndCheck(const Mesh& mesh, const CoverSettings& settings) {
  CoverRun run;
  const auto start = std::chrono::steady_clock::now();
  run.spheres = Cover(mesh, settings);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Denser than the cover's spacing, with the cover's own seed (CheckCover draws independently of it).
  run.report = CheckCover(mesh, run.spheres, settings.spacing / 2, settings.seed, 60000);
  return run;
}

TEST(CoverTest, CoversBoxCylinderAndLShapeWithinTheOvershootAndLooserForALargerOne) {
  struct Shape {
    std::string name;
    Mesh mesh;
    double volume;  // m³, of the solid (the L's boxes overlap in a 0.04 m cube)
  };
  const std::vector<Shape> shapes = {
      {"box", BoxMesh(0.1, 0.06, 0.04), 0.1 * 0.06 * 0.04},
      {"cylinder", CylinderMesh(0.03, 0.12), MeshVolume(CylinderMesh(0.03, 0.12))},
      {"L-shape", LShape(), 2 * 0.12 * 0.04 * 0.04 - 0.04 * 0.04 * 0.04}};
  for (const auto& [name, mesh, volume] : shapes) {
    SCOPED_TRACE(name);
    CoverRun runs[2];
    const double overshoots[2] = {0.005, 0.015};
    for (int k = 0; k < 2; ++k) {
      CoverSettings settings;
      settings.overshoot = overshoots[k];
      settings.max_spheres = 400;
      runs[k] = CoverAndCheck(mesh, settings);
      const CoverReport& r = runs[k].report;
      std::printf("[ figures  ] %-8s overshoot %.3f: %3d spheres, %lld/%lld uncovered (largest %.2g m), "
                  "union %.3g m^3, outside %.3g m^3 = %.3f of %.3g m^3, reach <= %.5f m, %.3f s\n",
                  name.c_str(), overshoots[k], r.spheres, static_cast<long long>(r.uncovered),
                  static_cast<long long>(r.samples), r.largest_uncovered, r.union_volume, r.outside_volume,
                  r.overshoot_ratio, r.mesh_volume, r.largest_outside, runs[k].seconds);
      EXPECT_EQ(r.spheres, static_cast<int>(runs[k].spheres.size()));
      EXPECT_LE(r.spheres, settings.max_spheres);
      EXPECT_GT(r.samples, 5000);
      EXPECT_EQ(r.uncovered, 0);
      EXPECT_LE(r.largest_uncovered, 1e-9);
      EXPECT_LE(r.largest_outside, overshoots[k] + 1e-9);
      EXPECT_GT(r.union_volume, r.mesh_volume);
      EXPECT_NEAR(r.mesh_volume, volume, 0.03 * volume);  // Monte Carlo
    }
    EXPECT_GE(runs[0].report.spheres, runs[1].report.spheres);
    EXPECT_LT(runs[0].report.overshoot_ratio, runs[1].report.overshoot_ratio);
  }
}

TEST(CoverTest, TheSameSeedGivesTheSameSpheresBitForBit) {
  const Mesh mesh = Transformed(CapsuleMesh(0.03, 0.08, 24), {0.1, 0.2, 0.3}, {0.8, 0.2, -0.1, 0.3});
  CoverSettings settings;
  settings.seed = 7;
  const auto a = Cover(mesh, settings);
  const auto b = Cover(mesh, settings);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(std::memcmp(a[i].centre.data(), b[i].centre.data(), sizeof(a[i].centre)), 0);
    EXPECT_EQ(std::memcmp(&a[i].radius, &b[i].radius, sizeof(double)), 0);
  }
  // Another seed gives other spheres, which cover as well.
  settings.seed = 8;
  const auto c = Cover(mesh, settings);
  bool differ = c.size() != a.size();
  for (size_t i = 0; i < std::min(a.size(), c.size()); ++i) differ = differ || a[i].centre != c[i].centre;
  EXPECT_TRUE(differ);
  EXPECT_EQ(CheckCover(mesh, c, 0.002, 1, 0).uncovered, 0);
}

TEST(CoverTest, TooFewSpheresAllowedRaiseTheOvershootButStillCover) {
  const Mesh box = BoxMesh(0.1, 0.06, 0.04);
  CoverSettings settings;
  settings.overshoot = 0.002;
  settings.max_spheres = 6;
  const CoverRun run = CoverAndCheck(box, settings);
  std::printf("[ figures  ] box      overshoot 0.002, at most 6 spheres: %d spheres, reach <= %.4f m, "
              "outside %.3f of the volume, %.3f s\n",
              run.report.spheres, run.report.largest_outside, run.report.overshoot_ratio, run.seconds);
  EXPECT_LE(run.report.spheres, 6);
  EXPECT_EQ(run.report.uncovered, 0);
  EXPECT_LE(run.report.largest_uncovered, 1e-9);
  EXPECT_GT(run.report.largest_outside, settings.overshoot);  // the price of the cap
  // Uncapped, the same box needs many more spheres at this overshoot.
  settings.max_spheres = 1000;
  settings.spacing = 0.008;
  EXPECT_GT(Cover(box, settings).size(), 100u);
}

TEST(CoverTest, OpenAndThinMeshesStillGetACover) {
  Mesh sheet;  // one open square, no inside at all
  sheet.vertices = {{0, 0, 0}, {0.1, 0, 0}, {0.1, 0.08, 0}, {0, 0.08, 0}};
  sheet.triangles = {{0, 1, 2}, {0, 2, 3}};
  CoverSettings settings;
  settings.overshoot = 0.01;
  settings.max_spheres = 200;
  const CoverRun flat = CoverAndCheck(sheet, settings);
  EXPECT_EQ(flat.report.uncovered, 0);
  EXPECT_LE(flat.report.largest_uncovered, 1e-9);
  for (const Sphere& s : flat.spheres) {
    EXPECT_NEAR(s.centre[2], 0.0, 1e-15);  // on the sheet
    EXPECT_LE(s.radius, settings.overshoot * (1 + 1e-9));
  }
  const CoverRun thin = CoverAndCheck(BoxMesh(0.1, 0.08, 0.001), settings);
  EXPECT_EQ(thin.report.uncovered, 0);
  EXPECT_LE(thin.report.largest_outside, settings.overshoot + 1e-9);
}

TEST(CoverTest, BadSettingsNameTheSetting) {
  const Mesh box = BoxMesh(0.1, 0.1, 0.1);
  CoverSettings settings;
  settings.overshoot = 0.0;
  EXPECT_THAT([&] { Cover(box, settings); },
              ThrowsMessage<Error>(HasSubstr("CoverSettings.overshoot: expected a positive finite length (m), got 0")));
  settings = CoverSettings();
  settings.spacing = NAN;
  EXPECT_THAT([&] { Cover(box, settings); }, ThrowsMessage<Error>(HasSubstr("CoverSettings.spacing")));
  settings = CoverSettings();
  settings.max_spheres = 0;
  EXPECT_THAT([&] { Cover(box, settings); },
              ThrowsMessage<Error>(HasSubstr("CoverSettings.max_spheres: expected at least 1, got 0")));
  EXPECT_THAT([&] { Cover(Mesh{}, CoverSettings()); }, ThrowsMessage<Error>(HasSubstr("mesh: no triangles")));
}

TEST(CheckCoverTest, ReportsTheGapOfAnIncompleteCoverExactlyAtTheCorners) {
  // One ball inside a cube: the corners (samples, as vertices) are the farthest uncovered points.
  const double half = 0.05, r = 0.04;
  const Mesh cube = BoxMesh(2 * half, 2 * half, 2 * half);
  const CoverReport report = CheckCover(cube, {{{0, 0, 0}, r}}, 0.004, 0, 400000);
  EXPECT_EQ(report.spheres, 1);
  EXPECT_GT(report.uncovered, report.samples / 2);
  EXPECT_NEAR(report.largest_uncovered, std::sqrt(3.0) * half - r, 1e-15);
  const double ball = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(report.union_volume, ball, 0.01 * ball);
  EXPECT_EQ(report.outside_volume, 0.0);
  EXPECT_EQ(report.largest_outside, 0.0);
  EXPECT_THAT([&] { CheckCover(cube, {{{0, 0, NAN}, r}}, 0.004, 0); },
              ThrowsMessage<Error>(HasSubstr("CheckCover: sphere 0: expected a finite centre")));
}

TEST(CheckCoverTest, MeasuresTheVolumesAndTheReachOfAnOversizedBall) {
  // A ball of radius 0.1 around a cube of half side 0.05 (half diagonal 0.087): it holds the
  // cube, so the part outside is the ball minus the cube, and it reaches 0.05 past each face.
  const double half = 0.05, r = 0.1;
  const Mesh cube = BoxMesh(2 * half, 2 * half, 2 * half);
  const CoverReport report = CheckCover(cube, {{{0, 0, 0}, r}}, 0.004, 0, 400000);
  const double ball = 4.0 / 3.0 * M_PI * r * r * r, box = std::pow(2 * half, 3);
  EXPECT_EQ(report.uncovered, 0);
  EXPECT_EQ(report.largest_uncovered, 0.0);
  EXPECT_NEAR(report.mesh_volume, box, 0.02 * box);
  EXPECT_NEAR(report.union_volume, ball, 0.01 * ball);
  EXPECT_NEAR(report.outside_volume, ball - box, 0.015 * (ball - box));
  EXPECT_NEAR(report.overshoot_ratio, (ball - box) / box, 0.015 * (ball - box) / box);
  EXPECT_NEAR(report.largest_outside, r - half, 1e-12);
}

}  // namespace
}  // namespace flowplan::spheres
