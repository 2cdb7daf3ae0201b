// A small arm that tests import as a user's robot: 4 planned joints on a
// vertical lift (one prismatic joint), a mesh link (an octagonal prism as a
// binary STL), primitives and a fixed tool link, written as a URDF.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace flowplan::testing {

namespace fs = std::filesystem;

/// An octagonal prism of radius r and height h along z, from z = 0, as a binary STL.
inline void WritePrismStl(const fs::path& path, double r, double h) {
  std::vector<std::array<std::array<float, 3>, 3>> triangles;
  const int n = 8;
  for (int k = 0; k < n; ++k) {
    const double a0 = 2 * M_PI * k / n, a1 = 2 * M_PI * (k + 1) / n;
    const float x0 = static_cast<float>(r * std::cos(a0)), y0 = static_cast<float>(r * std::sin(a0));
    const float x1 = static_cast<float>(r * std::cos(a1)), y1 = static_cast<float>(r * std::sin(a1));
    const float H = static_cast<float>(h);
    triangles.push_back({{{0, 0, 0}, {x1, y1, 0}, {x0, y0, 0}}});
    triangles.push_back({{{0, 0, H}, {x0, y0, H}, {x1, y1, H}}});
    triangles.push_back({{{x0, y0, 0}, {x1, y1, 0}, {x1, y1, H}}});
    triangles.push_back({{{x0, y0, 0}, {x1, y1, H}, {x0, y0, H}}});
  }
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  const char header[80] = {};
  out.write(header, 80);
  const uint32_t count = static_cast<uint32_t>(triangles.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const auto& t : triangles) {
    const float normal[3] = {0, 0, 0};
    out.write(reinterpret_cast<const char*>(normal), 12);
    for (const auto& v : t) out.write(reinterpret_cast<const char*>(v.data()), 12);
    const uint16_t attribute = 0;
    out.write(reinterpret_cast<const char*>(&attribute), 2);
  }
}

inline const char* kInertial = R"(<inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>)";

/// The URDF: base (box) - lift (prismatic, z) - column (cylinder) - shoulder (z) - upper (cylinder along x) -
/// elbow (y) - fore (cylinder along x) - wrist (about the hand's z) - hand (STL) - fixed - tool. `extra` goes
/// inside <robot>; `wrist_limit` is the wrist's <limit> element.
inline std::string LiftArmUrdf(const std::string& hand_mesh, const std::string& extra = "",
                        const std::string& wrist_limit = R"(<limit lower="-3.0" upper="3.0" velocity="2.0" effort="20"/>)") {
  const std::string I = kInertial;
  return R"(<?xml version="1.0"?>
<robot name="lift_arm">)" + extra + R"(
  <link name="base">)" + I + R"(<collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="column">)" + I + R"(<collision><origin xyz="0 0 0.2"/><geometry><cylinder radius="0.05" length="0.4"/></geometry></collision></link>
  <link name="upper">)" + I + R"(<collision><origin xyz="0.15 0 0" rpy="0 1.5707963267948966 0"/><geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <link name="fore">)" + I + R"(<collision><origin xyz="0.125 0 0" rpy="0 1.5707963267948966 0"/><geometry><cylinder radius="0.035" length="0.25"/></geometry></collision></link>
  <link name="hand">)" + I + R"(<collision><geometry><mesh filename=")" + hand_mesh + R"("/></geometry></collision></link>
  <link name="tool">)" + I + R"(</link>
  <joint name="lift" type="prismatic"><parent link="base"/><child link="column"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.3" velocity="0.2" effort="500"/></joint>
  <joint name="shoulder" type="revolute"><parent link="column"/><child link="upper"/><origin xyz="0 0 0.45" rpy="0 0 0.3"/><axis xyz="0 0 1"/>
    <limit lower="-2.8" upper="2.8" velocity="1.5" effort="80"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-2.0" upper="2.0" velocity="1.5" effort="60"/></joint>
  <joint name="wrist" type="revolute"><parent link="fore"/><child link="hand"/><origin xyz="0.25 0 0" rpy="0 1.5707963267948966 0"/><axis xyz="0 0 1"/>
    )" + wrist_limit + R"(</joint>
  <joint name="tool_joint" type="fixed"><parent link="hand"/><child link="tool"/><origin xyz="0 0 0.12"/></joint>
</robot>
)";
}

inline void WriteText(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

}  // namespace flowplan::testing
