#include "problems/scene_families.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>

#include "core/error.h"
#include "core/parallel.h"
#include "core/random.h"
#include "geometry/scene_rows.h"
#include "robotfiles/robot_folder.h"
#include "robotfiles/robot_model.h"
#include "collision/checker.h"
#include "sim/franka_ik.h"
#include "sim/mujoco_util.h"

namespace flowplan::problems {
namespace {

// Every random draw is a declaration of its own (never two in one call's
// arguments or one sum, whose order C++ leaves to the compiler), so that the
// problems are the same whatever compiler built flowplan.

constexpr int kDraws = 2000;        // scenes drawn per problem before giving up
constexpr int kPoseTries = 20;      // start or goal poses tried per scene
constexpr double kMinTravel = 0.2;  // m between the start and goal TCP

/// A frame standing on the floor in front of the arm: origin `distance` m out
/// along the direction `yaw`, x pointing away from the arm.
struct Frame {
  double yaw = 0.0;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();

  Eigen::Vector3d Point(double x, double y, double z) const {
    return origin + Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(x, y, z);
  }
  Eigen::Vector3d Direction(double x, double y, double z) const {
    return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(x, y, z);
  }
  /// (w, x, y, z) of the frame's yaw, turned further by `extra` about z.
  std::vector<double> Quaternion(double extra = 0.0) const {
    return {std::cos(0.5 * (yaw + extra)), 0.0, 0.0, std::sin(0.5 * (yaw + extra))};
  }
};

std::vector<double> Values(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

/// What a family draws: the scene, and how to draw a start and a goal TCP pose.
struct Layout {
  double yaw = 0.0;  // rad: the direction from the arm to the scene
  geometry::Scene scene;
  std::vector<std::string> box_names, cylinder_names;  // in the scene's numbering of each kind
  std::function<void(Rng&, Eigen::Vector3d&, Eigen::Matrix3d&)> start, goal;
};

void AddBox(Layout& l, const std::string& name, const Frame& f, double x, double y, double z, double lx, double ly,
            double lz, double turn = 0.0) {
  l.scene.boxes.push_back({Values(f.Point(x, y, z)), {lx, ly, lz}, f.Quaternion(turn), NAN});
  l.box_names.push_back(name);
}

void AddCylinder(Layout& l, const std::string& name, const Eigen::Vector3d& centre, double radius, double height,
                 const Eigen::Quaterniond& orientation = Eigen::Quaterniond::Identity()) {
  l.scene.cylinders.push_back(
      {Values(centre), radius, height, {orientation.w(), orientation.x(), orientation.y(), orientation.z()}, NAN});
  l.cylinder_names.push_back(name);
}

/// A cylinder from a to b.
void AddBar(Layout& l, const std::string& name, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius) {
  const Eigen::Quaterniond turn = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), b - a);
  AddCylinder(l, name, 0.5 * (a + b), radius, (b - a).norm(), turn);
}

/// Gripper down, turned by `yaw` about the world z axis.
Eigen::Matrix3d Down(double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * sim::DownwardTcpRotation();
}

/// Gripper horizontal, pointing along `approach` (horizontal), the fingers
/// opening horizontally or vertically.
Eigen::Matrix3d Horizontal(const Eigen::Vector3d& approach, bool fingers_vertical) {
  const Eigen::Vector3d z = approach.normalized();
  const Eigen::Vector3d x = fingers_vertical ? Eigen::Vector3d(0.0, 0.0, -1.0) : Eigen::Vector3d(-z.y(), z.x(), 0.0);
  Eigen::Matrix3d r;
  r.col(0) = x;
  r.col(1) = z.cross(x);
  r.col(2) = z;
  return r;
}

Frame InFront(Rng& rng, double distance) {
  Frame f;
  f.yaw = rng.Uniform(-0.6, 0.6);
  f.origin = Eigen::Vector3d(distance * std::cos(f.yaw), distance * std::sin(f.yaw), 0.0);
  return f;
}

/// Clutter of boxes and cans on a table top at height `top` within |x| < hx, |y| < hy of the frame.
void AddClutter(Layout& l, Rng& rng, const Frame& f, double top, double hx, double hy, int count) {
  for (int k = 0; k < count; ++k) {
    const double x = rng.Uniform(-hx, hx), y = rng.Uniform(-hy, hy);
    const double h = rng.Uniform(0.06, 0.25);
    if (rng.Uniform() < 0.5) {
      const double turn = rng.Uniform(-0.8, 0.8), wy = rng.Uniform(0.04, 0.1), wx = rng.Uniform(0.04, 0.1);
      AddBox(l, "clutter" + std::to_string(k), f, x, y, top + 0.5 * h, wx, wy, h, turn);
    } else {
      AddCylinder(l, "clutter" + std::to_string(k), f.Point(x, y, top + 0.5 * h), rng.Uniform(0.02, 0.05), h);
    }
  }
}

Layout Table(Rng& rng) {
  Layout l;
  const Frame f = InFront(rng, rng.Uniform(0.55, 0.65));
  l.yaw = f.yaw;
  const double top = rng.Uniform(0.0, 0.12), depth = 0.6, width = 1.2;
  AddBox(l, "table", f, 0.0, 0.0, top - 0.02, depth, width, 0.04);
  AddClutter(l, rng, f, top, 0.25, 0.5, 3 + static_cast<int>(rng.Below(5)));
  auto pose = [f, top](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double z = top + r.Uniform(0.06, 0.3), y = r.Uniform(-0.45, 0.45), x = r.Uniform(-0.22, 0.2);
    p = f.Point(x, y, z);
    rot = Down(f.yaw + r.Uniform(-1.2, 1.2));
  };
  l.start = pose;
  l.goal = pose;
  return l;
}

Layout Shelf(Rng& rng) {
  Layout l;
  const double front = rng.Uniform(0.5, 0.65), depth = rng.Uniform(0.3, 0.4), width = rng.Uniform(0.8, 1.0);
  Frame f = InFront(rng, front + 0.5 * depth);  // origin: the bookcase's centre on the floor
  l.yaw = f.yaw;
  const int shelves = 2 + static_cast<int>(rng.Below(3));
  const double bottom = rng.Uniform(0.0, 0.15), gap = rng.Uniform(0.27, 0.35), board = 0.02;
  std::vector<double> levels;
  for (int k = 0; k <= shelves; ++k) levels.push_back(bottom + gap * k);  // board tops, the last one the lid
  const double height = levels.back() + board;
  for (int k = 0; k <= shelves; ++k) {
    AddBox(l, k == shelves ? "lid" : "shelf" + std::to_string(k), f, 0.0, 0.0, levels[k] - 0.5 * board, depth, width,
           board);
  }
  AddBox(l, "side_left", f, 0.0, 0.5 * width + 0.01, 0.5 * height, depth, 0.02, height);
  AddBox(l, "side_right", f, 0.0, -0.5 * width - 0.01, 0.5 * height, depth, 0.02, height);
  AddBox(l, "back", f, 0.5 * depth + 0.01, 0.0, 0.5 * height, 0.02, width + 0.04, height);
  const Eigen::Vector3d inward = f.Direction(1.0, 0.0, 0.0);
  l.goal = [f, levels, depth, width, gap, inward](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const size_t slot = r.Below(levels.size() - 1);
    const double z = levels[slot] + r.Uniform(0.1, gap - 0.1);
    const double y = r.Uniform(-0.5 * width + 0.12, 0.5 * width - 0.12), x = -0.5 * depth + r.Uniform(0.08, 0.2);
    p = f.Point(x, y, z);
    rot = Horizontal(inward, r.Uniform() < 0.5);
  };
  l.start = [f, depth, height, inward](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double z = r.Uniform(0.15, std::min(height, 0.7)), y = r.Uniform(-0.3, 0.3);
    const double x = -0.5 * depth - r.Uniform(0.12, 0.25);
    p = f.Point(x, y, z);
    rot = Horizontal(inward, r.Uniform() < 0.5);
  };
  return l;
}

Layout Box(Rng& rng) {
  Layout l;
  const Frame f = InFront(rng, rng.Uniform(0.45, 0.6));
  l.yaw = f.yaw;
  const double top = rng.Uniform(0.0, 0.1);
  const double lx = rng.Uniform(0.3, 0.42), ly = rng.Uniform(0.3, 0.42), h = rng.Uniform(0.12, 0.22), wall = 0.02;
  AddBox(l, "table", f, 0.0, 0.0, top - 0.02, 0.7, 1.2, 0.04);
  AddBox(l, "box_bottom", f, 0.0, 0.0, top + 0.5 * wall, lx, ly, wall);
  AddBox(l, "box_near", f, -0.5 * lx + 0.5 * wall, 0.0, top + 0.5 * h, wall, ly, h);
  AddBox(l, "box_far", f, 0.5 * lx - 0.5 * wall, 0.0, top + 0.5 * h, wall, ly, h);
  AddBox(l, "box_left", f, 0.0, 0.5 * ly - 0.5 * wall, top + 0.5 * h, lx - 2 * wall, wall, h);
  AddBox(l, "box_right", f, 0.0, -0.5 * ly + 0.5 * wall, top + 0.5 * h, lx - 2 * wall, wall, h);
  l.goal = [f, top, lx, ly, h](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double z = top + r.Uniform(0.06, std::max(0.07, 0.6 * h));
    const double y = r.Uniform(-0.5 * ly + 0.09, 0.5 * ly - 0.09), x = r.Uniform(-0.5 * lx + 0.09, 0.5 * lx - 0.09);
    p = f.Point(x, y, z);
    const double quarter = r.Uniform() < 0.5 ? 0.0 : M_PI_2, wobble = r.Uniform(-0.2, 0.2);
    rot = Down(f.yaw + quarter + wobble);
  };
  l.start = [f, top, lx, ly, h](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double side = r.Uniform() < 0.5 ? -1.0 : 1.0;
    const double z = top + h + r.Uniform(0.1, 0.35), y = side * (0.5 * ly + r.Uniform(0.05, 0.25));
    const double x = r.Uniform(-0.5 * lx, 0.3 * lx);
    p = f.Point(x, y, z);
    rot = Down(f.yaw + r.Uniform(-1.2, 1.2));
  };
  return l;
}

Layout Cage(Rng& rng) {
  Layout l;
  const double size = rng.Uniform(0.35, 0.45), height = rng.Uniform(0.35, 0.5), r = 0.012;
  const Frame f = InFront(rng, rng.Uniform(0.45, 0.55) + 0.5 * size);  // origin: the cage's centre on the floor
  l.yaw = f.yaw;
  const double base = rng.Uniform(0.0, 0.1), s = 0.5 * size;
  AddBox(l, "table", f, 0.0, 0.0, base - 0.02, size + 0.3, size + 0.6, 0.04);
  const double corners[4][2] = {{-s, -s}, {-s, s}, {s, s}, {s, -s}};
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d low = f.Point(corners[k][0], corners[k][1], base);
    const Eigen::Vector3d high = f.Point(corners[k][0], corners[k][1], base + height);
    AddBar(l, "post" + std::to_string(k), low, high, r);
    const Eigen::Vector3d next_low = f.Point(corners[(k + 1) % 4][0], corners[(k + 1) % 4][1], base);
    const Eigen::Vector3d next_high = f.Point(corners[(k + 1) % 4][0], corners[(k + 1) % 4][1], base + height);
    AddBar(l, "top" + std::to_string(k), high, next_high, r);
    AddBar(l, "bottom" + std::to_string(k), low, next_low, r);
  }
  // A bar across each side but the front, and one across the front at a random height.
  const double middle = base + rng.Uniform(0.35, 0.65) * height;
  AddBar(l, "side_bar_left", f.Point(-s, s, middle), f.Point(s, s, middle), r);
  AddBar(l, "side_bar_right", f.Point(-s, -s, middle), f.Point(s, -s, middle), r);
  AddBar(l, "back_bar", f.Point(s, -s, middle), f.Point(s, s, middle), r);
  const double front = base + rng.Uniform(0.3, 0.7) * height;
  AddBar(l, "front_bar", f.Point(-s, -s, front), f.Point(-s, s, front), r);
  const Eigen::Vector3d inward = f.Direction(1.0, 0.0, 0.0);
  l.goal = [f, s, base, height, inward](Rng& g, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double z = base + g.Uniform(0.08, height - 0.06), y = g.Uniform(-s + 0.08, s - 0.08);
    const double x = g.Uniform(-s + 0.1, s - 0.15);
    p = f.Point(x, y, z);
    rot = Horizontal(inward, g.Uniform() < 0.5);
  };
  l.start = [f, s, inward](Rng& g, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double z = g.Uniform(0.15, 0.6), y = g.Uniform(-0.35, 0.35), x = -s - g.Uniform(0.12, 0.25);
    p = f.Point(x, y, z);
    rot = Horizontal(inward, g.Uniform() < 0.5);
  };
  return l;
}

