#include "render/arm_renderer.h"

#include <GL/osmesa.h>
#include <dlfcn.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <Eigen/Geometry>
#include <cmath>

#include "core/error.h"
#include "sim/arm_xml.h"
#include "sim/franka_execution.h"

namespace flowplan::render {
namespace {

constexpr int kMaxGeoms = 20000;

/// MuJoCo looks OpenGL's functions up among the process's global symbols. A program linked with flowplan has
/// OSMesa's there; a process that loaded flowplan as a library (the Python package's module, opened with
/// RTLD_LOCAL) has them only in that library's scope: OSMesa is made global, once. Libraries the process loads
/// afterwards then see OSMesa's gl* functions too (as they would in a program linked with it).
void ExposeOpenGl() {
  static const bool exposed = [] {
    Dl_info info;
    if (dladdr(reinterpret_cast<void*>(&OSMesaCreateContextExt), &info) == 0 || info.dli_fname == nullptr) return false;
    return dlopen(info.dli_fname, RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD) != nullptr;
  }();
  (void)exposed;
}

/// The lowest point (m) of any obstacle of `scene`, bounded from below by its bounding sphere; +inf for none.
double LowestObstaclePoint(const geometry::Scene& scene) {
  double lowest = INFINITY;
  auto norm = [](const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x * x;
    return std::sqrt(s);
  };
  for (const auto& s : scene.spheres) lowest = std::min(lowest, s.centre[2] - s.radius);
  for (const auto& b : scene.boxes) lowest = std::min(lowest, b.centre[2] - 0.5 * norm(b.size));
  for (const auto& c : scene.cylinders) lowest = std::min(lowest, c.centre[2] - std::hypot(c.radius, 0.5 * c.height));
  for (const auto& c : scene.capsules) lowest = std::min(lowest, std::min(c.a[2], c.b[2]) - c.radius);
  return lowest;
}

}  // namespace

struct ArmRenderer::Gl {
  OSMesaContext context = nullptr;
  std::vector<unsigned char> buffer;  // the window OSMesa draws into (MuJoCo renders into its own offscreen buffer)
  mjvScene scene;
  mjrContext render;
  mjvOption option;
  mjvCamera camera;
  ~Gl() {
    mjr_freeContext(&render);
    mjv_freeScene(&scene);
    if (context != nullptr) OSMesaDestroyContext(context);
  }
};

namespace {

/// The Franka model's joints are its first qpos entries.
std::vector<int> FirstJoints(int count) {
  std::vector<int> qpos;
  for (int j = 0; j < count; ++j) qpos.push_back(j);
  return qpos;
}

/// A model of `robot` for drawing: its spheres as geoms, massless bodies given a token inertia, the obstacles.
sim::MjModelPtr SphereModel(const kinematics::RobotDescription& robot, const geometry::Scene& scene) {
  if (robot.kind != kinematics::RobotKind::kArm) throw Error("render: draws arms; the robot \"" + robot.name + "\" is a point");
  scene.Validate(3, "render scene");
  sim::ArmXmlOptions options;
  options.compiler = "angle=\"radian\" inertiafromgeom=\"false\"";
  for (const kinematics::RobotLink& link : robot.links) {
    options.body_elements[link.name] = "      <inertial pos=\"0 0 0\" mass=\"0.001\" diaginertia=\"1e-6 1e-6 1e-6\"/>\n";
  }
  for (const kinematics::RobotSphere& sphere : robot.spheres) {
    const std::string& link = robot.links[static_cast<size_t>(sphere.link)].name;
    options.body_elements[link] += "      <geom type=\"sphere\" contype=\"0\" conaffinity=\"0\" pos=\"" +
                                   sim::XmlNumber(sphere.centre[0]) + " " + sim::XmlNumber(sphere.centre[1]) + " " +
                                   sim::XmlNumber(sphere.centre[2]) + "\" size=\"" + sim::XmlNumber(sphere.radius) + "\"/>\n";
  }
  options.world_elements = sim::ObstacleGeomsXml(scene, "contype=\"0\" conaffinity=\"0\"");
  return sim::LoadModelFromXml(sim::ArmXml(robot, options), "render: the robot \"" + robot.name + "\"");
}

/// Where the description's planned joints are in the model of SphereModel.
std::vector<int> NamedJoints(const mjModel& m, int count) {
  std::vector<int> qpos;
  for (int j = 0; j < count; ++j) {
    const int id = mj_name2id(&m, mjOBJ_JOINT, ("q" + std::to_string(j)).c_str());
    FLOWPLAN_DEMAND(id >= 0);
    qpos.push_back(m.jnt_qposadr[id]);
  }
  return qpos;
}

}  // namespace

ArmRenderer::ArmRenderer(const geometry::Scene& scene, const RenderConfig& config)
    : ArmRenderer(sim::CopyModel(sim::MakeFrankaScene(scene, 0.001).mj()), FirstJoints(sim::kFrankaJoints), scene,
                  config) {}

ArmRenderer::ArmRenderer(const kinematics::RobotDescription& robot, const geometry::Scene& scene,
                         const RenderConfig& config)
    : ArmRenderer(SphereModel(robot, scene), {}, scene, config) {
  qpos_ = NamedJoints(*model_, robot.num_joints);
}

ArmRenderer::ArmRenderer(sim::MjModelPtr model, std::vector<int> qpos, const geometry::Scene& scene,
                         const RenderConfig& config)
    : config_(config), qpos_(std::move(qpos)), model_(std::move(model)), data_(sim::MakeData(*model_)) {
  floor_height_ = std::min(0.0, LowestObstaclePoint(scene)) - 0.002;
  mjModel& m = *model_;
  for (int g = 0; g < m.ngeom; ++g) {
    const bool arm = m.geom_bodyid[g] > 0;
    const std::array<float, 3>& colour = arm ? kArmColour : kObstacleColour;
    for (int c = 0; c < 3; ++c) m.geom_rgba[4 * g + c] = colour[c];
    m.geom_rgba[4 * g + 3] = 1.0f;
  }
  m.vis.global.offwidth = config.width;
  m.vis.global.offheight = config.height;
  m.vis.quality.shadowsize = 2048;

  ExposeOpenGl();
  gl_ = std::make_unique<Gl>();
  mjv_defaultScene(&gl_->scene);
  mjr_defaultContext(&gl_->render);
  gl_->context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (gl_->context == nullptr) throw Error("render: OSMesa could not create an OpenGL context");
  gl_->buffer.assign(4 * static_cast<size_t>(config.width) * config.height, 0);
  if (!OSMesaMakeCurrent(gl_->context, gl_->buffer.data(), GL_UNSIGNED_BYTE, config.width, config.height)) {
    throw Error("render: OSMesa could not make its OpenGL context current");
  }
  mjv_makeScene(&m, &gl_->scene, kMaxGeoms);
  mjr_makeContext(&m, &gl_->render, mjFONTSCALE_100);
  mjr_setBuffer(mjFB_OFFSCREEN, &gl_->render);
  if (gl_->render.currentBuffer != mjFB_OFFSCREEN || gl_->render.offWidth < config.width ||
      gl_->render.offHeight < config.height) {
    throw Error("render: MuJoCo could not make an offscreen buffer of " + std::to_string(config.width) + " x " +
                std::to_string(config.height));
  }
  mjv_defaultOption(&gl_->option);
  for (int group = 0; group < mjNGROUP; ++group) gl_->option.geomgroup[group] = 1;
  mjv_defaultCamera(&gl_->camera);
  gl_->camera.type = mjCAMERA_FREE;
  for (int i = 0; i < 3; ++i) gl_->camera.lookat[i] = config.lookat[i];
  gl_->camera.distance = config.distance;
  gl_->camera.azimuth = config.azimuth;
  gl_->camera.elevation = config.elevation;
}

ArmRenderer::~ArmRenderer() = default;

Image ArmRenderer::Render(const std::vector<double>& q, const std::vector<Eigen::Vector3d>& trail) {
  FLOWPLAN_DEMAND(q.size() == qpos_.size());
  const mjModel& m = *model_;
  mjData& d = *data_;
  mjvScene& scene = gl_->scene;
  OSMesaMakeCurrent(gl_->context, gl_->buffer.data(), GL_UNSIGNED_BYTE, config_.width, config_.height);
  for (size_t j = 0; j < qpos_.size(); ++j) d.qpos[qpos_[j]] = q[j];
  mj_kinematics(&m, &d);
  mjv_updateScene(&m, &d, &gl_->option, nullptr, &gl_->camera, mjCAT_ALL, &scene);
  auto add = [&](int type, const mjtNum size[3], const mjtNum pos[3], const std::array<float, 4>& rgba) {
    if (scene.ngeom >= scene.maxgeom) return;
    const float colour[4] = {rgba[0], rgba[1], rgba[2], rgba[3]};
    mjv_initGeom(&scene.geoms[scene.ngeom], type, size, pos, nullptr, colour);
    scene.geoms[scene.ngeom].category = mjCAT_DECOR;
    ++scene.ngeom;
  };
  const mjtNum floor_size[3] = {2.0, 2.0, 0.05};
  const mjtNum floor_at[3] = {0.3, 0.0, floor_height_};
  add(mjGEOM_PLANE, floor_size, floor_at, {0.42f, 0.43f, 0.45f, 1.0f});
  const mjtNum dot[3] = {0.01, 0.01, 0.01};
  for (const Eigen::Vector3d& p : trail) {
    const mjtNum at[3] = {p.x(), p.y(), p.z()};
    add(mjGEOM_SPHERE, dot, at, {kTrailColour[0], kTrailColour[1], kTrailColour[2], 1.0f});
  }
  // A light from above besides the headlight.
  if (scene.nlight < mjMAXLIGHT) {
    mjvLight& light = scene.lights[scene.nlight++];
    light = mjvLight{};
    light.pos[0] = 0.5f;
    light.pos[2] = 2.5f;
    light.dir[0] = -0.2f;
    light.dir[2] = -1.0f;
    light.directional = 1;
    light.castshadow = 1;
    for (int c = 0; c < 3; ++c) {
      light.diffuse[c] = 0.55f;
      light.specular[c] = 0.2f;
    }
  }
  const mjrRect viewport = {0, 0, config_.width, config_.height};
  mjr_render(viewport, &scene, &gl_->render);
  Image image;
  image.width = config_.width;
  image.height = config_.height;
  std::vector<uint8_t> bottom_up(3 * static_cast<size_t>(config_.width) * config_.height);
  mjr_readPixels(bottom_up.data(), nullptr, viewport, &gl_->render);
  image.rgb.resize(bottom_up.size());
  const size_t row = 3 * static_cast<size_t>(config_.width);
  for (int y = 0; y < config_.height; ++y) {
    std::copy_n(&bottom_up[static_cast<size_t>(config_.height - 1 - y) * row], row, &image.rgb[static_cast<size_t>(y) * row]);
  }
  // Mono rendering looks from between the two eyes of the scene's stereo pair.
  const mjvGLCamera c = mjv_averageCamera(&scene.camera[0], &scene.camera[1]);
  camera_.position = {c.pos[0], c.pos[1], c.pos[2]};
  camera_.forward = {c.forward[0], c.forward[1], c.forward[2]};
  camera_.up = {c.up[0], c.up[1], c.up[2]};
  camera_.frustum_center = c.frustum_center;
  camera_.frustum_bottom = c.frustum_bottom;
  camera_.frustum_top = c.frustum_top;
  camera_.frustum_near = c.frustum_near;
  return image;
}

RenderConfig Framed(RenderConfig config, const geometry::Scene& scene, const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(INFINITY), high = Eigen::Vector3d::Constant(-INFINITY);
  auto add = [&](const Eigen::Vector3d& centre, double reach) {
    low = low.cwiseMin((centre.array() - reach).matrix());
    high = high.cwiseMax((centre.array() + reach).matrix());
  };
  auto at = [](const std::vector<double>& v) { return Eigen::Vector3d(v[0], v[1], v[2]); };
  auto turn = [](const std::vector<double>& q) {
    return q.empty() ? Eigen::Quaterniond::Identity() : Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
  };
  for (const auto& s : scene.spheres) add(at(s.centre), s.radius);
  for (const auto& b : scene.boxes) {  // its eight corners
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d corner(((k & 1) ? 0.5 : -0.5) * b.size[0], ((k & 2) ? 0.5 : -0.5) * b.size[1],
                                   ((k & 4) ? 0.5 : -0.5) * b.size[2]);
      add(at(b.centre) + turn(b.quaternion) * corner, 0.0);
    }
  }
  for (const auto& c : scene.cylinders) {  // the ends of its axis, and its radius around them
    const Eigen::Vector3d axis = turn(c.quaternion) * Eigen::Vector3d(0.0, 0.0, 0.5 * c.height);
    add(at(c.centre) + axis, c.radius);
    add(at(c.centre) - axis, c.radius);
  }
  for (const auto& c : scene.capsules) {
    add(at(c.a), c.radius);
    add(at(c.b), c.radius);
  }
  for (const Eigen::Vector3d& p : points) add(p, 0.0);
  if (!(low.array() <= high.array()).all()) return config;  // nothing to frame
  const Eigen::Vector3d middle = 0.5 * (low + high);
  const double radius = std::max(0.5 * (high - low).norm(), 0.1);
  constexpr double kHalfFieldOfView = 22.5 * M_PI / 180.0;  // MuJoCo's default vertical field of view, halved
  config.lookat = {middle.x(), middle.y(), middle.z()};
  config.distance = radius / std::sin(kHalfFieldOfView);  // the sphere around the box just fits
  const double towards = std::hypot(middle.x(), middle.y()) < 1e-6 ? 0.0 : std::atan2(middle.y(), middle.x());
  config.azimuth = towards * 180.0 / M_PI + 60.0;
  return config;
}

}  // namespace flowplan::render
