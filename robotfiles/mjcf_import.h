#pragma once

// `flowplan robot import MODEL.xml`: a robot folder from an MJCF model, read by
// MuJoCo itself (mj_loadXML: includes, defaults, mesh files and compiler
// settings as MuJoCo resolves them). The tree below the base body (default:
// the first body of the world) becomes the robot: a body with one hinge or
// slide joint through its origin is a joint, a body without one is welded.
// Planned and held joints, the TCP and the collision spheres are chosen as for
// a URDF (robotfiles/urdf_import.h); the collision geometry is every geom of
// options.collision_group, or without one every geom that collides (contype or
// conaffinity set): spheres kept as they are;
// capsules, boxes, cylinders, ellipsoids and meshes covered.
//
// Limits: a joint's range (a hinge without one turns within ±π, a slide needs
// one); speeds, which MJCF does not have, from options.velocity_limit or a
// <numeric name="velocity_limit"> of J values; efforts from the actuator that
// drives the joint (its forcerange, else ctrlrange × gear), left out when a
// planned joint has none.

#include <string>

#include "robotfiles/urdf_import.h"

namespace flowplan::robotfiles {

/// Reads `mjcf_path` and fits the collision body, writing nothing.
/// @throws flowplan::Error naming the file and the element at fault.
ImportResult ImportMjcf(const std::string& mjcf_path, const ImportOptions& options);

}  // namespace flowplan::robotfiles