Layout UnderTable(Rng& rng) {
  Layout l;
  const double depth = rng.Uniform(0.45, 0.6), width = rng.Uniform(0.9, 1.2), top = rng.Uniform(0.35, 0.5);
  const Frame f = InFront(rng, rng.Uniform(0.38, 0.48) + 0.5 * depth);  // origin: under the table's centre
  l.yaw = f.yaw;
  AddBox(l, "table_top", f, 0.0, 0.0, top - 0.02, depth, width, 0.04);
  for (int k = 0; k < 4; ++k) {
    const double x = (k < 2 ? -1 : 1) * (0.5 * depth - 0.03), y = (k % 2 ? -1 : 1) * (0.5 * width - 0.03);
    AddBox(l, "leg" + std::to_string(k), f, x, y, 0.5 * (top - 0.04), 0.04, 0.04, top - 0.04);
  }
  const Eigen::Vector3d inward = f.Direction(1.0, 0.0, 0.0);
  l.goal = [f, depth, width, top, inward](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double z = r.Uniform(0.08, top - 0.14), y = r.Uniform(-0.5 * width + 0.15, 0.5 * width - 0.15);
    const double x = -0.5 * depth + r.Uniform(0.05, 0.2);
    p = f.Point(x, y, z);
    rot = Horizontal(inward, false);
  };
  l.start = [f, depth, width, top](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
    const double z = top + r.Uniform(0.1, 0.3), y = r.Uniform(-0.4 * width, 0.4 * width);
    const double x = r.Uniform(-0.5 * depth + 0.05, 0.1);
    p = f.Point(x, y, z);
    rot = Down(f.yaw + r.Uniform(-1.2, 1.2));
  };
  return l;
}

