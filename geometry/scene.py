# TorchScript (compiled by flowplan at run time, jit/library.h): a scene is a
# Dict[str, Tensor] from obstacle kind to its rows, in world units, e.g.
# {"spheres": (K1, W + 1), "boxes": (K2, 10)}; a kind with no obstacles is
# absent. Obstacles are numbered in the dict's order (the kinds' order below:
# spheres, boxes, cylinders, capsules), row by row. A planning call prepares its
# scene once (prepared_scene): rotated shapes' rows carry their rotation
# matrices after their own columns, which the distances take instead of
# computing them again in every guidance step.
#
# The shapes: one line per shape in each of the dispatch functions below
# (shape_distance_only: the shapes with a cheaper way to their distances alone).

from typing import Dict, List, Optional, Tuple

import torch
from torch import Tensor

from flowplan.script.geometry.frames import check_rows
from flowplan.script.geometry.sphere import sphere_columns, sphere_distance, sphere_distance_only, sphere_problem
from flowplan.script.geometry.box import box_columns, box_distance, box_distance_only, box_prepared, box_problem
from flowplan.script.geometry.cylinder import (
    cylinder_columns, cylinder_distance, cylinder_distance_only, cylinder_prepared, cylinder_problem,
)
from flowplan.script.geometry.capsule import capsule_columns, capsule_distance, capsule_problem


def shape_kinds() -> List[str]:
    return ["spheres", "boxes", "cylinders", "capsules"]


def shape_columns(kind: str, W: int) -> int:
    if kind == "spheres":
        return sphere_columns(W)
    if kind == "boxes":
        return box_columns(W)
    if kind == "cylinders":
        return cylinder_columns(W)
    if kind == "capsules":
        return capsule_columns(W)
    raise Exception("unknown obstacle kind " + kind)


def shape_problem(kind: str, params: Tensor, W: int) -> str:
    if kind == "spheres":
        return sphere_problem(params, W)
    if kind == "boxes":
        return box_problem(params, W)
    if kind == "cylinders":
        return cylinder_problem(params, W)
    if kind == "capsules":
        return capsule_problem(params, W)
    raise Exception("unknown obstacle kind " + kind)


def shape_distance(kind: str, points: Tensor, params: Tensor) -> Tuple[Tensor, Tensor]:
    if kind == "spheres":
        return sphere_distance(points, params)
    if kind == "boxes":
        return box_distance(points, params)
    if kind == "cylinders":
        return cylinder_distance(points, params)
    if kind == "capsules":
        return capsule_distance(points, params)
    raise Exception("unknown obstacle kind " + kind)


def shape_prepared(kind: str, params: Tensor, W: int) -> Tensor:
    """The rows of one kind with what every distance would compute from them
    again appended (a rotated shape's rotation matrix); the distances take
    either. The shapes without such a part are their own, and so are rows
    already prepared."""
    if params.size(1) != shape_columns(kind, W):
        return params
    if kind == "boxes":
        return box_prepared(params, W)
    if kind == "cylinders":
        return cylinder_prepared(params, W)
    return params


def shape_distance_only(kind: str, points: Tensor, params: Tensor) -> Tensor:
    """shape_distance's distances (M, K) alone, without the work of their
    gradient (a capsule's nearest point gives both at once)."""
    if kind == "spheres":
        return sphere_distance_only(points, params)
    if kind == "boxes":
        return box_distance_only(points, params)
    if kind == "cylinders":
        return cylinder_distance_only(points, params)
    return shape_distance(kind, points, params)[0]


def add_obstacles(scene: Dict[str, Tensor], kind: str, params: Optional[Tensor], W: int, where: str):
    """Checks the rows `params` of one kind (an argument named `where` in
    messages) and adds them to `scene`, after any rows of that kind already there."""
    if params is None:
        return
    problem = check_rows(params, shape_columns(kind, W), kind)
    if problem == "":
        problem = shape_problem(kind, params.double(), W)
    assert problem == "", where + ": " + problem
    if params.size(0) == 0:
        return
    if kind in scene:
        scene[kind] = torch.cat([scene[kind], params.to(scene[kind].dtype)], 0)
    else:
        scene[kind] = params


def prepared_scene(scene: Dict[str, Tensor], W: int) -> Dict[str, Tensor]:
    """A checked scene (add_obstacles) with every kind's rows prepared
    (shape_prepared), for the many distance passes of one planning call."""
    out: Dict[str, Tensor] = {}
    for kind, params in scene.items():
        out[kind] = shape_prepared(kind, params, W)
    return out


def given_scene(scene: Dict[str, Tensor], W: int) -> Dict[str, Tensor]:
    """A scene's rows as a caller gives them (shape_columns of each kind):
    a prepared scene without its appended columns."""
    out: Dict[str, Tensor] = {}
    for kind, params in scene.items():
        out[kind] = params.narrow(1, 0, shape_columns(kind, W))
    return out


def ordered_scene(scene: Dict[str, Tensor]) -> Dict[str, Tensor]:
    """The same obstacles with the kinds in their canonical order."""
    out: Dict[str, Tensor] = {}
    for kind in shape_kinds():
        if kind in scene:
            out[kind] = scene[kind]
    return out


def scene_size(scene: Dict[str, Tensor]) -> int:
    """K: the number of obstacles."""
    total = 0
    for kind, params in scene.items():
        total += params.size(0)
    return total


def scene_distance(points: Tensor, scene: Dict[str, Tensor]) -> Tuple[Tensor, Tensor]:
    """Signed distance from points (M, W) to every obstacle (negative inside):
    (M, K), and its gradient with respect to the points (M, K, W)."""
    if len(scene) == 1:
        for kind, params in scene.items():
            return shape_distance(kind, points, params.to(points.dtype))
    distances: List[Tensor] = []
    gradients: List[Tensor] = []
    for kind, params in scene.items():
        distance, gradient = shape_distance(kind, points, params.to(points.dtype))
        distances.append(distance)
        gradients.append(gradient)
    if len(distances) == 0:
        M = points.size(0)
        W = points.size(1)
        return torch.zeros([M, 0], dtype=points.dtype, device=points.device), torch.zeros([M, 0, W], dtype=points.dtype, device=points.device)
    return torch.cat(distances, 1), torch.cat(gradients, 1)


def scene_distance_only(points: Tensor, scene: Dict[str, Tensor]) -> Tensor:
    """The signed distances (M, K) of scene_distance without their gradient."""
    distances: List[Tensor] = []
    for kind, params in scene.items():
        distances.append(shape_distance_only(kind, points, params.to(points.dtype)))
    if len(distances) == 0:
        return torch.zeros([points.size(0), 0], dtype=points.dtype, device=points.device)
    return distances[0] if len(distances) == 1 else torch.cat(distances, 1)
