#pragma once

// A scene as planning calls, costs and checks take it: obstacle kind ->
// (K, columns) rows (geometry/*.py document the columns), the form the
// exported planner takes as tensor arguments.

#include <torch/torch.h>

#include <string>

#include "geometry/scene.h"

namespace flowplan::geometry {

/// kind -> (K, columns) rows, kinds in the canonical order (ObstacleKinds()),
/// kinds without obstacles absent; float64 when made from a Scene.
using SceneRows = c10::Dict<std::string, torch::Tensor>;

/// The rows of a validated scene (quaternions normalised).
/// @throws flowplan::Error as Scene::Validate.
SceneRows Rows(const Scene& scene, int workspace_dim, const std::string& where);

/// The number of obstacles K of `rows`.
int64_t CountObstacles(const SceneRows& rows);

/// Checks rows from outside (a caller's tensors) as the exported planner does:
/// known kinds, (K, columns) finite values, non-negative sizes, non-zero
/// quaternions. @throws flowplan::Error "<where>: boxes: row 0: expected ...".
void CheckRows(const SceneRows& rows, int workspace_dim, const std::string& where);

/// The scene of checked rows (the inverse of Rows, e.g. for a plan file's
/// scene): 3-D boxes and cylinders keep their quaternions, 2-D ones their angles.
/// @throws flowplan::Error as CheckRows.
Scene SceneOf(const SceneRows& rows, int workspace_dim, const std::string& where);

/// The same rows with what every distance would compute from them appended
/// (a box's or cylinder's rotation matrix: geometry/scene.py's
/// prepared_scene); every distance takes either form. For a caller that
/// measures one scene many times (a search, a plan check).
SceneRows PreparedRows(const SceneRows& rows, int workspace_dim);

/// The rows of a sphere tensor (K, W + 1) (the older form of a scene).
SceneRows SphereRows(const torch::Tensor& spheres);

}  // namespace flowplan::geometry
