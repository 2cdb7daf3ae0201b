// The native shape distances against the TorchScript distances they replace
// in guidance (geometry/*.py, themselves tested against a plain reference in
// tests/geometry/shapes_test.cc): every kind, 2-D and 3-D, float32 and
// float64, at random poses with points inside, near and far, on a sphere's
// centre and a capsule's segment; the same numbers for any
// thread count; the collision cost's two distance modules agree; and bad
// rows are one clear error.

#include "kernels/shape_distance_kernel.h"

#include <ATen/Parallel.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "jit/library.h"

namespace flowplan::kernels {
namespace {

using ::testing::HasSubstr;

/// Random rows of `kind` in the scripts' layout (not prepared), W-dimensional, about the unit cube.
torch::Tensor RandomRows(const std::string& kind, int64_t W, int64_t K) {
  const torch::Tensor centre = torch::rand({K, W}, torch::kFloat64) * 2 - 1;
  const torch::Tensor turn = W == 3 ? torch::randn({K, 4}, torch::kFloat64) : torch::rand({K, 1}, torch::kFloat64) * 6;
  if (kind == "spheres") return torch::cat({centre, torch::rand({K, 1}, torch::kFloat64) * 0.5 + 0.1}, 1);
  if (kind == "boxes") return torch::cat({centre, torch::rand({K, W}, torch::kFloat64) + 0.1, turn}, 1);
  if (kind == "cylinders") {
    return torch::cat({centre, torch::rand({K, 1}, torch::kFloat64) * 0.4 + 0.1,
                       torch::rand({K, 1}, torch::kFloat64) + 0.1, turn}, 1);
  }
  // Capsules, one of them a point (a = b).
  torch::Tensor b = centre + torch::rand({K, W}, torch::kFloat64) - 0.5;
  b[0] = centre[0];
  return torch::cat({centre, b, torch::rand({K, 1}, torch::kFloat64) * 0.3 + 0.05}, 1);
}

/// Points (M, W) about the rows; for spheres and capsules also their centres and first ends, where the
/// scripts take their fallbacks (a rotated shape's frame puts its centre at a rounding error from 0, so there
/// the scripts' side of the tie is not defined to the last bit).
torch::Tensor Points(const std::string& kind, const torch::Tensor& rows, int64_t W, int64_t M) {
  const torch::Tensor random = torch::rand({M, W}, torch::kFloat64) * 3 - 1.5;
  if (kind == "spheres" || kind == "capsules") return torch::cat({random, rows.slice(1, 0, W)}, 0);
  return random;
}

torch::Tensor Prepared(const std::string& kind, const torch::Tensor& rows, int64_t W) {
  return jit::CallFunction("shape_prepared", {kind, rows, W}).toTensor();
}

struct Case {
  std::string kind;
  int64_t W;
};

class NativeMatchesScript : public ::testing::TestWithParam<Case> {};

TEST_P(NativeMatchesScript, DistancesAndGradientsAgreeInBothPrecisions) {
  const auto [kind, W] = GetParam();
  torch::manual_seed(3);
  const torch::Tensor rows = RandomRows(kind, W, 5);
  const torch::Tensor prepared = Prepared(kind, rows, W);
  const torch::Tensor points = Points(kind, rows, W, 400);
  const auto script = jit::CallFunction("shape_distance", {kind, points, prepared}).toTuple();
  const torch::Tensor d_ref = script->elements()[0].toTensor(), g_ref = script->elements()[1].toTensor();
  ASSERT_EQ(d_ref.sizes(), torch::IntArrayRef({points.size(0), 5}));

  const auto [d64, g64] = ShapeDistance(kind, points, prepared, true);
  EXPECT_LT((d64 - d_ref).abs().max().item<double>(), 1e-12) << kind;
  EXPECT_LT((g64 - g_ref).abs().max().item<double>(), 1e-12) << kind;
  const auto [d_only, none] = ShapeDistance(kind, points, prepared, false);
  EXPECT_TRUE(torch::equal(d_only, d64)) << "the distances do not depend on whether the gradient is asked for";
  EXPECT_EQ(none.numel(), 0);

  const torch::Tensor points32 = points.to(torch::kFloat32);
  const auto script32 = jit::CallFunction("shape_distance", {kind, points32, prepared.to(torch::kFloat32)}).toTuple();
  const auto [d32, g32] = ShapeDistance(kind, points32, prepared, true);  // rows converted to the points' dtype
  EXPECT_EQ(d32.scalar_type(), torch::kFloat32);
  EXPECT_LT((d32 - script32->elements()[0].toTensor()).abs().max().item<double>(), 2e-6) << kind;
  // Gradients: a unit direction each, equal to the float32 script's up to rounding (a point within rounding of a
  // tie between two faces could turn either way; none of these random points is).
  EXPECT_LT((g32 - script32->elements()[1].toTensor()).abs().max().item<double>(), 1e-4) << kind;
  EXPECT_LT((g32.to(torch::kFloat64) - g64).abs().max().item<double>(), 1e-4) << kind;
}

TEST(ShapeDistanceKernelTest, TiesAndAxesGoWhereTheScriptsSendThem) {
  // Unrotated shapes, where both compute a point's local coordinates exactly: a cube's centre and its diagonal
  // (all faces equally near: the first axis, as torch.argmax), a cylinder's axis (local x, then the axial
  // direction where the cap is nearer) and a point as near the mantle as the cap (the mantle).
  const torch::Tensor cube = Prepared("boxes", torch::tensor({{0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0}},
                                                             torch::kFloat64), 3);
  const torch::Tensor cylinder = Prepared(
      "cylinders", torch::tensor({{0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 0.0, 0.0, 0.0}}, torch::kFloat64), 3);
  const torch::Tensor points = torch::tensor({{0.0, 0.0, 0.0}, {0.1, 0.1, 0.1}, {-0.1, -0.1, -0.1}, {0.0, 0.0, 0.2},
                                              {0.0, 0.0, -0.45}, {0.2, 0.0, 0.2}, {0.0, -0.2, -0.2}},
                                             torch::kFloat64);
  for (const auto& [kind, rows] : {std::pair<std::string, torch::Tensor>{"boxes", cube}, {"cylinders", cylinder}}) {
    const auto script = jit::CallFunction("shape_distance", {kind, points, rows}).toTuple();
    const auto [d, g] = ShapeDistance(kind, points, rows, true);
    EXPECT_TRUE(torch::equal(d, script->elements()[0].toTensor())) << kind;
    EXPECT_TRUE(torch::equal(g, script->elements()[1].toTensor())) << kind << "\n" << g << script->elements()[1];
  }
  const auto [d, g] = ShapeDistance("boxes", points, cube, true);
  EXPECT_TRUE(torch::equal(g[0][0], torch::tensor({1.0, 0.0, 0.0}, torch::kFloat64))) << "the centre: first face";
  EXPECT_TRUE(torch::equal(g[2][0], torch::tensor({-1.0, 0.0, 0.0}, torch::kFloat64))) << "its side of the x face";
  const auto [dc, gc] = ShapeDistance("cylinders", points, cylinder, true);
  EXPECT_TRUE(torch::equal(gc[0][0], torch::tensor({1.0, 0.0, 0.0}, torch::kFloat64))) << "on the axis: local x";
  EXPECT_TRUE(torch::equal(gc[4][0], torch::tensor({0.0, 0.0, -1.0}, torch::kFloat64))) << "near the lower cap";
  EXPECT_TRUE(torch::equal(gc[5][0], torch::tensor({1.0, 0.0, 0.0}, torch::kFloat64))) << "mantle as near as cap";
}

INSTANTIATE_TEST_SUITE_P(Kinds, NativeMatchesScript,
                         ::testing::Values(Case{"spheres", 3}, Case{"boxes", 3}, Case{"cylinders", 3},
                                           Case{"capsules", 3}, Case{"spheres", 2}, Case{"boxes", 2},
                                           Case{"cylinders", 2}, Case{"capsules", 2}),
                         [](const auto& info) { return info.param.kind + std::to_string(info.param.W) + "d"; });

TEST(ShapeDistanceKernelTest, SameBitsForAnyThreadCount) {
  torch::manual_seed(5);
  const torch::Tensor rows = Prepared("boxes", RandomRows("boxes", 3, 3), 3);
  const torch::Tensor points = torch::rand({5000, 3}) * 3 - 1.5;
  const int threads = at::get_num_threads();
  at::set_num_threads(1);
  const auto [d1, g1] = ShapeDistance("boxes", points, rows, true);
  at::set_num_threads(2);
  const auto [d2, g2] = ShapeDistance("boxes", points, rows, true);
  at::set_num_threads(threads);
  EXPECT_TRUE(torch::equal(d1, d2));
  EXPECT_TRUE(torch::equal(g1, g2));
}

TEST(ShapeDistanceKernelTest, ScriptOperatorAndBothDistanceModulesAgreeOnAScene) {
  torch::manual_seed(9);
  c10::Dict<std::string, torch::Tensor> scene;
  for (const std::string kind : {"spheres", "boxes", "cylinders", "capsules"}) scene.insert(kind, RandomRows(kind, 3, 2));
  const auto prepared = jit::CallFunction("prepared_scene", {scene, int64_t{3}}).toGenericDict();
  const torch::Tensor points = torch::rand({300, 3}, torch::kFloat64) * 3 - 1.5;
  torch::jit::Module native = jit::ModuleBuilder("NativeDistances")
                                  .Attribute("native_kinds", c10::List<std::string>(NativeShapeKinds()))
                                  .Methods("geometry/native_distances.py")
                                  .Build();
  torch::jit::Module portable = jit::ModuleBuilder("Distances").Methods("geometry/distances.py").Build();
  for (const auto& rows : {c10::IValue(scene), c10::IValue(prepared)}) {
    const auto n = jit::Call(native, "distance", {points, rows}).toTuple();
    const auto p = jit::Call(portable, "distance", {points, rows}).toTuple();
    EXPECT_LT((n->elements()[0].toTensor() - p->elements()[0].toTensor()).abs().max().item<double>(), 1e-12);
    EXPECT_LT((n->elements()[1].toTensor() - p->elements()[1].toTensor()).abs().max().item<double>(), 1e-12);
    EXPECT_EQ(n->elements()[1].toTensor().sizes(), torch::IntArrayRef({300, 8, 3}));
    const torch::Tensor only = jit::Call(native, "distance_only", {points, rows}).toTensor();
    EXPECT_LT((only - jit::Call(portable, "distance_only", {points, rows}).toTensor()).abs().max().item<double>(),
              1e-12);
  }
  // A kind the operator does not know goes to its script: here every kind is known but none is listed.
  torch::jit::Module scripted = jit::ModuleBuilder("NativeDistances")
                                    .Attribute("native_kinds", c10::ListType::ofStrings(), c10::List<std::string>())
                                    .Methods("geometry/native_distances.py")
                                    .Build();
  const auto s = jit::Call(scripted, "distance", {points, c10::IValue(prepared)}).toTuple();
  const auto p = jit::Call(portable, "distance", {points, c10::IValue(prepared)}).toTuple();
  EXPECT_TRUE(torch::equal(s->elements()[1].toTensor(), p->elements()[1].toTensor()));
}

TEST(ShapeDistanceKernelTest, BadRowsAreOneClearError) {
  const torch::Tensor points = torch::zeros({4, 3});
  const torch::Tensor box = RandomRows("boxes", 3, 1);  // not prepared
  try {
    ShapeDistance("boxes", points, box, true);
    FAIL() << "unprepared boxes were accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("boxes: expected (K, 19) rows (prepared_scene), got (1, 10)"));
  }
  try {
    ShapeDistance("cones", points, box, true);
    FAIL() << "an unknown kind was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown shape kind cones"));
  }
  try {
    ShapeDistance("spheres", points.to(torch::kInt64), box, true);
    FAIL() << "integer points were accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("float32 or float64"));
  }
  try {
    ShapeDistance("spheres", points.clone().requires_grad_(true), RandomRows("spheres", 3, 1), true);
    FAIL() << "points that need a gradient were accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("no autograd"));
  }
  // Through the registered operator the same message reaches the caller, as LibTorch's error.
  const c10::OperatorHandle op = c10::Dispatcher::singleton().findSchemaOrThrow("flowplan::shape_distance", "");
  try {
    torch::jit::Stack stack{c10::IValue(std::string("boxes")), points, box, true};
    op.callBoxed(&stack);
    FAIL() << "the operator accepted unprepared boxes";
  } catch (const c10::Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("boxes: expected (K, 19) rows (prepared_scene), got (1, 10)"));
  }
  torch::jit::Module native = jit::ModuleBuilder("NativeDistances")
                                  .Attribute("native_kinds", c10::List<std::string>(NativeShapeKinds()))
                                  .Methods("geometry/native_distances.py")
                                  .Build();
  // Points that need a gradient go to the scripts, which autograd can follow.
  const torch::Tensor tracked = torch::rand({5, 3}, torch::kFloat64).requires_grad_(true);
  c10::Dict<std::string, torch::Tensor> scene;
  scene.insert("boxes", RandomRows("boxes", 3, 2));
  const torch::Tensor d = jit::Call(native, "distance_only", {tracked, scene}).toTensor();
  EXPECT_TRUE(d.requires_grad());
}

}  // namespace
}  // namespace flowplan::kernels
