#include "robotfiles/collision_fit.h"

#include <tinyxml.h>

#include <algorithm>
#include <cctype>
#include <cmath>

#include "collision/self_pairs.h"
#include "core/error.h"
#include "core/random.h"
#include "jit/library.h"
#include "kinematics/robot.h"

namespace flowplan::robotfiles {
namespace {

/// The SRDF's disable_collisions pairs between links of the robot.
std::vector<kinematics::IgnoredLinkPair> ReadSrdf(const std::string& path, const kinematics::RobotDescription& robot,
                                                  std::vector<std::string>& notes) {
  TiXmlDocument doc;
  if (!doc.LoadFile(path)) {
    throw Error(path + ":" + std::to_string(doc.ErrorRow()) + ": not a readable SRDF: " + doc.ErrorDesc());
  }
  const TiXmlElement* root = doc.RootElement();
  if (root == nullptr || std::string(root->Value()) != "robot") throw Error(path + ": expected a <robot> element at the root");
  std::vector<kinematics::IgnoredLinkPair> pairs;
  int skipped = 0;
  for (const TiXmlElement* e = root->FirstChildElement("disable_collisions"); e != nullptr;
       e = e->NextSiblingElement("disable_collisions")) {
    const char* a = e->Attribute("link1");
    const char* b = e->Attribute("link2");
    if (a == nullptr || b == nullptr) {
      throw Error(path + ":" + std::to_string(e->Row()) + ": disable_collisions: expected link1 and link2");
    }
    if (robot.FindLink(a) < 0 || robot.FindLink(b) < 0) {
      ++skipped;
      continue;
    }
    const char* reason = e->Attribute("reason");
    pairs.push_back({{a, b}, std::string("srdf: ") + (reason != nullptr ? reason : "")});
  }
  notes.push_back(path + ": " + std::to_string(pairs.size()) + " disable_collisions pairs between the robot's links" +
                  (skipped > 0 ? ", " + std::to_string(skipped) + " naming links outside it skipped" : ""));
  return pairs;
}

}  // namespace

std::string SafeFileName(const std::string& name) {
  std::string out;
  for (const char c : name) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return out.empty() ? "link" : out;
}

void FitCollisionBody(const std::vector<LinkGeometry>& gathered, const ImportOptions& options, const std::string& where,
                      ImportResult& result) {
  spheres::CoverSettings cover;
  cover.overshoot = options.overshoot;
  cover.max_spheres = options.max_spheres;
  cover.spacing = options.surface_spacing;
  cover.seed = options.seed;
  // The cover is checked on surface samples 2 mm apart (half the surface spacing when that is coarser).
  const double kCheckSpacing = std::max(0.002, 0.5 * options.surface_spacing);
  for (const auto& [name, pieces, exact] : gathered) {
    std::vector<spheres::Sphere> fitted = exact;
    if (!pieces.empty()) {
      const spheres::Mesh merged = spheres::Merged(pieces);
      const std::vector<spheres::Sphere> covering = spheres::Cover(merged, cover);
      fitted.insert(fitted.end(), covering.begin(), covering.end());
      const spheres::CoverReport report = spheres::CheckCover(merged, covering, kCheckSpacing, StreamSeed(options.seed, 1));
      result.file.cover.push_back({name, static_cast<int>(fitted.size()), report.samples, report.largest_uncovered,
                                   report.largest_outside, report.overshoot_ratio});
    } else {
      result.file.cover.push_back({name, static_cast<int>(fitted.size()), 0, 0.0, 0.0, 0.0});
    }
    for (const spheres::Sphere& s : fitted) result.file.collision.spheres.push_back({name, s.centre, s.radius});
  }
  if (result.file.collision.spheres.empty()) {
    throw Error(where + ": no link below the base has collision geometry; nothing to check plans with");
  }

  // Self-collision pairs and the links standing on the floor.
  kinematics::RobotDescription with_spheres = result.file.robot;
  kinematics::ApplyCollisionBody(result.file.collision, with_spheres, where);
  if (!options.srdf.empty()) {
    result.file.collision.self_collision_ignore = ReadSrdf(options.srdf, with_spheres, result.notes);
  } else {
    collision::SelfPairSettings pair_settings;
    pair_settings.samples = options.pair_samples;
    pair_settings.seed = options.seed;
    const collision::SelfPairStudy study = collision::StudySelfPairs(with_spheres, pair_settings);
    for (const auto& pair : study.ignored) {
      result.file.collision.self_collision_ignore.push_back(
          {pair.links, pair.reason + " (" + std::to_string(pair.overlapping) + " of " + std::to_string(study.samples) +
                           " random configurations overlap)"});
    }
    result.notes.push_back(std::to_string(study.ignored.size()) + " of " + std::to_string(study.pairs) +
                           " link pairs not checked for self-collision (adjacent, touching at home, or at more than 95 % of " +
                           std::to_string(study.samples) + " random configurations)");
  }
  result.file.collision.self_collision = true;
  {
    // A link stands on the floor when its height never changes (every joint between it and the base is fixed,
    // held, or turns about the vertical) and a sphere of it reaches below z = 0 at home.
    const kinematics::Robot robot(with_spheres);
    const torch::Tensor home = torch::tensor(with_spheres.home, torch::kFloat64).unsqueeze(0);
    const torch::Tensor centres = robot.SphereCentres(home)[0];  // (S, 3)
    const auto frames = jit::Call(robot.module(), "link_frames", {home}).toTensorVector();  // (1, 4, 4) per link
    const size_t L = with_spheres.links.size();
    std::vector<bool> level(L, false), below(L, false);
    for (size_t l = 0; l < L; ++l) {
      const kinematics::RobotLink& link = with_spheres.links[l];
      const bool parent_level = link.parent < 0 || level[static_cast<size_t>(link.parent)];
      bool vertical = false;
      if (link.joint >= 0 && link.type == kinematics::JointType::kRevolute) {
        const torch::Tensor axis = frames[l][0].slice(0, 0, 3).slice(1, 0, 3).matmul(
            torch::tensor({link.axis[0], link.axis[1], link.axis[2]}, torch::kFloat64));
        vertical = std::abs(axis[2].item<double>()) > (1.0 - 1e-9) * axis.norm().item<double>();
      }
      level[l] = parent_level && (link.joint < 0 || vertical);
    }
    for (int s = 0; s < with_spheres.num_spheres(); ++s) {
      const double bottom = centres[s][2].item<double>() - with_spheres.spheres[s].radius;
      if (bottom < 0.0) below[static_cast<size_t>(with_spheres.spheres[s].link)] = true;
    }
    for (size_t l = 0; l < L; ++l) {
      if (level[l] && below[l]) result.file.collision.floor_exempt.push_back(with_spheres.links[l].name);
    }
  }
}

}  // namespace flowplan::robotfiles
