#include "geometry/scene.h"
#include "geometry/scene_rows.h"

#include <algorithm>

#include "core/error.h"
#include "core/format.h"
#include "jit/library.h"

namespace flowplan::geometry {
namespace {

std::string Count(size_t n) { return n == 0 ? std::string("none") : std::to_string(n); }

void CheckPoint(const std::vector<double>& values, int W, const std::string& entry) {
  if (values.size() != static_cast<size_t>(W)) {
    throw Error(entry + ": expected " + std::to_string(W) + " values (the robot's workspace is " + std::to_string(W) +
                "-D), got " + Count(values.size()));
  }
}

void CheckGiven(double value, const std::string& entry) {
  if (std::isnan(value)) throw Error(entry + ": missing");
}

/// The orientation of a box or cylinder: a quaternion in 3-D, an angle in 2-D.
void CheckOrientation(const std::vector<double>& quaternion, double angle, int W, const std::string& entry) {
  if (W == 3) {
    if (!std::isnan(angle)) throw Error(entry + ".angle: a 3-D obstacle is turned by `quaternion` (w, x, y, z)");
    if (quaternion.empty()) return;
    if (quaternion.size() != 4) {
      throw Error(entry + ".quaternion: expected 4 values (w, x, y, z), got " + std::to_string(quaternion.size()));
    }
    double norm = 0.0;
    for (double q : quaternion) norm += q * q;
    if (norm == 0.0) throw Error(entry + ".quaternion: expected a non-zero quaternion, got [0, 0, 0, 0]");
  } else if (!quaternion.empty()) {
    throw Error(entry + ".quaternion: a 2-D obstacle is turned by `angle` (rad)");
  }
}

std::vector<double> Orientation(const std::vector<double>& quaternion, double angle, int W) {
  if (W != 3) return {std::isnan(angle) ? 0.0 : angle};
  if (quaternion.empty()) return {1.0, 0.0, 0.0, 0.0};
  double norm = 0.0;
  for (double q : quaternion) norm += q * q;
  norm = std::sqrt(norm);
  return {quaternion[0] / norm, quaternion[1] / norm, quaternion[2] / norm, quaternion[3] / norm};
}

/// (K, columns) float64 from rows of numbers.
torch::Tensor Stack(const std::vector<std::vector<double>>& rows) {
  const int64_t K = static_cast<int64_t>(rows.size()), C = static_cast<int64_t>(rows[0].size());
  torch::Tensor out = torch::empty({K, C}, torch::kFloat64);
  auto a = out.accessor<double, 2>();
  for (int64_t k = 0; k < K; ++k) {
    for (int64_t c = 0; c < C; ++c) a[k][c] = rows[k][c];
  }
  return out;
}

void Append(std::vector<double>& row, const std::vector<double>& values) { row.insert(row.end(), values.begin(), values.end()); }

}  // namespace

const std::vector<std::string>& ObstacleKinds() {
  static const std::vector<std::string> kinds = {"spheres", "boxes", "cylinders", "capsules"};
  return kinds;
}

int64_t Scene::size() const {
  return static_cast<int64_t>(spheres.size() + boxes.size() + cylinders.size() + capsules.size());
}

std::vector<std::string> Scene::Names() const {
  std::vector<std::string> names;
  const size_t counts[] = {spheres.size(), boxes.size(), cylinders.size(), capsules.size()};
  for (size_t kind = 0; kind < 4; ++kind) {
    for (size_t k = 0; k < counts[kind]; ++k) names.push_back(ObstacleKinds()[kind] + "[" + std::to_string(k) + "]");
  }
  return names;
}

void Scene::Validate(int W, const std::string& where) const {
  auto entry = [&](const char* kind, size_t k) { return where + ": " + kind + "[" + std::to_string(k) + "]"; };
  for (size_t k = 0; k < spheres.size(); ++k) {
    CheckPoint(spheres[k].centre, W, entry("spheres", k) + ".centre");
    CheckGiven(spheres[k].radius, entry("spheres", k) + ".radius");
  }
  for (size_t k = 0; k < boxes.size(); ++k) {
    CheckPoint(boxes[k].centre, W, entry("boxes", k) + ".centre");
    CheckPoint(boxes[k].size, W, entry("boxes", k) + ".size");
    CheckOrientation(boxes[k].quaternion, boxes[k].angle, W, entry("boxes", k));
  }
  for (size_t k = 0; k < cylinders.size(); ++k) {
    CheckPoint(cylinders[k].centre, W, entry("cylinders", k) + ".centre");
    CheckGiven(cylinders[k].radius, entry("cylinders", k) + ".radius");
    CheckGiven(cylinders[k].height, entry("cylinders", k) + ".height");
    CheckOrientation(cylinders[k].quaternion, cylinders[k].angle, W, entry("cylinders", k));
  }
  for (size_t k = 0; k < capsules.size(); ++k) {
    CheckPoint(capsules[k].a, W, entry("capsules", k) + ".a");
    CheckPoint(capsules[k].b, W, entry("capsules", k) + ".b");
    CheckGiven(capsules[k].radius, entry("capsules", k) + ".radius");
  }
}

SceneRows Rows(const Scene& scene, int W, const std::string& where) {
  scene.Validate(W, where);
  SceneRows rows;
  std::vector<std::vector<double>> table;
  auto flush = [&](const std::string& kind) {
    if (!table.empty()) rows.insert(kind, Stack(table));
    table.clear();
  };
  for (const SphereObstacle& s : scene.spheres) {
    table.push_back(s.centre);
    table.back().push_back(s.radius);
  }
  flush("spheres");
  for (const BoxObstacle& b : scene.boxes) {
    table.push_back(b.centre);
    Append(table.back(), b.size);
    Append(table.back(), Orientation(b.quaternion, b.angle, W));
  }
  flush("boxes");
  for (const CylinderObstacle& c : scene.cylinders) {
    table.push_back(c.centre);
    Append(table.back(), {c.radius, c.height});
    Append(table.back(), Orientation(c.quaternion, c.angle, W));
  }
  flush("cylinders");
  for (const CapsuleObstacle& c : scene.capsules) {
    table.push_back(c.a);
    Append(table.back(), c.b);
    table.back().push_back(c.radius);
  }
  flush("capsules");
  return rows;
}

Scene LoadScene(const std::string& path) {
  Scene scene;
  config::Apply(config::ParseYamlFile(path), scene, path);
  return scene;
}

void AddObstacle(Scene& scene, const std::string& kind, const std::vector<double>& values, int W,
                 const std::string& where) {
  const size_t n = values.size(), w = static_cast<size_t>(W);
  const size_t turn = W == 3 ? 4 : 1;  // quaternion or angle
  auto expect = [&](const std::vector<size_t>& counts, const std::string& layout) {
    for (size_t c : counts) {
      if (n == c) return;
    }
    throw Error(where + ": expected " + layout + " (the robot's workspace is " + std::to_string(W) + "-D), got " +
                std::to_string(n) + " numbers");
  };
  auto slice = [&](size_t begin, size_t count) {
    return std::vector<double>(values.begin() + static_cast<std::ptrdiff_t>(begin),
                               values.begin() + static_cast<std::ptrdiff_t>(begin + count));
  };
  auto negative = [&](double value, const char* what) {
    if (value < 0) throw Error(where + ": expected a non-negative " + std::string(what) + ", got " + JsonNumber(value));
  };
  const std::string centre = W == 3 ? "cx,cy,cz" : "cx,cy";
  const std::string rotation = W == 3 ? "[,qw,qx,qy,qz]" : "[,angle]";
  if (kind == "spheres") {
    expect({w + 1}, centre + ",r");
    negative(values[w], "radius");
    scene.spheres.push_back({slice(0, w), values[w]});
  } else if (kind == "boxes") {
    expect({2 * w, 2 * w + turn}, centre + (W == 3 ? ",lx,ly,lz" : ",lx,ly") + rotation);
    BoxObstacle box{slice(0, w), slice(w, w), {}, NAN};
    for (double s : box.size) negative(s, "size");
    if (n > 2 * w) {
      if (W == 3) {
        box.quaternion = slice(2 * w, 4);
      } else {
        box.angle = values[2 * w];
      }
    }
    scene.boxes.push_back(box);
    CheckOrientation(box.quaternion, box.angle, W, where);
  } else if (kind == "cylinders") {
    expect({w + 2, w + 2 + turn}, centre + ",r,h" + rotation);
    CylinderObstacle cylinder{slice(0, w), values[w], values[w + 1], {}, NAN};
    negative(cylinder.radius, "radius");
    negative(cylinder.height, "height");
    if (n > w + 2) {
      if (W == 3) {
        cylinder.quaternion = slice(w + 2, 4);
      } else {
        cylinder.angle = values[w + 2];
      }
    }
    scene.cylinders.push_back(cylinder);
    CheckOrientation(cylinder.quaternion, cylinder.angle, W, where);
  } else if (kind == "capsules") {
    expect({2 * w + 1}, centre + "(a)," + centre + "(b),r");
    negative(values[2 * w], "radius");
    scene.capsules.push_back({slice(0, w), slice(w, w), values[2 * w]});
  } else {
    throw InternalError("AddObstacle: unknown kind " + kind);
  }
}

int64_t CountObstacles(const SceneRows& rows) {
  int64_t K = 0;
  for (const auto& entry : rows) K += entry.value().size(0);
  return K;
}

void CheckRows(const SceneRows& rows, int W, const std::string& where) {
  for (const auto& entry : rows) {
    const std::string& kind = entry.key();
    if (std::find(ObstacleKinds().begin(), ObstacleKinds().end(), kind) == ObstacleKinds().end()) {
      throw Error(where + ": unknown obstacle kind \"" + kind + "\" (expected " + Join(ObstacleKinds()) + ")");
    }
    c10::Dict<std::string, torch::Tensor> scratch;
    jit::CallFunction("add_obstacles", {scratch, kind, entry.value(), static_cast<int64_t>(W), where + ": " + kind});
  }
}

Scene SceneOf(const SceneRows& rows, int W, const std::string& where) {
  CheckRows(rows, W, where);
  Scene scene;
  auto row = [](const torch::Tensor& rows, int64_t k) {
    const torch::Tensor r = rows[k].to(torch::kFloat64).contiguous();
    return std::vector<double>(r.data_ptr<double>(), r.data_ptr<double>() + r.numel());
  };
  auto part = [](const std::vector<double>& v, size_t from, size_t count) {
    return std::vector<double>(v.begin() + static_cast<std::ptrdiff_t>(from),
                               v.begin() + static_cast<std::ptrdiff_t>(from + count));
  };
  const size_t w = static_cast<size_t>(W);
  for (const auto& entry : rows) {
    const torch::Tensor& table = entry.value();
    for (int64_t k = 0; k < table.size(0); ++k) {
      const std::vector<double> v = row(table, k);
      if (entry.key() == "spheres") {
        scene.spheres.push_back({part(v, 0, w), v[w]});
      } else if (entry.key() == "boxes") {
        BoxObstacle b{part(v, 0, w), part(v, w, w), {}, NAN};
        if (W == 3) b.quaternion = part(v, 2 * w, 4); else b.angle = v[2 * w];
        scene.boxes.push_back(b);
      } else if (entry.key() == "cylinders") {
        CylinderObstacle c{part(v, 0, w), v[w], v[w + 1], {}, NAN};
        if (W == 3) c.quaternion = part(v, w + 2, 4); else c.angle = v[w + 2];
        scene.cylinders.push_back(c);
      } else {
        scene.capsules.push_back({part(v, 0, w), part(v, w, w), v[2 * w]});
      }
    }
  }
  return scene;
}

SceneRows PreparedRows(const SceneRows& rows, int W) {
  SceneRows prepared;
  for (const auto& entry : jit::CallFunction("prepared_scene", {rows, static_cast<int64_t>(W)}).toGenericDict()) {
    prepared.insert(entry.key().toStringRef(), entry.value().toTensor());
  }
  return prepared;
}

SceneRows SphereRows(const torch::Tensor& spheres) {
  SceneRows rows;
  if (spheres.defined() && spheres.size(0) > 0) rows.insert("spheres", spheres);
  return rows;
}

}  // namespace flowplan::geometry
