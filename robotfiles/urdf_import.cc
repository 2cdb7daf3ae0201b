#include "robotfiles/urdf_import.h"

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "robotfiles/collision_fit.h"
#include "robotfiles/mjcf_import.h"
#include "spheres/mesh.h"

namespace flowplan::robotfiles {
namespace fs = std::filesystem;

namespace {

/// Collects what liburdfdom reports while it parses, so that its error becomes the one error of the import.
class Collector : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors.push_back(text);
  }
  std::vector<std::string> errors;
};

std::array<double, 4> Quat(const urdf::Rotation& r) {
  double x, y, z, w;
  r.getQuaternion(x, y, z, w);
  return {w, x, y, z};
}

std::array<double, 3> Vec(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool Movable(const urdf::Joint& joint) {
  return joint.type == urdf::Joint::REVOLUTE || joint.type == urdf::Joint::CONTINUOUS ||
         joint.type == urdf::Joint::PRISMATIC;
}

/// A mesh reference of the URDF as a file on this machine.
std::string ResolveMesh(const std::string& filename, const fs::path& urdf_dir, const std::string& package_dir,
                        const std::string& where) {
  const std::string package = "package://", file = "file://";
  std::vector<fs::path> tried;
  if (filename.rfind(package, 0) == 0) {
    const std::string rest = filename.substr(package.size());
    if (package_dir.empty()) {
      throw Error(where + ": mesh \"" + filename + "\": a package:// path needs --package-dir DIR (the folder holding the package)");
    }
    tried.push_back(fs::path(package_dir) / rest);
    const size_t slash = rest.find('/');
    if (slash != std::string::npos) tried.push_back(fs::path(package_dir) / rest.substr(slash + 1));
  } else if (filename.rfind(file, 0) == 0) {
    tried.push_back(fs::path(filename.substr(file.size())));
  } else {
    const fs::path p(filename);
    tried.push_back(p.is_absolute() ? p : urdf_dir / p);
  }
  for (const fs::path& p : tried) {
    if (fs::is_regular_file(p)) return p.string();
  }
  std::string list;
  for (const fs::path& p : tried) list += (list.empty() ? "" : ", ") + p.string();
  throw Error(where + ": mesh \"" + filename + "\": no such file (looked for " + list + ")");
}

}  // namespace

