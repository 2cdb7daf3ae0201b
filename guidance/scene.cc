#include "guidance/scene.h"

#include "core/error.h"
#include "core/format.h"

namespace flowplan::guidance {

void Scene::Validate(int workspace_dim, const std::string& where) const {
  for (size_t k = 0; k < spheres.size(); ++k) {
    const std::string entry = where + ": spheres[" + std::to_string(k) + "]";
    const SphereObstacle& sphere = spheres[k];
    if (sphere.centre.size() != static_cast<size_t>(workspace_dim)) {
      throw Error(entry + ".centre: expected " + std::to_string(workspace_dim) + " values (the robot's workspace is " +
                  std::to_string(workspace_dim) + "-D), got " +
                  (sphere.centre.empty() ? std::string("none") : std::to_string(sphere.centre.size())));
    }
    if (std::isnan(sphere.radius)) throw Error(entry + ".radius: missing");
  }
}

torch::Tensor Scene::Obstacles(int workspace_dim, const std::string& where) const {
  Validate(workspace_dim, where);
  torch::Tensor out = torch::empty({size(), workspace_dim + 1}, torch::kFloat32);
  for (int64_t k = 0; k < size(); ++k) {
    for (int i = 0; i < workspace_dim; ++i) out[k][i] = spheres[k].centre[i];
    out[k][workspace_dim] = spheres[k].radius;
  }
  return out;
}

Scene LoadScene(const std::string& path) {
  Scene scene;
  config::Apply(config::ParseYamlFile(path), scene, path);
  return scene;
}

void CheckObstacles(const torch::Tensor& obstacles, int workspace_dim, const std::string& where) {
  if (!obstacles.defined()) return;
  if (obstacles.dim() != 2 || obstacles.size(1) != workspace_dim + 1) {
    throw Error(where + ": expected (K, " + std::to_string(workspace_dim + 1) + ") rows of centre and radius, got " +
                ShapeText(obstacles.sizes().vec()));
  }
  const torch::Tensor o = obstacles.to(torch::kFloat64).contiguous();
  for (int64_t k = 0; k < o.size(0); ++k) {
    for (int i = 0; i <= workspace_dim; ++i) {
      const double value = o[k][i].item<double>();
      if (!std::isfinite(value)) {
        throw Error(where + ": obstacle " + std::to_string(k) + ": expected finite values, got " + config::internal::FormatDouble(value));
      }
    }
    if (o[k][workspace_dim].item<double>() < 0.0) {
      throw Error(where + ": obstacle " + std::to_string(k) + ": expected a non-negative radius, got " +
                  config::internal::FormatDouble(o[k][workspace_dim].item<double>()));
    }
  }
}

}  // namespace flowplan::guidance
