// Obstacle shapes: the TorchScript signed distances (geometry/*.py) against a
// plain-double reference written here from the definitions (closest points,
// nothing shared with the scripts), their written-out gradients against
// central differences and autograd in float64 at random poses, with points
// inside, near faces, edges and corners; and scenes with bad entries.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <fstream>
#include <random>

#include "core/error.h"
#include "geometry/scene_rows.h"
#include "jit/library.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::geometry {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;
using Vec = std::vector<double>;

/// Signed distance and gradient from the scripts: points (N, W), rows (K, C) -> (N, K), (N, K, W).
std::pair<torch::Tensor, torch::Tensor> ScriptDistance(const std::string& kind, const torch::Tensor& points,
                                                       const torch::Tensor& rows) {
  const auto out = jit::CallFunction("shape_distance", {kind, points, rows}).toTuple();
  return {out->elements()[0].toTensor(), out->elements()[1].toTensor()};
}

// ---- the reference: one point, one shape, plain doubles ----

/// Rotation matrix (row-major) of a quaternion (w, x, y, z) of any norm, or of a 2-D angle.
std::vector<double> Rotation(const Vec& turn, int W) {
  if (W == 2) return {std::cos(turn[0]), -std::sin(turn[0]), std::sin(turn[0]), std::cos(turn[0])};
  const double n = std::sqrt(turn[0] * turn[0] + turn[1] * turn[1] + turn[2] * turn[2] + turn[3] * turn[3]);
  const double w = turn[0] / n, x = turn[1] / n, y = turn[2] / n, z = turn[3] / n;
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
          2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)};
}

Vec Local(const Vec& p, const Vec& centre, const Vec& R, int W) {
  Vec out(W, 0.0);
  for (int i = 0; i < W; ++i) {
    for (int j = 0; j < W; ++j) out[i] += R[j * W + i] * (p[j] - centre[j]);
  }
  return out;
}

