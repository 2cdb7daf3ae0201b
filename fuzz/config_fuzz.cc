// Config YAML and key=value overrides (core/config.h's decoding, which every
// config section goes through), on sections whose libraries are below the
// planner: the plan checker's settings, a scene and a robot's collision body.
// The input's lines that start with "--- " are
// overrides ("--- check.margin=0.1"), applied after the rest, which is the
// YAML document.

#include <sstream>

#include "core/config.h"
#include "fuzz/fuzz_input.h"
#include "geometry/scene.h"
#include "kinematics/robot_description.h"
#include "validity/plan_check.h"

namespace {

struct Sections {
  flowplan::validity::CheckConfig check;
  flowplan::geometry::Scene scene;
  flowplan::kinematics::CollisionBody collision;

  template <class V>
  void Visit(V& v) {
    v.Field("check", check, "plan checker");
    v.Field("scene", scene, "obstacles");
    v.Field("collision", collision, "collision body");
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  std::string document;
  std::vector<std::string> overrides;
  std::istringstream lines(input);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("--- ", 0) == 0) {
      overrides.push_back(line.substr(4));
    } else {
      document += line + "\n";
    }
  }
  try {
    Sections sections;
    flowplan::config::Apply(flowplan::config::ParseYamlText(document, "fuzz.yaml"), sections, "fuzz.yaml");
    for (const std::string& o : overrides) {
      flowplan::config::Apply(flowplan::config::ParseOverride(o), sections, flowplan::config::kCommandLine);
    }
    sections.scene.Validate(3, "fuzz.yaml: scene");
    flowplan::config::ToYaml(sections);
  } catch (const flowplan::Error& error) {
    flowplan::fuzz::ExpectOneLine(error);
  }
  return 0;
}
