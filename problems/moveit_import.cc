#include "problems/moveit_import.h"

#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <regex>

#include "collision/checker.h"
#include "core/error.h"
#include "geometry/scene_rows.h"

namespace flowplan::problems {
namespace {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // (w, x, y, z)

/// A rigid transform: x -> rotation(x) + position.
struct Pose {
  Vec3 position{0.0, 0.0, 0.0};
  Quat orientation{1.0, 0.0, 0.0, 0.0};
};

Quat Multiply(const Quat& a, const Quat& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

Vec3 Rotate(const Quat& q, const Vec3& v) {
  const Quat p = Multiply(Multiply(q, {0.0, v[0], v[1], v[2]}), {q[0], -q[1], -q[2], -q[3]});
  return {p[1], p[2], p[3]};
}

/// outer ∘ inner: the pose of `inner` (given in outer's frame) in the world.
Pose Compose(const Pose& outer, const Pose& inner) {
  Pose out;
  const Vec3 moved = Rotate(outer.orientation, inner.position);
  for (int k = 0; k < 3; ++k) out.position[k] = outer.position[k] + moved[k];
  out.orientation = Multiply(outer.orientation, inner.orientation);
  return out;
}

/// Reads entries of one file, naming it and the entry in every error.
class Reader {
 public:
  explicit Reader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& entry, const std::string& what) const {
    throw Error(path_ + ": " + entry + ": " + what);
  }

  double Number(const YAML::Node& node, const std::string& entry) const {
    if (!node.IsDefined() || node.IsNull()) Fail(entry, "missing");
    if (!node.IsScalar()) Fail(entry, "expected a number, got " + config::internal::Describe(node));
    double value = NAN;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      Fail(entry, "expected a number, got " + config::internal::Describe(node));
    }
    if (!std::isfinite(value)) Fail(entry, "expected a finite number, got " + config::internal::Describe(node));
    return value;
  }

  std::vector<double> Numbers(const YAML::Node& node, const std::string& entry) const {
    if (!node.IsDefined() || node.IsNull()) Fail(entry, "missing");
    if (!node.IsSequence()) Fail(entry, "expected a list of numbers, got " + config::internal::Describe(node));
    std::vector<double> out;
    for (size_t i = 0; i < node.size(); ++i) out.push_back(Number(node[i], entry + "[" + std::to_string(i) + "]"));
    return out;
  }

  std::string Text(const YAML::Node& node, const std::string& entry) const {
    if (!node.IsDefined() || node.IsNull()) Fail(entry, "missing");
    if (!node.IsScalar()) Fail(entry, "expected a name, got " + config::internal::Describe(node));
    return node.as<std::string>();
  }

  /// `names` as a list [a, b, ...] or a mapping {a: , b: , ...}.
  std::vector<double> Components(const YAML::Node& node, const std::string& entry,
                                 const std::vector<std::string>& names) const {
    if (node.IsSequence()) {
      std::vector<double> values = Numbers(node, entry);
      if (values.size() != names.size()) {
        Fail(entry, "expected " + std::to_string(names.size()) + " values, got " + std::to_string(values.size()));
      }
      return values;
    }
    if (!node.IsMap()) Fail(entry, "expected a list or a mapping, got " + config::internal::Describe(node));
    std::vector<double> values;
    for (const std::string& name : names) values.push_back(Number(node[name], entry + "." + name));
    return values;
  }