using FamilyFn = Layout (*)(Rng&);

const std::vector<std::pair<std::string, FamilyFn>>& Registry() {
  static const std::vector<std::pair<std::string, FamilyFn>> families = {
      {"table", &Table}, {"shelf", &Shelf}, {"box", &Box}, {"cage", &Cage}, {"under_table", &UnderTable}};
  return families;
}

/// FNV-1a of the name: a family's problems do not move when families are added.
uint64_t NameHash(const std::string& name) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : name) h = (h ^ c) * 1099511628211ull;
  return h;
}

/// Every length of `layout` times `scale`, then the whole layout `shift` m farther from the arm along its direction,
/// then turned by `facing` rad about the world's z axis: the scene's shapes and the TCP poses it draws.
void Place(Layout& layout, double scale, double shift, double facing) {
  if (scale == 1.0 && shift == 0.0 && facing == 0.0) return;
  const Eigen::Vector3d away = shift * Eigen::Vector3d(std::cos(layout.yaw), std::sin(layout.yaw), 0.0);
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(facing, Eigen::Vector3d::UnitZ()));
  auto place = [&](std::vector<double>& centre, std::vector<double>& quaternion) {
    const Eigen::Vector3d c = turn * (scale * Eigen::Vector3d(centre[0], centre[1], centre[2]) + away);
    centre = {c.x(), c.y(), c.z()};
    const Eigen::Quaterniond q = quaternion.empty()
                                     ? turn
                                     : turn * Eigen::Quaterniond(quaternion[0], quaternion[1], quaternion[2],
                                                                 quaternion[3]);
    quaternion = {q.w(), q.x(), q.y(), q.z()};
  };
  for (auto& box : layout.scene.boxes) {
    place(box.centre, box.quaternion);
    for (double& v : box.size) v *= scale;
  }
  for (auto& cylinder : layout.scene.cylinders) {
    place(cylinder.centre, cylinder.quaternion);
    cylinder.radius *= scale;
    cylinder.height *= scale;
  }
  for (auto* draw : {&layout.start, &layout.goal}) {
    *draw = [inner = *draw, scale, away, turn](Rng& r, Eigen::Vector3d& p, Eigen::Matrix3d& rot) {
      inner(r, p, rot);
      p = turn * (scale * p + away);
      rot = turn.toRotationMatrix() * rot;
    };
  }
}