ImportResult ImportUrdf(const std::string& urdf_path, const ImportOptions& options) {
  ImportResult result;
  if (!fs::is_regular_file(urdf_path)) throw Error(urdf_path + ": no such file");
  const std::string extension = Lower(fs::path(urdf_path).extension().string());
  if (extension != ".urdf" && extension != ".xml") throw Error(urdf_path + ": expected a URDF file (.urdf or .xml)");
  std::ifstream in(urdf_path);
  std::stringstream text;
  text << in.rdbuf();
  Collector collector;
  console_bridge::useOutputHandler(&collector);
  urdf::ModelInterfaceSharedPtr model;
  try {
    model = urdf::parseURDF(text.str());
  } catch (const std::exception& e) {  // liburdfdom lets some conversions throw
    collector.errors.push_back(e.what());
  }
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    std::string why = collector.errors.empty() ? "not a valid URDF" : collector.errors.front();
    for (size_t i = 1; i < collector.errors.size(); ++i) why += "; " + collector.errors[i];
    for (char& c : why) {
      if (c == '\n' || c == '\r') c = ' ';  // one line
    }
    throw Error(urdf_path + ": " + why);
  }
  const fs::path urdf_dir = fs::absolute(urdf_path).parent_path();
  const std::string base_name = options.base.empty() ? model->getRoot()->name : options.base;
  const urdf::LinkConstSharedPtr base = model->getLink(base_name);
  if (!base) throw Error(urdf_path + ": --base: no link \"" + base_name + "\"");
  if (!options.tip.empty() && !model->getLink(options.tip)) throw Error(urdf_path + ": --tip: no link \"" + options.tip + "\"");

  // The links below the base, parents first (children in the order of their joints' names: liburdfdom's).
  std::vector<urdf::LinkConstSharedPtr> links = {base};
  for (size_t i = 0; i < links.size(); ++i) {
    for (const urdf::JointSharedPtr& joint : links[i]->child_joints) links.push_back(model->getLink(joint->child_link_name));
  }
  std::map<std::string, int> link_index;
  for (size_t i = 0; i < links.size(); ++i) link_index[links[i]->name] = static_cast<int>(i);
  for (const auto& [name, value] : options.hold) {
    const urdf::JointConstSharedPtr joint = model->getJoint(name);
    if (!joint || !link_index.count(joint->child_link_name) || joint->child_link_name == base_name) {
      throw Error(urdf_path + ": --hold: no joint \"" + name + "\" below the base link \"" + base_name + "\"");
    }
    if (!Movable(*joint)) throw Error(urdf_path + ": --hold: joint \"" + name + "\" is fixed; it has no value to hold");
    if (joint->type != urdf::Joint::CONTINUOUS && joint->limits &&
        (value < joint->limits->lower || value > joint->limits->upper)) {
      throw Error(urdf_path + ": --hold: " + name + " = " + config::internal::FormatDouble(value) + " is outside its limits [" +
                  config::internal::FormatDouble(joint->limits->lower) + ", " +
                  config::internal::FormatDouble(joint->limits->upper) + "]");
    }
  }
  if (!options.tip.empty() && (!link_index.count(options.tip) || options.tip == base_name)) {
    throw Error(urdf_path + ": --tip: link \"" + options.tip + "\" is not below the base \"" + base_name + "\"");
  }
  auto joint_of = [&](const urdf::LinkConstSharedPtr& link) -> urdf::JointConstSharedPtr {
    return link->name == base_name ? nullptr : link->parent_joint;
  };
  for (const auto& link : links) {
    const auto joint = joint_of(link);
    if (joint && (joint->type == urdf::Joint::FLOATING || joint->type == urdf::Joint::PLANAR)) {
      throw Error(urdf_path + ": joint \"" + joint->name + "\": a " +
                  (joint->type == urdf::Joint::FLOATING ? "floating" : "planar") +
                  " joint below the base; a robot folder is an arm on a fixed base (choose --base below it)");
    }
  }

  // The planned joints, in order.
  std::vector<std::string> planned = options.joints;
  if (planned.empty()) {
    if (!options.tip.empty()) {
      if (!link_index.count(options.tip)) throw Error(urdf_path + ": --tip: link \"" + options.tip + "\" is not below the base \"" + base_name + "\"");
      for (urdf::LinkConstSharedPtr l = model->getLink(options.tip); l && l->name != base_name; l = l->getParent()) {
        const auto joint = l->parent_joint;
        if (Movable(*joint) && !joint->mimic && !options.hold.count(joint->name)) planned.insert(planned.begin(), joint->name);
      }
    } else {
      for (const auto& link : links) {
        const auto joint = joint_of(link);
        if (joint && Movable(*joint) && !joint->mimic && !options.hold.count(joint->name)) planned.push_back(joint->name);
      }
    }
  }
  if (planned.empty()) throw Error(urdf_path + ": no movable joint to plan below the base link \"" + base_name + "\"");
  std::map<std::string, int> planned_index;
  for (size_t j = 0; j < planned.size(); ++j) {
    const urdf::JointConstSharedPtr joint = model->getJoint(planned[j]);
    if (!joint || !link_index.count(joint->child_link_name) || joint->child_link_name == base_name) {
      throw Error(urdf_path + ": --joints: no joint \"" + planned[j] + "\" below the base link \"" + base_name + "\"");
    }
    if (!Movable(*joint)) throw Error(urdf_path + ": --joints: joint \"" + planned[j] + "\" is fixed");
    if (joint->mimic) {
      throw Error(urdf_path + ": --joints: joint \"" + planned[j] + "\" mimics \"" + joint->mimic->joint_name +
                  "\"; plan its leader instead");
    }
    if (options.hold.count(planned[j])) throw Error(urdf_path + ": joint \"" + planned[j] + "\" is both planned and held");
    if (!planned_index.emplace(planned[j], static_cast<int>(j)).second) {
      throw Error(urdf_path + ": --joints: joint \"" + planned[j] + "\" named twice");
    }
  }

  kinematics::RobotDescription& d = result.file.robot;
  d.name = model->getName();
  d.kind = kinematics::RobotKind::kArm;
  d.workspace_dim = 3;
  const int J = static_cast<int>(planned.size());
  d.num_joints = J;
  d.joint_lower.assign(J, 0.0);
  d.joint_upper.assign(J, 0.0);
  d.velocity_limit.assign(J, 0.0);
  result.file.effort_limit.assign(J, 0.0);
  // Limits of a movable joint: (lower, upper), continuous joints turning within ±π.
  auto limits_of = [&](const urdf::Joint& joint) -> std::pair<double, double> {
    if (joint.type == urdf::Joint::CONTINUOUS) return {-M_PI, M_PI};
    if (!joint.limits) throw Error(urdf_path + ": joint \"" + joint.name + "\": no <limit>");
    if (!(joint.limits->lower < joint.limits->upper)) {
      throw Error(urdf_path + ": joint \"" + joint.name + "\": <limit lower=\"" + config::internal::FormatDouble(joint.limits->lower) +
                  "\" upper=\"" + config::internal::FormatDouble(joint.limits->upper) + "\">: expected lower < upper");
    }
    return {joint.limits->lower, joint.limits->upper};
  };
  // Held joints' values: given, or 0 moved into the limits; a mimic joint follows its leader, whatever order the
  // file lists them in.
  std::map<std::string, double> held;
  std::function<double(const urdf::Joint&, int)> held_value = [&](const urdf::Joint& joint, int depth) -> double {
    if (options.hold.count(joint.name)) return options.hold.at(joint.name);
    if (joint.mimic) {
      if (planned_index.count(joint.mimic->joint_name)) {
        throw Error(urdf_path + ": joint \"" + joint.name + "\" mimics \"" + joint.mimic->joint_name +
                    "\", which is planned; a mimic joint can only follow a held joint (hold both, or plan neither)");
      }
      const urdf::JointConstSharedPtr leader = model->getJoint(joint.mimic->joint_name);
      if (!leader || !Movable(*leader) || depth > 64) {
        throw Error(urdf_path + ": joint \"" + joint.name + "\" mimics \"" + joint.mimic->joint_name +
                    "\", which is not a movable joint (or the mimics form a loop)");
      }
      return joint.mimic->multiplier * held_value(*leader, depth + 1) + joint.mimic->offset;
    }
    const auto [lo, hi] = limits_of(joint);
    return std::clamp(0.0, lo, hi);
  };
  for (const auto& link : links) {
    kinematics::RobotLink out;
    out.name = link->name;
    const auto joint = joint_of(link);
    if (joint) {
      out.parent = link_index.at(joint->parent_link_name);
      out.pos = Vec(joint->parent_to_joint_origin_transform.position);
      out.quat = Quat(joint->parent_to_joint_origin_transform.rotation);
      if (Movable(*joint)) {
        out.joint_name = joint->name;  // a fixed joint has no value a MoveIt state could set
        const double n = std::sqrt(joint->axis.x * joint->axis.x + joint->axis.y * joint->axis.y + joint->axis.z * joint->axis.z);
        if (!(n > 0.0) || !std::isfinite(n)) throw Error(urdf_path + ": joint \"" + joint->name + "\": <axis> is zero");
        out.axis = {joint->axis.x / n, joint->axis.y / n, joint->axis.z / n};
        out.type = joint->type == urdf::Joint::PRISMATIC ? kinematics::JointType::kPrismatic : kinematics::JointType::kRevolute;
        const auto found = planned_index.find(joint->name);
        if (found != planned_index.end()) {
          const int j = found->second;
          out.joint = j;
          const auto [lo, hi] = limits_of(*joint);
          d.joint_lower[j] = lo;
          d.joint_upper[j] = hi;
          if (joint->type == urdf::Joint::CONTINUOUS) {
            result.notes.push_back("joint \"" + joint->name + "\" is continuous: planned within [-pi, pi] (edit its limits to widen)");
          }
          if (!joint->limits || !(joint->limits->velocity > 0.0)) {
            throw Error(urdf_path + ": joint \"" + joint->name + "\": <limit velocity> missing or not positive; plans are timed by it");
          }
          d.velocity_limit[j] = joint->limits->velocity;
          if (!(joint->limits->effort > 0.0)) {
            throw Error(urdf_path + ": joint \"" + joint->name + "\": <limit effort> missing or not positive");
          }
          result.file.effort_limit[j] = joint->limits->effort;
        } else {
          const double value = held_value(*joint, 0);
          held[joint->name] = value;
          out.offset = value;
          result.notes.push_back("joint \"" + joint->name + "\" is held at " + config::internal::FormatDouble(value));
        }
      }
    }
    d.links.push_back(out);
    if (link->inertial && link->inertial->mass > 0.0) {
      const urdf::Inertial& in = *link->inertial;
      LinkInertia inertia;
      inertia.link = link->name;
      inertia.mass = in.mass;
      inertia.com = Vec(in.origin.position);
      inertia.inertia = RotateInertia({in.ixx, in.iyy, in.izz, in.ixy, in.ixz, in.iyz}, Quat(in.origin.rotation));
      result.file.inertia.push_back(inertia);
    }
  }
  d.home.assign(J, 0.0);
  for (int j = 0; j < J; ++j) d.home[j] = std::clamp(0.0, d.joint_lower[j], d.joint_upper[j]);

  // The TCP.
  std::string tip = options.tip;
  if (tip.empty()) tip = model->getJoint(planned.back())->child_link_name;
  d.tcp_link = link_index.at(tip);
  d.tcp_pos = options.tcp_offset;
  result.notes.push_back("TCP on link \"" + tip + "\" at " + config::internal::FormatDouble(d.tcp_pos[0]) + ", " +
                         config::internal::FormatDouble(d.tcp_pos[1]) + ", " + config::internal::FormatDouble(d.tcp_pos[2]));

  // Collision geometry, link by link, and the spheres covering it.
  std::vector<LinkGeometry> gathered;
  for (const auto& link : links) {
    std::vector<spheres::Mesh> pieces;
    std::vector<spheres::Sphere> exact;  // the URDF's own spheres
    for (size_t c = 0; c < link->collision_array.size(); ++c) {
      const urdf::Collision& element = *link->collision_array[c];
      const std::string where = urdf_path + ": link \"" + link->name + "\" collision " + std::to_string(c);
      if (!element.geometry) throw Error(where + ": no geometry");
      CollisionGeometry g;
      g.link = link->name;
      g.pos = Vec(element.origin.position);
      g.quat = Quat(element.origin.rotation);
      spheres::Mesh mesh;
      switch (element.geometry->type) {
        case urdf::Geometry::SPHERE: {
          const double r = static_cast<const urdf::Sphere&>(*element.geometry).radius;
          if (!(r > 0.0)) throw Error(where + ": sphere radius " + config::internal::FormatDouble(r) + ": expected > 0");
          g.shape = "sphere";
          g.size = {r, 0.0, 0.0};
          exact.push_back({g.pos, r});
          break;
        }
        case urdf::Geometry::BOX: {
          const urdf::Vector3 dim = static_cast<const urdf::Box&>(*element.geometry).dim;
          g.shape = "box";
          g.size = Vec(dim);
          mesh = spheres::Transformed(spheres::BoxMesh(dim.x, dim.y, dim.z), g.pos, g.quat);
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& cylinder = static_cast<const urdf::Cylinder&>(*element.geometry);
          g.shape = "cylinder";
          g.size = {cylinder.radius, cylinder.length, 0.0};
          mesh = spheres::Transformed(spheres::CylinderMesh(cylinder.radius, cylinder.length), g.pos, g.quat);
          break;
        }
        case urdf::Geometry::MESH: {
          const auto& m = static_cast<const urdf::Mesh&>(*element.geometry);
          const std::string path = ResolveMesh(m.filename, urdf_dir, options.package_dir, where);
          const std::string ext = Lower(fs::path(path).extension().string());
          if (ext != ".stl" && ext != ".obj") {
            throw Error(where + ": mesh \"" + m.filename + "\": a " + ext +
                        " collision mesh cannot be read (STL or OBJ only; convert it, e.g. with meshlab or assimp)");
          }
          g.shape = "mesh";
          g.scale = Vec(m.scale);
          g.mesh = "meshes/" + SafeFileName(link->name) + "_" + std::to_string(c) + ext;
          result.meshes.push_back({path, g.mesh});
          try {
            mesh = spheres::Transformed(spheres::LoadMesh(path), g.pos, g.quat, g.scale);
          } catch (const Error& e) {
            throw Error(where + ": " + e.what());
          }
          break;
        }
      }
      if (!mesh.triangles.empty()) pieces.push_back(std::move(mesh));
      result.file.geometry.push_back(g);
    }
    if (!pieces.empty() || !exact.empty()) gathered.push_back({link->name, std::move(pieces), std::move(exact)});
  }
  // Every file is read before any cover is fitted: a missing mesh is reported at once.
  FitCollisionBody(gathered, options, urdf_path, result);
  result.file.source = fs::path(urdf_path).filename().string();
  result.file.Description(urdf_path);  // validates
  return result;
}

