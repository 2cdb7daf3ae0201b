#include "problems/problem.h"

#include <yaml-cpp/yaml.h>

namespace flowplan::problems {
namespace {

/// Removes every mapping entry whose value is an unset number (.nan), recursively.
YAML::Node WithoutUnset(const YAML::Node& node) {
  if (node.IsMap()) {
    YAML::Node out(YAML::NodeType::Map);
    for (const auto& entry : node) {
      if (entry.second.IsScalar() && entry.second.Scalar() == ".nan") continue;
      out[entry.first] = WithoutUnset(entry.second);
    }
    out.SetStyle(node.Style());
    return out;
  }
  if (node.IsSequence()) {
    YAML::Node out(YAML::NodeType::Sequence);
    for (const auto& element : node) out.push_back(WithoutUnset(element));
    out.SetStyle(node.Style());
    return out;
  }
  return node;
}

template <class T>
std::string Text(const T& value) {
  YAML::Emitter out;
  out << WithoutUnset(config::internal::Encode(value));
  return std::string(out.c_str()) + "\n";
}

}  // namespace

std::string ProblemSetYaml(const ProblemSet& set) { return Text(set); }

std::string SceneYaml(const geometry::Scene& scene) { return Text(scene); }

ProblemSet LoadProblemSet(const std::string& path) {
  ProblemSet set;
  config::Apply(config::ParseYamlFile(path), set, path);
  for (size_t i = 0; i < set.problems.size(); ++i) {
    set.problems[i].scene.Validate(3, path + ": problems[" + std::to_string(i) + "].scene");
  }
  return set;
}

}  // namespace flowplan::problems