/// Each revolute joint of q (J,) turned by whole turns, within the limits, to the value nearest the home posture:
/// the same posture, on home's side of the joint space. (A joint with limits of ±2π reaches one posture at
/// two values; between them the link sweeps a whole turn, through the floor for a shoulder.)
void NearestTurnToHome(const FamilyArm& arm, const std::vector<bool>& revolute, Eigen::VectorXd& q) {
  const Eigen::VectorXd& reference = arm.home;
  constexpr double kTurn = 2.0 * M_PI;
  const double margin = sim::IkSettings{}.limit_margin;  // as far from the limits as IK keeps
  for (int j = 0; j < q.size(); ++j) {
    if (!revolute[j]) continue;
    const double lower = arm.ik.lower[j] + margin, upper = arm.ik.upper[j] - margin;
    while (q[j] - kTurn >= lower && std::abs(q[j] - kTurn - reference[j]) < std::abs(q[j] - reference[j])) {
      q[j] -= kTurn;
    }
    while (q[j] + kTurn <= upper && std::abs(q[j] + kTurn - reference[j]) < std::abs(q[j] - reference[j])) {
      q[j] += kTurn;
    }
  }
}

/// A configuration (J,) whose TCP is at a pose drawn by `draw`, valid by `checker`, on home's side of every whole
/// turn (NearestTurnToHome), or false.
bool FreePose(const FamilyArm& arm, const std::vector<bool>& revolute, mjData& d, Rng& rng,
              const std::function<void(Rng&, Eigen::Vector3d&, Eigen::Matrix3d&)>& draw,
              const collision::Checker& checker, Eigen::VectorXd& q) {
  const int J = static_cast<int>(arm.home.size());
  for (int t = 0; t < kPoseTries; ++t) {
    Eigen::Vector3d p;
    Eigen::Matrix3d rotation;
    draw(rng, p, rotation);
    // From the home posture, then from a random posture.
    Eigen::VectorXd seed = arm.home;
    if (t % 2 == 1) {
      for (int j = 0; j < J; ++j) seed[j] = rng.Uniform(arm.ik.lower[j], arm.ik.upper[j]);
    }
    sim::ArmIkResult ik = sim::SolveArmIk(arm.ik, d, p, rotation, seed, arm.home);
    if (!ik.converged) continue;
    NearestTurnToHome(arm, revolute, ik.q);
    // Clear of the obstacles by `clearance`, and of itself and the floor, as the plan checker demands of every
    // state of a plan.
    if (!checker.Valid(ik.q.data())) continue;
    q = ik.q;
    return true;
  }
  return false;
}