  /// A geometry_msgs/Pose; a missing position is the origin, a missing orientation the identity.
  Pose ReadPose(const YAML::Node& node, const std::string& entry) const {
    Pose pose;
    if (!node.IsMap()) Fail(entry, "expected a mapping with position and orientation, got " +
                                       config::internal::Describe(node));
    if (node["position"]) {
      const std::vector<double> p = Components(node["position"], entry + ".position", {"x", "y", "z"});
      pose.position = {p[0], p[1], p[2]};
    }
    if (node["orientation"]) {
      const std::vector<double> q = Components(node["orientation"], entry + ".orientation", {"x", "y", "z", "w"});
      const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
      if (norm < 1e-9) {
        // An unset ROS pose: MoveIt reads it as the identity, with a warning.
        spdlog::warn("{}: {}.orientation: all zero, taken as the identity (as MoveIt does)", path_, entry);
      } else {
        pose.orientation = {q[3] / norm, q[0] / norm, q[1] / norm, q[2] / norm};
      }
    }
    return pose;
  }

  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// The pose of the robot's base in the world from a robot state's virtual joint (multi_dof_joint_state:
/// joint_names, transforms of translation and rotation); the identity when there is none. An absent transform or
/// part is the identity; so is an all-zero rotation (an unset ROS quaternion). Only the first transform is the
/// base's (MoveIt's one virtual joint).
Pose ReadVirtualJoint(const Reader& r, const YAML::Node& state, const std::string& entry) {
  Pose base;
  if (!state.IsDefined() || !state.IsMap()) return base;
  const YAML::Node multi = state["multi_dof_joint_state"];
  if (!multi.IsDefined() || multi.IsNull()) return base;
  if (!multi.IsMap()) r.Fail(entry, "expected a mapping with joint_names and transforms");
  const YAML::Node transforms = multi["transforms"];
  if (!transforms.IsDefined() || transforms.IsNull()) return base;
  if (!transforms.IsSequence()) r.Fail(entry + ".transforms", "expected a list of transforms");
  if (transforms.size() == 0) return base;
  if (transforms.size() > 1) {
    r.Fail(entry + ".transforms", "expected one transform (the virtual joint), got " + std::to_string(transforms.size()));
  }
  const YAML::Node names = multi["joint_names"];
  std::string where = entry + ".transforms[0]";
  if (names.IsDefined() && names.IsSequence() && names.size() > 0 && names[0].IsScalar()) {
    where += " (" + names[0].as<std::string>() + ")";
  }
  const YAML::Node t = transforms[0];
  if (!t.IsMap()) r.Fail(where, "expected a mapping with translation and rotation");
  if (t["translation"]) {
    const std::vector<double> p = r.Components(t["translation"], where + ".translation", {"x", "y", "z"});
    base.position = {p[0], p[1], p[2]};
  }
  if (t["rotation"]) {
    const std::vector<double> q = r.Components(t["rotation"], where + ".rotation", {"x", "y", "z", "w"});
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (norm >= 1e-9) base.orientation = {q[3] / norm, q[0] / norm, q[1] / norm, q[2] / norm};
  }
  return base;
}

/// The inverse of a rigid transform.
Pose Inverse(const Pose& pose) {
  Pose out;
  out.orientation = {pose.orientation[0], -pose.orientation[1], -pose.orientation[2], -pose.orientation[3]};
  const Vec3 back = Rotate(out.orientation, pose.position);
  out.position = {-back[0], -back[1], -back[2]};
  return out;
}

bool IsIdentity(const Pose& pose) {
  const auto& p = pose.position;
  const auto& q = pose.orientation;
  return std::abs(p[0]) < 1e-12 && std::abs(p[1]) < 1e-12 && std::abs(p[2]) < 1e-12 && std::abs(q[1]) < 1e-12 &&
         std::abs(q[2]) < 1e-12 && std::abs(q[3]) < 1e-12;
}

YAML::Node Load(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw Error(path + ": no such file");
  YAML::Node root = config::ParseYamlFile(path);
  if (!root.IsMap()) throw Error(path + ": expected a mapping at the top, got " + config::internal::Describe(root));
  return root;
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

/// "box", "sphere" or "cylinder" of a SolidPrimitive type (a name or its number).
std::string PrimitiveType(const Reader& r, const YAML::Node& node, const std::string& entry) {
  const std::string text = Lower(r.Text(node, entry));
  static const std::map<std::string, std::string> kinds = {
      {"box", "box"}, {"1", "box"}, {"sphere", "sphere"}, {"2", "sphere"}, {"cylinder", "cylinder"},
      {"3", "cylinder"}, {"cone", "cone"}, {"4", "cone"}};
  const auto it = kinds.find(text);
  if (it == kinds.end()) r.Fail(entry, "unknown primitive type \"" + text + "\" (box, sphere, cylinder)");
  if (it->second == "cone") r.Fail(entry, "cones are not supported (box, sphere, cylinder)");
  return it->second;
}

/// The position of each robot joint (J,) in a JointState {name, position}.
std::vector<double> JointPositions(const Reader& r, const YAML::Node& state, const std::string& entry,
                                   const MoveItImportOptions& options) {
  if (!state.IsMap()) r.Fail(entry, "expected a mapping with name and position, got " +
                                        config::internal::Describe(state));
  const YAML::Node names = state["name"];
  if (!names.IsDefined() || !names.IsSequence()) r.Fail(entry + ".name", "expected a list of joint names");
  const std::vector<double> positions = r.Numbers(state["position"], entry + ".position");
  if (positions.size() != names.size()) {
    r.Fail(entry, std::to_string(names.size()) + " names but " + std::to_string(positions.size()) + " positions");
  }
  std::vector<double> q(options.joint_names.size(), NAN);
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string name = r.Text(names[i], entry + ".name[" + std::to_string(i) + "]");
    for (size_t j = 0; j < options.joint_names.size(); ++j) {
      for (const std::string& accepted : options.joint_names[j]) {
        if (name == accepted) q[j] = positions[i];
      }
    }
  }
  for (size_t j = 0; j < q.size(); ++j) {
    if (std::isnan(q[j])) r.Fail(entry, "no position for " + options.joint_names[j][0]);
  }
  return q;
}

/// The MotionPlanRequest of a request file (at the top or under a key).
YAML::Node RequestNode(const Reader& r, const YAML::Node& root, std::string& prefix) {
  for (const char* key : {"motion_plan_request", "request"}) {
    if (root[key] && root[key].IsMap()) {
      prefix = std::string(key) + ".";
      return root[key];
    }
  }
  if (!root["goal_constraints"]) r.Fail("goal_constraints", "missing (not a MoveIt motion-plan request?)");
  prefix = "";
  return root;
}

}  // namespace

std::vector<std::vector<std::string>> FrankaJointNames() {
  std::vector<std::vector<std::string>> names;
  for (int j = 1; j <= 7; ++j) names.push_back({"panda_joint" + std::to_string(j), "joint" + std::to_string(j)});
  return names;
}

namespace {

/// Runs `read`, turning what yaml-cpp throws for a shape it did not expect into an error naming `path`.
template <class F>
auto Guarded(const std::string& path, F read) {
  try {
    return read();
  } catch (const YAML::Exception& e) {
    throw Error(path + ": unexpected structure (" + e.msg + ")");
  }
}

/// The fixed frames of a scene (fixed_frame_transforms: [{child_frame_id, transform}]), each a pose in the world.
std::map<std::string, Pose> ReadFixedFrames(const Reader& r, const YAML::Node& root) {
  std::map<std::string, Pose> frames;
  const YAML::Node list = root["fixed_frame_transforms"];
  if (!list.IsDefined() || list.IsNull()) return frames;
  if (!list.IsSequence()) r.Fail("fixed_frame_transforms", "expected a list of transforms");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string entry = "fixed_frame_transforms[" + std::to_string(i) + "]";
    const YAML::Node item = list[i];
    if (!item.IsMap()) r.Fail(entry, "expected a mapping with child_frame_id and transform");
    const std::string child = r.Text(item["child_frame_id"], entry + ".child_frame_id");
    Pose pose;
    const YAML::Node t = item["transform"];
    if (t.IsDefined() && !t.IsNull()) {
      if (!t.IsMap()) r.Fail(entry + ".transform", "expected a mapping with translation and rotation");
      if (t["translation"]) {
        const std::vector<double> p = r.Components(t["translation"], entry + ".transform.translation", {"x", "y", "z"});
        pose.position = {p[0], p[1], p[2]};
      }
      if (t["rotation"]) {
        const std::vector<double> q = r.Components(t["rotation"], entry + ".transform.rotation", {"x", "y", "z", "w"});
        const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (norm >= 1e-9) pose.orientation = {q[3] / norm, q[0] / norm, q[1] / norm, q[2] / norm};
      }
    }
    frames[child] = pose;
  }
  return frames;
}

/// The scene's obstacles in the robot's base frame, the base standing at `base_given` in the world (nullptr:
/// where the scene's own robot_state's virtual joint puts it); `base_out` receives that pose.
NamedScene ReadScene(const std::string& path, const MoveItImportOptions& options, const Pose* base_given,
                     Pose* base_out) {
  const YAML::Node root = Load(path);
  const Reader r(path);
  const Pose base = base_given != nullptr
                        ? *base_given
                        : ReadVirtualJoint(r, root["robot_state"], "robot_state.multi_dof_joint_state");
  if (base_out != nullptr) *base_out = base;
  const Pose base_from_world = Inverse(base);
  const std::map<std::string, Pose> fixed = ReadFixedFrames(r, root);
  const YAML::Node world = root["world"];
  if (!world.IsDefined()) r.Fail("world", "missing (not a MoveIt planning scene?)");
  if (!world.IsMap()) r.Fail("world", "expected a mapping, got " + config::internal::Describe(world));
  const YAML::Node objects = world["collision_objects"];
  // Names per kind, so that they follow the scene's numbering (spheres, boxes, cylinders).
  std::vector<std::string> sphere_names, box_names, cylinder_names;
  NamedScene out;
  if (!objects.IsDefined() || objects.IsNull()) return out;
  if (!objects.IsSequence()) {
    r.Fail("world.collision_objects", "expected a list, got " + config::internal::Describe(objects));
  }
  for (size_t i = 0; i < objects.size(); ++i) {
    const YAML::Node object = objects[i];
    std::string entry = "world.collision_objects[" + std::to_string(i) + "]";
    if (!object.IsMap()) r.Fail(entry, "expected a mapping, got " + config::internal::Describe(object));
    const std::string id = r.Text(object["id"], entry + ".id");
    entry += " (" + id + ")";
    std::string frame;
    if (object["header"]) {
      if (!object["header"].IsMap()) r.Fail(entry + ".header", "expected a mapping with frame_id, got " +
                                                                    config::internal::Describe(object["header"]));
      if (object["header"]["frame_id"]) frame = r.Text(object["header"]["frame_id"], entry + ".header.frame_id");
    }
    // Where the frame stands in the base frame: the base itself, the world, or a fixed frame in the world.
    Pose frame_pose;
    bool known = false;
    for (const std::string& name : options.base_frames) known = known || frame == name;
    if (!known) {
      for (const std::string& name : options.world_frames) known = known || frame == name;
      const auto it = fixed.find(frame);
      if (!known && it != fixed.end()) {
        frame_pose = Compose(base_from_world, it->second);
        known = true;
      } else if (known) {
        frame_pose = base_from_world;
      }
    }
    if (!known) {
      std::string list;
      for (const auto* names : {&options.base_frames, &options.world_frames}) {
        for (const std::string& name : *names) list += (list.empty() ? "" : ", ") + ("\"" + name + "\"");
      }
      for (const auto& entry_frame : fixed) list += ", \"" + entry_frame.first + "\"";
      r.Fail(entry + ".header.frame_id", "\"" + frame + "\" is neither the robot's base, the world nor a fixed frame (" +
                                             list + ")");
    }
    for (const char* unsupported : {"meshes", "planes"}) {
      const YAML::Node n = object[unsupported];
      if (n.IsDefined() && n.IsSequence() && n.size() > 0) {
        r.Fail(entry + "." + unsupported, std::string(unsupported) + " are not imported (box, sphere and cylinder primitives are)");
      }
    }
    const YAML::Node operation = object["operation"];
    if (operation.IsDefined() && operation.IsScalar()) {
      const std::string op = Lower(operation.as<std::string>());
      if (op != "0" && op != "add" && op != "2" && op != "append") {
        r.Fail(entry + ".operation", "\"" + op + "\": only added objects can be imported (ADD 0, APPEND 2)");
      }
    }
    const Pose object_pose =
        Compose(frame_pose, object["pose"] ? r.ReadPose(object["pose"], entry + ".pose") : Pose{});
    const YAML::Node primitives = object["primitives"];
    const YAML::Node poses = object["primitive_poses"];
    if (!primitives.IsDefined() || !primitives.IsSequence() || primitives.size() == 0) {
      r.Fail(entry + ".primitives", "expected a list of at least one primitive");
    }
    if (!poses.IsDefined() || !poses.IsSequence() || poses.size() != primitives.size()) {
      r.Fail(entry + ".primitive_poses", "expected one pose per primitive (" + std::to_string(primitives.size()) +
                                             "), got " + (poses.IsDefined() && poses.IsSequence() ? std::to_string(poses.size()) : "none"));
    }
    for (size_t p = 0; p < primitives.size(); ++p) {
      const std::string where = entry + ".primitives[" + std::to_string(p) + "]";
      const YAML::Node primitive = primitives[p];
      if (!primitive.IsMap()) r.Fail(where, "expected a mapping with type and dimensions");
      const std::string type = PrimitiveType(r, primitive["type"], where + ".type");
      const std::vector<double> dims = r.Numbers(primitive["dimensions"], where + ".dimensions");
      for (size_t k = 0; k < dims.size(); ++k) {
        if (dims[k] < 0.0) r.Fail(where + ".dimensions[" + std::to_string(k) + "]", "negative size");
      }
      const Pose pose =
          Compose(object_pose, r.ReadPose(poses[p], entry + ".primitive_poses[" + std::to_string(p) + "]"));
      const std::string name = primitives.size() == 1 ? id : id + "[" + std::to_string(p) + "]";
      const std::vector<double> centre(pose.position.begin(), pose.position.end());
      const std::vector<double> quaternion(pose.orientation.begin(), pose.orientation.end());
      if (type == "box") {
        if (dims.size() != 3) r.Fail(where + ".dimensions", "a box needs 3 values (x, y, z), got " + std::to_string(dims.size()));
        out.scene.boxes.push_back({centre, dims, quaternion, NAN});
        box_names.push_back(name);
      } else if (type == "cylinder") {
        if (dims.size() != 2) {
          r.Fail(where + ".dimensions", "a cylinder needs 2 values (height, radius), got " + std::to_string(dims.size()));
        }
        out.scene.cylinders.push_back({centre, dims[1], dims[0], quaternion, NAN});
        cylinder_names.push_back(name);
      } else {
        if (dims.size() != 1) r.Fail(where + ".dimensions", "a sphere needs 1 value (radius), got " + std::to_string(dims.size()));
        out.scene.spheres.push_back({centre, dims[0]});
        sphere_names.push_back(name);
      }
    }
  }
  for (const auto* names : {&sphere_names, &box_names, &cylinder_names}) {
    out.names.insert(out.names.end(), names->begin(), names->end());
  }
  out.scene.Validate(3, path);
  return out;
}

/// What a request says of the robot: start and goal (J), the joints it holds (by name), where its base stands.
struct RequestRead {
  std::vector<double> start_q, goal_q;
  std::map<std::string, double> held;
  bool base_given = false;  // the request's start_state places the base (a virtual joint)
  Pose base;
};

/// The values a JointState {name, position} gives to `held_names` (joints the robot holds), by name.
void HeldPositions(const Reader& r, const YAML::Node& state, const std::string& entry,
                   const std::vector<std::string>& held_names, std::map<std::string, double>& held) {
  const YAML::Node names = state["name"];
  const YAML::Node positions = state["position"];
  if (!names.IsDefined() || !names.IsSequence() || !positions.IsDefined() || !positions.IsSequence()) return;
  for (size_t i = 0; i < names.size() && i < positions.size(); ++i) {
    const std::string name = r.Text(names[i], entry + ".name[" + std::to_string(i) + "]");
    for (const std::string& h : held_names) {
      if (name == h) held[h] = r.Number(positions[i], entry + ".position[" + std::to_string(i) + "]");
    }
  }
}

RequestRead ReadRequest(const std::string& request_path, const std::string& scene_path,
                        const MoveItImportOptions& options) {
  RequestRead out;
  const YAML::Node root = Load(request_path);
  const Reader r(request_path);
  std::string prefix;
  const YAML::Node request = RequestNode(r, root, prefix);

  const YAML::Node start = request["start_state"];
  if (start.IsDefined() && !start.IsMap()) {
    r.Fail(prefix + "start_state", "expected a mapping with joint_state, got " + config::internal::Describe(start));
  }
  if (start.IsDefined() && start["multi_dof_joint_state"] && start["multi_dof_joint_state"]["transforms"] &&
      start["multi_dof_joint_state"]["transforms"].IsSequence() &&
      start["multi_dof_joint_state"]["transforms"].size() > 0) {
    out.base = ReadVirtualJoint(r, start, prefix + "start_state.multi_dof_joint_state");
    out.base_given = true;
  }
  if (start.IsDefined() && start["joint_state"] && !start["joint_state"].IsMap()) {
    r.Fail(prefix + "start_state.joint_state",
           "expected a mapping with name and position, got " + config::internal::Describe(start["joint_state"]));
  }
  // The scene's robot state first (MoveIt's start state is a change of it), then the request's own.
  const YAML::Node scene = Load(scene_path);
  const Reader s(scene_path);
  const YAML::Node scene_state = scene["robot_state"];
  const bool scene_has_state = scene_state.IsDefined() && scene_state.IsMap() && scene_state["joint_state"] &&
                               scene_state["joint_state"].IsMap();
  if (scene_has_state) HeldPositions(s, scene_state["joint_state"], "robot_state.joint_state", options.held_names, out.held);
  if (start.IsDefined() && start["joint_state"] && start["joint_state"]["name"] &&
      start["joint_state"]["name"].IsSequence() && start["joint_state"]["name"].size() > 0) {
    out.start_q = JointPositions(r, start["joint_state"], prefix + "start_state.joint_state", options);
    HeldPositions(r, start["joint_state"], prefix + "start_state.joint_state", options.held_names, out.held);
  } else {
    if (!scene_has_state) {
      r.Fail(prefix + "start_state", "missing, and " + scene_path + " has no robot_state.joint_state either");
    }
    out.start_q = JointPositions(s, scene_state["joint_state"], "robot_state.joint_state", options);
  }

  const YAML::Node goals = request["goal_constraints"];
  const std::string entry = prefix + "goal_constraints";
  if (!goals.IsDefined() || !goals.IsSequence() || goals.size() == 0) r.Fail(entry, "expected a list of at least one goal");
  if (!goals[0].IsMap()) r.Fail(entry + "[0]", "expected a mapping with joint_constraints");
  const YAML::Node joints = goals[0]["joint_constraints"];
  if (!joints.IsDefined() || !joints.IsSequence() || joints.size() == 0) {
    r.Fail(entry + "[0].joint_constraints", "missing: only joint-space goals are imported");
  }
  out.goal_q.assign(options.joint_names.size(), NAN);
  for (size_t i = 0; i < joints.size(); ++i) {
    const std::string where = entry + "[0].joint_constraints[" + std::to_string(i) + "]";
    if (!joints[i].IsMap()) r.Fail(where, "expected a mapping with joint_name and position");
    const std::string name = r.Text(joints[i]["joint_name"], where + ".joint_name");
    const double position = r.Number(joints[i]["position"], where + ".position");
    for (size_t j = 0; j < options.joint_names.size(); ++j) {
      for (const std::string& accepted : options.joint_names[j]) {
        if (name == accepted) out.goal_q[j] = position;
      }
    }
  }
  for (size_t j = 0; j < out.goal_q.size(); ++j) {
    if (std::isnan(out.goal_q[j])) r.Fail(entry + "[0].joint_constraints", "no constraint on " + options.joint_names[j][0]);
  }
  return out;
}

/// A number in a note or a reason: 7 significant digits.
std::string Num7(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.7g", v);
  return text;
}

/// Joint values past a limit by at most options.limit_tolerance are moved onto it, with a note each; the first
/// one past it by more gives the refusal. Compared in float64.
std::string Limits(const kinematics::RobotDescription& robot, std::vector<double>& q, const std::string& what,
                   const MoveItImportOptions& options, std::vector<std::string>& notes) {
  for (size_t j = 0; j < q.size(); ++j) {
    const double lower = robot.joint_lower[j], upper = robot.joint_upper[j];
    if (q[j] >= lower && q[j] <= upper) continue;
    const bool low = q[j] < lower;
    const double past = low ? lower - q[j] : q[j] - upper;
    const std::string text = what + ": " + options.joint_names[j][0] + " = " + Num7(q[j]) + " is " + Num7(past) +
                             " past its " + (low ? "lower" : "upper") + " limit " + Num7(low ? lower : upper);
    if (past > options.limit_tolerance) return text + " (more than the tolerance " + Num7(options.limit_tolerance) + ")";
    notes.push_back(text + "; moved onto the limit");
    q[j] = low ? lower : upper;
  }
  return "";
}

}  // namespace

