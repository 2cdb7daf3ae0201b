#include "collision/self_pairs.h"

#include <cmath>
#include <numeric>

#include "collision/body_model.h"
#include "core/error.h"
#include "core/random.h"

namespace flowplan::collision {
namespace {

/// Whether any sphere of link a overlaps any sphere of link b in the placed centres (S, 3).
bool Overlap(const BodyModel& body, const std::vector<double>& centres, int a, int b) {
  for (int sa = body.first_sphere(a); sa < body.first_sphere(a + 1); ++sa) {
    for (int sb = body.first_sphere(b); sb < body.first_sphere(b + 1); ++sb) {
      double d2 = 0.0;
      for (int i = 0; i < 3; ++i) d2 += std::pow(centres[3 * sa + i] - centres[3 * sb + i], 2);
      if (std::sqrt(d2) < body.sphere_radius(sa) + body.sphere_radius(sb)) return true;
    }
  }
  return false;
}

}  // namespace

SelfPairStudy StudySelfPairs(const kinematics::RobotDescription& robot, const SelfPairSettings& settings) {
  if (robot.kind != kinematics::RobotKind::kArm) throw Error("self-collision pairs: robot \"" + robot.name + "\" is not an arm");
  if (settings.samples < 1) throw Error("self-collision pairs: expected at least one sample");
  kinematics::RobotDescription all = robot;
  all.self_collision = true;
  all.self_collision_ignore.clear();
  const BodyModel body(all, "self-collision pairs: robot \"" + robot.name + "\"");
  const int L = body.num_links(), J = body.num_joints();
  // Each link's body: the first link of its welded chain (a link that does not move against its parent joins it).
  std::vector<int> group(static_cast<size_t>(L));
  for (int l = 0; l < L; ++l) {
    const auto& link = all.links[static_cast<size_t>(l)];
    group[l] = (link.parent >= 0 && !link.moves()) ? group[link.parent] : l;
  }
  auto adjacent = [&](int a, int b) {
    const int ga = group[a], gb = group[b];
    if (ga == gb) return true;
    const int pa = all.links[static_cast<size_t>(ga)].parent, pb = all.links[static_cast<size_t>(gb)].parent;
    return (pa >= 0 && group[pa] == gb) || (pb >= 0 && group[pb] == ga);
  };
  std::vector<std::array<int, 2>> pairs;
  for (int a = 0; a < L; ++a) {
    for (int b = a + 1; b < L; ++b) {
      if (body.bound_radius(a) >= 0 && body.bound_radius(b) >= 0) pairs.push_back({a, b});
    }
  }
  std::vector<Frame> frames(static_cast<size_t>(L));
  std::vector<double> centres(static_cast<size_t>(3 * body.num_spheres()));
  std::vector<int64_t> overlapping(pairs.size(), 0);
  std::vector<bool> at_home(pairs.size(), false);
  if (!all.home.empty()) {
    body.Place(all.home.data(), frames.data(), centres.data());
    for (size_t p = 0; p < pairs.size(); ++p) at_home[p] = Overlap(body, centres, pairs[p][0], pairs[p][1]);
  }
  Rng rng(settings.seed);
  std::vector<double> q(static_cast<size_t>(J));
  for (int64_t n = 0; n < settings.samples; ++n) {
    for (int j = 0; j < J; ++j) q[j] = rng.Uniform(all.joint_lower[j], all.joint_upper[j]);
    body.Place(q.data(), frames.data(), centres.data());
    for (size_t p = 0; p < pairs.size(); ++p) overlapping[p] += Overlap(body, centres, pairs[p][0], pairs[p][1]);
  }
  SelfPairStudy study;
  study.samples = settings.samples;
  study.pairs = static_cast<int64_t>(pairs.size());
  for (size_t p = 0; p < pairs.size(); ++p) {
    const auto [a, b] = pairs[p];
    std::string reason;
    if (adjacent(a, b)) {
      reason = "adjacent";
    } else if (at_home[p]) {
      reason = "default";
    } else if (static_cast<double>(overlapping[p]) > settings.always_share * static_cast<double>(settings.samples)) {
      reason = "always";
    } else if (overlapping[p] == 0 && settings.ignore_never) {
      reason = "never";
    }
    if (!reason.empty()) {
      study.ignored.push_back({{all.links[static_cast<size_t>(a)].name, all.links[static_cast<size_t>(b)].name}, reason,
                               overlapping[p]});
    }
  }
  return study;
}

}  // namespace flowplan::collision