/// How far the links that never turn (the base, a lift's column: no planned revolute joint between them and the
/// world) reach horizontally from the world's z axis: their spheres' farthest extent at home (a planned slide that
/// moves them sideways is measured where home puts it).
double Footprint(const kinematics::RobotDescription& robot) {
  if (robot.home.size() != static_cast<size_t>(robot.num_joints)) {
    throw Error("scene families: the robot \"" + robot.name + "\" has no home posture");
  }
  std::vector<bool> fixed(robot.links.size(), false);
  for (size_t i = 0; i < robot.links.size(); ++i) {
    const auto& link = robot.links[i];
    const bool turns = link.joint >= 0 && link.type == kinematics::JointType::kRevolute;  // held joints do not
    fixed[i] = !turns && (link.parent < 0 || fixed[static_cast<size_t>(link.parent)]);
  }
  const collision::BodyModel body(robot, "family: robot");
  std::vector<collision::Frame> frames(static_cast<size_t>(body.num_links()));
  std::vector<double> centres(static_cast<size_t>(body.num_spheres()) * 3);
  body.Place(robot.home.data(), frames.data(), centres.data());
  double footprint = 0.0;
  for (int s = 0; s < body.num_spheres(); ++s) {
    if (!fixed[static_cast<size_t>(body.sphere_link(s))]) continue;
    footprint = std::max(footprint, std::hypot(centres[3 * s], centres[3 * s + 1]) + body.sphere_radius(s));
  }
  return footprint;
}

