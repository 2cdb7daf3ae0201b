// The offscreen renderer: an obstacle's and the arm's pixels where a pinhole
// projection written here puts them, and the PNG and GIF files decoded by
// Pillow (an independent reader) to the pixels that were written.

#include "render/arm_renderer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <sstream>

#include "collision/body_model.h"
#include "core/error.h"
#include "render/image_files.h"
#include "robotfiles/robot_folder.h"
#include "sim/mujoco_util.h"
#include "tests/support/command.h"
#include "tests/support/scratch_dir.h"

namespace flowplan::render {
namespace {

/// The pixel (column, row from the top) of world point p, by OpenGL's perspective projection of `view`.
Eigen::Vector2d Project(const CameraView& view, const Eigen::Vector3d& p, int width, int height) {
  const Eigen::Vector3d right = view.forward.cross(view.up).normalized();
  const Eigen::Vector3d d = p - view.position;
  const double z = d.dot(view.forward), x = d.dot(right), y = d.dot(view.up);
  const double half_height = 0.5 * (view.frustum_top - view.frustum_bottom);
  const double half_width = half_height * width / height;
  const double u = (view.frustum_near * x / z - (view.frustum_center - half_width)) / (2 * half_width);
  const double v = (view.frustum_near * y / z - view.frustum_bottom) / (2 * half_height);
  return {u * width, (1.0 - v) * height};
}

geometry::Scene OneSphere(const Eigen::Vector3d& centre, double radius) {
  geometry::Scene scene;
  scene.spheres.push_back({{centre.x(), centre.y(), centre.z()}, radius});
  return scene;
}

TEST(ImageFilesTest, TileLaysImagesOutInRowsAndFillsTheLastRowWithWhite) {
  auto solid = [](uint8_t value) {
    Image image;
    image.width = 2;
    image.height = 1;
    image.rgb.assign(6, value);
    image.rgb[3] = static_cast<uint8_t>(value + 1);  // pixel (1, 0) differs, so a swapped column shows
    return image;
  };
  const Image tiled = Tile({solid(10), solid(20), solid(30)}, 2);
  ASSERT_EQ(tiled.width, 4);
  ASSERT_EQ(tiled.height, 2);
  EXPECT_EQ(tiled.At(0, 0)[0], 10);
  EXPECT_EQ(tiled.At(1, 0)[0], 11);
  EXPECT_EQ(tiled.At(2, 0)[0], 20);
  EXPECT_EQ(tiled.At(3, 0)[0], 21);
  EXPECT_EQ(tiled.At(0, 1)[0], 30);
  EXPECT_EQ(tiled.At(1, 1)[2], 30);
  EXPECT_EQ(tiled.At(2, 1)[1], 255);  // no fourth image: white
  EXPECT_EQ(tiled.At(3, 1)[2], 255);
}

TEST(ArmRendererTest, TheObstacleAndTheArmAreWhereAProjectionPutsThem) {
  const Eigen::Vector3d sphere(0.45, 0.45, 0.3);
  RenderConfig config;
  config.width = 320;
  config.height = 240;
  ArmRenderer renderer(OneSphere(sphere, 0.08), config);
  const sim::JointVector ready = sim::FrankaReadyPose();
  const Image image = renderer.Render(std::vector<double>(ready.data(), ready.data() + 7));
  ASSERT_EQ(image.width, 320);
  ASSERT_EQ(image.rgb.size(), 320u * 240u * 3u);
  auto pixel = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector2d at = Project(renderer.camera(), p, config.width, config.height);
    EXPECT_TRUE(at.x() >= 2 && at.x() < config.width - 2 && at.y() >= 2 && at.y() < config.height - 2) << at.transpose();
    return image.At(static_cast<int>(at.x()), static_cast<int>(at.y()));
  };
  // The sphere's centre: red.
  const uint8_t* red = pixel(sphere);
  EXPECT_GT(red[0], red[1] + 60);
  EXPECT_GT(red[0], red[2] + 60);
  // A point inside the forearm's capsule, from MuJoCo's kinematics: the arm's blue-grey.
  const sim::FrankaModel model = sim::LoadFrankaModel();
  sim::MjDataPtr d = sim::MakeData(model.mj());
  for (int j = 0; j < 7; ++j) d->qpos[j] = ready[j];
  mj_kinematics(&model.mj(), d.get());
  const int geom = mj_name2id(&model.mj(), mjOBJ_GEOM, "link5_c0");
  ASSERT_GE(geom, 0);
  const Eigen::Vector3d forearm(d->geom_xpos[3 * geom], d->geom_xpos[3 * geom + 1], d->geom_xpos[3 * geom + 2]);
  const uint8_t* arm = pixel(forearm);
  EXPECT_GT(arm[2], arm[0] + 8) << int(arm[0]) << " " << int(arm[1]) << " " << int(arm[2]);
  EXPECT_GT(arm[2], 60);
  // The same pixels differ once the sphere moves away: what was drawn there was the sphere.
  ArmRenderer elsewhere(OneSphere({0.45, -0.45, 0.3}, 0.08), config);
  const Image moved = elsewhere.Render(std::vector<double>(ready.data(), ready.data() + 7));
  const Eigen::Vector2d at = Project(renderer.camera(), sphere, config.width, config.height);
  const uint8_t* now = moved.At(static_cast<int>(at.x()), static_cast<int>(at.y()));
  EXPECT_LT(now[0], red[0] - 40);
  // A trail of points is drawn in its colour.
  const Eigen::Vector3d mark(0.3, -0.35, 0.4);
  const Image trail = renderer.Render(std::vector<double>(ready.data(), ready.data() + 7), {mark});
  const Eigen::Vector2d m = Project(renderer.camera(), mark, config.width, config.height);
  int greens = 0;  // the dot is a few pixels wide: look around its centre
  for (int dx = -1; dx <= 1; ++dx) {
    for (int dy = -1; dy <= 1; ++dy) {
      const uint8_t* p = trail.At(static_cast<int>(m.x()) + dx, static_cast<int>(m.y()) + dy);
      greens += p[1] > p[0] + 30 && p[1] > p[2] + 30;
    }
  }
  EXPECT_GE(greens, 3);
  const uint8_t* before = image.At(static_cast<int>(m.x()), static_cast<int>(m.y()));
  EXPECT_FALSE(before[1] > before[0] + 30 && before[1] > before[2] + 30);  // not green without the trail
}

TEST(ArmRendererTest, AFramedCameraShowsEveryObstacleCornerAndPointAndFillsThePicture) {
  // A turned bookcase-sized box and a cylinder off to the side of the arm, and points of a TCP path.
  geometry::Scene scene;
  const double s = std::sqrt(0.5);
  scene.boxes.push_back({{-0.6, 0.9, 0.6}, {0.35, 0.9, 1.2}, {std::cos(0.3), 0.0, 0.0, std::sin(0.3)}, NAN});
  scene.cylinders.push_back({{-0.2, 0.5, 0.2}, 0.05, 0.4, {s, s, 0.0, 0.0}, NAN});
  const std::vector<Eigen::Vector3d> points = {{0.0, 0.0, 0.0}, {-0.3, 0.4, 0.5}, {0.1, 0.2, 0.9}};
  RenderConfig config;
  config.width = 320;
  config.height = 240;
  const RenderConfig framed = Framed(config, scene, points);
  // It looks from 60° to the left of the direction towards the middle of what it shows.
  const Eigen::Vector3d middle(framed.lookat[0], framed.lookat[1], framed.lookat[2]);
  EXPECT_NEAR(framed.azimuth, std::atan2(middle.y(), middle.x()) * 180.0 / M_PI + 60.0, 1e-9);
  EXPECT_EQ(framed.elevation, config.elevation);
  ArmRenderer renderer(scene, framed);
  const sim::JointVector ready = sim::FrankaReadyPose();
  renderer.Render(std::vector<double>(ready.data(), ready.data() + 7));  // places the camera
  std::vector<Eigen::Vector3d> shown = points;
  const geometry::BoxObstacle& box = scene.boxes[0];
  const Eigen::Quaterniond turn(box.quaternion[0], box.quaternion[1], box.quaternion[2], box.quaternion[3]);
  for (int k = 0; k < 8; ++k) {
    shown.push_back(Eigen::Vector3d(box.centre.data()) +
                    turn * Eigen::Vector3d(((k & 1) ? 0.5 : -0.5) * box.size[0], ((k & 2) ? 0.5 : -0.5) * box.size[1],
                                           ((k & 4) ? 0.5 : -0.5) * box.size[2]));
  }
  double left = INFINITY, right = -INFINITY, top = INFINITY, bottom = -INFINITY;
  for (const Eigen::Vector3d& p : shown) {
    const Eigen::Vector2d at = Project(renderer.camera(), p, framed.width, framed.height);
    EXPECT_TRUE(at.x() >= 0 && at.x() < framed.width && at.y() >= 0 && at.y() < framed.height) << p.transpose();
    left = std::min(left, at.x());
    right = std::max(right, at.x());
    top = std::min(top, at.y());
    bottom = std::max(bottom, at.y());
  }
  // Not lost in the middle of the picture: what it frames spans at least half its width or height.
  EXPECT_TRUE(right - left > 0.5 * framed.width || bottom - top > 0.5 * framed.height)
      << left << " " << right << " " << top << " " << bottom;
  // Nothing to frame: the camera as given.
  const RenderConfig unchanged = Framed(config, geometry::Scene{}, {});
  EXPECT_EQ(unchanged.lookat, config.lookat);
  EXPECT_EQ(unchanged.distance, config.distance);
}

TEST(ArmRendererTest, AnyArmIsDrawnByItsCollisionSpheresWhereItsKinematicsPutThem) {
  // The shipped UR5 folder; its spheres placed by the collision check's kinematics (plain C++), drawn by MuJoCo
  // from the model ArmXml writes.
  const kinematics::RobotDescription ur5 = robotfiles::LoadRobot(std::string(FLOWPLAN_SOURCE_DIR) + "/robots/ur5");
  RenderConfig config;
  config.width = 320;
  config.height = 240;
  ArmRenderer renderer(ur5, OneSphere({0.45, -0.45, 0.3}, 0.08), config);
  ASSERT_EQ(renderer.num_joints(), 6);
  const std::vector<double> reaching = {M_PI, -0.6, 0.9, 0.0, 0.0, 0.0}, folded = {0.0, -2.5, 2.0, 0.0, 0.0, 0.0};
  const collision::BodyModel body(ur5);
  std::vector<collision::Frame> frames(static_cast<size_t>(body.num_links()));
  std::vector<double> centres(static_cast<size_t>(3 * body.num_spheres()));
  body.Place(reaching.data(), frames.data(), centres.data());
  // The biggest sphere on the forearm.
  int chosen = -1;
  for (int s = 0; s < body.num_spheres(); ++s) {
    if (body.link_name(body.sphere_link(s)) != "forearm_link") continue;
    if (chosen < 0 || body.sphere_radius(s) > body.sphere_radius(chosen)) chosen = s;
  }
  ASSERT_GE(chosen, 0);
  const Eigen::Vector3d forearm(centres[3 * chosen], centres[3 * chosen + 1], centres[3 * chosen + 2]);
  const Image image = renderer.Render(reaching);
  const Eigen::Vector2d at = Project(renderer.camera(), forearm, config.width, config.height);
  ASSERT_TRUE(at.x() >= 0 && at.x() < config.width && at.y() >= 0 && at.y() < config.height) << at.transpose();
  const uint8_t* arm = image.At(static_cast<int>(at.x()), static_cast<int>(at.y()));
  EXPECT_GT(arm[2], arm[0] + 8) << int(arm[0]) << " " << int(arm[1]) << " " << int(arm[2]);
  EXPECT_GT(arm[2], 60);
  // Folded away, the forearm is not drawn there.
  const Image away = renderer.Render(folded);
  const uint8_t* now = away.At(static_cast<int>(at.x()), static_cast<int>(at.y()));
  EXPECT_FALSE(now[2] > now[0] + 8 && now[2] > 60) << int(now[0]) << " " << int(now[1]) << " " << int(now[2]);
  // A point robot is refused with one line.
  kinematics::RobotDescription point;
  point.name = "disc";
  point.kind = kinematics::RobotKind::kPoint;
  EXPECT_THAT([&] { ArmRenderer(point, OneSphere({0.45, -0.45, 0.3}, 0.08), config); },
              ::testing::ThrowsMessage<Error>(::testing::HasSubstr("render: draws arms")));
}

TEST(ImageFilesTest, PillowReadsBackThePngExactlyAndTheGifWithinItsPalette) {
  RenderConfig config;
  config.width = 160;
  config.height = 120;
  ArmRenderer renderer(OneSphere({0.45, 0.45, 0.3}, 0.08), config);
  std::vector<Image> frames;
  sim::JointVector q = sim::FrankaReadyPose();
  for (int k = 0; k < 3; ++k) {
    q[0] += 0.3;
    frames.push_back(renderer.Render(std::vector<double>(q.data(), q.data() + 7)));
  }
  const std::string dir = flowplan::testing::ScratchDir().string();
  WritePng(dir + "/still.png", frames[0]);
  WriteGif(dir + "/clip.gif", frames, 1.0 / 15.0);
  // Pillow prints the frame count, the duration, and the RGB of three pixels of each frame.
  const std::string script =
      "import sys\nfrom PIL import Image, ImageSequence\n"
      "png = Image.open(sys.argv[1]).convert('RGB')\n"
      "print(png.size[0], png.size[1], *png.getpixel((80, 60)), *png.getpixel((10, 10)))\n"
      "gif = Image.open(sys.argv[2])\n"
      "print(gif.n_frames, gif.info.get('duration'), gif.info.get('loop'))\n"
      "for frame in ImageSequence.Iterator(gif):\n"
      "    f = frame.convert('RGB')\n"
      "    print(*f.getpixel((80, 60)), *f.getpixel((10, 10)), *f.getpixel((120, 90)))\n";
  std::ofstream(dir + "/read.py") << script;
  const flowplan::testing::Outcome out =
      flowplan::testing::RunCommand(std::string(FLOWPLAN_PYTHON) + " " + dir + "/read.py " + dir + "/still.png " + dir +
                                    "/clip.gif");
  ASSERT_EQ(out.exit_code, 0) << out.output;
  std::istringstream lines(out.output);
  int w, h;
  lines >> w >> h;
  EXPECT_EQ(w, 160);
  EXPECT_EQ(h, 120);
  for (const auto& [x, y] : {std::pair{80, 60}, std::pair{10, 10}}) {
    for (int c = 0; c < 3; ++c) {
      int v;
      lines >> v;
      EXPECT_EQ(v, frames[0].At(x, y)[c]) << "png pixel " << x << "," << y;
    }
  }
  int n, duration, loop;
  lines >> n >> duration >> loop;
  EXPECT_EQ(n, 3);
  EXPECT_EQ(duration, 70);  // 1/15 s in GIF's hundredths
  EXPECT_EQ(loop, 0);       // forever
  for (int k = 0; k < 3; ++k) {
    for (const auto& [x, y] : {std::pair{80, 60}, std::pair{10, 10}, std::pair{120, 90}}) {
      for (int c = 0; c < 3; ++c) {
        int v;
        lines >> v;
        EXPECT_NEAR(v, frames[static_cast<size_t>(k)].At(x, y)[c], 12) << "gif frame " << k << " pixel " << x << "," << y;
      }
    }
  }
}

}  // namespace
}  // namespace flowplan::render
