#include "problems/problem.h"

#include <yaml-cpp/yaml.h>

#include <limits>

#include "geometry/scene_rows.h"

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

std::vector<double> Row(const torch::Tensor& t) {
  const torch::Tensor c = t.to(torch::kFloat64).contiguous();
  return std::vector<double>(c.data_ptr<double>(), c.data_ptr<double>() + c.numel());
}

}  // namespace

void DescribeEnds(const kinematics::Robot& arm, Problem& problem) {
  const torch::Tensor q = torch::stack({torch::tensor(problem.start_q, torch::kFloat64),
                                        torch::tensor(problem.goal_q, torch::kFloat64)});  // (2, J)
  const torch::Tensor tcp = arm.Tcp(q);                                                     // (2, W)
  problem.start_tcp = Row(tcp[0]);
  problem.goal_tcp = Row(tcp[1]);
  if (problem.scene.size() == 0) {
    problem.start_clearance = problem.goal_clearance = std::numeric_limits<double>::infinity();
    return;
  }
  const torch::Tensor clearance = arm.Clearance(q, geometry::Rows(problem.scene, 3, "problem " + problem.name));  // (2, K)
  problem.start_clearance = clearance[0].min().item<double>();
  problem.goal_clearance = clearance[1].min().item<double>();
}

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
