// MuJoCo's own verdict on a problem file's starts and goals, with the Panda's
// published collision meshes instead of flowplan's spheres: whether a refusal
// (a start or goal flowplan's collision spheres find touching an obstacle) is
// right on the robot's real collision geometry.
//
//   mesh_contacts PROBLEMS.yaml [--meshes DIR] [--all] [--spacing 0.002]
//
// For each refused problem (every problem with --all), at its start and goal
// (the problem's held finger values applied), two checks that share no code
// with flowplan's collision library:
//  - MuJoCo's contacts between mesh geoms (robots/franka_panda/meshes, one per
//    link, in the link's body) and the obstacles, as MuJoCo 2.2 finds them:
//    on each mesh's convex hull, so a contact there is necessary, not
//    sufficient, for the mesh itself to touch;
//  - the mesh surface itself: points on its triangles (about one per
//    spacing², placed by MuJoCo's forward kinematics) measured against each
//    obstacle geom in closed form: the nearest point's clearance, or the
//    deepest point's depth. A surface point inside an obstacle shows that the
//    mesh enters the obstacle, by at least that point's depth.
// A refusal is shown right when the surface check finds a point inside.
// Only the Franka (the meshes are its links'); a Franka tool. Not looked at:
// the floor (MotionBenchMaker has none), and MuJoCo's contacts of link0, which
// MuJoCo welds to the world body with the obstacles and so never collides
// (the surface check covers link0).

#include <mujoco/mujoco.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <initializer_list>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include <spdlog/fmt/fmt.h>

#include "core/error.h"
#include "problems/problem.h"
#include "sim/franka_model.h"
#include "spheres/internal_geometry.h"
#include "spheres/mesh.h"

