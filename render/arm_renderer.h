#pragma once

// Pictures of an arm among a scene's obstacles from MuJoCo's own renderer,
// offscreen and headless: an OSMesa context (Mesa's software rasteriser,
// Debian's libosmesa6) holds the OpenGL state MuJoCo draws into, so no display,
// GPU or window system is needed. The built-in Franka is drawn by its collision
// capsules (its model has no meshes), any other arm by its collision spheres
// (what the planner and the plan checker see of it), the obstacles by their
// real shapes, the floor as a plane, and a path's TCP as a trail of small
// spheres.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "core/config.h"
#include "geometry/scene.h"
#include "kinematics/robot_description.h"
#include "render/image_files.h"
#include "sim/franka_model.h"
#include "sim/mujoco_util.h"

namespace flowplan::render {

/// The `render` section of an experiment config: the picture and the camera.
struct RenderConfig {
  int width = 640;
  int height = 480;
  std::array<double, 3> lookat = {0.35, 0.0, 0.35};  // m, the point the camera looks at
  double distance = 2.0;                              // m from it
  double azimuth = 145.0;                             // deg, about the world z axis
  double elevation = -25.0;                           // deg, negative: from above
  bool frame = true;  // `flowplan render`: lookat, distance and azimuth chosen by Framed (false: as given)

  template <class V>
  void Visit(V& v) {
    v.Field("width", width, "picture width (pixels)", config::InRange(16, 4096));
    v.Field("height", height, "picture height (pixels)", config::InRange(16, 4096));
    v.Field("lookat", lookat, "point the camera looks at (m)");
    v.Field("distance", distance, "camera distance from lookat (m)", config::Positive());
    v.Field("azimuth", azimuth, "camera azimuth about the world z axis (deg)");
    v.Field("elevation", elevation, "camera elevation (deg; negative looks down)", config::InRange(-90.0, 90.0));
    v.Field("frame", frame,
            "`flowplan render`: frame the scene and the plan (lookat, distance and azimuth chosen; false: as given)");
  }
};

/// `config` with a camera that frames `points` (world, m: the arm's states) and every obstacle of `scene`: looking
/// at the middle of their bounding box, from config.elevation, 60° to the left of the direction from the world's
/// origin (the arm's base) to that middle (from beside and in front of the arm, into shelves and boxes that open
/// towards it), far enough that the sphere around the box fits MuJoCo's 45° field of view.
RenderConfig Framed(RenderConfig config, const geometry::Scene& scene, const std::vector<Eigen::Vector3d>& points);

/// Colours of the pictures (RGB in [0, 1]); tests look for them.
inline constexpr std::array<float, 3> kArmColour = {0.62f, 0.68f, 0.80f};
inline constexpr std::array<float, 3> kObstacleColour = {0.85f, 0.18f, 0.16f};
inline constexpr std::array<float, 3> kTrailColour = {0.10f, 0.80f, 0.20f};

/// The camera as OpenGL sees it, for projecting world points to pixels.
struct CameraView {
  Eigen::Vector3d position, forward, up;  // world
  double frustum_center, frustum_bottom, frustum_top, frustum_near;
};

class ArmRenderer {
 public:
  /// The built-in Franka among `scene`'s obstacles, in an offscreen context of
  /// config.width × height.
  /// @throws flowplan::Error if the scene is not 3-D or no OpenGL context can be made.
  ArmRenderer(const geometry::Scene& scene, const RenderConfig& config);
  /// Any arm (`robot`, kind arm) drawn by its collision spheres, likewise.
  /// @throws flowplan::Error as above, or if `robot` is not an arm.
  ArmRenderer(const kinematics::RobotDescription& robot, const geometry::Scene& scene, const RenderConfig& config);
  ~ArmRenderer();
  ArmRenderer(const ArmRenderer&) = delete;
  ArmRenderer& operator=(const ArmRenderer&) = delete;

  /// The arm at q (its J joint values, rad or m), with an optional trail of points (m, e.g. the TCP path so far).
  Image Render(const std::vector<double>& q, const std::vector<Eigen::Vector3d>& trail = {});

  int num_joints() const { return static_cast<int>(qpos_.size()); }

  /// The camera of the last picture.
  const CameraView& camera() const { return camera_; }

 private:
  struct Gl;  // the OSMesa context, its buffer and MuJoCo's render context

  ArmRenderer(sim::MjModelPtr model, std::vector<int> qpos, const geometry::Scene& scene, const RenderConfig& config);

  RenderConfig config_;
  std::vector<int> qpos_;  // (J) index into qpos of joint j
  sim::MjModelPtr model_;  // the scene's model, recoloured for pictures
  sim::MjDataPtr data_;
  std::unique_ptr<Gl> gl_;
  CameraView camera_{};
  double floor_height_ = 0.0;
};

}  // namespace flowplan::render