/// The largest horizontal distance of the TCP from the world's z axis over a fixed draw of configurations.
double HorizontalReach(const kinematics::RobotDescription& robot) {
  const collision::BodyModel body(robot, "family: robot");
  Rng rng(0x5eac4u);
  std::vector<double> q(static_cast<size_t>(robot.num_joints)), tcp(static_cast<size_t>(body.workspace_dim()));
  double reach = 0.0;
  for (int i = 0; i < 4096; ++i) {
    for (int j = 0; j < robot.num_joints; ++j) q[j] = rng.Uniform(robot.joint_lower[j], robot.joint_upper[j]);
    body.Tcp(q.data(), tcp.data());
    reach = std::max(reach, std::hypot(tcp[0], tcp[1]));
  }
  return reach;
}

}  // namespace

const std::vector<std::string>& SceneFamilies() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& [name, fn] : Registry()) out.push_back(name);
    return out;
  }();
  return names;
}

FamilyArm FrankaFamilyArm() {
  auto model = std::make_shared<const sim::FrankaModel>(sim::LoadFrankaModel());
  FamilyArm arm;
  arm.robot = model->description();
  arm.ik = sim::FrankaIkModel(*model);
  arm.model = model;
  arm.home = sim::FrankaReadyPose();
  arm.scale = 1.0;
  return arm;
}

FamilyArm FolderFamilyArm(const std::string& dir) {
  const robotfiles::RobotFile file = robotfiles::LoadRobotFile(dir);
  const std::string where = dir + "/robot.yaml";
  FamilyArm arm;
  arm.robot = file.Description(where);
  const int J = arm.robot.num_joints;
  if (arm.robot.kind != kinematics::RobotKind::kArm || arm.robot.workspace_dim != 3) {
    throw Error(where + ": the scene families need an arm in 3-D");
  }
  if (arm.robot.home.size() != static_cast<size_t>(J)) {
    throw Error(where + ": the scene families need a home posture (home:) of " + std::to_string(J) +
                " values to start inverse kinematics from");
  }
  arm.scale = FamilyScale(arm.robot);
  arm.shift = FamilyShift(arm.robot, arm.scale);
  arm.facing = FamilyFacing(arm.robot);
  auto simulation = std::make_shared<const robotfiles::SimulationModel>(
      robotfiles::LoadSimulationModel(file, robotfiles::DriveSettings{}, where));
  arm.ik.model = simulation->model.get();
  arm.ik.qpos = simulation->qpos;
  arm.ik.dof = simulation->dof;
  arm.ik.tcp_site = simulation->tcp_site;
  arm.ik.lower = Eigen::Map<const Eigen::VectorXd>(arm.robot.joint_lower.data(), J);
  arm.ik.upper = Eigen::Map<const Eigen::VectorXd>(arm.robot.joint_upper.data(), J);
  arm.model = simulation;
  arm.home = Eigen::Map<const Eigen::VectorXd>(arm.robot.home.data(), J);
  return arm;
}

double FamilyFacing(const kinematics::RobotDescription& robot) {
  if (robot.home.size() != static_cast<size_t>(robot.num_joints)) {
    throw Error("scene families: the robot \"" + robot.name + "\" has no home posture");
  }
  const collision::BodyModel body(robot, "family: robot");
  double tcp[3];
  body.Tcp(robot.home.data(), tcp);
  return std::hypot(tcp[0], tcp[1]) < 0.01 ? 0.0 : std::atan2(tcp[1], tcp[0]);
}

double FamilyShift(const kinematics::RobotDescription& robot, double scale) {
  static const double franka = [] {
    kinematics::RobotDescription d = sim::LoadFrankaModel().description();
    const sim::JointVector ready = sim::FrankaReadyPose();
    d.home.assign(ready.data(), ready.data() + sim::kFrankaJoints);
    return Footprint(d);
  }();
  return std::max(0.0, Footprint(robot) - scale * franka);
}

