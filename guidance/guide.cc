#include "guidance/guide.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "jit/library.h"
#include "kernels/arm_collision_kernel.h"
#include "kernels/arm_guidance_kernel.h"
#include "kernels/shape_distance_kernel.h"

namespace flowplan::guidance {
namespace {

/// What a cost term's module may be given.
struct CostContext {
  const kinematics::Robot& robot;
  double dt;
  models::Kernels kernels;       // guidance.distance_kernels
  torch::jit::Module distances;  // geometry/distances.py or native_distances.py
};

/// A built-in cost term: its class, its file, the setting that weighs it.
struct CostTerm {
  const char* class_name;
  const char* path;
  const char* weight_key;
};

// The built-in cost terms, one line each; every guided planner sees them all.
const std::vector<CostTerm> kCostTerms = {
    {"CollisionCost", "guidance/collision.py", "guidance.collision_weight"},
    {"SmoothnessCost", "guidance/smoothness.py", "guidance.smoothness_weight"},
    {"JointLimitCost", "guidance/joint_limit.py", "guidance.joint_limit_weight"},
    {"JointSpeedCost", "guidance/joint_speed.py", "guidance.joint_speed_weight"},
};

c10::List<std::string> NativeKinds() {
  c10::List<std::string> kinds;
  for (const std::string& kind : kernels::NativeShapeKinds()) kinds.push_back(kind);
  return kinds;
}

/// The distance passes of the collision cost, in the code `kernels` asks for.
torch::jit::Module BuildDistances(models::Kernels kernels) {
  if (kernels == models::Kernels::kPortable) {
    return jit::ModuleBuilder("Distances").Methods("geometry/distances.py").Build();
  }
  return jit::ModuleBuilder("NativeDistances")
      .Attribute("native_kinds", NativeKinds())
      .Methods("geometry/native_distances.py")
      .Build();
}

/// Every term gets the robot, the scene's distance passes, dt and its weight key; a class uses what it needs.
jit::ModuleBuilder TermBuilder(const char* class_name, const char* weight_key, const CostContext& context) {
  jit::ModuleBuilder builder(class_name);
  builder.Submodule("robot", context.robot.module())
      .Submodule("distances", context.distances)
      .Attribute("dt", context.dt)
      .Attribute("weight_key", std::string(weight_key));
  return builder;
}

/// A built-in term's module. With native kernels an arm's collision hinge is one call of
/// flowplan::arm_collision (guidance/arm_collision.py), holding the script's term for what the operator
/// does not take.
torch::jit::Module BuildTerm(const CostTerm& term, const CostContext& context) {
  torch::jit::Module scripted = TermBuilder(term.class_name, term.weight_key, context).Methods(term.path).Build();
  if (std::string(term.class_name) != "CollisionCost" || context.kernels != models::Kernels::kNative ||
      !context.robot.is_arm()) {
    return scripted;
  }
  return jit::ModuleBuilder("ArmCollisionCost")
      .Submodule("robot", context.robot.module())
      .Submodule("scripted", scripted)
      .Attribute("native_kinds", c10::List<std::string>(kernels::ArmCollisionKinds()))
      .Attribute("weight_key", std::string(term.weight_key))
      .Methods("guidance/arm_collision.py")
      .Build();
}

std::string ReadUserCost(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw Error("guidance.user_cost: " + path + ": no such file");
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw Error("guidance.user_cost: " + path + ": cannot be read");
  const std::string source = text.str();
  if (source.find("def cost(self") == std::string::npos) {
    throw Error("guidance.user_cost: " + path +
                ": expected a method `def cost(self, q: Tensor, qd: Tensor, scene: Dict[str, Tensor]) -> Tensor`");
  }
  return source;
}

}  // namespace

torch::jit::Module BuildGuide(const GuidanceConfig& config, const kinematics::Robot& robot,
                              const torch::jit::Module& normalizer, double dt) {
  const CostContext context{robot, dt, config.distance_kernels, BuildDistances(config.distance_kernels)};
  std::vector<torch::jit::Module> terms;
  for (const CostTerm& term : kCostTerms) terms.push_back(BuildTerm(term, context));
  if (!config.user_cost.empty()) {
    const std::string source = ReadUserCost(config.user_cost);
    terms.push_back(TermBuilder("UserCost", "guidance.user_cost_weight", context)
                        .Attribute("source", config.user_cost)
                        .MethodsFromText(source, "guidance.user_cost: " + config.user_cost)
                        .Methods("guidance/user_cost.py")
                        .Build());
  }
  // The terms as a chain, the first term outermost.
  torch::jit::Module chain = jit::ModuleBuilder("NoCost").Methods("guidance/no_cost.py").Build();
  for (auto term = terms.rbegin(); term != terms.rend(); ++term) {
    chain = jit::ModuleBuilder("CostChain").Submodule("term", *term).Submodule("rest", chain).Methods("guidance/cost_chain.py").Build();
  }
  jit::ModuleBuilder guide("Guide");
  guide.Submodule("normalizer", normalizer)
      .Submodule("costs", chain)
      .Attribute("num_joints", robot.num_joints())
      .Methods("guidance/guide.py");
  // With native kernels, an arm whose chain holds the terms the operator computes, and no others, has its whole
  // gradient in one call of flowplan::arm_guidance; the chain stays for the cost's value and for what the operator
  // does not take. A term added to kCostTerms keeps the chain until the operator computes it too.
  std::vector<std::string> weight_keys;
  for (const CostTerm& term : kCostTerms) weight_keys.emplace_back(term.weight_key);
  if (config.distance_kernels == models::Kernels::kNative && robot.is_arm() && config.user_cost.empty() &&
      weight_keys == kernels::ArmGuidanceWeightKeys()) {
    guide.Submodule("robot", robot.module())
        .Attribute("native_kinds", c10::List<std::string>(kernels::ArmCollisionKinds()))
        .Attribute("dt", dt)
        .Methods("guidance/arm_guide.py");
  } else {
    guide.Methods("guidance/chain_gradient.py");
  }
  return guide.Build();
}

}  // namespace flowplan::guidance