double Norm(const Vec& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

/// Distance of a point to an axis-aligned box of half extents h centred at 0, signed:
/// outside, to the clamped point; inside, minus the distance to the nearest face.
double BoxReference(const Vec& p, const Vec& h) {
  Vec outside(p.size());
  bool inside = true;
  double nearest_face = INFINITY;
  for (size_t i = 0; i < p.size(); ++i) {
    const double clamped = std::min(std::max(p[i], -h[i]), h[i]);
    outside[i] = p[i] - clamped;
    if (std::abs(p[i]) > h[i]) inside = false;
    nearest_face = std::min(nearest_face, h[i] - std::abs(p[i]));
  }
  return inside ? -nearest_face : Norm(outside);
}

double Reference(const std::string& kind, const Vec& p, const Vec& row, int W) {
  const size_t w = static_cast<size_t>(W);
  const Vec centre(row.begin(), row.begin() + W);
  if (kind == "spheres") {
    Vec d(w);
    for (size_t i = 0; i < w; ++i) d[i] = p[i] - centre[i];
    return Norm(d) - row[w];
  }
  if (kind == "boxes") {
    const Vec turn(row.begin() + 2 * W, row.end());
    Vec half(w);
    for (size_t i = 0; i < w; ++i) half[i] = 0.5 * row[w + i];
    return BoxReference(Local(p, centre, Rotation(turn, W), W), half);
  }
  if (kind == "cylinders") {
    const Vec turn(row.begin() + W + 2, row.end());
    const Vec local = Local(p, centre, Rotation(turn, W), W);
    double radial = 0.0;
    for (size_t i = 0; i + 1 < w; ++i) radial += local[i] * local[i];
    // In the half-plane (distance from the axis, position along it) the cylinder is a rectangle.
    return BoxReference({std::sqrt(radial), local[w - 1]}, {row[w], 0.5 * row[w + 1]});
  }
  // capsules: distance to the nearest point of segment ab, minus the radius.
  const Vec a(row.begin(), row.begin() + W), b(row.begin() + W, row.begin() + 2 * W);
  double ab2 = 0.0, t = 0.0;
  for (size_t i = 0; i < w; ++i) {
    ab2 += (b[i] - a[i]) * (b[i] - a[i]);
    t += (p[i] - a[i]) * (b[i] - a[i]);
  }
  t = ab2 > 0 ? std::min(std::max(t / ab2, 0.0), 1.0) : 0.0;
  Vec d(w);
  for (size_t i = 0; i < w; ++i) d[i] = p[i] - (a[i] + t * (b[i] - a[i]));
  return Norm(d) - row[2 * w];
}

// ---- random shapes and test points ----

Vec RandomRow(const std::string& kind, int W, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> position(-0.5, 0.5), extent(0.1, 0.6), unit(-1.0, 1.0);
  Vec row;
  auto push_point = [&] {
    for (int i = 0; i < W; ++i) row.push_back(position(rng));
  };
  auto push_turn = [&] {
    if (W == 2) {
      row.push_back(3.0 * unit(rng));
    } else {
      const double scale = 0.3 + 2.0 * extent(rng);  // deliberately not unit
      for (int i = 0; i < 4; ++i) row.push_back(scale * unit(rng));
    }
  };
  if (kind == "spheres") {
    push_point();
    row.push_back(extent(rng));
  } else if (kind == "boxes") {
    push_point();
    for (int i = 0; i < W; ++i) row.push_back(extent(rng));
    push_turn();
  } else if (kind == "cylinders") {
    push_point();
    row.push_back(0.5 * extent(rng));
    row.push_back(extent(rng));
    push_turn();
  } else {
    push_point();
    push_point();
    row.push_back(0.5 * extent(rng));
  }
  return row;
}

/// Points around a shape: uniform in a box around it, and near the features
/// of its surface (a point on it, moved ±1..20 mm along a random direction):
/// faces, edges and corners of boxes, rims and caps of cylinders.
std::vector<Vec> TestPoints(const std::string& kind, const Vec& row, int W, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> around(-1.2, 1.2), unit(-1.0, 1.0), small(0.001, 0.02);
  std::vector<Vec> points;
  for (int n = 0; n < 40; ++n) {
    Vec p(W);
    for (int i = 0; i < W; ++i) p[i] = around(rng);
    points.push_back(p);
  }
  auto nudge = [&](Vec p) {
    Vec d(W);
    for (int i = 0; i < W; ++i) d[i] = unit(rng);
    const double length = Norm(d), step = small(rng);
    for (int i = 0; i < W; ++i) p[i] += step * d[i] / length;
    return p;
  };
  auto world = [&](const Vec& local, const Vec& centre, const Vec& R) {
    Vec p(W, 0.0);
    for (int i = 0; i < W; ++i) {
      p[i] = centre[i];
      for (int j = 0; j < W; ++j) p[i] += R[i * W + j] * local[j];
    }
    return p;
  };
  const Vec centre(row.begin(), row.begin() + W);
  for (int n = 0; n < 60; ++n) {
    Vec local(W);
    if (kind == "boxes") {
      // A feature: every coordinate either on a face (±h) or free inside; 1..W coordinates pinned.
      const Vec R = Rotation(Vec(row.begin() + 2 * W, row.end()), W);
      for (int i = 0; i < W; ++i) {
        const double h = 0.5 * row[W + i];
        local[i] = (i <= n % W) ? (unit(rng) < 0 ? -h : h) : h * unit(rng);
      }
      points.push_back(nudge(world(local, centre, R)));
    } else if (kind == "cylinders") {
      const Vec R = Rotation(Vec(row.begin() + W + 2, row.end()), W);
      const double r = row[W], h = 0.5 * row[W + 1];
      Vec across(W - 1);
      for (int i = 0; i < W - 1; ++i) across[i] = unit(rng);
      const double length = Norm(across);
      const int feature = n % 3;  // 0: mantle, 1: cap, 2: rim
      const double radius = feature == 1 ? r * std::abs(unit(rng)) : r;
      for (int i = 0; i < W - 1; ++i) local[i] = radius * across[i] / length;
      local[W - 1] = feature == 0 ? h * unit(rng) : (unit(rng) < 0 ? -h : h);
      points.push_back(nudge(world(local, centre, R)));
    } else if (kind == "capsules") {
      const double t = std::abs(unit(rng)) * 1.2 - 0.1;
      Vec p(W);
      for (int i = 0; i < W; ++i) p[i] = row[i] + t * (row[W + i] - row[i]);
      Vec d(W);
      for (int i = 0; i < W; ++i) d[i] = unit(rng);
      const double length = Norm(d);
      for (int i = 0; i < W; ++i) p[i] += row[2 * W] * d[i] / length;
      points.push_back(nudge(p));
    } else {
      Vec d(W);
      for (int i = 0; i < W; ++i) d[i] = unit(rng);
      const double length = Norm(d);
      Vec p(W);
      for (int i = 0; i < W; ++i) p[i] = centre[i] + row[W] * d[i] / length;
      points.push_back(nudge(p));
    }
  }
  return points;
}

torch::Tensor Tensor(const std::vector<Vec>& rows) {
  torch::Tensor out = torch::empty({static_cast<int64_t>(rows.size()), static_cast<int64_t>(rows[0].size())},
                                   torch::kFloat64);
  for (size_t i = 0; i < rows.size(); ++i) {
    for (size_t j = 0; j < rows[i].size(); ++j) out[i][j] = rows[i][j];
  }
  return out;
}

struct ShapeCase {
  std::string kind;
  int W;
};

// Names the case in test listings ("boxes in 3-D") instead of its bytes.
void PrintTo(const ShapeCase& c, std::ostream* os) { *os << c.kind << " in " << c.W << "-D"; }

class ShapeTest : public ::testing::TestWithParam<ShapeCase> {};

TEST_P(ShapeTest, DistanceMatchesTheReferenceAndItsGradientFiniteDifferencesAndAutograd) {
  const auto [kind, W] = GetParam();
  std::mt19937_64 rng(17 + W);
  int inside = 0, total = 0;
  for (int shape = 0; shape < 6; ++shape) {
    const Vec row = RandomRow(kind, W, rng);
    const torch::Tensor rows = Tensor({row});
    const std::vector<Vec> points = TestPoints(kind, row, W, rng);
    const torch::Tensor p = Tensor(points);
    const auto [distance, gradient] = ScriptDistance(kind, p, rows);
    ASSERT_EQ(distance.sizes(), torch::IntArrayRef({p.size(0), 1}));
    ASSERT_EQ(gradient.sizes(), torch::IntArrayRef({p.size(0), 1, W}));
    // Against the reference, point by point.
    for (size_t n = 0; n < points.size(); ++n) {
      const double want = Reference(kind, points[n], row, W);
      EXPECT_NEAR(distance[n][0].item<double>(), want, 1e-12) << kind << " point " << n;
      inside += want < 0;
      ++total;
    }
    // The distance alone (shape_distance_only; a sphere's is another computation) against the reference too.
    const torch::Tensor alone = jit::CallFunction("shape_distance_only", {kind, p, rows}).toTensor();
    ASSERT_EQ(alone.sizes(), distance.sizes());
    // The other shapes compute it as shape_distance does, without the gradient: the same numbers.
    if (kind != "spheres") EXPECT_TRUE(torch::equal(alone, distance)) << kind;
    for (size_t n = 0; n < points.size(); ++n) {
      EXPECT_NEAR(alone[n][0].item<double>(), Reference(kind, points[n], row, W), 1e-12) << kind << " point " << n;
    }
    // A prepared row (shape_prepared: a rotated shape's rotation matrix appended, as a planning call's scene
    // carries it) gives the same distances and gradients, bit for bit.
    const torch::Tensor prepared =
        jit::CallFunction("shape_prepared", {kind, rows, static_cast<int64_t>(W)}).toTensor();
    const bool rotated = kind == "boxes" || kind == "cylinders";
    EXPECT_EQ(prepared.size(1), rows.size(1) + (rotated ? W * W : 0)) << kind;
    EXPECT_EQ(jit::CallFunction("shape_prepared", {kind, prepared, static_cast<int64_t>(W)}).toTensor().sizes(),
              prepared.sizes())
        << kind << ": prepared rows are their own";
    // The stored matrix is what the distances use: with the orientation columns made NaN they do not change.
    if (rotated) {
      const int64_t orientation = kind == "boxes" ? 2 * W : W + 2;
      prepared.slice(1, orientation, orientation + (W == 3 ? 4 : 1)).fill_(std::nan(""));
    }
    const auto [prepared_distance, prepared_gradient] = ScriptDistance(kind, p, prepared);
    EXPECT_TRUE(torch::equal(prepared_distance, distance)) << kind;
    EXPECT_TRUE(torch::equal(prepared_gradient, gradient)) << kind;
    EXPECT_TRUE(torch::equal(jit::CallFunction("shape_distance_only", {kind, p, prepared}).toTensor(), alone)) << kind;
    // Central differences of the reference (h = 1e-6) and of the script itself.
    const double h = 1e-6;
    for (size_t n = 0; n < points.size(); ++n) {
      for (int i = 0; i < W; ++i) {
        Vec plus = points[n], minus = points[n];
        plus[i] += h;
        minus[i] -= h;
        const double numeric = (Reference(kind, plus, row, W) - Reference(kind, minus, row, W)) / (2 * h);
        EXPECT_NEAR(gradient[n][0][i].item<double>(), numeric, 1e-6) << kind << " point " << n << " axis " << i;
      }
    }
    // Autograd through the distance the script computes.
    const torch::Tensor leaf = p.clone().requires_grad_(true);
    const torch::Tensor value = ScriptDistance(kind, leaf, rows).first.sum();
    const torch::Tensor automatic = torch::autograd::grad({value}, {leaf})[0];
    EXPECT_TRUE(torch::allclose(automatic, gradient.squeeze(1), 1e-9, 1e-12)) << kind;
  }
  EXPECT_GT(inside, total / 10) << "the points should include many inside the shape";
  EXPECT_LT(inside, total - total / 10);
}

INSTANTIATE_TEST_SUITE_P(EveryShapeIn2dAnd3d, ShapeTest,
                         ::testing::Values(ShapeCase{"spheres", 3}, ShapeCase{"boxes", 3}, ShapeCase{"cylinders", 3},
                                           ShapeCase{"capsules", 3}, ShapeCase{"spheres", 2}, ShapeCase{"boxes", 2},
                                           ShapeCase{"cylinders", 2}, ShapeCase{"capsules", 2}),
                         [](const auto& info) { return info.param.kind + std::to_string(info.param.W) + "d"; });

TEST(Shapes, ClosedFormValues) {
  const torch::Tensor p = torch::tensor({{2.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}}, torch::kFloat64);
  // A unit cube at the origin turned 90° about z, and one turned 45°.
  const double s = std::sqrt(0.5);
  const torch::Tensor cube = torch::tensor({{0.0, 0.0, 0.0, 1.0, 1.0, 1.0, s, 0.0, 0.0, s}}, torch::kFloat64);
  const auto [d, g] = ScriptDistance("boxes", p, cube);
  EXPECT_NEAR(d[0][0].item<double>(), 1.5, 1e-12);
  EXPECT_NEAR(d[1][0].item<double>(), -0.5, 1e-12);
  EXPECT_NEAR(d[2][0].item<double>(), std::sqrt(3 * 0.25), 1e-12);
  EXPECT_NEAR(g[0][0][0].item<double>(), 1.0, 1e-12);
  const torch::Tensor diamond = torch::tensor({{0.0, 0.0, 0.0, 1.0, 1.0, 1.0, std::cos(M_PI / 8), 0.0, 0.0,
                                                std::sin(M_PI / 8)}}, torch::kFloat64);
  EXPECT_NEAR(ScriptDistance("boxes", p, diamond).first[0][0].item<double>(), 2.0 - std::sqrt(0.5), 1e-12);
  // A cylinder of radius 0.5 and height 2 lying along x (90° about y).
  const torch::Tensor rod = torch::tensor({{0.0, 0.0, 0.0, 0.5, 2.0, s, 0.0, s, 0.0}}, torch::kFloat64);
  EXPECT_NEAR(ScriptDistance("cylinders", p, rod).first[0][0].item<double>(), 1.0, 1e-12);
  EXPECT_NEAR(ScriptDistance("cylinders", p, rod).first[1][0].item<double>(), -0.5, 1e-12);
  // A capsule from (0, 0, 0) to (0, 0, 1), radius 0.25: (1, 1, 1) is sqrt(2) from its top end's axis point.
  const torch::Tensor capsule = torch::tensor({{0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.25}}, torch::kFloat64);
  EXPECT_NEAR(ScriptDistance("capsules", p, capsule).first[2][0].item<double>(), std::sqrt(2.0) - 0.25, 1e-12);
  // A scene numbers its obstacles kind by kind.
  SceneRows scene;
  scene.insert("spheres", torch::tensor({{2.0, 0.0, 0.0, 0.5}}, torch::kFloat64));
  scene.insert("boxes", cube);
  const auto all = jit::CallFunction("scene_distance", {p, scene}).toTuple();
  EXPECT_EQ(all->elements()[0].toTensor().sizes(), torch::IntArrayRef({3, 2}));
  EXPECT_NEAR(all->elements()[0].toTensor()[0][0].item<double>(), -0.5, 1e-12);
  EXPECT_TRUE(torch::equal(jit::CallFunction("scene_distance_only", {p, scene}).toTensor().slice(1, 1, 2),
                           all->elements()[0].toTensor().slice(1, 1, 2)))
      << "a box's distance alone is the same computation";
  EXPECT_NEAR(jit::CallFunction("scene_distance_only", {p, scene}).toTensor()[0][0].item<double>(), -0.5, 1e-12);
  EXPECT_EQ(jit::CallFunction("scene_distance_only", {p, SceneRows()}).toTensor().sizes(), torch::IntArrayRef({3, 0}));
  // Several spheres at once, in float32 too: distance alone against distance with gradient.
  const torch::Tensor balls = torch::tensor({{2.0, 0.0, 0.0, 0.5}, {0.0, 0.1, 0.0, 0.2}, {1.0, 1.0, 0.5, 0.3}},
                                            torch::kFloat64);
  const torch::Tensor many = torch::rand({50, 3}, torch::kFloat64) * 3 - 1;
  for (const auto dtype : {torch::kFloat64, torch::kFloat32}) {
    const torch::Tensor alone =
        jit::CallFunction("shape_distance_only", {std::string("spheres"), many.to(dtype), balls.to(dtype)}).toTensor();
    const torch::Tensor with = ScriptDistance("spheres", many.to(dtype), balls.to(dtype)).first;
    ASSERT_EQ(alone.sizes(), torch::IntArrayRef({50, 3}));
    EXPECT_LT((alone - with).abs().max().item<double>(), dtype == torch::kFloat64 ? 1e-14 : 1e-6);
  }
}

TEST(Scene, FileRowsAndNames) {
  const auto path = testing::ScratchDir() / "scene.yaml";
  std::ofstream(path) << "spheres: [{centre: [0.5, 0, 0.2], radius: 0.1}]\n"
                         "boxes: [{centre: [0.4, 0, 0.1], size: [0.1, 0.2, 0.3], quaternion: [2, 0, 0, 0]}]\n"
                         "cylinders: [{centre: [0, 0.5, 0.3], radius: 0.05, height: 0.4}]\n"
                         "capsules: [{a: [0, 0, 0], b: [0, 0, 1], radius: 0.02}]\n";
  const Scene scene = LoadScene(path.string());
  EXPECT_EQ(scene.size(), 4);
  EXPECT_EQ(scene.Names(), (std::vector<std::string>{"spheres[0]", "boxes[0]", "cylinders[0]", "capsules[0]"}));
  const SceneRows rows = Rows(scene, 3, path.string());
  EXPECT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows.at("boxes")[0][6].item<double>(), 1.0) << "the quaternion is normalised";
  EXPECT_EQ(rows.at("cylinders").sizes(), torch::IntArrayRef({1, 9}));
  EXPECT_EQ(rows.at("cylinders")[0][5].item<double>(), 1.0) << "identity by default";
  EXPECT_NO_THROW(CheckRows(rows, 3, "plan"));
}

