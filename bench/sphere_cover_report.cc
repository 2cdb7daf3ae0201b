// How well a robot's collision spheres cover its links' collision meshes:
// per link, the largest distance of a mesh surface point outside every sphere
// (0: covered) and the volume the spheres add outside the mesh, and the same
// for covers the sphere generator (spheres/cover.h) fits to the meshes at
// several overshoot settings.
//
//   sphere_cover_report MESH_DIR [--overshoot 0.01,0.015,0.02] [--max-spheres 64] [--out spheres.yaml]
//                       [--spheres FILE]
//
// MESH_DIR holds the built-in Franka's collision meshes by link (link0.obj ..
// link7.obj, hand.obj, finger.obj), each in its link's frame. With --out, the
// cover fitted at the first overshoot is written as the `spheres` list of a
// robot description (link indices of the built-in Franka). With --spheres, the
// spheres to report on are read from FILE (lines "link x y z radius", link
// indices and frames of the built-in Franka) instead of the built-in ones.
// --max-spheres caps each link's fitted cover (CoverSettings::max_spheres):
// a link that needs more for the overshoot asked for gets a larger one.

#include <spdlog/fmt/fmt.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "collision/self_pairs.h"
#include "core/error.h"
#include "sim/franka_model.h"
#include "spheres/cover.h"

namespace {

using namespace flowplan;

std::vector<double> Numbers(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) out.push_back(std::stod(item));
  return out;
}

int Main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::cout << "sphere_cover_report MESH_DIR [--overshoot a,b,c] [--max-spheres N] [--out spheres.yaml] "
                 "[--spheres FILE]\n";
    return argc < 2 ? 1 : 0;
  }
  const std::string dir = argv[1];
  std::vector<double> overshoots = {0.01, 0.015, 0.02};
  std::string out_path, spheres_path;
  int max_spheres = 64;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--overshoot") overshoots = Numbers(argv[i + 1]);
    else if (flag == "--out") out_path = argv[i + 1];
    else if (flag == "--spheres") spheres_path = argv[i + 1];
    else if (flag == "--max-spheres") max_spheres = std::stoi(argv[i + 1]);
    else throw Error("unknown option " + flag);
  }
  kinematics::RobotDescription robot = sim::LoadFrankaModel().description();
  if (!spheres_path.empty()) {
    std::ifstream in(spheres_path);
    if (!in) throw Error(spheres_path + ": no such file");
    robot.spheres.clear();
    kinematics::RobotSphere s;
    while (in >> s.link >> s.centre[0] >> s.centre[1] >> s.centre[2] >> s.radius) robot.spheres.push_back(s);
  }
  const std::map<std::string, std::string> meshes = {
      {"link0", "link0.obj"}, {"link1", "link1.obj"}, {"link2", "link2.obj"}, {"link3", "link3.obj"},
      {"link4", "link4.obj"}, {"link5", "link5.obj"}, {"link6", "link6.obj"}, {"link7", "link7.obj"},
      {"hand", "hand.obj"},   {"left_finger", "finger.obj"}, {"right_finger", "finger.obj"}};
  constexpr double kSpacing = 0.002;
  std::printf("%-13s %7s | %-28s", "link", "volume", "built-in spheres: n, gap, outside");
  for (double o : overshoots) std::printf(" | fitted %.3f: n, gap, outside", o);
  std::printf("\n");
  std::vector<kinematics::RobotSphere> fitted;
  int total_builtin = 0;
  std::vector<int> total_fitted(overshoots.size(), 0);
  for (size_t l = 0; l < robot.links.size(); ++l) {
    const std::string& name = robot.links[l].name;
    const auto found = meshes.find(name);
    if (found == meshes.end()) continue;
    const spheres::Mesh mesh = spheres::LoadMesh((std::filesystem::path(dir) / found->second).string());
    std::vector<spheres::Sphere> builtin;
    for (const auto& s : robot.spheres) {
      if (s.link == static_cast<int>(l)) builtin.push_back({s.centre, s.radius});
    }
    total_builtin += static_cast<int>(builtin.size());
    const spheres::CoverReport report = spheres::CheckCover(mesh, builtin, kSpacing, 7);
    std::printf("%-13s %6.0fcc | %3d, %6.1f mm, %5.0f %%      ", name.c_str(), report.mesh_volume * 1e6, report.spheres,
                report.largest_uncovered * 1e3, report.overshoot_ratio * 100);
    for (size_t o = 0; o < overshoots.size(); ++o) {
      spheres::CoverSettings settings;
      settings.overshoot = overshoots[o];
      settings.max_spheres = max_spheres;
      const std::vector<spheres::Sphere> cover = spheres::Cover(mesh, settings);
      const spheres::CoverReport r = spheres::CheckCover(mesh, cover, kSpacing, 7);
      total_fitted[o] += r.spheres;
      std::printf(" | %3d, %6.1f mm, %5.0f %% (reach %4.1f mm)", r.spheres, r.largest_uncovered * 1e3,
                  r.overshoot_ratio * 100, r.largest_outside * 1e3);
      if (o == 0) {
        for (const auto& s : cover) fitted.push_back({static_cast<int>(l), s.centre, s.radius, name + "_mesh"});
      }
    }
    std::printf("\n");
  }
  std::printf("%-13s %8s | %3d spheres%19s", "all", "", total_builtin, "");
  for (size_t o = 0; o < overshoots.size(); ++o) std::printf(" | %3d spheres%30s", total_fitted[o], "");
  std::printf("\n");
  if (!out_path.empty()) {
    // The fitted spheres, and the link pairs to ignore for them (collision/self_pairs.h).
    kinematics::RobotDescription d = robot;
    d.spheres = fitted;
    kinematics::CollisionBody body = kinematics::CollisionBodyOf(d);
    collision::SelfPairSettings pair_settings;
    pair_settings.samples = 20000;
    pair_settings.ignore_never = true;
    const collision::SelfPairStudy study = collision::StudySelfPairs(d, pair_settings);
    body.self_collision_ignore.clear();
    for (const auto& pair : study.ignored) {
      body.self_collision_ignore.push_back({pair.links, pair.reason + " (" + std::to_string(pair.overlapping) + " of " +
                                                            std::to_string(study.samples) + " samples overlap)"});
    }
    body.floor_exempt = {"link0", "link1"};
    std::ofstream out(out_path);
    out << "# The Franka Panda's collision body for planning: spheres covering its published collision meshes\n"
        << "# (overshoot " << overshoots[0] << " m, surface spacing " << kSpacing
        << " m; bench/sphere_cover_report), and the link pairs\n"
        << "# not checked against each other (collision/self_pairs.h, " << study.samples << " random configurations, "
        << study.pairs << " pairs).\n"
        << config::ToYaml(body);
    std::printf("wrote %s: %zu spheres, %zu of %lld pairs ignored\n", out_path.c_str(), body.spheres.size(),
                body.self_collision_ignore.size(), static_cast<long long>(study.pairs));
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "sphere_cover_report: " << e.what() << "\n";
    return 1;
  }
}
