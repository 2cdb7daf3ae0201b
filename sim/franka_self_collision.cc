#include "sim/franka_self_collision.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <memory>

#include "core/error.h"

namespace flowplan::sim {
namespace {

int BodyId(const mjModel& m, const char* name) {
  const int id = mj_name2id(&m, mjOBJ_BODY, name);
  FLOWPLAN_DEMAND(id >= 0);
  return id;
}

/// Lowest z (m) of a sphere or capsule geom in its current pose.
double LowestPoint(const mjModel& m, const mjData& d, int g) {
  const double radius = m.geom_size[3 * g];
  const double half_length = m.geom_type[g] == mjGEOM_CAPSULE ? m.geom_size[3 * g + 1] : 0.0;
  const double axis_z = d.geom_xmat[9 * g + 8];  // world z of the geom's local z axis
  return d.geom_xpos[3 * g + 2] - half_length * std::abs(axis_z) - radius;
}

}  // namespace

FrankaCollisionModel::FrankaCollisionModel(double floor_height) : floor_height_(floor_height) {
  model_ = LoadModelFromXml(FrankaModelXml(), "built-in franka_panda.xml");
  mjModel& m = *model_;
  for (int g = 0; g < m.ngeom; ++g) {
    const bool collision = m.geom_group[g] == kCollisionGeomGroup;
    m.geom_contype[g] = collision ? 1 : 0;
    m.geom_conaffinity[g] = collision ? 1 : 0;
    FLOWPLAN_DEMAND(!collision || m.geom_type[g] == mjGEOM_CAPSULE || m.geom_type[g] == mjGEOM_SPHERE);
  }
  m.opt.disableflags &= ~mjDSBL_CONTACT;
  // Room for every capsule pair at once (the model file sizes for no contacts).
  m.nconmax = std::max(m.nconmax, m.ngeom * m.ngeom);
  m.njmax = std::max(m.njmax, 4 * m.nconmax);
}

FrankaCollisionChecker::FrankaCollisionChecker(const FrankaCollisionModel& model)
    : model_(model),
      data_(MakeData(model.mj())),
      link0_(BodyId(model.mj(), "link0")),
      link1_(BodyId(model.mj(), "link1")),
      link5_(BodyId(model.mj(), "link5")),
      link7_(BodyId(model.mj(), "link7")) {}

std::string FrankaCollisionChecker::FirstCollision(const JointVector& q) {
  const mjModel& m = model_.mj();
  mjData& d = *data_;
  for (int j = 0; j < kFrankaJoints; ++j) d.qpos[j] = q[j];
  mj_kinematics(&m, &d);
  mj_collision(&m, &d);
  auto name = [&](int body) { return std::string(mj_id2name(&m, mjOBJ_BODY, body)); };
  auto is_pair = [](int a, int b, int x, int y) { return (a == x && b == y) || (a == y && b == x); };
  for (int c = 0; c < d.ncon; ++c) {
    const mjContact& contact = d.contact[c];
    if (contact.dist > 0.0) continue;
    const int a = m.geom_bodyid[contact.geom1], b = m.geom_bodyid[contact.geom2];
    if (is_pair(a, b, link0_, link1_) || is_pair(a, b, link5_, link7_)) continue;
    return name(std::min(a, b)) + "-" + name(std::max(a, b));
  }
  if (std::isfinite(model_.floor_height())) {
    for (int g = 0; g < m.ngeom; ++g) {
      const int body = m.geom_bodyid[g];
      if (m.geom_group[g] != kCollisionGeomGroup || body == link0_ || body == link1_) continue;
      if (LowestPoint(m, d, g) < model_.floor_height()) return "floor-" + name(body);
    }
  }
  return "";
}

std::function<std::string(const std::vector<double>& q)> FrankaConfigurationCheck(double floor_height) {
  static std::atomic<int64_t> next_id{0};
  const int64_t id = next_id++;
  auto model = std::make_shared<const FrankaCollisionModel>(floor_height);
  return [id, model](const std::vector<double>& q) -> std::string {
    if (q.size() != static_cast<size_t>(kFrankaJoints)) {
      return "expected 7 joint positions, got " + std::to_string(q.size());
    }
    // One checker per thread and model; it keeps the model alive as long as the thread does.
    struct Entry {
      std::shared_ptr<const FrankaCollisionModel> model;
      std::unique_ptr<FrankaCollisionChecker> checker;
    };
    thread_local std::map<int64_t, Entry> checkers;
    Entry& entry = checkers[id];
    if (!entry.checker) {
      entry.model = model;
      entry.checker = std::make_unique<FrankaCollisionChecker>(*model);
    }
    return entry.checker->FirstCollision(Eigen::Map<const JointVector>(q.data()));
  };
}

}  // namespace flowplan::sim
