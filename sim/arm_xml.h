#pragma once

// MJCF text of an arm from its plain description (kinematics/robot_description.h)
// and of a scene's obstacles: the one writer of both, for simulating a robot
// folder (robotfiles/robot_model.h), drawing any arm (render/), and executing
// plans of the Franka among obstacles (sim/franka_execution.h).

#include <map>
#include <string>
#include <vector>

#include "geometry/scene.h"
#include "kinematics/robot_description.h"

namespace flowplan::sim {

/// What ArmXml puts around the kinematic tree.
struct ArmXmlOptions {
  std::string compiler = "angle=\"radian\"";           // attributes of <compiler>
  std::map<std::string, std::string> body_elements;      // link name -> XML inside its body (inertial, geoms)
  std::string model_elements;                            // XML inside <mujoco> before <worldbody> (<asset>, <size>)
  std::string world_elements;                            // XML inside <worldbody> besides the arm (obstacles)
  std::vector<double> effort_limit;                      // (J) torque or force limits: one motor per planned joint;
                                                         // empty: none
  double armature = 0.0;                                 // added to every planned joint
  double damping = 0.0;                                  // viscous friction of every planned joint
};

/// The MJCF of `d`: a body per link named after it ("world (link)" for a link
/// called world, MuJoCo's name for its world body; pos and quat in its parent;
/// a held joint welded at its value), planned joint j as the hinge or slide
/// "q<j>" at the body's origin with its limits, the site "tcp", and motor j
/// driving joint j. The joints' order in MuJoCo is the tree's, not j's: find
/// them by name.
std::string ArmXml(const kinematics::RobotDescription& d, const ArmXmlOptions& options);

/// <geom> elements of every obstacle of `scene` (3-D), named obstacle0,
/// obstacle1, … in the scene's order (spheres, boxes, cylinders, capsules),
/// each carrying `attributes` (e.g. contact and colour settings).
std::string ObstacleGeomsXml(const geometry::Scene& scene, const std::string& attributes);

/// XML attribute text: the characters XML reserves, escaped.
std::string XmlEscaped(const std::string& text);

/// A number as MJCF text, exactly (17 significant digits).
std::string XmlNumber(double value);

}  // namespace flowplan::sim