namespace {

using namespace flowplan;
namespace fs = std::filesystem;

// The links that carry a mesh, by MJCF body name, and the mesh file of each.
const std::vector<std::pair<std::string, std::string>> kMeshes = {
    {"link0", "link0"}, {"link1", "link1"}, {"link2", "link2"}, {"link3", "link3"},
    {"link4", "link4"}, {"link5", "link5"}, {"link6", "link6"}, {"link7", "link7"},
    {"hand", "hand"},   {"left_finger", "finger"}, {"right_finger", "finger"}};

std::string Num(double v) { return fmt::format("{:.17g}", v); }

/// The MJCF of the Franka with one mesh geom per link (colliding with the obstacles only), the fingers opened to
/// their held values, and the obstacles of `scene`.
std::string SceneXml(const problems::Problem& problem, const std::string& meshes) {
  std::string xml = sim::FrankaModelXml();
  auto replace = [&](const std::string& from, const std::string& to) {
    const size_t at = xml.find(from);
    if (at == std::string::npos) throw Error("mesh_contacts: the Franka MJCF has no \"" + from + "\"");
    xml.replace(at, from.size(), to);
  };
  std::string assets = "<asset>";
  for (const auto& [body, file] : kMeshes) {
    if (body == "right_finger") continue;
    assets += "\n    <mesh name=\"m_" + file + "\" file=\"" + (fs::absolute(meshes) / (file + ".obj")).string() + "\"/>";
  }
  assets += "\n  </asset>";
  if (xml.find("<asset>") != std::string::npos) {
    replace("<asset>", assets.substr(0, assets.size() - std::string("\n  </asset>").size()));
  } else {
    replace("<worldbody>", assets + "\n  <worldbody>");
  }
  double left = 0.0, right = 0.0;
  for (const auto& h : problem.held) {
    if (h.joint == "panda_finger_joint1") left = h.value;
    else if (h.joint == "panda_finger_joint2") right = h.value;
  }
  // A finger slides along its body's y axis; the right finger's body is turned half a turn about the hand's z.
  replace("<body name=\"left_finger\" pos=\"0 0 0.0584\"", "<body name=\"left_finger\" pos=\"0 " + Num(left) + " 0.0584\"");
  replace("<body name=\"right_finger\" pos=\"0 0 0.0584\"",
          "<body name=\"right_finger\" pos=\"0 " + Num(-right) + " 0.0584\"");
  for (const auto& [body, file] : kMeshes) {
    const std::regex open("<body name=\"" + body + "\"[^>]*>");
    std::smatch m;
    if (!std::regex_search(xml, m, open)) throw Error("mesh_contacts: the Franka MJCF has no body " + body);
    const size_t end = static_cast<size_t>(m.position(0) + m.length(0));
    xml.insert(end, "\n<geom name=\"mesh_" + body + "\" type=\"mesh\" mesh=\"m_" + file +
                        "\" contype=\"1\" conaffinity=\"0\" group=\"2\" mass=\"0\"/>");
  }
  std::string geoms;
  int k = 0;
  auto add = [&](const std::string& shape) {
    geoms += "\n    <geom name=\"obstacle" + std::to_string(k++) + "\" " + shape +
             " contype=\"0\" conaffinity=\"1\" margin=\"0\"/>";
  };
  auto quat = [](const std::vector<double>& q) {
    return q.empty() ? std::string() : " quat=\"" + Num(q[0]) + " " + Num(q[1]) + " " + Num(q[2]) + " " + Num(q[3]) + "\"";
  };
  auto vec = [](const std::vector<double>& v) { return Num(v[0]) + " " + Num(v[1]) + " " + Num(v[2]); };
  const geometry::Scene& s = problem.scene;
  for (const auto& o : s.spheres) add("type=\"sphere\" pos=\"" + vec(o.centre) + "\" size=\"" + Num(o.radius) + "\"");
  for (const auto& o : s.boxes) {
    add("type=\"box\" pos=\"" + vec(o.centre) + "\" size=\"" + Num(o.size[0] / 2) + " " + Num(o.size[1] / 2) + " " +
        Num(o.size[2] / 2) + "\"" + quat(o.quaternion));
  }
  for (const auto& o : s.cylinders) {
    add("type=\"cylinder\" pos=\"" + vec(o.centre) + "\" size=\"" + Num(o.radius) + " " + Num(o.height / 2) + "\"" +
        quat(o.quaternion));
  }
  for (const auto& o : s.capsules) {
    add("type=\"capsule\" fromto=\"" + vec(o.a) + " " + vec(o.b) + "\" size=\"" + Num(o.radius) + "\"");
  }
  replace("<worldbody>", "<worldbody>" + geoms);
  // Room for many contacts.
  xml = std::regex_replace(xml, std::regex("njmax=\"[0-9]+\""), "njmax=\"4000\"");
  xml = std::regex_replace(xml, std::regex("nconmax=\"[0-9]+\""), "nconmax=\"2000\"");
  return xml;
}

/// The signed distance from point p (world) to obstacle geom g, < 0 inside; by the geom's own shape, in closed form.
double SignedDistance(const mjModel& m, const mjData& d, int g, const double* p) {
  double rel[3] = {p[0] - d.geom_xpos[3 * g], p[1] - d.geom_xpos[3 * g + 1], p[2] - d.geom_xpos[3 * g + 2]};
  double x[3];
  mju_mulMatTVec(x, d.geom_xmat + 9 * g, rel, 3, 3);  // into the geom's frame
  const double* size = m.geom_size + 3 * g;
  // Inside: minus the depth below the nearest face; outside: the distance to the nearest point.
  auto combine = [](std::initializer_list<double> excess) {
    double outside = 0.0, inside = -INFINITY;
    for (double e : excess) {
      outside += std::max(e, 0.0) * std::max(e, 0.0);
      inside = std::max(inside, e);
    }
    return inside > 0.0 ? std::sqrt(outside) : inside;
  };
  switch (m.geom_type[g]) {
    case mjGEOM_SPHERE: return std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - size[0];
    case mjGEOM_BOX:
      return combine({std::abs(x[0]) - size[0], std::abs(x[1]) - size[1], std::abs(x[2]) - size[2]});
    case mjGEOM_CYLINDER: return combine({std::hypot(x[0], x[1]) - size[0], std::abs(x[2]) - size[1]});
    case mjGEOM_CAPSULE: {
      const double z = std::clamp(x[2], -size[1], size[1]);
      return std::sqrt(x[0] * x[0] + x[1] * x[1] + (x[2] - z) * (x[2] - z)) - size[0];
    }
    default: throw Error("mesh_contacts: an obstacle of MuJoCo geom type " + std::to_string(m.geom_type[g]));
  }
}

int Main(int argc, char** argv) {
  const char* usage =
      "usage: mesh_contacts PROBLEMS.yaml [--meshes DIR] [--all] [--spacing 0.002]\n"
      "At each refused start and goal (every one with --all), MuJoCo's contacts between the Panda's collision\n"
      "meshes (DIR) and the problem's obstacles, and the nearest mesh surface point (samples SPACING m apart).\n";
  if (argc >= 2 && (std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h")) {
    std::cout << usage;
    return 0;
  }
  if (argc < 2) {
    std::cerr << usage;
    return 1;
  }
  std::string meshes = std::string(FLOWPLAN_SOURCE_DIR) + "/robots/franka_panda/meshes";
  bool all = false;
  double spacing = 0.002;
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--all") all = true;
    else if (flag == "--meshes" && i + 1 < argc) meshes = argv[++i];
    else if (flag == "--spacing" && i + 1 < argc) spacing = std::stod(argv[++i]);
    else throw Error("mesh_contacts: unknown option " + flag);
  }
  const problems::ProblemSet set = problems::LoadProblemSet(argv[1]);
  std::map<std::string, std::vector<std::array<double, 3>>> samples;  // surface points per mesh file, link frame
  for (const auto& [body, file] : kMeshes) {
    if (samples.count(file)) continue;
    const spheres::Mesh mesh = spheres::LoadMesh(meshes + "/" + file + ".obj");
    spheres::ValidateMesh(mesh);
    samples[file] = spheres::internal::RandomSurfacePoints(mesh, spacing, 7, nullptr);
  }
  const fs::path scratch = fs::temp_directory_path() / ("mesh_contacts_" + std::to_string(::getpid()));
  fs::create_directories(scratch);
  std::printf("problem\tend\tflowplan's spheres\tMuJoCo on the hulls (deepest, mm)\tmesh surface nearest an obstacle (mm)\n");
  int shown = 0, looked = 0;
  for (const problems::Problem& problem : set.problems) {
    if (!all && problem.status != "refused") continue;
    const std::string xml_path = (scratch / "scene.xml").string();
    {
      std::ofstream out(xml_path);
      out << SceneXml(problem, meshes);
    }
    char error[1000] = "";
    mjModel* m = mj_loadXML(xml_path.c_str(), nullptr, error, sizeof(error));
    if (m == nullptr) throw Error(problem.name + ": MuJoCo cannot load the scene: " + error);
    m->opt.disableflags &= ~mjDSBL_CONTACT;
    mjData* d = mj_makeData(m);
    auto name = [&](int g) { return std::string(mj_id2name(m, mjOBJ_GEOM, g) ? mj_id2name(m, mjOBJ_GEOM, g) : "?"); };
    auto obstacle_name = [&](int g) {
      const std::string n = name(g);
      const int k = std::stoi(n.substr(std::string("obstacle").size()));
      return k < static_cast<int>(problem.obstacle_names.size()) ? problem.obstacle_names[static_cast<size_t>(k)] : n;
    };
    for (const bool goal : {false, true}) {
      const std::vector<double>& q = goal ? problem.goal_q : problem.start_q;
      if (q.size() != 7) continue;
      for (int j = 0; j < 7; ++j) d->qpos[j] = q[static_cast<size_t>(j)];
      mj_forward(m, d);
      // MuJoCo's contacts, mesh against obstacle.
      std::string hull = "none";
      double deepest_hull = 0.0;
      for (int c = 0; c < d->ncon; ++c) {
        const mjContact& contact = d->contact[c];
        int arm = contact.geom1, obstacle = contact.geom2;
        if (name(arm).rfind("obstacle", 0) == 0) std::swap(arm, obstacle);
        if (name(arm).rfind("mesh_", 0) != 0 || name(obstacle).rfind("obstacle", 0) != 0) continue;
        if (contact.dist < deepest_hull) {
          deepest_hull = contact.dist;
          hull = fmt::format("{:.2f} ({} / {})", -1e3 * contact.dist, name(arm).substr(5), obstacle_name(obstacle));
        }
      }
      // The mesh surface against each obstacle.
      std::string nearest;
      double closest = INFINITY;
      for (const auto& [body, file] : kMeshes) {
        const int b = mj_name2id(m, mjOBJ_BODY, body.c_str());
        for (const auto& local : samples[file]) {
          double p[3];
          mju_mulMatVec(p, d->xmat + 9 * b, local.data(), 3, 3);
          for (int i = 0; i < 3; ++i) p[i] += d->xpos[3 * b + i];
          for (int g = 0; g < m->ngeom; ++g) {
            if (m->geom_bodyid[g] != 0 || name(g).rfind("obstacle", 0) != 0) continue;
            const double distance = SignedDistance(*m, *d, g, p);
            if (distance < closest) {
              closest = distance;
              nearest = fmt::format("{} ({} / {})", closest < 0 ? fmt::format("inside by {:.2f}", -1e3 * closest)
                                                                 : fmt::format("clear by {:.2f}", 1e3 * closest),
                                    body, obstacle_name(g));
            }
          }
        }
      }
      const bool flagged = problem.reason.rfind(goal ? "goal" : "start", 0) == 0;
      if (!all && !flagged) continue;
      ++looked;
      shown += closest < 0.0;
      std::printf("%s\t%s\t%s\t%s\t%s\n", problem.name.c_str(), goal ? "goal" : "start",
                  flagged ? problem.reason.c_str() : "ok", hull.c_str(), nearest.c_str());
    }
    mj_deleteData(d);
    mj_deleteModel(m);
  }
  fs::remove_all(scratch);
  std::printf("%d of %d ends have mesh surface inside an obstacle\n", shown, looked);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mesh_contacts: %s\n", e.what());
    return 1;
  }
}