TEST(Scene, BadEntriesAreOneClearError) {
  const auto dir = testing::ScratchDir();
  auto load = [&](const std::string& text, int W) {
    const std::string path = (dir / "bad.yaml").string();
    std::ofstream(path) << text;
    return Rows(LoadScene(path), W, path);
  };
  EXPECT_THAT([&] { load("boxes: [{centre: [0, 0, 0], size: [1, 1, 1], quaternion: [0, 0, 0, 0]}]\n", 3); },
              ThrowsMessage<Error>(HasSubstr("bad.yaml: boxes[0].quaternion: expected a non-zero quaternion")));
  EXPECT_THAT([&] { load("boxes: [{centre: [0, 0, 0], size: [1, -1, 1]}]\n", 3); },
              ThrowsMessage<Error>(HasSubstr("boxes[0].size[1]: expected a non-negative value, got \"-1\"")));
  EXPECT_THAT([&] { load("cylinders: [{centre: [0, 0, 0], radius: .nan, height: 1}]\n", 3); },
              ThrowsMessage<Error>(HasSubstr("cylinders[0].radius: expected a number")));
  EXPECT_THAT([&] { load("capsules: [{a: [0, 0], b: [0, 0, 1], radius: 0.1}]\n", 3); },
              ThrowsMessage<Error>(HasSubstr("bad.yaml: capsules[0].a: expected 3 values (the robot's workspace is 3-D), got 2")));
  EXPECT_THAT([&] { load("spheres: [{centre: [0, 0, 0]}]\n", 3); },
              ThrowsMessage<Error>(HasSubstr("spheres[0].radius: missing")));
  EXPECT_THAT([&] { load("boxes: [{centre: [0, 0, 0], size: [1, 1, 1], angle: 0.3}]\n", 3); },
              ThrowsMessage<Error>(HasSubstr("boxes[0].angle: a 3-D obstacle is turned by `quaternion`")));
  EXPECT_THAT([&] { load("boxes: [{centre: [0, 0], size: [1, 1], quaternion: [1, 0, 0, 0]}]\n", 2); },
              ThrowsMessage<Error>(HasSubstr("boxes[0].quaternion: a 2-D obstacle is turned by `angle`")));
  EXPECT_THAT([&] { load("prisms: []\n", 3); }, ThrowsMessage<Error>(HasSubstr("prisms")));
  // Rows from a caller, checked as the exported planner checks them.
  SceneRows rows;
  rows.insert("boxes", torch::tensor({{0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0},
                                      {0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0}}, torch::kFloat64));
  EXPECT_THAT([&] { CheckRows(rows, 3, "plan"); },
              ThrowsMessage<Error>(HasSubstr("plan: boxes: row 1: expected a non-zero quaternion")));
  rows.insert_or_assign("boxes", torch::zeros({1, 9}));
  EXPECT_THAT([&] { CheckRows(rows, 3, "plan"); }, ThrowsMessage<Error>(HasSubstr("plan: boxes: expected (K, 10)")));
  rows.insert_or_assign("boxes", torch::full({1, 10}, NAN));
  EXPECT_THAT([&] { CheckRows(rows, 3, "plan"); }, ThrowsMessage<Error>(HasSubstr("row 0: expected finite values")));
  SceneRows capsules;
  capsules.insert("capsules", torch::tensor({{0.0, 0.0, 1.0, 1.0, -0.5}}));
  EXPECT_THAT([&] { CheckRows(capsules, 2, "plan"); },
              ThrowsMessage<Error>(HasSubstr("plan: capsules: row 0: expected a non-negative radius, got -0.5")));
}

