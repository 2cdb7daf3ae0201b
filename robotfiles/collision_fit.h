#pragma once

// What every robot import shares once it has the kinematic tree and each
// link's collision geometry: the spheres covering the geometry and their
// report, the link pairs not checked for self-collision (an SRDF's, or
// sampled), and the links standing on the floor. robotfiles/urdf_import.h
// and robotfiles/mjcf_import.h call it.

#include <string>
#include <vector>

#include "robotfiles/urdf_import.h"
#include "spheres/cover.h"
#include "spheres/mesh.h"

namespace flowplan::robotfiles {

/// One link's collision geometry in its frame: meshes to cover, and spheres kept as they are.
struct LinkGeometry {
  std::string link;
  std::vector<spheres::Mesh> pieces;
  std::vector<spheres::Sphere> exact;
};

/// A link's name as a file name in the robot folder: letters, digits, '-' and '_' kept, anything else '_'
/// (so no '/' and no "..").
std::string SafeFileName(const std::string& name);

/// Fills result.file.collision (spheres, ignored pairs, floor_exempt) and result.file.cover for
/// result.file.robot, whose tree, joints and home must be set; notes go to result.notes.
/// @throws flowplan::Error prefixed by `where` if no link has collision geometry, or the SRDF cannot be read.
void FitCollisionBody(const std::vector<LinkGeometry>& gathered, const ImportOptions& options, const std::string& where,
                      ImportResult& result);

}  // namespace flowplan::robotfiles