NamedScene ReadMoveItScene(const std::string& path, const MoveItImportOptions& options) {
  return Guarded(path, [&] { return ReadScene(path, options, nullptr, nullptr); });
}

void ReadMoveItRequest(const std::string& request_path, const std::string& scene_path,
                       const MoveItImportOptions& options, std::vector<double>& start_q,
                       std::vector<double>& goal_q) {
  const RequestRead read = Guarded(request_path, [&] { return ReadRequest(request_path, scene_path, options); });
  start_q = read.start_q;
  goal_q = read.goal_q;
}

Problem ImportMoveItProblem(const collision::BodyModel& body, const std::string& scene_path,
                            const std::string& request_path, const std::string& name,
                            const MoveItImportOptions& options) {
  const kinematics::RobotDescription& robot = body.description();
  if (static_cast<int>(options.joint_names.size()) != body.num_joints()) {
    throw InternalError("MoveIt import: " + std::to_string(options.joint_names.size()) + " joint names for " +
                        std::to_string(body.num_joints()) + " joints");
  }
  const RequestRead request = Guarded(request_path, [&] { return ReadRequest(request_path, scene_path, options); });
  Pose base;
  NamedScene read = Guarded(scene_path, [&] {
    return ReadScene(scene_path, options, request.base_given ? &request.base : nullptr, &base);
  });
  Problem problem;
  problem.name = name;
  problem.start_q = request.start_q;
  problem.goal_q = request.goal_q;
  problem.floor_height = options.floor_height;
  for (const auto& [joint, value] : request.held) problem.held.push_back({joint, value});
  if (!IsIdentity(base)) {
    problem.base_pose = {base.position[0], base.position[1], base.position[2], base.orientation[0],
                         base.orientation[1], base.orientation[2], base.orientation[3]};
  }
  std::string refusal = Limits(robot, problem.start_q, "start", options, problem.notes);
  if (refusal.empty()) refusal = Limits(robot, problem.goal_q, "goal", options, problem.notes);

  // The body as this problem holds it (a gripper's fingers open).
  const auto held = std::make_shared<const collision::BodyModel>(collision::WithHeld(robot, problem.World().held),
                                                                 request_path);
  // The grasped object: every obstacle the goal's TCP lies in or touches.
  if (options.grasp == GraspRule::kTouchingTcp && read.scene.size() > 0) {
    double tcp[3];
    held->Tcp(problem.goal_q.data(), tcp);
    const collision::World world(read.scene, 3, {}, read.names, scene_path);
    geometry::Scene kept;
    std::vector<std::string> kept_names;
    int k = 0;
    auto keep = [&](auto& from, auto& to) {
      for (const auto& obstacle : from) {
        if (world.Distance(k, tcp) <= options.grasp_margin) {
          problem.left_out.push_back(read.names[static_cast<size_t>(k)]);
        } else {
          to.push_back(obstacle);
          kept_names.push_back(read.names[static_cast<size_t>(k)]);
        }
        ++k;
      }
    };
    keep(read.scene.spheres, kept.spheres);
    keep(read.scene.boxes, kept.boxes);
    keep(read.scene.cylinders, kept.cylinders);
    keep(read.scene.capsules, kept.capsules);
    read.scene = std::move(kept);
    read.names = std::move(kept_names);
  }
  problem.scene = std::move(read.scene);
  problem.obstacle_names = std::move(read.names);
  DescribeEnds(*held, problem);
  if (refusal.empty()) {
    // A start or goal that is not valid (in an obstacle, in itself, below a floor) cannot begin or end a plan.
    collision::Floor floor;
    floor.present = std::isfinite(problem.floor_height);
    floor.height = floor.present ? problem.floor_height : 0.0;
    const collision::Checker checker(
        held, std::make_shared<const collision::World>(problem.scene, 3, floor, problem.obstacle_names, scene_path),
        {options.margin, 0.001});
    for (const auto& [what, q] : {std::pair<const char*, const std::vector<double>*>{"start", &problem.start_q},
                                  std::pair<const char*, const std::vector<double>*>{"goal", &problem.goal_q}}) {
      const collision::Contact contact = checker.FirstContact(q->data());
      if (contact.found()) {
        refusal = std::string(what) + ": " + checker.Describe(contact);
        break;
      }
    }
  }
  if (!refusal.empty()) {
    problem.status = "refused";
    problem.reason = refusal;
  }
  return problem;
}

