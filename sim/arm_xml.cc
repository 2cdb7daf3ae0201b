#include "sim/arm_xml.h"

#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>

namespace flowplan::sim {
namespace {

template <class Values>
std::string Numbers(const Values& values) {
  std::string text;
  for (const double v : values) text += (text.empty() ? "" : " ") + XmlNumber(v);
  return text;
}


/// The orientation attribute of a box or cylinder (MuJoCo normalises the quaternion).
std::string Orientation(const std::vector<double>& quaternion) {
  return quaternion.empty() ? std::string() : " quat=\"" + Numbers(quaternion) + "\"";
}

}  // namespace

std::string XmlEscaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string XmlNumber(double value) {
  char buffer[40];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

std::string ArmXml(const kinematics::RobotDescription& d, const ArmXmlOptions& options) {
  const int L = static_cast<int>(d.links.size());
  std::vector<std::vector<int>> children(static_cast<size_t>(L));
  std::vector<int> roots;
  for (int l = 0; l < L; ++l) (d.links[l].parent < 0 ? roots : children[d.links[l].parent]).push_back(l);
  std::ostringstream xml;
  xml << "<mujoco model=\"" << XmlEscaped(d.name) << "\">\n"
      << "  <compiler " << options.compiler << "/>\n"
      << "  <option gravity=\"0 0 -9.81\"/>\n"
      << options.model_elements
      << "  <worldbody>\n"
      << options.world_elements;
  std::function<void(int, int)> body = [&](int l, int depth) {
    const kinematics::RobotLink& link = d.links[l];
    const std::string indent(static_cast<size_t>(2 * depth + 4), ' ');
    std::array<double, 3> pos = link.pos;
    std::array<double, 4> quat = link.quat;
    if (link.joint < 0) kinematics::FixedPose(link, pos, quat);  // a held joint is welded at its value
    // MuJoCo's world body is "world"; a URDF's root link often has that name too.
    const std::string body_name = link.name == "world" ? "world (link)" : link.name;
    xml << indent << "<body name=\"" << XmlEscaped(body_name) << "\" pos=\"" << Numbers(pos) << "\" quat=\""
        << Numbers(quat) << "\">\n";
    const auto elements = options.body_elements.find(link.name);
    if (elements != options.body_elements.end()) xml << elements->second;
    if (link.joint >= 0) {
      const int j = link.joint;
      const bool slide = link.type == kinematics::JointType::kPrismatic;
      xml << indent << "  <joint name=\"q" << j << "\" type=\"" << (slide ? "slide" : "hinge") << "\" axis=\""
          << Numbers(link.axis) << "\"";
      if (std::isfinite(d.joint_lower[j]) && std::isfinite(d.joint_upper[j])) {
        xml << " limited=\"true\" range=\"" << XmlNumber(d.joint_lower[j]) << " " << XmlNumber(d.joint_upper[j]) << "\"";
      }
      xml << " armature=\"" << XmlNumber(options.armature) << "\" damping=\"" << XmlNumber(options.damping) << "\"/>\n";
    }
    if (l == d.tcp_link) {
      xml << indent << "  <site name=\"tcp\" pos=\"" << Numbers(d.tcp_pos) << "\" quat=\"" << Numbers(d.tcp_quat)
          << "\"/>\n";
    }
    for (const int c : children[l]) body(c, depth + 1);
    xml << indent << "</body>\n";
  };
  for (const int r : roots) body(r, 0);
  xml << "  </worldbody>\n";
  if (!options.effort_limit.empty()) {
    xml << "  <actuator>\n";
    for (size_t j = 0; j < options.effort_limit.size(); ++j) {
      xml << "    <motor name=\"q" << j << "\" joint=\"q" << j << "\" ctrllimited=\"true\" ctrlrange=\""
          << XmlNumber(-options.effort_limit[j]) << " " << XmlNumber(options.effort_limit[j]) << "\"/>\n";
    }
    xml << "  </actuator>\n";
  }
  xml << "</mujoco>\n";
  return xml.str();
}

std::string ObstacleGeomsXml(const geometry::Scene& scene, const std::string& attributes) {
  std::vector<std::string> shapes;
  for (const auto& s : scene.spheres) {
    shapes.push_back("type=\"sphere\" pos=\"" + Numbers(s.centre) + "\" size=\"" + XmlNumber(s.radius) + "\"");
  }
  for (const auto& b : scene.boxes) {
    shapes.push_back("type=\"box\" pos=\"" + Numbers(b.centre) + "\" size=\"" +
                     Numbers(std::vector<double>{0.5 * b.size[0], 0.5 * b.size[1], 0.5 * b.size[2]}) + "\"" +
                     Orientation(b.quaternion));
  }
  for (const auto& c : scene.cylinders) {
    shapes.push_back("type=\"cylinder\" pos=\"" + Numbers(c.centre) + "\" size=\"" +
                     Numbers(std::vector<double>{c.radius, 0.5 * c.height}) + "\"" + Orientation(c.quaternion));
  }
  for (const auto& c : scene.capsules) {
    const bool point = c.a == c.b;  // MuJoCo needs a segment of non-zero length
    shapes.push_back(point ? "type=\"sphere\" pos=\"" + Numbers(c.a) + "\" size=\"" + XmlNumber(c.radius) + "\""
                           : "type=\"capsule\" fromto=\"" + Numbers(c.a) + " " + Numbers(c.b) + "\" size=\"" +
                                 XmlNumber(c.radius) + "\"");
  }
  std::string geoms;
  for (size_t k = 0; k < shapes.size(); ++k) {
    geoms += "    <geom name=\"obstacle" + std::to_string(k) + "\" " + shapes[k] + " " + attributes + "/>\n";
  }
  return geoms;
}

}  // namespace flowplan::sim