TEST(Scene, CommandLineRows) {
  Scene scene;
  AddObstacle(scene, "boxes", {0.5, 0.0, 0.2, 0.1, 0.1, 0.1}, 3, "--box");
  AddObstacle(scene, "cylinders", {0.5, 0.0, 0.2, 0.05, 0.3, 0.0, 1.0, 0.0, 0.0}, 3, "--cylinder");
  AddObstacle(scene, "capsules", {0.0, 0.0, 1.0, 1.0, 0.1}, 2, "--capsule");
  EXPECT_EQ(scene.size(), 3);
  EXPECT_THAT([&] { AddObstacle(scene, "boxes", {0.5, 0.0, 0.2, 0.1}, 3, "--box \"0.5,0,0.2,0.1\""); },
              ThrowsMessage<Error>(HasSubstr("--box \"0.5,0,0.2,0.1\": expected cx,cy,cz,lx,ly,lz[,qw,qx,qy,qz]")));
  EXPECT_THAT([&] { AddObstacle(scene, "cylinders", {0.5, 0.0, 0.2, -0.1, 0.3}, 3, "--cylinder"); },
              ThrowsMessage<Error>(HasSubstr("--cylinder: expected a non-negative radius")));
}

}  // namespace
}  // namespace flowplan::geometry