std::vector<std::pair<std::string, std::string>> FindMoveItPairs(const std::string& folder) {
  if (!std::filesystem::is_directory(folder)) throw Error(folder + ": no such folder");
  const std::regex pattern("(scene|request)([0-9]{1,18})\\.ya?ml");
  // (NNNN as a number, NNNN) -> (scene, request): 9 before 10, 0001 and 1 apart.
  std::map<std::pair<unsigned long long, std::string>, std::pair<std::string, std::string>> found;
  for (const auto& item : std::filesystem::directory_iterator(folder)) {
    std::smatch match;
    const std::string file = item.path().filename().string();
    if (!item.is_regular_file() || !std::regex_match(file, match, pattern)) continue;
    auto& pair = found[{std::stoull(match[2].str()), match[2].str()}];
    (match[1].str() == "scene" ? pair.first : pair.second) = item.path().string();
  }
  std::vector<std::pair<std::string, std::string>> pairs;
  for (const auto& [key, pair] : found) {
    const std::string& number = key.second;
    if (pair.first.empty()) throw Error(pair.second + ": no scene" + number + ".yaml beside it");
    if (pair.second.empty()) throw Error(pair.first + ": no request" + number + ".yaml beside it");
    pairs.push_back(pair);
  }
  if (pairs.empty()) throw Error(folder + ": no sceneNNNN.yaml / requestNNNN.yaml pairs");
  return pairs;
}

}  // namespace flowplan::problems