double FamilyScale(const kinematics::RobotDescription& robot) {
  if (robot.kind != kinematics::RobotKind::kArm || robot.workspace_dim != 3) {
    throw Error("scene families: the robot \"" + robot.name + "\" is not an arm in 3-D");
  }
  static const double franka = HorizontalReach(sim::LoadFrankaModel().description());
  return HorizontalReach(robot) / franka;
}

Problem MakeFamilyProblem(const FamilyArm& arm, const std::string& family, uint64_t seed, int index,
                          double clearance) {
  FamilyFn make = nullptr;
  std::string known;
  for (const auto& [name, fn] : Registry()) {
    if (name == family) make = fn;
    known += (known.empty() ? "" : ", ") + name;
  }
  if (make == nullptr) throw Error("scene family \"" + family + "\" is not one of " + known);
  Rng rng(StreamSeed(StreamSeed(seed, NameHash(family)), static_cast<uint64_t>(index)));
  const int J = static_cast<int>(arm.home.size());
  if (arm.ik.model == nullptr || arm.robot.num_joints != J || static_cast<int>(arm.ik.qpos.size()) != J) {
    throw Error("family " + family + ": the arm's description, MuJoCo joints and home posture disagree in length");
  }
  std::vector<bool> revolute(static_cast<size_t>(J), true);
  for (const auto& link : arm.robot.links) {
    if (link.joint >= 0 && link.type == kinematics::JointType::kPrismatic) revolute[link.joint] = false;
  }
  auto d = sim::MakeData(*arm.ik.model);
  auto body = std::make_shared<const collision::BodyModel>(arm.robot, "family: robot");
  collision::Floor floor;
  floor.present = true;
  for (int draw = 0; draw < kDraws; ++draw) {
    Layout layout = make(rng);
    Place(layout, arm.scale, arm.shift, arm.facing);
    const geometry::SceneRows rows = geometry::Rows(layout.scene, 3, "family " + family);
    const collision::Checker checker(body, std::make_shared<const collision::World>(rows, 3, floor),
                                     {clearance, 0.001});
    Eigen::VectorXd start, goal;
    // Both on home's side of every whole turn. (Putting the start on the goal's side instead, so that a start and
    // goal of nearby postures are near in joint space, made as many UR5 problems harder for RRT-Connect as it made
    // easier: a joint's short way round can be blocked where its long way is free.)
    if (!FreePose(arm, revolute, *d, rng, layout.goal, checker, goal)) continue;
    if (!FreePose(arm, revolute, *d, rng, layout.start, checker, start)) continue;
    Problem p;
    p.name = family + "/" + std::to_string(index);
    p.start_q.assign(start.data(), start.data() + J);
    p.goal_q.assign(goal.data(), goal.data() + J);
    p.obstacle_names = layout.box_names;  // the scene's numbering: (spheres,) boxes, cylinders
    p.obstacle_names.insert(p.obstacle_names.end(), layout.cylinder_names.begin(), layout.cylinder_names.end());
    p.scene = std::move(layout.scene);
    p.floor_height = 0.0;  // the arm and the scene stand on the floor
    DescribeEnds(*body, p);
    double travel = 0.0;
    for (size_t k = 0; k < p.start_tcp.size(); ++k) travel += std::pow(p.goal_tcp[k] - p.start_tcp[k], 2);
    if (std::sqrt(travel) < kMinTravel * arm.scale) continue;
    return p;
  }
  throw Error("family " + family + ": no valid problem " + std::to_string(index) + " in " + std::to_string(kDraws) +
              " draws (clearance " + config::internal::FormatDouble(clearance) + " m too large?)");
}

ProblemSet MakeFamilyProblems(const FamilyArm& arm, const std::string& family, uint64_t seed, int count,
                              double clearance, int threads) {
  ProblemSet set;
  set.source = "family " + family;
  set.seed = static_cast<int64_t>(seed);
  set.problems.resize(static_cast<size_t>(count));
  ParallelFor(count, threads, [&](int, int i) {
    set.problems[static_cast<size_t>(i)] = MakeFamilyProblem(arm, family, seed, i, clearance);
  });
  return set;
}

}  // namespace flowplan::problems
