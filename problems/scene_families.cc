#include "problems/scene_families.h"

#include <Eigen/Geometry>
#include <cmath>
#include <functional>

#include "core/error.h"
#include "core/parallel.h"
#include "core/random.h"
#include "geometry/scene_rows.h"
#include "sim/franka_ik.h"
#include "collision/checker.h"
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

/// A collision-free configuration whose TCP is at a pose drawn by `draw`, or false.
bool FreePose(const kinematics::Robot& arm, const sim::FrankaModel& model, mjData& d, Rng& rng,
              const std::function<void(Rng&, Eigen::Vector3d&, Eigen::Matrix3d&)>& draw,
              const geometry::SceneRows& rows, double clearance, sim::JointVector& q) {
  const sim::FrankaLimits& limits = model.limits();
  for (int t = 0; t < kPoseTries; ++t) {
    Eigen::Vector3d p;
    sim::IkOptions options;
    draw(rng, p, options.tcp_rotation);
    // From the ready pose, then from a random posture.
    sim::JointVector seed = sim::FrankaReadyPose();
    if (t % 2 == 1) {
      for (int j = 0; j < sim::kFrankaJoints; ++j) seed[j] = rng.Uniform(limits.q_lower[j], limits.q_upper[j]);
    }
    const sim::IkResult ik = sim::SolveTcpIk(model, d, p, seed, options);
    if (!ik.converged) continue;
    // Clear of the obstacles by `clearance`, and of itself and the floor, as the plan checker demands of every
    // state of a plan.
    const collision::BodyModel body(arm.description(), "family: robot");
    collision::Floor floor;
    floor.present = true;
    const collision::Checker checker(std::shared_ptr<const collision::BodyModel>(std::shared_ptr<const collision::BodyModel>(), &body),
                                     std::make_shared<const collision::World>(rows, 3, floor), {clearance, 0.001});
    if (!checker.Valid(ik.q.data())) continue;
    q = ik.q;
    return true;
  }
  return false;
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

Problem MakeFamilyProblem(const kinematics::Robot& arm, const sim::FrankaModel& model, const std::string& family,
                          uint64_t seed, int index, double clearance) {
  FamilyFn make = nullptr;
  std::string known;
  for (const auto& [name, fn] : Registry()) {
    if (name == family) make = fn;
    known += (known.empty() ? "" : ", ") + name;
  }
  if (make == nullptr) throw Error("scene family \"" + family + "\" is not one of " + known);
  Rng rng(StreamSeed(StreamSeed(seed, NameHash(family)), static_cast<uint64_t>(index)));
  auto d = sim::MakeData(model.mj());
  for (int draw = 0; draw < kDraws; ++draw) {
    Layout layout = make(rng);
    const geometry::SceneRows rows = geometry::Rows(layout.scene, 3, "family " + family);
    sim::JointVector start, goal;
    if (!FreePose(arm, model, *d, rng, layout.goal, rows, clearance, goal)) continue;
    if (!FreePose(arm, model, *d, rng, layout.start, rows, clearance, start)) continue;
    Problem p;
    p.name = family + "/" + std::to_string(index);
    p.start_q.assign(start.data(), start.data() + sim::kFrankaJoints);
    p.goal_q.assign(goal.data(), goal.data() + sim::kFrankaJoints);
    p.obstacle_names = layout.box_names;  // the scene's numbering: (spheres,) boxes, cylinders
    p.obstacle_names.insert(p.obstacle_names.end(), layout.cylinder_names.begin(), layout.cylinder_names.end());
    p.scene = std::move(layout.scene);
    p.floor_height = 0.0;  // the arm and the scene stand on the floor
    DescribeEnds(collision::BodyModel(arm.description(), "family: robot"), p);
    double travel = 0.0;
    for (size_t k = 0; k < p.start_tcp.size(); ++k) travel += std::pow(p.goal_tcp[k] - p.start_tcp[k], 2);
    if (std::sqrt(travel) < kMinTravel) continue;
    return p;
  }
  throw Error("family " + family + ": no valid problem " + std::to_string(index) + " in " + std::to_string(kDraws) +
              " draws (clearance " + config::internal::FormatDouble(clearance) + " m too large?)");
}

ProblemSet MakeFamilyProblems(const kinematics::Robot& arm, const std::string& family, uint64_t seed, int count,
                              double clearance, int threads) {
  const sim::FrankaModel model = sim::LoadFrankaModel();
  ProblemSet set;
  set.source = "family " + family;
  set.seed = static_cast<int64_t>(seed);
  set.problems.resize(static_cast<size_t>(count));
  ParallelFor(count, threads, [&](int, int i) {
    set.problems[static_cast<size_t>(i)] = MakeFamilyProblem(arm, model, family, seed, i, clearance);
  });
  return set;
}

}  // namespace flowplan::problems