ImportResult ImportRobot(const std::string& model_path, const ImportOptions& options, const std::string& dir) {
  const std::string extension = Lower(fs::path(model_path).extension().string());
  if (extension != ".urdf" && extension != ".xml") {
    throw Error(model_path + ": expected a URDF (.urdf) or an MJCF (.xml) model");
  }
  // A .xml file may be a URDF too (`robot.urdf.xml`): its root element decides.
  bool urdf = extension == ".urdf";
  if (!urdf) {
    std::ifstream in(model_path);
    std::string head(4096, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<size_t>(in.gcount()));
    const size_t robot = head.find("<robot"), mujoco = head.find("<mujoco");
    urdf = robot != std::string::npos && (mujoco == std::string::npos || robot < mujoco);
  }
  ImportResult result = urdf ? ImportUrdf(model_path, options) : ImportMjcf(model_path, options);
  // An earlier robot.yaml goes first and the new one comes last, the meshes between them (the earlier import's
  // removed): a folder with robot.yaml is whole.
  try {
    fs::remove(fs::path(dir) / "robot.yaml");
    fs::remove_all(fs::path(dir) / "meshes");
    fs::create_directories(fs::path(dir) / "meshes");
    for (const auto& [from, to] : result.meshes) fs::copy_file(from, fs::path(dir) / to, fs::copy_options::overwrite_existing);
  } catch (const fs::filesystem_error& e) {
    throw Error(dir + ": cannot write the robot folder: " + e.what());
  }
  for (const auto& [to, mesh] : result.mesh_files) {
    std::ofstream out(fs::path(dir) / to);
    out.precision(9);
    for (const auto& v : mesh.vertices) out << "v " << v[0] << " " << v[1] << " " << v[2] << "\n";
    for (const auto& t : mesh.triangles) out << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    if (!out) throw Error((fs::path(dir) / to).string() + ": write failed");
  }
  WriteRobotFile(result.file, dir);
  return result;
}

}  // namespace flowplan::robotfiles
